//! The path-continuation system: Russian roulette and depth limits, and the next ray of every
//! path that goes on from a group of scattering vertices.

use crate::bxdf_samples::BxdfSamples;
use crate::ray::{offset_origin, InteriorBoundaries};
use glam::Vec3;
use risotto_components::{RayColumns, Rays, Rgb, ShadingPoints, StackEvent};
use std::ops::Range;

/// A group of scattering vertices: shading points and the rays that arrived there.
#[derive(Clone)]
pub struct Vertices<'a> {
    /// The shading points (rows `range` are the group's).
    pub points: &'a ShadingPoints,
    /// The group's rows.
    pub range: Range<usize>,
    /// True for surface points (rays leave off the surface, to the side they go to); false
    /// for points inside a volume (rays start at the point).
    pub on_surface: bool,
    /// Whether the points' `terminator_lift` column may be non-zero (the scene has meshes
    /// that ask for the shadow-terminator offset, `crate::terminator`): rays leaving a
    /// surface point to the viewer's side (reflected and shadow rays) then start from
    /// `p + terminator_lift`. When false the column is not read.
    pub terminator_lift: bool,
    /// The rays that arrived at the points (`points.ray_id` indexes it).
    pub incoming: &'a Rays,
}

impl Vertices<'_> {
    /// The point rays leave point `i` (a row of `points`) from in direction `wi`, before the
    /// surface offset: `p + terminator_lift` when [`Self::terminator_lift`] is set and the
    /// ray goes to the viewer's side by the geometric or the shading normal (a reflected or
    /// shadow ray; the shading stage keeps no direction the shading normal calls
    /// transmission and the geometric one reflection), else `p` (transmitted rays leave
    /// from the flat triangle they cross).
    #[inline(always)]
    pub fn leaving_point(&self, i: usize, wi: glam::Vec3) -> glam::Vec3 {
        let pts = self.points;
        let p = pts.p[i];
        if self.terminator_lift && self.lifted(i, wi) {
            p + pts.terminator_lift[i]
        } else {
            p
        }
    }

    /// Whether a ray leaving point `i` in direction `wi` goes to the viewer's side by the
    /// geometric or the shading normal (where [`Self::leaving_point`] lifts it).
    #[inline(always)]
    pub fn lifted(&self, i: usize, wi: glam::Vec3) -> bool {
        let pts = self.points;
        let (ng, nn, vn) = (pts.ng[i], pts.nn[i], pts.vn[i]);
        wi.dot(ng) * vn.dot(ng) > 0.0 || wi.dot(nn) * vn.dot(nn) > 0.0
    }
}

/// Path-length limits (Mitsuba's `max_depth` convention: a path of `k` segments has `k - 1`
/// scattering vertices) and the sampler budget of a vertex.
#[derive(Clone, Copy, Debug)]
pub struct PathLimits {
    /// Maximum number of segments; `u32::MAX` = unbounded.
    pub max_depth: u32,
    /// Scattering vertices after which Russian roulette starts.
    pub rr_depth: u32,
    /// Sampler dimensions one vertex uses: the next ray starts this many further on.
    pub dims_per_vertex: u32,
}

/// What [`continue_paths`] did with a group's points.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Continuations {
    /// Rays written.
    pub written: usize,
    /// Paths ended because the next segment would exceed `max_depth`.
    pub max_depth: usize,
    /// Paths ended because the sample had pdf 0 or a black (or non-finite) weight.
    pub absorbed: usize,
    /// Paths ended by Russian roulette.
    pub roulette: usize,
    /// Paths ended at their [`MAX_PATH_VERTICES`]-th scattering vertex (only a `max_depth`
    /// above it, or an unbounded one, lets a path get there).
    pub depth_limit: usize,
}

/// The most scattering vertices a path can have, whatever `max_depth` says: the range of the
/// rays' `depth` column (`u16`, the vertices before the ray). A path ends at this vertex
/// (counted in [`Continuations::depth_limit`]) where `max_depth` would let it go on: where
/// that is at least `MAX_PATH_VERTICES + 1` segments, or unbounded (`-1`). Only light that cannot leave a region gets
/// near it: paths in a closed room of albedo-1 walls, or frozen in an albedo-1 medium whose
/// mean free path is below the resolution of its coordinates, whose throughput stays 1 so
/// that Russian roulette never ends them; without the limit they would go on until a
/// numerical leak let them out, or for ever.
pub const MAX_PATH_VERTICES: u32 = u16::MAX as u32;

/// The probability that Russian roulette lets a path go on, given `rr_throughput`: the
/// largest channel of its throughput times `eta^2` (see [`continue_paths`]). Cycles' rule
/// (`path_state_continuation_probability`): `min(sqrt(rr_throughput), 1)`, whose survivors
/// carry weight `sqrt(rr_throughput)` instead of 1.
///
/// Against pbrt-v4's and Mitsuba 3's `q = rr_throughput`, a path at throughput 1/4 survives
/// with probability 1/2 instead of 1/4: the deep bounces of a dim-walled room or an albedo-0.8
/// smoke still carry a good part of the image, and killing three quarters of them where half
/// would do buys little time for much variance (the equal-spp comparison on the Mitsuba suite
/// is in benches/README.md, "Russian roulette"). Either rule is unbiased. A path whose
/// throughput cannot fall below 1 (an albedo-1 medium, a white furnace) is never culled,
/// where Mitsuba's `min(q, 0.95)` kills 5% per bounce and inflates the survivors' weights by
/// 1/0.95: same expectation, much more variance. `NaN` in gives `NaN` out, which the
/// caller's `q < 1` reads as "no roulette" (non-finite throughput is the film's to drop and
/// count).
#[inline]
pub fn survival_probability(rr_throughput: f32) -> f32 {
    if rr_throughput >= 1.0 {
        1.0
    } else {
        rr_throughput.sqrt()
    }
}

/// Writes to `out` from row `start` on the ray each vertex continues its path with
/// (direction, weight, pdf and lobe from `samples`, Russian roulette with `u4[k][3]`), unless
/// the path reached `max_depth`, the sample was absorbed or the roulette ended it. `boundaries`
/// (when volume stacks can be non-empty) copies the stacks and lets a transmitted ray cross
/// the surface's interior boundary, appending every crossing that corrupts the stack (leaving
/// a volume the ray was not in, entering one it was already in) to `stack_errors`; `None`
/// means every stack is empty, and the rows' stacks are left as they are. The caller sets
/// `tmin` and `tmax`.
///
/// Russian roulette: survival probability [`survival_probability`] of `max(beta) * eta^2`, the
/// throughput after the vertex with the radiance scaling of refraction undone (pbrt-v4's
/// `VolPathIntegrator`), and no roulette when that is at least 1.
///
/// A first pass decides which points continue and writes the columns that decision computes
/// (throughput, `eta_scale`, depth, lobe, pdf, point index); a second pass, driven by the
/// point index (increasing, so the point columns are still read in order), writes the
/// geometry and what the path carries over: one pass doing both kept about twenty column
/// pointers live and spilled to the stack. The stack pass, when needed, follows.
#[allow(
    clippy::too_many_arguments,
    reason = "the columns it reads and writes, named"
)]
pub fn continue_paths(
    limits: PathLimits,
    from: Vertices<'_>,
    samples: &BxdfSamples,
    u4: &[[f32; 4]],
    boundaries: Option<InteriorBoundaries<'_>>,
    stack_errors: &mut Vec<(u32, StackEvent)>,
    out: &mut RayColumns<'_>,
    start: usize,
) -> Continuations {
    let Vertices {
        points: pts,
        range,
        on_surface,
        terminator_lift,
        incoming,
    } = from;
    let lift = terminator_lift && on_surface;
    let ray_id = &pts.ray_id[range.clone()];
    let (m, n) = (ray_id.len(), incoming.len());
    let rows = start..start + m;
    let (o_origin, o_direction, o_path, o_throughput, o_lobe, o_depth, o_passes) = (
        &mut out.origin[rows.clone()],
        &mut out.direction[rows.clone()],
        &mut out.path[rows.clone()],
        &mut out.throughput[rows.clone()],
        &mut out.lobe[rows.clone()],
        &mut out.depth[rows.clone()],
        &mut out.passes[rows.clone()],
    );
    let (o_pdf, o_eta_scale, o_dimension, o_ctx, o_prev_p, o_stack) = (
        &mut out.pdf[rows.clone()],
        &mut out.eta_scale[rows.clone()],
        &mut out.dimension[rows.clone()],
        &mut out.shading_ctx_index[rows.clone()],
        &mut out.prev_p[rows.clone()],
        &mut out.volume_stack[rows],
    );
    // Pass 1: which points continue, with which throughput.
    let (in_throughput, in_eta_scale, in_depth) = (
        &incoming.throughput[..n],
        &incoming.eta_scale[..n],
        &incoming.depth[..n],
    );
    let (s_pdf, s_weight, s_lobe, s_eta, rr_u) = (
        &samples.pdf[..m],
        &samples.weight[..m],
        &samples.lobe[..m],
        &samples.eta[..m],
        &u4[..m],
    );
    let mut done = Continuations::default();
    let (p, ng, p_offset, s_wi) = (
        &pts.p[range.clone()][..m],
        &pts.ng[range.clone()][..m],
        &pts.p_offset[range.clone()][..m],
        &samples.wi[..m],
    );
    let (in_path, in_passes, in_dimension) = (
        &incoming.path[..n],
        &incoming.passes[..n],
        &incoming.dimension[..n],
    );
    let segment_cap = limits.max_depth.min(MAX_PATH_VERTICES);
    let mut count = 0;
    for k in 0..m {
        let r = ray_id[k] as usize;
        // The next segment must fit in max_depth, and its vertex count in the depth column
        // (`depth + 1 >= MAX_PATH_VERTICES`, i.e. `depth + 2 > MAX_PATH_VERTICES`): one
        // test against the smaller bound, then which one it was.
        if in_depth[r] as u32 + 2 > segment_cap {
            if in_depth[r] as u32 + 2 > limits.max_depth {
                done.max_depth += 1;
            } else {
                done.depth_limit += 1;
            }
            continue;
        }
        let pdf = s_pdf[k];
        let weight = s_weight[k];
        if pdf <= 0.0 || is_black_or_not_finite(weight) {
            done.absorbed += 1;
            continue;
        }
        let mut throughput = in_throughput[r] * weight;
        let lobe = s_lobe[k];
        let eta = s_eta[k];
        let eta_scale = in_eta_scale[r] * if lobe.is_transmit() { eta * eta } else { 1.0 };
        let depth = in_depth[r] + 1;
        if depth as u32 > limits.rr_depth {
            let q = survival_probability(throughput.max_channel() * eta_scale);
            if q < 1.0 {
                if rr_u[k][3] >= q {
                    done.roulette += 1;
                    continue;
                }
                throughput *= 1.0 / q;
            }
        }
        o_throughput[count] = throughput;
        o_eta_scale[count] = eta_scale;
        o_depth[count] = depth;
        o_lobe[count] = lobe;
        o_pdf[count] = if lobe.is_specular() { 0.0 } else { pdf };
        o_ctx[count] = k as u32;
        count += 1;
    }
    let ctx = &o_ctx[..count];
    // Pass 2: geometry and carried-over columns of the continuing rays.
    let (o_origin, o_direction, o_prev_p) = (
        &mut o_origin[..count],
        &mut o_direction[..count],
        &mut o_prev_p[..count],
    );
    let (o_path, o_passes, o_dimension) = (
        &mut o_path[..count],
        &mut o_passes[..count],
        &mut o_dimension[..count],
    );
    for (j, &k) in ctx.iter().enumerate() {
        let k = k as usize;
        let r = ray_id[k] as usize;
        o_path[j] = in_path[r];
        o_passes[j] = in_passes[r];
        o_dimension[j] = in_dimension[r] + limits.dims_per_vertex;
        let (p, wi) = (p[k], s_wi[k]);
        o_origin[j] = if on_surface {
            offset_origin(p, ng[k], p_offset[k], wi)
        } else {
            p
        };
        o_direction[j] = wi;
        o_prev_p[j] = p;
    }
    // Pass 2b, only with the shadow-terminator offset: reflected rays of lifted points
    // leave from the smooth surface (`crate::terminator`). Its own pass keeps pass 2 as
    // lean as in scenes without it.
    if lift {
        let from = Vertices {
            points: pts,
            range: range.clone(),
            on_surface,
            terminator_lift,
            incoming,
        };
        lift_origins(&from, ctx, o_direction, o_origin);
    }
    // Pass 3: volume stacks; a transmitted ray crosses the surface's interior boundary.
    if let Some(b) = boundaries {
        let in_stack = &incoming.volume_stack[..n];
        let rows = o_stack[..count].iter_mut().zip(&o_lobe[..count]);
        for (((stack, &lobe), &k), &wi) in rows.zip(ctx).zip(&o_direction[..count]) {
            let k = k as usize;
            *stack = in_stack[ray_id[k] as usize].clone();
            let i = range.start + k;
            let shape = pts.shape[i];
            let crosses = if b.by_geometric_side {
                let ng = pts.ng[i];
                (wi.dot(ng) > 0.0) != (pts.vn[i].dot(ng) > 0.0)
            } else {
                lobe.is_transmit()
            };
            if on_surface && crosses {
                if let Some(e @ (StackEvent::UnmatchedExit | StackEvent::EnteredAgain)) =
                    b.cross(stack, shape, pts.front_face[i])
                {
                    stack_errors.push((shape, e))
                }
            }
        }
    }
    done.written = count;
    done
}

/// Pass 2b of [`continue_paths`]: the origin of each written ray `j` (from point
/// `ctx[j]` of the group, direction `direction[j]`) recomputed from
/// [`Vertices::leaving_point`]. Out of line, so that scenes without the offset run the same
/// pass 2 as before it existed.
#[inline(never)]
fn lift_origins(from: &Vertices<'_>, ctx: &[u32], direction: &[Vec3], origin: &mut [Vec3]) {
    let pts = from.points;
    for ((&k, &wi), o) in ctx.iter().zip(direction).zip(origin) {
        let i = from.range.start + k as usize;
        *o = offset_origin(from.leaving_point(i, wi), pts.ng[i], pts.p_offset[i], wi);
    }
}

/// `weight.is_black() || !weight.is_finite()`, exactly, in fewer instructions: `x * 0` is
/// (signed) zero for finite `x` and NaN for infinities and NaN, so the sum of the three
/// products is zero exactly when every channel is finite; then the sum of the absolute
/// values is zero exactly when every channel is (a sum of non-negative numbers is at least
/// its largest term; overflow gives infinity, not zero).
#[inline]
pub fn is_black_or_not_finite(w: Rgb) -> bool {
    let finite = w.r * 0.0 + w.g * 0.0 + w.b * 0.0 == 0.0;
    !finite || w.r.abs() + w.g.abs() + w.b.abs() == 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn survival_is_the_square_root_below_one() {
        for (x, want) in [
            (0.25f32, 0.5f32),
            (0.01, 0.1),
            (0.0, 0.0),
            (1.0, 1.0),
            (7.0, 1.0),
        ] {
            assert_eq!(survival_probability(x), want, "{x}");
        }
        // Never below pbrt's `q = x`, and survivors never weigh more than 1 (`x / q <= 1`).
        for i in 1..1000 {
            let x = i as f32 / 1000.0;
            let q = survival_probability(x);
            assert!(q >= x && q <= 1.0 && x / q <= 1.0 + 1e-6, "{x} -> {q}");
        }
        // Non-finite throughput is left to the film (counted there), not culled silently.
        assert!(survival_probability(f32::NAN).is_nan());
    }

    #[test]
    fn paths_end_at_the_vertex_limit_without_wrapping_their_depth() {
        // Two volume points reached by rays of depth MAX - 2 and MAX - 1: vertices MAX - 1
        // and MAX of their paths, throughput 1 (no roulette), an unbounded max_depth.
        let (p, d) = (glam::Vec3::ZERO, glam::Vec3::Z);
        let mut incoming = Rays::default();
        for depth in [MAX_PATH_VERTICES - 2, MAX_PATH_VERTICES - 1] {
            incoming.push(risotto_components::RayRow {
                direction: d,
                throughput: Rgb::WHITE,
                eta_scale: 1.0,
                depth: depth as u16,
                ..Default::default()
            });
        }
        let mut points = ShadingPoints::default();
        points.extend_in_volume(&[p; 2], &[d; 2], 0);
        let mut samples = BxdfSamples::default();
        samples.reset(2);
        for i in 0..2 {
            (samples.wi[i], samples.weight[i], samples.pdf[i]) = (d, Rgb::WHITE, 1.0);
            samples.eta[i] = 1.0;
        }
        let continue_with = |max_depth: u32| {
            let mut next = Rays::default();
            let from = Vertices {
                points: &points,
                range: 0..2,
                on_surface: false,
                terminator_lift: false,
                incoming: &incoming,
            };
            let limits = PathLimits {
                max_depth,
                rr_depth: 5,
                dims_per_vertex: 8,
            };
            let mut rows = next.reuse_rows(2);
            let done = continue_paths(
                limits,
                from,
                &samples,
                &[[0.0; 4]; 2],
                None,
                &mut Vec::new(),
                &mut rows,
                0,
            );
            (done, rows.depth[0])
        };
        // Unbounded: the first goes on at depth MAX - 1, the second ends at the limit (its
        // next depth, MAX, would be wrapped to 0 by the u16 column in release builds).
        let (done, depth) = continue_with(u32::MAX);
        assert_eq!(
            (done.written, done.depth_limit, done.max_depth),
            (1, 1, 0),
            "{done:?}"
        );
        assert_eq!(depth as u32, MAX_PATH_VERTICES - 1);
        // A max_depth that ends the second path first counts as max_depth, not the limit.
        let (done, _) = continue_with(MAX_PATH_VERTICES);
        assert_eq!(
            (done.written, done.depth_limit, done.max_depth),
            (1, 0, 1),
            "{done:?}"
        );
    }

    #[test]
    fn black_or_not_finite_is_exact() {
        for (w, want) in [
            (Rgb::BLACK, true),
            (Rgb::new(0.0, -0.0, 0.0), true),
            (Rgb::new(0.0, 1e-30, 0.0), false),
            (Rgb::new(f32::NAN, 1.0, 1.0), true),
            (Rgb::new(1.0, f32::INFINITY, 1.0), true),
            (Rgb::new(f32::MAX, f32::MAX, f32::MAX), false),
        ] {
            assert_eq!(is_black_or_not_finite(w), want, "{w:?}");
        }
    }
}
