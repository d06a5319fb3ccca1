//! Homogeneous participating media, one ray segment at a time (plus a column form): exact
//! transmittance, free-flight distance sampling with one-sample spectral MIS over the RGB
//! channels, and equiangular sampling of a distance towards a point light.
//!
//! # Conventions
//! - Coefficients are per world unit and per RGB channel, non-negative and finite:
//!   extinction `sigma_t = sigma_a + sigma_s`, scattering `sigma_s <= sigma_t`,
//!   single-scattering albedo `sigma_s / sigma_t`.
//! - A segment is `[0, tmax]` along a **unit** direction from its start; `tmax` may be
//!   `+inf` (an unbounded medium) or 0.
//! - Distance pdfs are densities per unit length. A returned pdf of 0 means "no sample"
//!   (an empty segment); the caller skips it.
//! - Nothing here returns NaN for valid coefficients and `u` in `[0, 1]`.
//!
//! # Why spectral MIS
//! Sampling distances with one channel's `sigma_t` and weighting all three by
//! `T_c(t) / pdf(t)` gives weights `exp(-(sigma_c - sigma_picked) t)` that are unbounded when
//! the channels differ (the fireflies of a chromatic medium). Treating the three per-channel
//! exponential samplers as three techniques combined by the one-sample balance heuristic
//! (Veach 1997, sec. 9.2.4; applied to chromatic media by Miller, Georgiev and Jarosz 2019,
//! "A null-scattering path integral formulation of light transport", sec. 6, and implemented
//! by Mitsuba 3's `volpathmis`) replaces the single channel's pdf by the mixture
//! `pdf_mis(t) = sum_c p_c sigma_t,c exp(-sigma_t,c t)`, which is at least
//! `p_c sigma_t,c exp(-sigma_t,c t)` for *every* channel: each channel's weight is then bounded
//! by `albedo_c / p_c`.

use crate::distribution::ONE_MINUS_EPSILON;
use risotto_components::{Rgb, Vec3};

/// Whether free flights from `p` in a medium of extinction `sigma_t` can no longer move the
/// point. A coordinate `x` changes only by steps of at least half its float spacing
/// (`|x| f32::EPSILON`, up to a factor 2); against the finest of the three, `sigma_t x spacing
/// / 2 > 32` in every channel makes a flight that moves the point at all less likely than
/// `e^-32` (1e-14). A walk there stays at one point for good (with albedo 1 its throughput
/// never falls, so neither Russian roulette nor anything but the path-vertex limit ends it),
/// and what it still gathers is nil: the point lies at least a spacing inside the boundary
/// it entered through (the spawn offset), so a light sample from it leaves through more than
/// 64 optical depths. Callers end such walks instead of stepping them in place. `false` where
/// a channel is empty or a coordinate is 0 (its spacing is then the smallest subnormal).
#[inline]
pub fn flights_frozen(sigma_t: Rgb, p: Vec3) -> bool {
    let spacing = p.abs().min_element() * f32::EPSILON;
    sigma_t.min_channel() * spacing > FROZEN_DEPTH
}

/// The optical depth of a float spacing above which [`flights_frozen`] holds.
const FROZEN_DEPTH: f32 = 64.0;

/// Whether [`flights_frozen`] can hold anywhere in the box `[lo, hi]` (or within 1 % of its
/// coordinates around it): false lets a caller skip the per-event test for a whole volume,
/// as for every medium whose mean free path is above a ten-millionth of its coordinates.
#[inline]
pub fn flights_may_freeze(sigma_t: Rgb, lo: Vec3, hi: Vec3) -> bool {
    flights_may_freeze_within(sigma_t, lo.abs().max(hi.abs()).max_element())
}

/// [`flights_may_freeze`] for the points whose coordinates are all at most `largest` in
/// magnitude.
#[inline]
pub fn flights_may_freeze_within(sigma_t: Rgb, largest: f32) -> bool {
    let depth = sigma_t.min_channel() * (largest * 1.01) * f32::EPSILON;
    // NaN (a malformed medium): test each event.
    depth > FROZEN_DEPTH || depth.is_nan()
}

/// An optical depth sampled from the unit exponential, `-ln(1 - u)` for a uniform
/// `u in [0, 1)` (the inverse CDF of `exp(-tau)`). `1 - u` is exact for the samplers'
/// multiples of 2^-24 and at least 2^-24 after the clamp (finite), and `ln` costs about half
/// of `ln_1p`: every free flight and tentative collision of every medium draws one.
#[inline]
pub fn sample_optical_depth(u: f32) -> f32 {
    -(1.0 - u.clamp(0.0, ONE_MINUS_EPSILON)).ln()
}

/// Optical depth `sigma_t * distance`, with `0 * inf = 0`: an empty medium over an infinite
/// distance, or any medium over a zero distance, attenuates nothing (IEEE would give NaN).
#[inline]
pub fn optical_depth(sigma_t: f32, distance: f32) -> f32 {
    if sigma_t == 0.0 || distance == 0.0 {
        0.0
    } else {
        sigma_t * distance
    }
}

/// Beer-Lambert transmittance of a homogeneous medium, `T = exp(-sigma_t d)` per channel:
/// exact, 1 for `sigma_t = 0` even at `d = inf`, 0 for `sigma_t > 0` at `d = inf`.
#[inline]
pub fn transmittance(sigma_t: Rgb, distance: f32) -> Rgb {
    let one = |s: f32| (-optical_depth(s, distance)).exp();
    // A grey medium (the same bits in every channel) needs one exponential, not three.
    let bits = sigma_t.to_array().map(f32::to_bits);
    if bits[0] == bits[1] && bits[1] == bits[2] {
        Rgb::splat(one(sigma_t.r))
    } else {
        sigma_t.map(one)
    }
}

/// Channel-selection probabilities for [`sample_free_flight`] proportional to the path
/// throughput (channels the path no longer carries are never picked; channels it carries
/// always have `p_c > 0`, which the estimator's unbiasedness needs, see
/// [`sample_free_flight`]). Negative and NaN channels count as 0; uniform when nothing is
/// left or the sum is not finite.
#[inline]
pub fn channel_pdf(throughput: Rgb) -> [f32; 3] {
    let a = throughput.to_array().map(|c| c.max(0.0));
    let sum = a[0] + a[1] + a[2];
    if sum > 0.0 && sum.is_finite() {
        a.map(|c| c / sum)
    } else {
        [1.0 / 3.0; 3]
    }
}

/// `p` normalised to sum 1 as [`channel_pdf`] does, so that every function here agrees on
/// the same probabilities.
#[inline]
fn normalized(p: [f32; 3]) -> [f32; 3] {
    channel_pdf(Rgb::from_array(p))
}

/// `sum_c p_c x_c`.
#[inline]
fn expect(p: [f32; 3], x: Rgb) -> f32 {
    p[0] * x.r + p[1] * x.g + p[2] * x.b
}

/// `T_c(d) / T_ref(d) = exp(-(sigma_c - sigma_ref) d)` per channel. The estimator's weights
/// are ratios in which `T_ref(d)` cancels; dividing it out first keeps every term finite and
/// away from underflow: when the reference channel produced the distance, `sigma_ref d` is at
/// most `-ln(2^-24) ~ 16.6`, so no ratio exceeds `e^16.6` and the reference term is exactly 1.
#[inline]
fn transmittance_relative(sigma_t: Rgb, sigma_ref: f32, d: f32) -> Rgb {
    sigma_t.map(|s| (-optical_depth(s - sigma_ref, d)).exp())
}

/// The outcome of one free flight through a homogeneous segment. The default (`t = 0`, not
/// scattered, black weight) is a placeholder for output columns.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FreeFlight {
    /// Distance of the scattering event from the segment start when `scattered`, else
    /// `tmax` (the segment's end, possibly `+inf`).
    pub t: f32,
    /// `true`: a real scattering event at `t < tmax`; `false`: the flight passed the segment.
    pub scattered: bool,
    /// The factor to multiply the path throughput by, per channel:
    /// `sigma_s T(t) / pdf_mis(t)` at a scattering event (it **includes `sigma_s`**, so the
    /// phase function sampled next weighs `p / pdf = 1`, no albedo again), and
    /// `T(tmax) / P_mis(pass)` on passing. Finite and non-negative.
    pub weight: Rgb,
}

/// Samples a free-flight distance in a homogeneous medium with one-sample spectral MIS.
///
/// `u_channel` picks channel `c` with probability `channel_pdf[c]` (normalised here; see
/// [`channel_pdf`]); `u_distance` samples `t` from that channel's exponential,
/// `t = -ln(1 - u) / sigma_t,c` (channels with `sigma_t = 0` never sample a distance: picking
/// one passes the segment). If `t < tmax` the flight scatters at `t`, else it passes.
///
/// **Unbiasedness.** The distance density of this procedure is the mixture
/// `pdf_mis(t) = sum_c p_c sigma_t,c exp(-sigma_t,c t)` on `[0, tmax)` ([`free_flight_pdf`])
/// plus a point mass `P_mis(pass) = sum_c p_c exp(-sigma_t,c tmax)` at `tmax`
/// ([`free_flight_pass_probability`]). With `f_c(t) = sigma_s,c T_c(t)` the collision
/// integrand, `E[weight_c 1{scatter}] = int_0^tmax f_c(t) / pdf_mis(t) pdf_mis(t) dt =
/// int_0^tmax sigma_s,c T_c(t) dt = albedo_c (1 - T_c(tmax))`, and
/// `E[weight_c 1{pass}] = T_c(tmax)`: the two terms of the volume rendering equation for a
/// homogeneous segment, exactly, per channel -- provided the pdf is positive wherever
/// `f_c` or `T_c(tmax)` is, which holds when `p_c > 0` for every channel the path carries
/// (pass-through then has probability at least `p_c T_c(tmax)`, and a collision density at
/// least `p_c sigma_t,c T_c(t)`). This is Miller et al. 2019, eq. 19's balance-heuristic
/// weight with the `sigma_s` of the real-scattering event folded in, for a medium without
/// null collisions (majorant = `sigma_t`).
pub fn sample_free_flight(
    sigma_t: Rgb,
    sigma_s: Rgb,
    channel_pdf: [f32; 3],
    u_channel: f32,
    u_distance: f32,
    tmax: f32,
) -> FreeFlight {
    if sigma_t.r == sigma_t.g
        && sigma_t.g == sigma_t.b
        && sigma_s.r == sigma_s.g
        && sigma_s.g == sigma_s.b
    {
        return grey_free_flight(sigma_t.r, sigma_s.r, u_distance, tmax);
    }
    let p = normalized(channel_pdf);
    // NaN -> 0: a malformed segment is empty rather than poisoning the throughput.
    let tmax = tmax.max(0.0);
    // The last channel with p > 0 takes the rounding slack of the cumulative sum.
    let c = if u_channel < p[0] || (p[1] == 0.0 && p[2] == 0.0) {
        0
    } else if u_channel < p[0] + p[1] || p[2] == 0.0 {
        1
    } else {
        2
    };
    let sigma_c = sigma_t.to_array()[c];
    if sigma_c > 0.0 {
        // Inverse CDF of sigma e^(-sigma t).
        let s = sample_optical_depth(u_distance);
        let t = s / sigma_c;
        if t < tmax {
            // sigma_s T(t) / sum_k p_k sigma_k T_k(t), numerator and denominator divided by
            // T_c(t) (see transmittance_relative).
            let r = transmittance_relative(sigma_t, sigma_c, t);
            let pdf = expect(p, sigma_t * r);
            return FreeFlight {
                t,
                scattered: true,
                weight: finite_ratio(sigma_s * r, pdf),
            };
        }
    }
    // Passing. For finite tmax, T(tmax) / sum_k p_k T_k(tmax) relative to the picked channel
    // (which passed, so sigma_c tmax <= ~16.6); at tmax = inf only channels with sigma_t = 0
    // pass, and the plain transmittance (0 or 1 per channel) is exact.
    let r = if tmax.is_finite() {
        transmittance_relative(sigma_t, sigma_c, tmax)
    } else {
        transmittance(sigma_t, tmax)
    };
    FreeFlight {
        t: tmax,
        scattered: false,
        weight: finite_ratio(r, expect(p, r)),
    }
}

/// [`sample_free_flight`] when every channel has the same `sigma_t` and `sigma_s` (a grey
/// medium: the subsurface and smoke scenes, where the walk's events are the hot loop): the
/// channel choice does not matter, every ratio `T_c / T_ref` is exactly 1, so the weights
/// are the albedo `sigma_s / sigma_t` at an event and exactly 1 on passing, with no
/// exponentials.
#[inline]
fn grey_free_flight(sigma_t: f32, sigma_s: f32, u_distance: f32, tmax: f32) -> FreeFlight {
    let tmax = tmax.max(0.0);
    if sigma_t > 0.0 {
        let s = sample_optical_depth(u_distance);
        let t = s / sigma_t;
        if t < tmax {
            return FreeFlight {
                t,
                scattered: true,
                weight: Rgb::splat(sigma_s / sigma_t),
            };
        }
    }
    FreeFlight {
        t: tmax,
        scattered: false,
        weight: Rgb::WHITE,
    }
}

/// `x / d`, or black if `d` is not positive or the result is not finite (cannot happen for
/// valid inputs, see [`sample_free_flight`]; kept so no NaN can reach the film).
#[inline]
fn finite_ratio(x: Rgb, d: f32) -> Rgb {
    let w = x * (1.0 / d);
    if d > 0.0 && w.is_finite() {
        w
    } else {
        Rgb::BLACK
    }
}

/// The density per unit length with which [`sample_free_flight`] scatters at `t` inside a
/// segment (`t < tmax`): `sum_c p_c sigma_t,c exp(-sigma_t,c t)`. This is the distance
/// technique's pdf for MIS against [`equiangular_pdf`].
pub fn free_flight_pdf(sigma_t: Rgb, channel_pdf: [f32; 3], t: f32) -> f32 {
    let p = normalized(channel_pdf);
    expect(p, sigma_t * transmittance(sigma_t, t))
}

/// The probability that [`sample_free_flight`] passes a segment of length `tmax`:
/// `sum_c p_c exp(-sigma_t,c tmax)`.
pub fn free_flight_pass_probability(sigma_t: Rgb, channel_pdf: [f32; 3], tmax: f32) -> f32 {
    let p = normalized(channel_pdf);
    expect(p, transmittance(sigma_t, tmax.max(0.0)))
}

/// [`sample_free_flight`] over columns of rays in one homogeneous medium, with channels
/// picked in proportion to each ray's throughput ([`channel_pdf`]).
///
/// # Panics
/// If the columns have different lengths.
pub fn sample_free_flights(
    sigma_t: Rgb,
    sigma_s: Rgb,
    throughput: &[Rgb],
    u_channel: &[f32],
    u_distance: &[f32],
    tmax: &[f32],
    out: &mut [FreeFlight],
) {
    let n = out.len();
    assert!(
        throughput.len() == n && u_channel.len() == n && u_distance.len() == n && tmax.len() == n,
        "sample_free_flights: columns of different lengths"
    );
    for i in 0..n {
        out[i] = sample_free_flight(
            sigma_t,
            sigma_s,
            channel_pdf(throughput[i]),
            u_channel[i],
            u_distance[i],
            tmax[i],
        );
    }
}

// ---------------------------------------------------------------------------------------
// Equiangular sampling
// ---------------------------------------------------------------------------------------

/// Smallest distance from the light to the ray line, relative to the light's distance from
/// the origin. A light on the line makes the equiangular density a Dirac delta (and the
/// inverse-square integrand non-integrable); flooring the distance keeps a finite, valid
/// density -- any `h > 0` gives a normalised pdf, so the floor costs efficiency only in
/// near-degenerate cases, never correctness. 1e-4 keeps the peak ~800 f32 ulps of `t` wide:
/// a narrower density cannot be represented by f32 distances, whose rounding would then no
/// longer follow the pdf evaluated at them.
const EQUIANGULAR_MIN_H_REL: f64 = 1e-4;
/// Absolute floor of that distance, for a light exactly at the ray origin.
const EQUIANGULAR_MIN_H_ABS: f64 = 1e-30;

/// A segment `[0, tmax]` seen from a point light, in f64 (the angles near `+-pi/2` and the
/// differences of nearly equal distances need the extra precision).
struct EquiangularSegment {
    /// Ray parameter of the light's foot point on the ray line.
    delta: f64,
    /// Distance from the light to the ray line (floored).
    h: f64,
    /// `tmax`.
    tmax: f64,
    /// Angle subtended by the segment at the light, in `(0, pi)`.
    dtheta: f64,
}

impl EquiangularSegment {
    /// `None` for an empty segment (`tmax <= 0` or NaN).
    fn new(origin: Vec3, dir: Vec3, light_pos: Vec3, tmax: f32) -> Option<Self> {
        if tmax.is_nan() || tmax <= 0.0 {
            return None;
        }
        let v = (light_pos - origin).as_dvec3();
        let d = dir.as_dvec3();
        let delta = v.dot(d);
        // |v x d| rather than sqrt(|v|^2 - delta^2), which cancels for lights near the line.
        let h = v
            .cross(d)
            .length()
            .max(EQUIANGULAR_MIN_H_REL * v.length())
            .max(EQUIANGULAR_MIN_H_ABS);
        let b = tmax as f64;
        // theta_b - theta_a with theta_x = atan((x - delta) / h), a = 0, as one atan2:
        // tan(theta_b - theta_a) = b h / (h^2 - delta (b - delta)). Unlike the difference of
        // two atans it stays accurate when both angles are near +-pi/2 (a segment far from
        // the light's foot point), and its b -> inf limit is atan2(h, -delta).
        let dtheta = if b.is_finite() {
            (b * h).atan2(h * h - delta * (b - delta))
        } else {
            h.atan2(-delta)
        };
        (dtheta > 0.0).then_some(EquiangularSegment {
            delta,
            h,
            tmax: b,
            dtheta,
        })
    }

    /// Kulla and Fajardo 2012, eq. 6: `pdf(t) = h / (dtheta (h^2 + (t - delta)^2))`.
    fn pdf(&self, t: f64) -> f64 {
        if !(0.0..=self.tmax).contains(&t) {
            return 0.0;
        }
        let x = t - self.delta;
        self.h / (self.dtheta * (self.h * self.h + x * x))
    }

    /// Kulla and Fajardo 2012, eq. 5, `t = delta + h tan(theta_a + u dtheta)`, rewritten
    /// around the segment start so that nothing cancels: with `phi = u dtheta` and the
    /// tangent addition formula, `t = sin(phi) (h^2 + delta^2) / (h cos(phi) + delta sin(phi))`.
    /// The denominator is `R cos(theta_a + phi) > 0` on the segment, so `t >= 0` and there is
    /// no tangent of an angle that rounding can push past `pi/2`.
    fn sample(&self, u: f64) -> f64 {
        let (s, c) = (u * self.dtheta).sin_cos();
        let den = self.h * c + self.delta * s;
        if den > 0.0 {
            (s * (self.h * self.h + self.delta * self.delta) / den).min(self.tmax)
        } else {
            self.tmax
        }
    }
}

/// Equiangular sampling (Kulla and Fajardo 2012, "Importance Sampling Techniques for Path
/// Tracing in Participating Media", sec. 4.1) of a distance `t` in `[0, tmax]` along the ray
/// `origin + t dir` (`dir` unit length), with density proportional to `1 / r^2` from the point
/// light at `light_pos`'s foot on the ray, i.e. uniform in the angle subtended at the light:
/// it cancels the inverse-square falloff of single scattering from a point light.
///
/// Returns `(t, pdf)` with `pdf == equiangular_pdf(.., t)`. `tmax = inf` is supported; an
/// empty segment (`tmax <= 0`) returns `(0, 0)`. A light on the ray line is handled by a
/// floored line distance (see the module's constants), so the pdf stays finite.
pub fn equiangular_sample(
    origin: Vec3,
    dir: Vec3,
    light_pos: Vec3,
    tmax: f32,
    u: f32,
) -> (f32, f32) {
    let Some(seg) = EquiangularSegment::new(origin, dir, light_pos, tmax) else {
        return (0.0, 0.0);
    };
    let t64 = seg.sample(u.clamp(0.0, ONE_MINUS_EPSILON) as f64);
    // Round to f32 first and evaluate the pdf at the returned t, so that sample and
    // equiangular_pdf agree exactly; a huge t of an infinite segment saturates at f32::MAX.
    let t = (t64 as f32).clamp(0.0, tmax.min(f32::MAX));
    (t, seg.pdf(t as f64) as f32)
}

/// The density per unit length of [`equiangular_sample`] at `t` (0 outside `[0, tmax]` and
/// for an empty segment). Integrates to 1 over `[0, tmax]`.
pub fn equiangular_pdf(origin: Vec3, dir: Vec3, light_pos: Vec3, tmax: f32, t: f32) -> f32 {
    EquiangularSegment::new(origin, dir, light_pos, tmax)
        .map_or(0.0, |seg| seg.pdf(t as f64) as f32)
}

// ---------------------------------------------------------------------------------------
// Emission
// ---------------------------------------------------------------------------------------

/// Radiance a homogeneous emissive medium sends to the start of a segment of length
/// `distance` along it: the exact integral `int_0^d T(s) j ds = j (1 - exp(-sigma_t d)) /
/// sigma_t` per channel (`j d` where `sigma_t = 0`), with `j` the **emission coefficient**
/// (radiance per unit length, the source term of `dL/ds = -sigma_t L + j + ...`).
///
/// Computed as `j d * (-expm1(-x) / x)` with `x = sigma_t d`, which keeps full precision for
/// optically thin segments. A segment that is not finite (`+inf`: nothing ahead, the ray
/// has left the medium) or not positive emits nothing; no NaN for finite non-negative
/// inputs, and an infinite product only when `j d` itself overflows.
#[inline]
pub fn emitted_radiance(sigma_t: Rgb, emission: Rgb, distance: f32) -> Rgb {
    if !(distance.is_finite() && distance > 0.0) {
        return Rgb::BLACK;
    }
    let s = sigma_t.to_array();
    let j = emission.to_array();
    Rgb::from_array(std::array::from_fn(|c| {
        if j[c] == 0.0 {
            return 0.0;
        }
        let x = s[c] * distance;
        if x > 0.0 {
            // (1 - e^-x) / x, in (0, 1]; for x = inf it is 0 and j / sigma_t is the answer.
            if x.is_finite() {
                j[c] * distance * (-(-x).exp_m1() / x)
            } else {
                j[c] / s[c]
            }
        } else {
            j[c] * distance
        }
    }))
}

#[cfg(test)]
mod frozen_tests {
    use super::*;

    #[test]
    fn flights_freeze_only_where_no_coordinate_can_move() {
        let p = Vec3::new(0.5, -0.7, 0.3);
        // Mean free path 1e-7 at unit coordinates (tests/hard_media.rs): steps of about the
        // float spacing, the walk moves.
        assert!(!flights_frozen(Rgb::splat(1e7), p));
        assert!(!flights_frozen(Rgb::splat(2.0), p));
        // 1e-30: no coordinate can move; nor at 1e10 (steps a hundredth of the spacing).
        assert!(flights_frozen(Rgb::splat(1e30), p));
        assert!(flights_frozen(Rgb::splat(1e10), p));
        // A coordinate near 0 keeps a fine spacing: a thin dense slab along y still walks.
        assert!(!flights_frozen(Rgb::splat(1e10), Vec3::new(1.0, 1e-4, 1.0)));
        assert!(!flights_frozen(Rgb::splat(1e30), Vec3::new(0.5, 0.0, 0.5)));
        // Every channel must be frozen: an empty or thin one still moves the point.
        assert!(!flights_frozen(Rgb::new(1e30, 1e30, 0.0), p));
        assert!(!flights_frozen(Rgb::new(1e30, 2.0, 1e30), p));
        // The whole-volume test never says no where some point of the box is frozen.
        let (lo, hi) = (Vec3::splat(-1.0), Vec3::splat(1.0));
        for sigma in [2.0f32, 1e7, 1e9, 1e10, 1e30] {
            let frozen_somewhere = flights_frozen(Rgb::splat(sigma), hi);
            assert!(!frozen_somewhere || flights_may_freeze(Rgb::splat(sigma), lo, hi));
        }
        assert!(!flights_may_freeze(Rgb::splat(2.0), lo, hi));
        assert!(!flights_may_freeze(Rgb::splat(1e7), lo, hi));
        assert!(flights_may_freeze(Rgb::splat(1e10), lo, hi));
        assert!(flights_may_freeze(Rgb::splat(f32::NAN), lo, hi));
    }
}

#[cfg(test)]
mod emission_tests {
    use super::*;

    #[test]
    fn grey_transmittance_is_the_per_channel_one_bit_for_bit() {
        for s in [0.0f32, 1e-30, 0.5, 2.0, 1e30, f32::INFINITY] {
            for d in [0.0f32, 1e-8, 0.3, 7.0, f32::INFINITY] {
                let grey = transmittance(Rgb::splat(s), d);
                let each = Rgb::splat((-optical_depth(s, d)).exp());
                assert_eq!(
                    grey.to_array().map(f32::to_bits),
                    each.to_array().map(f32::to_bits)
                );
            }
        }
        // Channels that differ only in sign of zero are not grey: each keeps its own.
        let t = transmittance(Rgb::new(0.0, -0.0, 1.0), 2.0);
        assert_eq!((t.r, t.g), (1.0, 1.0));
        assert!((t.b - (-2.0f32).exp()).abs() < 1e-7);
    }

    #[test]
    fn emitted_radiance_is_the_segment_integral() {
        let (st, j) = (Rgb::new(0.0, 1e-7, 2.0), Rgb::new(3.0, 3.0, 3.0));
        let e = emitted_radiance(st, j, 1.5);
        assert!((e.r - 4.5).abs() < 1e-6);
        // Thin: j d (1 - x / 2 + ...).
        assert!((e.g - 4.5 * (1.0 - 0.75e-7)).abs() < 1e-6);
        assert!((e.b - 1.5 * (1.0 - (-3.0f32).exp())).abs() < 1e-6);
        assert_eq!(emitted_radiance(st, j, f32::INFINITY), Rgb::BLACK);
        assert_eq!(emitted_radiance(st, j, 0.0), Rgb::BLACK);
        // Extreme coefficients stay finite.
        let e = emitted_radiance(Rgb::new(1e-6, 1e6, f32::MAX), Rgb::splat(1e30), 1.0);
        assert!(e.is_finite(), "{e:?}");
        assert!((e.g - 1e24).abs() < 1e18);
    }
}
