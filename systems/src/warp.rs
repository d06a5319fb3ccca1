//! The sampling geometry shared by surfaces and media: the shading [`Frame`] and the warps
//! from the unit square to the disk, hemisphere, sphere, cone and triangle. Below both
//! [`crate::bxdf`] and [`crate::phase`], which use it; `bxdf` re-exports the public items at
//! their old paths.

use risotto_components::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4, PI};
use std::ops::{Add, Mul, Sub};

/// `1 / (4 pi)`: the density of the uniform distribution on the unit sphere.
pub const INV_4PI: f32 = 0.25 * FRAC_1_PI;

/// An orthonormal, right-handed basis (`s x t = n`) around a unit normal `n`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// First tangent.
    pub s: Vec3,
    /// Second tangent (`n x s`).
    pub t: Vec3,
    /// The normal; maps to local `+z`.
    pub n: Vec3,
}

impl Frame {
    /// Builds a frame from a **unit** normal with the branchless construction of Duff et al.
    /// 2017, "Building an Orthonormal Basis, Revisited" (JCGT 6(1)), listing 3. It is
    /// continuous everywhere except across `n.z = 0` with `n.z` changing sign, and -- unlike
    /// Frisvad's original -- stays accurate as `n` approaches `-z`.
    pub fn from_normal(n: Vec3) -> Self {
        // copysign rather than signum so that n.z = -0.0 takes the "-z" branch consistently
        // and never divides by zero: sign + n.z has |.| >= 1.
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }

    /// World direction to local coordinates (`n` becomes `+z`).
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Local coordinates to a world direction.
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

// ---------------------------------------------------------------------------------------
// Warps from the unit square
// ---------------------------------------------------------------------------------------

/// Maps `u` in `[0,1)^2` to the unit disk with Shirley and Chiu's concentric mapping
/// ("A Low Distortion Map Between Disk and Square", 1997): area preserving and continuous,
/// so stratification of `u` survives.
#[inline]
pub fn sample_concentric_disk(u: Vec2) -> Vec2 {
    let p = 2.0 * u - Vec2::ONE;
    if p.x == 0.0 && p.y == 0.0 {
        return Vec2::ZERO;
    }
    // Each wedge |x| > |y| maps radius |x| and angle phi in [-pi/4, pi/4] (the ratio of the
    // smaller to the larger coordinate is in [-1, 1]); the other wedge uses the angle
    // pi/2 - phi, whose sine and cosine are phi's cosine and sine.
    if p.x.abs() > p.y.abs() {
        let (sin, cos) = sin_cos_quarter_pi(FRAC_PI_4 * (p.y / p.x));
        Vec2::new(p.x * cos, p.x * sin)
    } else {
        let (sin, cos) = sin_cos_quarter_pi(FRAC_PI_4 * (p.x / p.y));
        Vec2::new(p.y * sin, p.y * cos)
    }
}

/// `(sin x, cos x)` for `|x| <= pi/4` without range reduction: the minimax polynomial
/// kernels of Cephes' `sinf`/`cosf` (S. L. Moshier, "Methods and Programs for Mathematical
/// Functions", 1989), accurate to about 1 ulp on this interval. Every diffuse bounce samples
/// a disk point, and libm's general `sincosf` (a call plus range reduction) was a visible
/// share of the shading time.
#[inline]
pub fn sin_cos_quarter_pi(x: f32) -> (f32, f32) {
    sin_cos_quarter_pi_with(x, SIN_COS_POLY)
}

/// The coefficients of [`sin_cos_quarter_pi`]: `sin` `S0..S2`, `cos` `C0..C2`, then `0.5`
/// and `1`.
pub(crate) const SIN_COS_POLY: [f32; 8] = [
    -1.951_529_6e-4,
    8.332_161e-3,
    1.666_665_5e-1,
    2.443_315_7e-5,
    1.388_731_6e-3,
    4.166_664_6e-2,
    0.5,
    1.0,
];

/// The body of [`sin_cos_quarter_pi`] on any number type (`f32`, or eight lanes), with
/// `k` the coefficients [`SIN_COS_POLY`] in that type.
#[inline(always)]
pub(crate) fn sin_cos_quarter_pi_with<T>(x: T, k: [T; 8]) -> (T, T)
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T>,
{
    let z = x * x;
    let sin = ((k[0] * z + k[1]) * z - k[2]) * z * x + x;
    let cos = (((k[3] * z - k[4]) * z + k[5]) * z * z - k[6] * z) + k[7];
    (sin, cos)
}

/// Cosine-weighted direction on the `+z` hemisphere (Malley's method: project a uniform
/// disk sample up onto the hemisphere). Density `cos theta / pi`. The result can have
/// `z = 0` when `u` is on the square's boundary.
#[inline]
pub fn sample_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = sample_concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Uniform direction on the unit sphere; density [`INV_4PI`]. `z = 1 - 2 u.x` is uniform by
/// Archimedes' hat-box theorem.
pub fn sample_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    // (1 - z)(1 + z) instead of 1 - z^2 keeps precision near the poles.
    let r = ((1.0 - z) * (1.0 + z)).max(0.0).sqrt();
    let (sin, cos) = (2.0 * PI * u.y).sin_cos();
    Vec3::new(r * cos, r * sin, z)
}

/// Uniform direction in the cone of half-angle `acos(cos_max)` around `+z`; density
/// [`uniform_cone_pdf`]. `cos theta` is uniform on `[cos_max, 1]` (hat-box again).
pub fn sample_uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let cos_max = cos_max.clamp(-1.0, 1.0);
    // 1 - cos theta = u (1 - cos_max), computed directly so narrow cones keep their
    // resolution (cos theta itself would round to 1).
    let one_minus_cos = u.x * (1.0 - cos_max);
    let z = 1.0 - one_minus_cos;
    let r = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0).sqrt();
    let (sin, cos) = (2.0 * PI * u.y).sin_cos();
    Vec3::new(r * cos, r * sin, z)
}

/// Density of [`sample_uniform_cone`]: `1 / (2 pi (1 - cos_max))` (infinite for a
/// degenerate cone, where the distribution is a Dirac delta).
pub fn uniform_cone_pdf(cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * (1.0 - cos_max.clamp(-1.0, 1.0)))
}

/// Uniformly distributed barycentrics `(b0, b1)` on a triangle (`b2 = 1 - b0 - b1`), with the
/// low-distortion warp of Heitz 2019 ("A Low-Distortion Map Between Triangle and Square"):
/// an offset along the diagonal instead of the classic `sqrt(u)` fold, which keeps
/// neighbouring `u` neighbours on the triangle.
pub fn sample_uniform_triangle(u: Vec2) -> Vec2 {
    let (b0, b1) = if u.x < u.y {
        let b0 = 0.5 * u.x;
        (b0, u.y - b0)
    } else {
        let b1 = 0.5 * u.y;
        (u.x - b1, b1)
    };
    Vec2::new(b0, b1)
}
