//! The rough conductor: microfacet reflection (GGX or Beckmann) with the conductor Fresnel term, plus the
//! optional Kulla-Conty multiple-scattering lobe. Local shading frame and conventions of
//! [`crate::bxdf`]; one-sided (black seen from below), as Mitsuba 3's `roughconductor`.

use crate::bxdf::{sample_cosine_hemisphere, BxdfSample};
use crate::conductor::fresnel_conductor_rgb;
use crate::energy_compensation::AlbedoTable;
use crate::microfacet::{positive, reflection_half_vector, Microfacet};
use risotto_components::{LobeSampled, Rgb, Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

/// Lobe bits of every sample: a reflection with a density (light sampling and MIS apply).
const GLOSSY_REFLECT: LobeSampled = LobeSampled(LobeSampled::REFLECT.0 | LobeSampled::DIFFUSE.0);

/// A rough conductor's parameters, with what the multiple-scattering lobe needs computed
/// once ([`RoughConductor::new`]).
#[derive(Clone, Debug, PartialEq)]
pub struct RoughConductor {
    /// The microfacet distribution (GGX or Beckmann).
    pub distribution: Microfacet,
    /// Real part of the relative complex index per channel.
    pub eta: Rgb,
    /// Imaginary part per channel.
    pub k: Rgb,
    /// Multiplies the Fresnel term (Mitsuba's `specular_reflectance`), in [0, 1].
    pub tint: Rgb,
    /// The multiple-scattering lobe, when energy compensation is on.
    compensation: Option<MultipleScattering>,
}

/// Kulla & Conty 2017's multiple-scattering lobe for one conductor:
/// `f_ms = F_ms (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg))` with the Fresnel colour of
/// the multiply scattered light `F_ms = F_avg^2 E_avg / (1 - F_avg (1 - E_avg))` (their
/// eq. for the "Fresnel for multiple scattering": a geometric series of bounces, each
/// keeping `F_avg` and escaping with `E_avg`).
#[derive(Clone, Debug, PartialEq)]
struct MultipleScattering {
    /// `E(mu)` of the white lobe at this roughness.
    table: AlbedoTable,
    /// `F_ms / (pi (1 - E_avg))`.
    scale: Rgb,
}

impl RoughConductor {
    /// A conductor with microfacet `distribution` (a [`crate::microfacet::Ggx`], a
    /// [`crate::microfacet::Beckmann`] or either as [`Microfacet`]), complex index `eta + i k`, Fresnel tint `tint`,
    /// and the multiple-scattering lobe when `energy_compensation` (its table is integrated
    /// here; an anisotropic lobe's is averaged over the azimuth of `wo`).
    pub fn new(
        distribution: impl Into<Microfacet>,
        eta: Rgb,
        k: Rgb,
        tint: Rgb,
        energy_compensation: bool,
    ) -> Self {
        let distribution = distribution.into();
        let table = energy_compensation.then(|| AlbedoTable::conductor(&distribution));
        RoughConductor::with_table(distribution, eta, k, tint, table, || {
            fresnel_average(eta, k)
        })
    }

    /// [`RoughConductor::new`] with the white lobe's albedo `table` given (`None`: no
    /// energy compensation) instead of integrated, and `F_avg` of `eta + i k` from
    /// `fresnel_avg` (called only when the lobe is compensated): for a roughness or an index
    /// that varies per shading point, whose tables are interpolated from a
    /// [`crate::roughness_grid::RoughnessGrid`] and whose `F_avg` may be shared.
    pub fn with_table(
        distribution: Microfacet,
        eta: Rgb,
        k: Rgb,
        tint: Rgb,
        table: Option<AlbedoTable>,
        fresnel_avg: impl FnOnce() -> Rgb,
    ) -> Self {
        let compensation = table.and_then(|table| {
            let loss = 1.0 - table.e_avg;
            // Smooth enough that single scattering keeps everything: no lobe.
            if loss <= 1e-5 {
                return None;
            }
            let f_avg = fresnel_avg() * tint;
            let e_avg = table.e_avg;
            let f_ms = f_avg
                * f_avg
                * e_avg
                * Rgb::new(
                    1.0 / (1.0 - f_avg.r * loss),
                    1.0 / (1.0 - f_avg.g * loss),
                    1.0 / (1.0 - f_avg.b * loss),
                );
            Some(MultipleScattering {
                table,
                scale: f_ms * (FRAC_1_PI / loss),
            })
        });
        RoughConductor {
            distribution,
            eta,
            k,
            tint,
            compensation,
        }
    }

    /// True when the multiple-scattering lobe is on.
    pub fn compensated(&self) -> bool {
        self.compensation.is_some()
    }

    /// `F(cos) * tint`.
    #[inline]
    fn fresnel(&self, cos: f32) -> Rgb {
        fresnel_conductor_rgb(cos, self.eta, self.k) * self.tint
    }

    /// Probability of sampling the multiple-scattering lobe seen from `mu_o`: the white
    /// lobe's share of the energy, `1 - E(mu_o)`.
    #[inline]
    fn ms_probability(&self, mu_o: f32) -> f32 {
        self.compensation
            .as_ref()
            .map_or(0.0, |c| (1.0 - c.table.e(mu_o)).clamp(0.0, 1.0))
    }

    /// `(f * cos theta_i, pdf)` at local `wo`, `wi`: the microfacet term
    /// `F(wo . m) D(m) G2(wo, wi) / (4 cos_o)` (Walter et al. 2007 eq. 20 times `cos_i`)
    /// plus the multiple-scattering lobe, and the density of [`RoughConductor::sample`].
    /// Zero when either direction is at or below the surface.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> (Rgb, f32) {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return (Rgb::BLACK, 0.0);
        }
        let Some(m) = reflection_half_vector(wo, wi) else {
            return (Rgb::BLACK, 0.0);
        };
        let wo_m = wo.dot(m);
        let d = self.distribution.d(m);
        let single = self.fresnel(wo_m) * (d * self.distribution.g2(wo, wi) / (4.0 * wo.z));
        // Reflection's Jacobian dm/dwi = 1 / (4 |wi . m|) (Walter et al. 2007 eq. 14).
        let pdf_single = self.distribution.pdf_visible(wo, m) / (4.0 * wo_m);
        match &self.compensation {
            None => (single, pdf_single),
            Some(c) => {
                let q = self.ms_probability(wo.z);
                let ms = c.scale * ((1.0 - c.table.e(wo.z)) * (1.0 - c.table.e(wi.z)) * wi.z);
                let pdf = (1.0 - q) * pdf_single + q * wi.z * FRAC_1_PI;
                (single + ms, pdf)
            }
        }
    }

    /// Samples a direction from local `wo` (`u` a 2D sample, `u_lobe` a third number for
    /// the lobe choice): a visible normal (Heitz 2018) mirrored, or with probability
    /// `1 - E(mu_o)` (the white lobe's missing share) a cosine-weighted direction for the
    /// multiple-scattering lobe; the weight is `f cos / pdf` of the one-sample mixture. The
    /// microfacet term's weight is `F G2 / G1(wo)`, finite at any roughness. `None` for
    /// `wo` at or below the surface or a sample below it.
    pub fn sample(&self, wo: Vec3, u: Vec2, u_lobe: f32) -> Option<BxdfSample> {
        if !positive(wo.z) {
            return None;
        }
        let wi = if u_lobe < self.ms_probability(wo.z) {
            sample_cosine_hemisphere(u)
        } else {
            let m = self.distribution.sample_visible(wo, u);
            2.0 * wo.dot(m) * m - wo
        };
        let (value, pdf) = self.eval(wo, wi);
        if !positive(pdf) || !pdf.is_finite() {
            return None;
        }
        Some(BxdfSample {
            wi,
            weight: value * (1.0 / pdf),
            pdf,
            lobe: GLOSSY_REFLECT,
            eta: 1.0,
        })
    }

    /// The reflectance at normal incidence, `F(1) * tint` (the `albedo` AOV).
    pub fn normal_reflectance(&self) -> Rgb {
        self.fresnel(1.0)
    }
}

/// `F_avg = 2 int_0^1 F(mu) mu dmu` per channel, by a 64-point midpoint rule (the
/// integrand is smooth; 1e-4 accurate).
pub fn fresnel_average(eta: Rgb, k: Rgb) -> Rgb {
    const N: usize = 64;
    let mut sum = Rgb::BLACK;
    for i in 0..N {
        let mu = (i as f32 + 0.5) / N as f32;
        sum += fresnel_conductor_rgb(mu, eta, k) * (2.0 * mu / N as f32);
    }
    sum
}

#[cfg(test)]
mod tests;
