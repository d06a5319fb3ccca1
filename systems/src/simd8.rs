//! Eight f32 lanes: the one SIMD style of the crate. The wide-BVH kernels of
//! [`crate::intersect`] put one lane per child box of a node or per triangle of a leaf
//! packet; the shading kernels ([`crate::bxdf::diffuse_sample_world`],
//! [`crate::lights::LightSet::sample_column`], the camera's perspective rays) one lane per
//! point. The sampler's column draws are plain Rust over blocks of eight that
//! [`Backend::run`] only compiles per backend (the compiler vectorises them).
//!
//! The kernels are written once, generic over [`Simd`], and instantiated twice: with
//! [`Portable`] (two glam `Vec4`, i.e. SSE on x86-64 and scalar code elsewhere) and, on
//! x86-64, with [`Avx2`] (one 256-bit register per value). An [`Avx2`] token can only be
//! obtained from [`Avx2::detect`], which checks that the CPU has AVX2 and FMA, so every
//! operation on [`Avx2`] lanes runs on a CPU that has those instructions. The AVX2
//! instantiation is compiled inside a `#[target_feature(enable = "avx2,fma")]` function
//! ([`Backend::run`], or [`crate::intersect`]'s own), into which these `#[inline(always)]`
//! wrappers and the intrinsics they call are inlined. Every kernel has a scalar reference
//! and a test that each backend this CPU runs computes its bits.

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Sub};

use glam::{BVec4A, Vec3, Vec4};

/// Eight f32 in memory, aligned for one 256-bit load.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct Row8(pub(crate) [f32; 8]);

/// A lane-wise comparison result.
pub(crate) trait Mask8: Copy + BitAnd<Output = Self> + BitOr<Output = Self> {
    /// Bit `l` set where lane `l` is true.
    fn bits(self) -> u32;
    /// True where `self` is and `o` is not.
    fn and_not(self, o: Self) -> Self;
}

/// Eight f32 lanes.
pub(crate) trait Lanes8:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// The comparison result.
    type Mask: Mask8;
    /// Lane-wise minimum (either operand where one is NaN).
    fn min(self, o: Self) -> Self;
    /// Lane-wise maximum (either operand where one is NaN).
    fn max(self, o: Self) -> Self;
    /// Lane-wise magnitude.
    fn abs(self) -> Self;
    /// Lane-wise square root (correctly rounded, as `f32::sqrt`).
    fn sqrt(self) -> Self;
    /// The sign bit flipped (as `-x` on `f32`).
    fn neg(self) -> Self;
    /// The magnitude of `self` with the sign bit of `sign` (as `f32::copysign`).
    fn copysign(self, sign: Self) -> Self;
    /// `a` where `m` is true, else `b`.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
    /// `neg` where `sign` is negative, else `pos` (`sign` is never zero or NaN).
    fn select_negative(sign: Self, neg: Self, pos: Self) -> Self;
    /// `self * a + b`, with one rounding where the CPU has FMA and two otherwise. Only for
    /// the node test, whose error bound holds either way; the triangle test never fuses,
    /// so that both kernels compute the same bits.
    fn mul_add(self, a: Self, b: Self) -> Self;
    /// `self <= o` (false for NaN).
    fn le(self, o: Self) -> Self::Mask;
    /// `self < o` (false for NaN).
    fn lt(self, o: Self) -> Self::Mask;
    /// `self > o` (false for NaN).
    fn gt(self, o: Self) -> Self::Mask;
    /// `self == o` (false for NaN; `-0 == 0`).
    fn eq(self, o: Self) -> Self::Mask;
    /// Bit `l` set where lane `l` has its sign bit set.
    fn sign_bits(self) -> u32;
    /// The sign bits of `self`, `b` and `c` (as [`Self::sign_bits`]) combined: set in all
    /// three, and set in any.
    #[inline(always)]
    fn sign_bits_all_any(self, b: Self, c: Self) -> (u32, u32) {
        let (x, y, z) = (self.sign_bits(), b.sign_bits(), c.sign_bits());
        (x & y & z, x | y | z)
    }
    /// The lanes in memory order.
    fn to_array(self) -> [f32; 8];
}

/// An instruction set the kernels run on: creates lanes.
pub(crate) trait Simd: Copy {
    /// The lane type.
    type F: Lanes8;
    /// All lanes `x`.
    fn splat(self, x: f32) -> Self::F;
    /// The eight values of `r`.
    fn load(self, r: &Row8) -> Self::F;
    /// The x, y and z coordinates of eight points, as three rows (lane `l` point `l`).
    fn load_xyz(self, v: &[Vec3; 8]) -> [Self::F; 3];
    /// Lane `l` is `table.0[index[l]]`, with every lane of `index` one of the whole
    /// numbers `0..8`.
    fn lookup(self, table: &Row8, index: Self::F) -> Self::F;
}

/// Portable lanes: two glam `Vec4`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Portable;

/// [`Portable`]'s lanes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct P8([Vec4; 2]);

/// [`Portable`]'s comparison result.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PMask([BVec4A; 2]);

impl Simd for Portable {
    type F = P8;
    #[inline(always)]
    fn splat(self, x: f32) -> P8 {
        P8([Vec4::splat(x); 2])
    }
    #[inline(always)]
    fn load(self, r: &Row8) -> P8 {
        let [a, b, c, d, e, f, g, h] = r.0;
        P8([Vec4::new(a, b, c, d), Vec4::new(e, f, g, h)])
    }
    #[inline(always)]
    fn load_xyz(self, v: &[Vec3; 8]) -> [P8; 3] {
        let row = |a: usize| {
            P8([
                Vec4::new(v[0][a], v[1][a], v[2][a], v[3][a]),
                Vec4::new(v[4][a], v[5][a], v[6][a], v[7][a]),
            ])
        };
        [row(0), row(1), row(2)]
    }
    #[inline(always)]
    fn lookup(self, table: &Row8, index: P8) -> P8 {
        self.load(&Row8(index.to_array().map(|i| table.0[i as usize & 7])))
    }
}

macro_rules! portable_binop {
    ($tr:ident, $f:ident) => {
        impl $tr for P8 {
            type Output = P8;
            #[inline(always)]
            fn $f(self, o: P8) -> P8 {
                P8([self.0[0].$f(o.0[0]), self.0[1].$f(o.0[1])])
            }
        }
    };
}
portable_binop!(Add, add);
portable_binop!(Sub, sub);
portable_binop!(Mul, mul);
portable_binop!(Div, div);

impl BitAnd for PMask {
    type Output = PMask;
    #[inline(always)]
    fn bitand(self, o: PMask) -> PMask {
        PMask([self.0[0] & o.0[0], self.0[1] & o.0[1]])
    }
}

impl BitOr for PMask {
    type Output = PMask;
    #[inline(always)]
    fn bitor(self, o: PMask) -> PMask {
        PMask([self.0[0] | o.0[0], self.0[1] | o.0[1]])
    }
}

impl Mask8 for PMask {
    #[inline(always)]
    fn bits(self) -> u32 {
        self.0[0].bitmask() | (self.0[1].bitmask() << 4)
    }
    #[inline(always)]
    fn and_not(self, o: PMask) -> PMask {
        PMask([self.0[0] & !o.0[0], self.0[1] & !o.0[1]])
    }
}

impl Lanes8 for P8 {
    type Mask = PMask;
    #[inline(always)]
    fn min(self, o: P8) -> P8 {
        P8([self.0[0].min(o.0[0]), self.0[1].min(o.0[1])])
    }
    #[inline(always)]
    fn max(self, o: P8) -> P8 {
        P8([self.0[0].max(o.0[0]), self.0[1].max(o.0[1])])
    }
    #[inline(always)]
    fn abs(self) -> P8 {
        P8([self.0[0].abs(), self.0[1].abs()])
    }
    #[inline(always)]
    fn sqrt(self) -> P8 {
        P8([self.0[0].sqrt(), self.0[1].sqrt()])
    }
    #[inline(always)]
    fn neg(self) -> P8 {
        P8([-self.0[0], -self.0[1]])
    }
    #[inline(always)]
    fn copysign(self, sign: P8) -> P8 {
        P8([self.0[0].copysign(sign.0[0]), self.0[1].copysign(sign.0[1])])
    }
    #[inline(always)]
    fn select_negative(sign: P8, neg: P8, pos: P8) -> P8 {
        P8::select(sign.lt(P8([Vec4::ZERO; 2])), neg, pos)
    }
    #[inline(always)]
    fn select(m: PMask, a: P8, b: P8) -> P8 {
        P8([
            Vec4::select(m.0[0], a.0[0], b.0[0]),
            Vec4::select(m.0[1], a.0[1], b.0[1]),
        ])
    }
    #[inline(always)]
    fn mul_add(self, a: P8, b: P8) -> P8 {
        self * a + b
    }
    #[inline(always)]
    fn le(self, o: P8) -> PMask {
        PMask([self.0[0].cmple(o.0[0]), self.0[1].cmple(o.0[1])])
    }
    #[inline(always)]
    fn lt(self, o: P8) -> PMask {
        PMask([self.0[0].cmplt(o.0[0]), self.0[1].cmplt(o.0[1])])
    }
    #[inline(always)]
    fn gt(self, o: P8) -> PMask {
        PMask([self.0[0].cmpgt(o.0[0]), self.0[1].cmpgt(o.0[1])])
    }
    #[inline(always)]
    fn eq(self, o: P8) -> PMask {
        PMask([self.0[0].cmpeq(o.0[0]), self.0[1].cmpeq(o.0[1])])
    }
    #[inline(always)]
    fn sign_bits(self) -> u32 {
        self.0[0].is_negative_bitmask() | (self.0[1].is_negative_bitmask() << 4)
    }
    #[inline(always)]
    fn to_array(self) -> [f32; 8] {
        let (a, b) = (self.0[0].to_array(), self.0[1].to_array());
        [a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]]
    }
}

/// A computation written once over the lanes of any [`Simd`], run by [`Backend::run`].
pub(crate) trait Kernel8 {
    /// What the computation returns.
    type Output;
    /// The computation on the lanes of `s`; `#[inline(always)]`, so that it is compiled
    /// with the target features of [`Backend::run`]'s instantiation.
    fn run<S: Simd>(self, s: S) -> Self::Output;
}

/// A lane implementation this CPU was checked to run (the AVX2 variant holds the token).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Backend {
    /// [`Portable`] lanes.
    Portable,
    /// [`Avx2`] lanes.
    #[cfg(target_arch = "x86_64")]
    Avx2(Avx2),
}

impl Backend {
    /// The fastest backend this CPU runs.
    #[inline]
    pub(crate) fn best() -> Self {
        #[cfg(target_arch = "x86_64")]
        if let Some(t) = Avx2::detect() {
            return Backend::Avx2(t);
        }
        Backend::Portable
    }

    /// Every backend this CPU runs (for the tests that compare them with the scalar
    /// references).
    #[cfg(test)]
    pub(crate) fn all() -> Vec<Self> {
        let mut all = vec![Backend::Portable];
        #[cfg(target_arch = "x86_64")]
        all.extend(Avx2::detect().map(Backend::Avx2));
        all
    }

    /// Runs `k` on this backend's lanes.
    #[inline]
    pub(crate) fn run<K: Kernel8>(self, k: K) -> K::Output {
        match self {
            Backend::Portable => k.run(Portable),
            #[cfg(target_arch = "x86_64")]
            Backend::Avx2(t) => avx2::run(t, k),
        }
    }
}

#[cfg(target_arch = "x86_64")]
pub(crate) use avx2::Avx2;

#[cfg(target_arch = "x86_64")]
#[allow(
    unsafe_code,
    reason = "AVX2 intrinsics, only reachable through an `Avx2` token (CPU support checked)"
)]
mod avx2 {
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
            (is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"))
                .then_some(Avx2(()))
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
}
