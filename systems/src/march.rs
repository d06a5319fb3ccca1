//! The jittered march of the optical depth along one ray, shared by the ray-marching
//! estimators apart from either: the grey ones of [`crate::ray_marching`] (whose module docs
//! describe the march and the unbiased series) and the chromatic ones of
//! [`crate::spectral_tracking`]. `ray_marching` re-exports the public limits at their old
//! paths.

use crate::grid::MajorantSegment;
use risotto_components::Rgb;

/// The most steps one majorant segment is cut into (a tiny `step` on a long segment marches
/// this many steps of `len / MAX_STEPS_PER_SEGMENT`): bounds the work of one march.
pub const MAX_STEPS_PER_SEGMENT: u32 = 1 << 16;

/// The smallest roulette rate `rho` of [`unbiased_ray_marching`]: even where the pivot saw
/// no variation (a feature between its samples), the series goes on with probability about
/// `RHO_MIN`, and its factors `(c - X_j) / rho` stay bounded by `tau_max / RHO_MIN`.
///
/// [`unbiased_ray_marching`]: crate::ray_marching::unbiased_ray_marching
pub const RHO_MIN: f32 = 0.1;

/// The largest roulette rate: `rho` terms of the series are always evaluated.
pub const RHO_MAX: f32 = 8.0;

/// The highest series order evaluated: the probability of reaching it is at most
/// `RHO_MAX^64 / 64!` (below 1e-31), the truncation bias below that times the term.
pub const MAX_ORDER: u32 = 64;

/// `x > 0` (false for NaN).
#[inline]
pub(crate) fn positive(x: f32) -> bool {
    x > 0.0
}

/// One march along a ray.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct March {
    /// The optical-depth estimate `X`.
    pub(crate) depth: f32,
    /// `sum h |Delta sigma_t|` between neighbouring steps of a segment.
    pub(crate) variation: f32,
    /// `sigma_t` lookups.
    pub(crate) lookups: u32,
    /// Lookups above their segment's majorant.
    pub(crate) violations: u32,
}

/// The step count and length of a segment of length `len > 0`.
#[inline]
pub(crate) fn steps(len: f32, step: f32) -> (u32, f32) {
    let n = (len / step).ceil();
    let n = if n >= 1.0 {
        n.min(MAX_STEPS_PER_SEGMENT as f32) as u32
    } else {
        1
    };
    (n, len / n as f32)
}

/// Whether a segment has no extinction (skipped) or a constant one (integrated exactly).
#[inline]
pub(crate) fn constant(seg: &MajorantSegment) -> Option<f32> {
    if !positive(seg.majorant) {
        Some(0.0)
    } else if seg.minorant >= seg.majorant {
        Some(seg.majorant)
    } else {
        None
    }
}

/// Marches the segments with jitter `u`.
pub(crate) fn march<I: IntoIterator<Item = MajorantSegment>>(
    segments: I,
    sigma_t: &mut impl FnMut(f32) -> f32,
    step: f32,
    u: f32,
) -> March {
    let mut m = March::default();
    for seg in segments {
        let len = seg.t1 - seg.t0;
        if !positive(len) {
            continue;
        }
        if let Some(s) = constant(&seg) {
            m.depth += s * len;
            continue;
        }
        let (n, h) = steps(len, step);
        let mut previous: Option<f32> = None;
        for k in 0..n {
            let s = sigma_t(seg.t0 + (k as f32 + u) * h);
            m.lookups += 1;
            m.violations += (s > seg.majorant) as u32;
            m.depth += s * h;
            if let Some(p) = previous {
                m.variation += h * (s - p).abs();
            }
            previous = Some(s);
        }
    }
    m
}

/// The unbiased ray-marching estimate ([`crate::ray_marching::unbiased_ray_marching`]) of
/// every channel `k_c sigma` from the same marches, as `(value, lookups, violations)`: the
/// body of [`crate::spectral_tracking::unbiased_ray_marching_rgb`], whose docs describe
/// it, and with `k = (1, 1, 1)` of the grey estimator.
pub(crate) fn unbiased_march_rgb<I: IntoIterator<Item = MajorantSegment>>(
    segments: impl Fn() -> I,
    mut sigma: impl FnMut(f32) -> f32,
    k: Rgb,
    mut rand: impl FnMut() -> f32,
    step: f32,
) -> (Rgb, u32, u32) {
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
    (
        k.map(|kc| (-(kc * pivot.depth)).exp()) * sum,
        lookups,
        violations,
    )
}
