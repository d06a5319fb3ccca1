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
//!   context's parameter cache (parameter [`G_PARAM`], [`crate::phase::PhaseBxdf`]); in the random
//!   walk, at each event.
//!
//! A medium's patterns see `P` only: `u` and `v` belong to surfaces, and a graph that reads
//! them is an error at load time, as are values outside the coefficient's range by the
//! graph's interval bounds over all of space (`albedo` in `[0, 1]`, `g` in `(-1, 1)`).

use glam::Vec3;
use risotto_components::{Rays, Rgb};
use risotto_engine::plugin::*;
use risotto_systems::pattern::{self, PatternGraph};
use risotto_systems::phase::PhaseFunction;

/// The parameter name under which a material exposes a medium's `g` pattern to
/// [`ShadingContext::eval_param`].
pub const G_PARAM: &str = "phase.g";

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

/// `graph` at every point of `ctx`, in the arena (for contexts without a cache).
pub fn eval_uncached<'a>(
    graph: &PatternGraph,
    ctx: &ShadingContext<'a>,
    arena: &'a bumpalo::Bump,
) -> &'a [Rgb] {
    let n = ctx.num_points();
    let out = arena.alloc_slice_fill_copy(n, Rgb::BLACK);
    let scratch = arena.alloc_slice_fill_copy(graph.scratch_len(n), Rgb::BLACK);
    pattern::eval_with(graph, ctx.p(), ctx.u(), ctx.v(), out, scratch);
    out
}
