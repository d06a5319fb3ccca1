//! Directional-albedo tables of single-scattering microfacet lobes (GGX or Beckmann: the
//! quadrature only samples visible normals and evaluates `G1`, `G2`), for the energy compensation
//! of multiple scattering between microfacets.
//!
//! A microfacet lobe with single scattering only loses the light that bounces more than
//! once between facets: a white rough conductor at `alpha = 1` reflects only ~60-70% of the
//! light. Kulla & Conty 2017 ("Revisiting Physically Based Shading at Imageworks", SIGGRAPH
//! course, sec. "Multiple scattering microfacet BSDFs with the Smith model") add a diffuse
//! like lobe `f_ms = (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg))` whose albedo is exactly
//! the missing `1 - E(mu_o)`, where `E(mu)` is the lobe's directional albedo with `F = 1` and
//! `E_avg = 2 int_0^1 E(mu) mu dmu` its hemispherical average. [`AlbedoTable`] holds `E` at
//! [`MU_POINTS`] cosines for one roughness (the built-in materials have one roughness each,
//! so a table per material is computed once when the scene is loaded: ~130k evaluations,
//! a millisecond or two) and `E_avg` of its piecewise-linear interpolant, so that the added
//! lobe makes up the loss exactly up to the interpolation error (< 0.5%, tested).

use crate::bxdf::fresnel_dielectric;
use crate::microfacet::{refract_about, Microfacet};
use risotto_components::{Vec2, Vec3};

/// Cosines at which the table holds the albedo: `mu_i = i / (MU_POINTS - 1)`.
pub const MU_POINTS: usize = 32;

/// Strata per axis of the quadrature of one table entry (`STRATA^2` visible normals).
const STRATA: usize = 64;

/// The directional albedo `E(mu)` of one lobe at [`MU_POINTS`] cosines, and its average.
#[derive(Clone, Debug, PartialEq)]
pub struct AlbedoTable {
    /// `E(mu_i)`, `mu_i = i / (MU_POINTS - 1)`.
    pub e: [f32; MU_POINTS],
    /// `2 int_0^1 E(mu) mu dmu` of the piecewise-linear interpolant of `e`.
    pub e_avg: f32,
}

impl AlbedoTable {
    /// The table of `albedo(mu)` at the grid cosines (`mu = 0` is evaluated at `1e-3`, where
    /// the lobes are continuous and the formulas finite).
    pub fn from_fn(albedo: impl Fn(f32) -> f32) -> Self {
        let mut e = [0.0; MU_POINTS];
        for (i, e) in e.iter_mut().enumerate() {
            let mu = (i as f32 / (MU_POINTS - 1) as f32).max(1e-3);
            *e = albedo(mu).clamp(0.0, 1.0);
        }
        // Each segment's E is linear, so E mu is quadratic and Simpson's rule exact.
        let h = 1.0 / (MU_POINTS - 1) as f64;
        let mut avg = 0.0f64;
        for i in 0..MU_POINTS - 1 {
            let (a, b) = (i as f64 * h, (i + 1) as f64 * h);
            let (ea, eb) = (e[i] as f64, e[i + 1] as f64);
            let mid = 0.5 * (a + b) * 0.5 * (ea + eb);
            avg += (b - a) / 6.0 * (a * ea + 4.0 * mid + b * eb);
        }
        AlbedoTable {
            e,
            e_avg: (2.0 * avg) as f32,
        }
    }

    /// The albedo of a white (`F = 1`) rough conductor: [`conductor_albedo`] at every cosine.
    pub fn conductor(distribution: &Microfacet) -> Self {
        AlbedoTable::from_fn(|mu| conductor_albedo(distribution, mu))
    }

    /// The albedo of a rough dielectric interface seen from the side where the relative
    /// index is `eta` (reflection plus transmission, without the radiance scaling):
    /// [`dielectric_albedo`] at every cosine.
    pub fn dielectric(distribution: &Microfacet, eta: f32) -> Self {
        AlbedoTable::from_fn(|mu| dielectric_albedo(distribution, eta, mu))
    }

    /// `E(mu)` by linear interpolation (`mu` clamped to `[0, 1]`).
    #[inline]
    pub fn e(&self, mu: f32) -> f32 {
        let x = mu.clamp(0.0, 1.0) * (MU_POINTS - 1) as f32;
        let i = (x as usize).min(MU_POINTS - 2);
        let t = x - i as f32;
        self.e[i] * (1.0 - t) + self.e[i + 1] * t
    }
}

/// Midpoints of a `STRATA x STRATA` grid over the unit square: a deterministic product
/// midpoint rule for the tables.
fn strata() -> impl Iterator<Item = Vec2> {
    strata_of(STRATA)
}

/// Midpoints of a `count x count` grid over the unit square (a product midpoint rule over
/// the samples of a visible-normal sampler).
pub(crate) fn strata_of(count: usize) -> impl Iterator<Item = Vec2> {
    let n = count as f32;
    (0..count * count).map(move |k| {
        Vec2::new(
            ((k / count) as f32 + 0.5) / n,
            ((k % count) as f32 + 0.5) / n,
        )
    })
}

/// The direction at cosine `mu` in the `xz` plane.
fn direction(mu: f32) -> Vec3 {
    Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu)
}

/// Azimuths over which an anisotropic lobe's albedo is averaged: the lobe is symmetric
/// about both tangent axes, so a quarter turn, at the midpoints of [`AZIMUTHS`] sectors.
const AZIMUTHS: usize = 4;

/// The mean of `albedo(wo)` over the azimuths of `wo` at cosine `mu`: one azimuth for an
/// isotropic lobe, [`AZIMUTHS`] over a quarter turn for an anisotropic one (whose
/// compensation is then exact on average over azimuth rather than at every azimuth).
fn azimuthal_mean(distribution: &Microfacet, mu: f32, albedo: impl Fn(Vec3) -> f64) -> f32 {
    let d = direction(mu);
    if distribution.is_isotropic() {
        return albedo(d) as f32;
    }
    let mut sum = 0.0;
    for k in 0..AZIMUTHS {
        let phi = (k as f32 + 0.5) / AZIMUTHS as f32 * std::f32::consts::FRAC_PI_2;
        let (s, c) = phi.sin_cos();
        sum += albedo(Vec3::new(d.x * c, d.x * s, d.z));
    }
    (sum / AZIMUTHS as f64) as f32
}

/// `E(mu) = int f cos dwi` of the white microfacet reflection lobe, by sampling visible normals:
/// each sample's weight `f cos / pdf` is `G2(wo, wi) / G1(wo)` (Heitz 2018 sec. 2), averaged
/// over a stratified grid.
pub fn conductor_albedo(distribution: &Microfacet, mu: f32) -> f32 {
    azimuthal_mean(distribution, mu, |wo| conductor_albedo_at(distribution, wo))
}

/// [`conductor_albedo`] seen from one direction `wo`.
fn conductor_albedo_at(distribution: &Microfacet, wo: Vec3) -> f64 {
    let g1 = distribution.g1(wo);
    let mut sum = 0.0f64;
    for u in strata() {
        let m = distribution.sample_visible(wo, u);
        let wi = 2.0 * wo.dot(m) * m - wo;
        if wi.z > 0.0 {
            sum += (distribution.g2(wo, wi) / g1) as f64;
        }
    }
    sum / (STRATA * STRATA) as f64
}

/// `E(mu)` of a rough dielectric interface (`eta` = index below over index above, `wo`
/// above): the Fresnel-weighted sum of the reflected and the refracted weights
/// `G2 / G1` per visible normal, without the `1 / eta^2` radiance factor -- the fraction
/// of energy single scattering keeps, which is 1 for a smooth interface.
pub fn dielectric_albedo(distribution: &Microfacet, eta: f32, mu: f32) -> f32 {
    azimuthal_mean(distribution, mu, |wo| {
        dielectric_albedo_at(distribution, eta, wo)
    })
}

/// [`dielectric_albedo`] seen from one direction `wo`.
fn dielectric_albedo_at(distribution: &Microfacet, eta: f32, wo: Vec3) -> f64 {
    let g1 = distribution.g1(wo);
    let mut sum = 0.0f64;
    for u in strata() {
        let m = distribution.sample_visible(wo, u);
        let c = wo.dot(m);
        let r = fresnel_dielectric(c, eta);
        let wr = 2.0 * c * m - wo;
        if wr.z > 0.0 {
            sum += (r * distribution.g2(wo, wr) / g1) as f64;
        }
        if let Some(wt) = refract_about(wo, m, eta) {
            if wt.z < 0.0 {
                sum += ((1.0 - r) * distribution.g2(wo, wt) / g1) as f64;
            }
        }
    }
    sum / (STRATA * STRATA) as f64
}
