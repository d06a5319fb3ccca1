//! The built-in surface Bxdf closures (Lambertian, smooth dielectric, mirror, the null
//! closure of index-matched boundaries) and the Henyey-Greenstein phase closure for
//! plug-in interiors.

use glam::{Vec2, Vec3};
use risotto_components::{LobeSampled, Rgb};
use risotto_engine::plugin::*;
use risotto_systems::bxdf;
use risotto_systems::sampler::{next_2d_column, PathSampler};
use std::ops::Range;

/// Points per block in the column-wise Bxdf kernels: the block's sample columns live on the
/// stack (no allocation per call) and stay in L1 between the passes.
const CHUNK: usize = 64;

/// Draws every sampler's next two dimensions, a stack block of [`CHUNK`] points at a time
/// through the column sampler, and hands each block to `f(point range, samples)`.
#[inline]
fn for_sample_blocks(samplers: &mut [PathSampler], mut f: impl FnMut(Range<usize>, &[Vec2])) {
    let mut u = [Vec2::ZERO; CHUNK];
    for start in (0..samplers.len()).step_by(CHUNK) {
        let end = (start + CHUNK).min(samplers.len());
        let u = &mut u[..end - start];
        next_2d_column(&mut samplers[start..end], u);
        f(start..end, u);
    }
}

/// [`for_sample_blocks`] one point at a time: `f(point index, sample)`, in order.
#[inline]
pub(super) fn for_sample_chunks(samplers: &mut [PathSampler], mut f: impl FnMut(usize, Vec2)) {
    for_sample_blocks(samplers, |range, u| {
        for (i, &u) in range.zip(u) {
            f(i, u);
        }
    });
}

/// Lobe bits of a Lambertian sample.
const DIFFUSE_REFLECT: LobeSampled = LobeSampled(LobeSampled::REFLECT.0 | LobeSampled::DIFFUSE.0);

/// Lambertian reflection (one-sided: black seen from behind). The reflectance is one colour
/// (`R = Rgb`, the default) or one per point of the context (`R = &[Rgb]`, a pattern's column
/// from [`ShadingContext::eval_param`]).
#[derive(Clone, Copy, Debug)]
pub struct DiffuseBxdf<R = Rgb> {
    /// Reflectance (albedo) per channel, in [0, 1].
    pub reflectance: R,
}

/// A reflectance a closure reads per point: a constant or a column.
pub trait Reflectance: Copy {
    /// The value at point `i` of the context.
    fn at(&self, i: usize) -> Rgb;
    /// The values of every point (`out` has one entry per point).
    fn fill(&self, out: &mut [Rgb]);
}

impl Reflectance for Rgb {
    #[inline]
    fn at(&self, _i: usize) -> Rgb {
        *self
    }
    fn fill(&self, out: &mut [Rgb]) {
        out.fill(*self);
    }
}

impl Reflectance for &[Rgb] {
    #[inline]
    fn at(&self, i: usize) -> Rgb {
        self[i]
    }
    fn fill(&self, out: &mut [Rgb]) {
        out.copy_from_slice(&self[..out.len()]);
    }
}

/// Local direction `w` relative to a frame whose normal is the point's shading normal, flipped
/// to the side the viewer is on only for two-sided lobes (callers decide).
#[inline]
pub(super) fn frame(n: Vec3) -> bxdf::Frame {
    bxdf::Frame::from_normal(n)
}

impl<R: Reflectance> Bxdf for DiffuseBxdf<R> {
    fn lobes(&self) -> LobeSampled {
        LobeSampled::REFLECT | LobeSampled::DIFFUSE
    }
    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    ) {
        let (nn, vn) = (ctx.nn(), ctx.vn());
        for_sample_blocks(samplers, |r, u| {
            bxdf::diffuse_sample_world(
                &nn[r.clone()],
                &vn[r.clone()],
                u,
                &mut out.wi[r.clone()],
                &mut out.pdf[r],
            );
        });
        // Cosine-weighted sampling of f = reflectance / pi: the weight is the reflectance.
        // (`out.reset` left black weights and no lobe where there is no sample.)
        let weights = out.weight.iter_mut().zip(&mut out.lobe).zip(&out.pdf);
        for (i, ((weight, lobe), &pdf)) in weights.enumerate() {
            if pdf > 0.0 {
                *weight = self.reflectance.at(i);
                *lobe = DIFFUSE_REFLECT;
            }
        }
    }
    fn evaluate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        wi: &[Vec3],
        value: &mut [Rgb],
        pdf: &mut [f32],
    ) {
        let (nn, vn) = (ctx.nn(), ctx.vn());
        for i in 0..ctx.num_points() {
            let (v, p) =
                bxdf::diffuse_eval_cos(self.reflectance.at(i), nn[i].dot(vn[i]), nn[i].dot(wi[i]));
            value[i] = v;
            pdf[i] = p;
        }
    }
    fn albedo(&self, _ctx: &ShadingContext<'_>, out: &mut [Rgb]) {
        self.reflectance.fill(out);
    }
}

/// Smooth dielectric boundary: Fresnel chooses reflection or refraction. The tint is one
/// colour (`R = Rgb`, the default) or one per point (`R = &[Rgb]`, a pattern's column).
#[derive(Clone, Copy, Debug)]
pub struct DielectricBxdf<R = Rgb> {
    /// Index of refraction of the interior.
    pub ior: f32,
    /// Colour multiplying refracted light.
    pub tint: R,
}

impl<R: Reflectance> Bxdf for DielectricBxdf<R> {
    fn lobes(&self) -> LobeSampled {
        LobeSampled::REFLECT | LobeSampled::TRANSMIT | LobeSampled::SPECULAR
    }
    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    ) {
        let (nn, vn, ior_out) = (ctx.nn(), ctx.vn(), ctx.ior_outside());
        for_sample_chunks(samplers, |i, u| {
            // The shading frame, as every other Bxdf's (and Mitsuba's and pbrt's dielectric):
            // `nn` lies on the outward side with `ng`, so `eta` keeps its meaning (inside /
            // outside) whichever side the ray arrives from. Where the viewer lies between the
            // two planes this reads as arriving from inside, as in Mitsuba; directions the
            // normals then classify differently are the path tracer's to keep or discard
            // (`ShadingNormals`).
            let f = frame(nn[i]);
            let eta = self.ior / ior_out[i].max(1e-6);
            if let Some(s) = bxdf::dielectric_sample(eta, self.tint.at(i), f.to_local(vn[i]), u) {
                out.set_local(i, &f, s);
            }
        });
    }
    fn evaluate_samples(
        &mut self,
        _ctx: &ShadingContext<'_>,
        _wi: &[Vec3],
        value: &mut [Rgb],
        pdf: &mut [f32],
    ) {
        value.fill(Rgb::BLACK);
        pdf.fill(0.0);
    }
    fn albedo(&self, _ctx: &ShadingContext<'_>, out: &mut [Rgb]) {
        out.fill(Rgb::WHITE);
    }
}

/// Perfect specular reflection weighted by a reflectance: one colour (`R = Rgb`, the
/// default) or one per point (`R = &[Rgb]`, a pattern's column), as [`DiffuseBxdf`].
#[derive(Clone, Copy, Debug)]
pub struct MirrorBxdf<R = Rgb> {
    /// Reflectance per channel, in [0, 1].
    pub reflectance: R,
}

impl<R: Reflectance> Bxdf for MirrorBxdf<R> {
    fn lobes(&self) -> LobeSampled {
        LobeSampled::REFLECT | LobeSampled::SPECULAR
    }
    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        _samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    ) {
        let (nn, vn) = (ctx.nn(), ctx.vn());
        for i in 0..ctx.num_points() {
            // Two-sided mirror: reflect about the normal facing the viewer.
            let n = if nn[i].dot(vn[i]) >= 0.0 {
                nn[i]
            } else {
                -nn[i]
            };
            let f = frame(n);
            if let Some(s) = bxdf::mirror_sample(self.reflectance.at(i), f.to_local(vn[i])) {
                out.set_local(i, &f, s);
            }
        }
    }
    fn evaluate_samples(
        &mut self,
        _ctx: &ShadingContext<'_>,
        _wi: &[Vec3],
        value: &mut [Rgb],
        pdf: &mut [f32],
    ) {
        value.fill(Rgb::BLACK);
        pdf.fill(0.0);
    }
    fn albedo(&self, _ctx: &ShadingContext<'_>, out: &mut [Rgb]) {
        self.reflectance.fill(out);
    }
}

/// The contract's closure that never scatters, under its old path here.
pub use risotto_engine::plugin::NullBxdf;

#[cfg(test)]
mod tests {
    use super::*;
    use risotto_components::{ShadingPointRow, ShadingPoints};
    use risotto_systems::bxdf_samples::BxdfSamples;

    #[test]
    fn the_smooth_dielectric_reflects_and_refracts_about_the_shading_normal() {
        // A facet facing +z seen from straight above, its shading normal leaning 20 degrees
        // towards +x: the mirror and refracted directions follow `nn`, not `ng` (Mitsuba's
        // and pbrt's dielectric; the facet's own frame gave `wi = +z` for every reflection).
        let nn = Vec3::new(20f32.to_radians().sin(), 0.0, 20f32.to_radians().cos());
        let vn = Vec3::Z;
        let mut points = ShadingPoints::default();
        let n = 64;
        for i in 0..n {
            points.push(ShadingPointRow {
                ng: Vec3::Z,
                nn,
                vn,
                shape: 0,
                ..ShadingPointRow::in_volume(Vec3::ZERO, -vn, i, 0)
            });
        }
        let ctx = ShadingContext::new(&points, 0..n as usize, ShadingMode::Scatter, 0, &[]);
        let mut samplers: Vec<PathSampler> = (0..n)
            .map(|i| PathSampler {
                seed: 7,
                sample: i,
                dimension: 0,
            })
            .collect();
        let mut out = BxdfSamples::default();
        out.reset(n as usize);
        let ior = 1.5;
        DielectricBxdf {
            ior,
            tint: Rgb::WHITE,
        }
        .generate_samples(&ctx, &mut samplers, &mut out);
        let mirror = 2.0 * vn.dot(nn) * nn - vn;
        // Snell about nn: the tangential part scales by 1/eta.
        let cos_i = vn.dot(nn);
        let sin2_t = (1.0 - cos_i * cos_i) / (ior * ior);
        let refracted = -vn / ior + (cos_i / ior - (1.0 - sin2_t).sqrt()) * nn;
        let (mut reflected, mut transmitted) = (0, 0);
        for k in 0..n as usize {
            assert!(out.pdf[k] > 0.0, "sample {k} absorbed");
            let want = if out.lobe[k].is_transmit() {
                transmitted += 1;
                refracted
            } else {
                reflected += 1;
                mirror
            };
            assert!(
                out.wi[k].distance(want) < 1e-5,
                "sample {k} ({:?}): wi {} against {want}",
                out.lobe[k],
                out.wi[k]
            );
        }
        assert!(
            reflected > 0 && transmitted > 0,
            "{reflected} reflected, {transmitted} refracted"
        );
    }
}
