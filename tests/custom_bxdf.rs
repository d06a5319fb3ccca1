//! The `custom_bxdf` example's modified Phong lobe against what it must be: its sampling
//! against its pdf (chi-square), the pdf the sampler uses equal to the one `evaluate`
//! reports, weights equal to `f cos / pdf`, the closed-form albedo at normal incidence; and
//! its scene rendering through the registered material type.

#[allow(dead_code, reason = "the example's main is not called here")]
#[path = "../examples/custom_bxdf.rs"]
mod example;

use example::{phong_eval, phong_sample, render_text, SCENE};
use glam::{Vec2, Vec3};
use risotto::components::Rgb;
use risotto::systems::sampler::SplitMix64;
use std::f64::consts::PI;

const KS: Rgb = Rgb::new(0.9, 0.6, 0.3);

/// A unit viewer direction above the surface at polar angle `theta`.
fn wo_at(theta: f32) -> Vec3 {
    Vec3::new(theta.sin(), 0.0, theta.cos())
}

/// At normal incidence `r` is the normal, so `cos alpha = cos theta_i` and its CDF is
/// `c^(n + 1)`: ten equiprobable bins of it get 1/10 of the samples each (chi-square, 9
/// degrees of freedom; 27.9 is the 0.1 % point). Every sample is above the surface there.
#[test]
fn sampling_follows_its_pdf_at_normal_incidence() {
    let mut rng = SplitMix64(11);
    for n in [1.0f32, 8.0, 200.0] {
        const N: usize = 100_000;
        let mut bins = [0usize; 10];
        for _ in 0..N {
            let s = phong_sample(KS, n, Vec3::Z, rng.vec2()).expect("always above");
            let cdf = (s.wi.z as f64).powf(n as f64 + 1.0);
            bins[((cdf * 10.0) as usize).min(9)] += 1;
        }
        let expected = N as f64 / 10.0;
        let chi2: f64 = bins
            .iter()
            .map(|&b| (b as f64 - expected).powi(2) / expected)
            .sum();
        assert!(chi2 < 27.9, "n = {n}: chi2 {chi2:.1}, bins {bins:?}");
    }
}

/// For an oblique viewer part of the lobe lies below the surface: the integral of the
/// reported pdf over the upper hemisphere (quadrature) must equal the fraction of samples the
/// sampler keeps (Monte Carlo, within 4 standard errors). A pdf normalised over the kept part
/// only, or a sampler that drew from another density, fails it.
#[test]
fn the_reported_pdf_is_the_samplers_density() {
    let mut rng = SplitMix64(12);
    for (n, theta) in [(1.0f32, 1.2f32), (8.0, 1.3), (40.0, 1.45)] {
        let wo = wo_at(theta);
        // Midpoint quadrature over (cos theta_i, phi) of the upper hemisphere.
        let (nt, np) = (800, 800);
        let mut integral = 0.0f64;
        for i in 0..nt {
            let z = (i as f64 + 0.5) / nt as f64;
            let s = (1.0 - z * z).sqrt();
            for j in 0..np {
                let phi = 2.0 * PI * (j as f64 + 0.5) / np as f64;
                let wi = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32);
                integral += phong_eval(KS, n, wo, wi).1 as f64;
            }
        }
        integral *= 2.0 * PI / (nt * np) as f64;
        const N: usize = 200_000;
        let kept = (0..N)
            .filter(|_| phong_sample(KS, n, wo, rng.vec2()).is_some())
            .count() as f64
            / N as f64;
        let sigma = (kept * (1.0 - kept) / N as f64).sqrt();
        assert!(
            kept < 0.99,
            "n = {n}: the case should lose samples ({kept})"
        );
        assert!(
            (integral - kept).abs() < 4.0 * sigma + 2e-3,
            "n = {n}, theta = {theta}: pdf integral {integral:.4}, kept {kept:.4} (sigma {sigma:.4})"
        );
    }
}

/// Every sample's weight is `f cos / pdf` and its pdf what `evaluate` reports for its
/// direction (what MIS relies on).
#[test]
fn sample_weights_and_pdfs_agree_with_evaluate() {
    let mut rng = SplitMix64(13);
    for _ in 0..20_000 {
        let n = 1.0 + 100.0 * rng.f32();
        let wo = wo_at(1.5 * rng.f32());
        let Some(s) = phong_sample(KS, n, wo, rng.vec2()) else {
            continue;
        };
        let (value, pdf) = phong_eval(KS, n, wo, s.wi);
        let rel = |a: f32, b: f32| (a - b).abs() <= 1e-4 * a.abs().max(b.abs()) + 1e-6;
        assert!(rel(pdf, s.pdf), "pdf {pdf} vs sampled {}", s.pdf);
        for (w, v) in s.weight.to_array().into_iter().zip(value.to_array()) {
            assert!(rel(w, v / pdf), "weight {w} vs f cos / pdf {}", v / pdf);
        }
    }
}

/// The directional albedo, the mean sample weight, is `ks` at normal incidence (closed form:
/// `E[cos alpha] = (n + 1) / (n + 2)`) and below it at grazing angles: no energy is created.
#[test]
fn albedo_is_ks_at_normal_incidence_and_less_elsewhere() {
    let mut rng = SplitMix64(14);
    const N: usize = 200_000;
    for n in [1.0f32, 20.0] {
        let albedo = |wo: Vec3, rng: &mut SplitMix64| {
            let (mut sum, mut sq) = (0.0f64, 0.0f64);
            for _ in 0..N {
                let w = phong_sample(Rgb::WHITE, n, wo, rng.vec2()).map_or(0.0, |s| s.weight.r);
                sum += w as f64;
                sq += (w as f64).powi(2);
            }
            let mean = sum / N as f64;
            (mean, ((sq / N as f64 - mean * mean) / N as f64).sqrt())
        };
        let (a0, s0) = albedo(Vec3::Z, &mut rng);
        assert!(
            (a0 - 1.0).abs() < 4.0 * s0 + 1e-4,
            "n = {n}: albedo {a0} +- {s0}"
        );
        let (a1, s1) = albedo(wo_at(1.4), &mut rng);
        assert!(a1 + 4.0 * s1 < 1.0, "n = {n}: grazing albedo {a1} +- {s1}");
    }
    // The colour scales it per channel.
    let s = phong_sample(KS, 20.0, Vec3::Z, Vec2::splat(0.3)).unwrap();
    assert_eq!(s.weight / s.weight.r, KS / KS.r);
}

/// The example scene renders through the registered `glossy` type: finite, lit, and the
/// sharp copper lobe gives a highlight far brighter than the image mean.
#[test]
fn the_example_scene_renders_with_the_registered_type() {
    let scene = SCENE
        .replace("width = 160", "width = 48")
        .replace("height = 120", "height = 36")
        .replace("spp = 32", "spp = 8");
    let out = render_text(&scene, "custom_bxdf.toml").expect("renders");
    assert!(out.beauty.pixels.iter().all(|p| p.is_finite()));
    let mean = out.beauty.mean();
    assert!(mean.iter().all(|&m| m > 0.02), "{mean:?}");
    let peak = out
        .beauty
        .pixels
        .iter()
        .map(|p| p.average())
        .fold(0.0f32, f32::max);
    assert!(peak as f64 > 5.0 * mean[0], "peak {peak}, mean {mean:?}");
    // A bad parameter is named.
    let bad = scene.replace("exponent = 200", "exponent = -1");
    let err = render_text(&bad, "custom_bxdf.toml")
        .err()
        .expect("refused");
    assert!(err.to_string().contains("exponent"), "{err}");
}
