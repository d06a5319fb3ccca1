//! Microfacet distributions: GGX (Trowbridge-Reitz, here) and Beckmann ([`Beckmann`]),
//! isotropic and anisotropic, each with its height-correlated Smith masking-shadowing
//! function and sampling of the visible normals; [`Microfacet`] is the choice of one, as a
//! material holds it (`distribution = "ggx" | "beckmann"`).
//!
//! Everything works in the local shading frame of [`crate::bxdf`] (macro normal `+z`, the
//! tangent `+x` carries `alpha_u`, the bitangent `+y` carries `alpha_v`). References:
//! - E. Heitz 2014, "Understanding the Masking-Shadowing Function in Microfacet-Based
//!   BRDFs", JCGT 3(2): the anisotropic GGX `D` (eq. 85), its Smith `Lambda` (eq. 86) and
//!   the height-correlated masking-shadowing `G2 = 1 / (1 + Lambda(wo) + Lambda(wi))`
//!   (eq. 99), which is what risotto uses (more accurate than the separable product
//!   `G1 G1`, and what pbrt-v4 uses). Mitsuba 3 uses the separable form, which is lower at
//!   grazing angles (about 20 % at the silhouette of a sphere at alpha 0.4 to 1); a
//!   distribution can be told to use it ([`Masking::Separable`], what the Mitsuba importer
//!   writes) so that an imported scene renders as there.
//! - E. Heitz 2018, "Sampling the GGX Distribution of Visible Normals", JCGT 7(4): the
//!   sampler ([`Ggx::sample_visible`], listing 1) and the visible-normal density
//!   `D_wo(m) = G1(wo) max(0, wo . m) D(m) / cos theta_o` (eq. 1 there, eq. 38 in 2014).

use risotto_components::{Vec2, Vec3};
use std::f32::consts::PI;

mod beckmann;
pub mod erf;
pub use beckmann::Beckmann;

/// Smallest roughness the distribution takes (Mitsuba 3 clamps at the same value): below
/// it `D` peaks above `1e7` and the lobe is a mirror for all practical purposes, while
/// `alpha^-4` terms would still fit an `f32`.
pub const ALPHA_MIN: f32 = 1e-4;

/// Strictly positive (false for NaN): the guard of the rough lobes against degenerate
/// directions and densities.
#[inline]
pub(crate) fn positive(x: f32) -> bool {
    x > 0.0
}

/// Which Smith masking-shadowing function a distribution's [`Microfacet::g2`] is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Masking {
    /// `G2 = 1 / (1 + Lambda(wo) + Lambda(wi))` (Heitz 2014 eq. 99): risotto's default.
    #[default]
    HeightCorrelated,
    /// `G2 = G1(wo) G1(wi)` (Heitz 2014 eq. 98): Mitsuba 3's.
    Separable,
}

/// The anisotropic GGX distribution of microfacet normals, `alpha_u` along the local `+x`
/// and `alpha_v` along `+y` (both in `[ALPHA_MIN, 1]` after [`Ggx::new`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    /// Roughness along the tangent (`+x`).
    pub alpha_u: f32,
    /// Roughness along the bitangent (`+y`).
    pub alpha_v: f32,
    /// The masking-shadowing function [`Microfacet::g2`] uses (height-correlated from
    /// [`Ggx::new`]).
    pub masking: Masking,
}

impl Ggx {
    /// The distribution with roughnesses clamped to `[ALPHA_MIN, 1]` (NaN becomes
    /// `ALPHA_MIN`; the scene loader rejects values outside `(0, 1]` before this).
    pub fn new(alpha_u: f32, alpha_v: f32) -> Self {
        let clamp = |a: f32| a.clamp(ALPHA_MIN, 1.0).max(ALPHA_MIN);
        Ggx {
            alpha_u: clamp(alpha_u),
            alpha_v: clamp(alpha_v),
            masking: Masking::HeightCorrelated,
        }
    }

    /// The isotropic distribution.
    pub fn isotropic(alpha: f32) -> Self {
        Ggx::new(alpha, alpha)
    }

    /// Samples a microfacet normal from the visible normals seen from `wo` (`wo.z > 0`),
    /// density [`Smith::pdf_visible`]: Heitz 2018, listing 1. The view direction is stretched
    /// to the configuration where the distribution is a hemisphere of unit roughness; the
    /// visible part of that hemisphere's projected disk is sampled (a uniform disk whose
    /// lower half is squeezed by `(1 + cos theta_v) / 2`); the point is lifted onto the
    /// hemisphere and unstretched.
    pub fn sample_visible(&self, wo: Vec3, u: Vec2) -> Vec3 {
        // Section 3.2: stretch.
        let vh = Vec3::new(self.alpha_u * wo.x, self.alpha_v * wo.y, wo.z).normalize();
        // Section 4.1: an orthonormal basis around vh (any tangent when vh is the pole).
        let len2 = vh.x * vh.x + vh.y * vh.y;
        let t1 = if len2 > 0.0 {
            Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt()
        } else {
            Vec3::X
        };
        let t2 = vh.cross(t1);
        // Section 4.2: a point of the projected area.
        let r = u.x.sqrt();
        let phi = 2.0 * PI * u.y;
        let (sin_phi, cos_phi) = phi.sin_cos();
        let p1 = r * cos_phi;
        let s = 0.5 * (1.0 + vh.z);
        let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * (r * sin_phi);
        // Section 4.3: reprojection onto the hemisphere.
        let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
        // Section 3.4: unstretch (z kept positive: the normal of a facet is never in the
        // plane, and `d` is 0 there).
        Vec3::new(self.alpha_u * nh.x, self.alpha_v * nh.y, nh.z.max(1e-6)).normalize()
    }
}

/// A microfacet distribution's density of normals and Smith's `Lambda`, with what follows
/// from them alone: the masking `G1`, the height-correlated masking-shadowing `G2` and the
/// density of the visible normals (the same formulas for every distribution).
pub trait Smith {
    /// Microfacet normal density `D(m)` per unit projected area; 0 for `m.z <= 0`.
    fn d(&self, m: Vec3) -> f32;

    /// Smith's `Lambda(w)`, even in `w`: 0 at the normal, infinite in the plane.
    fn lambda(&self, w: Vec3) -> f32;

    /// Smith masking `G1(w) = 1 / (1 + Lambda(w))` (Heitz 2014 eq. 43).
    #[inline]
    fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing `G2(wo, wi) = 1 / (1 + Lambda(wo) + Lambda(wi))`
    /// (Heitz 2014 eq. 99). `Lambda` is even in `w`, so this also serves transmission.
    #[inline]
    fn g2(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Density of the visible normals seen from `wo` (`wo.z > 0`), per solid angle of `m`:
    /// `G1(wo) max(0, wo . m) D(m) / wo.z` (Heitz 2018 eq. 1; Heitz and d'Eon 2014 eq. 2).
    /// 0 for `wo` at or below the horizon.
    #[inline]
    fn pdf_visible(&self, wo: Vec3, m: Vec3) -> f32 {
        if wo.z <= 0.0 {
            return 0.0;
        }
        let wo_m = wo.dot(m);
        if wo_m <= 0.0 {
            return 0.0;
        }
        self.g1(wo) * wo_m * self.d(m) / wo.z
    }
}

impl Smith for Ggx {
    /// Microfacet normal density `D(m)` per unit projected area (Heitz 2014 eq. 85 in
    /// Cartesian form): `1 / (pi au av (x^2/au^2 + y^2/av^2 + z^2)^2)`; 0 for `m.z <= 0`.
    #[inline]
    fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let (x, y) = (m.x / self.alpha_u, m.y / self.alpha_v);
        let t = x * x + y * y + m.z * m.z;
        1.0 / (PI * self.alpha_u * self.alpha_v * t * t)
    }

    /// Smith's `Lambda(w)` for GGX (Heitz 2014 eq. 86):
    /// `(-1 + sqrt(1 + (au^2 x^2 + av^2 y^2) / z^2)) / 2`; infinite in the plane.
    #[inline]
    fn lambda(&self, w: Vec3) -> f32 {
        let z2 = w.z * w.z;
        if z2 == 0.0 {
            return f32::INFINITY;
        }
        let (x, y) = (self.alpha_u * w.x, self.alpha_v * w.y);
        let tan2_alpha2 = (x * x + y * y) / z2;
        // sqrt(1 + t) - 1 = t / (sqrt(1 + t) + 1) keeps precision for tiny t (smooth
        // surfaces seen near the normal).
        0.5 * tan2_alpha2 / ((1.0 + tan2_alpha2).sqrt() + 1.0)
    }
}

/// A material's microfacet distribution: GGX or Beckmann. Every method forwards to the
/// distribution's own (same arithmetic, so a GGX lobe reads the same numbers as before the
/// choice existed).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Microfacet {
    /// GGX (Trowbridge-Reitz): long tails, risotto's default.
    Ggx(Ggx),
    /// Beckmann: Gaussian slopes, Mitsuba 3's default.
    Beckmann(Beckmann),
}

impl From<Ggx> for Microfacet {
    fn from(g: Ggx) -> Self {
        Microfacet::Ggx(g)
    }
}

impl From<Beckmann> for Microfacet {
    fn from(b: Beckmann) -> Self {
        Microfacet::Beckmann(b)
    }
}

/// `$call` on whichever distribution `$self` holds.
macro_rules! forward {
    ($self:ident, $d:ident => $call:expr) => {
        match $self {
            Microfacet::Ggx($d) => $call,
            Microfacet::Beckmann($d) => $call,
        }
    };
}

impl Microfacet {
    /// Roughness along the tangent (`+x`).
    #[inline]
    pub fn alpha_u(&self) -> f32 {
        forward!(self, d => d.alpha_u)
    }

    /// Roughness along the bitangent (`+y`).
    #[inline]
    pub fn alpha_v(&self) -> f32 {
        forward!(self, d => d.alpha_v)
    }

    /// The distribution of the same family with roughnesses `alpha_u`, `alpha_v` (for a
    /// roughness given per shading point by a pattern).
    #[inline]
    pub fn with_alphas(&self, alpha_u: f32, alpha_v: f32) -> Microfacet {
        let masking = self.masking();
        match self {
            Microfacet::Ggx(_) => Ggx {
                masking,
                ..Ggx::new(alpha_u, alpha_v)
            }
            .into(),
            Microfacet::Beckmann(_) => Beckmann {
                masking,
                ..Beckmann::new(alpha_u, alpha_v)
            }
            .into(),
        }
    }

    /// True when both roughnesses are equal.
    #[inline]
    pub fn is_isotropic(&self) -> bool {
        self.alpha_u() == self.alpha_v()
    }

    /// The distribution's name in the scene file (`"ggx"` or `"beckmann"`).
    pub fn name(&self) -> &'static str {
        match self {
            Microfacet::Ggx(_) => "ggx",
            Microfacet::Beckmann(_) => "beckmann",
        }
    }

    /// Microfacet normal density `D(m)` ([`Ggx::d`], [`Beckmann::d`]).
    #[inline]
    pub fn d(&self, m: Vec3) -> f32 {
        forward!(self, d => d.d(m))
    }

    /// Smith's `Lambda(w)` ([`Ggx::lambda`], [`Beckmann::lambda`]).
    #[inline]
    pub fn lambda(&self, w: Vec3) -> f32 {
        forward!(self, d => d.lambda(w))
    }

    /// Smith masking `G1(w) = 1 / (1 + Lambda(w))`.
    #[inline]
    pub fn g1(&self, w: Vec3) -> f32 {
        forward!(self, d => d.g1(w))
    }

    /// The masking-shadowing `G2(wo, wi)`: height-correlated, or separable when the
    /// distribution's [`Masking`] says so.
    #[inline]
    pub fn g2(&self, wo: Vec3, wi: Vec3) -> f32 {
        forward!(self, d => match d.masking {
            Masking::HeightCorrelated => d.g2(wo, wi),
            Masking::Separable => d.g1(wo) * d.g1(wi),
        })
    }

    /// The masking-shadowing function [`Self::g2`] uses.
    #[inline]
    pub fn masking(&self) -> Masking {
        forward!(self, d => d.masking)
    }

    /// The same distribution with masking-shadowing function `masking`.
    pub fn with_masking(self, masking: Masking) -> Microfacet {
        match self {
            Microfacet::Ggx(g) => Ggx { masking, ..g }.into(),
            Microfacet::Beckmann(b) => Beckmann { masking, ..b }.into(),
        }
    }

    /// Density of the visible normals seen from `wo`, per solid angle of `m`.
    #[inline]
    pub fn pdf_visible(&self, wo: Vec3, m: Vec3) -> f32 {
        forward!(self, d => d.pdf_visible(wo, m))
    }

    /// Samples a visible normal seen from `wo`, density [`Microfacet::pdf_visible`].
    #[inline]
    pub fn sample_visible(&self, wo: Vec3, u: Vec2) -> Vec3 {
        forward!(self, d => d.sample_visible(wo, u))
    }
}

/// The unit half vector of a reflection, `normalize(wo + wi)` (Walter et al. 2007 eq. 13);
/// `None` when `wo + wi` vanishes or overflows.
#[inline]
pub(crate) fn reflection_half_vector(wo: Vec3, wi: Vec3) -> Option<Vec3> {
    let h = wo + wi;
    let len2 = h.length_squared();
    if !positive(len2) || !len2.is_finite() {
        return None;
    }
    Some(h / len2.sqrt())
}

/// Refraction of `wo` through a microfacet with normal `m` (`wo . m > 0`), relative index
/// `eta = n_t / n_i` (Snell's law in vector form, Walter et al. 2007 eq. 40): `None` under
/// total internal reflection.
#[inline]
pub fn refract_about(wo: Vec3, m: Vec3, eta: f32) -> Option<Vec3> {
    let c = wo.dot(m);
    let sin2_t = (1.0 - c * c).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(m * (c / eta - cos_t) - wo / eta)
}
