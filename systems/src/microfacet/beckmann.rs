//! The Beckmann distribution of microfacet normals (the slopes of a Gaussian random
//! surface), isotropic and anisotropic, with its Smith `Lambda` and the sampling of its
//! visible normals. Mitsuba 3's default distribution for `roughconductor`,
//! `roughdielectric` and `roughplastic`.
//!
//! Same frame as [`super::Ggx`] (normal `+z`, `alpha_u` along `+x`, `alpha_v` along `+y`).
//! References:
//! - E. Heitz 2014, "Understanding the Masking-Shadowing Function in Microfacet-Based
//!   BRDFs", JCGT 3(2): the anisotropic Beckmann `D` (eq. 83) and its Smith `Lambda`
//!   (eq. 84, exact in terms of `erf`; Mitsuba uses a rational fit of `G1` within 0.35%).
//! - E. Heitz and E. d'Eon 2014, "Importance Sampling Microfacet-Based BSDFs using the
//!   Distribution of Visible Normals", EGSR: the sampler works on slopes, in the stretched
//!   configuration of unit roughness, where the visible slopes seen at `theta_o` have the
//!   marginal CDF (in `x_m`, the slope along the view's azimuth)
//!   `C(x_m) ~ 1 + erf(x_m) + tan(theta_o) exp(-x_m^2) / sqrt(pi)`, normalised at
//!   `x_m = cot(theta_o)`, and a Gaussian conditional in `y_m`.
//! - W. Jakob 2014, "An Improved Visible Normal Sampling Routine for the Beckmann
//!   Distribution" (the routine in Mitsuba): the CDF is inverted by Newton's method in the
//!   variable `x = erf(x_m)`, which is continuous in the sample (unlike the paper's
//!   original fitted inversion), from an initial guess exact at grazing incidence.

use super::erf::{erf, erfinv, FRAC_1_SQRT_PI};
use super::{Smith, ALPHA_MIN};
use risotto_components::{Vec2, Vec3};
use std::f32::consts::PI;

/// The anisotropic Beckmann distribution, `alpha_u` along `+x` and `alpha_v` along `+y`
/// (both in `[ALPHA_MIN, 1]` after [`Beckmann::new`]). `alpha` is `sqrt(2)` times the RMS
/// slope of the surface along its axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beckmann {
    /// Roughness along the tangent (`+x`).
    pub alpha_u: f32,
    /// Roughness along the bitangent (`+y`).
    pub alpha_v: f32,
    /// The masking-shadowing function `Microfacet::g2` uses (height-correlated from
    /// [`Beckmann::new`]).
    pub masking: super::Masking,
}

impl Beckmann {
    /// The distribution with roughnesses clamped to `[ALPHA_MIN, 1]` (NaN becomes
    /// `ALPHA_MIN`), as [`super::Ggx::new`].
    pub fn new(alpha_u: f32, alpha_v: f32) -> Self {
        let clamp = |a: f32| a.clamp(ALPHA_MIN, 1.0).max(ALPHA_MIN);
        Beckmann {
            alpha_u: clamp(alpha_u),
            alpha_v: clamp(alpha_v),
            masking: super::Masking::HeightCorrelated,
        }
    }

    /// The isotropic distribution.
    pub fn isotropic(alpha: f32) -> Self {
        Beckmann::new(alpha, alpha)
    }

    /// Samples a microfacet normal from the visible normals seen from `wo` (`wo.z > 0`),
    /// density [`Smith::pdf_visible`] (Heitz and d'Eon 2014 sec. 4 with Jakob 2014's
    /// inversion): stretch `wo` to unit roughness, draw the visible slopes there for its
    /// elevation, rotate them to its azimuth, unstretch, and turn the slope into a normal.
    pub fn sample_visible(&self, wo: Vec3, u: Vec2) -> Vec3 {
        // Stretch (Heitz and d'Eon 2014 sec. 4.2, step 1).
        let v = Vec3::new(self.alpha_u * wo.x, self.alpha_v * wo.y, wo.z).normalize();
        let sin_theta = (v.x * v.x + v.y * v.y).sqrt();
        let (cos_phi, sin_phi) = if sin_theta > 0.0 {
            (v.x / sin_theta, v.y / sin_theta)
        } else {
            (1.0, 0.0)
        };
        let (sx, sy) = visible_slopes_unit(v.z, sin_theta, u);
        // Rotate to the view's azimuth and unstretch (steps 3 and 4).
        let mx = (cos_phi * sx - sin_phi * sy) * self.alpha_u;
        let my = (sin_phi * sx + cos_phi * sy) * self.alpha_v;
        // A normal with slopes (mx, my) is (-mx, -my, 1) normalised; a huge slope still
        // gives a normal above the plane (z kept positive as the GGX sampler does).
        let m = Vec3::new(-mx, -my, 1.0);
        if !m.is_finite() {
            let flat = Vec3::new(-mx, -my, 0.0).normalize_or_zero();
            return Vec3::new(flat.x, flat.y, 1e-6).normalize();
        }
        m.normalize()
    }
}

impl Smith for Beckmann {
    /// Microfacet normal density `D(m)` per unit projected area (Heitz 2014 eq. 83):
    /// `exp(-(x^2/au^2 + y^2/av^2) / z^2) / (pi au av z^4)`; 0 for `m.z <= 0`.
    #[inline]
    fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let (x, y) = (m.x / self.alpha_u, m.y / self.alpha_v);
        let z2 = m.z * m.z;
        let e = (-(x * x + y * y) / z2).exp();
        e / (PI * self.alpha_u * self.alpha_v * z2 * z2)
    }

    /// Smith's `Lambda(w)` for Beckmann (Heitz 2014 eq. 84): with
    /// `a = 1 / (alpha_w tan theta)` (`alpha_w` the roughness projected on `w`'s azimuth),
    /// `Lambda = (erf(a) - 1) / 2 + exp(-a^2) / (2 a sqrt(pi))`; 0 at the normal, infinite in
    /// the plane.
    #[inline]
    fn lambda(&self, w: Vec3) -> f32 {
        let (x, y) = (self.alpha_u * w.x, self.alpha_v * w.y);
        let xy = (x * x + y * y).sqrt();
        if xy == 0.0 {
            return 0.0;
        }
        let a = w.z.abs() / xy;
        if a == 0.0 {
            return f32::INFINITY;
        }
        // Both terms fall as exp(-a^2); beyond a = 5 the sum is below 1e-13.
        if a > 5.0 {
            return 0.0;
        }
        (0.5 * (erf(a) - 1.0) + (-a * a).exp() * FRAC_1_SQRT_PI / (2.0 * a)).max(0.0)
    }
}

/// The slopes `(x_m, y_m)` of a visible normal of the unit-roughness Beckmann distribution
/// seen from elevation `theta` (`cos_theta`, `sin_theta`) along `+x`: Jakob 2014's Newton
/// inversion of the marginal CDF of `x_m` (module docs), then `y_m` from its Gaussian
/// conditional (`erf^-1` of a uniform number: the conditional of a unit-roughness Beckmann
/// slope is a normal law of variance `1/2`).
fn visible_slopes_unit(cos_theta: f32, sin_theta: f32, u: Vec2) -> (f32, f32) {
    let u = Vec2::new(u.x.clamp(1e-6, 1.0 - 1e-6), u.y.clamp(1e-6, 1.0 - 1e-6));
    let cos_theta = cos_theta.max(1e-7);
    let tan_theta = sin_theta / cos_theta;
    let cot_theta = cos_theta / sin_theta.max(1e-30);
    // The CDF in x = erf(x_m): C(x) = 1 + x + tan exp(-erfinv(x)^2) / sqrt(pi), from
    // C(-1) = 0 to C(x_max) = norm, x_max = erf(cot theta) (where the slope's facet turns
    // away from the viewer).
    let x_max = erf(cot_theta);
    let tail = if tan_theta > 0.0 {
        tan_theta * (-cot_theta * cot_theta).exp() * FRAC_1_SQRT_PI
    } else {
        0.0
    };
    let target = u.x * (1.0 + x_max + tail);
    // Initial guess: the exact inverse at grazing incidence (Jakob 2014).
    let mut x = x_max - (x_max + 1.0) * erf((-u.x.ln()).sqrt());
    for _ in 0..4 {
        let slope = erfinv(x);
        let value = 1.0 + x + tan_theta * FRAC_1_SQRT_PI * (-slope * slope).exp() - target;
        let derivative = 1.0 - slope * tan_theta;
        if derivative.is_nan() || derivative <= 0.0 {
            break;
        }
        // Stay inside the CDF's domain: Newton may overshoot near x_max, where C' -> 0.
        x = (x - value / derivative).clamp(-1.0 + 1e-7, x_max);
    }
    (erfinv(x), erfinv(2.0 * u.y - 1.0))
}

#[cfg(test)]
mod tests;
