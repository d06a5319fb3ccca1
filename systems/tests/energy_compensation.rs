//! The albedo tables against a different integration: a product midpoint rule over the
//! hemisphere of directions (not visible-normal sampling), evaluating the lobes' `f`.

//! (An integration test: it evaluates the rough lobes, which build on the tables.)

use glam::Vec3;
use risotto_components::Rgb;
use risotto_systems::energy_compensation::AlbedoTable;
use risotto_systems::microfacet::Ggx;
use risotto_systems::rough_conductor::RoughConductor;
use risotto_systems::rough_dielectric::RoughDielectric;
use std::f64::consts::PI;

/// The direction at cosine `mu` in the `xz` plane.
fn direction(mu: f32) -> Vec3 {
    Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu)
}

/// `int g(wi) dwi` over the sphere (`z > 0` half only when `upper`) by the midpoint rule in
/// `(cos theta, phi)` (uniform in solid angle), `n` x `2n` cells.
fn sphere_integral(n: usize, upper: bool, g: impl Fn(Vec3) -> f64) -> f64 {
    let (z0, z1) = if upper { (0.0, 1.0) } else { (-1.0, 1.0) };
    let dz = (z1 - z0) / n as f64;
    let dphi = 2.0 * PI / (2 * n) as f64;
    let mut sum = 0.0;
    for i in 0..n {
        let z = z0 + (i as f64 + 0.5) * dz;
        let r = (1.0 - z * z).sqrt();
        for j in 0..2 * n {
            let phi = (j as f64 + 0.5) * dphi;
            let w = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
            sum += g(w);
        }
    }
    sum * dz * dphi
}

#[test]
fn conductor_table_matches_hemisphere_quadrature() {
    for alpha in [0.3f32, 0.6, 1.0] {
        let ggx = Ggx::isotropic(alpha);
        let table = AlbedoTable::conductor(&ggx.into());
        let white = RoughConductor::new(ggx, Rgb::splat(0.0), Rgb::WHITE, Rgb::WHITE, false);
        for mu in [0.1f32, 0.35, 0.7, 1.0] {
            let wo = direction(mu);
            let e = sphere_integral(400, true, |wi| white.eval(wo, wi).0.r as f64);
            let got = table.e(mu) as f64;
            assert!(
                (got - e).abs() < 0.004,
                "alpha {alpha} mu {mu}: table {got} vs quadrature {e}"
            );
        }
    }
}

#[test]
fn dielectric_table_matches_sphere_quadrature() {
    for alpha in [0.5f32, 1.0] {
        let ggx = Ggx::isotropic(alpha);
        for eta in [1.5f32, 1.0 / 1.5] {
            let table = AlbedoTable::dielectric(&ggx.into(), eta);
            let glass = RoughDielectric::new(ggx, eta, Rgb::WHITE, false);
            for mu in [0.2f32, 0.6, 1.0] {
                let wo = direction(mu);
                // Undo the radiance factor 1 / eta^2 of the transmitted half.
                let e = sphere_integral(1500, false, |wi| {
                    let f = glass.eval(wo, wi).0.r as f64;
                    if wi.z < 0.0 {
                        f * (eta * eta) as f64
                    } else {
                        f
                    }
                });
                let got = table.e(mu) as f64;
                assert!(
                    (got - e).abs() < 0.006,
                    "alpha {alpha} eta {eta} mu {mu}: table {got} vs quadrature {e}"
                );
            }
        }
    }
}

/// The energy single scattering loses, `1 - E_avg`, printed against roughness (the curve
/// Kulla & Conty 2017 plot for GGX: nothing at the smooth end, growing with roughness).
/// Measured here (height-correlated Smith, 2026-12-06; `cargo test -p risotto-systems
/// --test energy_compensation single_scattering_loss -- --nocapture` prints the row):
///
/// | alpha | 0.1 | 0.2 | 0.3 | 0.4 | 0.5 | 0.6 | 0.7 | 0.8 | 0.9 | 1.0 |
/// |---|---|---|---|---|---|---|---|---|---|---|
/// | loss | 0.031 | 0.085 | 0.153 | 0.227 | 0.300 | 0.369 | 0.434 | 0.492 | 0.544 | 0.591 |
#[test]
fn single_scattering_loss_grows_with_roughness() {
    let mut last = 0.0;
    let mut row = String::new();
    for i in 1..=10 {
        let alpha = i as f32 / 10.0;
        let t = AlbedoTable::conductor(&Ggx::isotropic(alpha).into());
        let loss = 1.0 - t.e_avg;
        row += &format!(" {loss:.3} |");
        assert!(loss > last, "loss not increasing at alpha {alpha}");
        last = loss;
    }
    println!("loss 1 - E_avg, alpha 0.1..1:{row}");
    let smooth = AlbedoTable::conductor(&Ggx::isotropic(0.01).into());
    assert!(1.0 - smooth.e_avg < 1e-3);
}
