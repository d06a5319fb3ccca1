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
use crate::march::{march, unbiased_march_rgb};
use crate::medium::channel_pdf;
use crate::tracking::{control_extinction, roulette, roulette_limit, tentative, DepthToNext};
use risotto_components::Rgb;
use std::cell::Cell;

/// Whether every channel of `k` is the same (a grey medium: the spectral estimators reduce
/// to the grey ones, and skip their per-channel weight updates).
#[inline]
fn grey(k: Rgb) -> bool {
    k.r == k.g && k.g == k.b
}

/// The extinction of every channel along a ray, in the form the trackers use: at ray
/// parameter `t`, `sigma_t,c(t) = k_c(t) sigma(t)` with `sigma(t)` the densest channel's
/// extinction (bounded by the segments' grey majorant) and every `k_c(t)` in `[0, 1]`.
///
/// Two forms: [`Proportional`] (a chromatic `scale` times one density: `k` constant), and
/// [`PerChannel`] (a density per channel, e.g. a 3-channel grid: `k(t) = sigma_t(t) /
/// max_c sigma_t,c(t)`, varying along the ray). Every estimator here is written against
/// `k(t)`; with a constant `k` it computes exactly what it did with `k` fixed.
pub trait ChannelExtinction {
    /// `(sigma(t), k(t))`.
    fn at(&mut self, t: f32) -> (f32, Rgb);
    /// The factors of residual ratio tracking's per-channel controls: channel `c`'s control
    /// on a segment is `control_ratio_c` times the segment's minorant. [`Proportional`]:
    /// `k` (the minorant bounds the densest channel); [`PerChannel`]: 1 (the minorant
    /// bounds every channel from below, [`crate::grid::DensityChannels::majorants`]).
    fn control_ratios(&self) -> Rgb;
}

/// `sigma_t,c(t) = k_c sigma(t)`: a density times a chromatic scale (`k = scale /
/// max(scale)`).
#[derive(Clone, Copy, Debug)]
pub struct Proportional<F> {
    /// `sigma(t)`, the densest channel's extinction.
    pub sigma: F,
    /// `k`, every channel in `[0, 1]`.
    pub k: Rgb,
}

impl<F: FnMut(f32) -> f32> ChannelExtinction for Proportional<F> {
    #[inline]
    fn at(&mut self, t: f32) -> (f32, Rgb) {
        ((self.sigma)(t), self.k)
    }
    #[inline]
    fn control_ratios(&self) -> Rgb {
        self.k
    }
}

/// Each channel's extinction given at every point (`sigma_t(t)` per channel, each >= 0),
/// e.g. `scale_c density_c` of a 3-channel grid: split as `sigma = max_c sigma_t,c`, `k =
/// sigma_t / sigma` (`(1, 1, 1)` where every channel is 0).
#[derive(Clone, Copy, Debug)]
pub struct PerChannel<F>(pub F);

impl<F: FnMut(f32) -> Rgb> ChannelExtinction for PerChannel<F> {
    #[inline]
    fn at(&mut self, t: f32) -> (f32, Rgb) {
        let s = (self.0)(t);
        let m = s.max_channel();
        if m > 0.0 {
            // The densest channel's ratio is exactly 1 (x / x), so its factors match the
            // grey tracker's.
            (m, s.map(|c| c / m))
        } else {
            (0.0, Rgb::WHITE)
        }
    }
    #[inline]
    fn control_ratios(&self) -> Rgb {
        Rgb::WHITE
    }
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
        Proportional { sigma, k },
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
    track(
        segments,
        Proportional { sigma, k },
        channel_pdf,
        Some(emission),
        rand,
    )
}

/// [`spectral_tracking_emitting`] for any [`ChannelExtinction`] (e.g. [`PerChannel`], a
/// density per channel: the ratios `k(t)` then vary along the ray and enter each collision's
/// real probability and weight update as they are there; the module docs' derivation holds
/// point by point). `emission(t, sigma)` gets the densest channel's extinction. With
/// [`Proportional`] it is [`spectral_tracking_emitting`].
pub fn spectral_tracking_channels(
    segments: impl IntoIterator<Item = MajorantSegment>,
    sigma: impl ChannelExtinction,
    channel_pdf: [f32; 3],
    emission: impl FnMut(f32, f32) -> Rgb,
    rand: impl FnMut() -> f32,
) -> (SpectralFlight, Rgb) {
    track(segments, sigma, channel_pdf, Some(emission), rand)
}

fn track(
    segments: impl IntoIterator<Item = MajorantSegment>,
    mut extinction: impl ChannelExtinction,
    p0: [f32; 3],
    mut emission: Option<impl FnMut(f32, f32) -> Rgb>,
    mut rand: impl FnMut() -> f32,
) -> (SpectralFlight, Rgb) {
    let p0 = Rgb::from_array(channel_pdf(Rgb::from_array(p0)));
    // k at the last lookup (tentative() asks for sigma, then visits the same point).
    let k_at = Cell::new(Rgb::WHITE);
    let mut sigma = |t: f32| {
        let (s, k) = extinction.at(t);
        k_at.set(k);
        s
    };
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
                let k = k_at.get();
                let is_grey = grey(k);
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
    f.pass_value()
}

impl SpectralFlight {
    /// The flight as a delta-tracking transmittance estimate: its weight if it passed, 0 if
    /// it collided (its tentative collisions, the real one included, counted).
    pub fn pass_value(self) -> RgbTransmittance {
        RgbTransmittance {
            value: if self.collided {
                Rgb::BLACK
            } else {
                self.weight
            },
            nulls: self.nulls + self.collided as u32,
            violations: self.violations,
        }
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
        Proportional { sigma, k },
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
    ratio_rgb(
        segments,
        Proportional { sigma, k },
        Some(emission),
        rand,
        residual,
    )
}

/// [`ratio_tracking_rgb`] (or, with `emission`, [`ratio_tracking_emitting_rgb`]) for any
/// [`ChannelExtinction`]: each collision multiplies `T_c` by `1 - (k_c(t) sigma(t) -
/// control_c) / bound`, channel `c`'s control `control_c` being the segment's minorant times
/// [`ChannelExtinction::control_ratios`]. With [`PerChannel`] the minorant must bound every
/// channel from below (as [`crate::grid::DensityChannels::majorants`]' does), so every
/// residual lies in `[0, bound]`. Returns the emission gathered (black without `emission`).
pub fn ratio_tracking_channels(
    segments: impl IntoIterator<Item = MajorantSegment>,
    sigma: impl ChannelExtinction,
    emission: Option<impl FnMut(f32, f32) -> Rgb>,
    rand: impl FnMut() -> f32,
    residual: bool,
) -> (RgbTransmittance, Rgb) {
    ratio_rgb(segments, sigma, emission, rand, residual)
}

fn ratio_rgb(
    segments: impl IntoIterator<Item = MajorantSegment>,
    mut extinction: impl ChannelExtinction,
    mut emission: Option<impl FnMut(f32, f32) -> Rgb>,
    mut rand: impl FnMut() -> f32,
    residual: bool,
) -> (RgbTransmittance, Rgb) {
    let control_k = extinction.control_ratios();
    let k_at = Cell::new(Rgb::WHITE);
    let mut sigma = |t: f32| {
        let (s, k) = extinction.at(t);
        k_at.set(k);
        s
    };
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
        let control_c = control_k * control;
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
                let k = k_at.get();
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
    sigma: impl FnMut(f32) -> f32,
    k: Rgb,
    rand: impl FnMut() -> f32,
    step: f32,
) -> RgbTransmittance {
    let (value, nulls, violations) = unbiased_march_rgb(segments, sigma, k, rand, step);
    RgbTransmittance {
        value,
        nulls,
        violations,
    }
}

#[cfg(test)]
mod tests;
