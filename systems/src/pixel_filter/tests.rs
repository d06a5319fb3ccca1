use super::*;
use crate::distribution::tests::{chi_square, chi_square_limit};
use crate::sampler::SplitMix64 as Rng;

/// Mitsuba 3's defaults and pbrt-v4's, and a wide and a narrow one.
fn filters() -> Vec<PixelFilter> {
    vec![
        PixelFilter::Box { radius: 0.5 },
        PixelFilter::Box { radius: 1.5 },
        PixelFilter::Tent { radius: 1.0 },
        PixelFilter::Tent { radius: 2.0 },
        PixelFilter::Gaussian(GaussianFilter::new(0.5, 2.0).unwrap()),
        PixelFilter::Gaussian(GaussianFilter::new(0.5, 1.5).unwrap()),
        PixelFilter::Gaussian(GaussianFilter::new(1.0, 1.0).unwrap()),
        PixelFilter::Gaussian(GaussianFilter::new(0.1, 3.0).unwrap()),
    ]
}

/// `int_a^b f1` by Simpson's rule on 2000 intervals of the filter's own `eval_1d`: the
/// expected bin probabilities, computed without the sampler's table or quadrature.
fn simpson(filter: &PixelFilter, a: f64, b: f64) -> f64 {
    let n = 2000;
    let h = (b - a) / n as f64;
    let f = |x: f64| f64::from(filter.eval_1d(x as f32));
    let inner: f64 = (1..n)
        .map(|i| f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 })
        .sum();
    (f(a) + f(b) + inner) * h / 3.0
}

/// The error function in f64: its Taylor series (Abramowitz and Stegun 7.1.5) for |x| <= 4
/// (cancellation costs at most 5 of f64's digits there), beyond that 1 minus the first
/// terms of the asymptotic series of erfc (7.1.23), whose error is below 1e-12 there.
fn erf(x: f64) -> f64 {
    if x.abs() > 4.0 {
        let y = x.abs();
        let z = 1.0 / (2.0 * y * y);
        let erfc = (-y * y).exp() / (y * std::f64::consts::PI.sqrt())
            * (1.0 - z + 3.0 * z * z - 15.0 * z * z * z);
        return x.signum() * (1.0 - erfc);
    }
    let mut term = x;
    let mut sum = x;
    for n in 1..200 {
        term *= -x * x / n as f64;
        let add = term / (2 * n + 1) as f64;
        sum += add;
        if add.abs() < 1e-17 * sum.abs() {
            break;
        }
    }
    2.0 / std::f64::consts::PI.sqrt() * sum
}

/// The CDF of the truncated, lowered Gaussian in closed form: `int_{-r}^x (exp(-t^2 / (2
/// s^2)) - b) dt / int_{-r}^r ...`, with `int exp(-t^2 / (2 s^2)) = s sqrt(pi / 2)
/// erf(t / (s sqrt 2))`.
fn gaussian_cdf(s: f64, r: f64, x: f64) -> f64 {
    let b = (-r * r / (2.0 * s * s)).exp();
    let k = s * (std::f64::consts::PI / 2.0).sqrt();
    let e = |t: f64| k * erf(t / (s * std::f64::consts::SQRT_2)) - b * t;
    (e(x) - e(-r)) / (e(r) - e(-r))
}

#[test]
fn erf_of_the_tests_matches_tabulated_values() {
    // Abramowitz and Stegun, table 7.1.
    for (x, want) in [
        (0.5, 0.520_499_877_813_046_5),
        (1.0, 0.842_700_792_949_714_9),
        (2.0, 0.995_322_265_018_952_7),
        (3.0, 0.999_977_909_503_001_4),
        (4.5, 0.999_999_999_803_383_9),
    ] {
        assert!((erf(x) - want).abs() < 1e-13, "erf({x}) = {}", erf(x));
    }
}

/// Each filter's 1-D sampler against its density: a chi-square test over 64 bins of the
/// support, with probabilities from Simpson's rule on `eval_1d`. A sampler of the untruncated
/// Gaussian, of the Gaussian without the subtracted bias, or of a piecewise-constant
/// approximation of it would fail (the lowered Gaussian differs from the plain one by 0.03 %
/// of the peak at the defaults; the bins at the tails see it).
#[test]
fn filter_samples_follow_the_filter_chi_square() {
    let n = 1_000_000u64;
    let bins = 64;
    for filter in filters() {
        let r = f64::from(filter.radius());
        let total = simpson(&filter, -r, r);
        assert!(
            (total - f64::from(filter.integral_1d())).abs() < 1e-4 * total,
            "{filter:?}: integral {} vs Simpson {total}",
            filter.integral_1d()
        );
        let edge = |i: usize| -r + 2.0 * r * i as f64 / bins as f64;
        let probs: Vec<f64> = (0..bins)
            .map(|i| simpson(&filter, edge(i), edge(i + 1)) / total)
            .collect();
        let mut counts = vec![0u64; bins];
        let mut rng = Rng(17);
        for _ in 0..n {
            let x = f64::from(filter.sample_1d(rng.f32()));
            assert!(
                x.abs() <= r * (1.0 + 1e-6),
                "{filter:?}: {x} outside the support"
            );
            let bin = (((x + r) / (2.0 * r)) * bins as f64) as usize;
            counts[bin.min(bins - 1)] += 1;
        }
        let (stat, df) = chi_square(&counts, &probs, n);
        assert!(
            stat < chi_square_limit(df),
            "{filter:?}: chi2 {stat} with {df} dof"
        );
    }
}

/// The Gaussian sampler inverts the exact CDF (the closed form through erf): `F(x(u)) = u`
/// to f32 resolution, so the weight-1 estimator is unbiased for the truncated Gaussian, not
/// for a tabulated stand-in of it.
#[test]
fn gaussian_sampler_inverts_the_closed_form_cdf() {
    for (s, r) in [
        (0.5f32, 2.0f32),
        (0.5, 1.5),
        (1.0, 1.0),
        (0.1, 3.0),
        (2.0, 0.5),
    ] {
        let g = GaussianFilter::new(s, r).unwrap();
        let mut worst = 0.0f64;
        let mut last = -f32::INFINITY;
        for i in 0..=4096 {
            let u = (i as f32 / 4096.0).min(1.0 - f32::EPSILON / 2.0);
            let x = g.sample(u);
            assert!(x >= last, "not monotonic at u = {u}");
            last = x;
            let cdf = gaussian_cdf(f64::from(s), f64::from(r), f64::from(x));
            worst = worst.max((cdf - f64::from(u)).abs());
        }
        assert!(
            worst < 2e-6,
            "stddev {s}, radius {r}: |F(x(u)) - u| up to {worst}"
        );
        // And the filter value is the lowered Gaussian.
        let b = (-(r * r) / (2.0 * s * s)).exp();
        let x = 0.3 * r;
        let want = (-(x * x) / (2.0 * s * s)).exp() - b;
        assert!((PixelFilter::Gaussian(g).eval_1d(x) - want).abs() < 1e-6);
        assert_eq!(PixelFilter::Gaussian(g).eval_1d(r * 1.01), 0.0);
    }
}

/// The tent's inverse CDF against its closed-form CDF, and its end points.
#[test]
fn tent_sampler_inverts_its_cdf() {
    let r = 1.5f32;
    let cdf = |x: f64| {
        let r = f64::from(r);
        if x < 0.0 {
            (x + r).powi(2) / (2.0 * r * r)
        } else {
            1.0 - (r - x).powi(2) / (2.0 * r * r)
        }
    };
    for i in 0..1000 {
        let u = i as f32 / 1000.0;
        let x = sample_tent(u, r);
        assert!(
            (cdf(f64::from(x)) - f64::from(u)).abs() < 1e-6,
            "u {u}: x {x}"
        );
    }
    assert_eq!(sample_tent(0.0, r), -r);
    assert_eq!(sample_tent(0.5, r), 0.0);
}

/// The column warp is the per-axis sampler around the pixel centre, and the 2-D offsets
/// follow the separable 2-D filter: a chi-square over 16 x 16 cells of the support.
#[test]
fn warped_jitter_follows_the_2d_filter_chi_square() {
    let n = 400_000usize;
    let cells = 16;
    for filter in filters() {
        let mut rng = Rng(5);
        let mut jitter: Vec<Vec2> = (0..n).map(|_| rng.vec2()).collect();
        let before = jitter.clone();
        warp_pixel_jitter(&filter, &mut jitter);
        let r = f64::from(filter.radius());
        let edge = |i: usize| -r + 2.0 * r * i as f64 / cells as f64;
        let p1: Vec<f64> = (0..cells)
            .map(|i| simpson(&filter, edge(i), edge(i + 1)) / simpson(&filter, -r, r))
            .collect();
        let probs: Vec<f64> = (0..cells * cells)
            .map(|k| p1[k / cells] * p1[k % cells])
            .collect();
        let mut counts = vec![0u64; cells * cells];
        for (j, u) in jitter.iter().zip(&before) {
            let want = Vec2::splat(0.5) + Vec2::new(filter.sample_1d(u.x), filter.sample_1d(u.y));
            assert!(
                (*j - want).length() < 1e-6,
                "{filter:?}: warp {j} vs {want}"
            );
            let cell = |v: f32| {
                ((((f64::from(v) - 0.5 + r) / (2.0 * r)) * cells as f64) as usize).min(cells - 1)
            };
            counts[cell(j.y) * cells + cell(j.x)] += 1;
        }
        let (stat, df) = chi_square(&counts, &probs, n as u64);
        assert!(
            stat < chi_square_limit(df),
            "{filter:?}: chi2 {stat} with {df} dof"
        );
    }
}

#[test]
fn invalid_gaussians_are_refused() {
    for (s, r) in [
        (0.0, 1.0),
        (-1.0, 1.0),
        (0.5, 0.0),
        (f32::NAN, 1.0),
        (0.5, f32::INFINITY),
    ] {
        assert!(
            GaussianFilter::new(s, r).is_none(),
            "stddev {s}, radius {r}"
        );
    }
    assert!(PixelFilter::default().is_pixel_box());
    assert!(!PixelFilter::Box { radius: 0.6 }.is_pixel_box());
}
