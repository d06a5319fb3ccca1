//! The phase-function Bxdf: what a medium's factory returns for
//! [`ShadingMode::VolumeScatter`] contexts (RIS: a phase function is a Bxdf answering the
//! volume scatter query, RenderMan's `PxrDoubleHenyeyGreenstein` and its siblings). One
//! closure for every built-in medium and for plug-ins: a phase function the same at every
//! point, or Henyey-Greenstein with a mean cosine per point (a `g` pattern's column from the
//! context's cache, [`crate::scatter_patterns`]).
//!
//! Phase functions are sampled exactly (`p / pdf = 1`, Pharr et al., PBR 4th ed., 11.3), so a
//! sample's weight is 1, or the single-scattering albedo for a medium that leaves the albedo
//! to its phase function ([`PhaseBxdf::weighs_albedo`]); the built-in media apply the albedo
//! at their collisions instead.

use crate::scatter_patterns::{eval_uncached, hg_at, G_PARAM};
use glam::Vec3;
use risotto_components::{LobeSampled, Rgb};
use risotto_engine::plugin::*;
use risotto_systems::pattern::PatternGraph;
use risotto_systems::phase::PhaseFunction;
use risotto_systems::sampler::{next_2d_column, PathSampler};

/// Lobe bits of a phase-function sample.
pub const PHASE_LOBE: LobeSampled = LobeSampled(LobeSampled::SCATTER.0 | LobeSampled::DIFFUSE.0);

/// Where a [`PhaseBxdf`]'s phase function comes from.
#[derive(Clone, Copy, Debug)]
pub enum PhaseSource<'a> {
    /// The same phase function at every point.
    Uniform(PhaseFunction),
    /// Henyey-Greenstein with `g` per point: the first channel of point `i`'s value
    /// (clamped into `(-1, 1)`, [`crate::scatter_patterns::g_of`]).
    HgPerPoint(&'a [Rgb]),
}

impl PhaseSource<'_> {
    /// The phase function at point `i`.
    #[inline]
    fn at(&self, i: usize) -> PhaseFunction {
        match *self {
            PhaseSource::Uniform(p) => p,
            PhaseSource::HgPerPoint(g) => hg_at(g[i]),
        }
    }
}

/// A phase function as the Bxdf of [`ShadingMode::VolumeScatter`] contexts: value and pdf
/// `p(wo, wi)`, sampled exactly.
#[derive(Clone, Copy, Debug)]
pub struct PhaseBxdf<'a> {
    /// The phase function (per point or uniform).
    pub phase: PhaseSource<'a>,
    /// Single-scattering albedo `sigma_s / sigma_t`: the `albedo` AOV, and with
    /// [`weighs_albedo`](Self::weighs_albedo) every sample's weight and value.
    pub albedo: Rgb,
    /// Whether the albedo multiplies each sample's weight and each evaluated value: for a
    /// medium whose integrator leaves the albedo to its phase function. The built-in media
    /// weigh their collisions by the albedo themselves and say `false`.
    pub weighs_albedo: bool,
}

impl PhaseBxdf<'static> {
    /// `phase` at every point, weight 1 (`albedo` feeds the AOV only).
    pub fn new(phase: PhaseFunction, albedo: Rgb) -> Self {
        PhaseBxdf {
            phase: PhaseSource::Uniform(phase),
            albedo,
            weighs_albedo: false,
        }
    }

    /// `phase` at every point, each sample and value weighed by `albedo`.
    pub fn weighted(phase: PhaseFunction, albedo: Rgb) -> Self {
        PhaseBxdf {
            weighs_albedo: true,
            ..PhaseBxdf::new(phase, albedo)
        }
    }
}

impl Bxdf for PhaseBxdf<'_> {
    fn lobes(&self) -> LobeSampled {
        PHASE_LOBE
    }

    /// Three dimensions per point: the direction's two (through the column sampler, the
    /// same values as each sampler's `next_2d`, eight lanes at a time), then the lobe choice
    /// of a mixture (double Henyey-Greenstein).
    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    ) {
        const BLOCK: usize = 64;
        let vn = ctx.vn();
        let weight = if self.weighs_albedo {
            self.albedo
        } else {
            Rgb::WHITE
        };
        let mut u = [glam::Vec2::ZERO; BLOCK];
        for start in (0..samplers.len()).step_by(BLOCK) {
            let end = (start + BLOCK).min(samplers.len());
            let u = &mut u[..end - start];
            next_2d_column(&mut samplers[start..end], u);
            for (k, &u) in u.iter().enumerate() {
                let i = start + k;
                let u_lobe = samplers[i].next_1d();
                let (wi, pdf) = self.phase.at(i).sample(vn[i], u, u_lobe);
                // A sample whose pdf is not positive and finite leaves its row empty.
                if pdf > 0.0 && pdf.is_finite() {
                    out.wi[i] = wi;
                    out.weight[i] = weight;
                    out.pdf[i] = pdf;
                    out.lobe[i] = PHASE_LOBE;
                    out.eta[i] = 1.0;
                }
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
        let vn = ctx.vn();
        for i in 0..ctx.num_points() {
            let p = self.phase.at(i).eval(vn[i], wi[i]);
            value[i] = if self.weighs_albedo {
                self.albedo * p
            } else {
                Rgb::splat(p)
            };
            pdf[i] = p;
        }
    }

    fn albedo(&self, _ctx: &ShadingContext<'_>, out: &mut [Rgb]) {
        out.fill(self.albedo);
    }
}

/// The Bxdf of a medium's scattering points: `phase` everywhere, or with a `g` pattern
/// Henyey-Greenstein over the pattern's column from `ctx`'s cache (parameter [`G_PARAM`];
/// evaluated here for a context without one).
pub fn phase_bxdf<'a>(
    ctx: &ShadingContext<'a>,
    phase: PhaseFunction,
    g: Option<&PatternGraph>,
    albedo: Rgb,
    arena: &'a bumpalo::Bump,
) -> &'a mut (dyn Bxdf + 'a) {
    match g {
        None => arena.alloc(PhaseBxdf::new(phase, albedo)),
        Some(graph) => {
            let g = ctx
                .eval_param(G_PARAM)
                .unwrap_or_else(|| eval_uncached(graph, ctx, arena));
            arena.alloc(PhaseBxdf {
                phase: PhaseSource::HgPerPoint(g),
                albedo,
                weighs_albedo: false,
            })
        }
    }
}
