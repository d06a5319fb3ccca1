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
//!    implemented below), and reject at significance 0.01 after a Sidak correction for the
//!    number of tests in this file.
//!
//! The survival function is written here rather than pulled from `statrs`: it is ~60 lines,
//! is checked below against closed forms and tabulated quantiles, and keeps a statistics
//! crate out of the workspace for the sake of one test.

use risotto_components::{Rgb, Vec2, Vec3};
use risotto_systems::bxdf::{
    diffuse_eval, diffuse_sample, hg_eval, hg_sample, sample_uniform_sphere, Frame, INV_4PI,
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
/// Minimum expected count of a cell before pooling (the usual rule of thumb).
const MIN_EXPECTED: f64 = 5.0;

/// Per-test significance with Sidak's correction: `1 - (1 - alpha)^(1/m)`.
fn sidak_alpha() -> f64 {
    1.0 - (1.0 - ALPHA).powf(1.0 / NUM_TESTS as f64)
}

// ---------------------------------------------------------------------------------------
// Random numbers
// ---------------------------------------------------------------------------------------

use risotto_systems::sampler::SplitMix64 as Rng;
// ---------------------------------------------------------------------------------------
// Chi-square survival function
// ---------------------------------------------------------------------------------------

/// `ln Gamma(x)` for `x > 0`: Lanczos approximation with `g = 7`, 9 coefficients (accurate
/// to ~1e-15 relative), as given e.g. in Press et al., Numerical Recipes 3rd ed. sec. 6.1.
fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection formula: Gamma(x) Gamma(1 - x) = pi / sin(pi x).
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularized upper incomplete gamma `Q(a, x) = Gamma(a, x) / Gamma(a)`.
///
/// Series for `P = 1 - Q` when `x < a + 1`, where it converges fast; otherwise the
/// continued fraction for `Q` evaluated with the modified Lentz method (Numerical Recipes
/// sec. 6.2). Both share the prefactor `x^a e^-x / Gamma(a)`, computed in logs.
fn gamma_q(a: f64, x: f64) -> f64 {
    assert!(a > 0.0 && x >= 0.0);
    if x == 0.0 {
        return 1.0;
    }
    let ln_prefactor = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        // P(a, x) = x^a e^-x / Gamma(a + 1) * sum_n x^n / ((a + 1) ... (a + n)).
        let mut term = 1.0 / a;
        let mut sum = term;
        let mut n = 1.0;
        while term > sum * 1e-16 {
            term *= x / (a + n);
            sum += term;
            n += 1.0;
            assert!(n < 1e7, "series did not converge");
        }
        (1.0 - sum * ln_prefactor.exp()).max(0.0)
    } else {
        // Q(a, x) = x^a e^-x / Gamma(a) * 1 / (x + 1 - a - 1(1 - a) / (x + 3 - a - ...)).
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        let mut i = 1.0;
        loop {
            let an = -i * (i - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-16 {
                break;
            }
            i += 1.0;
            assert!(i < 1e7, "continued fraction did not converge");
        }
        (ln_prefactor.exp() * h).min(1.0)
    }
}

/// Probability that a chi-square variable with `dof` degrees of freedom exceeds `stat`.
fn chi2_survival(stat: f64, dof: usize) -> f64 {
    gamma_q(dof as f64 / 2.0, stat / 2.0)
}

// ---------------------------------------------------------------------------------------
// Binning and the test itself
// ---------------------------------------------------------------------------------------

/// Gauss-Legendre nodes and weights on `[0, 1]`: Newton iteration on the roots of `P_n`.
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        // Tricomi's initial guess for the i-th root of P_n.
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            // Three-term recurrence (k+1) P_{k+1} = (2k+1) x P_k - k P_{k-1}.
            let (mut p0, mut p1) = (1.0, x);
            for k in 1..n {
                let p2 = ((2 * k + 1) as f64 * x * p1 - k as f64 * p0) / (k + 1) as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        // Map [-1, 1] -> [0, 1].
        out.push((0.5 * (x + 1.0), 0.5 * w));
    }
    out
}

/// A partition of the sphere into `n_theta x n_phi` cells around `frame.n`, with polar angle
/// `theta = pi * x^power` for `x` in `[0, 1]`: `power = 1` is uniform in theta, `power = 2`
/// resolves lobes peaked around the axis.
struct Domain {
    frame: Frame,
    power: f64,
    n_theta: usize,
    n_phi: usize,
}

impl Domain {
    fn new(axis: Vec3, power: f64) -> Self {
        Domain {
            frame: Frame::from_normal(axis),
            power,
            n_theta: 64,
            n_phi: 128,
        }
    }

    fn cell_of(&self, w: Vec3) -> usize {
        let l = self.frame.to_local(w);
        let (x, y, z) = (l.x as f64, l.y as f64, l.z as f64);
        // atan2 of (sin, cos) keeps theta accurate near both poles.
        let theta = (x * x + y * y).sqrt().atan2(z);
        let phi = y.atan2(x).rem_euclid(2.0 * PI);
        let u = (theta / PI).powf(1.0 / self.power);
        let i = ((u * self.n_theta as f64) as usize).min(self.n_theta - 1);
        let j = ((phi / (2.0 * PI) * self.n_phi as f64) as usize).min(self.n_phi - 1);
        i * self.n_phi + j
    }

    /// Integral of `pdf` over every cell: `int pdf sin(theta) dtheta dphi` with
    /// `theta = pi x^p`, `dtheta = p pi x^(p-1) dx`, `phi = 2 pi y`, by a tensor
    /// Gauss-Legendre rule per cell.
    fn integrate(&self, pdf: &dyn Fn(Vec3) -> f64) -> Vec<f64> {
        let gl = gauss_legendre(6);
        let mut out = vec![0.0; self.n_theta * self.n_phi];
        let dx = 1.0 / self.n_theta as f64;
        let dy = 1.0 / self.n_phi as f64;
        for i in 0..self.n_theta {
            for (gx, wx) in &gl {
                let x = (i as f64 + gx) * dx;
                let theta = PI * x.powf(self.power);
                let jac = theta.sin() * self.power * PI * x.powf(self.power - 1.0) * 2.0 * PI;
                let w_theta = wx * dx * jac;
                for j in 0..self.n_phi {
                    let mut acc = 0.0;
                    for (gy, wy) in &gl {
                        let phi = 2.0 * PI * (j as f64 + gy) * dy;
                        let local = Vec3::new(
                            (theta.sin() * phi.cos()) as f32,
                            (theta.sin() * phi.sin()) as f32,
                            theta.cos() as f32,
                        );
                        acc += wy * dy * pdf(self.frame.to_world(local));
                    }
                    out[i * self.n_phi + j] += w_theta * acc;
                }
            }
        }
        out
    }
}

#[derive(Debug)]
struct Chi2 {
    stat: f64,
    dof: usize,
    p_value: f64,
}

/// Histograms `n_samples` draws of `sample` (a `None` is a lost sample and counts against
/// the sampler) and compares them with `pdf` integrated over the cells of `domain`.
fn chi2_test(
    domain: &Domain,
    seed: u64,
    n_samples: usize,
    mut sample: impl FnMut(Vec2) -> Option<Vec3>,
    pdf: &dyn Fn(Vec3) -> f64,
) -> Chi2 {
    let mut observed = vec![0u64; domain.n_theta * domain.n_phi];
    let mut rng = Rng(seed);
    for _ in 0..n_samples {
        if let Some(w) = sample(rng.vec2()) {
            assert!(w.is_finite(), "sampler produced {w}");
            observed[domain.cell_of(w)] += 1;
        }
    }
    let expected: Vec<f64> = domain
        .integrate(pdf)
        .into_iter()
        .map(|p| p * n_samples as f64)
        .collect();
    pearson(&observed, &expected)
}

/// Pearson's statistic with pooling: cells are visited in order of increasing expected
/// count and merged until each pooled group expects at least `MIN_EXPECTED`; a leftover
/// group too small on its own joins the last complete one. A sample in a cell with zero
/// expected mass is an outright failure (p = 0).
fn pearson(observed: &[u64], expected: &[f64]) -> Chi2 {
    let mut order: Vec<usize> = (0..observed.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let mut groups: Vec<(f64, f64)> = Vec::new();
    let (mut obs, mut exp) = (0.0, 0.0);
    for &c in &order {
        if expected[c] <= 0.0 && observed[c] > 0 {
            return Chi2 {
                stat: f64::INFINITY,
                dof: 0,
                p_value: 0.0,
            };
        }
        obs += observed[c] as f64;
        exp += expected[c];
        if exp >= MIN_EXPECTED {
            groups.push((obs, exp));
            (obs, exp) = (0.0, 0.0);
        }
    }
    if exp > 0.0 || obs > 0.0 {
        match groups.last_mut() {
            Some(last) => {
                last.0 += obs;
                last.1 += exp;
            }
            None => groups.push((obs, exp)),
        }
    }
    let stat: f64 = groups.iter().map(|(o, e)| (o - e) * (o - e) / e).sum();
    let dof = groups.len().saturating_sub(1).max(1);
    Chi2 {
        stat,
        dof,
        p_value: chi2_survival(stat, dof),
    }
}

fn assert_accepted(name: &str, r: &Chi2) {
    let alpha = sidak_alpha();
    println!(
        "{name}: chi2 {:.1}, dof {}, p {:.4}",
        r.stat, r.dof, r.p_value
    );
    assert!(
        r.p_value > alpha,
        "{name}: sampler rejected, chi2 {} with {} dof, p {:e} < per-test alpha {alpha:e}",
        r.stat,
        r.dof,
        r.p_value
    );
}

/// Local direction at polar angle `theta` (from `+z`) and azimuth `phi`.
fn dir(theta: f32, phi: f32) -> Vec3 {
    Vec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

/// Binning for an HG lobe: around the direction it peaks at (`-wo` forward for `g > 0`,
/// `wo` for `g < 0`), with finer polar cells near the peak when the lobe is narrow.
fn hg_domain(g: f32, wo: Vec3) -> Domain {
    let axis = if g >= 0.0 { -wo } else { wo };
    Domain::new(axis, if g.abs() >= 0.9 { 2.0 } else { 1.0 })
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
    assert_accepted("uniform sphere", &r);
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
        assert_accepted(&format!("diffuse wo theta {theta}"), &r);
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
        assert_accepted(&format!("HG g {g}"), &r);
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
