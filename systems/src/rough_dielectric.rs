//! The rough dielectric: microfacet (GGX or Beckmann) reflection and transmission through an interface
//! between two indices (Walter et al. 2007, "Microfacet Models for Refraction through Rough
//! Surfaces", EGSR), sampled by visible normals, with an optional energy compensation.
//! Local shading frame and conventions of [`crate::bxdf`]: `+z` is the outside,
//! `eta = n_inside / n_outside`, and `wo` may be on either side.
//!
//! Transmitted radiance is scaled by `1 / eta_rel^2` (`eta_rel = n_t / n_i` of the crossing),
//! as the smooth [`crate::bxdf::dielectric_sample`] does.

use crate::bxdf::{fresnel_dielectric, BxdfSample};
use crate::energy_compensation::AlbedoTable;
use crate::microfacet::{positive, refract_about, Microfacet};
use risotto_components::{LobeSampled, Rgb, Vec2, Vec3};

/// Lobe bits of a reflected sample (a density exists: light sampling and MIS apply).
const GLOSSY_REFLECT: LobeSampled = LobeSampled(LobeSampled::REFLECT.0 | LobeSampled::DIFFUSE.0);
/// Lobe bits of a transmitted sample.
const GLOSSY_TRANSMIT: LobeSampled = LobeSampled(LobeSampled::TRANSMIT.0 | LobeSampled::DIFFUSE.0);
/// Lobe bits of the pass-through of an index-matched interface (`eta = 1`).
const SPECULAR_TRANSMIT: LobeSampled =
    LobeSampled(LobeSampled::TRANSMIT.0 | LobeSampled::SPECULAR.0);

/// Which lobes of an interface a sampler may choose (pbrt-v4's `BxDFReflTransFlags`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lobes {
    /// Reflection or transmission, chosen by the Fresnel factor.
    Both,
    /// Reflection only.
    Reflection,
    /// Transmission only.
    Transmission,
}

/// A rough dielectric interface's parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughDielectric {
    /// The microfacet distribution (GGX or Beckmann).
    pub distribution: Microfacet,
    /// `n_inside / n_outside`.
    pub eta: f32,
    /// Multiplies transmitted light, in [0, 1].
    pub tint: Rgb,
    /// When energy compensation is on: the single-scattering albedo seen from outside
    /// (`[0]`, relative index `eta`) and from inside (`[1]`, `1 / eta`).
    /// Held inline (no heap) so that per-point lobes of a roughness pattern can live in a
    /// worker's arena, which drops nothing.
    compensation: Option<[AlbedoTable; 2]>,
}

impl RoughDielectric {
    /// An interface with microfacet `distribution` (GGX or Beckmann), relative index `eta` (`n_inside / n_outside`,
    /// positive and finite) and transmission tint `tint`.
    ///
    /// With `energy_compensation`, both lobes are divided by the single-scattering albedo
    /// `E(mu_o)` of the side `wo` is on (reflection plus transmission without the radiance
    /// factor; Turquin 2019, "Practical multiple scattering compensation for microfacet
    /// models", sec. 4, the dielectric case): an interface loses no energy, so the
    /// compensated lobe conserves it exactly (up to the table's interpolation), with the
    /// lobes' shape and their Fresnel split kept. It is not reciprocal (`E(mu_o)` only),
    /// as Turquin's is not; the tables are integrated here.
    pub fn new(
        distribution: impl Into<Microfacet>,
        eta: f32,
        tint: Rgb,
        energy_compensation: bool,
    ) -> Self {
        let distribution = distribution.into();
        let compensation = (energy_compensation && eta != 1.0).then(|| {
            [
                AlbedoTable::dielectric(&distribution, eta),
                AlbedoTable::dielectric(&distribution, 1.0 / eta),
            ]
        });
        RoughDielectric::with_tables(distribution, eta, tint, compensation)
    }

    /// [`RoughDielectric::new`] with the albedo tables seen from outside and from inside
    /// given (`None`: no energy compensation; ignored at `eta = 1`) instead of integrated:
    /// for a roughness that varies per shading point, whose tables are interpolated from a
    /// [`crate::roughness_grid::RoughnessGrid`].
    pub fn with_tables(
        distribution: Microfacet,
        eta: f32,
        tint: Rgb,
        tables: Option<[AlbedoTable; 2]>,
    ) -> Self {
        RoughDielectric {
            distribution,
            eta,
            tint,
            compensation: tables.filter(|_| eta != 1.0),
        }
    }

    /// The same interface at another relative index (a shape nested in a medium of index
    /// other than 1), without energy compensation: its tables hold the albedo at the
    /// material's own index, and integrating new ones per shading point would cost a few
    /// milliseconds each.
    pub fn with_eta(&self, eta: f32) -> Self {
        RoughDielectric {
            distribution: self.distribution,
            eta,
            tint: self.tint,
            compensation: None,
        }
    }

    /// True when energy compensation is on.
    pub fn compensated(&self) -> bool {
        self.compensation.is_some()
    }

    /// `wo` (and `wi`) mirrored to the outside when `wo` is inside, with the relative
    /// index and the table index of that side. The microfacet distribution and Smith's
    /// `Lambda` are even, so the inside looks like an outside of index `1 / eta`.
    #[inline]
    fn side(&self, wo: Vec3) -> (f32, f32, usize) {
        if wo.z > 0.0 {
            (1.0, self.eta, 0)
        } else {
            (-1.0, 1.0 / self.eta, 1)
        }
    }

    /// `(f * |cos theta_i|, pdf)` at local `wo`, `wi`: Walter et al. 2007's reflection
    /// (eq. 20) and transmission (eq. 21) terms with the height-correlated `G2`, and the
    /// density of [`RoughDielectric::sample`] (eqs. 14 and 17 for the Jacobians of the
    /// half vectors, times the Fresnel lobe probability).
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> (Rgb, f32) {
        self.eval_lobes(wo, wi, Lobes::Both)
    }

    /// [`RoughDielectric::eval`] with the density of a sampler restricted to `lobes`
    /// ([`RoughDielectric::sample_lobes`]): the value is the same, the density is that of
    /// the one lobe without the Fresnel choice, 0 for a direction of the other lobe (pbrt-v4's
    /// `PDF` with `BxDFReflTransFlags`, which its layered BxDF uses).
    pub fn eval_lobes(&self, wo: Vec3, wi: Vec3, lobes: Lobes) -> (Rgb, f32) {
        if wo.z == 0.0 || wi.z == 0.0 || !(self.eta > 0.0 && self.eta != 1.0) {
            return (Rgb::BLACK, 0.0);
        }
        let (flip, eta, side) = self.side(wo);
        let (wo, wi) = (wo * flip, wi * flip);
        let reflect = wi.z > 0.0;
        // The (generalised) half vector: wo + wi, or wo + eta wi for a refraction (Walter
        // eq. 16), turned to the outside.
        let h = if reflect { wo + wi } else { wo + wi * eta };
        let len2 = h.length_squared();
        if !positive(len2) || !len2.is_finite() {
            return (Rgb::BLACK, 0.0);
        }
        let m = h * (1.0f32.copysign(h.z) / len2.sqrt());
        let (wo_m, wi_m) = (wo.dot(m), wi.dot(m));
        // Both directions on the sides of the microfacet their macro sides say.
        if !positive(wo_m) || (reflect != (wi_m > 0.0)) || wi_m == 0.0 {
            return (Rgb::BLACK, 0.0);
        }
        let f = fresnel_dielectric(wo_m, eta);
        let d = self.distribution.d(m);
        let g = self.distribution.g2(wo, wi);
        let pdf_m = self.distribution.pdf_visible(wo, m);
        let scale = match &self.compensation {
            Some(t) => 1.0 / t[side].e(wo.z).max(1e-3),
            None => 1.0,
        };
        if reflect {
            let value = f * d * g / (4.0 * wo.z);
            let choice = match lobes {
                Lobes::Both => f,
                Lobes::Reflection => 1.0,
                Lobes::Transmission => 0.0,
            };
            (Rgb::splat(value * scale), pdf_m / (4.0 * wo_m) * choice)
        } else {
            // Walter eq. 21 in the form of pbrt-v4 sec. 9.7 with eta = n_t / n_i:
            // f_t |cos_i| = (1 - F) D G2 |wi.m| |wo.m| / (cos_o (wi.m + wo.m / eta)^2) / eta^2
            // (the last factor: radiance), and dm/dwi = |wi.m| / (wi.m + wo.m / eta)^2.
            let denom = wi_m + wo_m / eta;
            let denom2 = denom * denom;
            let dm_dwi = -wi_m / denom2;
            let value = (1.0 - f) * d * g * wo_m * dm_dwi / (wo.z * eta * eta);
            let choice = match lobes {
                Lobes::Both => 1.0 - f,
                Lobes::Reflection => 0.0,
                Lobes::Transmission => 1.0,
            };
            (self.tint * (value * scale), pdf_m * dm_dwi * choice)
        }
    }

    /// Samples a direction from local `wo` (either side): a visible normal (Heitz 2018),
    /// then reflection about it with probability `F(wo . m)` (`u_lobe < F`) or refraction.
    /// The weight is `f |cos| / pdf`: `G2 / G1(wo)`, times `tint / eta_rel^2` for a
    /// refraction (divided by `E(mu_o)` with compensation). `None` for `wo` in the plane or
    /// a sample on the wrong side. An index-matched interface (`eta = 1`) passes the ray
    /// straight through (a Dirac transmission of weight `tint`).
    pub fn sample(&self, wo: Vec3, u: Vec2, u_lobe: f32) -> Option<BxdfSample> {
        self.sample_lobes(wo, u, u_lobe, Lobes::Both)
    }

    /// [`RoughDielectric::sample`] restricted to `lobes`: `Reflection` always reflects about
    /// the visible normal, `Transmission` always refracts (`None` under total internal
    /// reflection), each with the density of [`RoughDielectric::eval_lobes`] (no Fresnel
    /// choice) and so a weight carrying the Fresnel factor. The index-matched pass-through
    /// is a transmission.
    pub fn sample_lobes(&self, wo: Vec3, u: Vec2, u_lobe: f32, lobes: Lobes) -> Option<BxdfSample> {
        if wo.z == 0.0 || !wo.z.is_finite() || !(self.eta > 0.0 && self.eta.is_finite()) {
            return None;
        }
        if self.eta == 1.0 {
            if lobes == Lobes::Reflection {
                return None;
            }
            return Some(BxdfSample {
                wi: -wo,
                weight: self.tint,
                pdf: 1.0,
                lobe: SPECULAR_TRANSMIT,
                eta: 1.0,
            });
        }
        let (flip, eta, _) = self.side(wo);
        let wo_up = wo * flip;
        let m = self.distribution.sample_visible(wo_up, u);
        let wo_m = wo_up.dot(m);
        let f = fresnel_dielectric(wo_m, eta);
        let reflect = match lobes {
            Lobes::Both => u_lobe < f,
            Lobes::Reflection => true,
            Lobes::Transmission => false,
        };
        let (wi_up, lobe, eta_rel) = if reflect {
            (2.0 * wo_m * m - wo_up, GLOSSY_REFLECT, 1.0)
        } else {
            (refract_about(wo_up, m, eta)?, GLOSSY_TRANSMIT, eta)
        };
        // A refraction that ends above the surface, or a reflection below it, is a path
        // the height-correlated model gives no weight to.
        if (lobe == GLOSSY_REFLECT) != (wi_up.z > 0.0) || wi_up.z == 0.0 {
            return None;
        }
        let wi = wi_up * flip;
        let (value, pdf) = self.eval_lobes(wo, wi, lobes);
        if !positive(pdf) || !pdf.is_finite() {
            return None;
        }
        Some(BxdfSample {
            wi,
            weight: value * (1.0 / pdf),
            pdf,
            lobe,
            eta: eta_rel,
        })
    }
}

#[cfg(test)]
mod tests;
