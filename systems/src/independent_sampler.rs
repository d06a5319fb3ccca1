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
