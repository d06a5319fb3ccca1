//! Tests of `spectral_tracking.rs`.

use super::*;
use crate::grid::{DensityGrid, MajorantGrid};
use crate::mean_se;
use crate::ray_marching::ray_marching_transmittance;
use crate::sampler::SplitMix64;
use crate::tracking::{
    delta_tracking, delta_tracking_emitting, ratio_tracking, ratio_tracking_emitting,
    residual_ratio_tracking,
};
use glam::Vec3;

/// `k` of `scale = [1, 2, 4]` (blue the densest channel).
const K: Rgb = Rgb::new(0.25, 0.5, 1.0);

/// An analytic field along the ray on `[0, 1]`: its name, `sigma(t)` (the densest
/// channel), its majorant segments and its optical depth `tau(t)` in closed form.
type Field = (
    &'static str,
    fn(f32) -> f32,
    fn() -> Vec<MajorantSegment>,
    fn(f64) -> f64,
);

fn seg(t0: f32, t1: f32, majorant: f32, minorant: f32) -> MajorantSegment {
    MajorantSegment {
        t0,
        t1,
        majorant,
        minorant,
    }
}

fn fields() -> [Field; 2] {
    [
        // sigma = 1.5 under a loose majorant 2.5 (40 % nulls for the densest channel).
        (
            "constant",
            |_| 1.5,
            || vec![seg(0.0, 1.0, 2.5, 1.5)],
            |t| 1.5 * t,
        ),
        // sigma = 0.5 + 2 t: two cells with their own bounds, tau = 0.5 t + t^2.
        (
            "ramp",
            |t| 0.5 + 2.0 * t,
            || vec![seg(0.0, 0.5, 1.5, 0.5), seg(0.5, 1.0, 2.5, 1.5)],
            |t| 0.5 * t + t * t,
        ),
    ]
}

/// `|mean - exact| < 3 se` per channel (a floor on `se` for exact estimators).
fn within(what: &str, means: [(f64, f64); 3], exact: [f64; 3]) {
    for c in 0..3 {
        let (m, se) = means[c];
        assert!(
            (m - exact[c]).abs() < 3.0 * se.max(1e-6),
            "{what}, channel {c}: {m} +- {se} vs {}",
            exact[c]
        );
    }
}

fn channel_means(n: usize, mut f: impl FnMut() -> Rgb) -> [(f64, f64); 3] {
    let samples: Vec<Rgb> = (0..n).map(|_| f()).collect();
    [0, 1, 2].map(|c| {
        let mut it = samples.iter().map(|v| v.to_array()[c]);
        mean_se(n, || it.next().unwrap())
    })
}

fn exact_t(tau: fn(f64) -> f64, t: f64) -> [f64; 3] {
    K.to_array().map(|k| (-(k as f64) * tau(t)).exp())
}

#[test]
fn every_transmittance_estimator_is_unbiased_per_channel() {
    for (name, sigma, segs, tau) in fields() {
        let exact = exact_t(tau, 1.0);
        let mut rng = SplitMix64(21);
        let n = 60_000;
        for est in ["ratio", "residual", "delta", "unbiased_ray_marching"] {
            let means = channel_means(n, || {
                let r = || rng.f32();
                let t = match est {
                    "ratio" => ratio_tracking_rgb(segs(), sigma, K, r, false),
                    "residual" => ratio_tracking_rgb(segs(), sigma, K, r, true),
                    "delta" => delta_tracking_transmittance_rgb(segs(), sigma, K, r),
                    _ => unbiased_ray_marching_rgb(segs, sigma, K, r, 0.25),
                };
                assert_eq!(t.violations, 0);
                t.value
            });
            eprintln!("{name} {est}: {means:?} vs {exact:?}");
            within(&format!("{name} {est}"), means, exact);
        }
        // Biased, but consistent: a fine step is within 1e-3 of the closed form.
        let means = channel_means(2_000, || {
            ray_marching_transmittance_rgb(segs(), sigma, K, || rng.f32(), 1e-3).value
        });
        for c in 0..3 {
            assert!((means[c].0 - exact[c]).abs() < 1e-3, "{name} marching {c}");
        }
    }
}

#[test]
fn channel_ratio_tracking_through_a_thick_medium_is_unbiased_and_stops_early() {
    // sigma = 24 + 8 t on [0, 1] (densest channel) under majorant 34, minorant 23.6:
    // channel depths 7, 14 and 28 (K), so even red's estimate falls below the roulette's
    // 0.05, which then stops the walk long before the 34 (residual: 10.4) tentative
    // collisions an estimate would visit without it.
    let sigma = |t: f32| 24.0 + 8.0 * t;
    let exact = K.to_array().map(|k| (-(k as f64) * 28.0).exp());
    let n = 200_000;
    for residual in [false, true] {
        let mut rng = SplitMix64(41 + residual as u64);
        let mut nulls = 0u64;
        let means = channel_means(n, || {
            let t = ratio_tracking_rgb(
                [seg(0.0, 1.0, 34.0, 23.6)],
                sigma,
                K,
                || rng.f32(),
                residual,
            );
            nulls += t.nulls as u64;
            t.value
        });
        for c in 0..3 {
            let (m, se) = means[c];
            assert!(
                (m - exact[c]).abs() < 4.0 * se + 1e-9,
                "residual {residual}, channel {c}: {m} +- {se} vs {}",
                exact[c]
            );
        }
        let per_estimate = nulls as f64 / n as f64;
        let without = if residual { 34.0 - 23.6 } else { 34.0 };
        assert!(
            per_estimate < 0.6 * without,
            "residual {residual}: {per_estimate} collisions an estimate"
        );
    }
}

#[test]
fn the_channels_residual_control_makes_a_constant_cell_free_and_exact() {
    let t = ratio_tracking_rgb(
        [seg(0.0, 2.0, 1.5, 1.5)],
        |_| 1.5,
        K,
        || panic!("no random number needed"),
        true,
    );
    assert_eq!(t.nulls, 0);
    for c in 0..3 {
        let want = (-3.0 * K.to_array()[c]).exp();
        assert!((t.value.to_array()[c] - want).abs() < 1e-6, "{c}");
    }
}

#[test]
fn spectral_free_flights_have_each_channels_collision_density_and_pass_probability() {
    // E[w_c 1{collide in [a, b)}] = T_c(a) - T_c(b) and E[w_c 1{pass}] = T_c(1), per
    // channel, for uniform channel probabilities and for throughput-like ones; and the
    // weights are bounded by 1 / p_c (module docs).
    let bins = 5;
    for (name, sigma, segs, tau) in fields() {
        for p in [[1.0f32 / 3.0; 3], [0.6, 0.3, 0.1]] {
            let mut rng = SplitMix64(8);
            let n = 200_000;
            let mut samples = vec![[Rgb::BLACK; 6]; 0];
            let mut max_w = [0.0f32; 3];
            for _ in 0..n {
                let f = spectral_tracking(segs(), sigma, K, p, || rng.f32());
                let mut row = [Rgb::BLACK; 6];
                let b = if f.collided {
                    ((f.t * bins as f32) as usize).min(bins - 1)
                } else {
                    assert_eq!(f.t, 1.0);
                    bins
                };
                row[b] = f.weight;
                for c in 0..3 {
                    max_w[c] = max_w[c].max(f.weight.to_array()[c]);
                }
                samples.push(row);
            }
            for c in 0..3 {
                assert!(max_w[c] <= 1.0 / p[c] * 1.0001, "{name} {p:?}: {max_w:?}");
            }
            for b in 0..=bins {
                let exact = if b == bins {
                    exact_t(tau, 1.0)
                } else {
                    let (t0, t1) = (b as f64 / bins as f64, (b + 1) as f64 / bins as f64);
                    let (a, z) = (exact_t(tau, t0), exact_t(tau, t1));
                    [0, 1, 2].map(|c| a[c] - z[c])
                };
                let mut it = samples.iter().map(|r| r[b]);
                let means = channel_means(n, || it.next().unwrap());
                within(&format!("{name} {p:?} bin {b}"), means, exact);
            }
        }
    }
}

#[test]
fn spectral_mis_bounds_what_tracking_one_channel_leaves_unbounded() {
    // The densest channel tracked alone (p = [0, 0, 1]) in a field close to its
    // majorant: the thin channels' null factors (1 - k s / mu) / (1 - s / mu) reach
    // ~15, so a pass carries huge weights. Spectral MIS keeps them below 1 / p_c = 3.
    let (segs, sigma) = (|| [seg(0.0, 1.0, 2.0, 0.0)], |_: f32| 1.9);
    let run = |p: [f32; 3]| {
        let mut rng = SplitMix64(4);
        let (mut max, mut sum2) = (0.0f32, 0.0f64);
        let n = 100_000;
        for _ in 0..n {
            let v = delta_like(spectral_tracking(segs(), sigma, K, p, || rng.f32())).r;
            max = max.max(v);
            sum2 += (v as f64).powi(2);
        }
        (max, sum2 / n as f64)
    };
    fn delta_like(f: SpectralFlight) -> Rgb {
        if f.collided {
            Rgb::BLACK
        } else {
            f.weight
        }
    }
    let (mis_max, mis_m2) = run([1.0 / 3.0; 3]);
    let (one_max, one_m2) = run([0.0, 0.0, 1.0]);
    eprintln!("red pass weight: MIS max {mis_max} E[w^2] {mis_m2}; blue only max {one_max} E[w^2] {one_m2}");
    assert!(mis_max <= 3.0001, "{mis_max}");
    assert!(one_max > 30.0 * mis_max, "{one_max} vs {mis_max}");
    assert!(one_m2 > 10.0 * mis_m2, "{one_m2} vs {mis_m2}");
}

#[test]
fn emission_is_gathered_per_channel_without_bias() {
    // j_c = (1, 2, 3) (2 + t) on the ramp; exact int_0^1 T_c(t) j_c(t) dt by Simpson.
    let (_, sigma, segs, tau) = fields()[1];
    let j = |t: f32, _s: f32| Rgb::new(1.0, 2.0, 3.0) * (2.0 + t);
    let exact = [0, 1, 2]
        .map(|c| crate::simpson_01(2_000, |t| exact_t(tau, t)[c] * (c as f64 + 1.0) * (2.0 + t)));
    let mut rng = SplitMix64(13);
    let n = 100_000;
    for est in ["delta mis", "delta", "ratio", "residual"] {
        let means = channel_means(n, || {
            let r = || rng.f32();
            match est {
                "delta mis" => {
                    spectral_tracking_emitting(segs(), sigma, K, [0.5, 0.3, 0.2], j, r).1
                }
                "delta" => delta_tracking_emitting_rgb(segs(), sigma, K, j, r).1,
                "ratio" => ratio_tracking_emitting_rgb(segs(), sigma, K, j, r, false).1,
                _ => ratio_tracking_emitting_rgb(segs(), sigma, K, j, r, true).1,
            }
        });
        within(est, means, exact);
    }
}

/// A 16^3 grid ramped along x with a 4^3 majorant grid, and random rays through it.
fn random_rays(
    mut f: impl FnMut(&mut dyn Iterator<Item = MajorantSegment>, &dyn Fn(f32) -> f32, u64),
) {
    let n = 16;
    let mut data = Vec::new();
    for _ in 0..n * n {
        for x in 0..n {
            data.push(0.2 + 1.6 * (x as f32 + 0.5) / n as f32);
        }
    }
    let grid = DensityGrid::new([n, n, n], data).unwrap();
    let m = MajorantGrid::new(&grid, [4, 4, 4]);
    let mut rng = SplitMix64(99);
    for seed in 0..300 {
        let a = Vec3::new(rng.f32(), rng.f32(), rng.f32());
        let b = Vec3::new(rng.f32(), rng.f32(), rng.f32());
        let len = (b - a).length().max(1e-3);
        let d = (b - a) / len;
        let scale = 3.0;
        let sigma = |t: f32| scale * grid.lookup(a + d * t);
        let mut segs = m.traverse(a, d, 0.0, len).map(|s| s.scaled(scale));
        f(&mut segs, &sigma, seed);
    }
}

#[test]
fn a_grey_k_reproduces_the_grey_estimators_bit_for_bit() {
    let grey = Rgb::WHITE;
    random_rays(|segs, sigma, seed| {
        let segs: Vec<MajorantSegment> = segs.collect();
        let rng = |s| {
            let mut r = SplitMix64(s);
            move || r.f32()
        };
        let old = delta_tracking(segs.clone(), sigma, rng(seed));
        let new = spectral_tracking(segs.clone(), sigma, grey, [0.2, 0.3, 0.5], rng(seed));
        assert_eq!(
            (old.t, old.collided, old.nulls),
            (new.t, new.collided, new.nulls)
        );
        assert_eq!(new.weight, Rgb::WHITE);
        let j = |t: f32, s: f32| Rgb::new(t, s, 1.0);
        let (old, oe) = delta_tracking_emitting(segs.clone(), sigma, j, rng(seed));
        let (new, ne) =
            spectral_tracking_emitting(segs.clone(), sigma, grey, [1.0; 3], j, rng(seed));
        assert_eq!((old.t, old.collided, oe), (new.t, new.collided, ne));
        for residual in [false, true] {
            let old = if residual {
                residual_ratio_tracking(segs.clone(), sigma, rng(seed))
            } else {
                ratio_tracking(segs.clone(), sigma, rng(seed))
            };
            let new = ratio_tracking_rgb(segs.clone(), sigma, grey, rng(seed), residual);
            assert_eq!(new.value, Rgb::splat(old.value), "residual {residual}");
            assert_eq!(new.nulls, old.nulls);
            let (old, oe) = ratio_tracking_emitting(segs.clone(), sigma, j, rng(seed), residual);
            let (new, ne) =
                ratio_tracking_emitting_rgb(segs.clone(), sigma, grey, j, rng(seed), residual);
            assert_eq!(new.value, Rgb::splat(old.value));
            // The emitting sums group their products differently: equal to rounding.
            for c in 0..3 {
                let (a, b) = (oe.to_array()[c], ne.to_array()[c]);
                assert!((a - b).abs() <= 1e-5 * a.abs().max(1.0), "{a} vs {b}");
            }
        }
        let old = ray_marching_transmittance(segs.clone(), sigma, rng(seed), 0.05);
        let new = ray_marching_transmittance_rgb(segs.clone(), sigma, grey, rng(seed), 0.05);
        assert_eq!(new.value, Rgb::splat(old.value));
    });
}

/// A density per channel along `[0, 1]` whose channels do not stay in proportion (a
/// 3-channel grid's extinction): red `0.5 + 2 t`, green `0.8`, blue `3 (1 - t)^2`; the
/// densest channel changes along the ray (blue, then green, then red).
fn per_channel_sigma(t: f32) -> Rgb {
    Rgb::new(0.5 + 2.0 * t, 0.8, 3.0 * (1.0 - t) * (1.0 - t))
}

/// Optical depths of [`per_channel_sigma`] on `[0, t]` in closed form.
fn per_channel_tau(t: f64) -> [f64; 3] {
    [0.5 * t + t * t, 0.8 * t, 1.0 - (1.0 - t).powi(3)]
}

/// Segments bounding every channel of [`per_channel_sigma`]: the max over channels above,
/// the min over channels below (as `DensityChannels::majorants` builds them).
fn per_channel_segments() -> Vec<MajorantSegment> {
    vec![seg(0.0, 0.5, 3.0, 0.5), seg(0.5, 1.0, 3.0, 0.0)]
}

#[test]
fn per_channel_transmittance_is_unbiased_where_the_channels_are_not_proportional() {
    let exact = per_channel_tau(1.0).map(|x| (-x).exp());
    let mut rng = SplitMix64(77);
    let n = 80_000;
    for est in ["ratio", "residual", "delta"] {
        let means = channel_means(n, || {
            let r = || rng.f32();
            let sigma = PerChannel(per_channel_sigma);
            let t = match est {
                "ratio" | "residual" => {
                    let none = None::<fn(f32, f32) -> Rgb>;
                    ratio_tracking_channels(
                        per_channel_segments(),
                        sigma,
                        none,
                        r,
                        est == "residual",
                    )
                    .0
                }
                _ => {
                    let f = spectral_tracking_channels(
                        per_channel_segments(),
                        sigma,
                        [1.0; 3],
                        |_, _| Rgb::BLACK,
                        r,
                    )
                    .0;
                    pass_value(f)
                }
            };
            assert_eq!(t.violations, 0);
            t.value
        });
        eprintln!("per-channel {est}: {means:?} vs {exact:?}");
        within(&format!("per-channel {est}"), means, exact);
    }
    // A proportional extinction through the per-channel form gives the proportional
    // estimate (the same random numbers; up to the rounding of k sigma / max).
    let mut a = SplitMix64(5);
    let mut b = SplitMix64(5);
    for _ in 0..200 {
        let (s, segs) = (fields()[1].1, fields()[1].2);
        let p = ratio_tracking_rgb(segs(), s, K, || a.f32(), false);
        let q = ratio_tracking_channels(
            segs(),
            PerChannel(|t| K * s(t)),
            None::<fn(f32, f32) -> Rgb>,
            || b.f32(),
            false,
        )
        .0;
        for c in 0..3 {
            let (x, y) = (p.value.to_array()[c], q.value.to_array()[c]);
            assert!((x - y).abs() <= 1e-5 * x.abs().max(1.0), "{p:?} {q:?}");
        }
    }
}

#[test]
fn per_channel_free_flights_have_each_channels_collision_and_pass_probability() {
    // With spectral MIS over an uneven channel pdf: E[w_c 1{pass}] = T_c(1), and
    // E[w_c 1{collided before 0.5}] = 1 - T_c(0.5), per channel.
    let pass = per_channel_tau(1.0).map(|x| (-x).exp());
    let early = per_channel_tau(0.5).map(|x| 1.0 - (-x).exp());
    let mut rng = SplitMix64(91);
    let n = 100_000;
    let flights: Vec<SpectralFlight> = (0..n)
        .map(|_| {
            spectral_tracking_channels(
                per_channel_segments(),
                PerChannel(per_channel_sigma),
                [0.2, 0.3, 0.5],
                |_, _| Rgb::BLACK,
                || rng.f32(),
            )
            .0
        })
        .collect();
    let mut it = flights.iter();
    let means = channel_means(n, || {
        let f = it.next().unwrap();
        if f.collided {
            Rgb::BLACK
        } else {
            f.weight
        }
    });
    within("per-channel pass", means, pass);
    let mut it = flights.iter();
    let means = channel_means(n, || {
        let f = it.next().unwrap();
        if f.collided && f.t < 0.5 {
            f.weight
        } else {
            Rgb::BLACK
        }
    });
    within("per-channel early collision", means, early);
    // Bounded: w_c <= 1 / p_c.
    for f in &flights {
        assert!(
            f.weight.r <= 5.0 + 1e-3 && f.weight.g <= 1.0 / 0.3 + 1e-3 && f.weight.b <= 2.0 + 1e-3
        );
    }
}
