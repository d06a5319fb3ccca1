//! Tests of the independent sampler (`crate::independent_sampler`) through the sampler
//! front end it serves.

use crate::independent_sampler::*;
use crate::sampler::PathSampler;
use crate::sampler::{first_2d_column, next_2d_column, next_4d_column, pixel_seed, SplitMix64};
use glam::Vec2;

/// Pearson's chi-square statistic of `counts` against equal expected counts.
fn chi_square(counts: &[u64]) -> f64 {
    let n: u64 = counts.iter().sum();
    let e = n as f64 / counts.len() as f64;
    counts.iter().map(|&c| (c as f64 - e).powi(2) / e).sum()
}

/// The chi-square bound that a uniform sample exceeds with probability about 1e-6 at
/// `dof` degrees of freedom (Wilson-Hilferty, z = 4.75).
fn chi_square_bound(dof: f64) -> f64 {
    let z = 4.75;
    let t = 1.0 - 2.0 / (9.0 * dof) + z * (2.0 / (9.0 * dof)).sqrt();
    dof * t * t * t
}

fn independent(seed: u32, index: u32, dimension: u32) -> PathSampler {
    PathSampler {
        seed,
        sample: SamplerKind::Independent.address(index),
        dimension,
    }
}

#[test]
fn one_and_two_dimensional_draws_are_uniform() {
    // 1D: 64 bins per dimension over 64k pixel samples; 2D: a 16x16 grid of pairs of
    // dimensions (neighbouring and far apart).
    for dim in [0u32, 1, 4, 7, 1024] {
        let mut bins = vec![0u64; 64];
        for p in 0..1024u32 {
            let seed = pixel_seed(3, p);
            for i in 0..64 {
                let v = sample_1d(seed, SamplerKind::Independent.address(i), dim);
                assert!((0.0..1.0).contains(&v));
                bins[(v * 64.0) as usize] += 1;
            }
        }
        let x2 = chi_square(&bins);
        assert!(x2 < chi_square_bound(63.0), "dimension {dim}: chi2 {x2}");
    }
    for (a, b) in [(0u32, 1u32), (4, 5), (6, 7), (3, 900)] {
        let mut bins = vec![0u64; 256];
        for p in 0..1024u32 {
            let seed = pixel_seed(9, p);
            for i in 0..64 {
                let s = SamplerKind::Independent.address(i);
                let (u, v) = (sample_1d(seed, s, a), sample_1d(seed, s, b));
                bins[(v * 16.0) as usize * 16 + (u * 16.0) as usize] += 1;
            }
        }
        let x2 = chi_square(&bins);
        assert!(x2 < chi_square_bound(255.0), "dims ({a}, {b}): chi2 {x2}");
    }
}

#[test]
fn dimensions_and_samples_are_decorrelated() {
    // Pearson correlation of neighbouring dimensions and of neighbouring samples of
    // one dimension: for n independent pairs its standard deviation is 1/sqrt(n).
    let n = 1 << 16;
    let corr = |f: &dyn Fn(u32) -> (f32, f32)| {
        let (mut sx, mut sy, mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for i in 0..n {
            let (x, y) = f(i);
            let (x, y) = (x as f64, y as f64);
            (sx, sy, sxx, syy, sxy) = (sx + x, sy + y, sxx + x * x, syy + y * y, sxy + x * y);
        }
        let nf = n as f64;
        let cov = sxy / nf - sx * sy / nf / nf;
        cov / ((sxx / nf - (sx / nf).powi(2)) * (syy / nf - (sy / nf).powi(2))).sqrt()
    };
    let bound = 5.0 / (n as f64).sqrt();
    let seed = pixel_seed(1, 2);
    for d in [0u32, 1, 3, 4, 100] {
        let c = corr(&|i| {
            let s = SamplerKind::Independent.address(i);
            (sample_1d(seed, s, d), sample_1d(seed, s, d + 1))
        });
        assert!(
            c.abs() < bound,
            "dimensions {d}, {}: correlation {c}",
            d + 1
        );
        let c = corr(&|i| {
            let s = SamplerKind::Independent.address(i);
            let t = SamplerKind::Independent.address(i + 1);
            (sample_1d(seed, s, d), sample_1d(seed, t, d))
        });
        assert!(c.abs() < bound, "samples of dimension {d}: correlation {c}");
        let c = corr(&|p| {
            let s = SamplerKind::Independent.address(0);
            (
                sample_1d(pixel_seed(4, p), s, d),
                sample_1d(pixel_seed(4, p + 1), s, d),
            )
        });
        assert!(c.abs() < bound, "pixels, dimension {d}: correlation {c}");
    }
}

#[test]
fn independent_draws_are_not_stratified_like_sobol() {
    // The first 64 Sobol points put one point in each 1/64 stratum; independent points
    // leave about 64 / e of them empty. This is what the bit switches.
    let seed = pixel_seed(7, 123);
    let empty = |kind: SamplerKind| {
        let mut strata = [false; 64];
        for i in 0..64 {
            let v = crate::sampler::sample_1d(seed, kind.address(i), 5);
            strata[(v * 64.0) as usize] = true;
        }
        strata.iter().filter(|&&s| !s).count()
    };
    assert_eq!(empty(SamplerKind::Sobol), 0);
    assert!(empty(SamplerKind::Independent) > 10);
}

#[test]
fn every_draw_function_honours_the_sampler_kind() {
    // The scalar, PathSampler and column functions of `sampler` all give this module's
    // values for independent addresses (aligned and unaligned dimensions).
    let mut rng = SplitMix64(5);
    for n in [0usize, 1, 5, 8, 13, 33] {
        let samplers: Vec<PathSampler> = (0..n)
            .map(|i| {
                independent(
                    rng.next_u64() as u32,
                    rng.next_u64() as u32 % 1024,
                    4 * (i as u32 % 7) + [0, 0, 1, 3][i % 4],
                )
            })
            .collect();
        let mut col = samplers.clone();
        let (mut out4, mut out2) = (vec![[0.0f32; 4]; n], vec![Vec2::ZERO; n]);
        next_4d_column(&mut col, &mut out4);
        next_2d_column(&mut col, &mut out2);
        for (i, s) in samplers.iter().enumerate() {
            assert_eq!(s.kind(), SamplerKind::Independent);
            let d = s.dimension;
            let want4: [f32; 4] =
                std::array::from_fn(|k| sample_1d(s.seed, s.sample, d + k as u32));
            let want2 = sample_2d(s.seed, s.sample, d + 4);
            assert_eq!(out4[i], want4, "n {n}, point {i}");
            assert_eq!(out2[i], want2, "n {n}, point {i}");
            assert_eq!(col[i].dimension, d + 6);
            let mut one = *s;
            assert_eq!(one.next_4d(), want4);
            assert_eq!(one.next_2d(), want2);
            assert_eq!(one.next_1d(), sample_1d(s.seed, s.sample, d + 6));
            if d % 4 == 0 {
                assert_eq!(crate::sampler::sample_4d(s.seed, s.sample, d / 4), want4);
                assert_eq!(sample_4d(s.seed, s.sample, d / 4), want4);
            }
        }
        let seed: Vec<u32> = samplers.iter().map(|s| s.seed).collect();
        let sample: Vec<u32> = samplers.iter().map(|s| s.sample).collect();
        let mut jitter = vec![Vec2::ZERO; n];
        first_2d_column(&seed, &sample, &mut jitter);
        for i in 0..n {
            assert_eq!(jitter[i], sample_2d(seed[i], sample[i], 0));
            assert_eq!(crate::sampler::sample_2d(seed[i], sample[i], 0), jitter[i]);
        }
    }
}

#[test]
fn addresses_keep_the_index_and_the_kind() {
    for i in [0u32, 1, 255, crate::sampler::MAX_SPP - 1] {
        assert_eq!(
            SamplerKind::of(SamplerKind::Sobol.address(i)),
            SamplerKind::Sobol
        );
        let a = SamplerKind::Independent.address(i);
        assert_eq!(SamplerKind::of(a), SamplerKind::Independent);
        assert_eq!(a & !INDEPENDENT_BIT, i);
    }
    let r = SamplerKind::Independent.addresses(2..6);
    assert_eq!(r.len(), 4);
    assert!(r
        .clone()
        .all(|a| SamplerKind::of(a) == SamplerKind::Independent));
}
