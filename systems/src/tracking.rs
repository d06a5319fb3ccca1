//! Null-collision estimators for heterogeneous media along one ray: delta (Woodcock)
//! tracking of free-flight distances, and delta, ratio and residual ratio tracking of
//! transmittance (Novák, Selle and Jarosz 2014, "Residual ratio tracking for estimating
//! attenuation in participating media").
//!
//! # Conventions
//! - A ray is given by its **majorant segments** in order ([`MajorantSegment`]: `[t0, t1)`,
//!   a bound `majorant >= sigma_t(t)` and a `minorant <= sigma_t(t)` on it, extinction units,
//!   per world unit), e.g. from [`crate::grid::MajorantGrid::traverse`] scaled by the
//!   medium's density scale. Parts of the ray not covered by a segment have `sigma_t = 0`.
//! - `sigma_t(t)` is the extinction at ray parameter `t` (grey: one channel).
//! - `rand()` draws the next uniform number in `[0, 1)`; each estimator draws as many as it
//!   needs (two per tentative collision for delta tracking; one for ratio tracking, and
//!   one more for each Russian-roulette decision on a low estimate, see [`ratio_tracking`]).
//! - A sampled `sigma_t` above its segment's majorant is a **majorant violation**: counted
//!   (the result's `violations`), never clamped silently; the estimators stay finite (the
//!   null-collision probability is then taken as 0, the ratio-tracking factor can become
//!   negative, which is what the unbiased estimator with a wrong bound computes).
//! - Emissive media ([`delta_tracking_emitting`], [`ratio_tracking_emitting`]): `j(t)` is
//!   the **emission coefficient**, radiance per unit length (the source term of
//!   `dL/ds = -sigma_t L + j + ...`), per RGB channel; the estimators return the radiance
//!   emitted along the segments that reaches their start, `int T(t) j(t) dt`.

use crate::grid::MajorantSegment;
use crate::medium::sample_optical_depth;
use risotto_components::Rgb;

pub mod dense;
use dense::{dense_flight, DenseSegments, TrackAll};

/// `x > 0` (false for NaN).
#[inline]
fn positive(x: f32) -> bool {
    x > 0.0
}

/// `t + depth / rate` for `rate > 0`: where the optical depth `depth` of tentative
/// collisions runs out, at least one ulp past `t` (so that tracking ends even where steps
/// underflow against `t`).
#[inline]
fn advance(t: f32, rate: f32, depth: f32) -> f32 {
    let next = t + depth / rate;
    if next > t {
        next
    } else {
        f32::from_bits(t.max(0.0).to_bits() + 1)
    }
}

/// The optical depth of tentative collisions still to go before the next one, carried from
/// segment to segment along one ray (`NaN`: none drawn yet).
///
/// Tentative collisions form a Poisson process whose rate is piecewise constant (each
/// segment's bound), so the next one lies where the integrated rate reaches an `Exp(1)`
/// draw; a segment that ends first consumes `rate x length` of the draw and the rest carries
/// into the next segment. That is the same process as restarting the exponential at every
/// segment boundary (memorylessness), with one random number and one logarithm per
/// collision instead of one more per segment crossed: a fine majorant grid then costs only
/// its DDA steps.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DepthToNext(f32);

impl DepthToNext {
    /// No draw yet.
    pub(crate) const NONE: DepthToNext = DepthToNext(f32::NAN);
}

/// The control extinction of residual ratio tracking on `seg`: its minorant, clamped into
/// `[0, majorant]` (a bound from rounding may cross it); 0 without `residual` (plain ratio
/// tracking).
#[inline]
pub(crate) fn control_extinction(seg: &MajorantSegment, residual: bool) -> f32 {
    if residual {
        seg.minorant.clamp(0.0, seg.majorant.max(0.0))
    } else {
        0.0
    }
}

/// Full transmittance estimate below which ratio tracking plays Russian roulette on it.
const ROULETTE_BELOW: f32 = 0.05;
/// The probability that the roulette ends a low estimate.
const ROULETTE_END: f32 = 0.75;

/// Russian roulette on a ratio-tracking estimate (pbrt-v4's `VolPathIntegrator::SampleLd`,
/// with its 0.05 and 0.75): `low` says the estimate's full value (the running product
/// times the control's `exp(-int control)`) is below [`ROULETTE_BELOW`]. The factor to
/// multiply the running product by: 1 when not `low`; else 0 with probability
/// [`ROULETTE_END`] (one random number; the walk then stops) and `1 / (1 - ROULETTE_END)`
/// otherwise. Its expectation is 1 given the walk so far, so the estimate stays unbiased;
/// a shadow ray through an optically thick medium then stops a few collisions after its
/// estimate has become negligible, instead of tracking to the far side. An estimate of
/// exactly 0 stops without a draw.
#[inline]
pub(crate) fn roulette(low: bool, zero: bool, rand: &mut impl FnMut() -> f32) -> f32 {
    if !low {
        1.0
    } else if zero || rand() < ROULETTE_END {
        0.0
    } else {
        1.0 / (1.0 - ROULETTE_END)
    }
}

/// The running product below which a segment's roulette plays, for the control's optical
/// depth `control_depth` through the segment's end ([`roulette`]; a bound that ignores the
/// part of the control still to come inside the segment would be as unbiased).
#[inline]
pub(crate) fn roulette_limit(control_depth: f32) -> f32 {
    ROULETTE_BELOW * control_depth.exp()
}

/// The outcome of [`delta_tracking`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FreeFlight {
    /// The real collision's distance when `collided`, else the end of the last segment.
    pub t: f32,
    /// A real collision happened before the segments ended.
    pub collided: bool,
    /// Null (fictitious) collisions on the way.
    pub nulls: u32,
    /// Sampled `sigma_t` above the segment's majorant.
    pub violations: u32,
}

/// Visits the tentative collisions of a segment sampled from `bound` (> 0) on
/// `[seg.t0, seg.t1)`, continuing the ray's carried `depth`: `visit(t, s, rand)` gets the distance, `sigma_t` there and the random
/// source; it returns `false` to stop the walk (and `tentative` returns `Some(t)`). Counts
/// majorant violations (`sigma_t > seg.majorant`) into `violations`.
pub(crate) fn tentative<R: FnMut() -> f32>(
    seg: &MajorantSegment,
    bound: f32,
    sigma_t: &mut impl FnMut(f32) -> f32,
    rand: &mut R,
    violations: &mut u32,
    depth: &mut DepthToNext,
    mut visit: impl FnMut(f32, f32, &mut R) -> bool,
) -> Option<f32> {
    if !positive(bound) {
        // No collisions here: the draw carries over unchanged.
        return None;
    }
    let mut t = seg.t0;
    loop {
        if depth.0.is_nan() {
            depth.0 = sample_optical_depth(rand());
        }
        let next = advance(t, bound, depth.0);
        if next >= seg.t1 {
            // Rounding may take the rest a hair below 0: the next segment then collides at
            // its start, a shift far below one ulp of optical depth.
            depth.0 = (depth.0 - (seg.t1 - t) * bound).max(0.0);
            return None;
        }
        *depth = DepthToNext::NONE;
        t = next;
        let s = sigma_t(t);
        if s > seg.majorant {
            *violations += 1;
        }
        if !visit(t, s, rand) {
            return Some(t);
        }
    }
}

/// Delta tracking (Woodcock et al. 1965; Novák et al. 2018, sec. 4.1): samples the distance
/// to the next real collision with density `sigma_t(t) exp(-int_0^t sigma_t)`, or passes the
/// segments with probability `exp(-int sigma_t)` (the transmittance). Tentative collisions
/// are sampled from each segment's majorant (one exponential draw carried across segment
/// boundaries: the rest of a draw carries into the next segment) and accepted with probability
/// `sigma_t(t) / majorant`.
pub fn delta_tracking(
    segments: impl IntoIterator<Item = MajorantSegment>,
    sigma_t: impl FnMut(f32) -> f32,
    rand: impl FnMut() -> f32,
) -> FreeFlight {
    delta_tracking_dense(segments, sigma_t, &mut TrackAll, rand)
}

/// [`delta_tracking`] that integrates the segments `dense` takes exactly instead of
/// tracking them ([`dense`]: the same distance distribution, at a cost bounded by the
/// segment's exact depth, not its `majorant x length`).
pub fn delta_tracking_dense(
    segments: impl IntoIterator<Item = MajorantSegment>,
    mut sigma_t: impl FnMut(f32) -> f32,
    dense: &mut impl DenseSegments,
    mut rand: impl FnMut() -> f32,
) -> FreeFlight {
    let mut out = FreeFlight::default();
    let mut depth = DepthToNext::NONE;
    for seg in segments {
        out.t = seg.t1;
        if dense.takes(&seg) {
            if let Some(t) = dense_flight(dense, &seg, &mut depth, &mut rand) {
                out.t = t;
                out.collided = true;
                return out;
            }
            continue;
        }
        let mut nulls = 0;
        let hit = tentative(
            &seg,
            seg.majorant,
            &mut sigma_t,
            &mut rand,
            &mut out.violations,
            &mut depth,
            |_, s, rand| {
                let null = rand() * seg.majorant >= s;
                nulls += null as u32;
                null
            },
        );
        out.nulls += nulls;
        if let Some(t) = hit {
            out.t = t;
            out.collided = true;
            return out;
        }
    }
    out
}

/// A transmittance estimate.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Transmittance {
    /// The estimate (its expectation is `exp(-int sigma_t)`).
    pub value: f32,
    /// Tentative collisions evaluated.
    pub nulls: u32,
    /// Sampled `sigma_t` above the segment's majorant.
    pub violations: u32,
}

/// Delta-tracking transmittance: 1 if a free flight passes the segments, else 0 (the
/// cheapest estimator: it stops at the first real collision, with the most variance).
pub fn delta_tracking_transmittance(
    segments: impl IntoIterator<Item = MajorantSegment>,
    sigma_t: impl FnMut(f32) -> f32,
    rand: impl FnMut() -> f32,
) -> Transmittance {
    delta_tracking_transmittance_dense(segments, sigma_t, &mut TrackAll, rand)
}

/// [`delta_tracking_transmittance`] over [`delta_tracking_dense`]'s flights.
pub fn delta_tracking_transmittance_dense(
    segments: impl IntoIterator<Item = MajorantSegment>,
    sigma_t: impl FnMut(f32) -> f32,
    dense: &mut impl DenseSegments,
    rand: impl FnMut() -> f32,
) -> Transmittance {
    let f = delta_tracking_dense(segments, sigma_t, dense, rand);
    Transmittance {
        value: if f.collided { 0.0 } else { 1.0 },
        nulls: f.nulls + f.collided as u32,
        violations: f.violations,
    }
}

/// Ratio tracking (Cramer 1978; Novák et al. 2014, sec. 3.2): tentative collisions from the
/// majorant, each multiplying the estimate by the null-collision probability
/// `1 - sigma_t(t) / majorant`. One random number per tentative collision. Once the estimate
/// is below 0.05, each further collision plays Russian roulette on it (pbrt-v4's
/// `SampleLd`: it ends with probability 0.75, else goes on times 4), which stops shadow
/// rays through optically thick media early at the same expectation.
pub fn ratio_tracking(
    segments: impl IntoIterator<Item = MajorantSegment>,
    sigma_t: impl FnMut(f32) -> f32,
    rand: impl FnMut() -> f32,
) -> Transmittance {
    ratio_tracking_dense(segments, sigma_t, &mut TrackAll, rand, false)
}

/// Residual ratio tracking (Novák et al. 2014, sec. 4): with each segment's `minorant` as
/// the control extinction `sigma_c`, `T = exp(-int sigma_c) * T_residual`, where the
/// residual `sigma_t - sigma_c` is ratio-tracked against the residual majorant
/// `majorant - minorant`. Segments whose bounds coincide (constant there) cost no tentative
/// collision at all.
pub fn residual_ratio_tracking(
    segments: impl IntoIterator<Item = MajorantSegment>,
    sigma_t: impl FnMut(f32) -> f32,
    rand: impl FnMut() -> f32,
) -> Transmittance {
    ratio_tracking_dense(segments, sigma_t, &mut TrackAll, rand, true)
}

/// Ratio tracking of `sigma_t - control` against `majorant - control`, times
/// `exp(-int control)`; the control is the segment's minorant, or 0 without `residual`
/// ([`ratio_tracking`], [`residual_ratio_tracking`]). The segments `dense` takes are not
/// tracked: their factor is their exact `exp(-depth)`, then one roulette decision
/// ([`dense`]).
pub fn ratio_tracking_dense(
    segments: impl IntoIterator<Item = MajorantSegment>,
    mut sigma_t: impl FnMut(f32) -> f32,
    dense: &mut impl DenseSegments,
    mut rand: impl FnMut() -> f32,
    residual: bool,
) -> Transmittance {
    let mut out = Transmittance {
        value: 1.0,
        ..Transmittance::default()
    };
    let mut control_depth = 0.0f32;
    let mut depth = DepthToNext::NONE;
    for seg in segments {
        if dense.takes(&seg) {
            out.value *= (-dense.depth(seg.t0, seg.t1)).exp() as f32;
            let low = out.value < roulette_limit(control_depth);
            out.value *= roulette(low, out.value == 0.0, &mut rand);
            if out.value == 0.0 {
                break;
            }
            continue;
        }
        let control = control_extinction(&seg, residual);
        if control > 0.0 {
            control_depth += control * (seg.t1 - seg.t0);
        }
        let bound = seg.majorant - control;
        let limit = roulette_limit(control_depth);
        let (mut value, mut nulls) = (out.value, 0);
        let ended = tentative(
            &seg,
            bound,
            &mut sigma_t,
            &mut rand,
            &mut out.violations,
            &mut depth,
            |_, s, rand| {
                value *= 1.0 - (s - control) / bound;
                nulls += 1;
                value *= roulette(value < limit, value == 0.0, rand);
                value != 0.0
            },
        );
        out.value = value;
        out.nulls += nulls;
        if ended.is_some() {
            break;
        }
    }
    out.value *= (-control_depth).exp();
    out
}

// ---------------------------------------------------------------------------------------
// Emission
// ---------------------------------------------------------------------------------------

/// Delta tracking that also gathers what an emissive medium sends back along the ray
/// (pbrt-v4's `VolPathIntegrator`): at **every** tentative collision `t_k`, null or real,
/// it adds `j(t_k) / majorant_k`, where `j` is the emission coefficient (radiance per unit
/// length) given by `emission(t, sigma_t(t))`. The tentative collisions form a Poisson
/// process of rate `majorant` that survives to `t` with probability `T(t)`, so the sum's
/// expectation is `int_0^d T(t) j(t) dt`, the emitted radiance reaching the ray's start --
/// **provided every segment's majorant is positive wherever `j` is** (a segment of zero
/// majorant has no collisions and its emission is lost; callers raise such bounds).
/// Returns the free flight (as [`delta_tracking`], drawing the same random numbers for the
/// same segments) and the emission gathered up to it.
pub fn delta_tracking_emitting(
    segments: impl IntoIterator<Item = MajorantSegment>,
    mut sigma_t: impl FnMut(f32) -> f32,
    mut emission: impl FnMut(f32, f32) -> Rgb,
    mut rand: impl FnMut() -> f32,
) -> (FreeFlight, Rgb) {
    let mut out = FreeFlight::default();
    let mut gathered = Rgb::BLACK;
    let mut depth = DepthToNext::NONE;
    for seg in segments {
        out.t = seg.t1;
        let mut nulls = 0;
        let inv = 1.0 / seg.majorant;
        let hit = tentative(
            &seg,
            seg.majorant,
            &mut sigma_t,
            &mut rand,
            &mut out.violations,
            &mut depth,
            |t, s, rand| {
                gathered += emission(t, s) * inv;
                let null = rand() * seg.majorant >= s;
                nulls += null as u32;
                null
            },
        );
        out.nulls += nulls;
        if let Some(t) = hit {
            out.t = t;
            out.collided = true;
            return (out, gathered);
        }
    }
    (out, gathered)
}

/// Ratio tracking (or, with `residual`, residual ratio tracking) of the transmittance,
/// gathering the emission reaching the segments' start on the way: at every tentative
/// collision `t_k` it adds `T_k j(t_k) / bound_k`, where `T_k` is the running transmittance
/// estimate just before `t_k` (the product of the earlier null-collision factors, times
/// `exp(-int_0^t_k control)` with `residual`) and `bound_k` the segment's tentative-collision
/// rate (`majorant - control`). `T_k` is an unbiased estimate of `T(t_k)` given the
/// collisions so far, so the sum's expectation is `int T(t) j(t) dt` -- provided every
/// segment's rate is positive wherever `j` is (callers raise the majorant of emitting
/// segments, see [`delta_tracking_emitting`]). Same random numbers and the same
/// transmittance as [`ratio_tracking`] / [`residual_ratio_tracking`] on the same segments.
pub fn ratio_tracking_emitting(
    segments: impl IntoIterator<Item = MajorantSegment>,
    mut sigma_t: impl FnMut(f32) -> f32,
    mut emission: impl FnMut(f32, f32) -> Rgb,
    mut rand: impl FnMut() -> f32,
    residual: bool,
) -> (Transmittance, Rgb) {
    let mut out = Transmittance {
        value: 1.0,
        ..Transmittance::default()
    };
    let mut gathered = Rgb::BLACK;
    let mut control_depth = 0.0f32;
    let mut depth = DepthToNext::NONE;
    for seg in segments {
        let control = control_extinction(&seg, residual);
        let bound = seg.majorant - control;
        let inv = 1.0 / bound;
        let (mut value, mut nulls) = (out.value, 0);
        let depth0 = control_depth;
        let limit = roulette_limit(depth0 + control.max(0.0) * (seg.t1 - seg.t0));
        let ended = tentative(
            &seg,
            bound,
            &mut sigma_t,
            &mut rand,
            &mut out.violations,
            &mut depth,
            |t, s, rand| {
                let before = if control > 0.0 {
                    value * (-(depth0 + control * (t - seg.t0))).exp()
                } else {
                    value * (-depth0).exp()
                };
                gathered += emission(t, s) * (before * inv);
                value *= 1.0 - (s - control) / bound;
                nulls += 1;
                value *= roulette(value < limit, value == 0.0, rand);
                value != 0.0
            },
        );
        if control > 0.0 {
            control_depth += control * (seg.t1 - seg.t0);
        }
        out.value = value;
        out.nulls += nulls;
        if ended.is_some() {
            break;
        }
    }
    out.value *= (-control_depth).exp();
    (out, gathered)
}

#[cfg(test)]
mod tests;
