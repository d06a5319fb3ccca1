//! SplitMix64 (Steele, Lea and Flood 2014): the 64-bit mix that both samplers hash with
//! ([`crate::sampler`]'s seeds, [`crate::independent_sampler`]'s draws) and the small
//! generator built on it. Below both samplers; [`crate::sampler`] re-exports
//! [`SplitMix64`] at its old path.

use glam::Vec2;

/// The SplitMix64 increment (the 64-bit golden ratio).
pub(crate) const GOLDEN_GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// The SplitMix64 output function (Steele, Lea and Flood 2014): a bijective 64-bit mix.
#[inline]
pub(crate) fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// SplitMix64 (Steele, Lea and Flood 2014, "Fast splittable pseudorandom number
/// generators"): a tiny deterministic generator for reproducible test inputs and bench data.
/// Rendering uses the samplers ([`crate::sampler`]), except for the tails of random walks inside dense
/// media (`risotto_engine::random_walk`), where no sampler keeps its stratification.
#[derive(Clone, Debug)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(GOLDEN_GAMMA);
        mix64(self.0)
    }
    /// Uniform in `[0, 1)` with 24 random bits (every multiple of 2^-24 is reachable).
    #[inline]
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }
    /// Two uniform numbers in `[0, 1)`.
    #[inline]
    pub fn vec2(&mut self) -> Vec2 {
        Vec2::new(self.f32(), self.f32())
    }
}

/// A 64-bit seed from the bits of `values` (each folded in with the SplitMix64 output function): the same numbers
/// give the same seed, nearby ones unrelated seeds. What a stochastic Bxdf seeds its
/// [`SplitMix64`] with from the directions it is asked about (pbrt-v4 seeds its layered
/// BxDF's RNG from `Hash(wo)` and `Hash(wi)` the same way), so evaluating one pair twice
/// gives the same value.
pub fn seed_from(values: &[f32]) -> u64 {
    values.iter().fold(GOLDEN_GAMMA, |h, v| {
        mix64(h ^ u64::from(v.to_bits()).wrapping_mul(GOLDEN_GAMMA))
    })
}
