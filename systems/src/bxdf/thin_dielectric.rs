//! Thin dielectric: a pane of glass too thin to model (Mitsuba 3's `thindielectric`,
//! pbrt-v4's `ThinDielectricBxDF`, sec. 9.5.3).
//!
//! Light meets two parallel interfaces a negligible distance apart. Each has the Fresnel
//! reflectance `R = F(|cos|, eta)` of a single interface; the light that enters bounces
//! between them, and summing the geometric series of the bounces gives
//!
//! `R' = R + T^2 R (1 + R^2 + R^4 + ...) = R + T^2 R / (1 - R^2)`, `T' = 1 - R'`
//!
//! with `T = 1 - R`, which simplifies to `R' = 2R / (1 + R)`. Inside a slab with parallel
//! faces the light leaves at the angle it entered, so the transmitted direction is `-wo`
//! (no refraction offset is modelled: the pane is thin) and the ray crosses no medium
//! boundary (`eta = 1`).
//!
//! Both lobes are Dirac. The pane is symmetric: `wo` may be on either side.

use super::{
    fresnel_dielectric, reflect_local, valid_eta, BxdfSample, SPECULAR_REFLECT, SPECULAR_TRANSMIT,
};
use risotto_components::{Rgb, Vec2, Vec3};

/// `R'` of a thin pane of relative index `eta` seen at `cos_theta` (either sign): the
/// single-interface Fresnel reflectance with the internal bounces summed (module docs). The
/// transmittance is `1 - R'`.
#[inline]
pub fn thin_dielectric_reflectance(cos_theta: f32, eta: f32) -> f32 {
    let r = fresnel_dielectric(cos_theta.abs(), eta);
    // R + T^2 R / (1 - R^2) with T = 1 - R, in the form that stays finite at R = 1.
    2.0 * r / (1.0 + r)
}

/// Samples a thin pane: reflection with probability `R'` (weight 1), straight transmission
/// `wi = -wo` with probability `T' = 1 - R'` (weight 1, `eta = 1`). `None` for `wo` in the
/// plane or a non-positive `eta`.
pub fn thin_dielectric_sample(eta: f32, wo: Vec3, u: Vec2) -> Option<BxdfSample> {
    if wo.z == 0.0 || !wo.z.is_finite() || !valid_eta(eta) {
        return None;
    }
    let r = thin_dielectric_reflectance(wo.z, eta);
    if u.x < r {
        Some(BxdfSample {
            wi: reflect_local(wo),
            weight: Rgb::WHITE,
            pdf: r,
            lobe: SPECULAR_REFLECT,
            eta: 1.0,
        })
    } else {
        Some(BxdfSample {
            wi: -wo,
            weight: Rgb::WHITE,
            pdf: 1.0 - r,
            lobe: SPECULAR_TRANSMIT,
            eta: 1.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::SplitMix64 as Rng;

    /// The bounce series summed term by term (f64), against the closed form.
    #[test]
    fn reflectance_is_the_summed_bounce_series_and_conserves_energy() {
        for eta in [1.1f32, 1.33, 1.5, 2.4] {
            for k in 0..=20 {
                let cos = (k as f32 / 20.0).max(1e-4);
                let r = fresnel_dielectric(cos, eta) as f64;
                let t = 1.0 - r;
                // Reflected off the front, or in, (2k + 1) internal reflections, out the front.
                let mut series = r;
                let mut inside = t * t * r;
                for _ in 0..10_000_000 {
                    if inside < 1e-16 {
                        break;
                    }
                    series += inside;
                    inside *= r * r;
                }
                let closed = thin_dielectric_reflectance(cos, eta);
                assert!(
                    (closed as f64 - series).abs() < 1e-5,
                    "eta {eta} cos {cos}: {closed} vs {series}"
                );
                // From the other side the same.
                assert_eq!(closed, thin_dielectric_reflectance(-cos, eta));
                assert!((0.0..=1.0).contains(&closed));
                // More than one interface, less than two independent ones.
                assert!(closed as f64 >= r - 1e-7 && (closed as f64) <= 2.0 * r + 1e-7);
            }
        }
        // Grazing: everything reflects; normal incidence of glass: 2 R0 / (1 + R0).
        assert_eq!(thin_dielectric_reflectance(0.0, 1.5), 1.0);
        let r0 = 0.04f32;
        assert!((thin_dielectric_reflectance(1.0, 1.5) - 2.0 * r0 / (1.0 + r0)).abs() < 1e-6);
    }

    #[test]
    fn samples_choose_reflection_with_probability_r_and_pass_straight_through() {
        let mut rng = Rng(5);
        for (wo, eta) in [
            (Vec3::new(0.6, 0.0, 0.8), 1.5f32),
            (Vec3::new(0.0, -0.8, -0.6), 1.5),
            (Vec3::new(0.995, 0.0, 0.0998).normalize(), 1.33),
        ] {
            let r = thin_dielectric_reflectance(wo.z, eta);
            let n = 200_000;
            let mut reflected = 0usize;
            for _ in 0..n {
                let s = thin_dielectric_sample(eta, wo, rng.vec2()).unwrap();
                assert_eq!(s.weight, Rgb::WHITE);
                assert_eq!(s.eta, 1.0);
                if s.lobe.is_transmit() {
                    assert_eq!(s.wi, -wo);
                    assert_eq!(s.pdf, 1.0 - r);
                } else {
                    assert_eq!(s.wi, reflect_local(wo));
                    assert_eq!(s.pdf, r);
                    reflected += 1;
                }
            }
            let freq = reflected as f64 / n as f64;
            let sigma = (r as f64 * (1.0 - r as f64) / n as f64).sqrt();
            assert!(
                (freq - r as f64).abs() < 5.0 * sigma + 1e-6,
                "{freq} vs {r}"
            );
        }
        assert!(thin_dielectric_sample(1.5, Vec3::X, Vec2::splat(0.5)).is_none());
        assert!(thin_dielectric_sample(f32::NAN, Vec3::Z, Vec2::splat(0.5)).is_none());
    }
}
