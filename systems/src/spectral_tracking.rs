//! Null-collision estimators for **chromatic** heterogeneous media along one ray: free
//! flights by spectral tracking with one-sample spectral MIS, and per-channel ratio,
//! residual ratio, delta-tracking and ray-marching transmittance, all against one grey
//! majorant.
//!
//! # Conventions
//! As [`crate::tracking`] (majorant segments in order, `rand()` uniform in `[0, 1)`,
//! majorant violations counted, never clamped), with a chromatic extinction of the form
//!
//! `sigma_t,c(t) = k_c sigma(t)`, `k = scale / max_channel(scale)`, every `k_c` in `[0, 1]`:
//!
//! `sigma(t)` is the extinction of the densest channel (the one with `k_c = 1`), and the
//! segments bound `sigma(t)` (a density grid's majorant segments scaled by the largest
//! channel of the scale). Each segment's majorant is then a **grey majorant** of all three
//! channels: one sequence of tentative collisions serves them all. With `k = (1, 1, 1)`
//! every estimator here draws the same random numbers as its grey counterpart in
//! [`crate::tracking`] / [`crate::ray_marching`] and returns its value in every channel (the
//! tests check this bit for bit; the grey unbiased ray-marching estimator is this file's
//! with `k = (1, 1, 1)`).
//!
//! # Spectral MIS for free flights
//! [`spectral_tracking`] samples tentative collisions at the grey rate `mu` and decides at
//! each whether it is real with the probability of the **one-sample balance heuristic** over
//! the three channels' delta-tracking techniques (Miller, Georgiev and Jarosz 2019, "A
//! null-scattering path integral formulation of light transport", sec. 5; Mitsuba 3's
//! `volpathmis`). Technique `c` (tracking channel `c`) has path pdf `prod_j q_c,j` times the
//! common tentative-collision density, with `q_c,j = k_c sigma_j / mu` at a real and
//! `1 - k_c sigma_j / mu` at a null collision. The path is sampled from the mixture
//! `sum_c p_c prod_j q_c,j` (`p` = the caller's channel pdf, e.g.
//! [`crate::medium::channel_pdf`] of the path throughput) and every channel's contribution
//! `prod_j q_c,j` is divided by it: the weight `w_c = prod_j q_c,j / sum_k p_k prod_j q_k,j`.
//!
//! The mixture is sampled one collision at a time: with running weights `w` (1 at the
//! start), collision `j` is real with probability `P_j = sum_c p_c w_c q_c,real`, and each
//! `w_c` is multiplied by `q_c,j / P_j` (real or null). The products of the `P_j` telescope
//! to the path mixture because `sum_c p_c w_c = 1` holds after every step (induction:
//! `sum_c p_c w_c q_c,j / P_j = P_j / P_j`), so the per-collision channel probabilities
//! `p_c w_c` are exactly the mixture's posterior ("history-aware" in Kutz et al. 2017,
//! "Spectral and decomposition tracking", sec. 5.1). Two consequences:
//! - **unbiased** per channel, for every channel with `p_c > 0`: the sampled path density
//!   is at least `p_c prod_j q_c,j` wherever channel `c`'s integrand is non-zero, so
//!   `E[w_c 1{pass}] = T_c` and the collision density weighted by `w_c` is
//!   `sigma_t,c(t) T_c(t)`;
//! - **bounded**: `w_c <= 1 / p_c` for every channel (the mixture is at least its own
//!   `c` term), while tracking one channel only gives the others unbounded weights
//!   (`(k_c / k_hero)^n` after `n` real collisions).
//!
//! The weight carries no albedo: the caller multiplies by `albedo_c` at a real collision
//! (`sigma_s,c / sigma_t,c`), as the grey [`crate::tracking::delta_tracking`]'s callers do.

use crate::grid::MajorantSegment;
use crate::medium::channel_pdf;
use crate::ray_marching::{march, MAX_ORDER, RHO_MAX, RHO_MIN};
use crate::tracking::{control_extinction, roulette, roulette_limit, tentative, DepthToNext};
use risotto_components::Rgb;

/// Whether every channel of `k` is the same (a grey medium: the spectral estimators reduce
/// to the grey ones, and skip their per-channel weight updates).
#[inline]
fn grey(k: Rgb) -> bool {
    k.r == k.g && k.g == k.b
}

/// The outcome of [`spectral_tracking`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SpectralFlight {
    /// The real collision's distance when `collided`, else the end of the last segment.
    pub t: f32,
    /// A real collision happened before the segments ended.
    pub collided: bool,
    /// The per-channel MIS weight `w_c` (module docs): multiply the path throughput by it
    /// (and by the albedo at a collision). `(1, 1, 1)` for a grey `k`.
    pub weight: Rgb,
    /// Null (fictitious) collisions on the way.
    pub nulls: u32,
    /// Sampled `sigma` above the segment's majorant.
    pub violations: u32,
}

/// Spectral tracking of a free flight with one-sample spectral MIS (module docs): two
/// random numbers per tentative collision, as [`crate::tracking::delta_tracking`], whose
/// results it reproduces exactly for a grey `k`. `channel_pdf` is normalised here; channels
/// with `p_c = 0` are not estimated (their weight may be anything finite).
pub fn spectral_tracking(
    segments: impl IntoIterator<Item = MajorantSegment>,
    sigma: impl FnMut(f32) -> f32,
    k: Rgb,
    channel_pdf: [f32; 3],
    rand: impl FnMut() -> f32,
) -> SpectralFlight {
    track(
        segments,
        sigma,
        k,
        channel_pdf,
        None::<fn(f32, f32) -> Rgb>,
        rand,
    )
    .0
}

/// [`spectral_tracking`] that also gathers an emissive medium's radiance reaching the ray's
/// start, as [`crate::tracking::delta_tracking_emitting`] does (pbrt-v4): at every
/// tentative collision `t_k`, null or real, it adds `w_c(t_k-) j_c(t_k) / mu`, `w` the
/// running weight before the collision's decision and `j = emission(t, sigma(t))` the
/// emission coefficient. `w_c 1{reached t}` is unbiased for `T_c(t)` (the pass estimator of
/// the prefix) and the tentative collisions are a Poisson process of rate `mu` independent
/// of the decisions, so the sum's expectation is `int T_c(t) j_c(t) dt` per channel --
/// provided the majorant is positive wherever `j` is. The same random numbers and flight
/// as [`spectral_tracking`].
pub fn spectral_tracking_emitting(
    segments: impl IntoIterator<Item = MajorantSegment>,
    sigma: impl FnMut(f32) -> f32,
    k: Rgb,
    channel_pdf: [f32; 3],
    emission: impl FnMut(f32, f32) -> Rgb,
    rand: impl FnMut() -> f32,
) -> (SpectralFlight, Rgb) {
    track(segments, sigma, k, channel_pdf, Some(emission), rand)
}

fn track(
    segments: impl IntoIterator<Item = MajorantSegment>,
    mut sigma: impl FnMut(f32) -> f32,
    k: Rgb,
    p0: [f32; 3],
    mut emission: Option<impl FnMut(f32, f32) -> Rgb>,
    mut rand: impl FnMut() -> f32,
) -> (SpectralFlight, Rgb) {
    let p0 = Rgb::from_array(channel_pdf(Rgb::from_array(p0)));
    let is_grey = grey(k);
    let mut out = SpectralFlight {
        weight: Rgb::WHITE,
        ..SpectralFlight::default()
    };
    let mut gathered = Rgb::BLACK;
    let mut w = Rgb::WHITE;
    let mut depth = DepthToNext::NONE;
    for seg in segments {
        out.t = seg.t1;
        let mu = seg.majorant;
        let inv = 1.0 / mu;
        let mut nulls = 0;
        let hit = tentative(
            &seg,
            mu,
            &mut sigma,
            &mut rand,
            &mut out.violations,
            &mut depth,
            |t, s, rand| {
                if let Some(e) = &mut emission {
                    gathered += e(t, s) * w * inv;
                }
                // P_real * mu = sum_c p_c w_c k_c sigma (module docs); p w sums to 1 up to
                // rounding, renormalised by channel_pdf. Grey: exactly sigma, as the grey
                // tracker's test `u mu >= sigma`.
                let kbar = if is_grey {
                    k.r
                } else {
                    let p = channel_pdf(p0 * w);
                    p[0] * k.r + p[1] * k.g + p[2] * k.b
                };
                let null = rand() * mu >= s * kbar;
                if !is_grey {
                    // q_c / P: real k_c / kbar, null (mu - k_c s) / (mu - kbar s); a null
                    // is only drawn when mu > kbar s, so the denominators are positive.
                    let f = if null {
                        let d = 1.0 / (mu - kbar * s);
                        k.map(|kc| (mu - kc * s) * d)
                    } else {
                        k * (1.0 / kbar)
                    };
                    w *= f;
                    if !w.is_finite() {
                        w = Rgb::BLACK;
                    }
                }
                nulls += null as u32;
                null
            },
        );
        out.nulls += nulls;
        if let Some(t) = hit {
            out.t = t;
            out.collided = true;
            break;
        }
    }
    out.weight = w;
    (out, gathered)
}

/// A per-channel transmittance estimate.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RgbTransmittance {
    /// The estimate (its expectation is `exp(-int sigma_t,c)` per channel).
    pub value: Rgb,
    /// Tentative collisions (or lookups, for the marching estimators) evaluated.
    pub nulls: u32,
    /// Sampled `sigma` above the segment's majorant.
    pub violations: u32,
}

/// Delta-tracking transmittance of a chromatic medium: a [`spectral_tracking`] free flight
/// with equal channel probabilities, its MIS weight if it passes and 0 if it collides.
/// Unbiased per channel (`E[w_c 1{pass}] = T_c`) and at most 3 (`1 / p_c`); a per-channel
/// 0/1 indicator from tracking one channel would be unbounded or noisy in the others.
pub fn delta_tracking_transmittance_rgb(
    segments: impl IntoIterator<Item = MajorantSegment>,
    sigma: impl FnMut(f32) -> f32,
    k: Rgb,
    rand: impl FnMut() -> f32,
) -> RgbTransmittance {
    let f = spectral_tracking(segments, sigma, k, [1.0; 3], rand);
    pass_value(f)
}

/// [`delta_tracking_transmittance_rgb`] gathering emission as
/// [`spectral_tracking_emitting`] (pbrt's sum: up to the collision, if any).
pub fn delta_tracking_emitting_rgb(
    segments: impl IntoIterator<Item = MajorantSegment>,
    sigma: impl FnMut(f32) -> f32,
    k: Rgb,
    emission: impl FnMut(f32, f32) -> Rgb,
    rand: impl FnMut() -> f32,
) -> (RgbTransmittance, Rgb) {
    let (f, e) = spectral_tracking_emitting(segments, sigma, k, [1.0; 3], emission, rand);
    (pass_value(f), e)
}

fn pass_value(f: SpectralFlight) -> RgbTransmittance {
    RgbTransmittance {
        value: if f.collided { Rgb::BLACK } else { f.weight },
        nulls: f.nulls + f.collided as u32,
        violations: f.violations,
    }
}

/// Ratio tracking (or, with `residual`, residual ratio tracking) of every channel along one
/// sequence of tentative collisions at the grey rate, with three running products.
///
/// Ratio: each collision multiplies `T_c` by `1 - k_c sigma / mu`, non-negative since
/// `k_c <= 1`. Residual: channel `c`'s control is `k_c m` (`m` the segment's minorant,
/// clamped to `[0, mu]`), its residual `k_c (sigma - m)` lies in `[0, mu - m]`, so the
/// shared residual rate `mu - m` (the densest channel's, as in
/// [`crate::tracking::residual_ratio_tracking`]) bounds every channel's; each collision
/// multiplies `T_c` by `1 - k_c (sigma - m) / (mu - m)`, and `T_c` ends times
/// `exp(-k_c int m)`. Unbiased per channel for any bound above the residual (Novák et al.
/// 2014, sec. 4).
pub fn ratio_tracking_rgb(
    segments: impl IntoIterator<Item = MajorantSegment>,
    sigma: impl FnMut(f32) -> f32,
    k: Rgb,
    rand: impl FnMut() -> f32,
    residual: bool,
) -> RgbTransmittance {
    ratio_rgb(
        segments,
        sigma,
        k,
        None::<fn(f32, f32) -> Rgb>,
        rand,
        residual,
    )
    .0
}

/// [`ratio_tracking_rgb`] gathering emission as [`crate::tracking::ratio_tracking_emitting`]
/// does, per channel: at every tentative collision it adds `T_k,c j_c(t_k) / bound_k`,
/// `T_k,c` the running estimate of channel `c` just before `t_k` (with its control's
/// `exp(-k_c int_0^t_k m)`). The same random numbers and transmittance as
/// [`ratio_tracking_rgb`].
pub fn ratio_tracking_emitting_rgb(
    segments: impl IntoIterator<Item = MajorantSegment>,
    sigma: impl FnMut(f32) -> f32,
    k: Rgb,
    emission: impl FnMut(f32, f32) -> Rgb,
    rand: impl FnMut() -> f32,
    residual: bool,
) -> (RgbTransmittance, Rgb) {
    ratio_rgb(segments, sigma, k, Some(emission), rand, residual)
}

fn ratio_rgb(
    segments: impl IntoIterator<Item = MajorantSegment>,
    mut sigma: impl FnMut(f32) -> f32,
    k: Rgb,
    mut emission: Option<impl FnMut(f32, f32) -> Rgb>,
    mut rand: impl FnMut() -> f32,
    residual: bool,
) -> (RgbTransmittance, Rgb) {
    let mut out = RgbTransmittance {
        value: Rgb::WHITE,
        ..RgbTransmittance::default()
    };
    let mut gathered = Rgb::BLACK;
    // Per channel: int_0 k_c m over the segments so far.
    let mut control_depth = Rgb::BLACK;
    let mut depth = DepthToNext::NONE;
    for seg in segments {
        let control = control_extinction(&seg, residual);
        let bound = seg.majorant - control;
        let inv = 1.0 / bound;
        let control_c = k * control;
        let depth0 = control_depth;
        let (mut value, mut nulls) = (out.value, 0);
        // Every channel's full estimate below the roulette's bound.
        let limit =
            (depth0 + control_c.map(|c| c.max(0.0)) * (seg.t1 - seg.t0)).map(roulette_limit);
        let ended = tentative(
            &seg,
            bound,
            &mut sigma,
            &mut rand,
            &mut out.violations,
            &mut depth,
            |t, s, rand| {
                if let Some(e) = &mut emission {
                    let depth = depth0 + control_c * (t - seg.t0);
                    gathered += e(t, s) * value * depth.map(|x| (-x).exp()) * inv;
                }
                value = Rgb::new(
                    value.r * (1.0 - (k.r * s - control_c.r) / bound),
                    value.g * (1.0 - (k.g * s - control_c.g) / bound),
                    value.b * (1.0 - (k.b * s - control_c.b) / bound),
                );
                nulls += 1;
                let low = value.r < limit.r && value.g < limit.g && value.b < limit.b;
                value = value * roulette(low, value.is_black(), rand);
                !value.is_black()
            },
        );
        if control > 0.0 {
            control_depth += control_c * (seg.t1 - seg.t0);
        }
        out.value = value;
        out.nulls += nulls;
        if ended.is_some() {
            break;
        }
    }
    out.value *= control_depth.map(|x| (-x).exp());
    (out, gathered)
}

/// Fixed-step ray marching of every channel: one jittered march of `sigma` (the densest
/// channel; see [`crate::ray_marching`]) gives `X`, and channel `c` gets `exp(-k_c X)` (the
/// same march, so the same random number and lookups; biased as the grey estimator).
pub fn ray_marching_transmittance_rgb(
    segments: impl IntoIterator<Item = MajorantSegment>,
    mut sigma: impl FnMut(f32) -> f32,
    k: Rgb,
    mut rand: impl FnMut() -> f32,
    step: f32,
) -> RgbTransmittance {
    let m = march(segments, &mut sigma, step, rand());
    RgbTransmittance {
        value: k.map(|kc| (-(kc * m.depth)).exp()),
        nulls: m.lookups,
        violations: m.violations,
    }
}

/// The unbiased ray-marching estimator ([`crate::ray_marching::unbiased_ray_marching`]) of
/// every channel from the same marches: the pivot `c` and the marches `X_j` of `sigma` are
/// shared, channel `c`'s pivot is `k_c c` and its series factors `k_c (c - X_j) / (j q_j)`,
/// so each channel's series is the grey estimator's for `k_c sigma` with the same roulette.
/// The roulette rate is set by the densest channel's pivot variation (any rate that depends
/// on the pivot only keeps every channel unbiased; the densest channel's is the largest).
pub fn unbiased_ray_marching_rgb<I: IntoIterator<Item = MajorantSegment>>(
    segments: impl Fn() -> I,
    mut sigma: impl FnMut(f32) -> f32,
    k: Rgb,
    mut rand: impl FnMut() -> f32,
    step: f32,
) -> RgbTransmittance {
    let pivot = march(segments(), &mut sigma, step, rand());
    let (mut lookups, mut violations) = (pivot.lookups, pivot.violations);
    let rho = (2.0 * pivot.variation).clamp(RHO_MIN, RHO_MAX);
    let (mut sum, mut term) = (Rgb::WHITE, Rgb::WHITE);
    for order in 1..=MAX_ORDER {
        let q = (rho / order as f32).min(1.0);
        if q < 1.0 && rand() >= q {
            break;
        }
        let x = march(segments(), &mut sigma, step, rand());
        lookups += x.lookups;
        violations += x.violations;
        let d = (pivot.depth - x.depth) / (order as f32 * q);
        term = Rgb::new(term.r * (k.r * d), term.g * (k.g * d), term.b * (k.b * d));
        sum += term;
        if term.is_black() {
            break;
        }
    }
    RgbTransmittance {
        value: k.map(|kc| (-(kc * pivot.depth)).exp()) * sum,
        nulls: lookups,
        violations,
    }
}

#[cfg(test)]
mod tests {
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
        let exact = [0, 1, 2].map(|c| {
            crate::simpson_01(2_000, |t| exact_t(tau, t)[c] * (c as f64 + 1.0) * (2.0 + t))
        });
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
                let (old, oe) =
                    ratio_tracking_emitting(segs.clone(), sigma, j, rng(seed), residual);
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
}
