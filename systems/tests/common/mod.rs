//! Statistics shared by the sampling tests (`bxdf_chi2`, `phase_chi2`, `medium`): the
//! chi-square survival function, Gauss-Legendre quadrature, a binning of the sphere and
//! Pearson's test with pooling, in the style of Mitsuba 3's `mitsuba.chi2` and pbrt-v3's
//! `src/tests/bsdfs.cpp`.
//!
//! The survival function is written here rather than pulled from `statrs`: it is ~60 lines,
//! is checked in `bxdf_chi2` against closed forms and tabulated quantiles, and keeps a
//! statistics crate out of the workspace for the sake of a few tests.

// Each test crate that includes this module uses a different subset of it.
#![allow(
    dead_code,
    reason = "shared by several test crates, each using a subset"
)]

use risotto_components::{Vec2, Vec3};
use risotto_systems::bxdf::Frame;
use std::f64::consts::PI;

pub use risotto_systems::sampler::SplitMix64 as Rng;

/// Minimum expected count of a cell before pooling (the usual rule of thumb).
pub const MIN_EXPECTED: f64 = 5.0;

/// Per-test significance for a family-wise level `alpha` over `num_tests` tests, with
/// Sidak's correction: `1 - (1 - alpha)^(1/m)`.
pub fn sidak_alpha(alpha: f64, num_tests: u32) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / num_tests as f64)
}

// ---------------------------------------------------------------------------------------
// Chi-square survival function
// ---------------------------------------------------------------------------------------

/// `ln Gamma(x)` for `x > 0`: Lanczos approximation with `g = 7`, 9 coefficients (accurate
/// to ~1e-15 relative), as given e.g. in Press et al., Numerical Recipes 3rd ed. sec. 6.1.
pub fn ln_gamma(x: f64) -> f64 {
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
pub fn gamma_q(a: f64, x: f64) -> f64 {
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
pub fn chi2_survival(stat: f64, dof: usize) -> f64 {
    gamma_q(dof as f64 / 2.0, stat / 2.0)
}

// ---------------------------------------------------------------------------------------
// Binning and the test itself
// ---------------------------------------------------------------------------------------

/// Gauss-Legendre nodes and weights on `[0, 1]`: Newton iteration on the roots of `P_n`.
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
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

/// How a [`Domain`] spaces its polar cells: `theta = pi * s(x)` for `x` in `[0, 1]`.
#[derive(Clone, Copy, Debug)]
pub enum ThetaWarp {
    /// `s = x^p`: `p = 1` is uniform in theta, `p = 2` resolves a lobe peaked around the
    /// axis (`theta = 0`).
    Power(f64),
    /// `s = (2x)^p / 2` below `x = 1/2` and its mirror image above: fine cells at *both*
    /// poles, for mixtures with a forward and a backward peak (double HG). With an even
    /// number of polar cells the kink at `x = 1/2` is a cell boundary.
    BothPoles(f64),
}

impl ThetaWarp {
    /// `(s(x), ds/dx)`.
    fn forward(self, x: f64) -> (f64, f64) {
        match self {
            ThetaWarp::Power(p) => (x.powf(p), p * x.powf(p - 1.0)),
            ThetaWarp::BothPoles(p) => {
                if x < 0.5 {
                    (0.5 * (2.0 * x).powf(p), p * (2.0 * x).powf(p - 1.0))
                } else {
                    let y = 2.0 * (1.0 - x);
                    (1.0 - 0.5 * y.powf(p), p * y.powf(p - 1.0))
                }
            }
        }
    }

    /// `x` with `s(x) = s`.
    fn inverse(self, s: f64) -> f64 {
        match self {
            ThetaWarp::Power(p) => s.powf(1.0 / p),
            ThetaWarp::BothPoles(p) => {
                if s < 0.5 {
                    0.5 * (2.0 * s).powf(1.0 / p)
                } else {
                    1.0 - 0.5 * (2.0 * (1.0 - s)).powf(1.0 / p)
                }
            }
        }
    }
}

/// A partition of the sphere into `n_theta x n_phi` cells around `frame.n`, polar cells
/// spaced by a [`ThetaWarp`].
pub struct Domain {
    pub frame: Frame,
    pub warp: ThetaWarp,
    pub n_theta: usize,
    pub n_phi: usize,
}

impl Domain {
    /// Cells around `axis` with `theta = pi * x^power`.
    pub fn new(axis: Vec3, power: f64) -> Self {
        Domain::with_warp(axis, ThetaWarp::Power(power))
    }

    /// Cells around `axis` spaced by `warp`.
    pub fn with_warp(axis: Vec3, warp: ThetaWarp) -> Self {
        Domain {
            frame: Frame::from_normal(axis),
            warp,
            n_theta: 64,
            n_phi: 128,
        }
    }

    pub fn cell_of(&self, w: Vec3) -> usize {
        let l = self.frame.to_local(w);
        let (x, y, z) = (l.x as f64, l.y as f64, l.z as f64);
        // atan2 of (sin, cos) keeps theta accurate near both poles.
        let theta = (x * x + y * y).sqrt().atan2(z);
        let phi = y.atan2(x).rem_euclid(2.0 * PI);
        let u = self.warp.inverse(theta / PI);
        let i = ((u * self.n_theta as f64) as usize).min(self.n_theta - 1);
        let j = ((phi / (2.0 * PI) * self.n_phi as f64) as usize).min(self.n_phi - 1);
        i * self.n_phi + j
    }

    /// Integral of `pdf` over every cell: `int pdf sin(theta) dtheta dphi` with
    /// `theta = pi s(x)`, `dtheta = pi s'(x) dx`, `phi = 2 pi y`, by a tensor Gauss-Legendre
    /// rule per cell.
    pub fn integrate(&self, pdf: &dyn Fn(Vec3) -> f64) -> Vec<f64> {
        let gl = gauss_legendre(6);
        let mut out = vec![0.0; self.n_theta * self.n_phi];
        let dx = 1.0 / self.n_theta as f64;
        let dy = 1.0 / self.n_phi as f64;
        for i in 0..self.n_theta {
            for (gx, wx) in &gl {
                let x = (i as f64 + gx) * dx;
                let (s, ds) = self.warp.forward(x);
                let theta = PI * s;
                let jac = theta.sin() * PI * ds * 2.0 * PI;
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

    /// The integral of `pdf` over the whole sphere.
    pub fn total(&self, pdf: &dyn Fn(Vec3) -> f64) -> f64 {
        self.integrate(pdf).iter().sum()
    }
}

/// The outcome of one Pearson test.
#[derive(Debug)]
pub struct Chi2 {
    pub stat: f64,
    pub dof: usize,
    pub p_value: f64,
}

/// Histograms `n_samples` draws of `sample` (a `None` is a lost sample and counts against
/// the sampler) and compares them with `pdf` integrated over the cells of `domain`.
pub fn chi2_test(
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
pub fn pearson(observed: &[u64], expected: &[f64]) -> Chi2 {
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

/// Passes when `r`'s p-value exceeds the per-test significance `alpha`.
pub fn assert_accepted(name: &str, r: &Chi2, alpha: f64) {
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
pub fn dir(theta: f32, phi: f32) -> Vec3 {
    Vec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

/// Binning for an HG lobe: around the direction it peaks at (`-wo` forward for `g > 0`,
/// `wo` for `g < 0`), with finer polar cells near the peak when the lobe is narrow.
pub fn hg_domain(g: f32, wo: Vec3) -> Domain {
    let axis = if g >= 0.0 { -wo } else { wo };
    Domain::new(axis, if g.abs() >= 0.9 { 2.0 } else { 1.0 })
}
