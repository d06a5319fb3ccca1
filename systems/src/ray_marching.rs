//! Quadrature estimators for heterogeneous media along one ray: fixed-step ray marching of
//! the optical depth (biased transmittance and free flights, as Cycles ships again), and an
//! unbiased ray-marching transmittance estimator built on it (a power series around a
//! ray-marched pivot: Georgiev et al. 2019, "Integral formulations of volumetric
//! transmittance", sec. 6; Kettunen et al. 2021, "An unbiased ray-marching transmittance
//! estimator").
//!
//! # Conventions
//! As [`crate::tracking`]: a ray is given by its majorant segments in order (`[t0, t1)`,
//! bounds `minorant <= sigma_t <= majorant`, extinction per world unit), parts not covered
//! by a segment have `sigma_t = 0`, `rand()` draws the next uniform number in `[0, 1)`.
//! The segments are passed as a closure that makes them afresh, since the unbiased estimator
//! marches the same ray several times.
//!
//! # The march
//! Each segment of length `len` is cut into `n = ceil(len / step)` equal steps (at most
//! [`MAX_STEPS_PER_SEGMENT`]); `sigma_t` is sampled once per step at `t0 + (k + u) h`, one
//! jitter `u` shared by the whole march. The optical-depth estimate `X = sum h sigma_t` is
//! then unbiased (`E[X] = tau`, the exact optical depth: each step's sample is uniform over
//! its step). Segments with `majorant <= 0` are skipped (`sigma_t = 0` there) and segments
//! whose bounds coincide are integrated exactly, without a lookup: the majorant grid gives
//! the march empty-space skipping and exact constant regions for free.
//!
//! - [`ray_marching_transmittance`] returns `exp(-X)`: biased upwards (Jensen:
//!   `E[exp(-X)] >= exp(-E[X])`), the bias about `exp(-tau) Var(X) / 2`, shrinking with the
//!   step.
//! - [`unbiased_ray_marching`]: with a pivot `c` (one march) and independent marches `X_j`,
//!   `exp(-tau) = exp(-c) sum_k (c - tau)^k / k!` and `prod_{j <= k} (c - X_j)` is an unbiased
//!   estimate of `(c - tau)^k`; the series is cut by Russian roulette, term `k` kept with
//!   probability `prod_{i <= k} min(1, rho / i)` and weighted by its inverse, so each factor
//!   is `(c - X_j) / rho` once `i > rho`. Unbiased for any `rho > 0` that depends on the pivot
//!   only; `rho = max(RHO_MIN, 2 h TV)` with `h TV` the pivot's sum of `h |Delta sigma_t|`
//!   between neighbouring steps (the jittered march's error is about one step times the
//!   variation of `sigma_t`), so factors stay near or below 1 and smooth media cost about
//!   `e^rho - 1` extra marches. The estimate can fall slightly outside `[0, 1]` (the series
//!   alternates); it is not clamped (clamping would bias it).
//! - [`ray_marching_free_flight`]: a free-flight distance by inverting the marched optical
//!   depth against an exponential target `-ln(1 - u)` (linear within the step where it is
//!   crossed). Biased like the transmittance; consistent as the step shrinks.

use crate::grid::MajorantSegment;
use crate::march::{constant, march, positive, steps, unbiased_march_rgb};
use crate::medium::sample_optical_depth;
use crate::tracking::{FreeFlight, Transmittance};
use risotto_components::Rgb;

// The march and its limits live in `crate::march`, shared with the chromatic estimators of
// `crate::spectral_tracking`; these are the limits' public paths.
pub use crate::march::{MAX_ORDER, MAX_STEPS_PER_SEGMENT, RHO_MAX, RHO_MIN};

/// Fixed-step ray marching: `exp(-X)` for one jittered march (biased; see the module docs).
/// `step > 0` in ray-parameter units.
pub fn ray_marching_transmittance<I: IntoIterator<Item = MajorantSegment>>(
    segments: I,
    mut sigma_t: impl FnMut(f32) -> f32,
    mut rand: impl FnMut() -> f32,
    step: f32,
) -> Transmittance {
    let m = march(segments, &mut sigma_t, step, rand());
    Transmittance {
        value: (-m.depth).exp(),
        nulls: m.lookups,
        violations: m.violations,
    }
}

/// The unbiased ray-marching transmittance estimator (module docs): a pivot march, then
/// independent marches for the terms of the power series the roulette keeps. (The grey case
/// of [`crate::spectral_tracking::unbiased_ray_marching_rgb`], whose arithmetic with
/// `k = (1, 1, 1)` is exactly this estimator's; the marches dominate its cost.)
pub fn unbiased_ray_marching<I: IntoIterator<Item = MajorantSegment>>(
    segments: impl Fn() -> I,
    sigma_t: impl FnMut(f32) -> f32,
    rand: impl FnMut() -> f32,
    step: f32,
) -> Transmittance {
    let (value, nulls, violations) = unbiased_march_rgb(segments, sigma_t, Rgb::WHITE, rand, step);
    Transmittance {
        value: value.r,
        nulls,
        violations,
    }
}

/// A free flight by ray marching (module docs): collides where the marched optical depth
/// reaches `-ln(1 - u)`, else passes the segments (`t` = the end of the last one). Two random
/// numbers: the target and the jitter.
pub fn ray_marching_free_flight<I: IntoIterator<Item = MajorantSegment>>(
    segments: I,
    mut sigma_t: impl FnMut(f32) -> f32,
    mut rand: impl FnMut() -> f32,
    step: f32,
) -> FreeFlight {
    let target = sample_optical_depth(rand());
    let u = rand();
    let mut out = FreeFlight::default();
    let mut depth = 0.0f32;
    for seg in segments {
        out.t = seg.t1;
        let len = seg.t1 - seg.t0;
        if !positive(len) {
            continue;
        }
        if let Some(s) = constant(&seg) {
            if s > 0.0 && depth + s * len > target {
                out.t = (seg.t0 + (target - depth) / s).min(seg.t1);
                out.collided = true;
                return out;
            }
            depth += s * len;
            continue;
        }
        let (n, h) = steps(len, step);
        for k in 0..n {
            let s = sigma_t(seg.t0 + (k as f32 + u) * h);
            out.nulls += 1;
            out.violations += (s > seg.majorant) as u32;
            if s > 0.0 && depth + s * h > target {
                let start = seg.t0 + k as f32 * h;
                out.t = (start + (target - depth) / s).min(seg.t1);
                out.collided = true;
                return out;
            }
            depth += s * h;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mean_se;
    use crate::sampler::SplitMix64;

    /// A density along the ray on [0, 1], its majorant and its exact optical depth.
    type Field = (&'static str, fn(f32) -> f32, f32, f64);

    fn fields() -> [Field; 4] {
        [
            ("constant", |_| 1.7, 1.7, 1.7),
            ("ramp", |t| 0.5 + 2.0 * t, 2.5, 1.5),
            (
                "step",
                |t| if t < 0.37 { 3.0 } else { 0.5 },
                3.0,
                3.0 * 0.37 + 0.5 * 0.63,
            ),
            (
                "exponential",
                |t| 4.0 * (-2.0 * t).exp(),
                4.0,
                2.0 * (1.0 - (-2.0f64).exp()),
            ),
        ]
    }

    fn one(majorant: f32) -> [MajorantSegment; 1] {
        [MajorantSegment {
            t0: 0.0,
            t1: 1.0,
            majorant,
            minorant: 0.0,
        }]
    }

    #[test]
    fn the_march_estimates_the_optical_depth_without_bias() {
        for (name, f, majorant, depth) in fields() {
            for step in [0.5f32, 0.1] {
                let mut rng = SplitMix64(5);
                let mut g = f;
                let (mean, se) = mean_se(40_000, || {
                    march(one(majorant), &mut g, step, rng.f32()).depth
                });
                assert!(
                    (mean - depth).abs() < 4.0 * se.max(1e-6),
                    "{name} step {step}: {mean} +- {se} vs {depth}"
                );
            }
        }
    }

    #[test]
    fn unbiased_ray_marching_matches_the_closed_form() {
        for (name, f, majorant, depth) in fields() {
            // A coarse step: the pivot is far off, the series must correct it.
            for step in [0.5f32, 0.125] {
                let mut rng = SplitMix64(11);
                let (mean, se) = mean_se(100_000, || {
                    unbiased_ray_marching(|| one(majorant), f, || rng.f32(), step).value
                });
                let exact = (-depth).exp();
                assert!(
                    (mean - exact).abs() < 4.0 * se.max(1e-7),
                    "{name} step {step}: {mean} +- {se} vs {exact}"
                );
            }
        }
    }

    #[test]
    fn ray_marching_bias_shrinks_with_the_step() {
        // The step field, whose discontinuity makes the jittered march's depth random:
        // exp(-X) is biased upwards, by about exp(-tau) Var(X) / 2 ~ step^2.
        let (_, f, majorant, depth) = fields()[2];
        let exact = (-depth).exp();
        let bias = |step: f32| {
            let mut rng = SplitMix64(3);
            let (mean, se) = mean_se(200_000, || {
                ray_marching_transmittance(one(majorant), f, || rng.f32(), step).value
            });
            (mean - exact, se)
        };
        let (coarse, se_coarse) = bias(0.5);
        let (fine, se_fine) = bias(0.1);
        assert!(
            coarse > 10.0 * se_coarse,
            "coarse bias {coarse} +- {se_coarse}"
        );
        assert!(fine >= -4.0 * se_fine, "fine bias {fine} +- {se_fine}");
        assert!(fine.abs() < coarse / 5.0, "{fine} vs {coarse}");
    }

    #[test]
    fn constant_and_empty_segments_need_no_lookup() {
        let segs = [
            MajorantSegment {
                t0: 0.0,
                t1: 0.5,
                majorant: 0.0,
                minorant: 0.0,
            },
            MajorantSegment {
                t0: 0.5,
                t1: 2.0,
                majorant: 2.0,
                minorant: 2.0,
            },
        ];
        let never = |_: f32| -> f32 { panic!("no lookup needed") };
        let t = ray_marching_transmittance(segs, never, || 0.5, 0.01);
        assert_eq!((t.value, t.nulls), ((-3.0f32).exp(), 0));
        let u = unbiased_ray_marching(|| segs, never, || 0.5, 0.01);
        assert!((u.value - (-3.0f32).exp()).abs() < 1e-6 && u.nulls == 0);
        // Target depth -ln(1 - 0.5) = ln 2, reached at 0.5 + ln 2 / 2 in the constant part.
        let f = ray_marching_free_flight(segs, never, || 0.5, 0.01);
        assert!(f.collided && (f.t - (0.5 + 2f32.ln() / 2.0)).abs() < 1e-6);
    }

    #[test]
    fn ray_marched_free_flights_follow_the_exponential() {
        // sigma_t = 2 (sampled, not declared constant): P(t < x) = 1 - exp(-2 x).
        let mut rng = SplitMix64(9);
        let n = 100_000;
        let mut below = [0u32; 4];
        let mut passed = 0;
        for _ in 0..n {
            let f = ray_marching_free_flight(one(3.0), |_| 2.0, || rng.f32(), 0.1);
            if !f.collided {
                passed += 1;
                continue;
            }
            for (b, x) in [0.1f32, 0.3, 0.6, 0.9].iter().enumerate() {
                below[b] += (f.t < *x) as u32;
            }
        }
        let p_pass = (-2.0f64).exp();
        let se = (p_pass * (1.0 - p_pass) / n as f64).sqrt();
        assert!((passed as f64 / n as f64 - p_pass).abs() < 4.0 * se);
        for (b, x) in [0.1f64, 0.3, 0.6, 0.9].iter().enumerate() {
            let p = 1.0 - (-2.0 * x).exp();
            let se = (p * (1.0 - p) / n as f64).sqrt();
            assert!((below[b] as f64 / n as f64 - p).abs() < 4.0 * se, "{x}");
        }
    }

    #[test]
    fn tiny_steps_are_capped() {
        let mut lookups = 0;
        let t = ray_marching_transmittance(
            one(1.0),
            |_| {
                lookups += 1;
                0.5
            },
            || 0.5,
            1e-30,
        );
        assert_eq!(lookups, MAX_STEPS_PER_SEGMENT);
        assert!((t.value - (-0.5f32).exp()).abs() < 1e-4);
    }
}
