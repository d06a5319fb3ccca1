//! The two interfaces of a layered Bxdf ([`crate::layered`]): the dielectric coat on top and
//! the opaque base at the bottom, each with pbrt-v4's BxDF interface in its own terms
//! (`f` without the cosine, `Sample_f` and `PDF` restricted to reflection or transmission),
//! built on [`crate::rough_dielectric`], [`crate::rough_conductor`] and the smooth lobes of
//! [`crate::bxdf`]. Local frame of [`crate::bxdf`]; the coat's `+z` is the outside.

use crate::bxdf::{fresnel_dielectric, reflect_local, refract_local, sample_cosine_hemisphere};
use crate::conductor::fresnel_conductor_rgb;
use crate::microfacet::positive;
use crate::microfacet::Ggx;
use crate::rough_conductor::RoughConductor;
use crate::rough_dielectric::{Lobes, RoughDielectric};
use risotto_components::{Rgb, Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

/// Below this roughness (the larger `alpha`) an interface is a perfect specular one:
/// pbrt-v4's `TrowbridgeReitzDistribution::EffectivelySmooth` threshold.
pub const SMOOTH_ALPHA: f32 = 1e-3;

/// One sampled direction at an interface, in pbrt-v4's terms: `f` is the BSDF value
/// *without* the cosine (for a Dirac lobe: the value whose `f |cos| / pdf` is the weight),
/// `pdf` the solid-angle density (a Dirac lobe's: its discrete probability).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InterfaceSample {
    /// Sampled direction, local.
    pub wi: Vec3,
    /// BSDF value without the cosine.
    pub f: Rgb,
    /// Density (or discrete probability of a Dirac lobe).
    pub pdf: f32,
    /// True for a reflection (same side as `wo`).
    pub reflect: bool,
    /// True for a Dirac lobe.
    pub specular: bool,
}

impl InterfaceSample {
    /// A usable sample: positive finite density, non-black value, off the plane (pbrt-v4's
    /// `!bs || !bs->f || bs->pdf == 0 || bs->wi.z == 0` tests).
    #[inline]
    fn usable(self) -> Option<Self> {
        (self.pdf > 0.0 && self.pdf.is_finite() && !self.f.is_black() && self.wi.z != 0.0)
            .then_some(self)
    }

    /// `f |cos theta_i| / pdf`.
    #[inline]
    pub fn weight(&self) -> Rgb {
        self.f * (self.wi.z.abs() / self.pdf)
    }
}

/// The dielectric coat: index `eta` (inside over outside); smooth (Dirac lobes) when its
/// roughness is below [`SMOOTH_ALPHA`] or `eta = 1` (pbrt-v4's `DielectricBxDF` takes its
/// specular branch then), else a GGX interface.
#[derive(Clone, Debug, PartialEq)]
pub enum Coat {
    /// A smooth interface.
    Smooth {
        /// `n_inside / n_outside`.
        eta: f32,
    },
    /// A rough interface (no energy compensation: pbrt-v4 has none). Boxed: the interface
    /// holds its (unused here) compensation tables inline, 260 bytes.
    Rough(Box<RoughDielectric>),
}

impl Coat {
    /// The coat of index `eta` and distribution `ggx`.
    pub fn new(ggx: Ggx, eta: f32) -> Self {
        if eta == 1.0 || ggx.alpha_u.max(ggx.alpha_v) < SMOOTH_ALPHA {
            Coat::Smooth { eta }
        } else {
            Coat::Rough(Box::new(RoughDielectric::new(ggx, eta, Rgb::WHITE, false)))
        }
    }

    /// The index of refraction (inside over outside).
    pub fn eta(&self) -> f32 {
        match self {
            Coat::Smooth { eta } => *eta,
            Coat::Rough(d) => d.eta,
        }
    }

    /// True when every lobe is a Dirac one.
    pub fn is_specular(&self) -> bool {
        matches!(self, Coat::Smooth { .. })
    }

    /// `f(wo, wi)` without the cosine (radiance transport); 0 for a smooth coat.
    pub fn f(&self, wo: Vec3, wi: Vec3) -> Rgb {
        match self {
            Coat::Smooth { .. } => Rgb::BLACK,
            Coat::Rough(d) => cosine_removed(d.eval(wo, wi).0, wi),
        }
    }

    /// The density of [`Coat::sample`] restricted to `lobes` (0 for a smooth coat).
    pub fn pdf(&self, wo: Vec3, wi: Vec3, lobes: Lobes) -> f32 {
        match self {
            Coat::Smooth { .. } => 0.0,
            Coat::Rough(d) => d.eval_lobes(wo, wi, lobes).1,
        }
    }

    /// Samples a direction from `wo` (either side) restricted to `lobes`: `uc` chooses the
    /// lobe, `u` the microfacet. `importance` transports importance instead of radiance: a
    /// refraction then lacks the `1 / eta_rel^2` factor of radiance (pbrt-v4's
    /// `TransportMode::Importance`; the layered evaluation samples the light's side so).
    pub fn sample(
        &self,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        lobes: Lobes,
        importance: bool,
    ) -> Option<InterfaceSample> {
        let s = match self {
            Coat::Smooth { eta } => smooth_dielectric_sample(*eta, wo, uc, lobes)?,
            Coat::Rough(d) => {
                let s = d.sample_lobes(wo, u, uc, lobes)?;
                InterfaceSample {
                    wi: s.wi,
                    f: cosine_removed(s.weight * s.pdf, s.wi),
                    pdf: s.pdf,
                    reflect: s.wi.z * wo.z > 0.0,
                    specular: s.lobe.is_specular(),
                }
            }
        };
        let mut s = s.usable()?;
        if importance && !s.reflect {
            // Undo the radiance factor 1 / eta_rel^2 of the crossing.
            let eta_rel = if wo.z > 0.0 {
                self.eta()
            } else {
                1.0 / self.eta()
            };
            s.f *= eta_rel * eta_rel;
        }
        Some(s)
    }
}

/// A smooth dielectric's Dirac lobes restricted to `lobes` (pbrt-v4's `DielectricBxDF`
/// specular branch): reflection with probability `R / (R + T)` of the allowed ones, value
/// `R / |cos|`; refraction with `T / (R + T)`, value `T / (eta_rel^2 |cos|)` (radiance).
fn smooth_dielectric_sample(eta: f32, wo: Vec3, uc: f32, lobes: Lobes) -> Option<InterfaceSample> {
    if wo.z == 0.0 {
        return None;
    }
    let r = fresnel_dielectric(wo.z, eta);
    let t = 1.0 - r;
    let (pr, pt) = match lobes {
        Lobes::Both => (r, t),
        Lobes::Reflection => (r, 0.0),
        Lobes::Transmission => (0.0, t),
    };
    if pr + pt <= 0.0 {
        return None;
    }
    if uc < pr / (pr + pt) {
        let wi = reflect_local(wo);
        return Some(InterfaceSample {
            wi,
            f: Rgb::splat(r / wi.z.abs()),
            pdf: pr / (pr + pt),
            reflect: true,
            specular: true,
        });
    }
    let (wi, eta_rel) = refract_local(wo, eta)?;
    Some(InterfaceSample {
        wi,
        f: Rgb::splat(t / (eta_rel * eta_rel * wi.z.abs())),
        pdf: pt / (pr + pt),
        reflect: false,
        specular: true,
    })
}

/// `f |cos_i| -> f`.
#[inline]
fn cosine_removed(f_cos: Rgb, wi: Vec3) -> Rgb {
    if wi.z == 0.0 {
        Rgb::BLACK
    } else {
        f_cos * (1.0 / wi.z.abs())
    }
}

/// The opaque base under the coat, seen from above (`+z`): it reflects only.
#[derive(Clone, Copy, Debug)]
pub enum Base<'a> {
    /// Lambertian of the given reflectance (pbrt-v4's `DiffuseBxDF`).
    Diffuse(Rgb),
    /// A smooth conductor of complex index `eta + i k` (relative to the coat's index).
    SmoothConductor {
        /// Real part per channel.
        eta: Rgb,
        /// Imaginary part per channel.
        k: Rgb,
    },
    /// A GGX conductor (its index relative to the coat's).
    RoughConductor(&'a RoughConductor),
}

impl Base<'_> {
    /// True when every lobe is a Dirac one.
    pub fn is_specular(&self) -> bool {
        matches!(self, Base::SmoothConductor { .. })
    }

    /// `f(wo, wi)` without the cosine; 0 unless both directions are above.
    pub fn f(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return Rgb::BLACK;
        }
        match self {
            Base::Diffuse(r) => *r * FRAC_1_PI,
            Base::SmoothConductor { .. } => Rgb::BLACK,
            Base::RoughConductor(c) => cosine_removed(c.eval(wo, wi).0, wi),
        }
    }

    /// The density of [`Base::sample`].
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return 0.0;
        }
        match self {
            Base::Diffuse(_) => wi.z * FRAC_1_PI,
            Base::SmoothConductor { .. } => 0.0,
            Base::RoughConductor(c) => c.eval(wo, wi).1,
        }
    }

    /// Samples a reflected direction from `wo` (above): cosine-weighted for the diffuse
    /// base, the mirror direction for the smooth conductor, visible normals for the rough
    /// one.
    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<InterfaceSample> {
        if !positive(wo.z) {
            return None;
        }
        let s = match self {
            Base::Diffuse(r) => {
                let wi = sample_cosine_hemisphere(u);
                InterfaceSample {
                    wi,
                    f: *r * FRAC_1_PI,
                    pdf: wi.z * FRAC_1_PI,
                    reflect: true,
                    specular: false,
                }
            }
            Base::SmoothConductor { eta, k } => {
                let wi = reflect_local(wo);
                InterfaceSample {
                    wi,
                    f: fresnel_conductor_rgb(wo.z, *eta, *k) * (1.0 / wi.z),
                    pdf: 1.0,
                    reflect: true,
                    specular: true,
                }
            }
            Base::RoughConductor(c) => {
                let s = c.sample(wo, u, uc)?;
                InterfaceSample {
                    wi: s.wi,
                    f: cosine_removed(s.weight * s.pdf, s.wi),
                    pdf: s.pdf,
                    reflect: true,
                    specular: false,
                }
            }
        };
        s.usable()
    }
}
