//! The [`Avx2`] lanes: eight f32 in one 256-bit register, through the AVX2 and FMA
//! intrinsics (only reachable with a token from [`Avx2::detect`]).

use std::arch::x86_64::*;
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Sub};

use glam::Vec3;

use super::{Kernel8, Lanes8, Mask8, Row8, Simd};

/// Proof that the CPU runs AVX2 and FMA: the private field keeps it from being made
/// anywhere but [`Avx2::detect`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Avx2(());

/// `k` on [`Avx2`] lanes, compiled with AVX2 and FMA.
#[inline]
pub(super) fn run<K: Kernel8>(t: Avx2, k: K) -> K::Output {
    #[target_feature(enable = "avx2,fma")]
    fn with_avx2<K: Kernel8>(t: Avx2, k: K) -> K::Output {
        k.run(t)
    }
    // SAFETY: the token exists only if `Avx2::detect` found AVX2 and FMA on this CPU.
    unsafe { with_avx2(t, k) }
}

impl Avx2 {
    /// The token, if this CPU has AVX2 and FMA.
    pub(crate) fn detect() -> Option<Self> {
        (is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")).then_some(Avx2(()))
    }
}

/// [`Avx2`]'s lanes. Values exist only where an [`Avx2`] token does (they are made by
/// its [`Simd`] methods and by operations on other values), so the CPU has AVX2 and FMA
/// wherever one is used.
#[derive(Clone, Copy, Debug)]
pub(crate) struct A8(__m256);

/// [`Avx2`]'s comparison result (all-ones or all-zeros lanes), made like [`A8`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct AMask(__m256);

/// Calls an AVX/AVX2/FMA intrinsic.
macro_rules! avx {
    ($e:expr) => {
        // SAFETY: only reached through an `A8`/`AMask` value or an `Avx2` token, which
        // exist only after `Avx2::detect` found AVX2 and FMA on this CPU.
        unsafe { $e }
    };
}

impl Simd for Avx2 {
    type F = A8;
    #[inline(always)]
    fn splat(self, x: f32) -> A8 {
        A8(avx!(_mm256_set1_ps(x)))
    }
    #[inline(always)]
    fn load(self, r: &Row8) -> A8 {
        // SAFETY: `r` is a reference to 32 readable bytes aligned to 32 (`Row8`), and
        // the token guarantees AVX.
        A8(unsafe { _mm256_load_ps(r.0.as_ptr()) })
    }
    #[inline(always)]
    fn load_xyz(self, v: &[Vec3; 8]) -> [A8; 3] {
        // Three loads of eight floats: `m0 = x0 y0 z0 x1 y1 z1 x2 y2`,
        // `m1 = z2 x3 y3 z3 x4 y4 z4 x5`, `m2 = y5 z5 x6 y6 z6 x7 y7 z7`. Each coordinate
        // sits at lanes that differ between the three (x: m0 {0, 3, 6}, m1 {1, 4, 7},
        // m2 {2, 5}), so two blends gather it into one register and one permutation
        // puts it in order.
        let p = v.as_ptr().cast::<f32>();
        // SAFETY: `Vec3` is `#[repr(C)]` with three `f32` fields and no padding (12
        // bytes), so `v` is 24 contiguous readable `f32`: the loads read floats 0..8,
        // 8..16 and 16..24 (unaligned loads); the token guarantees AVX2.
        let (m0, m1, m2) = unsafe {
            (
                _mm256_loadu_ps(p),
                _mm256_loadu_ps(p.add(8)),
                _mm256_loadu_ps(p.add(16)),
            )
        };
        [
            A8(gather::<0b1001_0010, 0b0010_0100>(
                m0,
                m1,
                m2,
                [0, 3, 6, 1, 4, 7, 2, 5],
            )),
            A8(gather::<0b0010_0100, 0b0100_1001>(
                m0,
                m1,
                m2,
                [1, 4, 7, 2, 5, 0, 3, 6],
            )),
            A8(gather::<0b0100_1001, 0b1001_0010>(
                m0,
                m1,
                m2,
                [2, 5, 0, 3, 6, 1, 4, 7],
            )),
        ]
    }
    #[inline(always)]
    fn store_xyz(self, [x, y, z]: [A8; 3], out: &mut [Vec3; 8]) {
        // `load_xyz` backwards: each coordinate permuted so that its lanes for `m0`, `m1`
        // and `m2` (x: points 0-2, 3-5, 6-7) sit where those rows hold that coordinate
        // (x: m0 {0, 3, 6}, m1 {1, 4, 7}, m2 {2, 5}), then two blends per row.
        let px = permute(x.0, [0, 3, 6, 1, 4, 7, 2, 5]);
        let py = permute(y.0, [5, 0, 3, 6, 1, 4, 7, 2]);
        let pz = permute(z.0, [2, 5, 0, 3, 6, 1, 4, 7]);
        let m0 = avx!(_mm256_blend_ps::<0b0010_0100>(
            _mm256_blend_ps::<0b1001_0010>(px, py),
            pz
        ));
        let m1 = avx!(_mm256_blend_ps::<0b0100_1001>(
            _mm256_blend_ps::<0b0010_0100>(px, py),
            pz
        ));
        let m2 = avx!(_mm256_blend_ps::<0b1001_0010>(
            _mm256_blend_ps::<0b0100_1001>(px, py),
            pz
        ));
        let p = out.as_mut_ptr().cast::<f32>();
        // SAFETY: `Vec3` is `#[repr(C)]` with three `f32` fields and no padding (12
        // bytes), so `out` is 24 contiguous writable `f32`: the stores write floats 0..8,
        // 8..16 and 16..24 (unaligned stores); the token guarantees AVX.
        unsafe {
            _mm256_storeu_ps(p, m0);
            _mm256_storeu_ps(p.add(8), m1);
            _mm256_storeu_ps(p.add(16), m2);
        }
    }
    #[inline(always)]
    fn lookup(self, table: &Row8, index: A8) -> A8 {
        let index = avx!(_mm256_cvttps_epi32(index.0));
        A8(avx!(_mm256_permutevar8x32_ps(self.load(table).0, index)))
    }
}

/// One coordinate of [`Avx2::load_xyz`]'s three loads: lanes set in `FROM1` taken from
/// `m1`, those in `FROM2` from `m2`, the rest from `m0`, then lane `order[i]` moved to
/// lane `i`.
#[inline(always)]
fn gather<const FROM1: i32, const FROM2: i32>(
    m0: __m256,
    m1: __m256,
    m2: __m256,
    order: [i32; 8],
) -> __m256 {
    let [a, b, c, d, e, f, g, h] = order;
    avx!(_mm256_permutevar8x32_ps(
        _mm256_blend_ps::<FROM2>(_mm256_blend_ps::<FROM1>(m0, m1), m2),
        _mm256_setr_epi32(a, b, c, d, e, f, g, h)
    ))
}

/// Lane `order[i]` of `v` moved to lane `i`.
#[inline(always)]
fn permute(v: __m256, order: [i32; 8]) -> __m256 {
    let [a, b, c, d, e, f, g, h] = order;
    avx!(_mm256_permutevar8x32_ps(
        v,
        _mm256_setr_epi32(a, b, c, d, e, f, g, h)
    ))
}

macro_rules! avx_binop {
    ($tr:ident, $f:ident, $intr:ident) => {
        impl $tr for A8 {
            type Output = A8;
            #[inline(always)]
            fn $f(self, o: A8) -> A8 {
                A8(avx!($intr(self.0, o.0)))
            }
        }
    };
}
avx_binop!(Add, add, _mm256_add_ps);
avx_binop!(Sub, sub, _mm256_sub_ps);
avx_binop!(Mul, mul, _mm256_mul_ps);
avx_binop!(Div, div, _mm256_div_ps);

impl BitAnd for AMask {
    type Output = AMask;
    #[inline(always)]
    fn bitand(self, o: AMask) -> AMask {
        AMask(avx!(_mm256_and_ps(self.0, o.0)))
    }
}

impl BitOr for AMask {
    type Output = AMask;
    #[inline(always)]
    fn bitor(self, o: AMask) -> AMask {
        AMask(avx!(_mm256_or_ps(self.0, o.0)))
    }
}

impl Mask8 for AMask {
    #[inline(always)]
    fn bits(self) -> u32 {
        avx!(_mm256_movemask_ps(self.0)) as u32
    }
    #[inline(always)]
    fn and_not(self, o: AMask) -> AMask {
        AMask(avx!(_mm256_andnot_ps(o.0, self.0)))
    }
}

impl Lanes8 for A8 {
    type Mask = AMask;
    #[inline(always)]
    fn min(self, o: A8) -> A8 {
        A8(avx!(_mm256_min_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn max(self, o: A8) -> A8 {
        A8(avx!(_mm256_max_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn abs(self) -> A8 {
        A8(avx!(_mm256_andnot_ps(_mm256_set1_ps(-0.0), self.0)))
    }
    #[inline(always)]
    fn sqrt(self) -> A8 {
        A8(avx!(_mm256_sqrt_ps(self.0)))
    }
    #[inline(always)]
    fn neg(self) -> A8 {
        A8(avx!(_mm256_xor_ps(_mm256_set1_ps(-0.0), self.0)))
    }
    #[inline(always)]
    fn copysign(self, sign: A8) -> A8 {
        let m = avx!(_mm256_set1_ps(-0.0));
        A8(avx!(_mm256_or_ps(
            _mm256_andnot_ps(m, self.0),
            _mm256_and_ps(m, sign.0)
        )))
    }
    #[inline(always)]
    fn select_negative(sign: A8, neg: A8, pos: A8) -> A8 {
        // `blendv` reads only each lane's sign bit.
        A8(avx!(_mm256_blendv_ps(pos.0, neg.0, sign.0)))
    }
    #[inline(always)]
    fn select(m: AMask, a: A8, b: A8) -> A8 {
        A8(avx!(_mm256_blendv_ps(b.0, a.0, m.0)))
    }
    #[inline(always)]
    fn mul_add(self, a: A8, b: A8) -> A8 {
        A8(avx!(_mm256_fmadd_ps(self.0, a.0, b.0)))
    }
    #[inline(always)]
    fn le(self, o: A8) -> AMask {
        AMask(avx!(_mm256_cmp_ps::<_CMP_LE_OQ>(self.0, o.0)))
    }
    #[inline(always)]
    fn lt(self, o: A8) -> AMask {
        AMask(avx!(_mm256_cmp_ps::<_CMP_LT_OQ>(self.0, o.0)))
    }
    #[inline(always)]
    fn gt(self, o: A8) -> AMask {
        AMask(avx!(_mm256_cmp_ps::<_CMP_GT_OQ>(self.0, o.0)))
    }
    #[inline(always)]
    fn eq(self, o: A8) -> AMask {
        AMask(avx!(_mm256_cmp_ps::<_CMP_EQ_OQ>(self.0, o.0)))
    }
    #[inline(always)]
    fn sign_bits(self) -> u32 {
        avx!(_mm256_movemask_ps(self.0)) as u32
    }
    #[inline(always)]
    fn sign_bits_all_any(self, b: A8, c: A8) -> (u32, u32) {
        // Bitwise and/or of the lanes first: one mask extraction each.
        let all = avx!(_mm256_and_ps(_mm256_and_ps(self.0, b.0), c.0));
        let any = avx!(_mm256_or_ps(_mm256_or_ps(self.0, b.0), c.0));
        (
            avx!(_mm256_movemask_ps(all)) as u32,
            avx!(_mm256_movemask_ps(any)) as u32,
        )
    }
    #[inline(always)]
    fn to_array(self) -> [f32; 8] {
        bytemuck::cast(self.0)
    }
}
