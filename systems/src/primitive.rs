//! The primitives of a compiled scene, apart from the aggregate over them ([`SceneGeometry`]
//! and its BVH): the analytic sphere, the triangle with its normal and area, a surface point and the error
//! bounds of its position. The BVH (`crate::bvh8`), the geometry and the intersection
//! systems all build on these; [`crate::geometry`] re-exports the public ones.
//!
//! [`SceneGeometry`]: crate::geometry::SceneGeometry

use glam::{DVec3, Vec2, Vec3, Vec3A};

/// An analytic sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre in world space.
    pub center: Vec3,
    /// Radius (> 0).
    pub radius: f32,
}

/// Geometry of a surface point found by a ray hit or by sampling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceSample {
    /// World-space position.
    pub p: Vec3,
    /// Unit geometric normal. Triangles: `normalize((v1 - v0) x (v2 - v0))`; spheres: outward.
    pub ng: Vec3,
    /// Surface parameters. Triangles: barycentrics `(b1, b2)` of `v1` and `v2`; spheres:
    /// always `(0, 0)` from [`SceneGeometry::surface_at`] (their parameters cost two `atan2`
    /// that hardly any material wants: [`SceneGeometry::surface_uv`] computes them).
    ///
    /// [`SceneGeometry::surface_at`]: crate::geometry::SceneGeometry::surface_at
    /// [`SceneGeometry::surface_uv`]: crate::geometry::SceneGeometry::surface_uv
    pub uv: Vec2,
    /// Conservative per-component absolute bound of `p`'s rounding error: a point of the
    /// exact surface lies in the box `p +- p_error` (pbrt-v4 sec. 6.8; how each shape's
    /// bound is derived: [`triangle_point_error`], [`sphere_point_error`]).
    pub p_error: Vec3,
}

impl SurfaceSample {
    /// `dot(|ng|, p_error)`: how far along `ng` the surface can be from `p`, the distance a
    /// ray spawned here moves off ([`crate::ray::spawn_origin`]).
    #[inline(always)]
    pub fn offset(&self) -> f32 {
        surface_offset(self.ng, self.p_error)
    }
}

/// `dot(|ng|, p_error)` (pbrt-v4's `OffsetRayOrigin`): the largest distance along the unit
/// normal `ng` between a point and the surface it is within `p_error` of.
#[inline(always)]
pub fn surface_offset(ng: Vec3, p_error: Vec3) -> f32 {
    ng.abs().dot(p_error)
}

/// `gamma(n) = n eps / (1 - n eps)` with `eps = 2^-24` (unit roundoff): the relative error
/// bound of `n` chained f32 operations (Higham; pbrt-v4 sec. 6.8.1).
#[inline(always)]
pub(crate) const fn gamma(n: f32) -> f32 {
    let e = f32::EPSILON * 0.5;
    n * e / (1.0 - n * e)
}

/// The smallest subnormal: bounds the absolute error of an f32 product or sum that
/// underflows (the relative bounds `gamma` do not cover results below `f32::MIN_POSITIVE`).
pub(crate) const UNDERFLOW: f32 = f32::from_bits(8);

/// Error bound of `p = v0 b0 + v1 b1 + v2 b2` computed in f32 as [`SceneGeometry::surface_at`] interpolates
/// triangle hits,
/// with `b0 = (1 - b1) - b2` rounded (`b0` here is that computed value), against the exact
/// point `(1 - b1 - b2) v0 + b1 v1 + b2 v2` of the triangle's plane.
///
/// pbrt-v4 sec. 6.8.6 bounds a barycentric point by `gamma(7) sum |b_i p_i|` with all three
/// `b_i` from the intersection test; here `b0` is derived from `b1, b2`, which is exact in
/// its own right but for the rounding of `b0`: `fl(fl(1 - b1) - b2)` errs by at most
/// `gamma(2) (1 + |b1| + |b2|)`, an error that multiplies `v0` whatever `b0`'s size (near
/// the edge `v1 v2`, `b0` is small while its error is not), so the bound is
/// - `gamma(3) sum |b_i v_i|` for the three products and two sums (Higham's bound of a
///   sum of products), plus
/// - `gamma(2) (1 + |b1| + |b2|) |v0|` for `b0`'s rounding,
///
/// each `gamma` raised by one to cover the rounding of the bound's own arithmetic, and a
/// few subnormals for products that underflow. Per component: a floor at `y = 0` has
/// `p_error.y = 0` whatever its `x` and `z`.
///
/// [`SceneGeometry::surface_at`]: crate::geometry::SceneGeometry::surface_at
#[inline(always)]
pub fn triangle_point_error(v: [Vec3A; 3], b0: f32, b1: f32, b2: f32) -> Vec3 {
    let [v0, v1, v2] = v.map(Vec3A::abs);
    let sum = v0 * b0.abs() + v1 * b1.abs() + v2 * b2.abs();
    let e = sum * gamma(4.0) + v0 * (gamma(3.0) * (1.0 + b1.abs() + b2.abs()));
    Vec3::from(e) + Vec3::splat(UNDERFLOW)
}

/// Error bound of a sphere point computed as `(centre + n r)` in double precision from the
/// f32 centre and radius and a unit `n` normalised in double precision, then rounded once to
/// f32 (`p` is that rounded point): the f64 point is within about ten f64 ulps of `|centre| +
/// r` of the exact sphere (`n`'s length errs by a few ulps, the sum by two), bounded by
/// `2^-48 (|centre_i| + r)`, and the final rounding adds half an f32 ulp of `p_i`, bounded by
/// `eps |p_i|` plus a subnormal. pbrt-v4 (sec. 6.8.6) re-projects an f32 point and bounds it
/// by `gamma(5) |p|`; one rounding from f64 is tighter by a factor of ten, and per component.
#[inline(always)]
pub fn sphere_point_error(center: Vec3, radius: f32, p: Vec3) -> Vec3 {
    const F64_PART: f32 = 1.0 / (1u64 << 48) as f32;
    p.abs() * f32::EPSILON
        + (center.abs() + Vec3::splat(radius)) * F64_PART
        + Vec3::splat(UNDERFLOW)
}

/// A triangle with its unit geometric normal and area, made where a hit or a light sample
/// needs them from the vertices its BVH leaf packet holds ([`crate::geometry::Triangles`]):
/// not stored, since a 64-byte record per triangle repeated the packets' vertices (issue 36,
/// memory per triangle). In 16-byte lanes: interpolating a point is three SIMD multiplies and
/// two adds, lane by lane the same float operations as on `Vec3`s.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Triangle {
    pub(crate) v: [Vec3A; 3],
    /// `normalize((v1 - v0) x (v2 - v0))`, zero for a degenerate triangle.
    ng: Vec3,
}

impl Triangle {
    /// The triangle of `v` with its normal: inlined where hits are shaded (a call per hit
    /// cost more than the arithmetic), the overflowing case apart.
    #[inline(always)]
    pub(crate) fn new(v: [Vec3; 3]) -> Self {
        let c = (v[1] - v[0]).cross(v[2] - v[0]);
        // `|c|^2` is finite exactly when `c` and `|c|` are.
        let ng = if c.length_squared().is_finite() {
            c.normalize_or_zero()
        } else {
            wide_cross(v).normalize_or_zero().as_vec3()
        };
        Triangle {
            v: v.map(Vec3A::from),
            ng,
        }
    }

    /// The area, `|(v1 - v0) x (v2 - v0)| / 2` (saturating at `f32::MAX`).
    pub(crate) fn area(&self) -> f32 {
        let v = self.v.map(Vec3::from);
        let c = (v[1] - v[0]).cross(v[2] - v[0]);
        if c.length_squared().is_finite() {
            0.5 * c.length()
        } else {
            (0.5 * wide_cross(v).length()).min(f32::MAX as f64) as f32
        }
    }

    /// Barycentric interpolation of the vertices (`b0 = 1 - b1 - b2`).
    #[inline(always)]
    fn point(&self, b1: f32, b2: f32) -> Vec3 {
        let [v0, v1, v2] = self.v;
        let b0 = 1.0 - b1 - b2;
        (v0 * b0 + v1 * b1 + v2 * b2).into()
    }

    #[inline(always)]
    pub(crate) fn ng(&self) -> Vec3 {
        self.ng
    }

    /// [`SceneGeometry::surface_at`] on this triangle.
    ///
    /// [`SceneGeometry::surface_at`]: crate::geometry::SceneGeometry::surface_at
    #[inline(always)]
    pub(crate) fn surface_at(&self, b1: f32, b2: f32) -> SurfaceSample {
        let b0 = 1.0 - b1 - b2;
        SurfaceSample {
            p: self.point(b1, b2),
            ng: self.ng(),
            uv: Vec2::new(b1, b2),
            p_error: triangle_point_error(self.v, b0, b1, b2),
        }
    }
}

/// `(v1 - v0) x (v2 - v0)` in f64: edges beyond about 1e19 overflow f32's cross product.
#[cold]
#[inline(never)]
fn wide_cross(v: [Vec3; 3]) -> DVec3 {
    let [a, b, c] = v.map(Vec3::as_dvec3);
    (b - a).cross(c - a)
}

/// Surface parameters `(phi / 2pi, theta / pi)` of the direction `h` (centre to point).
pub(crate) fn sphere_uv(h: DVec3) -> Vec2 {
    use std::f64::consts::PI as PI64;
    // atan2 of (sin, cos) keeps full precision near the poles, unlike acos(z / r).
    let theta = h.x.hypot(h.y).atan2(h.z);
    let mut phi = h.y.atan2(h.x);
    if phi < 0.0 {
        phi += 2.0 * PI64;
    }
    // u must stay below 1 after rounding so it is a valid [0, 1) parameter.
    let u = ((phi / (2.0 * PI64)) as f32).min(1.0 - f32::EPSILON / 2.0);
    Vec2::new(u, (theta / PI64) as f32)
}

/// The unit direction (in double precision) from the centre of `s` to the hit at
/// `t + b1` (the double-precision root, see [`SceneGeometry::surface_at`]) on the ray
/// `origin + t direction`; `+z` for a degenerate input.
///
/// [`SceneGeometry::surface_at`]: crate::geometry::SceneGeometry::surface_at
#[inline]
pub(crate) fn sphere_hit_dir(s: Sphere, origin: Vec3, direction: Vec3, t: f32, b1: f32) -> DVec3 {
    let t64 = t as f64 + if b1.is_finite() { b1 as f64 } else { 0.0 };
    let h = (origin.as_dvec3() - s.center.as_dvec3()) + direction.as_dvec3() * t64;
    // A hit lies on the sphere to f64 precision (t plus the root's residual in `b1`), or to
    // f32 precision without it, so g = h / r has |g|^2 = 1 + e with |e| < 1e-6, and
    // 1/|g| = (1 + e)^(-1/2) = 1 - e/2 + 3e^2/8 - O(e^3): the series to second order is
    // within 5|e|^3/16 (< 4e-19) of it, below the f64 rounding that `normalize` commits
    // itself. This trades normalize's square root and second division, a latency chain on
    // every sphere hit, for multiplications; points off the sphere (not hits) normalize.
    let g = h * (1.0 / s.radius as f64);
    let e = g.length_squared() - 1.0;
    if e.abs() < 1e-6 {
        g * (1.0 - e * (0.5 - 0.375 * e))
    } else {
        h.try_normalize().unwrap_or(DVec3::Z)
    }
}
