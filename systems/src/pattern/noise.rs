//! Perlin's improved gradient noise (K. Perlin, "Improving Noise", SIGGRAPH 2002) and its
//! fractal sum (fBm), with the analytic bound the interval bounds of the pattern graph use.

use super::PatternError;
use crate::sampler::SplitMix64;
use glam::Vec3;

/// A bound on `|noise(p)|` over all of space for [`perlin`] (one octave).
///
/// Why 1.5 holds: inside a lattice cell with fractional position `(x, y, z)`, noise is
/// `sum_c w_c g_c . (p - c)` over the eight corners `c`, with weights
/// `w_c = s_x s_y s_z` products of the fade `s(t) = 6t^5 - 15t^4 + 10t^3` or `1 - s(t)`:
/// non-negative and summing to 1. Every gradient of Perlin 2002 is an edge vector of the cube
/// (two components +-1, one 0), so `|g_c . d| <= |d_x| + |d_y| + |d_z|`, and the weighted sum
/// of `|d_x|` over the corners is `h(x) = (1 - s(x)) x + s(x) (1 - x)`. `s` is convex on
/// [0, 1/2] with `s(0) = 0`, `s(1/2) = 1/2`, so `s(t) <= t` there and
/// `h(t) <= t + t (1 - 2t) = 2t (1 - t) <= 1/2`; `h(1 - t) = h(t)` covers the other half.
/// Hence `|noise| <= h(x) + h(y) + h(z) <= 3/2`. (The true maximum is near 1.04; the bound
/// is conservative, not tight.)
pub const PERLIN_BOUND: f32 = 1.5;

/// Per-octave offsets of the lattice, so that the octaves of an fBm do not all vanish at
/// the origin (every octave's lattice contains it). Octave 0 is unshifted.
const OCTAVE_OFFSET: Vec3 = Vec3::new(19.19, 7.31, 3.77);

/// Octaves an [`Fbm`] may have.
pub const MAX_OCTAVES: u32 = 16;

/// Fractal Brownian motion over Perlin noise:
/// `fbm(p) = sum_{k < octaves} gain^k noise(frequency lacunarity^k p + k offset)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Fbm {
    /// Lattice cells per world unit of the first octave, >= 0.
    pub frequency: f32,
    /// Number of octaves, in [1, 16].
    pub octaves: u32,
    /// Frequency ratio of successive octaves, > 0.
    pub lacunarity: f32,
    /// Amplitude ratio of successive octaves, >= 0.
    pub gain: f32,
    /// The seed the permutation was shuffled with.
    pub seed: u32,
    /// Perlin's permutation of 0..256, shuffled by `seed` (Fisher-Yates with SplitMix64).
    perm: [u8; 256],
}

impl Fbm {
    /// An fBm; errors for octaves outside [1, 16], a negative or non-finite frequency, a
    /// lacunarity <= 0 or a negative gain.
    pub fn new(
        frequency: f32,
        octaves: u32,
        lacunarity: f32,
        gain: f32,
        seed: u32,
    ) -> Result<Fbm, PatternError> {
        let bad = |what: &str| Err(PatternError::Parameter(format!("noise: {what}")));
        if !(1..=MAX_OCTAVES).contains(&octaves) {
            return bad(&format!("octaves must be in [1, 16], got {octaves}"));
        }
        if !(frequency.is_finite() && frequency >= 0.0) {
            return bad(&format!("frequency must be >= 0, got {frequency}"));
        }
        if !(lacunarity.is_finite() && lacunarity > 0.0) {
            return bad(&format!("lacunarity must be > 0, got {lacunarity}"));
        }
        if !(gain.is_finite() && gain >= 0.0) {
            return bad(&format!("gain must be >= 0, got {gain}"));
        }
        let mut perm = [0u8; 256];
        for (i, p) in perm.iter_mut().enumerate() {
            *p = i as u8;
        }
        let mut rng = SplitMix64(u64::from(seed) ^ 0x9E37_79B9_7F4A_7C15);
        for i in (1..256usize).rev() {
            let j = (rng.next_u64() % (i as u64 + 1)) as usize;
            perm.swap(i, j);
        }
        Ok(Fbm {
            frequency,
            octaves,
            lacunarity,
            gain,
            seed,
            perm,
        })
    }

    /// The fBm at `p` (0 for a non-finite `p`).
    #[inline]
    pub fn eval(&self, p: Vec3) -> f32 {
        if !p.is_finite() {
            return 0.0;
        }
        let (mut sum, mut amplitude, mut frequency) = (0.0, 1.0, self.frequency);
        for k in 0..self.octaves {
            sum += amplitude * perlin(&self.perm, p * frequency + OCTAVE_OFFSET * k as f32);
            amplitude *= self.gain;
            frequency *= self.lacunarity;
        }
        sum
    }

    /// `sum_k gain^k` times [`PERLIN_BOUND`]: `|fbm| <=` this everywhere.
    pub fn bound(&self) -> f32 {
        let (mut sum, mut amplitude) = (0.0f32, 1.0f32);
        for _ in 0..self.octaves {
            sum += amplitude;
            amplitude *= self.gain;
        }
        PERLIN_BOUND * sum
    }
}

/// A Lipschitz bound of one octave of [`perlin`] per axis: `|dn/dx_i| <= PERLIN_SLOPE`
/// everywhere, so `|n(x) - n(c)| <= PERLIN_SLOPE |x - c|_1` (and, as `|d|_1 <= sqrt(3) |d|_2`,
/// `L = sqrt(3) PERLIN_SLOPE` in the Euclidean form `|n(x) - n(c)| <= L |x - c|`).
///
/// Derivation (the notation of [`PERLIN_BOUND`]): in a cell, write the noise as the fade
/// lerp along `x` of two faces, `n = (1 - s(x)) A0 + s(x) A1`, where `A0` (`A1`) is the
/// fade-weighted average over the four corners with `c_x = 0` (`c_x = 1`) of `g_c . (p - c)`.
/// Then `dn/dx = s'(x) (A1 - A0) + (1 - s(x)) dA0/dx + s(x) dA1/dx`.
/// - `dA_i/dx` is a weighted average (weights >= 0 summing to 1) of `g_c.x` in {-1, 0, 1}:
///   at most 1, and so is the convex combination of the two.
/// - `|g_c . d| <= |d_x| + |d_y| + |d_z|` (edge gradients), so `|A0| <= x + h(y) + h(z)` and
///   `|A1| <= (1 - x) + h(y) + h(z)`, with `h <= 1/2` as in [`PERLIN_BOUND`]: `|A1 - A0| <=
///   1 + 2 (1/2 + 1/2) = 3`.
/// - The quintic fade's slope `s'(t) = 30 t^2 (1 - t)^2` peaks at `t = 1/2`: `15/8`.
///
/// Hence `|dn/dx| <= 3 * 15/8 + 1 = 53/8`, the same for `y` and `z` by symmetry. The noise is
/// C2 across cell faces, so the bound holds along any segment, not only inside one cell.
pub const PERLIN_SLOPE: f32 = 53.0 / 8.0;

impl Fbm {
    /// Bounds `(lo, hi)` of the fBm over the box `[lo, hi]` of `P` (any corner may be
    /// infinite; NaN corners read as unbounded), octave by octave: octave `k` (amplitude
    /// `gain^k`, lattice frequency `f_k = frequency lacunarity^k`) lies within `n_k(c) +-
    /// PERLIN_SLOPE f_k |e|_1` at the box's centre `c` with half-extents `e` ([`PERLIN_SLOPE`]),
    /// clamped to `+-PERLIN_BOUND`; the sum of the octaves' intervals bounds the fBm.
    ///
    /// A rounding margin per octave covers the `f32` evaluation: the lattice coordinate
    /// `q = f_k p + offset` is rounded (a relative error of a few ulps of `|q|`, times the
    /// slope), and the noise's own arithmetic (a few ulps of its magnitude <= 3/2).
    pub fn bounds_over(&self, lo: Vec3, hi: Vec3) -> (f32, f32) {
        let global = self.bound();
        let finite = lo.is_finite() && hi.is_finite() && lo.cmple(hi).all();
        if !finite {
            return (-global, global);
        }
        let c = (lo + hi) * 0.5;
        let e = ((hi - lo) * 0.5).max(Vec3::ZERO);
        let e1 = f64::from(e.x) + f64::from(e.y) + f64::from(e.z);
        let (mut l, mut h) = (0.0f64, 0.0f64);
        // The frequency in f32 as `eval` computes it, so that `q` is `eval`'s at `c`.
        let (mut amplitude, mut frequency32) = (1.0f64, self.frequency);
        let eps = f64::from(f32::EPSILON);
        for k in 0..self.octaves {
            let frequency = f64::from(frequency32);
            let q = c * frequency32 + OCTAVE_OFFSET * k as f32;
            let nc = f64::from(perlin(&self.perm, q));
            let q1 = f64::from(q.x.abs() + q.y.abs() + q.z.abs());
            let slope = f64::from(PERLIN_SLOPE);
            let reach = slope * frequency * e1
                + slope * 8.0 * eps * (q1 + frequency * e1 + 3.0)
                + 32.0 * eps;
            let bound = f64::from(PERLIN_BOUND);
            l += amplitude * (nc - reach).max(-bound);
            h += amplitude * (nc + reach).min(bound);
            amplitude *= f64::from(self.gain);
            frequency32 *= self.lacunarity;
        }
        // The sum itself is rounded in `eval` (one rounding per octave).
        let slack = 4.0 * eps * f64::from(global) * f64::from(self.octaves);
        let (l, h) = ((l - slack) as f32, (h + slack) as f32);
        (l.max(-global), h.min(global))
    }
}

/// Perlin's fade curve `6t^5 - 15t^4 + 10t^3` (C2 at the lattice).
#[inline]
fn fade(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

#[inline]
fn lerp(t: f32, a: f32, b: f32) -> f32 {
    a + t * (b - a)
}

/// Perlin 2002's gradient: the low 4 bits of the hash pick one of 12 cube-edge directions
/// (four repeated to make 16), dotted with `(x, y, z)`.
#[inline]
fn grad(hash: u8, x: f32, y: f32, z: f32) -> f32 {
    let h = hash & 15;
    let u = if h < 8 { x } else { y };
    let v = if h < 4 {
        y
    } else if h == 12 || h == 14 {
        x
    } else {
        z
    };
    (if h & 1 == 0 { u } else { -u }) + (if h & 2 == 0 { v } else { -v })
}

/// One octave of improved Perlin noise at `p` with permutation `perm`: 0 at every lattice
/// point, `|noise| <= PERLIN_BOUND`.
#[inline]
pub fn perlin(perm: &[u8; 256], p: Vec3) -> f32 {
    let (fx, fy, fz) = (p.x.floor(), p.y.floor(), p.z.floor());
    // The lattice repeats every 256 cells (Perlin's `& 255`); saturating casts keep huge
    // coordinates defined.
    let (xi, yi, zi) = (
        (fx as i64 & 255) as usize,
        (fy as i64 & 255) as usize,
        (fz as i64 & 255) as usize,
    );
    let (x, y, z) = (p.x - fx, p.y - fy, p.z - fz);
    let (u, v, w) = (fade(x), fade(y), fade(z));
    // Perlin's doubled table p[i] for i < 512 is perm[i & 255].
    let pm = |i: usize| perm[i & 255] as usize;
    let a = pm(xi) + yi;
    let (aa, ab) = (pm(a) + zi, pm(a + 1) + zi);
    let b = pm(xi + 1) + yi;
    let (ba, bb) = (pm(b) + zi, pm(b + 1) + zi);
    let h = |i: usize| perm[i & 255];
    lerp(
        w,
        lerp(
            v,
            lerp(u, grad(h(aa), x, y, z), grad(h(ba), x - 1.0, y, z)),
            lerp(
                u,
                grad(h(ab), x, y - 1.0, z),
                grad(h(bb), x - 1.0, y - 1.0, z),
            ),
        ),
        lerp(
            v,
            lerp(
                u,
                grad(h(aa + 1), x, y, z - 1.0),
                grad(h(ba + 1), x - 1.0, y, z - 1.0),
            ),
            lerp(
                u,
                grad(h(ab + 1), x, y - 1.0, z - 1.0),
                grad(h(bb + 1), x - 1.0, y - 1.0, z - 1.0),
            ),
        ),
    )
}

impl Fbm {
    /// The permutation (for single-octave reference evaluations in tests).
    pub fn permutation(&self) -> &[u8; 256] {
        &self.perm
    }
}
