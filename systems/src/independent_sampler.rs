//! The independent sampler: every `(pixel seed, sample index, dimension)` gets its own
//! uniform random number, a hash of the three, with no stratification between samples or
//! dimensions. It is the baseline that stratified samplers are measured against (pbrt-v4's
//! `IndependentSampler`, Mitsuba's `independent`), registered as the technique
//! `sampler = independent`.
//!
//! Which sampler a point uses travels with its sample index: a sample index with
//! [`INDEPENDENT_BIT`] set addresses the independent sampler ([`SamplerKind::address`]).
//! The Sobol sampler only reads the low 16 bits of the index (`MAX_SPP` = 2^16 points), so the
//! bit leaves every Sobol draw, and the 12-byte `PathSampler` layout the AVX2 column kernels
//! load, exactly as they were; every draw function of [`crate::sampler`], scalar and column,
//! dispatches on the bit (a column on its first sampler: one branch per column).
//!
//! The hash is SplitMix64 (Steele, Lea and Flood 2014) used as a counter-based generator:
//! `key = mix64(seed << 32 | index)` picks a stream per pixel sample and dimension `d` is
//! its output `mix64(key + (d + 1) * golden gamma)`. It is deterministic and does not depend
//! on threads or batches, like the Sobol sampler.

use crate::splitmix::{mix64, GOLDEN_GAMMA};
use glam::Vec2;
use std::ops::Range;

/// The bit of a sample index that selects the independent sampler (see the module docs).
pub const INDEPENDENT_BIT: u32 = 1 << 31;

/// Which sampler draws a path's numbers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SamplerKind {
    /// Padded Owen-scrambled Sobol ([`crate::sampler`]).
    #[default]
    Sobol,
    /// Independent uniform random numbers (this module).
    Independent,
}

impl SamplerKind {
    /// The sampler that the sample address `sample` (a `PathSampler::sample`) uses.
    #[inline(always)]
    pub fn of(sample: u32) -> Self {
        if sample & INDEPENDENT_BIT != 0 {
            SamplerKind::Independent
        } else {
            SamplerKind::Sobol
        }
    }

    /// The address of sample index `index` (below `MAX_SPP`) with this sampler: what goes in
    /// `PathSampler::sample` and the path table's sample column.
    #[inline]
    pub fn address(self, index: u32) -> u32 {
        match self {
            SamplerKind::Sobol => index,
            SamplerKind::Independent => index | INDEPENDENT_BIT,
        }
    }

    /// The addresses of the sample indices `indices`, as the range the renderer's
    /// `render_tile` takes.
    pub fn addresses(self, indices: Range<u32>) -> Range<u32> {
        self.address(indices.start)..self.address(indices.end)
    }
}

/// The stream of one pixel sample.
#[inline(always)]
fn key(seed: u32, sample: u32) -> u64 {
    mix64(((seed as u64) << 32) | (sample & !INDEPENDENT_BIT) as u64)
}

/// Dimension `dimension` of the stream `key`, uniform in `[0, 1)` with 24 random bits.
#[inline(always)]
fn draw(key: u64, dimension: u32) -> f32 {
    let bits = mix64(key.wrapping_add((dimension as u64 + 1).wrapping_mul(GOLDEN_GAMMA)));
    (bits >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// One dimension.
#[inline]
pub fn sample_1d(seed: u32, sample: u32, dimension: u32) -> f32 {
    draw(key(seed, sample), dimension)
}

/// Dimensions `dimension` and `dimension + 1`.
#[inline]
pub fn sample_2d(seed: u32, sample: u32, dimension: u32) -> Vec2 {
    let k = key(seed, sample);
    Vec2::new(draw(k, dimension), draw(k, dimension.wrapping_add(1)))
}

/// Dimensions `4 set .. 4 set + 4`.
#[inline]
pub fn sample_4d(seed: u32, sample: u32, set: u32) -> [f32; 4] {
    let k = key(seed, sample);
    let d = set.wrapping_mul(4);
    std::array::from_fn(|i| draw(k, d.wrapping_add(i as u32)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::PathSampler;
    use crate::sampler::{first_2d_column, next_2d_column, next_4d_column, pixel_seed, SplitMix64};

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
}
