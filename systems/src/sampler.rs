//! Owen-scrambled Sobol samples (Burley, "Practical Hash-based Owen Scrambling", JCGT 2020),
//! through the `sobol_burley` crate.
//!
//! A sample is addressed by `(pixel seed, sample index, dimension)`: it does not depend on
//! which thread renders it or in which batch, so the same seed gives the same image for any
//! thread count. Each path consumes dimensions in a fixed order (the ray's `dimension` column).
//!
//! Dimensions come in sets of four, and every set is the first four dimensions of its own
//! Owen-scrambled Sobol sequence, seeded by `(pixel seed, set)` ("padding", Burley 2020,
//! sec. 4; pbrt-v4's `PaddedSobolSampler` does the same for 1D/2D): each set keeps the
//! excellent 4D stratification of Sobol's first dimensions, and sets are independent of
//! each other. Using Sobol dimensions 4, 5, ... of one sequence instead correlates some pairs
//! of them (measured: the `glass_beer` reference error at 256 spp moved between 0.0096 and
//! 0.0116 depending only on which dimensions the path started at). Any number of dimensions
//! is available.
//!
//! A sample index with [`independent::INDEPENDENT_BIT`] set addresses the independent sampler
//! instead (`crate::independent_sampler`): every draw function here dispatches on it.

use crate::independent_sampler::{self as independent, SamplerKind};
use glam::Vec2;

/// Largest supported samples per pixel (the Sobol tables of `sobol_burley` hold 2^16 points).
pub const MAX_SPP: u32 = 1 << 16;

/// The SplitMix64 increment (the 64-bit golden ratio).
pub(crate) const GOLDEN_GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// The SplitMix64 output function (Steele, Lea and Flood 2014): a bijective 64-bit mix.
#[inline]
pub(crate) fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Mixes the render seed and a pixel index into a per-pixel scrambling seed.
pub fn pixel_seed(render_seed: u64, pixel: u32) -> u32 {
    mix64(
        render_seed
            .wrapping_add(GOLDEN_GAMMA)
            .wrapping_add((pixel as u64).wrapping_mul(0xD1B5_4A32_D192_ED03)),
    ) as u32
}

/// SplitMix64 (Steele, Lea and Flood 2014, "Fast splittable pseudorandom number
/// generators"): a tiny deterministic generator for reproducible test inputs and bench data.
/// Rendering uses the samplers above, never this.
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

/// The scrambling seed of the 4-dimension set `set` of a pixel's sequence.
#[inline(always)]
fn set_seed(seed: u32, set: u32) -> u32 {
    if set == 0 {
        seed
    } else {
        pixel_seed(seed as u64, set)
    }
}

/// One sample dimension in [0, 1).
#[inline]
pub fn sample_1d(seed: u32, sample: u32, dimension: u32) -> f32 {
    if SamplerKind::of(sample) == SamplerKind::Independent {
        return independent::sample_1d(seed, sample, dimension);
    }
    sample_4d(seed, sample, dimension / 4)[(dimension % 4) as usize]
}

/// The four dimensions `4 * set .. 4 * set + 4` at once: the first four dimensions of the
/// set's own Owen-scrambled Sobol sequence, bit for bit `sobol_burley::sample_4d(sample, 0,
/// seed of the set)` (tested), about four times faster.
///
/// `sobol_burley` evaluates the Sobol matrix-vector product bit by bit (a loop over the set
/// bits of the scrambled index, whose exit mispredicts); only 16 index bits matter and only
/// dimensions 0..4 are used here, so the product is two lookups in per-byte tables of XORed
/// direction vectors (linearity over GF(2)), built once from `sobol_burley::parts`. Index
/// shuffle and Owen scramble follow the crate's `sample_4d` (Burley 2020, sec. 3-4) through
/// the same public `parts` functions.
#[inline]
pub fn sample_4d(seed: u32, sample: u32, set: u32) -> [f32; 4] {
    if SamplerKind::of(sample) == SamplerKind::Independent {
        return independent::sample_4d(seed, sample, set);
    }
    use sobol_burley::parts::{hash, hash_int4, owen_scramble_int4_rev, owen_scramble_rev, Int4};
    let seed = set_seed(seed, set);
    let index_rev = owen_scramble_rev((sample % MAX_SPP).reverse_bits(), hash(seed ^ 0x79c6_8e4a));
    let table = sobol_byte_table();
    let high: Int4 = table[0][(index_rev >> 24) as usize].into();
    let low: Int4 = table[1][((index_rev >> 16) & 0xff) as usize].into();
    let scramble: Int4 = {
        let s: Int4 = [seed.wrapping_mul(0x9c8f_2d3b); 4].into();
        s ^ [0x912f_69ba, 0x174f_18ab, 0x691e_72ca, 0xb40c_c1b8].into()
    };
    owen_scramble_int4_rev(high ^ low, hash_int4(scramble))
        .reverse_bits()
        .to_f32_norm()
}

/// The type of [`sobol_byte_table`].
type SobolTable = [[[u32; 4]; 256]; 2];

/// Per-byte Sobol products of dimensions 0..4: `table[b][v]` is the bit-reversed Sobol value
/// of the reversed index whose byte `b` (0 = bits 31..24, 1 = bits 23..16) is `v` and whose
/// other bits are zero.
fn sobol_byte_table() -> &'static SobolTable {
    static TABLE: std::sync::OnceLock<Box<SobolTable>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let mut t: Box<SobolTable> = Box::new([[[0u32; 4]; 256]; 2]);
        for (b, bytes) in t.iter_mut().enumerate() {
            for (v, entry) in bytes.iter_mut().enumerate() {
                *entry = sobol_burley::parts::sobol_int4_rev((v as u32) << (24 - 8 * b), 0).into();
            }
        }
        t
    })
}

/// Two consecutive sample dimensions (`dimension`, `dimension + 1`) in [0, 1)^2.
#[inline]
pub fn sample_2d(seed: u32, sample: u32, dimension: u32) -> Vec2 {
    if SamplerKind::of(sample) == SamplerKind::Independent {
        return independent::sample_2d(seed, sample, dimension);
    }
    if dimension % 4 <= 2 {
        // Both dimensions lie in one aligned set of four.
        let v = sample_4d(seed, sample, dimension / 4);
        let k = (dimension % 4) as usize;
        Vec2::new(v[k], v[k + 1])
    } else {
        Vec2::new(
            sample_1d(seed, sample, dimension),
            sample_1d(seed, sample, dimension + 1),
        )
    }
}

/// Points evaluated together by the column functions ([`next_4d_column`],
/// [`next_2d_column`]): one SSE vector of `u32` lanes.
const LANES: usize = 4;

/// Salts of the four dimensions' Owen scrambles (as in `sobol_burley::sample_4d`).
const DIM_SALT: [u32; 4] = [0x912f_69ba, 0x174f_18ab, 0x691e_72ca, 0xb40c_c1b8];

/// The per-point part of [`sample_4d`] for `LANES` points whose next dimension starts an
/// aligned set: each point's shuffled (reversed) sample index split into the two table
/// bytes, and its set seed times the scramble multiplier. Only the set seed's 64-bit
/// SplitMix stays scalar (SSE has no 64-bit multiply); the rest is four-wide where
/// [`sample_4d`] is scalar. `None` when some point is not at the start of a set.
#[inline(always)]
fn lanes_prefix(
    lanes: &[PathSampler; LANES],
) -> Option<([u32; LANES], [u32; LANES], [u32; LANES])> {
    use sobol_burley::parts::{hash_int4, owen_scramble_int4_rev, Int4};
    if lanes.iter().any(|s| s.dimension % 4 != 0) {
        return None;
    }
    let mut seed = [0u32; LANES];
    let mut sample = [0u32; LANES];
    for l in 0..LANES {
        seed[l] = set_seed(lanes[l].seed, lanes[l].dimension / 4);
        sample[l] = lanes[l].sample;
    }
    let s = Int4::from(seed);
    let index = Int4::from(sample) & Int4::from([MAX_SPP - 1; LANES]);
    let index_rev = owen_scramble_int4_rev(
        index.reverse_bits(),
        hash_int4(s ^ Int4::from([0x79c6_8e4a; LANES])),
    );
    let high: [u32; LANES] = (index_rev >> 24).into();
    let low: [u32; LANES] = ((index_rev >> 16) & Int4::from([0xff; LANES])).into();
    let seed_mul: [u32; LANES] = (s * Int4::from([0x9c8f_2d3b; LANES])).into();
    Some((high, low, seed_mul))
}

/// The Owen scramble and float conversion of [`sample_4d`] on four lanes, each lane one
/// (point, dimension) pair: `sobol` the unscrambled reversed Sobol values, `seed_mul` the
/// point's set seed times the scramble multiplier, `salt` the dimension's salt.
#[inline(always)]
fn scramble_lanes(sobol: [u32; 4], seed_mul: [u32; 4], salt: [u32; 4]) -> [f32; 4] {
    use sobol_burley::parts::{hash_int4, owen_scramble_int4_rev, Int4};
    let scramble = hash_int4(Int4::from(seed_mul) ^ Int4::from(salt));
    owen_scramble_int4_rev(Int4::from(sobol), scramble)
        .reverse_bits()
        .to_f32_norm()
}

/// Four dimensions of `LANES` points into `out` (lanes: one point per vector, its four
/// dimensions); false (and `out` untouched) unless every point starts a set.
#[inline(always)]
fn kernel_4d(
    table: &SobolTable,
    lanes: &[PathSampler; LANES],
    out: &mut [[f32; 4]; LANES],
) -> bool {
    let Some((high, low, seed_mul)) = lanes_prefix(lanes) else {
        return false;
    };
    for l in 0..LANES {
        let (h, w) = (&table[0][high[l] as usize], &table[1][low[l] as usize]);
        let sobol = [h[0] ^ w[0], h[1] ^ w[1], h[2] ^ w[2], h[3] ^ w[3]];
        out[l] = scramble_lanes(sobol, [seed_mul[l]; 4], DIM_SALT);
    }
    true
}

/// Two dimensions of `LANES` points into `out` (lanes: two points per vector, only the two
/// dimensions they use); false (and `out` untouched) unless every point starts a set.
#[inline(always)]
fn kernel_2d(table: &SobolTable, lanes: &[PathSampler; LANES], out: &mut [Vec2; LANES]) -> bool {
    let Some((high, low, seed_mul)) = lanes_prefix(lanes) else {
        return false;
    };
    let sobol = |l: usize, d: usize| table[0][high[l] as usize][d] ^ table[1][low[l] as usize][d];
    let salt = [DIM_SALT[0], DIM_SALT[1], DIM_SALT[0], DIM_SALT[1]];
    for a in [0, 2] {
        let b = a + 1;
        let r = scramble_lanes(
            [sobol(a, 0), sobol(a, 1), sobol(b, 0), sobol(b, 1)],
            [seed_mul[a], seed_mul[a], seed_mul[b], seed_mul[b]],
            salt,
        );
        out[a] = Vec2::new(r[0], r[1]);
        out[b] = Vec2::new(r[2], r[3]);
    }
    true
}

/// Runs `chunk` on every group of `LANES` samplers (the last group padded with copies of
/// its first sampler, whose results are dropped) together with the matching rows of `out`; `chunk` returns false when it could not handle the group, which then goes
/// through `single` one sampler at a time. Neither advances the samplers.
#[inline(always)]
fn for_lane_groups<T: Copy>(
    samplers: &[PathSampler],
    out: &mut [T],
    table: &SobolTable,
    chunk: impl Fn(&SobolTable, &[PathSampler; LANES], &mut [T; LANES]) -> bool,
    single: impl Fn(&PathSampler) -> T,
) {
    let (lanes, rest) = samplers.as_chunks::<LANES>();
    let (rows, rest_out) = out.as_chunks_mut::<LANES>();
    for (s, o) in lanes.iter().zip(rows) {
        if !chunk(table, s, o) {
            o.iter_mut().zip(s).for_each(|(o, s)| *o = single(s));
        }
    }
    if let Some(&first) = rest.first() {
        let mut s = [first; LANES];
        s[..rest.len()].copy_from_slice(rest);
        let mut o = [rest_out[0]; LANES];
        if chunk(table, &s, &mut o) {
            rest_out.copy_from_slice(&o[..rest_out.len()]);
        } else {
            rest_out
                .iter_mut()
                .zip(rest)
                .for_each(|(o, s)| *o = single(s));
        }
    }
}

/// [`PathSampler::next_4d`] for a column of samplers: `out[i]` gets sampler `i`'s next four
/// dimensions and every sampler advances by four. Exactly the per-sampler values; groups
/// of four points whose dimensions are aligned sets (the renderer's vertices always are)
/// are evaluated together by a vectorised kernel.
///
/// # Panics
/// When `out` and `samplers` differ in length.
pub fn next_4d_column(samplers: &mut [PathSampler], out: &mut [[f32; 4]]) {
    assert_eq!(samplers.len(), out.len(), "next_4d_column: column lengths");
    if first_is_independent(samplers) {
        return independent_column(samplers, out, |s| s.next_4d());
    }
    column_draws(
        samplers,
        out,
        4,
        #[cfg(target_arch = "x86_64")]
        [avx2::column_4d_dq, avx2::column_4d],
        kernel_4d,
        |&s| {
            let mut s = s;
            s.next_4d()
        },
    );
}

/// [`PathSampler::next_2d`] for a column of samplers: `out[i]` gets sampler `i`'s next two
/// dimensions and every sampler advances by two. Exactly the per-sampler values; groups of
/// four points that all start a set (as Bxdf sampling does at every vertex) are evaluated
/// together, computing only the two dimensions they use.
///
/// # Panics
/// When `out` and `samplers` differ in length.
pub fn next_2d_column(samplers: &mut [PathSampler], out: &mut [Vec2]) {
    assert_eq!(samplers.len(), out.len(), "next_2d_column: column lengths");
    if first_is_independent(samplers) {
        return independent_column(samplers, out, |s| s.next_2d());
    }
    column_draws(
        samplers,
        out,
        2,
        #[cfg(target_arch = "x86_64")]
        [avx2::column_2d_dq, avx2::column_2d],
        kernel_2d,
        |&s| {
            let mut s = s;
            s.next_2d()
        },
    );
}

/// Whether a column's first sampler addresses the independent sampler: a column is one
/// sampler kind (one render's paths), so this one branch per call picks its path.
#[inline(always)]
fn first_is_independent(samplers: &[PathSampler]) -> bool {
    samplers
        .first()
        .is_some_and(|s| s.kind() == SamplerKind::Independent)
}

/// The independent sampler's column draws: each sampler's own draw (`single`, which
/// dispatches per sampler, so a mixed column still gets each sampler's values), advancing it.
#[cold]
fn independent_column<T>(
    samplers: &mut [PathSampler],
    out: &mut [T],
    single: impl Fn(&mut PathSampler) -> T,
) {
    for (o, s) in out.iter_mut().zip(samplers.iter_mut()) {
        *o = single(s);
    }
}

/// An AVX2 column kernel of the sampler (`avx2::column_*`): the draws of a column without
/// advancing the samplers; unsafe because its CPU features must have been detected.
#[cfg(target_arch = "x86_64")]
type ColumnDraws<T> = unsafe fn(&SobolTable, &[PathSampler], &mut [T]);

/// The body of [`next_4d_column`] and [`next_2d_column`]: the draws of `dims` dimensions
/// into `out` by the AVX2 kernels where the CPU has AVX2 (`avx2_draws[0]` with AVX-512 DQ,
/// else `avx2_draws[1]`), else by the four-lane `kernel` (`single` for groups it cannot
/// take), then every sampler advanced by `dims` (the kernels leave them alone).
#[inline(always)]
fn column_draws<T: Copy>(
    samplers: &mut [PathSampler],
    out: &mut [T],
    dims: u32,
    #[cfg(target_arch = "x86_64")] avx2_draws: [ColumnDraws<T>; 2],
    kernel: impl Fn(&SobolTable, &[PathSampler; LANES], &mut [T; LANES]) -> bool,
    single: impl Fn(&PathSampler) -> T,
) {
    debug_assert!(
        samplers.iter().all(|s| s.kind() == SamplerKind::Sobol),
        "a column mixes Sobol and independent samplers"
    );
    let table = sobol_byte_table();
    #[cfg(target_arch = "x86_64")]
    let done = avx2::detected() && {
        let draws = avx2_draws[if avx2::detected_dq() { 0 } else { 1 }];
        // SAFETY: `avx2::detected_dq` found AVX2, AVX-512 F, DQ and VL for `avx2_draws[0]`,
        // `avx2::detected` found AVX2 for `avx2_draws[1]`.
        #[allow(unsafe_code, reason = "AVX2 dispatch after run-time detection")]
        unsafe {
            draws(table, samplers, out)
        };
        true
    };
    #[cfg(not(target_arch = "x86_64"))]
    let done = false;
    if !done {
        for_lane_groups(samplers, out, table, kernel, single);
    }
    for s in samplers.iter_mut() {
        s.dimension += dims;
    }
}

/// Dimensions 0 and 1 (set 0) of `(seed[i], sample[i])` into `out[i]`: exactly
/// `sample_2d(seed[i], sample[i], 0)` (the camera jitter), eight points per AVX2 kernel call
/// where the CPU has AVX2.
///
/// # Panics
/// When the three columns differ in length.
pub fn first_2d_column(seed: &[u32], sample: &[u32], out: &mut [Vec2]) {
    assert_eq!(seed.len(), out.len(), "first_2d_column: column lengths");
    assert_eq!(sample.len(), out.len(), "first_2d_column: column lengths");
    if sample
        .first()
        .is_some_and(|&s| SamplerKind::of(s) == SamplerKind::Independent)
    {
        for ((o, &seed), &sample) in out.iter_mut().zip(seed).zip(sample) {
            *o = sample_2d(seed, sample, 0);
        }
        return;
    }
    #[cfg(target_arch = "x86_64")]
    if avx2::detected() {
        // SAFETY: `avx2::detected` found AVX2 on this CPU.
        #[allow(unsafe_code, reason = "AVX2 dispatch after run-time detection")]
        unsafe {
            avx2::first_2d(sobol_byte_table(), seed, sample, out)
        };
        return;
    }
    for ((o, &seed), &sample) in out.iter_mut().zip(seed).zip(sample) {
        *o = sample_2d(seed, sample, 0);
    }
}

/// The column kernels on eight points per call with AVX2 (one 256-bit vector holds two
/// points' four dimensions or four points' two dimensions), including the set seeds'
/// SplitMix64 (AVX2's `vpmuludq` gives the 32x32->64-bit products a 64-bit multiply is made
/// of). Same arithmetic as [`sample_4d`], so the same bits.
#[cfg(target_arch = "x86_64")]
#[allow(
    unsafe_code,
    reason = "AVX2 intrinsics: loads and stores of references' memory, and the calls into \
              `#[target_feature]` functions, reached only after `detected`"
)]
mod avx2 {
    use super::{PathSampler, SobolTable, DIM_SALT, GOLDEN_GAMMA, MAX_SPP};
    use glam::Vec2;
    use std::arch::x86_64::*;

    /// Points per kernel call.
    const N: usize = 8;

    /// Whether this CPU has AVX2 (cached by the standard library after the first call).
    #[inline]
    pub(super) fn detected() -> bool {
        is_x86_feature_detected!("avx2")
    }

    /// All lanes `x`.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn splat(x: u32) -> __m256i {
        _mm256_set1_epi32(x as i32)
    }

    /// `sobol_burley::parts::hash_int4` on eight lanes.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn hash(mut n: __m256i) -> __m256i {
        n = _mm256_xor_si256(n, splat(0xe6fe_3beb));
        n = _mm256_xor_si256(n, _mm256_srli_epi32::<16>(n));
        n = _mm256_mullo_epi32(n, splat(0x7feb_352d));
        n = _mm256_xor_si256(n, _mm256_srli_epi32::<15>(n));
        n = _mm256_mullo_epi32(n, splat(0x846c_a68b));
        _mm256_xor_si256(n, _mm256_srli_epi32::<16>(n))
    }

    /// `sobol_burley::parts::owen_scramble_int4_rev` on eight lanes.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn owen(mut n: __m256i, scramble: __m256i) -> __m256i {
        n = _mm256_xor_si256(n, _mm256_mullo_epi32(n, splat(0x3d20_adea)));
        n = _mm256_add_epi32(n, scramble);
        let m = _mm256_or_si256(_mm256_srli_epi32::<16>(scramble), splat(1));
        n = _mm256_mullo_epi32(n, m);
        n = _mm256_xor_si256(n, _mm256_mullo_epi32(n, splat(0x0552_6c56)));
        _mm256_xor_si256(n, _mm256_mullo_epi32(n, splat(0x53a2_2864)))
    }

    /// `u32::reverse_bits` on eight lanes: each byte's two nibbles through a 16-entry
    /// table (`vpshufb`), then the bytes of each lane in reverse order.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn reverse_bits(n: __m256i) -> __m256i {
        const REV: [i8; 16] = [0, 8, 4, 12, 2, 10, 6, 14, 1, 9, 5, 13, 3, 11, 7, 15];
        const fn shifted() -> [i8; 16] {
            let mut t = [0i8; 16];
            let mut i = 0;
            while i < 16 {
                t[i] = ((REV[i] as u8) << 4) as i8;
                i += 1;
            }
            t
        }
        const REV_HI: [i8; 16] = shifted();
        let rev = _mm256_broadcastsi128_si256(_mm_setr_epi8(
            REV[0], REV[1], REV[2], REV[3], REV[4], REV[5], REV[6], REV[7], REV[8], REV[9],
            REV[10], REV[11], REV[12], REV[13], REV[14], REV[15],
        ));
        let rev_hi = _mm256_broadcastsi128_si256(_mm_setr_epi8(
            REV_HI[0], REV_HI[1], REV_HI[2], REV_HI[3], REV_HI[4], REV_HI[5], REV_HI[6], REV_HI[7],
            REV_HI[8], REV_HI[9], REV_HI[10], REV_HI[11], REV_HI[12], REV_HI[13], REV_HI[14],
            REV_HI[15],
        ));
        let nibble = _mm256_set1_epi8(0x0f);
        let lo = _mm256_and_si256(n, nibble);
        let hi = _mm256_and_si256(_mm256_srli_epi16::<4>(n), nibble);
        // Reversed byte: the low nibble reversed into the high half, and vice versa.
        let bytes = _mm256_or_si256(
            _mm256_shuffle_epi8(rev_hi, lo),
            _mm256_shuffle_epi8(rev, hi),
        );
        let order = _mm256_setr_epi8(
            3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12, 3, 2, 1, 0, 7, 6, 5, 4, 11, 10,
            9, 8, 15, 14, 13, 12,
        );
        _mm256_shuffle_epi8(bytes, order)
    }

    /// `Int4::to_f32_norm` on eight lanes: the top 23 bits as a float in [0, 1).
    #[target_feature(enable = "avx2")]
    #[inline]
    fn to_f32_norm(n: __m256i) -> __m256 {
        let one_bits = _mm256_or_si256(_mm256_srli_epi32::<9>(n), splat(0x3f80_0000));
        _mm256_sub_ps(_mm256_castsi256_ps(one_bits), _mm256_set1_ps(1.0))
    }

    /// Wrapping `a * c` on four u64 lanes from 32x32->64-bit products (the `hi * hi` term
    /// falls out of the low 64 bits).
    #[target_feature(enable = "avx2")]
    #[inline]
    fn mul64(a: __m256i, c: u64) -> __m256i {
        let c_lo = _mm256_set1_epi64x((c & 0xffff_ffff) as i64);
        let c_hi = _mm256_set1_epi64x((c >> 32) as i64);
        let cross = _mm256_add_epi64(
            _mm256_mul_epu32(_mm256_srli_epi64::<32>(a), c_lo),
            _mm256_mul_epu32(a, c_hi),
        );
        _mm256_add_epi64(_mm256_mul_epu32(a, c_lo), _mm256_slli_epi64::<32>(cross))
    }

    /// Defines `$name(seed, set)`: `set_seed(seed, set)` on eight lanes, compiled with
    /// `$features`, with `$mul(a, c)` the wrapping product of the u64 lanes of `a` by `c`.
    /// One body for the AVX2 build ([`mul64`]) and the AVX-512 DQ one (one `vpmullq`, the
    /// same bits); a macro rather than a shared function taking `mul`, so that each
    /// product is compiled, and inlined, with its own target features.
    macro_rules! set_seeds_fn {
        ($name:ident, $features:literal, $mul:expr) => {
            #[target_feature(enable = $features)]
            #[inline]
            fn $name(seed: __m256i, set: __m256i) -> __m256i {
                let mul = $mul;
                // The low 32 bits of `pixel_seed(seed, set)` on four u64 lanes holding
                // u32 values.
                let pixel_seed4 = |seed: __m256i, set: __m256i| {
                    let mut z = _mm256_add_epi64(
                        _mm256_add_epi64(seed, _mm256_set1_epi64x(GOLDEN_GAMMA as i64)),
                        mul(set, 0xD1B5_4A32_D192_ED03),
                    );
                    // mix64 (SplitMix64's output function).
                    z = mul(
                        _mm256_xor_si256(z, _mm256_srli_epi64::<30>(z)),
                        0xBF58_476D_1CE4_E5B9,
                    );
                    z = mul(
                        _mm256_xor_si256(z, _mm256_srli_epi64::<27>(z)),
                        0x94D0_49BB_1331_11EB,
                    );
                    _mm256_xor_si256(z, _mm256_srli_epi64::<31>(z))
                };
                let widen = |v: __m128i| _mm256_cvtepu32_epi64(v);
                let (s_lo, s_hi) = (
                    _mm256_castsi256_si128(seed),
                    _mm256_extracti128_si256::<1>(seed),
                );
                let (t_lo, t_hi) = (
                    _mm256_castsi256_si128(set),
                    _mm256_extracti128_si256::<1>(set),
                );
                let a = pixel_seed4(widen(s_lo), widen(t_lo));
                let b = pixel_seed4(widen(s_hi), widen(t_hi));
                // The low halves of a's and b's u64 lanes, back in point order.
                let packed = _mm256_castps_si256(_mm256_shuffle_ps::<0b10_00_10_00>(
                    _mm256_castsi256_ps(a),
                    _mm256_castsi256_ps(b),
                ));
                let mixed = _mm256_permute4x64_epi64::<0b11_01_10_00>(packed);
                let first = _mm256_cmpeq_epi32(set, _mm256_setzero_si256());
                _mm256_blendv_epi8(mixed, seed, first)
            }
        };
    }

    set_seeds_fn!(set_seeds, "avx2", |a, c| mul64(a, c));
    set_seeds_fn!(
        set_seeds_dq,
        "avx2,avx512f,avx512dq,avx512vl",
        |a: __m256i, c: u64| _mm256_mullo_epi64(a, _mm256_set1_epi64x(c as i64))
    );

    /// Field `K` (0 seed, 1 sample, 2 dimension) of eight `repr(C)` samplers held in three
    /// vectors: lane `i` is u32 number `3 i + K`, which lies in vector `(3 i + K) / 8` at
    /// position `(3 i + K) % 8`.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn field<const K: i32>(v: [__m256i; 3]) -> __m256i {
        let idx = _mm256_setr_epi32(K, 3 + K, 6 + K, 9 + K, 12 + K, 15 + K, 18 + K, 21 + K);
        let idx = _mm256_and_si256(idx, splat(7));
        let p = v.map(|v| _mm256_permutevar8x32_epi32(v, idx));
        // Lanes from the second and third vectors.
        let (in_b, in_c) = match K {
            0 => (0b0011_1000, 0b1100_0000),
            1 => (0b0001_1000, 0b1110_0000),
            _ => (0b0001_1100, 0b1110_0000),
        };
        let pick = |mask: i32| {
            let bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
            _mm256_cmpeq_epi32(_mm256_and_si256(bits, splat(mask as u32)), bits)
        };
        let ab = _mm256_blendv_epi8(p[0], p[1], pick(in_b));
        _mm256_blendv_epi8(ab, p[2], pick(in_c))
    }

    /// Per-point prefix of eight points: the shuffled reversed sample index (its top two
    /// bytes address the Sobol tables) and the set seed times the scramble multiplier.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn prefix(seed: __m256i, sample: __m256i) -> ([u32; N], __m256i) {
        let index = _mm256_and_si256(sample, splat(MAX_SPP - 1));
        let index_rev = owen(
            reverse_bits(index),
            hash(_mm256_xor_si256(seed, splat(0x79c6_8e4a))),
        );
        let mut idx = [0u32; N];
        // SAFETY: `idx` is 32 writable bytes.
        unsafe { _mm256_storeu_si256(idx.as_mut_ptr().cast(), index_rev) };
        (idx, _mm256_mullo_epi32(seed, splat(0x9c8f_2d3b)))
    }

    /// The Sobol table rows of a reversed shuffled index.
    #[inline(always)]
    fn rows(table: &SobolTable, index_rev: u32) -> (&[u32; 4], &[u32; 4]) {
        (
            &table[0][(index_rev >> 24) as usize],
            &table[1][((index_rev >> 16) & 0xff) as usize],
        )
    }

    /// Scramble, reverse and convert eight (point, dimension) lanes.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn finish(sobol: __m256i, seed_mul: __m256i, salt: __m256i) -> __m256 {
        let scramble = hash(_mm256_xor_si256(seed_mul, salt));
        to_f32_norm(reverse_bits(owen(sobol, scramble)))
    }

    /// Four dimensions of eight points whose set seeds and samples are given.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn kernel_4d(table: &SobolTable, seed: __m256i, sample: __m256i, out: &mut [[f32; 4]; N]) {
        let (idx, seed_mul) = prefix(seed, sample);
        let s = DIM_SALT;
        let salt = _mm256_setr_epi32(
            s[0] as i32,
            s[1] as i32,
            s[2] as i32,
            s[3] as i32,
            s[0] as i32,
            s[1] as i32,
            s[2] as i32,
            s[3] as i32,
        );
        for (p, pair) in out.as_chunks_mut::<2>().0.iter_mut().enumerate() {
            let (a, b) = (2 * p as i32, 2 * p as i32 + 1);
            let (ha, la) = rows(table, idx[2 * p]);
            let (hb, lb) = rows(table, idx[2 * p + 1]);
            // SAFETY: every row is 16 readable bytes; `pair` is 32 writable bytes.
            unsafe {
                let h = _mm256_loadu2_m128i(hb.as_ptr().cast(), ha.as_ptr().cast());
                let l = _mm256_loadu2_m128i(lb.as_ptr().cast(), la.as_ptr().cast());
                let m = _mm256_permutevar8x32_epi32(
                    seed_mul,
                    _mm256_setr_epi32(a, a, a, a, b, b, b, b),
                );
                let r = finish(_mm256_xor_si256(h, l), m, salt);
                _mm256_storeu_ps(pair.as_mut_ptr().cast(), r);
            }
        }
    }

    /// Two dimensions of eight points whose set seeds and samples are given.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn kernel_2d(table: &SobolTable, seed: __m256i, sample: __m256i, out: &mut [Vec2; N]) {
        let (idx, seed_mul) = prefix(seed, sample);
        let (s0, s1) = (DIM_SALT[0] as i32, DIM_SALT[1] as i32);
        let salt = _mm256_setr_epi32(s0, s1, s0, s1, s0, s1, s0, s1);
        // Two points' table rows (all four dimensions) in one vector.
        let two = |i: usize| {
            let (ha, la) = rows(table, idx[i]);
            let (hb, lb) = rows(table, idx[i + 1]);
            // SAFETY: every row is 16 readable bytes.
            unsafe {
                _mm256_xor_si256(
                    _mm256_loadu2_m128i(hb.as_ptr().cast(), ha.as_ptr().cast()),
                    _mm256_loadu2_m128i(lb.as_ptr().cast(), la.as_ptr().cast()),
                )
            }
        };
        for (g, quad) in out.as_chunks_mut::<4>().0.iter_mut().enumerate() {
            let i = 4 * g;
            // Dimensions 0 and 1 of points i, i+2 | i+1, i+3, then the 64-bit quarters
            // back in point order.
            let sobol = _mm256_permute4x64_epi64::<0b11_01_10_00>(_mm256_unpacklo_epi64(
                two(i),
                two(i + 2),
            ));
            let (a, b, c, d) = (i as i32, i as i32 + 1, i as i32 + 2, i as i32 + 3);
            let m =
                _mm256_permutevar8x32_epi32(seed_mul, _mm256_setr_epi32(a, a, b, b, c, c, d, d));
            let r = finish(sobol, m, salt);
            // SAFETY: `quad` is four `Vec2` (`repr(C)`, two f32 each): 32 writable bytes.
            unsafe { _mm256_storeu_ps(quad.as_mut_ptr().cast(), r) };
        }
    }

    /// Runs `f` out of line: keeps the rare unaligned path's registers and stack out of the
    /// kernel loop.
    #[cold]
    #[inline(never)]
    fn cold(f: impl FnOnce()) {
        f()
    }

    /// Seeds, samples and dimensions of eight samplers.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn load(s: &[PathSampler; N]) -> (__m256i, __m256i, __m256i) {
        let p = s.as_ptr().cast::<__m256i>();
        // SAFETY: `PathSampler` is `repr(C)` of three u32, so eight are 96 readable bytes.
        let v = unsafe {
            [
                _mm256_loadu_si256(p),
                _mm256_loadu_si256(p.add(1)),
                _mm256_loadu_si256(p.add(2)),
            ]
        };
        (field::<0>(v), field::<1>(v), field::<2>(v))
    }

    /// Runs `kernel(seed of the set, sample)` on groups of eight samplers (the last padded
    /// with copies of its first sampler) whose dimensions all start a set; other groups go
    /// through the four-lane path, `portable`.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn groups<T: Copy>(
        samplers: &[PathSampler],
        out: &mut [T],
        seeds: impl Fn(__m256i, __m256i) -> __m256i,
        kernel: impl Fn(__m256i, __m256i, &mut [T; N]),
        portable: impl Fn(&[PathSampler], &mut [T]),
    ) {
        let run = |s: &[PathSampler; N], o: &mut [T; N]| {
            let (seed, sample, dimension) = load(s);
            if _mm256_testz_si256(dimension, splat(3)) == 0 {
                cold(|| portable(s, o));
                return;
            }
            kernel(seeds(seed, _mm256_srli_epi32::<2>(dimension)), sample, o);
        };
        let (lanes, rest) = samplers.as_chunks::<N>();
        let (rows, rest_out) = out.as_chunks_mut::<N>();
        for (s, o) in lanes.iter().zip(rows) {
            run(s, o);
        }
        if let Some(&first) = rest.first() {
            // Element loops, not `copy_from_slice`: a `memcpy` call of a varying small
            // length mispredicts inside.
            let mut s = [first; N];
            for (s, &r) in s.iter_mut().zip(rest) {
                *s = r;
            }
            let mut o = [rest_out[0]; N];
            run(&s, &mut o);
            for (r, &o) in rest_out.iter_mut().zip(&o) {
                *r = o;
            }
        }
    }

    /// `next_4d_column`'s draws (without advancing the samplers), with `seeds` the set
    /// seeds ([`set_seeds`] or [`set_seeds_dq`]).
    #[target_feature(enable = "avx2")]
    #[inline]
    fn draws_4d(
        table: &SobolTable,
        samplers: &[PathSampler],
        out: &mut [[f32; 4]],
        seeds: impl Fn(__m256i, __m256i) -> __m256i,
    ) {
        groups(
            samplers,
            out,
            seeds,
            |seed, sample, o| kernel_4d(table, seed, sample, o),
            |s, o| {
                super::for_lane_groups(s, o, table, super::kernel_4d, |&s| {
                    let mut s = s;
                    s.next_4d()
                })
            },
        );
    }

    /// `next_2d_column`'s draws (without advancing the samplers), with `seeds` as in
    /// [`draws_4d`].
    #[target_feature(enable = "avx2")]
    #[inline]
    fn draws_2d(
        table: &SobolTable,
        samplers: &[PathSampler],
        out: &mut [Vec2],
        seeds: impl Fn(__m256i, __m256i) -> __m256i,
    ) {
        groups(
            samplers,
            out,
            seeds,
            |seed, sample, o| kernel_2d(table, seed, sample, o),
            |s, o| {
                super::for_lane_groups(s, o, table, super::kernel_2d, |&s| {
                    let mut s = s;
                    s.next_2d()
                })
            },
        );
    }

    /// `next_4d_column`'s draws (without advancing the samplers).
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn column_4d(
        table: &SobolTable,
        samplers: &[PathSampler],
        out: &mut [[f32; 4]],
    ) {
        draws_4d(table, samplers, out, |seed, set| set_seeds(seed, set));
    }

    /// `next_2d_column`'s draws (without advancing the samplers).
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn column_2d(table: &SobolTable, samplers: &[PathSampler], out: &mut [Vec2]) {
        draws_2d(table, samplers, out, |seed, set| set_seeds(seed, set));
    }

    /// Whether this CPU also has AVX-512 DQ and VL: 64-bit lane multiplies (`vpmullq`) on
    /// 256-bit vectors for the set seeds' SplitMix64 (cached by the standard library).
    #[inline]
    pub(super) fn detected_dq() -> bool {
        is_x86_feature_detected!("avx2")
            && is_x86_feature_detected!("avx512f")
            && is_x86_feature_detected!("avx512dq")
            && is_x86_feature_detected!("avx512vl")
    }

    /// [`column_4d`] with native 64-bit multiplies in the set seeds ([`set_seeds_dq`]: one
    /// `vpmullq` where [`mul64`] takes three 32-bit products and four shifts and adds).
    ///
    /// # Safety
    /// The CPU must have what [`detected_dq`] checks.
    #[target_feature(enable = "avx2,avx512f,avx512dq,avx512vl")]
    pub(super) unsafe fn column_4d_dq(
        table: &SobolTable,
        samplers: &[PathSampler],
        out: &mut [[f32; 4]],
    ) {
        draws_4d(table, samplers, out, |seed, set| set_seeds_dq(seed, set));
    }

    /// [`column_2d`] with native 64-bit multiplies in the set seeds (see
    /// [`column_4d_dq`]).
    ///
    /// # Safety
    /// The CPU must have what [`detected_dq`] checks.
    #[target_feature(enable = "avx2,avx512f,avx512dq,avx512vl")]
    pub(super) unsafe fn column_2d_dq(
        table: &SobolTable,
        samplers: &[PathSampler],
        out: &mut [Vec2],
    ) {
        draws_2d(table, samplers, out, |seed, set| set_seeds_dq(seed, set));
    }

    /// `first_2d_column` (set 0: the seeds are the set seeds).
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn first_2d(
        table: &SobolTable,
        seed: &[u32],
        sample: &[u32],
        out: &mut [Vec2],
    ) {
        let (seeds, seed_rest) = seed.as_chunks::<N>();
        let samples = sample.as_chunks::<N>().0;
        let (rows, rest_out) = out.as_chunks_mut::<N>();
        let ld = |v: &[u32; N]| {
            // SAFETY: `v` is 32 readable bytes.
            unsafe { _mm256_loadu_si256(v.as_ptr().cast()) }
        };
        for ((s, t), o) in seeds.iter().zip(samples).zip(rows) {
            kernel_2d(table, ld(s), ld(t), o);
        }
        if !rest_out.is_empty() {
            let n = rest_out.len();
            let start = seed.len() - n;
            let (mut s, mut t) = ([0u32; N], [0u32; N]);
            s[..n].copy_from_slice(seed_rest);
            t[..n].copy_from_slice(&sample[start..]);
            let mut o = [Vec2::ZERO; N];
            kernel_2d(table, ld(&s), ld(&t), &mut o);
            rest_out.copy_from_slice(&o[..n]);
        }
    }
}

/// Per-ray sample source handed to plug-ins: each call consumes the next dimensions of the
/// ray's path, so plug-ins never need to know the sampler's addressing.
#[derive(Clone, Copy, Debug)]
#[repr(C)] // Three u32 in this order: the AVX2 column kernels load eight samplers at once.
pub struct PathSampler {
    /// Per-pixel scrambling seed ([`pixel_seed`]).
    pub seed: u32,
    /// Sample index within the pixel, as an address of the sampler: with
    /// [`independent::INDEPENDENT_BIT`] set the independent sampler draws the path's numbers
    /// ([`SamplerKind::address`]), else the Sobol sampler.
    pub sample: u32,
    /// Next dimension to consume.
    pub dimension: u32,
}

impl PathSampler {
    /// The next sample dimension.
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        let v = sample_1d(self.seed, self.sample, self.dimension);
        self.dimension += 1;
        v
    }
    /// The next two sample dimensions.
    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let v = sample_2d(self.seed, self.sample, self.dimension);
        self.dimension += 2;
        v
    }
    /// The next four sample dimensions (one SIMD evaluation when `dimension` is a multiple
    /// of 4).
    #[inline]
    pub fn next_4d(&mut self) -> [f32; 4] {
        let d = self.dimension;
        self.dimension += 4;
        if d.is_multiple_of(4) {
            sample_4d(self.seed, self.sample, d / 4)
        } else {
            std::array::from_fn(|k| sample_1d(self.seed, self.sample, d + k as u32))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_are_in_unit_interval_and_stratified() {
        // The first 2^k Sobol points of one dimension fall one per stratum of width 2^-k
        // (a (0,1)-sequence property Owen scrambling preserves).
        let seed = pixel_seed(7, 123);
        for dim in [0u32, 1, 5, 255, 256, 300] {
            let mut strata = [false; 64];
            for i in 0..64 {
                let v = sample_1d(seed, i, dim);
                assert!((0.0..1.0).contains(&v));
                strata[(v * 64.0) as usize] = true;
            }
            assert!(strata.iter().all(|&s| s), "dimension {dim} not stratified");
        }
    }

    #[test]
    fn four_and_two_dimensional_samples_equal_one_dimensional_ones() {
        // sample_4d / sample_2d / next_4d are only faster paths: they must return exactly
        // the per-dimension values, including past the first 256-dimension block and at
        // unaligned starts.
        let seed = pixel_seed(11, 4321);
        for sample in [0u32, 1, 7, 1000] {
            for set in [0u32, 1, 63, 64, 65, 200, 100_000] {
                let v = sample_4d(seed, sample, set);
                for k in 0..4 {
                    assert_eq!(v[k], sample_1d(seed, sample, 4 * set + k as u32));
                }
            }
            for dim in [0u32, 1, 2, 3, 254, 255, 256, 301] {
                let v = sample_2d(seed, sample, dim);
                assert_eq!(v.x, sample_1d(seed, sample, dim));
                assert_eq!(v.y, sample_1d(seed, sample, dim + 1));
                let mut s = PathSampler {
                    seed,
                    sample,
                    dimension: dim,
                };
                let w = s.next_4d();
                assert_eq!(s.dimension, dim + 4);
                for k in 0..4 {
                    assert_eq!(w[k], sample_1d(seed, sample, dim + k as u32));
                }
            }
        }
    }

    #[test]
    fn column_draws_equal_per_sampler_draws() {
        // The column kernels are only faster paths: every length (full groups of four and
        // a remainder), aligned and unaligned dimensions (which fall back per sampler),
        // set 0 and large sets must give exactly next_4d / next_2d and advance the same.
        let mut rng = SplitMix64(99);
        for n in [0usize, 1, 3, 4, 5, 8, 13, 64] {
            for unaligned_every in [0usize, 1, 3, 7] {
                let samplers: Vec<PathSampler> = (0..n)
                    .map(|i| {
                        let set = [0u32, 1, 2, 63, 64, 1000][i % 6];
                        let shift = if unaligned_every > 0 && i % unaligned_every == 0 {
                            1 + i as u32 % 3
                        } else {
                            0
                        };
                        PathSampler {
                            seed: rng.next_u64() as u32,
                            sample: (rng.next_u64() % (2 * MAX_SPP as u64)) as u32,
                            dimension: 4 * set + shift,
                        }
                    })
                    .collect();
                let mut col = samplers.clone();
                let mut out4 = vec![[0.0f32; 4]; n];
                next_4d_column(&mut col, &mut out4);
                let mut out2 = vec![Vec2::ZERO; n];
                next_2d_column(&mut col, &mut out2);
                for (i, s) in samplers.iter().enumerate() {
                    let mut one = *s;
                    assert_eq!(out4[i], one.next_4d(), "4d: n {n}, point {i}");
                    assert_eq!(out2[i], one.next_2d(), "2d: n {n}, point {i}");
                    assert_eq!(col[i].dimension, one.dimension);
                    assert_eq!((col[i].seed, col[i].sample), (s.seed, s.sample));
                }
            }
        }
    }

    #[test]
    #[cfg(target_arch = "x86_64")]
    #[allow(
        unsafe_code,
        reason = "calls the AVX2 kernels after run-time detection"
    )]
    fn avx2_kernels_with_and_without_avx512_equal_per_sampler_draws() {
        // The column functions take the AVX-512 DQ seeds where the CPU has them; the plain
        // AVX2 kernels must give the same draws on machines without.
        if !avx2::detected() {
            return;
        }
        let mut rng = SplitMix64(7);
        let table = sobol_byte_table();
        for n in [1usize, 5, 8, 13, 64] {
            let samplers: Vec<PathSampler> = (0..n)
                .map(|i| PathSampler {
                    seed: rng.next_u64() as u32,
                    sample: (rng.next_u64() % (2 * MAX_SPP as u64)) as u32,
                    dimension: 4 * [0u32, 1, 2, 63, 64, 1000, 1 << 29][i % 7],
                })
                .collect();
            let (mut out4, mut out2) = (vec![[0.0f32; 4]; n], vec![Vec2::ZERO; n]);
            // SAFETY: `avx2::detected` found AVX2.
            unsafe { avx2::column_4d(table, &samplers, &mut out4) };
            let mut two = samplers.clone();
            for s in two.iter_mut() {
                s.dimension += 4;
            }
            // SAFETY: as above.
            unsafe { avx2::column_2d(table, &two, &mut out2) };
            for (i, s) in samplers.iter().enumerate() {
                let mut one = *s;
                assert_eq!(out4[i], one.next_4d(), "4d: n {n}, point {i}");
                assert_eq!(out2[i], one.next_2d(), "2d: n {n}, point {i}");
            }
            if avx2::detected_dq() {
                let (mut dq4, mut dq2) = (vec![[0.0f32; 4]; n], vec![Vec2::ZERO; n]);
                // SAFETY: `avx2::detected_dq` found AVX2 and AVX-512 F, DQ and VL.
                unsafe {
                    avx2::column_4d_dq(table, &samplers, &mut dq4);
                    avx2::column_2d_dq(table, &two, &mut dq2);
                }
                assert_eq!((dq4, dq2), (out4, out2), "n {n}");
            }
        }
    }

    #[test]
    fn portable_column_path_and_camera_column_equal_per_sampler_draws() {
        // On AVX2 machines the column functions take the AVX2 kernels (checked above); the
        // four-lane path they fall back to elsewhere must give the same values, and the
        // camera's set-0 column must equal sample_2d at dimension 0 for every length.
        let mut rng = SplitMix64(7);
        let table = sobol_byte_table();
        for n in [0usize, 1, 4, 7, 8, 9, 16, 23] {
            let samplers: Vec<PathSampler> = (0..n)
                .map(|i| PathSampler {
                    seed: rng.next_u64() as u32,
                    sample: rng.next_u64() as u32 % MAX_SPP,
                    dimension: 4 * [0u32, 1, 5, 70, 3][i % 5] + [0, 0, 0, 2][i % 4],
                })
                .collect();
            let mut out4 = vec![[0.0f32; 4]; n];
            for_lane_groups(&samplers, &mut out4, table, kernel_4d, |&s| {
                let mut s = s;
                s.next_4d()
            });
            let mut out2 = vec![Vec2::ZERO; n];
            for_lane_groups(&samplers, &mut out2, table, kernel_2d, |&s| {
                let mut s = s;
                s.next_2d()
            });
            for (i, s) in samplers.iter().enumerate() {
                assert_eq!(out4[i], { *s }.next_4d(), "4d: n {n}, point {i}");
                assert_eq!(out2[i], { *s }.next_2d(), "2d: n {n}, point {i}");
            }
            let seed: Vec<u32> = samplers.iter().map(|s| s.seed).collect();
            let sample: Vec<u32> = samplers.iter().map(|s| s.sample).collect();
            let mut jitter = vec![Vec2::ZERO; n];
            first_2d_column(&seed, &sample, &mut jitter);
            for i in 0..n {
                assert_eq!(
                    jitter[i],
                    sample_2d(seed[i], sample[i], 0),
                    "n {n}, point {i}"
                );
            }
        }
    }

    #[test]
    fn sets_equal_sobol_burley_bit_for_bit() {
        // The table-driven evaluation must be exactly the crate's sample_4d of the set's own
        // sequence, for all sample indices and many seeds and sets.
        for sample in 0..MAX_SPP {
            let seed = pixel_seed(sample as u64, sample.wrapping_mul(2_654_435_761));
            let set = sample % 97;
            let expected = sobol_burley::sample_4d(sample, 0, set_seed(seed, set));
            assert_eq!(sample_4d(seed, sample, set), expected, "sample {sample}");
            let d = 4 * set + sample % 4;
            assert_eq!(
                sample_1d(seed, sample, d),
                sobol_burley::sample(sample, d % 4, set_seed(seed, set))
            );
        }
    }

    #[test]
    fn every_set_starts_with_a_stratified_2d_pair() {
        // Padding: each set is Sobol's first dimensions, whose first two form a (0,2)-sequence:
        // 16 points put exactly one point in every elementary interval of area 1/16 (16x1,
        // 8x2, 4x4, 2x8 and 1x16 grids). Later dimensions of one Sobol sequence do not have
        // this for every pair.
        let seed = pixel_seed(5, 77);
        for set in [0u32, 1, 2, 3, 37, 1000] {
            for (cols, rows) in [(16usize, 1usize), (8, 2), (4, 4), (2, 8), (1, 16)] {
                let mut cells = vec![0u32; 16];
                for i in 0..16 {
                    let v = sample_4d(seed, i, set);
                    let c = (v[0] * cols as f32) as usize;
                    let r = (v[1] * rows as f32) as usize;
                    cells[r * cols + c] += 1;
                }
                assert!(
                    cells.iter().all(|&c| c == 1),
                    "set {set}, {cols}x{rows}: {cells:?}"
                );
            }
        }
    }

    #[test]
    fn seeds_decorrelate_pixels() {
        let a: Vec<f32> = (0..16).map(|i| sample_1d(pixel_seed(0, 1), i, 0)).collect();
        let b: Vec<f32> = (0..16).map(|i| sample_1d(pixel_seed(0, 2), i, 0)).collect();
        assert_ne!(a, b);
        let mean: f32 = (0..4096)
            .map(|p| sample_1d(pixel_seed(3, p), 0, 2))
            .sum::<f32>()
            / 4096.0;
        assert!((mean - 0.5).abs() < 0.02, "mean {mean}");
    }
}
