//! Tests of the homogeneous-medium estimators in `risotto_systems::medium`:
//! transmittance against `exp` in f64, unbiasedness of the spectral-MIS free flight by Monte
//! Carlo against the closed forms of a homogeneous segment, goodness of fit of the sampled
//! distances (free flight and equiangular) against densities written here in f64, the
//! normalisation of those densities, and robustness at the edges (sigma_t = 0 and 1e6,
//! tmax = 0 and infinity, a light on the ray line, u = 0 and 1 - ulp).

mod common;
use common::*;

use risotto_components::{Rgb, Vec3};
use risotto_systems::medium::{
    channel_pdf, equiangular_pdf, equiangular_sample, free_flight_pass_probability,
    free_flight_pdf, sample_free_flight, sample_free_flights, transmittance, FreeFlight,
};

const ALBEDO: Rgb = Rgb::new(0.9, 0.5, 0.7);
/// The chromatic media, plus a 1e6 channel (a nearly opaque one beside thin ones).
const SIGMA_T: [Rgb; 3] = [
    Rgb::new(1.0, 2.0, 4.0),
    Rgb::new(0.0, 1.0, 100.0),
    Rgb::new(1e6, 1.0, 0.5),
];
const CHANNEL_PDFS: [[f32; 3]; 3] = [[1.0 / 3.0; 3], [0.6, 0.3, 0.1], [0.1, 0.1, 0.8]];
const ONE_MINUS_ULP: f32 = 1.0 - f32::EPSILON / 2.0;

/// Chi-square tests in this file expected to pass: 7 equiangular segments, 6 free flights.
const NUM_TESTS: u32 = 7 + 6;
const ALPHA: f64 = 0.01;
const N_CHI2: usize = 200_000;

fn sidak() -> f64 {
    sidak_alpha(ALPHA, NUM_TESTS)
}

/// `exp(-sigma d)` in f64 with `0 * inf = 0`.
fn transmittance64(sigma: f64, d: f64) -> f64 {
    if sigma == 0.0 || d == 0.0 {
        1.0
    } else {
        (-sigma * d).exp()
    }
}

fn channels(c: Rgb) -> [f64; 3] {
    c.to_array().map(|x| x as f64)
}

/// The free-flight mixture density `sum_c p_c sigma_c exp(-sigma_c t)`, in f64, from the
/// definition (not from the code under test).
fn mixture_pdf64(sigma_t: Rgb, p: [f32; 3], t: f64) -> f64 {
    let s = channels(sigma_t);
    (0..3)
        .map(|c| p[c] as f64 * s[c] * transmittance64(s[c], t))
        .sum()
}

fn mixture_pass64(sigma_t: Rgb, p: [f32; 3], tmax: f64) -> f64 {
    let s = channels(sigma_t);
    (0..3)
        .map(|c| p[c] as f64 * transmittance64(s[c], tmax))
        .sum()
}

// ---------------------------------------------------------------------------------------
// 1-D binning and quadrature
// ---------------------------------------------------------------------------------------

/// Bin edges on `[0, tmax]` that resolve a density peaked at `centre` with width `scale`:
/// `centre +- scale 2^(k/4)` for `k` in `-40..=240` (ratio 1.19 between neighbours, out to
/// `2^60 scale`), clipped to the segment, plus its ends.
fn edges(tmax: f64, centre: f64, scale: f64) -> Vec<f64> {
    let mut e = vec![0.0];
    for k in -40..=240 {
        let r = scale * 2f64.powf(k as f64 / 4.0);
        for x in [centre - r, centre + r] {
            if x > 0.0 && x < tmax {
                e.push(x);
            }
        }
    }
    if centre > 0.0 && centre < tmax {
        e.push(centre);
    }
    if tmax.is_finite() {
        e.push(tmax);
    }
    e.sort_by(f64::total_cmp);
    e.dedup();
    e
}

/// `int pdf` over each bin `[edges[i], edges[i + 1]]` (Gauss-Legendre, 6 points per bin).
fn integrate_bins(edges: &[f64], pdf: &dyn Fn(f64) -> f64) -> Vec<f64> {
    let gl = gauss_legendre(6);
    edges
        .windows(2)
        .map(|w| {
            let (a, b) = (w[0], w[1]);
            gl.iter()
                .map(|(x, wx)| wx * (b - a) * pdf(a + x * (b - a)))
                .sum()
        })
        .collect()
}

/// Pearson's test of distances `t` against a density on `[0, tmax)` with a point mass
/// `pass_prob` at `tmax` (samples with `t >= tmax`). Samples past the last finite edge of an
/// infinite segment go to a tail bin whose expected mass is what the bins leave of 1.
fn chi2_distances(
    samples: &[(f64, bool)],
    edges: &[f64],
    pdf: &dyn Fn(f64) -> f64,
    pass_prob: f64,
) -> Chi2 {
    let n = samples.len() as f64;
    // The sampled t are f32: bins narrower than a few f32 ulps (a light on the ray line
    // makes a peak ~800 ulps wide at t = 1) would test the rounding, not the sampler.
    let mut coarse: Vec<f64> = Vec::with_capacity(edges.len());
    for &e in edges {
        let min_width = 128.0 * f32::EPSILON as f64 * e.abs();
        if coarse.last().is_none_or(|&last| e - last >= min_width) {
            coarse.push(e);
        }
    }
    let edges = &coarse[..];
    let mut expected = integrate_bins(edges, pdf);
    let tail = (1.0 - pass_prob - expected.iter().sum::<f64>()).max(0.0);
    expected.push(tail);
    expected.push(pass_prob);
    let mut observed = vec![0u64; expected.len()];
    let pass_bin = expected.len() - 1;
    for &(t, scattered) in samples {
        assert!(t.is_finite() || !scattered, "scattered at {t}");
        let bin = if !scattered {
            pass_bin
        } else {
            // edges[0] = 0 <= t: the bin is the last edge <= t (the tail past the end).
            edges.partition_point(|&e| e <= t) - 1
        };
        observed[bin] += 1;
    }
    let expected: Vec<f64> = expected.into_iter().map(|e| e * n).collect();
    pearson(&observed, &expected)
}

// ---------------------------------------------------------------------------------------
// Transmittance
// ---------------------------------------------------------------------------------------

#[test]
fn transmittance_is_exp_and_multiplicative() {
    let sigmas = [0.0f32, 1e-6, 0.5, 1.0, 4.0, 100.0, 1e6];
    let ds = [0.0f32, 1e-7, 0.3, 1.0, 10.0, 1e4, f32::INFINITY];
    for &s in &sigmas {
        for &d in &ds {
            let t = transmittance(Rgb::new(s, 2.0 * s, 0.0), d);
            assert!(t.is_finite(), "sigma {s} d {d}: {t:?}");
            for (got, sigma) in [(t.r, s), (t.g, 2.0 * s)] {
                let want = transmittance64(sigma as f64, d as f64);
                // f32 rounds the optical depth tau by up to half an ulp, which moves
                // exp(-tau) by a relative ~6e-8 tau (want = 0 must be hit exactly).
                let tol = if want > 0.0 {
                    2e-7 * (1.0 - want.ln()) * want
                } else {
                    0.0
                };
                assert!(
                    (got as f64 - want).abs() <= tol + 1e-38,
                    "sigma {sigma} d {d}: {got} vs {want}"
                );
            }
            assert_eq!(t.b, 1.0, "sigma 0 attenuates nothing, even over d = {d}");
        }
    }
    // T(a + b) = T(a) T(b): Beer-Lambert's defining property.
    let sigma = Rgb::new(0.7, 1.3, 5.0);
    let (a, b) = (0.4f32, 1.1f32);
    let lhs = transmittance(sigma, a + b);
    let rhs = transmittance(sigma, a) * transmittance(sigma, b);
    for (l, r) in lhs.to_array().into_iter().zip(rhs.to_array()) {
        assert!((l - r).abs() < 1e-6 * l, "{l} vs {r}");
    }
    assert_eq!(transmittance(Rgb::splat(1.0), f32::INFINITY), Rgb::BLACK);
}

// ---------------------------------------------------------------------------------------
// Spectral-MIS free flights
// ---------------------------------------------------------------------------------------

/// Monte Carlo estimate (mean, standard error) per channel of `weight * 1{scatter}` and
/// `weight * 1{pass}`.
fn estimate(sigma_t: Rgb, p: [f32; 3], tmax: f32, n: usize, seed: u64) -> [[(f64, f64); 3]; 2] {
    let sigma_s = ALBEDO * sigma_t;
    let mut rng = Rng(seed);
    let mut sum = [[0.0f64; 3]; 2];
    let mut sum2 = [[0.0f64; 3]; 2];
    for _ in 0..n {
        let f = sample_free_flight(sigma_t, sigma_s, p, rng.f32(), rng.f32(), tmax);
        let k = if f.scattered { 0 } else { 1 };
        for (c, w) in f.weight.to_array().into_iter().enumerate() {
            sum[k][c] += w as f64;
            sum2[k][c] += (w as f64) * (w as f64);
        }
    }
    let mut out = [[(0.0, 0.0); 3]; 2];
    for k in 0..2 {
        for c in 0..3 {
            let mean = sum[k][c] / n as f64;
            let var = (sum2[k][c] / n as f64 - mean * mean).max(0.0);
            out[k][c] = (mean, (var / n as f64).sqrt());
        }
    }
    out
}

#[test]
fn spectral_mis_free_flight_is_unbiased() {
    // The homogeneous segment's two terms, per channel: the probability-weighted
    // pass-through averages T(tmax), and the collision term (weight includes sigma_s)
    // averages int_0^tmax sigma_s T(t) dt = albedo (1 - T(tmax)).
    let n = 200_000;
    let mut seed = 1000;
    for sigma_t in SIGMA_T {
        for p in CHANNEL_PDFS {
            for tmax in [0.0f32, 0.3, 2.0, f32::INFINITY] {
                seed += 1;
                let est = estimate(sigma_t, p, tmax, n, seed);
                for c in 0..3 {
                    let s = channels(sigma_t)[c];
                    let t = transmittance64(s, tmax as f64);
                    let a = channels(ALBEDO)[c];
                    let want = [if s > 0.0 { a * (1.0 - t) } else { 0.0 }, t];
                    for (k, name) in ["scatter", "pass"].into_iter().enumerate() {
                        let (mean, se) = est[k][c];
                        assert!(
                            (mean - want[k]).abs() <= 4.0 * se + 1e-5 * want[k] + 1e-30,
                            "sigma_t {sigma_t:?} p {p:?} tmax {tmax} channel {c} {name}: \
                             {mean} +- {se} vs {}",
                            want[k]
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn spectral_mis_weights_are_bounded_by_albedo_over_channel_probability() {
    // The point of the mixture pdf: pdf_mis >= p_c sigma_c T_c, so a scatter weight never
    // exceeds albedo_c / p_c (single-channel sampling's weights exp((sigma_k - sigma_c) t)
    // are unbounded). Dense u including u -> 1, where single-channel weights blow up.
    for sigma_t in SIGMA_T {
        let sigma_s = ALBEDO * sigma_t;
        for p in CHANNEL_PDFS {
            for i in 0..4096 {
                let u = (i as f32 / 4096.0).min(ONE_MINUS_ULP);
                for uc in [0.05f32, 0.5, 0.95] {
                    let f = sample_free_flight(sigma_t, sigma_s, p, uc, u, f32::INFINITY);
                    if !f.scattered {
                        continue;
                    }
                    for c in 0..3 {
                        let bound = ALBEDO.to_array()[c] / p[c];
                        let w = f.weight.to_array()[c];
                        assert!(
                            w <= bound * (1.0 + 1e-5),
                            "{sigma_t:?} {p:?}: {w} > {bound}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn free_flight_weights_match_pdfs() {
    let mut rng = Rng(2000);
    for sigma_t in SIGMA_T {
        let sigma_s = ALBEDO * sigma_t;
        for p in CHANNEL_PDFS {
            for tmax in [0.3f32, 2.0, f32::INFINITY] {
                let pass = mixture_pass64(sigma_t, p, tmax as f64);
                let got = free_flight_pass_probability(sigma_t, p, tmax) as f64;
                assert!((got - pass).abs() <= 1e-6 * pass + 1e-12, "{got} vs {pass}");
                for _ in 0..2000 {
                    let f = sample_free_flight(sigma_t, sigma_s, p, rng.f32(), rng.f32(), tmax);
                    assert!(f.weight.is_finite());
                    for c in 0..3 {
                        let s = channels(sigma_t)[c];
                        let (t, w) = (f.t as f64, f.weight.to_array()[c] as f64);
                        let want = if f.scattered {
                            let pdf = mixture_pdf64(sigma_t, p, t);
                            let ff = free_flight_pdf(sigma_t, p, f.t) as f64;
                            assert!((ff - pdf).abs() <= 1e-5 * pdf + 1e-30, "{ff} vs {pdf}");
                            s * channels(ALBEDO)[c] * transmittance64(s, t) / pdf
                        } else {
                            assert_eq!(f.t, tmax);
                            transmittance64(s, tmax as f64) / pass
                        };
                        assert!(
                            (w - want).abs() <= 1e-4 * want + 1e-30,
                            "{sigma_t:?} {p:?} tmax {tmax} {f:?} channel {c}: {w} vs {want}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn free_flight_pdf_integrates_to_one_minus_pass_probability() {
    for sigma_t in SIGMA_T {
        for p in CHANNEL_PDFS {
            for tmax in [0.3f32, 2.0, f32::INFINITY] {
                let sigma_max = sigma_t.max_channel() as f64;
                let e = edges(tmax as f64, 0.0, 1e-3 / sigma_max);
                let total: f64 =
                    integrate_bins(&e, &|t| free_flight_pdf(sigma_t, p, t as f32) as f64)
                        .iter()
                        .sum();
                let pass = free_flight_pass_probability(sigma_t, p, tmax) as f64;
                assert!(
                    (total + pass - 1.0).abs() < 1e-4,
                    "{sigma_t:?} {p:?} tmax {tmax}: {total} + {pass}"
                );
            }
        }
    }
}

#[test]
fn chi2_free_flight_distances() {
    let p = CHANNEL_PDFS[1];
    let mut k = 0;
    for sigma_t in SIGMA_T {
        for tmax in [2.0f32, f32::INFINITY] {
            k += 1;
            let mut rng = Rng(3000 + k);
            let samples: Vec<(f64, bool)> = (0..N_CHI2)
                .map(|_| {
                    let f = sample_free_flight(
                        sigma_t,
                        ALBEDO * sigma_t,
                        p,
                        rng.f32(),
                        rng.f32(),
                        tmax,
                    );
                    (f.t as f64, f.scattered)
                })
                .collect();
            let sigma_max = sigma_t.max_channel() as f64;
            let e = edges(tmax as f64, 0.0, 1e-3 / sigma_max);
            let r = chi2_distances(
                &samples,
                &e,
                &|t| mixture_pdf64(sigma_t, p, t),
                mixture_pass64(sigma_t, p, tmax as f64),
            );
            assert_accepted(&format!("free flight {sigma_t:?} tmax {tmax}"), &r, sidak());
        }
    }
    // Teeth: distances sampled with the wrong channel probabilities are rejected.
    let sigma_t = SIGMA_T[0];
    let mut rng = Rng(3100);
    let samples: Vec<(f64, bool)> = (0..N_CHI2)
        .map(|_| {
            let f =
                sample_free_flight(sigma_t, sigma_t, CHANNEL_PDFS[0], rng.f32(), rng.f32(), 2.0);
            (f.t as f64, f.scattered)
        })
        .collect();
    let r = chi2_distances(
        &samples,
        &edges(2.0, 0.0, 1e-3 / 4.0),
        &|t| mixture_pdf64(sigma_t, p, t),
        mixture_pass64(sigma_t, p, 2.0),
    );
    assert!(r.p_value < sidak(), "wrong channel pdf not rejected: {r:?}");
}

#[test]
fn free_flight_edge_cases_stay_finite() {
    let sigmas = [
        Rgb::BLACK,
        Rgb::splat(1e6),
        Rgb::new(1e-30, 1.0, 0.0),
        Rgb::new(0.0, 1.0, 100.0),
        Rgb::new(1e6, 1e-6, 3.0),
    ];
    let tmaxes = [0.0f32, 1e-30, 1e-7, 1.0, 1e30, f32::INFINITY];
    let pdfs = [
        [1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, 0.0],
        [f32::NAN, 0.5, 0.5],
        [1.0 / 3.0; 3],
    ];
    let mut us: Vec<f32> = (0..64).map(|i| i as f32 / 64.0).collect();
    us.extend([1e-30, 1e-7, ONE_MINUS_ULP, 1.0]);
    for sigma_t in sigmas {
        for albedo in [Rgb::BLACK, ALBEDO, Rgb::WHITE] {
            let sigma_s = albedo * sigma_t;
            for tmax in tmaxes {
                for p in pdfs {
                    for &uc in &us {
                        for &ud in &us {
                            let f = sample_free_flight(sigma_t, sigma_s, p, uc, ud, tmax);
                            let ok = f.weight.is_finite()
                                && f.weight.min_channel() >= 0.0
                                && if f.scattered {
                                    f.t >= 0.0 && f.t < tmax
                                } else {
                                    f.t == tmax
                                };
                            assert!(
                                ok,
                                "{sigma_t:?} {albedo:?} {p:?} tmax {tmax} u ({uc}, {ud}): {f:?}"
                            );
                        }
                    }
                }
            }
        }
    }
    // tmax = 0 always passes with weight exactly 1; an empty medium always passes with 1.
    let f = sample_free_flight(SIGMA_T[0], SIGMA_T[0], CHANNEL_PDFS[1], 0.5, 0.0, 0.0);
    assert_eq!((f.scattered, f.t, f.weight), (false, 0.0, Rgb::WHITE));
    let f = sample_free_flight(
        Rgb::BLACK,
        Rgb::BLACK,
        CHANNEL_PDFS[1],
        0.5,
        0.9,
        f32::INFINITY,
    );
    assert!(!f.scattered && (f.weight.r - 1.0).abs() < 1e-6, "{f:?}");
    // An infinite segment: channels with sigma_t > 0 never pass, the sigma_t = 0 channel
    // always carries its full throughput through (weight 1 / p_0 on the pass it takes).
    let f = sample_free_flight(
        SIGMA_T[1],
        SIGMA_T[1],
        [0.5, 0.25, 0.25],
        0.1,
        0.5,
        f32::INFINITY,
    );
    assert!(!f.scattered);
    assert_eq!(f.weight, Rgb::new(2.0, 0.0, 0.0));
}

#[test]
fn channel_pdf_follows_throughput_with_uniform_fallback() {
    assert_eq!(channel_pdf(Rgb::new(2.0, 1.0, 1.0)), [0.5, 0.25, 0.25]);
    assert_eq!(channel_pdf(Rgb::new(0.0, 3.0, 0.0)), [0.0, 1.0, 0.0]);
    // A NaN channel counts as 0; nothing usable left, or an infinite sum, gives uniform.
    assert_eq!(channel_pdf(Rgb::new(f32::NAN, 1.0, 1.0)), [0.0, 0.5, 0.5]);
    for t in [Rgb::BLACK, Rgb::splat(-1.0), Rgb::splat(f32::INFINITY)] {
        assert_eq!(channel_pdf(t), [1.0 / 3.0; 3], "{t:?}");
    }
}

#[test]
fn free_flight_column_equals_per_ray_sampling() {
    let n = 257;
    let mut rng = Rng(4000);
    let sigma_t = SIGMA_T[0];
    let sigma_s = ALBEDO * sigma_t;
    let throughput: Vec<Rgb> = (0..n)
        .map(|_| Rgb::new(rng.f32(), rng.f32(), rng.f32()))
        .collect();
    let uc: Vec<f32> = (0..n).map(|_| rng.f32()).collect();
    let ud: Vec<f32> = (0..n).map(|_| rng.f32()).collect();
    let tmax: Vec<f32> = (0..n)
        .map(|i| {
            if i % 3 == 0 {
                f32::INFINITY
            } else {
                2.0 * rng.f32()
            }
        })
        .collect();
    let mut out = vec![FreeFlight::default(); n];
    sample_free_flights(sigma_t, sigma_s, &throughput, &uc, &ud, &tmax, &mut out);
    for i in 0..n {
        let want = sample_free_flight(
            sigma_t,
            sigma_s,
            channel_pdf(throughput[i]),
            uc[i],
            ud[i],
            tmax[i],
        );
        assert_eq!(out[i], want, "ray {i}");
    }
}

// ---------------------------------------------------------------------------------------
// Equiangular sampling
// ---------------------------------------------------------------------------------------

/// `(origin, dir, light, tmax)` cases: light beside the segment, behind its start, far
/// ahead of it, an infinite segment, the light on the ray line (inside the segment, and
/// behind the origin of an infinite one), and a general position.
fn equiangular_cases() -> Vec<(Vec3, Vec3, Vec3, f32)> {
    let o = Vec3::new(3.0, -2.0, 1.0);
    let d = Vec3::new(1.0, 2.0, -2.0).normalize();
    let perp = d.cross(Vec3::Z).normalize();
    vec![
        (Vec3::ZERO, Vec3::X, Vec3::new(0.5, 1.0, 0.0), 2.0),
        (Vec3::ZERO, Vec3::X, Vec3::new(-3.0, 0.2, 0.0), 5.0),
        (Vec3::ZERO, Vec3::X, Vec3::new(50.0, 0.1, 0.0), 10.0),
        (Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.5, 0.0), f32::INFINITY),
        (Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, 0.0), 3.0),
        (
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(-1.0, 0.0, 0.0),
            f32::INFINITY,
        ),
        (o, d, o + 4.0 * d + 0.3 * perp, 6.0),
    ]
}

/// Foot point and line distance of the light, in f64 (for binning only).
fn foot(o: Vec3, d: Vec3, light: Vec3) -> (f64, f64) {
    let v = (light - o).as_dvec3();
    let d = d.as_dvec3();
    (v.dot(d), v.cross(d).length().max(1e-4 * v.length()))
}

#[test]
fn equiangular_pdf_integrates_to_one() {
    for (o, d, light, tmax) in equiangular_cases() {
        let (delta, h) = foot(o, d, light);
        let e = edges(tmax as f64, delta, h);
        let total: f64 =
            integrate_bins(&e, &|t| equiangular_pdf(o, d, light, tmax, t as f32) as f64)
                .iter()
                .sum();
        // An infinite segment's tail past the last edge (2^60 h beyond the foot) holds
        // about h / (dtheta 2^60 h) < 1e-17 of the mass.
        assert!((total - 1.0).abs() < 1e-4, "{light} tmax {tmax}: {total}");
        // Outside the segment the density is zero.
        assert_eq!(equiangular_pdf(o, d, light, tmax, -1e-3), 0.0);
        if tmax.is_finite() {
            assert_eq!(equiangular_pdf(o, d, light, tmax, tmax * 1.001), 0.0);
        }
    }
}

#[test]
fn chi2_equiangular() {
    for (k, (o, d, light, tmax)) in equiangular_cases().into_iter().enumerate() {
        let (delta, h) = foot(o, d, light);
        let mut rng = Rng(5000 + k as u64);
        let samples: Vec<(f64, bool)> = (0..N_CHI2)
            .map(|_| {
                (
                    equiangular_sample(o, d, light, tmax, rng.f32()).0 as f64,
                    true,
                )
            })
            .collect();
        // The density written out here from Kulla and Fajardo's eq. 6 with the
        // angles as plain atan differences in f64, independently of the code under test.
        let (a, b) = ((-delta / h).atan(), ((tmax as f64 - delta) / h).atan());
        let pdf = |t: f64| h / ((b - a) * (h * h + (t - delta) * (t - delta)));
        let r = chi2_distances(&samples, &edges(tmax as f64, delta, h), &pdf, 0.0);
        assert_accepted(
            &format!("equiangular light {light} tmax {tmax}"),
            &r,
            sidak(),
        );
    }
    // Teeth: samples for a light 10% further from the ray fail against the true density.
    let (o, d, light, tmax) = equiangular_cases()[0];
    let moved = light + Vec3::new(0.0, 0.1, 0.0);
    let mut rng = Rng(5100);
    let samples: Vec<(f64, bool)> = (0..N_CHI2)
        .map(|_| {
            (
                equiangular_sample(o, d, moved, tmax, rng.f32()).0 as f64,
                true,
            )
        })
        .collect();
    let (delta, h) = foot(o, d, light);
    let r = chi2_distances(
        &samples,
        &edges(tmax as f64, delta, h),
        &|t| equiangular_pdf(o, d, light, tmax, t as f32) as f64,
        0.0,
    );
    assert!(r.p_value < sidak(), "moved light not rejected: {r:?}");
}

#[test]
fn equiangular_sampled_pdf_equals_pdf_and_stays_finite() {
    let mut cases = equiangular_cases();
    // Degenerate and extreme segments on top of the regular ones.
    cases.extend([
        (Vec3::ZERO, Vec3::X, Vec3::ZERO, 2.0),
        (Vec3::ZERO, Vec3::X, Vec3::ZERO, f32::INFINITY),
        (Vec3::ZERO, Vec3::X, Vec3::new(0.5, 1.0, 0.0), 0.0),
        (Vec3::ZERO, Vec3::X, Vec3::new(0.5, 1.0, 0.0), 1e-30),
        (Vec3::ZERO, Vec3::X, Vec3::new(1e4, 1e-3, 0.0), 1.0),
        (
            Vec3::splat(1e6),
            Vec3::Y,
            Vec3::new(1e6, 1e6 + 10.0, 1e6 + 1e-3),
            1e3,
        ),
        (
            Vec3::ZERO,
            -Vec3::Z,
            Vec3::new(0.0, 0.0, -1e-20),
            f32::INFINITY,
        ),
    ]);
    let mut us: Vec<f32> = (0..1024).map(|i| i as f32 / 1024.0).collect();
    us.extend([1e-30, 1e-7, 0.5 - 3e-8, ONE_MINUS_ULP, 1.0]);
    for (o, d, light, tmax) in cases {
        for &u in &us {
            let (t, pdf) = equiangular_sample(o, d, light, tmax, u);
            if tmax <= 0.0 {
                assert_eq!((t, pdf), (0.0, 0.0), "empty segment");
                continue;
            }
            let ok = t.is_finite() && t >= 0.0 && t <= tmax && pdf.is_finite() && pdf > 0.0;
            assert!(ok, "{o} {d} {light} tmax {tmax} u {u}: t {t} pdf {pdf}");
            let e = equiangular_pdf(o, d, light, tmax, t);
            assert_eq!(e, pdf, "{light} tmax {tmax} u {u}");
        }
        // Monotone in u: the sampler is an inverse CDF.
        let ts: Vec<f32> = us[..1024]
            .iter()
            .map(|&u| equiangular_sample(o, d, light, tmax, u).0)
            .collect();
        assert!(
            ts.windows(2).all(|w| w[0] <= w[1]),
            "{light} tmax {tmax} not monotone"
        );
    }
}
