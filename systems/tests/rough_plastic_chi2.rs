//! Chi-square test of the rough plastic's sampler (`risotto_systems::rough_plastic`) against
//! its own density, with the binning and statistics of `bxdf_chi2` (`common`): GGX and
//! Beckmann at `alpha` 0.05, 0.3 and 0.8, `wo` near the normal and grazing (`cos 0.1`), a
//! coloured base so that both lobes are drawn. Also: the test rejects a density whose
//! lobe-choice probability is not the sampler's.

mod common;
use common::*;

use risotto_components::{Rgb, Vec3};
use risotto_systems::bxdf::reflect_local;
use risotto_systems::microfacet::{Beckmann, Ggx, Microfacet};
use risotto_systems::rough_plastic::RoughPlastic;

const N_SAMPLES: usize = 300_000;
/// Chi-square tests: 2 families x 3 roughnesses x 2 directions.
const NUM_TESTS: u32 = 12;

/// Cells around the mirror direction for a narrow lobe seen near the normal; around the
/// normal otherwise, finer at grazing views (cells around a mirror direction near the
/// horizon would cut it in slivers whose quadrature misses the diffuse lobe's mass there).
fn domain(g: &Microfacet, wo: Vec3) -> Domain {
    if wo.z < 0.5 {
        let mut d = Domain::new(Vec3::Z, 1.0);
        (d.n_theta, d.n_phi) = (256, 512);
        return d;
    }
    match g.alpha_u() {
        a if a < 0.1 => Domain::new(reflect_local(wo), 3.0),
        a if a < 0.5 => Domain::new(reflect_local(wo), 2.0),
        _ => Domain::new(Vec3::Z, 1.0),
    }
}

#[test]
fn chi2_rough_plastic() {
    let base = Rgb::new(0.6, 0.3, 0.1);
    for alpha in [0.05f32, 0.3, 0.8] {
        for g in [
            Microfacet::from(Ggx::isotropic(alpha)),
            Beckmann::isotropic(alpha).into(),
        ] {
            let c = RoughPlastic::new(g, 1.5, Rgb::splat(0.8), false);
            for wo in [dir(0.3, 0.7), dir(0.1f32.acos(), 2.2)] {
                let mut lobe = Rng(31);
                let r = chi2_test(
                    &domain(&g, wo),
                    8,
                    N_SAMPLES,
                    |u| c.sample(base, wo, u, lobe.vec2().x).map(|s| s.wi),
                    &|wi| c.eval(base, wo, wi).1 as f64,
                );
                assert_accepted(
                    &format!("rough plastic {g:?} wo {wo}"),
                    &r,
                    sidak_alpha(0.01, NUM_TESTS),
                );
            }
        }
    }
}

/// The test can fail: the same samples against the density of a plastic whose base is
/// white (its specular lobe is chosen less often, so the reported mixture is wrong).
#[test]
fn chi2_rejects_a_wrong_lobe_probability() {
    let c = RoughPlastic::new(Beckmann::isotropic(0.3), 1.5, Rgb::WHITE, false);
    let wo = dir(0.5, 0.3);
    let mut lobe = Rng(5);
    let r = chi2_test(
        &domain(&c.distribution, wo),
        9,
        200_000,
        |u| {
            c.sample(Rgb::splat(0.05), wo, u, lobe.vec2().x)
                .map(|s| s.wi)
        },
        &|wi| c.eval(Rgb::WHITE, wo, wi).1 as f64,
    );
    assert!(r.p_value < 1e-12, "{r:?}");
}
