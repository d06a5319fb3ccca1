//! Chi-square goodness-of-fit tests of the direction samplers in `risotto_systems::bxdf`
//! against their own densities, in the style of Mitsuba 3's `mitsuba.chi2` and pbrt-v3's
//! `src/tests/bsdfs.cpp`:
//!
//! 1. bin the sphere in (theta, phi) around an axis and histogram `N` samples;
//! 2. integrate the density over every cell numerically (Gauss-Legendre per cell) to get the
//!    expected counts -- this only *evaluates* the pdf, so a sampler that disagrees with it
//!    shows up as a misfit;
//! 3. pool cells whose expected count is below 5, compute Pearson's statistic and its
//!    p-value from the chi-square survival function (regularized upper incomplete gamma,
//!    in `common`), and reject at significance 0.01 after a Sidak correction for the
//!    number of tests in this file.
//!
//! The statistics live in `common` (shared with `phase_chi2` and `medium`) and are checked
//! here against closed forms and tabulated quantiles.

mod common;
use common::*;

use risotto_components::{Rgb, Vec2, Vec3};
use risotto_systems::bxdf::{
    diffuse_eval, diffuse_sample, hg_eval, hg_sample, sample_uniform_sphere, INV_4PI,
};
use std::f64::consts::PI;

/// Chi-square tests in this file that are expected to pass (uniform sphere, 4 diffuse
/// `wo`, 7 HG `g`). Used for the Sidak correction.
const NUM_TESTS: u32 = 1 + 4 + 7;
/// Family-wise significance level.
const ALPHA: f64 = 0.01;
/// Samples per test: ~1e6 keeps a release run well under a second per test.
const N_SAMPLES: usize = 1_000_000;
/// Samples for the must-reject tests: their statistics exceed the threshold by orders of
/// magnitude at 1e6, so a quarter of that still rejects with a wide margin.
const N_SAMPLES_REJECT: usize = 250_000;
/// Per-test significance with Sidak's correction over this file's tests.
fn sidak_alpha() -> f64 {
    common::sidak_alpha(ALPHA, NUM_TESTS)
}

// ---------------------------------------------------------------------------------------
// Tests of the statistics themselves
// ---------------------------------------------------------------------------------------

#[test]
fn ln_gamma_matches_factorials_and_half_integers() {
    let mut fact = 1.0f64;
    for n in 1..30 {
        // Gamma(n) = (n - 1)!
        assert!((ln_gamma(n as f64) - fact.ln()).abs() < 1e-12 * fact.ln().max(1.0));
        fact *= n as f64;
    }
    // Gamma(1/2) = sqrt(pi), Gamma(3/2) = sqrt(pi) / 2.
    assert!((ln_gamma(0.5) - PI.sqrt().ln()).abs() < 1e-13);
    assert!((ln_gamma(1.5) - (PI.sqrt() / 2.0).ln()).abs() < 1e-13);
    // Stirling for a large argument: ln Gamma(x) ~ (x - 1/2) ln x - x + ln(2 pi)/2 + 1/(12x).
    let x = 5000.0f64;
    let stirling = (x - 0.5) * x.ln() - x + 0.5 * (2.0 * PI).ln() + 1.0 / (12.0 * x);
    assert!((ln_gamma(x) - stirling).abs() < 1e-9 * stirling);
}

#[test]
fn chi2_survival_matches_closed_forms_and_tables() {
    // dof = 2 is an exponential: Q = exp(-x / 2).
    for x in [0.1, 1.0, 5.991_464_547, 20.0, 100.0] {
        assert!((chi2_survival(x, 2) - (-x / 2.0f64).exp()).abs() < 1e-12);
    }
    // dof = 1: Q = erfc(sqrt(x / 2)); tabulated upper quantiles (e.g. Abramowitz & Stegun
    // table 26.8) with their tail probabilities.
    let table: [(usize, f64, f64); 7] = [
        (1, 3.841_459, 0.05),
        (1, 6.634_897, 0.01),
        (5, 11.070_50, 0.05),
        (10, 23.209_25, 0.01),
        (30, 50.892_18, 0.01),
        (100, 135.806_7, 0.01),
        (100, 124.342_1, 0.05),
    ];
    for (dof, x, p) in table {
        let q = chi2_survival(x, dof);
        assert!((q - p).abs() < 1e-5, "dof {dof} x {x}: {q} vs {p}");
    }
    // Large dof (what the tests below see): the statistic's mean is dof, median a little
    // below (Wilson-Hilferty: median ~ k (1 - 2/(9k))^3).
    let k = 6000usize;
    let median = k as f64 * (1.0 - 2.0 / (9.0 * k as f64)).powi(3);
    assert!((chi2_survival(median, k) - 0.5).abs() < 1e-3);
    assert!(chi2_survival(k as f64 + 10.0 * (2.0 * k as f64).sqrt(), k) < 1e-15);
    assert!(chi2_survival(k as f64 - 10.0 * (2.0 * k as f64).sqrt(), k) > 1.0 - 1e-15);
}

#[test]
fn gauss_legendre_integrates_polynomials_exactly() {
    let gl = gauss_legendre(6);
    // Exact up to degree 2n - 1 = 11: int_0^1 x^k = 1 / (k + 1).
    for k in 0..12 {
        let s: f64 = gl.iter().map(|(x, w)| w * x.powi(k)).sum();
        assert!((s - 1.0 / (k as f64 + 1.0)).abs() < 1e-13, "degree {k}");
    }
}

// ---------------------------------------------------------------------------------------
// Goodness of fit
// ---------------------------------------------------------------------------------------

#[test]
fn chi2_uniform_sphere() {
    let r = chi2_test(
        &Domain::new(Vec3::new(0.48, 0.6, 0.64), 1.0),
        11,
        N_SAMPLES,
        |u| Some(sample_uniform_sphere(u)),
        &|_| INV_4PI as f64,
    );
    assert_accepted("uniform sphere", &r, sidak_alpha());
}

#[test]
fn chi2_diffuse() {
    let albedo = Rgb::new(0.9, 0.5, 0.1);
    // n_theta is even and the axis is +z, so the horizon -- where the density jumps to 0 --
    // is a cell boundary and the quadrature never straddles the discontinuity.
    let domain = Domain::new(Vec3::Z, 1.0);
    for (k, theta) in [0.0f32, 0.5, 1.2, 1.55].into_iter().enumerate() {
        let wo = dir(theta, 0.7);
        let r = chi2_test(
            &domain,
            20 + k as u64,
            N_SAMPLES,
            |u| diffuse_sample(albedo, wo, u).map(|s| s.wi),
            &|wi| diffuse_eval(albedo, wo, wi).1 as f64,
        );
        assert_accepted(&format!("diffuse wo theta {theta}"), &r, sidak_alpha());
    }
}

#[test]
fn chi2_henyey_greenstein() {
    let wo = Vec3::new(-0.36, 0.48, 0.8);
    for (k, g) in [-0.9f32, -0.5, 0.0, 0.3, 0.7, 0.95, 0.99]
        .into_iter()
        .enumerate()
    {
        let r = chi2_test(
            &hg_domain(g, wo),
            30 + k as u64,
            N_SAMPLES,
            |u| Some(hg_sample(g, wo, u).0),
            &|wi| hg_eval(g, wo, wi) as f64,
        );
        assert_accepted(&format!("HG g {g}"), &r, sidak_alpha());
    }
}

/// The test has teeth: a sampler checked against a slightly wrong density is rejected.
#[test]
fn chi2_rejects_wrong_densities() {
    let alpha = sidak_alpha();
    let wo = Vec3::new(0.0, 0.6, -0.8);
    // g + 0.05 as in the brief, plus narrower perturbations of the peaked lobes.
    for (g, wrong) in [
        (0.3f32, 0.35f32),
        (0.7, 0.75),
        (-0.5, -0.45),
        (0.95, 0.96),
        (0.99, 0.992),
    ] {
        let r = chi2_test(
            &hg_domain(g, wo),
            40,
            N_SAMPLES_REJECT,
            |u| Some(hg_sample(g, wo, u).0),
            &|wi| hg_eval(wrong, wo, wi) as f64,
        );
        println!("HG g {g} vs pdf g {wrong}: {r:?}");
        assert!(
            r.p_value < alpha,
            "HG g {g} vs pdf g {wrong} not rejected: {r:?}"
        );
    }
    // Cosine-weighted samples against a uniform-hemisphere density.
    let r = chi2_test(
        &Domain::new(Vec3::Z, 1.0),
        41,
        N_SAMPLES_REJECT,
        |u| diffuse_sample(Rgb::WHITE, Vec3::Z, u).map(|s| s.wi),
        &|wi| if wi.z > 0.0 { 0.5 / PI } else { 0.0 },
    );
    assert!(r.p_value < alpha, "cosine vs uniform not rejected: {r:?}");
    // A subtle azimuthal bug: phi squeezed by 2% (u.y -> 0.98 u.y) in a uniform sphere.
    let r = chi2_test(
        &Domain::new(Vec3::Z, 1.0),
        42,
        N_SAMPLES_REJECT,
        |u| Some(sample_uniform_sphere(Vec2::new(u.x, 0.98 * u.y))),
        &|_| INV_4PI as f64,
    );
    println!("squeezed phi: {r:?}");
    assert!(r.p_value < alpha, "squeezed phi not rejected: {r:?}");
    // Samples landing where the density is zero fail outright.
    let r = chi2_test(
        &Domain::new(Vec3::Z, 1.0),
        43,
        N_SAMPLES_REJECT,
        |u| Some(sample_uniform_sphere(u)),
        &|wi| if wi.z > 0.0 { 0.5 / PI } else { 0.0 },
    );
    assert_eq!(r.p_value, 0.0);
}

// ---------------------------------------------------------------------------------------
// Normalization
// ---------------------------------------------------------------------------------------

#[test]
fn densities_integrate_to_one() {
    let total = |d: &Domain, pdf: &dyn Fn(Vec3) -> f64| d.integrate(pdf).iter().sum::<f64>();
    let wo = Vec3::new(0.36, -0.48, 0.8);
    for g in [-0.99f32, -0.9, -0.5, 0.0, 0.3, 0.7, 0.95, 0.99] {
        let s = total(&hg_domain(g, wo), &|wi| hg_eval(g, wo, wi) as f64);
        assert!((s - 1.0).abs() < 1e-4, "HG g {g}: {s}");
    }
    let up = Domain::new(Vec3::Z, 1.0);
    for theta in [0.0f32, 0.5, 1.2, 1.55] {
        let wo = dir(theta, 0.3);
        let s = total(&up, &|wi| diffuse_eval(Rgb::WHITE, wo, wi).1 as f64);
        assert!((s - 1.0).abs() < 1e-4, "diffuse theta {theta}: {s}");
        // f |cos| integrates to the albedo, per channel.
        let albedo = Rgb::new(0.9, 0.5, 0.1);
        for (c, a) in albedo.to_array().into_iter().enumerate() {
            let s = total(&up, &|wi| {
                diffuse_eval(albedo, wo, wi).0.to_array()[c] as f64
            });
            assert!((s - a as f64).abs() < 1e-4, "albedo channel {c}: {s}");
        }
    }
    // Below the surface the one-sided lobe is zero everywhere.
    let below = dir(2.0, 0.3);
    assert_eq!(
        total(&up, &|wi| diffuse_eval(Rgb::WHITE, below, wi).1 as f64),
        0.0
    );
    // The quadrature itself: exact up to the f32 rounding of INV_4PI.
    let s = total(&up, &|_| INV_4PI as f64);
    assert!((s - 1.0).abs() < 1e-6, "{s}");
}
