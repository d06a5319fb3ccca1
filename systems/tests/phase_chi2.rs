//! Goodness of fit, normalisation and robustness of the phase functions in
//! `risotto_systems::phase`, with the chi-square machinery of `common` (the same as
//! `bxdf_chi2`): samples are histogrammed on a binning of the sphere around the lobe's peak and
//! compared with the pdf integrated over each cell, so a sampler that disagrees with its own
//! `eval` is rejected.
//!
//! Strongly peaked lobes (`|g| = 0.99`: angular width ~0.01 rad) get polar cells that shrink
//! quadratically towards the peak (`theta = pi x^2`, first cell ~8e-4 rad), and a double HG
//! with a forward and a backward peak gets fine cells at both poles.

mod common;
use common::*;

use risotto_components::{Vec2, Vec3};
use risotto_systems::bxdf::INV_4PI;
use risotto_systems::phase::{
    double_hg_eval, double_hg_sample, hg_eval, hg_sample, isotropic_eval, isotropic_sample,
    PhaseFunction,
};

/// The HG list.
const HG_G: [f32; 6] = [-0.99, -0.5, 0.0, 0.3, 0.9, 0.99];
/// Two double-HG settings: the scene-format example, and a sharp forward lobe with a strong,
/// sharp backward one (both poles peaked).
const DOUBLE_HG: [(f32, f32, f32); 2] = [(0.8, -0.3, 0.7), (0.99, -0.9, 0.25)];
/// Chi-square tests in this file that are expected to pass: isotropic, HG, double HG.
const NUM_TESTS: u32 = 1 + HG_G.len() as u32 + DOUBLE_HG.len() as u32;
/// Family-wise significance level.
const ALPHA: f64 = 0.01;
/// Samples per accepted test.
const N_SAMPLES: usize = 1_000_000;
/// Samples per must-reject test (they miss by orders of magnitude).
const N_SAMPLES_REJECT: usize = 250_000;

/// A `wo` off every axis, so no binning accidentally lines up with the local frame.
fn wo() -> Vec3 {
    Vec3::new(-0.36, 0.48, 0.8)
}

fn sidak() -> f64 {
    sidak_alpha(ALPHA, NUM_TESTS)
}

fn double_hg(g1: f32, g2: f32, blend: f32) -> PhaseFunction {
    PhaseFunction::double_henyey_greenstein(g1, g2, blend).expect("valid parameters")
}

/// Binning for any phase function: HG around its peak; double HG around the g1 lobe's peak
/// with fine cells at both poles (the g2 lobe peaks at the other one when the signs differ).
fn phase_domain(phase: &PhaseFunction, wo: Vec3) -> Domain {
    match *phase {
        PhaseFunction::Isotropic => Domain::new(Vec3::new(0.48, 0.6, 0.64), 1.0),
        PhaseFunction::HenyeyGreenstein { g } => hg_domain(g, wo),
        PhaseFunction::DoubleHenyeyGreenstein { g1, .. } => {
            Domain::with_warp(if g1 >= 0.0 { -wo } else { wo }, ThetaWarp::BothPoles(2.0))
        }
    }
}

/// Every phase function the tests cover.
fn all_phases() -> Vec<PhaseFunction> {
    let mut v = vec![PhaseFunction::Isotropic];
    v.extend(HG_G.map(|g| PhaseFunction::henyey_greenstein(g).expect("valid g")));
    v.extend(DOUBLE_HG.map(|(g1, g2, b)| double_hg(g1, g2, b)));
    v
}

/// Draws `u` and `u_lobe` from one generator stream: `chi2_test` hands out a `Vec2` per sample,
/// and the lobe choice takes a third number from a second generator seeded alongside.
fn chi2_phase(phase: &PhaseFunction, sampled: PhaseFunction, seed: u64, n: usize) -> common::Chi2 {
    let wo = wo();
    let mut lobe_rng = Rng(seed ^ 0x5EED);
    chi2_test(
        &phase_domain(phase, wo),
        seed,
        n,
        |u| Some(sampled.sample(wo, u, lobe_rng.f32()).0),
        &|wi| phase.eval(wo, wi) as f64,
    )
}

#[test]
fn chi2_phase_functions() {
    for (k, phase) in all_phases().into_iter().enumerate() {
        let r = chi2_phase(&phase, phase, 100 + k as u64, N_SAMPLES);
        assert_accepted(&format!("{phase:?}"), &r, sidak());
    }
}

/// The test has teeth: samplers with the sign of g flipped, a swapped blend, or a lobe choice
/// that ignores blend are rejected against the correct pdf.
#[test]
fn chi2_rejects_broken_samplers() {
    let alpha = sidak();
    let mut cases: Vec<(PhaseFunction, PhaseFunction)> = [-0.99f32, -0.5, 0.3, 0.9, 0.99]
        .into_iter()
        .map(|g| {
            (
                PhaseFunction::HenyeyGreenstein { g },
                PhaseFunction::HenyeyGreenstein { g: -g },
            )
        })
        .collect();
    // Near misses of the peaked lobes: g off by 0.002.
    cases.push((
        PhaseFunction::HenyeyGreenstein { g: 0.99 },
        PhaseFunction::HenyeyGreenstein { g: 0.992 },
    ));
    cases.push((
        PhaseFunction::HenyeyGreenstein { g: -0.99 },
        PhaseFunction::HenyeyGreenstein { g: -0.988 },
    ));
    for (g1, g2, blend) in DOUBLE_HG {
        // blend read as the weight of the g2 lobe instead of g1.
        cases.push((double_hg(g1, g2, blend), double_hg(g1, g2, 1.0 - blend)));
        // Signs of both lobes flipped.
        cases.push((double_hg(g1, g2, blend), double_hg(-g1, -g2, blend)));
        // Always the g1 lobe.
        cases.push((double_hg(g1, g2, blend), double_hg(g1, g2, 1.0)));
    }
    // Isotropic samples against a mild HG lobe.
    cases.push((
        PhaseFunction::HenyeyGreenstein { g: 0.1 },
        PhaseFunction::Isotropic,
    ));
    for (k, (phase, broken)) in cases.into_iter().enumerate() {
        let r = chi2_phase(&phase, broken, 200 + k as u64, N_SAMPLES_REJECT);
        println!("{broken:?} against {phase:?}: {r:?}");
        assert!(
            r.p_value < alpha,
            "{broken:?} sampled against {phase:?} was not rejected: {r:?}"
        );
    }
}

#[test]
fn pdfs_integrate_to_one() {
    let wo = wo();
    let mut phases = all_phases();
    // Beyond the chi-square list: the sharpest lobes the validating constructor accepts in
    // practice, and a blend at each end.
    phases.push(PhaseFunction::HenyeyGreenstein { g: 0.999 });
    phases.push(PhaseFunction::HenyeyGreenstein { g: -0.999 });
    phases.push(double_hg(0.5, -0.5, 0.0));
    phases.push(double_hg(0.5, -0.5, 1.0));
    for phase in phases {
        let mut domain = phase_domain(&phase, wo);
        // |g| = 0.999 is 1e-3 rad wide: cube the polar spacing (first cell ~4e-6 rad).
        if let PhaseFunction::HenyeyGreenstein { g } = phase {
            if g.abs() > 0.995 {
                domain.warp = ThetaWarp::Power(3.0);
            }
        }
        let total = domain.total(&|wi| phase.eval(wo, wi) as f64);
        assert!((total - 1.0).abs() < 1e-3, "{phase:?}: {total}");
    }
    // The per-lobe functions agree with the enum and the isotropic constant is 1 / (4 pi).
    assert_eq!(isotropic_eval(), INV_4PI);
    let wi = Vec3::new(0.6, 0.0, -0.8);
    assert_eq!(
        double_hg(0.8, -0.3, 0.7).eval(wo, wi),
        double_hg_eval(0.8, -0.3, 0.7, wo, wi)
    );
    assert_eq!(
        PhaseFunction::HenyeyGreenstein { g: 0.3 }.eval(wo, wi),
        hg_eval(0.3, wo, wi)
    );
}

#[test]
fn sampled_pdf_equals_eval_and_weight_is_one() {
    let mut rng = Rng(300);
    for phase in all_phases() {
        for _ in 0..5000 {
            let wo = isotropic_sample(rng.vec2()).0;
            let (wi, pdf) = phase.sample(wo, rng.vec2(), rng.f32());
            let p = phase.eval(wo, wi);
            // p / pdf is the sample's weight; exact sampling makes it 1.
            assert!(
                (p / pdf - 1.0).abs() < 2e-3,
                "{phase:?} wo {wo} wi {wi}: eval {p} vs sampled pdf {pdf}"
            );
        }
    }
    // The free functions match the enum sample for sample.
    let (wo, u) = (wo(), Vec2::new(0.3, 0.7));
    assert_eq!(
        double_hg(0.8, -0.3, 0.7).sample(wo, u, 0.2),
        double_hg_sample(0.8, -0.3, 0.7, wo, u, 0.2)
    );
    assert_eq!(
        PhaseFunction::HenyeyGreenstein { g: -0.5 }.sample(wo, u, 0.9),
        hg_sample(-0.5, wo, u)
    );
}

#[test]
fn sampling_is_finite_and_unit_over_a_dense_u_grid() {
    let one_minus_ulp = 1.0 - f32::EPSILON / 2.0;
    // 0, 1 - ulp, a regular grid, and values a few ulps from both ends.
    let mut us: Vec<f32> = (0..=128).map(|i| i as f32 / 128.0).collect();
    us.pop();
    us.extend([1e-7, 1e-30, one_minus_ulp, 1.0 - f32::EPSILON, 0.5 - 3e-8]);
    let mut phases = vec![PhaseFunction::Isotropic];
    for g in [
        -0.999f32, -0.99, -0.5, -1e-7, 0.0, 1e-7, 0.3, 0.9, 0.99, 0.999, 0.99999,
    ] {
        phases.push(PhaseFunction::HenyeyGreenstein { g });
    }
    phases.push(double_hg(0.999, -0.999, 0.5));
    phases.push(double_hg(0.8, -0.3, 0.7));
    let wos = [Vec3::Z, -Vec3::Z, Vec3::X, Vec3::new(0.0, -1.0, -0.0), wo()];
    let lobes = [0.0f32, 0.5 - 3e-8, 0.5, 0.7, one_minus_ulp];
    for phase in &phases {
        for &wo in &wos {
            for &a in &us {
                for &b in &us {
                    for &ul in &lobes {
                        let (wi, pdf) = phase.sample(wo, Vec2::new(a, b), ul);
                        let ok = wi.is_finite()
                            && (wi.length() - 1.0).abs() < 1e-5
                            && pdf.is_finite()
                            && pdf > 0.0;
                        assert!(ok, "{phase:?} wo {wo} u ({a}, {b}, {ul}): {wi} {pdf}");
                        let p = phase.eval(wo, wi);
                        assert!(p.is_finite() && p > 0.0, "{phase:?}: eval {p}");
                    }
                }
            }
        }
    }
}
