//! Phase functions: the angular distribution of light scattered at a point inside a medium,
//! as plain functions over directions, one sample at a time.
//!
//! # Direction convention
//! The same as every Bxdf in [`crate::bxdf`], so the engine's volume closures and its surface
//! closures share one path-tracing loop:
//! - `wo` is the unit vector from the scattering point back towards where the *path* came
//!   from: `wo = -d` for the ray that arrived, the shading point's `vn`. Light leaves the point
//!   along `wo` (towards the viewer).
//! - `wi` is the unit vector from the point towards where light *arrives from*: the sampled
//!   direction the path continues along. Light travels along `-wi` into the point.
//! - The **scattering angle** `theta` is the angle between light's direction of travel before
//!   (`-wi`) and after (`wo`) the event: `cos theta = dot(-wi, wo) = dot(-wo, wi)`.
//!   Forward scattering (`theta = 0`) therefore means `wi = -wo`: the path continues straight
//!   on along its ray direction `-wo`, and light keeps travelling along `wo`.
//! - Henyey-Greenstein's `g` is the mean of `cos theta`; `g > 0` scatters forward. pbrt-v4's
//!   `HGPhaseFunction::p(wo, wi)` evaluates `HenyeyGreenstein(Dot(wo, wi), g)` with the
//!   denominator `1 + g^2 + 2 g Dot(wo, wi)`, i.e. it passes `-cos theta` and flips the sign
//!   inside: for the same `(wo, wi)` pair it gives the same value as [`hg_eval`].
//!
//! Phase functions integrate to 1 over the sphere, so a phase function's value *is* the
//! solid-angle pdf of sampling it exactly: every `*_eval` returns that one number, every
//! `*_sample` returns `(wi, pdf)` with `pdf == *_eval(wo, wi)` up to rounding, and the
//! sample's weight `p / pdf` is 1 (the single-scattering albedo is the medium's business, see
//! [`crate::medium`]). All functions are frame independent (pass world directions) and
//! never return NaN for unit `wo` and `u` in `[0, 1]`.

use crate::warp::{sample_uniform_sphere, Frame, INV_4PI};
use risotto_components::{Vec2, Vec3};
use std::f32::consts::PI;
use std::fmt;

/// Largest `|g|` the Henyey-Greenstein functions use. At `|g| = 1` the lobe is a Dirac delta
/// and the density formula is `0/0`; clamping keeps every result finite (the clamped lobe
/// has an angular width of about `1e-5` rad, far below anything a renderer resolves).
pub const HG_G_MAX: f32 = 0.99999;

// ---------------------------------------------------------------------------------------
// Isotropic
// ---------------------------------------------------------------------------------------

/// Isotropic phase function: `1 / (4 pi)` for every pair of directions.
#[inline]
pub fn isotropic_eval() -> f32 {
    INV_4PI
}

/// Samples [`isotropic_eval`]: a uniform direction on the sphere, `(wi, 1 / (4 pi))`.
#[inline]
pub fn isotropic_sample(u: Vec2) -> (Vec3, f32) {
    (sample_uniform_sphere(u), INV_4PI)
}

// ---------------------------------------------------------------------------------------
// Henyey-Greenstein
// ---------------------------------------------------------------------------------------

/// HG density from `1 - cos theta` and `1 + cos theta`, both passed separately because each
/// is computed without cancellation.
///
/// The denominator `1 + g^2 - 2 g cos theta` is rewritten as a sum of non-negative terms:
/// `(1 - g)^2 + 2 g (1 - cos)` for `g >= 0` and `(1 + g)^2 - 2 g (1 + cos)` for `g < 0`.
/// The naive form cancels catastrophically near the peak when `|g| -> 1` (it can even go
/// negative in f32); this one is bounded below by `(1 - |g|)^2 > 0`.
#[inline]
fn hg_density(g: f32, one_minus_cos: f32, one_plus_cos: f32) -> f32 {
    let g = g.clamp(-HG_G_MAX, HG_G_MAX);
    let denom = if g >= 0.0 {
        (1.0 - g) * (1.0 - g) + 2.0 * g * one_minus_cos
    } else {
        (1.0 + g) * (1.0 + g) - 2.0 * g * one_plus_cos
    };
    (1.0 - g) * (1.0 + g) * INV_4PI / (denom * denom.sqrt())
}

/// Henyey-Greenstein phase function (1941),
/// `p = (1 - g^2) / (4 pi (1 + g^2 - 2 g cos theta)^1.5)`, in 1/sr, integrating to 1.
///
/// Directions as in the [module convention](self): `wo` points back along the arriving path
/// (`wo = -ray direction`), so `cos theta = dot(-wo, wi)` and `g > 0` scatters forward (`wi`
/// close to `-wo`). Frame independent: pass world or local directions. `g` is clamped to
/// `[-HG_G_MAX, HG_G_MAX]`.
pub fn hg_eval(g: f32, wo: Vec3, wi: Vec3) -> f32 {
    // For unit vectors a, b: 1 - a.b = |a - b|^2 / 2 and 1 + a.b = |a + b|^2 / 2. Unlike
    // 1 - dot(a, b) these keep full relative precision for nearly (anti)parallel vectors,
    // which is exactly where a strongly peaked lobe lives.
    let d = -wo;
    let one_minus_cos = (0.5 * (d - wi).length_squared()).min(2.0);
    let one_plus_cos = (0.5 * (d + wi).length_squared()).min(2.0);
    hg_density(g, one_minus_cos, one_plus_cos)
}

/// Samples [`hg_eval`] exactly by inverting its CDF; returns `(wi, pdf)` with
/// `pdf == hg_eval(g, wo, wi)` (up to rounding). Same convention as [`hg_eval`]; `wo` must be
/// a unit vector. `u.x` picks the polar angle, `u.y` the azimuth.
///
/// Derivation: with `mu = cos theta` the marginal is `(1 - g^2) / (2 (1 + g^2 - 2 g mu)^1.5)`
/// and its CDF from `mu = -1` is
/// `F(mu) = (1 - g^2) / (2g) * ((1 + g^2 - 2 g mu)^-1/2 - 1 / (1 + g))`.
/// Solving `F(mu) = xi` gives `1 + g^2 - 2 g mu = ((1 - g^2) / D)^2` with
/// `D = 1 - g + 2 g xi`, and after factoring differences of squares
/// - `1 - mu = 2 (1 - g)^2 (1 - xi) (1 + g xi) / D^2`,
/// - `1 + mu = 2 (1 + g)^2 xi (1 - g + g xi) / D^2`,
/// - `p = D^3 / (4 pi (1 - g^2)^2)`.
///
/// No `1/g` survives (so `g = 0` is exactly uniform, with no special case) and no
/// difference of nearly equal numbers remains (so `|g| -> 1` is accurate). `D` lies between
/// `1 - |g|` and `1 + |g|`, hence is positive: the result is never NaN.
pub fn hg_sample(g: f32, wo: Vec3, u: Vec2) -> (Vec3, f32) {
    let g = g.clamp(-HG_G_MAX, HG_G_MAX);
    let xi = u.x.clamp(0.0, 1.0);
    let d = 1.0 - g + 2.0 * g * xi;
    let inv_d2 = 1.0 / (d * d);
    let one_minus_mu =
        (2.0 * (1.0 - g) * (1.0 - g) * (1.0 - xi) * (1.0 + g * xi) * inv_d2).clamp(0.0, 2.0);
    let one_plus_mu =
        (2.0 * (1.0 + g) * (1.0 + g) * xi * (1.0 - g + g * xi) * inv_d2).clamp(0.0, 2.0);
    // Take mu from whichever side is closer to its pole, where that side is the accurate one.
    let mu = if one_minus_mu < one_plus_mu {
        1.0 - one_minus_mu
    } else {
        one_plus_mu - 1.0
    };
    let sin_theta = (one_minus_mu * one_plus_mu).max(0.0).sqrt();
    let (sin_phi, cos_phi) = (2.0 * PI * u.y).sin_cos();
    let local = Vec3::new(sin_theta * cos_phi, sin_theta * sin_phi, mu);
    let wi = Frame::from_normal(-wo).to_world(local);
    let one_minus_g2 = (1.0 - g) * (1.0 + g);
    let pdf = d * d * d * INV_4PI / (one_minus_g2 * one_minus_g2);
    (wi, pdf)
}

// ---------------------------------------------------------------------------------------
// Double Henyey-Greenstein
// ---------------------------------------------------------------------------------------

/// Double Henyey-Greenstein (RenderMan's `PxrDoubleHenyeyGreenstein`): the mixture
/// `blend * HG(g1) + (1 - blend) * HG(g2)`, so `blend` is the weight of the `g1` lobe. A forward
/// lobe plus a weaker backward one fits measured phase functions (clouds, skin, jade) far
/// better than one HG lobe (Kattawar 1975, "A three-parameter analytic phase function for
/// multiple scattering calculations"). `blend` is clamped to `[0, 1]`, `g` as in [`hg_eval`].
pub fn double_hg_eval(g1: f32, g2: f32, blend: f32, wo: Vec3, wi: Vec3) -> f32 {
    let blend = blend.clamp(0.0, 1.0);
    blend * hg_eval(g1, wo, wi) + (1.0 - blend) * hg_eval(g2, wo, wi)
}

/// Samples [`double_hg_eval`]: `u_lobe < blend` picks the `g1` lobe, otherwise the `g2` lobe,
/// which is then sampled exactly with `u`. The returned pdf is the **mixture** density at
/// `wi` (the picked lobe's closed-form pdf plus the other lobe evaluated at `wi`), i.e. the
/// one-sample MIS balance heuristic over the two lobes, which for a mixture equals the
/// mixture itself (Veach 1997, sec. 9.2.4): `p / pdf = 1` exactly in exact arithmetic, with
/// no variance from the lobe choice.
pub fn double_hg_sample(
    g1: f32,
    g2: f32,
    blend: f32,
    wo: Vec3,
    u: Vec2,
    u_lobe: f32,
) -> (Vec3, f32) {
    let blend = blend.clamp(0.0, 1.0);
    // `<` so that blend = 0 never picks g1 and blend = 1 always does (u_lobe < 1).
    let (g_picked, g_other, w_picked) = if u_lobe < blend {
        (g1, g2, blend)
    } else {
        (g2, g1, 1.0 - blend)
    };
    let (wi, pdf_picked) = hg_sample(g_picked, wo, u);
    let pdf = w_picked * pdf_picked + (1.0 - w_picked) * hg_eval(g_other, wo, wi);
    (wi, pdf)
}

// ---------------------------------------------------------------------------------------
// The phase function of a medium
// ---------------------------------------------------------------------------------------

/// A medium's phase function, as a scene file names it (`phase = { type = "isotropic" }`,
/// `{ type = "hg", g }`, `{ type = "double_hg", g1, g2, blend }`).
///
/// Build it with [`PhaseFunction::henyey_greenstein`] / [`PhaseFunction::double_henyey_greenstein`]
/// (or [`PhaseFunction::validate`] a literal) so that bad parameters become an error instead of
/// a silently clamped lobe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PhaseFunction {
    /// Uniform over the sphere.
    Isotropic,
    /// One Henyey-Greenstein lobe.
    HenyeyGreenstein {
        /// Mean cosine of the scattering angle, in `(-1, 1)`; `> 0` forward.
        g: f32,
    },
    /// `blend * HG(g1) + (1 - blend) * HG(g2)` (RenderMan's `PxrDoubleHenyeyGreenstein`).
    DoubleHenyeyGreenstein {
        /// Mean cosine of the first lobe, in `(-1, 1)`.
        g1: f32,
        /// Mean cosine of the second lobe, in `(-1, 1)`.
        g2: f32,
        /// Weight of the `g1` lobe, in `[0, 1]`.
        blend: f32,
    },
}

/// Why a [`PhaseFunction`]'s parameters were rejected: which parameter, its value and the
/// range it must lie in.
#[derive(Clone, Debug, PartialEq)]
pub struct PhaseFunctionError {
    /// The parameter's name as the scene file spells it (`g`, `g1`, `g2`, `blend`).
    pub parameter: &'static str,
    /// The rejected value (may be NaN).
    pub value: f32,
    /// The accepted range, in words.
    pub expected: &'static str,
}

impl fmt::Display for PhaseFunctionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "phase function parameter {} = {} is out of range: expected {}",
            self.parameter, self.value, self.expected
        )
    }
}

impl std::error::Error for PhaseFunctionError {}

/// `|g| < 1` (false for NaN): at `|g| = 1` HG is a Dirac delta, not a density.
fn check_g(parameter: &'static str, g: f32) -> Result<(), PhaseFunctionError> {
    if g.abs() < 1.0 {
        Ok(())
    } else {
        Err(PhaseFunctionError {
            parameter,
            value: g,
            expected: "-1 < g < 1 (|g| = 1 is a Dirac delta, not a Henyey-Greenstein lobe)",
        })
    }
}

impl PhaseFunction {
    /// A Henyey-Greenstein phase function; errors unless `|g| < 1`.
    pub fn henyey_greenstein(g: f32) -> Result<Self, PhaseFunctionError> {
        PhaseFunction::HenyeyGreenstein { g }.validate()
    }

    /// A double Henyey-Greenstein phase function; errors unless `|g1| < 1`, `|g2| < 1` and
    /// `0 <= blend <= 1`.
    pub fn double_henyey_greenstein(
        g1: f32,
        g2: f32,
        blend: f32,
    ) -> Result<Self, PhaseFunctionError> {
        PhaseFunction::DoubleHenyeyGreenstein { g1, g2, blend }.validate()
    }

    /// Returns `self` if its parameters are in range (NaN never is), else the first offending
    /// parameter.
    pub fn validate(self) -> Result<Self, PhaseFunctionError> {
        match self {
            PhaseFunction::Isotropic => {}
            PhaseFunction::HenyeyGreenstein { g } => check_g("g", g)?,
            PhaseFunction::DoubleHenyeyGreenstein { g1, g2, blend } => {
                check_g("g1", g1)?;
                check_g("g2", g2)?;
                if !(0.0..=1.0).contains(&blend) {
                    return Err(PhaseFunctionError {
                        parameter: "blend",
                        value: blend,
                        expected: "0 <= blend <= 1 (the weight of the g1 lobe)",
                    });
                }
            }
        }
        Ok(self)
    }

    /// Value (= solid-angle pdf) for the pair `(wo, wi)`, in 1/sr.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> f32 {
        match *self {
            PhaseFunction::Isotropic => isotropic_eval(),
            PhaseFunction::HenyeyGreenstein { g } => hg_eval(g, wo, wi),
            PhaseFunction::DoubleHenyeyGreenstein { g1, g2, blend } => {
                double_hg_eval(g1, g2, blend, wo, wi)
            }
        }
    }

    /// Samples `wi` given `wo`; returns `(wi, pdf)`. `u` drives the direction, `u_lobe` the
    /// lobe choice of the double-HG mixture (ignored otherwise, so callers always draw it and
    /// sample dimensions do not depend on the phase function).
    #[inline]
    pub fn sample(&self, wo: Vec3, u: Vec2, u_lobe: f32) -> (Vec3, f32) {
        match *self {
            PhaseFunction::Isotropic => isotropic_sample(u),
            PhaseFunction::HenyeyGreenstein { g } => hg_sample(g, wo, u),
            PhaseFunction::DoubleHenyeyGreenstein { g1, g2, blend } => {
                double_hg_sample(g1, g2, blend, wo, u, u_lobe)
            }
        }
    }

    /// Mean cosine of the scattering angle, `E[dot(-wo, wi)]`: 0, `g`, or
    /// `blend g1 + (1 - blend) g2` (the mean of a mixture is the mixture of the means). Used
    /// e.g. by similarity theory (`sigma_s' = sigma_s (1 - g)`).
    pub fn mean_cosine(&self) -> f32 {
        match *self {
            PhaseFunction::Isotropic => 0.0,
            PhaseFunction::HenyeyGreenstein { g } => g,
            PhaseFunction::DoubleHenyeyGreenstein { g1, g2, blend } => {
                blend * g1 + (1.0 - blend) * g2
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::SplitMix64 as Rng;

    #[test]
    fn hg_sample_pdf_matches_eval_and_isotropic_at_zero() {
        let mut rng = Rng(8);
        for g in [-0.99f32, -0.5, 0.0, 0.3, 0.9, 0.99] {
            for _ in 0..2000 {
                let wo = sample_uniform_sphere(rng.vec2());
                let (wi, pdf) = hg_sample(g, wo, rng.vec2());
                assert!((wi.length() - 1.0).abs() < 1e-5);
                let e = hg_eval(g, wo, wi);
                assert!(
                    (e - pdf).abs() <= 2e-3 * pdf,
                    "g {g}: eval {e} vs sample {pdf}"
                );
            }
        }
        for _ in 0..100 {
            let wo = sample_uniform_sphere(rng.vec2());
            let (_, pdf) = hg_sample(0.0, wo, rng.vec2());
            assert_eq!(pdf, INV_4PI);
            assert_eq!(hg_eval(0.0, wo, sample_uniform_sphere(rng.vec2())), INV_4PI);
        }
        // Convention: g > 0 favours continuing along the propagation direction -wo.
        let wo = Vec3::Z;
        assert!(hg_eval(0.7, wo, -Vec3::Z) > hg_eval(0.7, wo, Vec3::Z));
        assert!(hg_eval(-0.7, wo, -Vec3::Z) < hg_eval(-0.7, wo, Vec3::Z));
        // Closed forms at the poles: (1 + g) / (4 pi (1 - g)^2) forward.
        let g = 0.5f32;
        let forward = (1.0 + g) / (1.0 - g).powi(2) * INV_4PI;
        assert!((hg_eval(g, wo, -wo) - forward).abs() < 1e-6 * forward);
        let backward = (1.0 - g) / (1.0 + g).powi(2) * INV_4PI;
        assert!((hg_eval(g, wo, wo) - backward).abs() < 1e-6 * backward);
    }

    #[test]
    fn hg_mean_cosine_is_g() {
        // The defining property of HG: E[cos theta] = g.
        for g in [-0.9f32, -0.3, 0.0, 0.5, 0.95] {
            let mut rng = Rng(9);
            let wo = Vec3::new(0.36, -0.48, 0.8);
            let n = 200_000;
            let mut sum = 0.0f64;
            let mut sum2 = 0.0f64;
            for _ in 0..n {
                let (wi, _) = hg_sample(g, wo, rng.vec2());
                let c = (-wo).dot(wi) as f64;
                sum += c;
                sum2 += c * c;
            }
            let mean = sum / n as f64;
            let var = sum2 / n as f64 - mean * mean;
            assert!(
                (mean - g as f64).abs() < 5.0 * (var / n as f64).sqrt() + 1e-5,
                "g {g}"
            );
        }
    }

    #[test]
    fn hg_peaked_lobe_keeps_angular_resolution() {
        // For g = 0.9999 the lobe's angular scale is ~ (1 - g) = 1e-4 rad, below what a
        // naive f32 cos theta can represent (its spacing near 1 is ~6e-8, i.e. ~3e-4 rad).
        // Compare the sampled polar angle with the exact inverse CDF in f64.
        let (g32, wo) = (0.9999f32, Vec3::Z);
        let g = g32 as f64;
        for xi32 in [0.1f32, 0.5, 0.9, 0.999] {
            let xi = xi32 as f64;
            let (wi, _) = hg_sample(g32, wo, Vec2::new(xi32, 0.25));
            let theta = ((-wo).cross(wi).length() as f64).atan2((-wo).dot(wi) as f64);
            // Exact: 1 - mu = 2 (1-g)^2 (1-xi)(1+g xi) / (1 - g + 2 g xi)^2 in f64.
            let d = 1.0 - g + 2.0 * g * xi;
            let omm = 2.0 * (1.0 - g).powi(2) * (1.0 - xi) * (1.0 + g * xi) / (d * d);
            let exact = (1.0 - omm).acos();
            assert!(
                (theta - exact).abs() < 1e-2 * exact + 1e-7,
                "xi {xi}: theta {theta} vs {exact}"
            );
        }
    }
    #[test]
    fn validating_constructors_reject_out_of_range_parameters() {
        assert!(PhaseFunction::henyey_greenstein(0.999).is_ok());
        assert!(PhaseFunction::henyey_greenstein(-0.999).is_ok());
        for g in [1.0f32, -1.0, 1.5, f32::NAN, f32::INFINITY] {
            let e = PhaseFunction::henyey_greenstein(g).unwrap_err();
            assert_eq!(e.parameter, "g");
            assert!(e.to_string().contains("-1 < g < 1"), "{e}");
        }
        assert!(PhaseFunction::double_henyey_greenstein(0.8, -0.3, 0.7).is_ok());
        assert!(PhaseFunction::double_henyey_greenstein(0.8, -0.3, 0.0).is_ok());
        assert!(PhaseFunction::double_henyey_greenstein(0.8, -0.3, 1.0).is_ok());
        let cases = [
            ((1.0f32, 0.0f32, 0.5f32), "g1"),
            ((0.0, -1.0, 0.5), "g2"),
            ((0.0, 0.0, 1.1), "blend"),
            ((0.0, 0.0, -0.1), "blend"),
            ((0.0, 0.0, f32::NAN), "blend"),
        ];
        for ((g1, g2, blend), which) in cases {
            let e = PhaseFunction::double_henyey_greenstein(g1, g2, blend).unwrap_err();
            assert_eq!(e.parameter, which, "{e}");
        }
        assert_eq!(
            PhaseFunction::Isotropic.validate(),
            Ok(PhaseFunction::Isotropic)
        );
    }

    #[test]
    fn mean_cosine_matches_sampled_mean() {
        // E[dot(-wo, wi)] estimated from the samplers (which the chi-square tests tie to the
        // densities), against mean_cosine's closed forms.
        let wo = Vec3::new(0.36, -0.48, 0.8);
        for phase in [
            PhaseFunction::Isotropic,
            PhaseFunction::HenyeyGreenstein { g: -0.6 },
            PhaseFunction::DoubleHenyeyGreenstein {
                g1: 0.8,
                g2: -0.3,
                blend: 0.7,
            },
        ] {
            let mut rng = Rng(12);
            let n = 200_000;
            let (mut sum, mut sum2) = (0.0f64, 0.0f64);
            for _ in 0..n {
                let (wi, _) = phase.sample(wo, rng.vec2(), rng.f32());
                let c = (-wo).dot(wi) as f64;
                sum += c;
                sum2 += c * c;
            }
            let mean = sum / n as f64;
            let sigma = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
            let want = phase.mean_cosine() as f64;
            assert!(
                (mean - want).abs() < 4.0 * sigma,
                "{phase:?}: {mean} vs {want}"
            );
        }
    }
}
