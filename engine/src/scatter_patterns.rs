//! Medium coefficients that patterns give at the scattering points (issue 11): the
//! single-scattering `albedo` of the homogeneous and heterogeneous interiors, and the mean
//! cosine `g` of a Henyey-Greenstein phase function (`phase = { type = "hg", g = { pattern
//! = .. } }`), each a pattern graph of the world position `P`.
//!
//! # Why at the scattering points
//! Neither coefficient changes where light collides, only what a collision does. The free
//! flight's density depends on `sigma_t` alone, and its weight at a collision is
//! `sigma_s T / p = albedo (sigma_t T / p)`: a medium samples its flights with albedo 1 and
//! multiplies each collision's weight by the albedo there (one evaluation per event). `g`
//! enters only the phase function at the event. So a homogeneous medium with a pattern
//! albedo or `g` keeps its exact transmittance, its closed-form shadow rays and its random
//! walk, and a heterogeneous one its trackers and majorants. For albedo the product is
//! exact: with a power-of-two albedo a pattern renders the same image bit for bit as the
//! constant (`tests/medium_patterns.rs` relies on it).
//!
//! # Where they are evaluated
//! - `albedo`, in the bounce and single-scattering paths: by the volume integrator at the
//!   rows that scatter, one column ([`albedo_column`]); in the random walk, at each event
//!   ([`PointPattern`]). Both count into the stats' `volume_pattern_evals`.
//! - `g`: by the phase Bxdf the material builds on the `VolumeScatter` context, through the
//!   context's parameter cache (parameter [`G_PARAM`], [`PhasePatternBxdf`]); in the random
//!   walk, at each event.
//!
//! A medium's patterns see `P` only: `u` and `v` belong to surfaces, and a graph that reads
//! them is an error at load time, as are values outside the coefficient's range by the
//! graph's interval bounds over all of space (`albedo` in `[0, 1]`, `g` in `(-1, 1)`).

use crate::builtin::eval_uncached;
use crate::media::{evaluate_phase, sample_phase, PhaseBxdf, PHASE_LOBE};
use crate::plugin::*;
use crate::scene_file::{ColourParam, MaterialParams, SceneError};
use glam::Vec3;
use risotto_components::{LobeSampled, Rays, Rgb};
use risotto_systems::pattern::{self, PatternGraph};
use risotto_systems::phase::PhaseFunction;
use risotto_systems::sampler::PathSampler;
use std::sync::Arc;

/// The parameter name under which a material exposes a medium's `g` pattern to
/// [`ShadingContext::eval_param`].
pub const G_PARAM: &str = "phase.g";

/// The error for a medium pattern that reads `u` / `v`.
const WORLD_P_ONLY: &str =
    "a medium's pattern sees the world position P only (u and v belong to surfaces)";

/// Reads a medium's `albedo` key: a colour in `[0, 1]` (default 1), or a pattern of `P`
/// bounded in `[0, 1]`. Returns the constant albedo (1 with a pattern, which then gives it)
/// and the pattern.
pub(crate) fn parse_albedo(
    t: &MaterialParams,
) -> Result<(Rgb, Option<Arc<PatternGraph>>), SceneError> {
    match t.colour_or_pattern("albedo", Rgb::WHITE, [0.0, 1.0])? {
        ColourParam::Constant(c) => Ok((c, None)),
        ColourParam::Pattern(g) if g.reads_uv() => Err(t.error(Some("albedo"), WORLD_P_ONLY)),
        ColourParam::Pattern(g) => Ok((Rgb::WHITE, Some(Arc::new(g)))),
    }
}

/// Reads a medium's `phase` key (absent: isotropic). `g` of an `hg` phase may be a grey
/// pattern of `P` whose interval bounds lie in `(-1, 1)`: the phase function is then
/// Henyey-Greenstein with `g` read per scattering point: the returned function is HG with
/// `g = 0`, a placeholder no point uses, and the pattern is returned beside it.
pub(crate) fn parse_phase(
    t: &MaterialParams,
) -> Result<(PhaseFunction, Option<Arc<PatternGraph>>), SceneError> {
    let Some(p) = t.table("phase")? else {
        return Ok((PhaseFunction::Isotropic, None));
    };
    if !p.is_table("g") {
        if p.is_table("g1") || p.is_table("g2") || p.is_table("blend") {
            return Err(p.error(
                None,
                "a pattern is taken for the `g` of an `hg` phase function only; `double_hg` \
                 takes numbers",
            ));
        }
        return Ok((crate::load::phase_function(&p)?, None));
    }
    let kind = p.string("type", None)?;
    if kind != "hg" {
        return Err(p.error(
            Some("g"),
            format!("a pattern `g` belongs to `type = \"hg\"`, not \"{kind}\""),
        ));
    }
    p.deny_unknown(&["type", "g"])?;
    let graph = p.pattern("g")?.expect("checked: a table");
    if graph.reads_uv() {
        return Err(p.error(Some("g"), WORLD_P_ONLY));
    }
    if !graph.is_grey() {
        return Err(p.error(
            Some("g"),
            "a `g` pattern must be grey (every colour in it a single number): g is one mean \
             cosine per point",
        ));
    }
    let (lo, hi) = pattern::bounds(&graph, Vec3::NEG_INFINITY, Vec3::INFINITY);
    // NaN reads as out of range.
    if !(lo.r > -1.0 && hi.r < 1.0) {
        return Err(p.error(
            Some("g"),
            format!(
                "the `g` pattern may reach [{}, {}] (interval bounds over all of space), but g \
                 must lie in (-1, 1): wrap it in `remap` (e.g. to = [-0.9, 0.9])",
                lo.r, hi.r
            ),
        ));
    }
    Ok((
        PhaseFunction::HenyeyGreenstein { g: 0.0 },
        Some(Arc::new(graph)),
    ))
}

/// The albedo pattern at the points `p` (world positions), into `out`.
pub fn albedo_column(graph: &PatternGraph, p: &[Vec3], out: &mut [Rgb]) {
    let zeros = vec![0.0f32; p.len()];
    pattern::eval(graph, p, &zeros, &zeros, out);
}

/// Scales `weight[i]` by the albedo pattern at the collision `o_i + t_i d_i` of every ray
/// `i` of `rays` with `collides[i]`: the collision weight `albedo (sigma_t T / p)` of a
/// flight sampled at albedo 1 (module docs). Returns the evaluations made (one per such
/// ray), which the caller counts.
pub fn scale_by_albedo(
    graph: &PatternGraph,
    rays: &Rays,
    t: &[f32],
    collides: &[bool],
    weight: &mut [Rgb],
) -> u64 {
    let rows: Vec<usize> = (0..collides.len()).filter(|&i| collides[i]).collect();
    if rows.is_empty() {
        return 0;
    }
    let p: Vec<Vec3> = rows
        .iter()
        .map(|&i| rays.origin[i] + rays.direction[i] * t[i])
        .collect();
    let mut albedo = vec![Rgb::BLACK; rows.len()];
    albedo_column(graph, &p, &mut albedo);
    for (&i, a) in rows.iter().zip(&albedo) {
        weight[i] *= *a;
    }
    rows.len() as u64
}

/// One pattern evaluated at one point at a time, with its scratch kept between calls (the
/// random walk's events).
pub struct PointPattern<'g> {
    graph: &'g PatternGraph,
    scratch: Vec<Rgb>,
    /// Evaluations made.
    pub evals: u64,
}

impl<'g> PointPattern<'g> {
    /// An evaluator of `graph`.
    pub fn new(graph: &'g PatternGraph) -> Self {
        PointPattern {
            graph,
            scratch: vec![Rgb::BLACK; graph.scratch_len(1)],
            evals: 0,
        }
    }

    /// The graph's value at world position `p`.
    pub fn at(&mut self, p: Vec3) -> Rgb {
        let mut out = [Rgb::BLACK];
        pattern::eval_with(
            self.graph,
            &[p],
            &[0.0],
            &[0.0],
            &mut out,
            &mut self.scratch,
        );
        self.evals += 1;
        out[0]
    }
}

/// A pattern's value as a Henyey-Greenstein mean cosine: within `(-1, 1)` by the load-time
/// bounds, clamped there against rounding (NaN: 0).
#[inline]
pub fn g_of(value: Rgb) -> f32 {
    const G_MAX: f32 = 1.0 - 1e-6;
    let g = value.r;
    if g.is_nan() {
        0.0
    } else {
        g.clamp(-G_MAX, G_MAX)
    }
}

/// The Henyey-Greenstein phase function of a `g` pattern's value.
#[inline]
pub fn hg_at(value: Rgb) -> PhaseFunction {
    PhaseFunction::HenyeyGreenstein { g: g_of(value) }
}

/// Henyey-Greenstein with `g` per point (the first channel of the `g` column, a grey
/// pattern evaluated through the context's cache): as [`PhaseBxdf`] at each point.
#[derive(Clone, Copy, Debug)]
pub struct PhasePatternBxdf<'a> {
    /// `g` per point of the context.
    pub g: &'a [Rgb],
    /// Single-scattering albedo, for the `albedo` AOV.
    pub albedo: Rgb,
}

impl Bxdf for PhasePatternBxdf<'_> {
    fn lobes(&self) -> LobeSampled {
        PHASE_LOBE
    }
    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    ) {
        sample_phase(ctx, samplers, out, |i| hg_at(self.g[i]));
    }
    fn evaluate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        wi: &[Vec3],
        value: &mut [Rgb],
        pdf: &mut [f32],
    ) {
        evaluate_phase(ctx, wi, value, pdf, |i| hg_at(self.g[i]));
    }
    fn albedo(&self, _ctx: &ShadingContext<'_>, out: &mut [Rgb]) {
        out.fill(self.albedo);
    }
}

/// The Bxdf of a medium's scattering points: [`PhaseBxdf`], or with a `g` pattern a
/// [`PhasePatternBxdf`] over the pattern's column from `ctx`'s cache (evaluated here for a
/// context without one).
pub(crate) fn phase_bxdf<'a>(
    ctx: &ShadingContext<'a>,
    phase: PhaseFunction,
    g: Option<&PatternGraph>,
    albedo: Rgb,
    arena: &'a bumpalo::Bump,
) -> &'a mut (dyn Bxdf + 'a) {
    match g {
        None => arena.alloc(PhaseBxdf { phase, albedo }),
        Some(graph) => {
            let g = ctx
                .eval_param(G_PARAM)
                .unwrap_or_else(|| eval_uncached(graph, ctx, arena));
            arena.alloc(PhasePatternBxdf { g, albedo })
        }
    }
}
