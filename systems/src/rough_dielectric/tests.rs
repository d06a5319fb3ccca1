//! Reciprocity, furnace and robustness of the rough dielectric.

use super::*;
use crate::bxdf::sample_uniform_sphere;
use crate::microfacet::{Beckmann, Ggx};
use crate::sampler::SplitMix64 as Rng;

/// Reflection is reciprocal; transmission with the radiance factor obeys
/// `f(wo, wi) / n_o^2 = f(wi, wo) / n_i^2` (Veach's thesis sec. 5.2: the radiance BTDF is
/// `n_o^2` times a symmetric kernel), `n_o`, `n_i` the indices on `wo`'s and `wi`'s sides.
#[test]
fn rough_dielectric_reciprocity() {
    let mut rng = Rng(5);
    let eta = 1.5f32;
    for ggx in [Ggx::isotropic(0.2), Ggx::new(0.5, 0.1), Ggx::isotropic(1.0)] {
        let d = RoughDielectric::new(ggx, eta, Rgb::WHITE, false);
        let (mut checked_r, mut checked_t) = (0, 0);
        for _ in 0..20_000 {
            let wo = sample_uniform_sphere(rng.vec2());
            let wi = sample_uniform_sphere(rng.vec2());
            let a = d.eval(wo, wi).0.r / wi.z.abs();
            let b = d.eval(wi, wo).0.r / wo.z.abs();
            let n = |w: Vec3| if w.z > 0.0 { 1.0 } else { eta };
            let (a, b) = (a / (n(wo) * n(wo)), b / (n(wi) * n(wi)));
            assert!(
                (a - b).abs() <= 2e-4 * a.abs().max(1.0),
                "{wo} {wi}: {a} vs {b}"
            );
            if a > 0.0 {
                if wo.z * wi.z > 0.0 {
                    checked_r += 1;
                } else {
                    checked_t += 1;
                }
            }
        }
        assert!(
            checked_r > 1000 && checked_t > 1000,
            "{checked_r} {checked_t}"
        );
    }
}

/// The mean weight with the radiance factor undone is the energy the interface keeps: 1
/// within 1% with compensation (alpha 0.1 to 1, GGX and Beckmann, both sides); less
/// without.
#[test]
fn furnace_with_compensation_keeps_energy() {
    let n = 200_000;
    let both = |a: f32| {
        [
            Microfacet::from(Ggx::isotropic(a)),
            Beckmann::isotropic(a).into(),
        ]
    };
    for ggx in [0.1f32, 0.3, 0.6, 1.0].into_iter().flat_map(both) {
        let alpha = ggx.alpha_u();
        let on = RoughDielectric::new(ggx, 1.5, Rgb::WHITE, true);
        let off = RoughDielectric::new(ggx, 1.5, Rgb::WHITE, false);
        for &mu in &[0.15f32, 0.5, 0.95, -0.3, -0.8] {
            let wo = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            let mut rng = Rng(13);
            let (mut e_on, mut e_off) = (0.0f64, 0.0f64);
            for _ in 0..n {
                let (u, ul) = (rng.vec2(), rng.vec2().x);
                for (d, e) in [(&on, &mut e_on), (&off, &mut e_off)] {
                    if let Some(s) = d.sample(wo, u, ul) {
                        assert!(s.weight.is_finite(), "{s:?}");
                        *e += (s.weight.r * s.eta * s.eta) as f64;
                    }
                }
            }
            let (e_on, e_off) = (e_on / n as f64, e_off / n as f64);
            assert!((e_on - 1.0).abs() < 0.01, "alpha {alpha} mu {mu}: {e_on}");
            assert!(e_off <= e_on + 1e-6);
        }
    }
}

#[test]
fn tiny_alpha_stays_finite_and_refracts_like_the_smooth_interface() {
    let d = RoughDielectric::new(Ggx::isotropic(1e-4), 1.5, Rgb::WHITE, true);
    let mut rng = Rng(9);
    for _ in 0..20_000 {
        let wo = sample_uniform_sphere(rng.vec2());
        if let Some(s) = d.sample(wo, rng.vec2(), rng.vec2().x) {
            assert!(
                s.weight.is_finite() && s.pdf.is_finite() && s.pdf > 0.0,
                "{s:?}"
            );
            let want = if s.lobe.is_transmit() {
                crate::bxdf::refract_local(wo, 1.5).unwrap().0
            } else {
                crate::bxdf::reflect_local(wo)
            };
            assert!(s.wi.dot(want) > 0.999, "{wo} -> {} vs {want}", s.wi);
        }
        let (v, p) = d.eval(wo, sample_uniform_sphere(rng.vec2()));
        assert!(v.is_finite() && p.is_finite());
    }
    // Index matched: a straight pass.
    let matched = RoughDielectric::new(Ggx::isotropic(0.5), 1.0, Rgb::WHITE, true);
    let s = matched
        .sample(Vec3::new(0.0, 0.6, 0.8), Vec2::splat(0.3), 0.3)
        .unwrap();
    assert_eq!(s.wi, Vec3::new(0.0, -0.6, -0.8));
}
