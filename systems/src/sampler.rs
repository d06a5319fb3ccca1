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
//! Set 0, the camera's (the pixel jitter is its first two dimensions), is the exception: it
//! is the Sobol sequence itself, in its own order, with a per-pixel random digital shift
//! (an XOR of every point with one random word per dimension; Kollig and Keller 2002,
//! "Efficient Multidimensional Sampling", the scheme of Mitsuba's `ldsampler`). A digital
//! shift keeps the net's lattice-like structure, which Owen scrambling randomises: a pixel's
//! points then count the area on either side of a slanted edge more evenly (measured at 64
//! spp: 24 % less variance along the slanted side edges of `smoke_homog`'s light, 4.5 % less
//! over all of `cornell`). A shift leaves each point uniform and keeps the (0,2)-sequence
//! property of the first two dimensions, so every prefix of a pixel's samples stays
//! stratified.
//!
//! A sample index with [`independent::INDEPENDENT_BIT`] set addresses the independent sampler
//! instead (`crate::independent_sampler`): every draw function here dispatches on it.

use crate::independent_sampler::{self as independent, SamplerKind};
use crate::simd8::{Backend, Kernel8, Simd};
use crate::splitmix::{mix64, GOLDEN_GAMMA};
// The generator lives in `crate::splitmix`, below both samplers; this is its public path.
pub use crate::splitmix::{seed_from, SplitMix64};
use glam::Vec2;

/// Largest supported samples per pixel (the Sobol tables of `sobol_burley` hold 2^16 points).
pub const MAX_SPP: u32 = 1 << 16;

/// Mixes the render seed and a pixel index into a per-pixel scrambling seed.
pub fn pixel_seed(render_seed: u64, pixel: u32) -> u32 {
    mix64(
        render_seed
            .wrapping_add(GOLDEN_GAMMA)
            .wrapping_add((pixel as u64).wrapping_mul(0xD1B5_4A32_D192_ED03)),
    ) as u32
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

/// Multiplier of the pixel seed in every dimension's scramble word (as in
/// `sobol_burley::sample_4d`); the camera set's shift words are made the same way.
const SCRAMBLE_SEED_MUL: u32 = 0x9c8f_2d3b;

/// One sample dimension in [0, 1).
#[inline]
pub fn sample_1d(seed: u32, sample: u32, dimension: u32) -> f32 {
    if SamplerKind::of(sample) == SamplerKind::Independent {
        return independent::sample_1d(seed, sample, dimension);
    }
    sample_4d(seed, sample, dimension / 4)[(dimension % 4) as usize]
}

/// The four dimensions `4 * set .. 4 * set + 4` at once: for sets past the first, the first
/// four dimensions of the set's own Owen-scrambled Sobol sequence, bit for bit
/// `sobol_burley::sample_4d(sample, 0, seed of the set)` (tested), about four times faster;
/// for set 0, the digitally shifted Sobol point [`camera_set`].
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
    if set == 0 {
        return camera_set(seed, sample);
    }
    let seed = set_seed(seed, set);
    let index_rev = owen_scramble_rev((sample % MAX_SPP).reverse_bits(), hash(seed ^ 0x79c6_8e4a));
    let table = sobol_byte_table();
    let sobol: Int4 = sobol_rev(table, index_rev).into();
    let scramble: Int4 = {
        let s: Int4 = [seed.wrapping_mul(SCRAMBLE_SEED_MUL); 4].into();
        s ^ DIM_SALT.into()
    };
    owen_scramble_int4_rev(sobol, hash_int4(scramble))
        .reverse_bits()
        .to_f32_norm()
}

/// Set 0 of pixel `seed`, the camera's: Sobol point `sample` (dimensions 0..4, in the
/// sequence's own order) XOR the pixel's shift, one hashed word per dimension (see the
/// module documentation for why the camera's set is shifted, not Owen-scrambled).
#[inline]
pub fn camera_set(seed: u32, sample: u32) -> [f32; 4] {
    let sobol = sobol_rev(sobol_byte_table(), (sample % MAX_SPP).reverse_bits());
    std::array::from_fn(|d| shifted_unit(sobol[d], seed, d))
}

/// The bit-reversed Sobol value `sobol_rev` of dimension `d`, shifted by pixel `seed`'s word
/// for that dimension, as a float in [0, 1) (its top 23 bits, as `Int4::to_f32_norm`).
#[inline(always)]
fn shifted_unit(sobol_rev: u32, seed: u32, d: usize) -> f32 {
    let shift = sobol_burley::parts::hash(seed.wrapping_mul(SCRAMBLE_SEED_MUL) ^ DIM_SALT[d]);
    to_unit(sobol_rev.reverse_bits() ^ shift)
}

/// The top 23 bits of `bits` as a float in [0, 1).
#[inline(always)]
fn to_unit(bits: u32) -> f32 {
    f32::from_bits((bits >> 9) | 0x3f80_0000) - 1.0
}

/// Bit-reversed Sobol dimensions 0..4 of the bit-reversed index `index_rev` (only its top 16
/// bits matter, see [`sample_4d`]): the XOR of its two bytes' table entries.
#[inline(always)]
fn sobol_rev(table: &SobolTable, index_rev: u32) -> [u32; 4] {
    let high = &table[0][(index_rev >> 24) as usize];
    let low = &table[1][((index_rev >> 16) & 0xff) as usize];
    std::array::from_fn(|d| high[d] ^ low[d])
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

/// Points per block of the column kernels ([`next_4d_column`], [`next_2d_column`],
/// [`first_2d_column`]).
const BLOCK: usize = 8;

/// Salts of the four dimensions' Owen scrambles (as in `sobol_burley::sample_4d`).
const DIM_SALT: [u32; 4] = [0x912f_69ba, 0x174f_18ab, 0x691e_72ca, 0xb40c_c1b8];

/// [`set_seed`] for a block of points, with no branch per point.
#[inline(always)]
fn set_seeds(seed: [u32; BLOCK], set: [u32; BLOCK]) -> [u32; BLOCK] {
    let mut out = [0; BLOCK];
    for l in 0..BLOCK {
        let mixed = pixel_seed(seed[l] as u64, set[l]);
        out[l] = if set[l] == 0 { seed[l] } else { mixed };
    }
    out
}

/// The first `D` dimensions of [`sample_4d`] for a block of points with set seeds `seed`
/// and samples `sample`: `out[l][d]` is dimension `d` of point `l`. The same scalar
/// functions as `sample_4d`, lane by lane (so the same bits), as loops over the block
/// without a branch, which the compiler vectorises (eight u32 lanes in one AVX2 register
/// in the [`Backend::run`] instantiation).
#[inline(always)]
fn draws_block<const D: usize>(
    table: &SobolTable,
    seed: &[u32; BLOCK],
    sample: &[u32; BLOCK],
    out: &mut [[f32; D]; BLOCK],
) {
    use sobol_burley::parts::{hash, owen_scramble_rev};
    let mut index_rev = [0u32; BLOCK];
    for l in 0..BLOCK {
        let index = (sample[l] % MAX_SPP).reverse_bits();
        index_rev[l] = owen_scramble_rev(index, hash(seed[l] ^ 0x79c6_8e4a));
    }
    // Flat (point, dimension) lanes, point-major: element `e` is dimension `e % D` of
    // point `e / D`, so that the scramble below is one loop over plain arrays.
    let (mut sobol, mut seed_mul, mut salt) =
        ([0u32; 4 * BLOCK], [0u32; 4 * BLOCK], [0; 4 * BLOCK]);
    for l in 0..BLOCK {
        let point = sobol_rev(table, index_rev[l]);
        for d in 0..D {
            sobol[D * l + d] = point[d];
            seed_mul[D * l + d] = seed[l].wrapping_mul(SCRAMBLE_SEED_MUL);
            salt[D * l + d] = DIM_SALT[d];
        }
    }
    let mut v = [0.0f32; 4 * BLOCK];
    for e in 0..D * BLOCK {
        let r = owen_scramble_rev(sobol[e], hash(seed_mul[e] ^ salt[e])).reverse_bits();
        v[e] = to_unit(r);
    }
    for l in 0..BLOCK {
        for d in 0..D {
            out[l][d] = v[D * l + d];
        }
    }
}

/// The first two dimensions of [`camera_set`] for a block of pixel seeds `seed` and samples
/// `sample`, lane by lane as loops without a branch.
#[inline(always)]
fn camera_block(
    table: &SobolTable,
    seed: &[u32; BLOCK],
    sample: &[u32; BLOCK],
    out: &mut [[f32; 2]; BLOCK],
) {
    for l in 0..BLOCK {
        let point = sobol_rev(table, (sample[l] % MAX_SPP).reverse_bits());
        for d in 0..2 {
            out[l][d] = shifted_unit(point[d], seed[l], d);
        }
    }
}

/// The draws of [`next_4d_column`] (`D` = 4) and [`next_2d_column`] (`D` = 2) without
/// advancing the samplers, as a [`Kernel8`]: blocks whose samplers all start a set through
/// [`draws_block`], others through `single`.
struct ColumnDraws<'a, T, const D: usize> {
    samplers: &'a [PathSampler],
    out: &'a mut [T],
    single: fn(PathSampler) -> T,
}

impl<T: Copy + From<[f32; D]>, const D: usize> ColumnDraws<'_, T, D> {
    /// One block, with `single` the per-sampler draw.
    #[inline(always)]
    fn block(
        single: fn(PathSampler) -> T,
        table: &SobolTable,
        s: &[PathSampler; BLOCK],
        out: &mut [T; BLOCK],
    ) {
        // Unaligned draws, and the camera's set (never drawn through a path's sampler by
        // the renderer), go point by point.
        if s.iter().any(|s| s.dimension % 4 != 0 || s.dimension < 4) {
            cold(|| {
                for (o, &s) in out.iter_mut().zip(s) {
                    *o = single(s);
                }
            });
            return;
        }
        let seed = set_seeds(s.map(|s| s.seed), s.map(|s| s.dimension / 4));
        let mut v = [[0.0; D]; BLOCK];
        draws_block(table, &seed, &s.map(|s| s.sample), &mut v);
        for (o, v) in out.iter_mut().zip(v) {
            *o = T::from(v);
        }
    }
}

impl<T: Copy + From<[f32; D]>, const D: usize> Kernel8 for ColumnDraws<'_, T, D> {
    type Output = ();
    #[inline(always)]
    fn run<S: Simd>(self, _: S) {
        let (table, single) = (sobol_byte_table(), self.single);
        let (blocks, rest) = self.samplers.as_chunks::<BLOCK>();
        let (rows, rest_out) = self.out.as_chunks_mut::<BLOCK>();
        for (s, o) in blocks.iter().zip(rows) {
            Self::block(single, table, s, o);
        }
        if let Some(&first) = rest.first() {
            // The last partial block, padded with copies of its first sampler. Element
            // loops, not `copy_from_slice`: a `memcpy` call of a varying small length
            // mispredicts inside.
            let mut s = [first; BLOCK];
            for (s, &r) in s.iter_mut().zip(rest) {
                *s = r;
            }
            let mut o = [rest_out[0]; BLOCK];
            Self::block(single, table, &s, &mut o);
            for (r, &o) in rest_out.iter_mut().zip(&o) {
                *r = o;
            }
        }
    }
}

/// Runs `f` out of line: keeps the rare unaligned path's registers and stack out of the
/// kernel loop.
#[cold]
#[inline(never)]
fn cold(f: impl FnOnce()) {
    f()
}

/// [`PathSampler::next_4d`] for a column of samplers: `out[i]` gets sampler `i`'s next four
/// dimensions and every sampler advances by four. Exactly the per-sampler values; blocks
/// of eight points whose dimensions are aligned sets (the renderer's vertices always are)
/// are evaluated together by a vectorised kernel.
///
/// # Panics
/// When `out` and `samplers` differ in length.
pub fn next_4d_column(samplers: &mut [PathSampler], out: &mut [[f32; 4]]) {
    assert_eq!(samplers.len(), out.len(), "next_4d_column: column lengths");
    if first_is_independent(samplers) {
        return independent_column(samplers, out, |s| s.next_4d());
    }
    next_4d_column_on(Backend::best(), samplers, out);
}

/// [`next_4d_column`] on the lanes of `backend`.
fn next_4d_column_on(backend: Backend, samplers: &mut [PathSampler], out: &mut [[f32; 4]]) {
    let single = |mut s: PathSampler| s.next_4d();
    backend.run(ColumnDraws {
        samplers,
        out,
        single,
    });
    advance(samplers, 4);
}

/// [`PathSampler::next_2d`] for a column of samplers: `out[i]` gets sampler `i`'s next two
/// dimensions and every sampler advances by two. Exactly the per-sampler values; blocks of
/// eight points that all start a set (as Bxdf sampling does at every vertex) are evaluated
/// together, computing only the two dimensions they use.
///
/// # Panics
/// When `out` and `samplers` differ in length.
pub fn next_2d_column(samplers: &mut [PathSampler], out: &mut [Vec2]) {
    assert_eq!(samplers.len(), out.len(), "next_2d_column: column lengths");
    if first_is_independent(samplers) {
        return independent_column(samplers, out, |s| s.next_2d());
    }
    next_2d_column_on(Backend::best(), samplers, out);
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

/// [`next_2d_column`] on the lanes of `backend`.
fn next_2d_column_on(backend: Backend, samplers: &mut [PathSampler], out: &mut [Vec2]) {
    let single = |mut s: PathSampler| s.next_2d();
    backend.run(ColumnDraws {
        samplers,
        out,
        single,
    });
    advance(samplers, 2);
}

/// Every sampler's dimension advanced by `dims` (the kernels leave them alone).
fn advance(samplers: &mut [PathSampler], dims: u32) {
    for s in samplers.iter_mut() {
        s.dimension += dims;
    }
}

/// Dimensions 0 and 1 (set 0) of `(seed[i], sample[i])` into `out[i]`: exactly
/// `sample_2d(seed[i], sample[i], 0)` (the camera jitter), eight points per block.
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
    first_2d_column_on(Backend::best(), seed, sample, out);
}

/// [`first_2d_column`] on the lanes of `backend`.
fn first_2d_column_on(backend: Backend, seed: &[u32], sample: &[u32], out: &mut [Vec2]) {
    backend.run(FirstColumn { seed, sample, out });
}

/// The columns of [`first_2d_column`], as a [`Kernel8`].
struct FirstColumn<'a> {
    seed: &'a [u32],
    sample: &'a [u32],
    out: &'a mut [Vec2],
}

impl Kernel8 for FirstColumn<'_> {
    type Output = ();
    #[inline(always)]
    fn run<S: Simd>(self, _: S) {
        let table = sobol_byte_table();
        let (seeds, seed_rest) = self.seed.as_chunks::<BLOCK>();
        let (samples, sample_rest) = self.sample.as_chunks::<BLOCK>();
        let (rows, rest_out) = self.out.as_chunks_mut::<BLOCK>();
        let mut v = [[0.0; 2]; BLOCK];
        for ((s, t), o) in seeds.iter().zip(samples).zip(rows) {
            camera_block(table, s, t, &mut v);
            *o = v.map(Vec2::from);
        }
        if !rest_out.is_empty() {
            let (mut s, mut t) = ([0u32; BLOCK], [0u32; BLOCK]);
            for (j, (&sr, &tr)) in seed_rest.iter().zip(sample_rest).enumerate() {
                (s[j], t[j]) = (sr, tr);
            }
            camera_block(table, &s, &t, &mut v);
            for (o, &v) in rest_out.iter_mut().zip(&v) {
                *o = Vec2::from(v);
            }
        }
    }
}

/// Per-ray sample source handed to plug-ins: each call consumes the next dimensions of the
/// ray's path, so plug-ins never need to know the sampler's addressing.
#[derive(Clone, Copy, Debug)]
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
    /// The sampler this sampler's sample address selects.
    #[inline]
    pub fn kind(&self) -> SamplerKind {
        SamplerKind::of(self.sample)
    }
    /// The sampler's dimensions one at a time, each set of four evaluated once
    /// ([`DimensionStream`]).
    #[inline]
    pub fn stream(&mut self) -> DimensionStream<'_> {
        DimensionStream {
            independent: SamplerKind::of(self.sample) == SamplerKind::Independent,
            sampler: self,
            set: u32::MAX,
            values: [0.0; 4],
        }
    }
}

/// Successive dimensions of a [`PathSampler`] for code that draws a variable number of them
/// one at a time (the tentative collisions of delta and ratio tracking): the same numbers as
/// as many [`PathSampler::next_1d`] calls, bit for bit, but each set of four dimensions is
/// evaluated once instead of once per dimension (a Sobol set costs its index scramble, table
/// lookups and Owen scramble whichever of its dimensions is asked for; the independent
/// sampler's dimensions are drawn one by one, as `next_1d` does). Advances the sampler's
/// `dimension` as it goes.
pub struct DimensionStream<'a> {
    sampler: &'a mut PathSampler,
    /// The sampler is the independent one.
    independent: bool,
    /// The set held in `values` (`u32::MAX`: none yet).
    set: u32,
    values: [f32; 4],
}

impl DimensionStream<'_> {
    /// The next sample dimension.
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        let s = &mut *self.sampler;
        if self.independent {
            // Its dimensions are independent hashes: one costs less than a cached set.
            return s.next_1d();
        }
        let d = s.dimension;
        if d / 4 != self.set {
            self.set = d / 4;
            self.values = sample_4d(s.seed, s.sample, self.set);
        }
        s.dimension += 1;
        self.values[(d % 4) as usize]
    }
}

#[cfg(test)]
mod independent_tests;
#[cfg(test)]
mod tests;
