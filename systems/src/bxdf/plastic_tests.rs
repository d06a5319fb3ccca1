//! Tests of `plastic.rs`: the diffuse Fresnel reflectance, sampling against the reported
//! pdf (chi-square), the lobe probability, reciprocity and white furnaces.

use super::*;
use crate::sampler::SplitMix64 as Rng;

fn dir(theta: f32, phi: f32) -> Vec3 {
    Vec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

/// Mitsuba 3's polynomial fits of `Fdr` (fresnel.h: Egan and Hilgeman 1973 below 1, d'Eon
/// and Irving 2011 above), quoted to an accuracy of 0.1-0.6%: an independent check of the
/// numeric integral.
fn fdr_fit(eta: f64) -> f64 {
    let inv = 1.0 / eta;
    if eta < 1.0 {
        0.0636 * inv + eta * (eta * -1.4399 + 0.7099) + 0.6681
    } else {
        let c = [0.919317, -3.4793, 6.75335, -7.80989, 4.98554, -1.36881];
        c.iter().rev().fold(0.0, |acc, &k| acc * inv + k)
    }
}

#[test]
fn diffuse_fresnel_reflectance_matches_the_fits_and_the_radiance_theorem() {
    for eta in [1.2f32, 1.33, 1.49, 1.5, 1.8] {
        let (ext, int) = (
            fresnel_diffuse_reflectance(eta),
            fresnel_diffuse_reflectance(1.0 / eta),
        );
        let (fit_ext, fit_int) = (fdr_fit(eta as f64), fdr_fit(1.0 / eta as f64));
        assert!(
            ((ext as f64 - fit_ext) / fit_ext).abs() < 0.005,
            "eta {eta}: {ext} vs fit {fit_ext}"
        );
        assert!(
            ((int as f64 - fit_int) / fit_int).abs() < 0.005,
            "eta {eta}: {int} vs fit {fit_int}"
        );
        // What leaves a diffuse field outward equals what enters it, scaled by eta^2 (the
        // radiance theorem): 1 - Fdr_ext = eta^2 (1 - Fdr_int), exactly in theory.
        let lhs = 1.0 - ext;
        let rhs = eta * eta * (1.0 - int);
        assert!((lhs - rhs).abs() < 2e-5, "eta {eta}: {lhs} vs {rhs}");
    }
    // No interface, no reflection.
    assert!(fresnel_diffuse_reflectance(1.0).abs() < 1e-7);
}

/// Upper 0.1% point of the chi-square distribution with `df` degrees of freedom
/// (Wilson-Hilferty, good to a few percent for df >= 3).
fn chi2_critical(df: usize) -> f64 {
    let k = df as f64;
    let z = 3.09;
    let a = 2.0 / (9.0 * k);
    k * (1.0 - a + z * a.sqrt()).powi(3)
}

/// Draws `n` samples at `wo` and compares their histogram over (cos^2 theta, phi) bins and a
/// "specular" bin with the probabilities the pdf reported by [`plastic_eval`] gives (its
/// integral over each bin by a sub-grid) and the specular probability the samples report.
fn chi_square_diffuse_lobe(coat: &PlasticCoat, d: Rgb, wo: Vec3, seed: u64) {
    const NT: usize = 10;
    const NP: usize = 20;
    const SUB: usize = 8;
    let n = 200_000usize;
    let mut rng = Rng(seed);
    let mut counts = vec![0u64; NT * NP + 1];
    let mut p_spec = None;
    for _ in 0..n {
        let Some(s) = plastic_sample(coat, d, wo, rng.vec2()) else {
            continue;
        };
        if s.lobe.is_specular() {
            assert_eq!(s.wi, reflect_local(wo));
            p_spec = Some(s.pdf);
            counts[NT * NP] += 1;
            continue;
        }
        let x = (s.wi.z * s.wi.z).clamp(0.0, 0.999_999);
        let phi = s.wi.y.atan2(s.wi.x).rem_euclid(std::f32::consts::TAU);
        let (i, j) = (
            (x * NT as f32) as usize,
            ((phi / std::f32::consts::TAU * NP as f32) as usize).min(NP - 1),
        );
        counts[i * NP + j] += 1;
    }
    // Expected: the reported pdf integrated over each bin. With x = cos^2 theta,
    // d omega = dx dphi / (2 cos theta).
    let mut expected = vec![0.0f64; NT * NP + 1];
    let mut total = 0.0;
    for i in 0..NT {
        for j in 0..NP {
            let mut p = 0.0f64;
            for a in 0..SUB {
                for b in 0..SUB {
                    let x = (i as f64 + (a as f64 + 0.5) / SUB as f64) / NT as f64;
                    let phi = (j as f64 + (b as f64 + 0.5) / SUB as f64) / NP as f64
                        * std::f64::consts::TAU;
                    let cos = x.sqrt();
                    let wi = dir(cos.acos() as f32, phi as f32);
                    let (_, pdf) = plastic_eval(coat, d, wo.z, wi.z);
                    p += pdf as f64 / (2.0 * cos);
                }
            }
            let area = (1.0 / NT as f64) * (std::f64::consts::TAU / NP as f64);
            expected[i * NP + j] = p * area / (SUB * SUB) as f64;
            total += expected[i * NP + j];
        }
    }
    let p_s = p_spec.map_or(0.0, |p| p as f64);
    expected[NT * NP] = p_s;
    // The diffuse lobe's pdf integrates to its own probability: all but the specular one.
    assert!(
        (total + p_s - 1.0).abs() < 2e-3,
        "wo {wo:?}: pdf integrates to {total}, specular {p_s}"
    );
    let (mut chi2, mut df) = (0.0, 0usize);
    for (&c, &e) in counts.iter().zip(&expected) {
        let e = e * n as f64;
        if e < 5.0 {
            assert!(c < 20, "wo {wo:?}: {c} samples where {e} expected");
            continue;
        }
        chi2 += (c as f64 - e).powi(2) / e;
        df += 1;
    }
    if df < 4 {
        // At grazing angles over a dark base nearly every sample is specular: the counts
        // of the diffuse bins were checked above, there is nothing left to test.
        return;
    }
    let limit = chi2_critical(df - 1);
    assert!(
        chi2 < limit,
        "wo {wo:?}: chi2 {chi2} over {limit} (df {})",
        df - 1
    );
}

#[test]
fn diffuse_lobe_sampling_matches_its_pdf_chi_square() {
    let coats = [
        PlasticCoat::new(1.49, Rgb::WHITE, false),
        PlasticCoat::new(1.8, Rgb::splat(0.5), true),
    ];
    let bases = [Rgb::new(0.8, 0.3, 0.1), Rgb::splat(0.05)];
    let mut seed = 1;
    for coat in &coats {
        for &d in &bases {
            // Normal, oblique, grazing (85 and 89.5 degrees).
            for theta in [0.0f32, 0.7, 1.2, 85f32.to_radians(), 89.5f32.to_radians()] {
                seed += 1;
                chi_square_diffuse_lobe(coat, d, dir(theta, 0.3), seed);
            }
        }
    }
}

#[test]
fn the_specular_probability_is_what_samples_report_and_eval_leaves() {
    // Frequency of specular samples vs their reported pdf, and 1 - (eval's pdf integral).
    let coat = PlasticCoat::new(1.49, Rgb::WHITE, false);
    let d = Rgb::new(0.2, 0.5, 0.9);
    let mut rng = Rng(11);
    for theta in [0.1f32, 1.0, 1.45] {
        let wo = dir(theta, 1.0);
        let n = 100_000;
        let (mut spec, mut reported) = (0usize, 0.0f32);
        for _ in 0..n {
            let s = plastic_sample(&coat, d, wo, rng.vec2()).unwrap();
            if s.lobe.is_specular() {
                spec += 1;
                reported = s.pdf;
                // The Dirac lobe's weight is s F / P_s.
                let f = fresnel_dielectric(wo.z, coat.eta);
                assert!((s.weight.r - f / s.pdf).abs() < 1e-5);
            } else {
                // The sample's weight is eval's value over eval's pdf at that direction.
                let (v, p) = plastic_eval(&coat, d, wo.z, s.wi.z);
                assert!((p - s.pdf).abs() <= 1e-6 * p);
                let w = v * (1.0 / p);
                assert!(
                    (w.b - s.weight.b).abs() <= 1e-5 * w.b,
                    "{w:?} {:?}",
                    s.weight
                );
            }
        }
        let freq = spec as f64 / n as f64;
        let sigma = (reported as f64 * (1.0 - reported as f64) / n as f64).sqrt();
        assert!(
            (freq - reported as f64).abs() < 5.0 * sigma,
            "{freq} vs {reported}"
        );
    }
}

#[test]
fn the_diffuse_lobe_is_reciprocal() {
    let mut rng = Rng(3);
    for nonlinear in [false, true] {
        let coat = PlasticCoat::new(1.6, Rgb::splat(0.7), nonlinear);
        let d = Rgb::new(0.9, 0.4, 0.2);
        for _ in 0..1000 {
            let (a, b) = (rng.f32().max(1e-3), rng.f32().max(1e-3));
            // f = value / cos_i must be symmetric.
            let fab = plastic_eval(&coat, d, a, b).0 * (1.0 / b);
            let fba = plastic_eval(&coat, d, b, a).0 * (1.0 / a);
            for (x, y) in fab.to_array().into_iter().zip(fba.to_array()) {
                assert!((x - y).abs() <= 1e-5 * x.max(y), "{a} {b}: {fab:?} {fba:?}");
            }
        }
    }
}

/// The directional albedo by numeric integration of eval over the hemisphere (midpoint in
/// `x = cos^2`, so `cos d omega = dx dphi / 2`, and the lobe has no phi dependence) plus the
/// specular lobe's `s F(cos_o)`.
fn albedo_by_integration(coat: &PlasticCoat, d: Rgb, cos_o: f32) -> Rgb {
    let n = 20_000;
    let mut sum = [0.0f64; 3];
    for k in 0..n {
        let x = (k as f64 + 0.5) / n as f64;
        let cos = x.sqrt() as f32;
        // value = f cos, so f cos d omega = value / cos * (dx dphi / 2) -> pi dx value / cos.
        let v = plastic_eval(coat, d, cos_o, cos).0;
        for (s, c) in sum.iter_mut().zip(v.to_array()) {
            *s += c as f64 / cos as f64 * std::f64::consts::PI / n as f64;
        }
    }
    let f_o = fresnel_dielectric(cos_o, coat.eta);
    Rgb::new(sum[0] as f32, sum[1] as f32, sum[2] as f32) + coat.specular * f_o
}

#[test]
fn white_furnace_energy_and_albedo() {
    let mut rng = Rng(9);
    for nonlinear in [false, true] {
        let coat = PlasticCoat::new(1.49, Rgb::WHITE, nonlinear);
        for cos_o in [1.0f32, 0.5, 0.1, 0.02] {
            let wo = Vec3::new((1.0 - cos_o * cos_o).sqrt(), 0.0, cos_o);
            // A white base under a clear coat loses nothing (module docs).
            let a = albedo_by_integration(&coat, Rgb::WHITE, cos_o);
            assert!(
                (a.r - 1.0).abs() < 2e-3,
                "nonlinear {nonlinear} cos {cos_o}: {a:?}"
            );
            // The sampling weights average the albedo (Monte Carlo, 1%).
            let n = 200_000;
            let mut mean = 0.0f64;
            for _ in 0..n {
                if let Some(s) = plastic_sample(&coat, Rgb::WHITE, wo, rng.vec2()) {
                    mean += s.weight.g as f64;
                }
            }
            mean /= n as f64;
            assert!(
                (mean - 1.0).abs() < 0.01,
                "nonlinear {nonlinear} cos {cos_o}: {mean}"
            );
            // Grey bases: energy <= 1, and with nonlinear = false exactly F + (1 - F) d.
            for level in [0.0f32, 0.3, 0.9] {
                let d = Rgb::splat(level);
                let a = albedo_by_integration(&coat, d, cos_o);
                assert!(a.max_channel() <= 1.0 + 2e-3, "{a:?}");
                let closed = plastic_albedo(&coat, d, cos_o);
                assert!((a.r - closed.r).abs() < 2e-3, "{a:?} vs {closed:?}");
                if !nonlinear {
                    let f = fresnel_dielectric(cos_o, coat.eta);
                    let want = f + (1.0 - f) * level;
                    assert!((a.r - want).abs() < 2e-3, "{} vs {want}", a.r);
                } else if level > 0.0 && level < 1.0 {
                    // The internal bounces darken a grey base below nonlinear = false's.
                    let f = fresnel_dielectric(cos_o, coat.eta);
                    assert!(a.r < f + (1.0 - f) * level - 1e-3);
                }
            }
        }
    }
}

#[test]
fn no_sample_from_behind_or_nan_at_the_edges() {
    let coat = PlasticCoat::new(1.49, Rgb::WHITE, true);
    let d = Rgb::splat(0.5);
    assert!(plastic_sample(&coat, d, -Vec3::Z, Vec2::splat(0.5)).is_none());
    assert!(plastic_sample(&coat, d, Vec3::X, Vec2::splat(0.5)).is_none());
    assert_eq!(plastic_eval(&coat, d, -0.5, 0.5), (Rgb::BLACK, 0.0));
    assert_eq!(plastic_eval(&coat, d, 0.5, -0.5), (Rgb::BLACK, 0.0));
    let grazing = Vec3::new(1.0, 0.0, 1e-6).normalize();
    for u in [0.0f32, 0.5, ONE_MINUS_EPSILON, 1.0] {
        for v in [0.0f32, 0.5, ONE_MINUS_EPSILON] {
            for wo in [grazing, Vec3::Z] {
                for d in [Rgb::BLACK, Rgb::WHITE] {
                    if let Some(s) = plastic_sample(&coat, d, wo, Vec2::new(u, v)) {
                        assert!(s.weight.is_finite() && s.pdf.is_finite() && s.pdf > 0.0);
                        assert!(s.wi.is_finite());
                    }
                }
            }
        }
    }
    // A black coat over a black base: no NaN from the lobe choice.
    let black = PlasticCoat::new(1.49, Rgb::BLACK, false);
    let s = plastic_sample(&black, Rgb::BLACK, Vec3::Z, Vec2::splat(0.7)).unwrap();
    assert!(s.weight.is_finite() && s.weight.is_black());
}
