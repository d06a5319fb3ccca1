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
    /// The inverse of [`Self::load_xyz`]: point `l` of `out` made of lane `l` of the
    /// three rows.
    fn store_xyz(self, xyz: [Self::F; 3], out: &mut [Vec3; 8]);
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
    fn store_xyz(self, [x, y, z]: [P8; 3], out: &mut [Vec3; 8]) {
        let (x, y, z) = (x.to_array(), y.to_array(), z.to_array());
        for l in 0..8 {
            out[l] = Vec3::new(x[l], y[l], z[l]);
        }
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

/// Which implementation runs the intersection kernels ([`intersect_closest`],
/// [`intersect_occluded`]). Both traverse the same tree and run the same watertight test
/// with the same roundings, so they report the same hits; only the node test may differ in
/// the last bit (fused multiply-add), which its widening covers. The public name of a lane
/// backend of this module, re-exported as `crate::intersect::Kernel`.
///
/// [`intersect_closest`]: crate::intersect::intersect_closest
/// [`intersect_occluded`]: crate::intersect::intersect_occluded
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// Eight lanes as two glam `Vec4` (SSE on x86-64); runs everywhere.
    Portable,
    /// Eight lanes in one AVX2 register, with FMA in the node test; x86-64 CPUs with AVX2
    /// and FMA only.
    Avx2,
}

impl Kernel {
    /// The fastest kernel this CPU runs (what [`SceneGeometry::build`] selects).
    ///
    /// [`SceneGeometry::build`]: crate::geometry::SceneGeometry::build
    pub fn best() -> Self {
        if Self::Avx2.is_supported() {
            Self::Avx2
        } else {
            Self::Portable
        }
    }

    /// Whether this CPU runs the kernel.
    pub fn is_supported(self) -> bool {
        self.backend().is_some()
    }

    /// The backend token, if this CPU runs the kernel.
    pub(crate) fn backend(self) -> Option<Backend> {
        match self {
            Kernel::Portable => Some(Backend::Portable),
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 => Avx2::detect().map(Backend::Avx2),
            #[cfg(not(target_arch = "x86_64"))]
            Kernel::Avx2 => None,
        }
    }
}

impl Backend {
    /// The public name.
    pub(crate) fn kernel(self) -> Kernel {
        match self {
            Backend::Portable => Kernel::Portable,
            #[cfg(target_arch = "x86_64")]
            Backend::Avx2(_) => Kernel::Avx2,
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
mod avx2;
