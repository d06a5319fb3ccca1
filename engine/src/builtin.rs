//! Built-in materials (factories), their Bxdf closures, the phase function and the built-in
//! interiors (`null`, `beer`).
//!
//! Scene-file material types: `diffuse`, `dielectric`, `conductor` / `mirror`, `interface`.
//! Any of them may carry an `interior = { type = "null" | "beer", ... }` table that makes the
//! shape's inside a volume with that integrator (see `docs/scene-format.md`).

use crate::context::IntegratorContext;
use crate::heterogeneous::{HeterogeneousInterior, HeterogeneousMedium};
use crate::media::{HomogeneousInterior, HomogeneousMedium, PhaseBxdf};
use crate::plugin::*;
use crate::scatter_patterns::phase_bxdf;
use bumpalo::Bump;
use glam::{Vec2, Vec3};
use risotto_components::{LobeSampled, Rays, Rgb};
use risotto_systems::bxdf;
use risotto_systems::pattern::{self, PatternGraph};
use risotto_systems::sampler::{next_2d_column, PathSampler};
use std::ops::Range;
use std::sync::Arc;

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
fn for_sample_chunks(samplers: &mut [PathSampler], mut f: impl FnMut(usize, Vec2)) {
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
fn frame(n: Vec3) -> bxdf::Frame {
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
        let (ng, vn, ior_out) = (ctx.ng(), ctx.vn(), ctx.ior_outside());
        for_sample_chunks(samplers, |i, u| {
            // The frame follows the outward geometric normal so `eta` keeps its meaning
            // (inside / outside) whichever side the ray arrives from.
            let f = frame(ng[i]);
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

/// Henyey-Greenstein phase function as a Bxdf for volume points (`vn` = towards where the ray
/// came from). `albedo` (single-scattering albedo) weights every sample.
#[derive(Clone, Copy, Debug)]
pub struct HenyeyGreensteinPhase {
    /// Mean cosine, in (-1, 1).
    pub g: f32,
    /// Single-scattering albedo `sigma_s / sigma_t`.
    pub albedo: Rgb,
}

impl Bxdf for HenyeyGreensteinPhase {
    fn lobes(&self) -> LobeSampled {
        LobeSampled::SCATTER | LobeSampled::DIFFUSE
    }
    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    ) {
        let vn = ctx.vn();
        for_sample_chunks(samplers, |i, u| {
            let (wi, pdf) = bxdf::hg_sample(self.g, vn[i], u);
            if pdf > 0.0 {
                out.wi[i] = wi;
                // p / pdf = 1 for exact sampling.
                out.weight[i] = self.albedo;
                out.pdf[i] = pdf;
                out.lobe[i] = LobeSampled::SCATTER | LobeSampled::DIFFUSE;
                out.eta[i] = 1.0;
            }
        });
    }
    fn evaluate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        wi: &[Vec3],
        value: &mut [Rgb],
        pdf: &mut [f32],
    ) {
        let vn = ctx.vn();
        for i in 0..ctx.num_points() {
            let p = bxdf::hg_eval(self.g, vn[i], wi[i]);
            value[i] = self.albedo * p;
            pdf[i] = p;
        }
    }
    fn albedo(&self, _ctx: &ShadingContext<'_>, out: &mut [Rgb]) {
        out.fill(self.albedo);
    }
}

/// A Bxdf that never scatters (index-matched boundaries are never shaded; this closure exists
/// so that a factory always has one).
#[derive(Clone, Copy, Debug)]
pub struct NullBxdf;

impl Bxdf for NullBxdf {
    fn lobes(&self) -> LobeSampled {
        LobeSampled::NONE
    }
    fn generate_samples(
        &mut self,
        _ctx: &ShadingContext<'_>,
        _samplers: &mut [PathSampler],
        _out: &mut BxdfSamples,
    ) {
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
}

/// The seed's `NullInterior`: passes hits through, transmission 1.
#[derive(Clone, Copy, Debug, Default)]
pub struct NullInterior;

impl VolumeIntegrator for NullInterior {
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        _samplers: &mut [PathSampler],
        _lobes_wanted: LobeSampled,
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
        services.ictx.nearest_hits(rays, out);
    }
    fn transmission(
        &self,
        _segments: &Segments,
        _samplers: &mut [PathSampler],
        _ictx: &IntegratorContext<'_>,
        trans: &mut [Rgb],
        emission: &mut [Rgb],
    ) {
        trans.fill(Rgb::WHITE);
        emission.fill(Rgb::BLACK);
    }
}

/// The seed's `GlassInterior`: Beer-Lambert absorption, `T = exp(-sigma_a * d)` per channel,
/// on the hits it returns and on shadow segments. No scattering.
#[derive(Clone, Copy, Debug)]
pub struct BeerInterior {
    /// Absorption coefficient per channel (per world unit), >= 0.
    pub sigma_a: Rgb,
}

impl BeerInterior {
    /// Transmittance over a distance.
    #[inline]
    pub fn transmittance(&self, distance: f32) -> Rgb {
        beer(self.sigma_a, distance)
    }
}

/// `exp(-sigma * d)` per channel; an infinite distance through a non-absorbing channel gives 1
/// (not NaN: `0 * inf` is defined as 0 here).
#[inline]
pub fn beer(sigma: Rgb, distance: f32) -> Rgb {
    sigma.map(|s| if s == 0.0 { 1.0 } else { (-s * distance).exp() })
}

impl VolumeIntegrator for BeerInterior {
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        _samplers: &mut [PathSampler],
        _lobes_wanted: LobeSampled,
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
        services.ictx.nearest_hits(rays, out);
        out.attenuate_segments(rays, |length| self.transmittance(length));
    }
    fn transmission(
        &self,
        segments: &Segments,
        _samplers: &mut [PathSampler],
        _ictx: &IntegratorContext<'_>,
        trans: &mut [Rgb],
        emission: &mut [Rgb],
    ) {
        for i in 0..segments.len() {
            trans[i] = self.transmittance(segments.length[i]);
        }
        emission.fill(Rgb::BLACK);
    }
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

/// Which built-in interior a material has.
#[derive(Clone, Debug, PartialEq)]
pub enum Interior {
    /// No volume inside.
    None,
    /// Pass-through volume (transmission 1).
    Null,
    /// Beer-Lambert absorber.
    Beer {
        /// Absorption coefficient per channel.
        sigma_a: Rgb,
    },
    /// Homogeneous scattering medium.
    Homogeneous(HomogeneousMedium),
    /// Heterogeneous scattering medium (a density grid; shared, not copied).
    Heterogeneous(Arc<HeterogeneousMedium>),
    /// The `subsurface` material's interior ([`crate::subsurface`]): the walked medium and
    /// the diffusion profile made from the artist's parameters, and the mode to use.
    Subsurface(crate::subsurface::SubsurfaceInteriorParams),
}

impl Interior {
    fn hints(&self) -> InstanceHints {
        let volume = InstanceHints::COMPUTES_INTERIOR | InstanceHints::INTERIOR_TRANSMISSION;
        // The built-in emissive media report their emission along path rays (and fill
        // `transmission`'s emission output too).
        let emits = InstanceHints::INTERIOR_EMITS | InstanceHints::INTERIOR_EMITS_ALONG_PATHS;
        match self {
            Interior::None => InstanceHints::NONE,
            Interior::Null | Interior::Beer { .. } => volume,
            Interior::Homogeneous(m) if m.emits() => {
                volume | InstanceHints::INTERIOR_SCATTERS | emits
            }
            Interior::Heterogeneous(m) if m.emits() => {
                volume
                    | InstanceHints::INTERIOR_SCATTERS
                    | InstanceHints::INTERIOR_HETEROGENEOUS
                    | emits
            }
            Interior::Homogeneous(_) => volume | InstanceHints::INTERIOR_SCATTERS,
            Interior::Subsurface(_) => {
                volume | InstanceHints::INTERIOR_SCATTERS | InstanceHints::INTERIOR_SUBSURFACE
            }
            Interior::Heterogeneous(_) => {
                volume | InstanceHints::INTERIOR_SCATTERS | InstanceHints::INTERIOR_HETEROGENEOUS
            }
        }
    }
    /// `boundary_blocks_shadows`: the surface around it lets no shadow ray through.
    fn begin<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        arena: &'a Bump,
        boundary_blocks_shadows: bool,
    ) -> Option<&'a mut (dyn VolumeIntegrator + 'a)> {
        match self {
            Interior::None => None,
            Interior::Null => Some(arena.alloc(NullInterior)),
            Interior::Beer { sigma_a } => Some(arena.alloc(BeerInterior { sigma_a: *sigma_a })),
            Interior::Subsurface(params) => {
                Some(arena.alloc(crate::subsurface::SubsurfaceInterior {
                    walk: HomogeneousInterior {
                        medium: &params.walk,
                        ctx,
                        boundary_blocks_shadows,
                    },
                    diffusion: crate::diffusion::DiffusionInterior {
                        medium: params.diffusion,
                    },
                    mode: params.mode,
                    patterned: params.patterned.as_deref(),
                }))
            }
            Interior::Homogeneous(medium) => Some(arena.alloc(HomogeneousInterior {
                medium,
                ctx,
                boundary_blocks_shadows,
            })),
            Interior::Heterogeneous(medium) => {
                Some(arena.alloc(HeterogeneousInterior { medium, ctx }))
            }
        }
    }
}

/// The surface part of a built-in material.
#[derive(Clone, Debug, PartialEq)]
pub enum Surface {
    /// Lambertian.
    Diffuse {
        /// Reflectance.
        reflectance: Rgb,
    },
    /// Lambertian with a reflectance pattern (every value in [0, 1] by the graph's bounds,
    /// which the scene loader checks), evaluated per point through the context's cache
    /// (parameter `reflectance`).
    DiffusePattern {
        /// The reflectance graph.
        reflectance: Arc<PatternGraph>,
    },
    /// Smooth dielectric.
    Dielectric {
        /// Interior IOR.
        ior: f32,
        /// Refraction tint.
        tint: Rgb,
        /// Shadow rays pass (attenuated by `tint`) instead of being blocked: the seed's cheap
        /// non-refracting glass shadows.
        cheap_shadows: bool,
    },
    /// Smooth dielectric with a tint pattern (every value in [0, 1] by the graph's bounds,
    /// checked by the scene loader), evaluated per hit through the context's cache
    /// (parameter `tint`). Shadow rays are blocked (cheap shadows attenuate by one colour).
    DielectricPattern {
        /// Interior IOR.
        ior: f32,
        /// The tint graph.
        tint: Arc<PatternGraph>,
    },
    /// Perfect mirror / smooth conductor.
    Mirror {
        /// Reflectance.
        reflectance: Rgb,
    },
    /// Perfect mirror with a reflectance pattern (every value in [0, 1] by the graph's
    /// bounds, checked by the scene loader), evaluated per point through the context's cache
    /// (parameter `reflectance`), as [`Surface::DiffusePattern`].
    MirrorPattern {
        /// The reflectance graph.
        reflectance: Arc<PatternGraph>,
    },
    /// Index-matched boundary: rays pass unchanged.
    Interface,
}

/// A built-in material: a surface and an optional interior.
#[derive(Clone, Debug, PartialEq)]
pub struct BuiltinMaterial {
    /// Surface scattering.
    pub surface: Surface,
    /// Interior volume.
    pub interior: Interior,
}

impl BxdfFactory for BuiltinMaterial {
    fn instance_hints(&self) -> InstanceHints {
        let surface = match &self.surface {
            Surface::Diffuse { .. } | Surface::Mirror { .. } => InstanceHints::NONE,
            Surface::DiffusePattern { reflectance } | Surface::MirrorPattern { reflectance }
                if reflectance.reads_uv() =>
            {
                InstanceHints::READS_SURFACE_UV
            }
            Surface::DiffusePattern { .. } | Surface::MirrorPattern { .. } => InstanceHints::NONE,
            Surface::DielectricPattern { tint, .. } if tint.reads_uv() => {
                InstanceHints::TRANSMITS | InstanceHints::READS_SURFACE_UV
            }
            Surface::DielectricPattern { .. } => InstanceHints::TRANSMITS,
            &Surface::Dielectric { cheap_shadows, .. } => {
                let h = InstanceHints::TRANSMITS;
                if cheap_shadows {
                    h | InstanceHints::TRANSMISSION_SHADOWS
                } else {
                    h
                }
            }
            Surface::Interface => {
                InstanceHints::INDEX_MATCHED
                    | InstanceHints::TRANSMISSION_SHADOWS
                    | InstanceHints::TRANSMITS
            }
        };
        surface | self.interior.hints()
    }

    fn begin_scatter<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        mode: ShadingMode,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a) {
        match mode {
            // A point inside the interior: its phase function (an interior that does not
            // scatter never returns such points; isotropic and black if asked anyway).
            ShadingMode::VolumeScatter => {
                return match &self.interior {
                    Interior::Subsurface(params) => arena.alloc(PhaseBxdf {
                        phase: params.walk.phase,
                        albedo: params.walk.albedo(),
                    }),
                    // A `g` pattern is read through the context's cache.
                    Interior::Homogeneous(m) => {
                        phase_bxdf(ctx, m.phase, m.g_pattern.as_deref(), m.albedo(), arena)
                    }
                    Interior::Heterogeneous(m) => {
                        phase_bxdf(ctx, m.phase, m.g_pattern.as_deref(), m.albedo, arena)
                    }
                    _ => arena.alloc(NullBxdf),
                };
            }
            // Interiors are built by `begin_interior`; a surface closure is never needed for
            // them.
            ShadingMode::Interior => return arena.alloc(NullBxdf),
            ShadingMode::Scatter => {}
        }
        match self.surface {
            Surface::Diffuse { reflectance } => arena.alloc(DiffuseBxdf { reflectance }),
            // Patterns go through the context's cache ([`pattern_column`]).
            Surface::DiffusePattern { ref reflectance } => arena.alloc(DiffuseBxdf {
                reflectance: pattern_column(ctx, "reflectance", reflectance, arena),
            }),
            Surface::Dielectric { ior, tint, .. } => arena.alloc(DielectricBxdf { ior, tint }),
            Surface::DielectricPattern { ior, ref tint } => arena.alloc(DielectricBxdf {
                ior,
                tint: pattern_column(ctx, "tint", tint, arena),
            }),
            Surface::Mirror { reflectance } => arena.alloc(MirrorBxdf { reflectance }),
            Surface::MirrorPattern { ref reflectance } => arena.alloc(MirrorBxdf {
                reflectance: pattern_column(ctx, "reflectance", reflectance, arena),
            }),
            Surface::Interface => arena.alloc(NullBxdf),
        }
    }

    fn begin_interior<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> Option<&'a mut (dyn VolumeIntegrator + 'a)> {
        let blocks = self.surface != Surface::Interface && self.shadow_transmittance().is_black();
        self.interior.begin(ctx, arena, blocks)
    }

    fn shadow_transmittance(&self) -> Rgb {
        match self.surface {
            Surface::Interface => Rgb::WHITE,
            Surface::Dielectric {
                tint,
                cheap_shadows: true,
                ..
            } => tint,
            _ => Rgb::BLACK,
        }
    }

    fn param(&self, name: &str) -> Option<ParamValue<'_>> {
        match (&self.surface, name) {
            (Surface::Diffuse { reflectance } | Surface::Mirror { reflectance }, "reflectance") => {
                Some(ParamValue::Color(*reflectance))
            }
            (
                Surface::DiffusePattern { reflectance } | Surface::MirrorPattern { reflectance },
                "reflectance",
            ) => Some(ParamValue::Pattern(reflectance)),
            (Surface::Dielectric { ior, .. } | Surface::DielectricPattern { ior, .. }, "ior") => {
                Some(ParamValue::Float(*ior))
            }
            (Surface::DielectricPattern { tint, .. }, "tint") => Some(ParamValue::Pattern(tint)),
            (Surface::Dielectric { tint, .. }, "tint") => Some(ParamValue::Color(*tint)),
            (_, crate::scatter_patterns::G_PARAM) => match &self.interior {
                Interior::Homogeneous(m) => m.g_pattern.as_deref().map(ParamValue::Pattern),
                Interior::Heterogeneous(m) => m.g_pattern.as_deref().map(ParamValue::Pattern),
                _ => None,
            },
            _ => None,
        }
    }

    fn ior(&self) -> f32 {
        match self.surface {
            Surface::Dielectric { ior, .. } | Surface::DielectricPattern { ior, .. } => ior,
            _ => 1.0,
        }
    }

    /// A heterogeneous emissive interior behind an index-matched `interface` is a light
    /// (behind other surfaces path rays do not keep their pdf, `crate::volume_lights`).
    fn volume_emitter(
        &self,
        bounds: (glam::Vec3, glam::Vec3),
        support: crate::volume_lights::EmitterSupport,
    ) -> Option<crate::volume_lights::VolumeEmitter> {
        match (&self.surface, &self.interior) {
            (Surface::Interface, Interior::Heterogeneous(m)) => m.volume_emitter(bounds, support),
            (Surface::Interface, Interior::Homogeneous(m)) => m.volume_emitter(bounds, support),
            _ => None,
        }
    }
}

/// The column of pattern parameter `name` (the material's `graph`) over `ctx`'s points:
/// through the context's cache, or, for a context without one (a plug-in's own), evaluated
/// here.
fn pattern_column<'a>(
    ctx: &ShadingContext<'a>,
    name: &str,
    graph: &PatternGraph,
    arena: &'a Bump,
) -> &'a [Rgb] {
    ctx.eval_param(name)
        .unwrap_or_else(|| eval_uncached(graph, ctx, arena))
}

/// `graph` at every point of `ctx`, in the arena (for contexts without a cache).
pub(crate) fn eval_uncached<'a>(
    graph: &PatternGraph,
    ctx: &ShadingContext<'a>,
    arena: &'a Bump,
) -> &'a [Rgb] {
    let n = ctx.num_points();
    let out = arena.alloc_slice_fill_copy(n, Rgb::BLACK);
    let scratch = arena.alloc_slice_fill_copy(graph.scratch_len(n), Rgb::BLACK);
    pattern::eval_with(graph, ctx.p(), ctx.u(), ctx.v(), out, scratch);
    out
}
