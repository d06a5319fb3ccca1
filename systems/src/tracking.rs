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
    mut sigma_t: impl FnMut(f32) -> f32,
    mut rand: impl FnMut() -> f32,
) -> FreeFlight {
    let mut out = FreeFlight::default();
    let mut depth = DepthToNext::NONE;
    for seg in segments {
        out.t = seg.t1;
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
    let f = delta_tracking(segments, sigma_t, rand);
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
    ratio_tracking_with_control(segments, sigma_t, rand, false)
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
    ratio_tracking_with_control(segments, sigma_t, rand, true)
}

/// Ratio tracking of `sigma_t - control` against `majorant - control`, times
/// `exp(-int control)`; the control is the segment's minorant, or 0 without `residual`.
fn ratio_tracking_with_control(
    segments: impl IntoIterator<Item = MajorantSegment>,
    mut sigma_t: impl FnMut(f32) -> f32,
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
mod tests {
    use super::*;
    use crate::grid::{DensityGrid, MajorantGrid};
    use crate::mean_se;
    use crate::sampler::SplitMix64;
    use glam::Vec3;

    fn one(t0: f32, t1: f32, majorant: f32) -> [MajorantSegment; 1] {
        [MajorantSegment {
            t0,
            t1,
            majorant,
            minorant: 0.0,
        }]
    }

    /// Checks a histogram of free-flight distances over `[0, tmax]` (`hist.len() - 1` equal
    /// bins, the last entry the flights that passed) against the distribution of optical
    /// depth `depth(t)`, within 4 sigma per bin.
    fn assert_flight_histogram(hist: &[u32], tmax: f32, n: u32, depth: impl Fn(f32) -> f32) {
        let bins = hist.len() - 1;
        for (b, &count) in hist.iter().enumerate() {
            let p = if b == bins {
                (-depth(tmax)).exp()
            } else {
                let (a, c) = (
                    b as f32 * tmax / bins as f32,
                    (b + 1) as f32 * tmax / bins as f32,
                );
                (-depth(a)).exp() - (-depth(c - 1e-6)).exp()
            } as f64;
            let expected = p * n as f64;
            let sd = (n as f64 * p * (1.0 - p)).sqrt();
            assert!(
                (count as f64 - expected).abs() < 4.0 * sd,
                "bin {b}: {count} vs {expected:.0} +- {sd:.0}"
            );
        }
    }

    #[test]
    fn delta_tracking_samples_the_exponential_in_a_constant_medium() {
        // sigma_t = 2 under majorant 5 (60 % null collisions), segment [0, 1.5]: the
        // distance CDF is 1 - exp(-2 t) below 1.5, and P(pass) = exp(-3).
        let (sigma, tmax, n) = (2.0f32, 1.5f32, 200_000);
        let mut rng = SplitMix64(1);
        let bins = 15;
        let mut hist = vec![0u32; bins + 1];
        let mut nulls = 0u64;
        for _ in 0..n {
            let f = delta_tracking(one(0.0, tmax, 5.0), |_| sigma, || rng.f32());
            nulls += f.nulls as u64;
            assert_eq!(f.violations, 0);
            let b = if f.collided {
                assert!(f.t < tmax);
                ((f.t / tmax * bins as f32) as usize).min(bins - 1)
            } else {
                assert_eq!(f.t, tmax);
                bins
            };
            hist[b] += 1;
        }
        assert_flight_histogram(&hist, tmax, n, |t| sigma * t);
        // Expected null collisions: (majorant - sigma) * E[distance travelled].
        let mean_distance = (1.0 - (-sigma * tmax).exp()) / sigma;
        let expected_nulls = 3.0 * mean_distance * n as f32;
        assert!((nulls as f32 / expected_nulls - 1.0).abs() < 0.02);
    }

    /// The carried optical depth ([`DepthToNext`]) across many short segments of different
    /// majorants (some 0, as empty majorant cells are): the free flight still has the
    /// exponential distance distribution of the constant medium, and the random numbers drawn
    /// follow the tentative collisions, not the segments crossed (restarting the exponential
    /// at each of the 60 boundaries would draw about 60 more per flight).
    #[test]
    fn carried_depth_across_many_segments_keeps_the_distribution() {
        let (sigma, tmax, n) = (2.0f32, 1.5f32, 200_000);
        // 60 segments of length 0.025, majorants cycling 2, 7, 3.5 (all >= sigma_t = 2) and
        // a zero-majorant segment wherever sigma_t is 0 there (every tenth: [0.225, 0.25)...).
        let segs: Vec<MajorantSegment> = (0..60)
            .map(|k| MajorantSegment {
                t0: k as f32 * 0.025,
                t1: (k + 1) as f32 * 0.025,
                majorant: if k % 10 == 9 {
                    0.0
                } else {
                    [2.0, 7.0, 3.5][k % 3]
                },
                minorant: 0.0,
            })
            .collect();
        let field = |t: f32| {
            if ((t / 0.025) as usize) % 10 == 9 {
                0.0
            } else {
                sigma
            }
        };
        // The optical depth up to t of that field (6 empty segments of 0.025 in [0, 1.5]).
        let depth = |t: f32| {
            let cell = (t / 0.025) as usize;
            // Empty cells wholly before this one: 9, 19, ... below `cell`.
            let empty_before = cell / 10;
            let in_empty = cell % 10 == 9;
            let empty = empty_before as f32 * 0.025
                + if in_empty {
                    t - cell as f32 * 0.025
                } else {
                    0.0
                };
            sigma * (t - empty)
        };
        let bins = 12;
        let mut hist = vec![0u32; bins + 1];
        let mut rng = SplitMix64(3);
        let mut draws = 0u64;
        let mut tentatives = 0u64;
        for _ in 0..n {
            let f = delta_tracking(segs.iter().copied(), field, || {
                draws += 1;
                rng.f32()
            });
            tentatives += (f.nulls + f.collided as u32) as u64;
            let b = if f.collided {
                ((f.t / tmax * bins as f32) as usize).min(bins - 1)
            } else {
                bins
            };
            hist[b] += 1;
        }
        assert_flight_histogram(&hist, tmax, n, |t| depth(t.min(tmax - 1e-6)));
        // Delta tracking draws two numbers per tentative collision (distance, acceptance)
        // and one more for a flight that passes (its last draw runs past the end).
        assert!(
            draws <= 2 * tentatives + n as u64,
            "{draws} draws for {tentatives} tentative collisions of {n} flights"
        );
    }

    #[test]
    fn a_majorant_below_the_density_is_counted() {
        let mut rng = SplitMix64(3);
        let f = delta_tracking(one(0.0, 10.0, 1.0), |_| 2.0, || rng.f32());
        assert!(f.collided && f.violations == 1);
        let t = ratio_tracking(one(0.0, 10.0, 1.0), |_| 2.0, || rng.f32());
        assert!(t.violations > 0 && t.value.is_finite());
    }

    /// A grid ramped along x: voxel value `c0 + c1 (ix + 0.5) / n`; the clamped trilinear
    /// field is `c0 + c1 clamp(u, 1/2n, 1 - 1/2n)`, whose mean over u in [0, 1] is
    /// `c0 + c1 / 2` exactly (the clamped ends cancel).
    fn ramp(n: usize, c0: f32, c1: f32) -> DensityGrid {
        let mut data = Vec::new();
        for _z in 0..n {
            for _y in 0..n {
                for x in 0..n {
                    data.push(c0 + c1 * (x as f32 + 0.5) / n as f32);
                }
            }
        }
        DensityGrid::new([n, n, n], data).unwrap()
    }

    #[test]
    fn transmittance_estimators_are_unbiased_on_a_linear_ramp() {
        // sigma_t = scale * density, density a ramp 0.2 + 1.6 u through a majorant grid: for
        // a ray from the face u = 0 to the face u = 1 of world length L the optical depth is
        // scale L (0.2 + 0.8) in closed form.
        let (scale, grid) = (1.5f32, ramp(16, 0.2, 1.6));
        for res in [[1, 1, 1], [4, 4, 4], [16, 16, 16]] {
            let m = MajorantGrid::new(&grid, res);
            for (y0, z0, y1, z1) in [(0.5, 0.5, 0.5, 0.5), (0.1, 0.9, 0.8, 0.3)] {
                let (a, b) = (Vec3::new(0.0, y0, z0), Vec3::new(1.0, y1, z1));
                let length = (b - a).length();
                let d = (b - a) / length;
                let exact = (-(scale * length * 1.0) as f64).exp();
                let sigma = |t: f32| scale * grid.lookup(a + d * t);
                let segs = || m.traverse(a, d, 0.0, length).map(|s| s.scaled(scale));
                let mut rng = SplitMix64(7 + res[0] as u64);
                let n = 40_000;
                for name in ["ratio", "residual", "delta"] {
                    let (mean, se) = mean_se(n, || {
                        let mut r = || rng.f32();
                        let t = match name {
                            "ratio" => ratio_tracking(segs(), sigma, &mut r),
                            "residual" => residual_ratio_tracking(segs(), sigma, &mut r),
                            _ => delta_tracking_transmittance(segs(), sigma, &mut r),
                        };
                        assert_eq!(t.violations, 0);
                        t.value
                    });
                    assert!(
                        (mean - exact).abs() < 4.0 * se.max(1e-7),
                        "{name} {res:?}: {mean} +- {se} vs {exact}"
                    );
                }
            }
        }
    }

    #[test]
    fn ratio_tracking_matches_exp_of_a_step_and_an_exponential() {
        // sigma_t(t) = 3 for t < 0.4 else 0.5 on [0, 1]; and sigma_t = 4 exp(-2 t).
        /// A density along the ray, its majorant and its exact optical depth on [0, 1].
        type Case = (fn(f32) -> f32, f32, f64);
        let cases: [Case; 2] = [
            (
                |t| if t < 0.4 { 3.0 } else { 0.5 },
                3.0,
                3.0 * 0.4 + 0.5 * 0.6,
            ),
            (
                |t| 4.0 * (-2.0 * t).exp(),
                4.0,
                2.0 * (1.0 - (-2.0f64).exp()),
            ),
        ];
        for (f, majorant, depth) in cases {
            let mut rng = SplitMix64(17);
            let (mean, se) = mean_se(50_000, || {
                ratio_tracking(one(0.0, 1.0, majorant), f, || rng.f32()).value
            });
            let exact = (-depth).exp();
            assert!((mean - exact).abs() < 4.0 * se, "{mean} +- {se} vs {exact}");
        }
    }

    #[test]
    fn ratio_tracking_through_a_thick_medium_is_unbiased_and_stops_early() {
        // sigma_t = 6 + 2 t on [0, 1] under majorant 8.5 (minorant 5.9 for the residual
        // control): optical depth 7, T = 9.1e-4, far below the roulette's 0.05. Without the
        // roulette every estimate visits all 8.5 tentative collisions on average; with it
        // the walk stops a few collisions after its estimate became negligible. The emission
        // j = 1 + t gathered on the way must stay unbiased too.
        let sigma = |t: f32| 6.0 + 2.0 * t;
        let seg = [MajorantSegment {
            t0: 0.0,
            t1: 1.0,
            majorant: 8.5,
            minorant: 5.9,
        }];
        let exact = (-7.0f64).exp();
        let n = 400_000;
        let emitted = crate::simpson_01(20_000, |t| (-(6.0 * t + t * t)).exp() * (1.0 + t));
        for residual in [false, true] {
            let mut rng = SplitMix64(23 + residual as u64);
            let mut nulls = 0u64;
            let (mean, se) = mean_se(n, || {
                let t = ratio_tracking_with_control(seg, sigma, || rng.f32(), residual);
                nulls += t.nulls as u64;
                t.value
            });
            assert!(
                (mean - exact).abs() < 4.0 * se,
                "residual {residual}: {mean} +- {se} vs {exact}"
            );
            let per_estimate = nulls as f64 / n as f64;
            let without = if residual { 8.5 - 5.9 } else { 8.5 };
            assert!(
                per_estimate < 0.6 * without,
                "residual {residual}: {per_estimate} collisions an estimate"
            );
            let j = |t: f32, _s: f32| Rgb::splat(1.0 + t);
            let (mean, se) = mean_se(n, || {
                ratio_tracking_emitting(seg, sigma, j, || rng.f32(), residual)
                    .1
                    .r
            });
            assert!(
                (mean - emitted).abs() < 4.0 * se,
                "emission, residual {residual}: {mean} +- {se} vs {emitted}"
            );
        }
    }

    #[test]
    fn residual_tracking_of_a_constant_cell_is_exact_and_free() {
        let segs = [MajorantSegment {
            t0: 0.0,
            t1: 2.0,
            majorant: 1.5,
            minorant: 1.5,
        }];
        let t = residual_ratio_tracking(segs, |_| 1.5, || panic!("no random number needed"));
        assert_eq!((t.value, t.nulls), ((-3.0f32).exp(), 0));
    }

    #[test]
    fn tiny_steps_terminate() {
        // A majorant so large that steps underflow against t: still ends (one ulp a step).
        let t0 = 1.0e6f32;
        let f = delta_tracking(
            one(t0, f32::from_bits(t0.to_bits() + 50), 1.0e30),
            |_| 0.0,
            || 0.5,
        );
        assert!(!f.collided && f.nulls <= 50);
    }
}

#[cfg(test)]
mod emission_tests {
    use super::*;
    use crate::sampler::SplitMix64;

    fn mean_se(n: usize, mut f: impl FnMut() -> f32) -> (f64, f64) {
        let (mut s, mut s2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let v = f() as f64;
            s += v;
            s2 += v * v;
        }
        let m = s / n as f64;
        (m, ((s2 / n as f64 - m * m) / n as f64).sqrt())
    }

    /// `sigma_t(t)` = 3 on [0, 0.4), 0.5 on [0.4, 1]; `j(t) = 2 + t`; the exact emission
    /// reaching t = 0 is `int_0^1 T(t) (2 + t) dt` (Simpson in f64).
    fn exact() -> f64 {
        let depth = |t: f64| {
            if t < 0.4 {
                3.0 * t
            } else {
                1.2 + 0.5 * (t - 0.4)
            }
        };
        let f = |t: f64| (-depth(t)).exp() * (2.0 + t);
        let n = 20_000;
        let h = 1.0 / n as f64;
        let mut s = f(0.0) + f(1.0);
        for k in 1..n {
            s += f(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
        }
        s * h / 3.0
    }

    fn segments(raised: bool) -> [MajorantSegment; 2] {
        // Exact bounds (minorant = majorant): residual tracking would take no collision
        // there; raised by 2 per unit length, as the engine raises emitting cells.
        let lift = if raised { 2.0 } else { 0.0 };
        [
            MajorantSegment {
                t0: 0.0,
                t1: 0.4,
                majorant: 3.0 + lift,
                minorant: 3.0,
            },
            MajorantSegment {
                t0: 0.4,
                t1: 1.0,
                majorant: 0.5 + lift,
                minorant: 0.5,
            },
        ]
    }

    #[test]
    fn tracked_emission_is_unbiased() {
        let sigma = |t: f32| if t < 0.4 { 3.0 } else { 0.5 };
        let j = |t: f32, _s: f32| Rgb::splat(2.0 + t);
        let want = exact();
        let n = 100_000;
        let mut rng = SplitMix64(5);
        let (m, se) = mean_se(n, || {
            delta_tracking_emitting(segments(true), sigma, j, || rng.f32())
                .1
                .r
        });
        assert!((m - want).abs() < 4.0 * se, "delta: {m} +- {se} vs {want}");
        for residual in [false, true] {
            let (m, se) = mean_se(n, || {
                ratio_tracking_emitting(segments(true), sigma, j, || rng.f32(), residual)
                    .1
                    .g
            });
            assert!(
                (m - want).abs() < 4.0 * se,
                "ratio (residual {residual}): {m} +- {se} vs {want}"
            );
        }
    }

    #[test]
    fn emitting_tracking_draws_what_plain_tracking_draws() {
        let sigma = |t: f32| if t < 0.4 { 3.0 } else { 0.5 };
        let j = |_t: f32, _s: f32| Rgb::splat(1.0);
        for seed in 0..200 {
            let (mut a, mut b) = (SplitMix64(seed), SplitMix64(seed));
            let plain = delta_tracking(segments(true), sigma, || a.f32());
            let (f, _) = delta_tracking_emitting(segments(true), sigma, j, || b.f32());
            assert_eq!(plain, f);
            for residual in [false, true] {
                let (mut a, mut b) = (SplitMix64(seed), SplitMix64(seed));
                let plain = if residual {
                    residual_ratio_tracking(segments(false), sigma, || a.f32())
                } else {
                    ratio_tracking(segments(false), sigma, || a.f32())
                };
                let (t, _) =
                    ratio_tracking_emitting(segments(false), sigma, j, || b.f32(), residual);
                assert_eq!(plain, t);
            }
        }
    }
}
