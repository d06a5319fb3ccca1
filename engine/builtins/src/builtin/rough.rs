//! The microfacet closures: rough conductor, rough dielectric and rough plastic, over the
//! per-sample functions of [`risotto_systems::rough_conductor`],
//! [`risotto_systems::rough_dielectric`] and [`risotto_systems::rough_plastic`]. Their
//! lobes have densities (`DIFFUSE` bits), so the renderer light-samples them with MIS.

use super::bxdfs::Reflectance;
use glam::Vec3;
use risotto_components::{LobeSampled, Rgb};
use risotto_engine::plugin::*;
use risotto_systems::bxdf::{BxdfSample, Frame};
use risotto_systems::rough_conductor::RoughConductor;
use risotto_systems::rough_dielectric::RoughDielectric;
use risotto_systems::rough_plastic::RoughPlastic;
use risotto_systems::sampler::PathSampler;

/// The local frame of a microfacet lobe at a point with unit shading normal `nn` and the
/// point's tangent ([`ShadingContext::tangent`]): `s` (the direction of `alpha_u`) is the
/// tangent made orthogonal to `nn` (Gram-Schmidt: a two-sided view flips `nn`, and the
/// tangent must stay orthogonal to the normal actually used), `t = nn x s`, so anisotropy
/// follows the surface's `dP/du` as in Mitsuba 3 and pbrt-v4. A degenerate tangent falls back
/// to Duff et al.'s basis around the normal.
#[inline]
pub fn microfacet_frame(nn: Vec3, tangent: Vec3) -> Frame {
    match (tangent - nn * nn.dot(tangent)).try_normalize() {
        Some(s) => Frame {
            s,
            t: nn.cross(s),
            n: nn,
        },
        None => Frame::from_normal(nn),
    }
}

/// Samples every point of `ctx` in its [`microfacet_frame`]: three sampler dimensions per
/// point (the Bxdf's 2D pair, then the lobe choice), handed to `sample(i, wo, u, u_lobe)`
/// with the local `wo`.
pub(super) fn generate(
    ctx: &ShadingContext<'_>,
    samplers: &mut [PathSampler],
    out: &mut BxdfSamples,
    mut sample: impl FnMut(usize, Vec3, glam::Vec2, f32) -> Option<BxdfSample>,
) {
    let (nn, vn, tangent) = (ctx.nn(), ctx.vn(), ctx.tangent());
    for (i, sampler) in samplers.iter_mut().enumerate().take(ctx.num_points()) {
        let u = sampler.next_2d();
        let u_lobe = sampler.next_1d();
        let f = microfacet_frame(nn[i], tangent[i]);
        if let Some(s) = sample(i, f.to_local(vn[i]), u, u_lobe) {
            out.set_local(i, &f, s);
        }
    }
}

/// Evaluates every point of `ctx` towards `wi[i]` in its [`microfacet_frame`]:
/// `eval(i, wo, wi)` with local directions gives `(f |cos|, pdf)`.
pub(super) fn evaluate(
    ctx: &ShadingContext<'_>,
    wi: &[Vec3],
    value: &mut [Rgb],
    pdf: &mut [f32],
    mut eval: impl FnMut(usize, Vec3, Vec3) -> (Rgb, f32),
) {
    let (nn, vn, tangent) = (ctx.nn(), ctx.vn(), ctx.tangent());
    for i in 0..ctx.num_points() {
        let f = microfacet_frame(nn[i], tangent[i]);
        (value[i], pdf[i]) = eval(i, f.to_local(vn[i]), f.to_local(wi[i]));
    }
}

/// The lobes of a context's points: one shared by every point (`&T`, a material whose
/// parameters are numbers: no per-point cost) or one per point (`&[T]`, built from
/// patterns by [`super::rough_patterns`]), as [`super::bxdfs::Reflectance`] is for colours.
pub trait Lobes<T>: Copy {
    /// The lobe of point `i` of the context.
    fn at(&self, i: usize) -> &T;
    /// `out[i] = f(lobe of point i)` for every point (`f` called once when shared).
    fn fill(&self, out: &mut [Rgb], f: impl Fn(&T) -> Rgb);
}

impl<T> Lobes<T> for &T {
    #[inline]
    fn at(&self, _i: usize) -> &T {
        self
    }
    fn fill(&self, out: &mut [Rgb], f: impl Fn(&T) -> Rgb) {
        out.fill(f(self));
    }
}

impl<T> Lobes<T> for &[T] {
    #[inline]
    fn at(&self, i: usize) -> &T {
        &self[i]
    }
    fn fill(&self, out: &mut [Rgb], f: impl Fn(&T) -> Rgb) {
        for (o, lobe) in out.iter_mut().zip(self.iter()) {
            *o = f(lobe);
        }
    }
}

/// The rough conductor closure (one-sided, as Mitsuba 3's `roughconductor`: black seen
/// from behind the shading normal), over one lobe (`L = &RoughConductor`) or one per
/// point (`L = &[RoughConductor]`).
#[derive(Clone, Copy, Debug)]
pub struct RoughConductorBxdf<L> {
    /// The lobe's parameters (the material's, or each point's).
    pub lobe: L,
}

impl<L: Lobes<RoughConductor>> Bxdf for RoughConductorBxdf<L> {
    fn lobes(&self) -> LobeSampled {
        LobeSampled::REFLECT | LobeSampled::DIFFUSE
    }
    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    ) {
        generate(ctx, samplers, out, |i, wo, u, u_lobe| {
            self.lobe.at(i).sample(wo, u, u_lobe)
        });
    }
    fn evaluate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        wi: &[Vec3],
        value: &mut [Rgb],
        pdf: &mut [f32],
    ) {
        evaluate(ctx, wi, value, pdf, |i, wo, wi| {
            self.lobe.at(i).eval(wo, wi)
        });
    }
    fn albedo(&self, _ctx: &ShadingContext<'_>, out: &mut [Rgb]) {
        self.lobe.fill(out, RoughConductor::normal_reflectance);
    }
}

/// The rough dielectric closure, over one lobe (`L = &RoughDielectric`) or one per point
/// (`L = &[RoughDielectric]`). Each lobe's `eta` is the material's index over 1; the
/// relative index over the index outside the shape (the context's `ior_outside`) is
/// applied per point, as the smooth dielectric's.
#[derive(Clone, Copy, Debug)]
pub struct RoughDielectricBxdf<L> {
    /// The lobe's parameters, with the material's index over 1 (vacuum outside).
    pub lobe: L,
}

impl<L: Lobes<RoughDielectric>> RoughDielectricBxdf<L> {
    /// The lobe at point `i`: its own when the outside is vacuum (the common case, with
    /// its compensation tables), else one for the relative index there (kept in `scratch`
    /// while neighbouring points share index and roughness).
    fn at<'b>(
        &'b self,
        i: usize,
        ior_outside: f32,
        scratch: &'b mut Option<RoughDielectric>,
    ) -> &'b RoughDielectric {
        let lobe = self.lobe.at(i);
        if ior_outside == 1.0 {
            return lobe;
        }
        let eta = lobe.eta / ior_outside.max(1e-6);
        let fresh = scratch
            .as_ref()
            .is_none_or(|d| d.eta != eta || d.distribution != lobe.distribution);
        if fresh {
            *scratch = Some(lobe.with_eta(eta));
        }
        scratch.as_ref().unwrap_or(lobe)
    }
}

impl<L: Lobes<RoughDielectric>> Bxdf for RoughDielectricBxdf<L> {
    fn lobes(&self) -> LobeSampled {
        LobeSampled::REFLECT | LobeSampled::TRANSMIT | LobeSampled::DIFFUSE
    }
    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    ) {
        let ior_out = ctx.ior_outside();
        let mut scratch = None;
        generate(ctx, samplers, out, |i, wo, u, u_lobe| {
            self.at(i, ior_out[i], &mut scratch).sample(wo, u, u_lobe)
        });
    }
    fn evaluate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        wi: &[Vec3],
        value: &mut [Rgb],
        pdf: &mut [f32],
    ) {
        let ior_out = ctx.ior_outside();
        let mut scratch = None;
        evaluate(ctx, wi, value, pdf, |i, wo, wi| {
            self.at(i, ior_out[i], &mut scratch).eval(wo, wi)
        });
    }
    fn albedo(&self, _ctx: &ShadingContext<'_>, out: &mut [Rgb]) {
        out.fill(Rgb::WHITE);
    }
}

/// The rough plastic closure (one-sided, as Mitsuba 3's `roughplastic`). The base
/// reflectance is one colour (`R = Rgb`) or one per point (`R = &[Rgb]`, a pattern's
/// column), as [`super::PlasticBxdf`]'s; the coat is the material's (`L = &RoughPlastic`)
/// or one per point (`L = &[RoughPlastic]`, a roughness pattern).
#[derive(Clone, Copy, Debug)]
pub struct RoughPlasticBxdf<L, R = Rgb> {
    /// The coat (with its tables).
    pub lobe: L,
    /// The base's (diffuse) reflectance, in [0, 1].
    pub diffuse: R,
}

impl<L: Lobes<RoughPlastic>, R: Reflectance> Bxdf for RoughPlasticBxdf<L, R> {
    fn lobes(&self) -> LobeSampled {
        LobeSampled::REFLECT | LobeSampled::DIFFUSE
    }
    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    ) {
        generate(ctx, samplers, out, |i, wo, u, u_lobe| {
            self.lobe.at(i).sample(self.diffuse.at(i), wo, u, u_lobe)
        });
    }
    fn evaluate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        wi: &[Vec3],
        value: &mut [Rgb],
        pdf: &mut [f32],
    ) {
        evaluate(ctx, wi, value, pdf, |i, wo, wi| {
            self.lobe.at(i).eval(self.diffuse.at(i), wo, wi)
        });
    }
    fn albedo(&self, _ctx: &ShadingContext<'_>, out: &mut [Rgb]) {
        // The base's reflectance, as Mitsuba's `eval_diffuse_reflectance`.
        self.diffuse.fill(out);
    }
}
