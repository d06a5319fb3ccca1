//! Unit tests of the null-collision estimators (free flights, transmittance, emission).
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
            let t = ratio_tracking_dense(seg, sigma, &mut dense::TrackAll, || rng.f32(), residual);
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

mod emission {
    use super::*;

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
        crate::simpson_01(20_000, |t| (-depth(t)).exp() * (2.0 + t))
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
