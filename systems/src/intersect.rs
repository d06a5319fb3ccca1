//! Ray/scene intersection systems: closest hit and occlusion over columns of rays.
//!
//! Traversal runs over the uncompressed 8-wide BVH of [`SceneGeometry`] (f32 child boxes
//! stored as SoA rows, triangle leaves as 8-lane packets, see `crate::bvh8`), with eight
//! SIMD lanes: one ray against eight child boxes is a dozen lane-wise multiply-adds and
//! min/max with no decoding, and one ray against the up to eight triangles of a leaf is one
//! pass of the watertight test. The kernels are generic over the lane implementation
//! (`crate::simd8`) and instantiated twice, selected by [`Kernel`]: portable code, and AVX2
//! with FMA in the node test, chosen at run time when the CPU has them. The node test
//! honours the ray's `tmin` and widens every slab by a bound on its floating-point error (a
//! per-ray constant, see `NODE_SLACK`), so a box is never culled when the primitive test
//! would report a hit inside it (a plain slab test loses rays grazing box faces, e.g. along
//! the edges of an axis-aligned mesh); it also culls, with exact comparisons, children
//! whose box lies wholly behind the origin across an axis, which the triangle test would
//! reject anyway, so a ray spawned on a wall does not visit the wall's leaf (a third of
//! the leaf visits on the Cornell box). Closest-hit rays visit hit children, leaves
//! included, nearest entry distance first and skip stacked ones beyond the closest hit so
//! far; shadow rays test a node's hit leaves at once and stop at the first hit.
//! Primitive tests:
//! - triangles: watertight test of Woop, Benthin and Wald 2013 ("Watertight Ray/Triangle
//!   Intersection", JCGT 2(1)), two-sided. The scalar form ([`WatertightRay`]) works on
//!   triangles stored coordinate by coordinate ([`PackedTriangle`]) so the three vertices
//!   are sheared and the three edge functions evaluated together; the leaf packets run the
//!   same operations in the same order with one triangle per lane (bit-identical results,
//!   no fused multiply-add), and leave lanes with an edge function exactly zero to the
//!   scalar test and its double-precision fallback. Rays through shared edges and vertices
//!   of a closed mesh cannot slip through;
//! - spheres: the quadratic in the form of Haines et al. 2019 ("Precision Improvements for
//!   Ray/Sphere Intersection", Ray Tracing Gems ch. 7), evaluated in double precision so
//!   tiny spheres far away and huge spheres seen from close by stay accurate.
//!
//! Hits are accepted for `tmin < t < tmax`; a triangle hit must also be farther beyond
//! `tmin` than the rounding-error bound of its computed `t` (pbrt-v4's conservative t, with
//! the terms that grow with the distance to the origin tightened, see `t_error_bound`), so
//! that rays spawned on a large triangle, or walks that restart just past a hit, do not find
//! the same surface again. For rays from a free origin ([`FREE_ORIGIN`], camera rays) a hit
//! within the f32 bound is decided again in double precision, whose bound is 2^29 times
//! smaller: a camera 1e-6 above a 40-unit floor sees the floor.

use std::marker::PhantomData;

use glam::{Vec3, Vec3A, Vec4, Vec4Swizzles};
use risotto_components::NO_HIT;

use crate::bvh8::{Bvh8, Node8, SphereLeaf, TriPacket8, INDEX_MASK, LEAF, SPHERE, WIDTH};
use crate::geometry::SceneGeometry;
#[cfg(target_arch = "x86_64")]
use crate::simd8::Avx2;
use crate::simd8::{Backend, Lanes8, Mask8, Portable, Row8, Simd};

/// A ray/triangle hit: distance and the barycentrics of `v1` and `v2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Hit distance along the ray (in units of the direction's length).
    pub t: f32,
    /// Barycentric weight of `v1`.
    pub b1: f32,
    /// Barycentric weight of `v2`.
    pub b2: f32,
}

/// A triangle stored coordinate by coordinate, the layout the triangle test reads:
/// `rows[a]` holds coordinate `a` (x, y, z) of `v0, v1, v2` in lanes 0, 1, 2 (lane 3 is
/// zero). The BVH leaves use the same layout, so one triangle costs three aligned loads and
/// the three vertices are transformed together.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PackedTriangle {
    pub(crate) rows: [Vec4; 3],
}

impl PackedTriangle {
    /// Packs the triangle `(v0, v1, v2)`.
    #[inline]
    pub fn new(v0: Vec3, v1: Vec3, v2: Vec3) -> Self {
        Self {
            rows: [
                Vec4::new(v0.x, v1.x, v2.x, 0.0),
                Vec4::new(v0.y, v1.y, v2.y, 0.0),
                Vec4::new(v0.z, v1.z, v2.z, 0.0),
            ],
        }
    }
}

/// A coordinate axis; as an index its range `0..3` is known to the compiler, so indexing a
/// three-element array with it needs no bounds check.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
enum Axis {
    X = 0,
    Y = 1,
    Z = 2,
}

/// The ray transform of the watertight test (Woop et al. 2013, sec. 3): the axis
/// permutation `(kx, ky, kz)` with `kz` the dominant direction axis, `kx = (kz + 1) % 3`,
/// `ky = (kx + 1) % 3`, the origin permuted to `(kx, ky, kz)`, and the shear constants
/// `(Sx, Sy, Sz) = (d[kx] / d[kz], d[ky] / d[kz], 1 / d[kz])` (paper eq. (2)).
#[inline(always)]
fn shear(origin: Vec3A, direction: Vec3A) -> (Axis, Axis, Axis, Vec3A, Vec3A) {
    // Branch-free: ray directions are random, so the axis choice is a coin toss that a
    // branch predictor gets wrong about every other ray. `kz` is X where `|d.x|` beats both
    // others, else Y where `|d.y|` beats `|d.z|` (and `|d.x|` does not beat `|d.y|`), else Z:
    // the same strict comparisons, so the same choice on ties, as the nested `if`s of the
    // paper's reference code.
    let a = direction.abs();
    let x_beats_y = a.x > a.y;
    let x_dominant = x_beats_y & (a.x > a.z);
    let y_dominant = !x_beats_y & (a.y > a.z);
    let kz = (!x_dominant as usize) * (1 + !y_dominant as usize);
    const AXES: [Axis; 5] = [Axis::X, Axis::Y, Axis::Z, Axis::X, Axis::Y];
    let (kx, ky, kz) = (AXES[kz + 1], AXES[kz + 2], AXES[kz]);
    let permute = |v: Vec3A| {
        let v = v.to_array();
        Vec3A::new(v[kx as usize], v[ky as usize], v[kz as usize])
    };
    let (o, d) = (permute(origin), permute(direction));
    // Each one division.
    (kx, ky, kz, o, Vec3A::new(d.x, d.y, 1.0) / d.z)
}

/// Per-ray precomputation of the watertight ray/triangle test (Woop et al. 2013, sec. 3):
/// the affine map that moves the origin to zero, makes the dominant direction axis `z` and
/// shears the ray onto the `+z` axis, so the 2D edge functions of the transformed vertices
/// decide the hit. A vertex shared by two triangles is transformed identically in both and
/// edge functions of a shared edge are exact negatives, which is what makes it watertight.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    /// Origin coordinate along `kx`, `ky`, `kz`, in every lane.
    ox: Vec4,
    oy: Vec4,
    oz: Vec4,
    /// The shear constants `Sx = d[kx] / d[kz]`, `Sy = d[ky] / d[kz]`, `Sz = 1 / d[kz]`
    /// (paper eq. (2)), in every lane.
    sx: Vec4,
    sy: Vec4,
    sz: Vec4,
    /// `|d[kx]|` and `|d[ky]|`, for the error bound of the sheared coordinates (see
    /// [`t_error_bound`]).
    adx: f32,
    ady: f32,
    /// The paper's axis permutation: `kz` is the dominant direction axis,
    /// `kx = (kz + 1) % 3`, `ky = (kx + 1) % 3`.
    kx: Axis,
    ky: Axis,
    kz: Axis,
}

impl WatertightRay {
    /// Precomputes the transform for the ray `origin + t * direction` (direction non-zero,
    /// not necessarily unit).
    #[inline]
    pub fn new(origin: Vec3, direction: Vec3) -> Self {
        let (kx, ky, kz, o, s) = shear(origin.into(), direction.into());
        Self {
            ox: Vec4::splat(o.x),
            oy: Vec4::splat(o.y),
            oz: Vec4::splat(o.z),
            sx: Vec4::splat(s.x),
            sy: Vec4::splat(s.y),
            sz: Vec4::splat(s.z),
            adx: direction[kx as usize].abs(),
            ady: direction[ky as usize].abs(),
            kx,
            ky,
            kz,
        }
    }

    /// Two-sided watertight intersection with triangle `(v0, v1, v2)`, accepting
    /// `tmin < t < tmax` where `t - tmin` also exceeds the error bound of the computed `t`.
    /// Degenerate triangles and rays in the triangle's plane miss.
    #[inline]
    pub fn intersect_triangle(
        &self,
        v0: Vec3A,
        v1: Vec3A,
        v2: Vec3A,
        tmin: f32,
        tmax: f32,
    ) -> Option<TriangleHit> {
        self.intersect_packed(
            &PackedTriangle::new(v0.into(), v1.into(), v2.into()),
            tmin,
            tmax,
        )
    }

    /// [`Self::intersect_triangle`] on a packed triangle (same result, bit for bit).
    #[inline(always)]
    pub fn intersect_packed(
        &self,
        tri: &PackedTriangle,
        tmin: f32,
        tmax: f32,
    ) -> Option<TriangleHit> {
        self.intersect_rows(&tri.rows, tmin, tmax)
    }

    #[inline(always)]
    fn intersect_rows(&self, rows: &[Vec4; 3], tmin: f32, tmax: f32) -> Option<TriangleHit> {
        // Lane i holds vertex i. Paper sec. 3: after translating and permuting,
        // A'x = A[kx] - Sx A[kz], A'y = A[ky] - Sy A[kz]; the products and differences are
        // rounded once each, the same for every triangle sharing the vertex.
        let z = rows[self.kz as usize] - self.oz;
        let x = (rows[self.kx as usize] - self.ox) - self.sx * z;
        let y = (rows[self.ky as usize] - self.oy) - self.sy * z;
        // Scaled barycentrics (2D edge functions), paper eq. (4)-(6), all three at once:
        // lanes (U, V, W) = (Cx By - Cy Bx, Ax Cy - Ay Cx, Bx Ay - By Ax).
        let uvw = x.zxyw() * y.yzxw() - y.zxyw() * x.yzxw();
        let uvw = if uvw.cmpeq(Vec4::ZERO).bitmask() & 0b111 != 0 {
            edge_functions_f64(x, y)?
        } else {
            // No edge function is zero: two-sided hit iff all three share a sign. (A NaN
            // lane may pass here; it makes `t` NaN, which the range test rejects.)
            let neg = uvw.is_negative_bitmask() & 0b111;
            if neg != 0 && neg != 0b111 {
                return None;
            }
            uvw
        };
        let (u, v, w) = (uvw.x, uvw.y, uvw.z);
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        // A'z = Sz A[kz] is only needed from here on.
        let z = z * self.sz;
        let scaled_t = u * z.x + v * z.y + w * z.z;
        let inv_det = 1.0 / det;
        let t = scaled_t * inv_det;
        if !(t > tmin && t < tmax) {
            // A ray from a free origin may still hit where f32 put `t` at or behind it.
            if from_free_origin(tmin) && t < tmax && -t <= t_error_bound(x, y, z, u, v, w, inv_det)
            {
                return self.near_hit_f64(rows, tmin, tmax);
            }
            return None;
        }
        // The computed `t` is only known to within `delta_t`; a hit that close to `tmin`
        // may lie on the wrong side of it (a ray spawned on this very triangle, or a walk
        // re-finding the triangle it just crossed, would hit it again). Reject it, as
        // pbrt-v4 does for `tmin = 0` ("Physically Based Rendering", 4th ed., sec. 6.8.7,
        // conservative ray-triangle t: bounds on the rounding of the transformed vertices,
        // the edge functions and the scaled t), unless double precision decides it.
        if t - tmin <= t_error_bound(x, y, z, t, inv_det, self.adx, self.ady) {
            return self.near_hit_f64(rows, tmin, tmax);
        }
        Some(TriangleHit {
            t,
            b1: v * inv_det,
            b2: w * inv_det,
        })
    }
}

impl WatertightRay {
    /// A hit the f32 test found within its error bound of `tmin`, decided again in double
    /// precision (the edge functions' signs as the f32 test found them, so closed meshes
    /// stay watertight). Only for rays from a free origin (`tmin = -0.0`, see
    /// [`FREE_ORIGIN`]): their origin is no computed surface point, so a hit the f64 `t`
    /// and its bound put past the origin is real. The f32 bound grows with the vertices' distance from the origin, not with the
    /// origin's distance from the triangle: it rejected the floor 1e-6 below a camera
    /// whenever the far corners, 20 units away, were sheared into the test (issue 14 item
    /// 4: the image's upper half saw through the floor). Walks that restart past a hit
    /// (`tmin > 0`) keep the f32 rejection: their `tmin` is measured from the f32 `t` of
    /// the surface they left.
    ///
    /// The shear constants are the f32 ones, which define a ray through the same origin
    /// whose direction differs by about 1e-7 relative: `t`'s sign is the same for both, its
    /// value agrees to that relative error.
    #[cold]
    #[inline(never)]
    fn near_hit_f64(&self, rows: &[Vec4; 3], tmin: f32, tmax: f32) -> Option<TriangleHit> {
        if !from_free_origin(tmin) {
            return None;
        }
        let [ox, oy, oz] = [self.ox.x, self.oy.x, self.oz.x].map(f64::from);
        let [sx, sy, sz] = [self.sx.x, self.sy.x, self.sz.x].map(f64::from);
        let (rx, ry, rz) = (
            rows[self.kx as usize].to_array(),
            rows[self.ky as usize].to_array(),
            rows[self.kz as usize].to_array(),
        );
        let mut x = [0.0f64; 3];
        let mut y = [0.0f64; 3];
        let mut z = [0.0f64; 3];
        for i in 0..3 {
            // The difference of two f32 values is exact in f64.
            z[i] = rz[i] as f64 - oz;
            x[i] = (rx[i] as f64 - ox) - sx * z[i];
            y[i] = (ry[i] as f64 - oy) - sy * z[i];
        }
        let u = x[2] * y[1] - y[2] * x[1];
        let v = x[0] * y[2] - y[0] * x[2];
        let w = x[1] * y[0] - y[1] * x[0];
        let det = u + v + w;
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let z = z.map(|z| z * sz);
        let t = (u * z[0] + v * z[1] + w * z[2]) / det;
        // pbrt-v4's bound (see `t_error_bound`) with the f64 unit roundoff, plus the
        // relative error of `t` from the shear constants' rounding.
        let gamma = |n: f64| {
            let e = f64::EPSILON * 0.5;
            n * e / (1.0 - n * e)
        };
        let max3 = |a: [f64; 3]| a[0].abs().max(a[1].abs()).max(a[2].abs());
        let (max_x, max_y, max_z) = (max3(x), max3(y), max3(z));
        let delta_z = gamma(3.0) * max_z;
        let delta_x = gamma(5.0) * (max_x + max_z);
        let delta_y = gamma(5.0) * (max_y + max_z);
        let delta_e = 2.0 * (gamma(2.0) * max_x * max_y + delta_y * max_x + delta_x * max_y);
        let max_e = max3([u, v, w]);
        let bound = 3.0 * (gamma(3.0) * max_e * max_z + delta_e * max_z + delta_z * max_e)
            / det.abs()
            + 4.0 * f32::EPSILON as f64 * t.abs();
        let t32 = t as f32;
        if !(t > bound && t32 > 0.0 && t32 < tmax) {
            return None;
        }
        Some(TriangleHit {
            t: t32,
            b1: (v / det) as f32,
            b2: (w / det) as f32,
        })
    }
}

/// The `tmin` of a ray whose origin is not a computed surface point (camera rays, probes
/// from a given point): `-0.0`, equal to `0.0` in every comparison, so such a ray is a
/// `tmin = 0` ray everywhere, except that hits within the triangle test's f32 error bound
/// of its origin are decided in double precision instead of rejected.
///
/// A ray spawned off a surface must keep `tmin = +0.0`: its origin is the surface point
/// moved off by the point's error bound ([`crate::ray::spawn_origin`]), which is zero where
/// the point is exact (a floor at `y = 0` has exact `y` coordinates), so such a ray may start
/// on its own surface, and only the triangle test's f32 bound on `t` rejects the re-hit at
/// `t ~ 0`.
pub const FREE_ORIGIN: f32 = -0.0;

/// Whether `tmin` marks a ray from a free origin ([`FREE_ORIGIN`]).
#[inline(always)]
fn from_free_origin(tmin: f32) -> bool {
    tmin.to_bits() == FREE_ORIGIN.to_bits()
}

/// `gamma(n) = n eps / (1 - n eps)` with `eps = 2^-24` (unit roundoff): the relative error
/// bound of `n` chained f32 operations (Higham; pbrt-v4 sec. 6.8.1).
#[inline(always)]
fn gamma(n: f32) -> f32 {
    let e = f32::EPSILON * 0.5;
    n * e / (1.0 - n * e)
}

/// Largest magnitude among lanes 0..3 (the three vertices).
#[inline(always)]
fn max_abs3(v: Vec4) -> f32 {
    let a = v.abs();
    a.x.max(a.y).max(a.z)
}

/// Absolute error bound of the `t` computed by [`WatertightRay::intersect_triangle`] from
/// the transformed vertices (coordinates `x, y, z`, one vertex per lane, `z` scaled by
/// `Sz`), the computed `t` and `1 / det`; `adx`, `ady` are `|d[kx]|`, `|d[ky]|`.
///
/// pbrt-v4's bound (sec. 6.8.7) with two of its worst cases replaced by the actual values,
/// because it grows with the distance from the origin to the triangle (`max|z|`) where the
/// error does not: a walk that keeps its origin and advances `tmin` past each hit (shadow
/// rays through boundaries, `engine/src/transmission.rs`) had exit hits 0.03 beyond `tmin`
/// rejected 19 units from its origin on a grazing tumbler wall (bound 0.09).
/// - The sheared `x' = x - Sx z` is rounded by `gamma(5) (|x'| + |Sx z|)`; pbrt takes
///   `|Sx| <= 1`, but `Sx z = d[kx] z'` with the scaled `z' = z / d[kz]`, so
///   `delta_x = gamma(7) (max|x'| + |d[kx]| max|z'|)` (two more roundings for `z'`), and
///   likewise `delta_y`. Edge functions are then within pbrt's
///   `delta_e = 2 (gamma(2) max|x'| max|y'| + delta_y max|x'| + delta_x max|y'|)`.
/// - `t = sum e_i z'_i / sum e_i` is a weighted mean of the `z'_i` (all `e_i` share a
///   sign), so errors `eps_i` in the edge functions move it by
///   `sum eps_i (z'_i - t) / det`: at most `k (max|z'_i - t| + delta_z + delta_t)` with
///   `k = 3 delta_e / |det|`, i.e. `k (max|z'_i - t| + delta_z) / (1 - k)`, below
///   `k (1 + 2k) (max|z'_i - t| + delta_z)` while `k <= 1/2`, where pbrt has `k max|z'|`;
///   the smaller of the two is used (pbrt's alone when `k > 1/2`).
/// - The rounding of the weighted mean itself (numerator `gamma(3)`, `det` `gamma(2)`,
///   `1 / det` and the product one each) and the error `delta_z = gamma(3) max|z'|` of the
///   `z'_i` add at most `gamma(10) max|z'|`.
#[inline(always)]
fn t_error_bound(x: Vec4, y: Vec4, z: Vec4, t: f32, inv_det: f32, adx: f32, ady: f32) -> f32 {
    let max_x = max_abs3(x);
    let max_y = max_abs3(y);
    let max_z = max_abs3(z);
    let spread = max_abs3(z - Vec4::splat(t));
    let delta_z = gamma(3.0) * max_z;
    let delta_x = gamma(7.0) * (max_x + adx * max_z);
    let delta_y = gamma(7.0) * (max_y + ady * max_z);
    let delta_e = 2.0 * (gamma(2.0) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    let k = 3.0 * delta_e * inv_det.abs();
    let lever = if k <= 0.5 {
        (1.0 + 2.0 * k) * (spread + delta_z)
    } else {
        max_z
    };
    gamma(10.0) * max_z + k * lever.min(max_z)
}

/// The paper's fallback (sec. 3, "if any edge function is exactly zero"): recompute in
/// double precision, where the products of f32 values are exact, so the sign of an edge
/// function that rounded to zero is resolved consistently for both triangles of an edge.
/// Returns the edge functions, or `None` if they have mixed signs (zeros lie on an edge
/// and count as either sign).
#[cold]
#[inline(never)]
fn edge_functions_f64(x: Vec4, y: Vec4) -> Option<Vec4> {
    let (ax, ay) = (x.x as f64, y.x as f64);
    let (bx, by) = (x.y as f64, y.y as f64);
    let (cx, cy) = (x.z as f64, y.z as f64);
    let u = (cx * by - cy * bx) as f32;
    let v = (ax * cy - ay * cx) as f32;
    let w = (bx * ay - by * ax) as f32;
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    Some(Vec4::new(u, v, w, 0.0))
}

/// The nearest root of the ray/sphere quadratic with `tmin < t < tmax` (compared after
/// rounding `t` to f32), in double precision.
fn sphere_t64(o: Vec3, d: Vec3, center: Vec3, radius: f32, tmin: f32, tmax: f32) -> Option<f64> {
    let (t0, t1) = sphere_roots64(o, d, center, radius, tmin, tmax)?;
    // The nearer root in range, without branches (a mispredicted branch here stalls the
    // traversal behind the square root and division).
    let t = if sphere_root_in_range(t0, tmin, tmax) {
        t0
    } else {
        t1
    };
    sphere_root_in_range(t, tmin, tmax).then_some(t)
}

/// Whether a sphere root lies in `(tmin, tmax)`, compared after rounding it to f32 (the
/// distance the hit reports).
#[inline(always)]
fn sphere_root_in_range(t: f64, tmin: f32, tmax: f32) -> bool {
    let t32 = t as f32;
    t32 > tmin && t32 < tmax
}

/// Both roots `t0 <= t1` of the ray/sphere quadratic in double precision, or `None` where
/// neither can lie in `(tmin, tmax)` (the early rejections below decide only that) or the
/// ray misses the sphere. The caller picks the roots in range
/// ([`sphere_root_in_range`]).
#[inline(always)]
fn sphere_roots64(
    o: Vec3,
    d: Vec3,
    center: Vec3,
    radius: f32,
    tmin: f32,
    tmax: f32,
) -> Option<(f64, f64)> {
    // A segment whose two ends lie inside the ball cannot cross the sphere (the ball is
    // convex). The margin (1e-3 of r^2, i.e. 5e-4 r) is far above the f32 rounding of the
    // ends, so the test is conservative; it spares the double-precision roots for the short
    // segments a random walk inside a dense medium traces by the million
    // (`risotto_engine::random_walk`). Unbounded rays skip it.
    if tmax.is_finite() {
        let r2 = radius * radius * (1.0 - 1e-3);
        let (a, b) = (o + d * tmin - center, o + d * tmax - center);
        if a.length_squared() < r2 && b.length_squared() < r2 {
            return None;
        }
    }
    let f = o.as_dvec3() - center.as_dvec3();
    let d = d.as_dvec3();
    let r = radius as f64;
    // |o + t d - c|^2 = r^2  <=>  a t^2 + 2 b t + cc = 0.
    let a = d.length_squared();
    let inv_a = 1.0 / a;
    let b = f.dot(d);
    // Ray Tracing Gems ch. 7 eq. (12): b^2 - a cc = a (r^2 - |l|^2) with l = f - (b/a) d the
    // perpendicular from the centre to the ray line, which avoids the catastrophic
    // cancellation of b^2 - a cc for distant spheres. The inputs are f32, so in f64 every
    // square is exact and r^2 - |l|^2 (like cc below) is off by a few f64 ulps of r^2: the
    // factored forms (r - |l|)(r + |l|) that f32 needs buy nothing here but two square roots.
    let cc = f.length_squared() - r * r;
    // Two rejections without the square root and division below (shadow rays walking out
    // of a medium and rays leaving a sphere make most sphere queries that miss). Both only
    // decide what the roots would: with `tmin >= 0`, an origin outside (or on) the sphere
    // moving away has both roots <= 0; an origin inside has one root on each side of 0, and
    // the polynomial at `tmin` is >= 0 exactly when `tmin` is at or past the far one (were
    // rounding to flip that sign, the root would lie within an f64 ulp of `tmin` and round
    // to it, which `t32 > tmin` rejects as well).
    if tmin >= 0.0 {
        let tm = tmin as f64;
        let past_exit = cc < 0.0 && (a * tm + 2.0 * b) * tm + cc >= 0.0;
        if (cc >= 0.0 && b >= 0.0) || past_exit {
            return None;
        }
    }
    let l = f - d * (b * inv_a);
    let disc = a * (r * r - l.length_squared());
    // Also rejects NaN (zero direction).
    if disc.is_nan() || disc < 0.0 {
        return None;
    }
    // Numerically stable root pair (eq. (13)-(14)): q has no cancellation; the small root
    // is cc / q, accurate for origins near the surface.
    let q = -(b + disc.sqrt().copysign(b));
    let (t0, t1) = if q == 0.0 {
        // b = 0 and disc = 0: the origin is on the sphere, moving tangentially.
        (0.0, 0.0)
    } else {
        let (x, y) = (cc / q, q * inv_a);
        (x.min(y), x.max(y))
    };
    Some((t0, t1))
}

/// Ray/sphere intersection: the nearest `t` with `tmin < t < tmax`, or `f32::INFINITY`.
/// A ray starting inside the sphere hits its far side.
pub fn intersect_sphere(
    origin: Vec3,
    direction: Vec3,
    center: Vec3,
    radius: f32,
    tmin: f32,
    tmax: f32,
) -> f32 {
    sphere_t64(origin, direction, center, radius, tmin, tmax).map_or(f32::INFINITY, |t| t as f32)
}

/// The double-precision root of [`intersect_sphere`] over `(0, inf)`, for the geometry
/// tests of the hit direction.
#[cfg(test)]
pub(crate) fn sphere_root_for_tests(o: Vec3, d: Vec3, s: crate::geometry::Sphere) -> Option<f64> {
    sphere_t64(o, d, s.center, s.radius, 0.0, f32::INFINITY)
}

/// Smallest direction component used in the slab test; `1/d` is clamped to `1e20` so no
/// infinities (and `0 * inf` NaNs) arise for axis-parallel rays.
const MIN_DIR: f32 = 1e-20;

/// Relative slab widening of the node test. A slab distance is computed as
/// `b * inv + near_orig` with `inv = fl(1/d)` and `near_orig = fl(fl(-o * inv) -+ s)`: with
/// unit roundoff `u = 2^-24` its error against `(b - o) / d` is below
/// `u (3 |b| + 4 |o|) / |d| + 2 u s` (standard model, Higham 2002 ch. 3: two roundings in
/// `b * inv`, two in `-o * inv`, one in the widening and one in the sum; a fused
/// multiply-add drops one of them), and `|b|` is at most the largest box coordinate
/// magnitude `B` on that axis. Widening by `s = 8 u (B + |o|) |inv|` therefore covers it on
/// every axis, for every node of the tree, so the widening is a per-ray constant folded
/// into `near_orig`/`far_orig`.
const NODE_SLACK: f32 = 4.0 * f32::EPSILON;

/// Which implementation runs the intersection kernels ([`intersect_closest`],
/// [`intersect_occluded`]). Both traverse the same tree and run the same watertight test
/// with the same roundings, so they report the same hits; only the node test may differ in
/// the last bit (fused multiply-add), which its widening covers.
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

/// Rays set up together: one lane of a [`RayBlock`] each.
const BLOCK: usize = 8;

/// The per-ray constants of both tests for up to [`BLOCK`] rays, one row per constant and
/// one lane per ray. [`RayBlock::set`] computes them for all lanes at once, with the same
/// operations per lane as [`shear`] and the per-ray formulas documented on the rows (so the
/// same bits), in the kernels' 8-lane operations: about 15 instructions per ray, where one
/// ray at a time it took about a hundred (cornell, 1 spp: closest-hit kernel 128.8M ->
/// 116.8M instructions, occlusion 37.2M -> 31.2M). The
/// traversal then reads ray `l`'s constants straight from lane `l` of the rows (one
/// broadcast from memory each, where a test needs them).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
struct RayBlock {
    /// The node test's rows `3 r + a`, axis `a`: `r = 0` is `1 / d`, with components below
    /// [`MIN_DIR`] clamped; `r = 1` and `r = 2` are the slab distance offsets of the box
    /// minimum and maximum planes, `-o / d - s` for the near one (the minimum where
    /// `d > 0`) and `-o / d + s` for the far one, so the widening `s` (see [`NODE_SLACK`])
    /// moves both planes outwards.
    node: [[f32; BLOCK]; 9],
    /// The triangle test's rows ([`WatertightRay`]'s constants): the origin permuted to
    /// `(kx, ky, kz)`, then the shear `(Sx, Sy, Sz)`, then `|d[kx]|` and `|d[ky]|`.
    tri: [[f32; BLOCK]; 8],
    /// The origin (rows 0 to 2) and the direction (rows 3 to 5), for the sphere and
    /// scalar fallback tests.
    od: [[f32; BLOCK]; 6],
    /// The node test's exact cull of boxes behind the origin (see [`intersect_node8`]),
    /// axis `a`: row `a` the sign `±1` of `d[a]`, row `3 + a` the threshold `±o[a]` (sign
    /// times origin), so that `sign * bound <= threshold` on the box maximum (`d[a] > 0`)
    /// or minimum (`d[a] < 0`) says the box is behind; `-inf` (nothing behind) where
    /// `d[a] = 0` or `tmin < 0`.
    cull: [[f32; BLOCK]; 6],
    /// Bit `l` set where ray `l`'s dominant direction axis is X, and where it is Y (the
    /// permutation of [`shear`], see [`RayBlock::axes`]).
    x_dominant: u32,
    y_dominant: u32,
}

/// `(kx, ky, kz)` of [`shear`], indexed by "X dominant" + 2 "Y dominant" (never both).
const SHEAR_AXES: [[Axis; 3]; 4] = [
    [Axis::X, Axis::Y, Axis::Z],
    [Axis::Y, Axis::Z, Axis::X],
    [Axis::Z, Axis::X, Axis::Y],
    [Axis::X, Axis::Y, Axis::Z],
];

impl RayBlock {
    /// A block to [`Self::set`] (all zero).
    fn zero() -> Self {
        RayBlock {
            node: [[0.0; BLOCK]; 9],
            tri: [[0.0; BLOCK]; 8],
            od: [[0.0; BLOCK]; 6],
            cull: [[0.0; BLOCK]; 6],
            x_dominant: 0,
            y_dominant: 0,
        }
    }

    /// Sets the constants of the rays `origin[l] + t * direction[l]` (at most [`BLOCK`];
    /// lanes past them get a zero ray, never read) in a tree whose box coordinates are at
    /// most `max_abs` in magnitude per axis, computed on the lanes of `s`. Every row is
    /// overwritten.
    #[inline(always)]
    fn set<S: Simd>(
        &mut self,
        s: S,
        origin: &[Vec3],
        direction: &[Vec3],
        tmin: &[f32],
        max_abs: Vec3A,
    ) {
        let b = self;
        let (o, d) = match (origin.first_chunk(), direction.first_chunk()) {
            (Some(origin), Some(direction)) => (s.load_xyz(origin), s.load_xyz(direction)),
            _ => {
                // A partial block: the rays, then zero rays.
                let mut rays = [[Vec3::ZERO; BLOCK]; 2];
                for (l, (o, d)) in origin.iter().zip(direction).take(BLOCK).enumerate() {
                    (rays[0][l], rays[1][l]) = (*o, *d);
                }
                (s.load_xyz(&rays[0]), s.load_xyz(&rays[1]))
            }
        };
        for a in 0..3 {
            b.od[a] = o[a].to_array();
            b.od[3 + a] = d[a].to_array();
        }
        let mut tmins = [f32::NAN; BLOCK];
        for (t, &tmin) in tmins.iter_mut().zip(tmin) {
            *t = tmin;
        }
        let cull_on = s.splat(0.0).le(s.load(&Row8(tmins)));
        for a in 0..3 {
            let sign = S::F::select(d[a].lt(s.splat(0.0)), s.splat(-1.0), s.splat(1.0));
            let live = (d[a].lt(s.splat(0.0)) | d[a].gt(s.splat(0.0))) & cull_on;
            b.cull[a] = sign.to_array();
            b.cull[3 + a] = S::F::select(live, sign * o[a], s.splat(f32::NEG_INFINITY)).to_array();
        }
        for a in 0..3 {
            // NodeRay: `1 / d` clamped, and the widened plane offsets.
            let tiny = d[a].abs().lt(s.splat(MIN_DIR));
            let clamped = s.splat(1.0 / MIN_DIR).copysign(d[a]);
            let inv = S::F::select(tiny, clamped, s.splat(1.0) / d[a]);
            let c = (o[a] * inv).neg();
            let widening = inv.abs() * s.splat(NODE_SLACK);
            let slack = ((s.splat(max_abs[a]) + o[a].abs()) * widening).copysign(inv);
            b.node[a] = inv.to_array();
            b.node[3 + a] = (c - slack).to_array();
            b.node[6 + a] = (c + slack).to_array();
        }
        // `shear` on every lane: selects for its branches, the same comparisons.
        let (ax, ay, az) = (d[0].abs(), d[1].abs(), d[2].abs());
        let x_beats_y = ax.gt(ay);
        let x_dominant = x_beats_y & ax.gt(az);
        let y_dominant = ay.gt(az).and_not(x_beats_y);
        let pick = |v: &[S::F; 3], x: usize, y: usize, z: usize| {
            S::F::select(x_dominant, v[x], S::F::select(y_dominant, v[y], v[z]))
        };
        // kz is X, Y or Z; kx and ky follow it cyclically.
        let (dkx, dky, dkz) = (pick(&d, 1, 2, 0), pick(&d, 2, 0, 1), pick(&d, 0, 1, 2));
        b.tri[0] = pick(&o, 1, 2, 0).to_array();
        b.tri[1] = pick(&o, 2, 0, 1).to_array();
        b.tri[2] = pick(&o, 0, 1, 2).to_array();
        b.tri[3] = (dkx / dkz).to_array();
        b.tri[4] = (dky / dkz).to_array();
        b.tri[5] = (s.splat(1.0) / dkz).to_array();
        b.tri[6] = dkx.abs().to_array();
        b.tri[7] = dky.abs().to_array();
        b.x_dominant = x_dominant.bits();
        b.y_dominant = y_dominant.bits();
    }

    /// Ray `l`'s `(kx, ky, kz)`.
    #[inline(always)]
    fn axes(&self, l: usize) -> [Axis; 3] {
        let l = l % BLOCK;
        SHEAR_AXES[((self.x_dominant >> l) & 1 | ((self.y_dominant >> l) & 1) << 1) as usize]
    }

    /// Ray `l`'s origin.
    #[inline(always)]
    fn origin(&self, l: usize) -> Vec3 {
        let l = l % BLOCK;
        Vec3::new(self.od[0][l], self.od[1][l], self.od[2][l])
    }

    /// Ray `l`'s direction.
    #[inline(always)]
    fn direction(&self, l: usize) -> Vec3 {
        let l = l % BLOCK;
        Vec3::new(self.od[3][l], self.od[4][l], self.od[5][l])
    }
}

/// Ray `l` of a [`RayBlock`] for the 8-wide node test. Its per-axis values stay in the
/// block and are broadcast to the child lanes where the node test reads them (one
/// `vbroadcastss` from memory each, see [`intersect_node8`]): a ray visits little more than
/// one node on average in small scenes, and splatting all nine once per ray costs a
/// broadcast and a spill each.
struct NodeRay<'a, F> {
    block: &'a RayBlock,
    lane: usize,
    tmin: F,
}

impl<'a, F: Lanes8> NodeRay<'a, F> {
    #[inline(always)]
    fn new<S: Simd<F = F>>(s: S, block: &'a RayBlock, lane: usize, tmin: f32) -> Self {
        Self {
            block,
            lane: lane % BLOCK,
            tmin: s.splat(tmin),
        }
    }
}

/// Near and far slab distances of the eight child boxes along axis `a`: the distances to
/// the minimum and maximum planes, ordered (which one is near depends on the sign of
/// `d[a]`; ordering them costs a min and a max, picking rows by the sign an address
/// computation per row). (Helpers of the kernels are functions, not closures: closures
/// would not inherit the AVX2 target feature, and the intrinsics would not be inlined into
/// them.)
#[inline(always)]
fn slab<S: Simd>(s: S, b: &[Row8; 6], k: &[[f32; BLOCK]; 9], l: usize, a: usize) -> (S::F, S::F) {
    let l = l % BLOCK;
    let inv = s.splat(k[a][l]);
    let lo = s.load(&b[2 * a]).mul_add(inv, s.splat(k[3 + a][l]));
    let hi = s.load(&b[2 * a + 1]).mul_add(inv, s.splat(k[6 + a][l]));
    (lo.min(hi), lo.max(hi))
}

/// Slab test of the ray against the eight children of a node: the hit mask (bit `c` for
/// child `c`) and the entry distances.
#[inline(always)]
fn intersect_node8<S: Simd>(s: S, node: &Node8, ray: &NodeRay<S::F>, tmax: f32) -> (u32, S::F) {
    // `black_box` only keeps the compiler from hoisting the nine broadcasts out of the
    // traversal loop into the per-ray set-up (and spilling them there); the values read are
    // those of `ray` either way, so correctness does not depend on it.
    let k = std::hint::black_box(&ray.block.node);
    let (nx, fx) = slab(s, &node.bounds, k, ray.lane, 0);
    let (ny, fy) = slab(s, &node.bounds, k, ray.lane, 1);
    let (nz, fz) = slab(s, &node.bounds, k, ray.lane, 2);
    let tnear = nx.max(ny).max(nz.max(ray.tmin));
    let tfar = fx.min(fy).min(fz.min(s.splat(tmax)));
    // Exact cull of children whose box lies wholly on or behind the plane through the
    // origin across an axis `a` (`max_a <= o_a` for `d_a > 0`, `min_a >= o_a` for
    // `d_a < 0`, exact comparisons): every point of such a box has `t* <= 0` on the ray's
    // line, so for `tmin >= 0` the triangle test rejects all its triangles (a computed `t`
    // is within its error bound of `t*`, and hits with `t <= tmin + bound` are rejected,
    // see `t_error_bound`). The widened slab test above keeps such boxes, as the widening
    // exceeds the offset of a ray spawned on a surface from that surface: without this
    // the ray would visit the leaf it starts on. Spheres have no such bound, so subtrees
    // holding one ([`Node8::tri_only`]) are kept.
    let c = std::hint::black_box(&ray.block.cull);
    let behind = behind_axis(s, &node.bounds, c, ray.lane, 0)
        | behind_axis(s, &node.bounds, c, ray.lane, 1)
        | behind_axis(s, &node.bounds, c, ray.lane, 2);
    let culled = behind.bits() & node.tri_only;
    (tnear.le(tfar).bits() & node.valid & !culled, tnear)
}

/// The children whose box is behind the ray origin across axis `a` (see
/// [`intersect_node8`]; `c` is [`RayBlock::cull`], `l` the ray's lane).
#[inline(always)]
fn behind_axis<S: Simd>(
    s: S,
    b: &[Row8; 6],
    c: &[[f32; BLOCK]; 6],
    l: usize,
    a: usize,
) -> <S::F as Lanes8>::Mask {
    let l = l % BLOCK;
    let sign = s.splat(c[a][l]);
    let bound = S::F::select_negative(sign, s.load(&b[2 * a]), s.load(&b[2 * a + 1]));
    (bound * sign).le(s.splat(c[3 + a][l]))
}

/// Ray `l` of a [`RayBlock`] for the packet triangle test: [`WatertightRay`]'s constants,
/// kept in the block and broadcast to the triangle lanes in [`intersect_packet`] (as
/// [`NodeRay`]'s).
struct PacketRay<'a, F> {
    block: &'a RayBlock,
    lane: usize,
    kx: Axis,
    ky: Axis,
    kz: Axis,
    lanes: PhantomData<F>,
}

impl<'a, F: Lanes8> PacketRay<'a, F> {
    #[inline(always)]
    fn new<S: Simd<F = F>>(_: S, block: &'a RayBlock, lane: usize) -> Self {
        let lane = lane % BLOCK;
        let [kx, ky, kz] = block.axes(lane);
        Self {
            block,
            lane,
            kx,
            ky,
            kz,
            lanes: PhantomData,
        }
    }

    /// The ray's origin (for the sphere and scalar fallback tests).
    #[inline(always)]
    fn origin(&self) -> Vec3 {
        self.block.origin(self.lane)
    }

    /// The ray's direction.
    #[inline(always)]
    fn direction(&self) -> Vec3 {
        self.block.direction(self.lane)
    }
}

/// [`PacketRay`]'s constants on every lane, for one packet test.
struct PacketLanes<F> {
    ox: F,
    oy: F,
    oz: F,
    sx: F,
    sy: F,
    sz: F,
}

/// The outcome of [`intersect_packet`]: lanes accepted (`hit`, with their `t` and
/// barycentrics; the vectors are meaningless where `hit` is 0) and lanes left to the scalar
/// test (`fallback`: an edge function is exactly zero, or, for a free origin, the hit lies
/// within the f32 error bound of the origin; both are resolved in f64 there).
struct PacketHits<F> {
    hit: u32,
    fallback: u32,
    t: F,
    b1: F,
    b2: F,
    /// Per accepted lane, an upper bound on the error bound of its `t`: a later query from
    /// any `tmin' < t` accepts the hit if `t - tmin' > bound` (what
    /// [`intersect_all`](all_hits) records to replay those queries).
    bound: F,
}

/// One vertex of eight triangles translated, permuted and sheared, as in the scalar test:
/// `(A[kx] - Sx A[kz], A[ky] - Sy A[kz], A[kz])` with `A` relative to the origin.
#[inline(always)]
fn shear_vertex<S: Simd>(
    s: S,
    r: &PacketRay<S::F>,
    l: &PacketLanes<S::F>,
    v: &[Row8; 3],
) -> (S::F, S::F, S::F) {
    let z = s.load(&v[r.kz as usize]) - l.oz;
    let x = (s.load(&v[r.kx as usize]) - l.ox) - l.sx * z;
    let y = (s.load(&v[r.ky as usize]) - l.oy) - l.sy * z;
    (x, y, z)
}

/// The watertight test of [`WatertightRay::intersect_packed`] on the eight triangles of a
/// packet at once, with the same operations in the same order on every lane (no fused
/// multiply-add), so a lane's `t`, barycentrics and decision are bit-identical to the
/// scalar test's on that triangle. Lanes with an edge function exactly zero, and lanes of a
/// free-origin ray whose hit lies within the error bound, are reported in `fallback`
/// instead.
#[inline(always)]
fn intersect_packet<S: Simd>(
    s: S,
    r: &PacketRay<S::F>,
    p: &TriPacket8,
    tmin: f32,
    tmax: f32,
) -> PacketHits<S::F> {
    // `black_box`: see `intersect_node8` (keeps the broadcasts here, out of the set-up).
    let k = std::hint::black_box(&r.block.tri);
    let lane = r.lane % BLOCK;
    let l = PacketLanes {
        ox: s.splat(k[0][lane]),
        oy: s.splat(k[1][lane]),
        oz: s.splat(k[2][lane]),
        sx: s.splat(k[3][lane]),
        sy: s.splat(k[4][lane]),
        sz: s.splat(k[5][lane]),
    };
    let (x0, y0, z0) = shear_vertex(s, r, &l, &p.v[0]);
    let (x1, y1, z1) = shear_vertex(s, r, &l, &p.v[1]);
    let (x2, y2, z2) = shear_vertex(s, r, &l, &p.v[2]);
    // The lanes (U, V, W) of the scalar test, one triangle per lane.
    let u = x2 * y1 - y2 * x1;
    let v = x0 * y2 - y0 * x2;
    let w = x1 * y0 - y1 * x0;
    let zero = s.splat(0.0);
    let fallback = (u.eq(zero) | v.eq(zero) | w.eq(zero)).bits();
    let (all_neg, any_neg) = u.sign_bits_all_any(v, w);
    let same_sign = all_neg | !any_neg;
    let mut hit = same_sign & !fallback & 0xff;
    if hit == 0 {
        return PacketHits {
            hit,
            fallback,
            t: u,
            b1: v,
            b2: w,
            bound: u,
        };
    }
    let det = u + v + w;
    hit &= !det.eq(zero).bits();
    let (z0, z1, z2) = (z0 * l.sz, z1 * l.sz, z2 * l.sz);
    let scaled_t = u * z0 + v * z1 + w * z2;
    let inv_det = s.splat(1.0) / det;
    let t = scaled_t * inv_det;
    let below_tmax = t.lt(s.splat(tmax)).bits();
    // Rays from a free origin also look again at hits f32 put at or behind it (`near`).
    let behind = if from_free_origin(tmin) {
        hit & below_tmax & !t.gt(zero).bits()
    } else {
        0
    };
    hit &= t.gt(s.splat(tmin)).bits() & below_tmax;
    if hit | behind == 0 {
        return PacketHits {
            hit,
            fallback,
            t,
            b1: v,
            b2: w,
            bound: t,
        };
    }
    // `t_error_bound` per lane, the same operations (max is exact, so the order of the
    // maxima is free).
    let max_x = x0.abs().max(x1.abs()).max(x2.abs());
    let max_y = y0.abs().max(y1.abs()).max(y2.abs());
    let max_z = z0.abs().max(z1.abs()).max(z2.abs());
    let (g2, g3, g7) = (
        s.splat(gamma(2.0)),
        s.splat(gamma(3.0)),
        s.splat(gamma(7.0)),
    );
    let (adx, ady) = (s.splat(k[6][lane]), s.splat(k[7][lane]));
    let delta_z = g3 * max_z;
    let delta_x = g7 * (max_x + adx * max_z);
    let delta_y = g7 * (max_y + ady * max_z);
    let delta_e = s.splat(2.0) * (g2 * max_x * max_y + delta_y * max_x + delta_x * max_y);
    let kk = s.splat(3.0) * delta_e * inv_det.abs();
    let base = s.splat(gamma(10.0)) * max_z;
    let gap = t - s.splat(tmin);
    // The bound with `min(lever, max_z)` taken as `max_z` is at least the bound (rounding
    // is monotone), so hits beyond it are accepted without the lever: nearly every hit,
    // so the weighted-mean term is only computed for hits close to `tmin`.
    let bound_max = base + kk * max_z;
    let sure = hit & !gap.le(bound_max).bits();
    let mut keep = sure;
    if sure != hit {
        let spread = (z0 - t).abs().max((z1 - t).abs()).max((z2 - t).abs());
        let lever = S::F::select(
            kk.le(s.splat(0.5)),
            (s.splat(1.0) + s.splat(2.0) * kk) * (spread + delta_z),
            max_z,
        );
        keep = hit & !gap.le(base + kk * lever.min(max_z)).bits();
    }
    // Rays from a free origin decide hits within the bound of it in double precision (the
    // scalar test's `near_hit_f64`), on either side (the larger bound: the f64 test
    // decides exactly).
    let fallback = if from_free_origin(tmin) {
        let near_behind = behind & (zero - t).le(bound_max).bits();
        fallback | (hit & !keep) | near_behind
    } else {
        fallback
    };
    hit = keep;
    PacketHits {
        hit,
        fallback,
        t,
        b1: v * inv_det,
        b2: w * inv_det,
        bound: bound_max,
    }
}

/// The scalar test on lane `l` of a packet, for lanes [`intersect_packet`] leaves to it.
#[cold]
#[inline(never)]
fn packet_lane_scalar(
    p: &TriPacket8,
    l: usize,
    o: Vec3A,
    d: Vec3A,
    tmin: f32,
    tmax: f32,
) -> Option<TriangleHit> {
    let [v0, v1, v2] = p.triangle(l);
    WatertightRay::new(o.into(), d.into()).intersect_packed(
        &PackedTriangle::new(v0, v1, v2),
        tmin,
        tmax,
    )
}

/// A stacked child of the closest-hit traversal ([`Node8::child`] encoding) with its entry
/// distance.
#[derive(Clone, Copy)]
struct Entry {
    child: u32,
    t: f32,
}

impl Entry {
    /// Child `c` of `node` with entry distance `t[c]`.
    #[inline(always)]
    fn new(node: &Node8, t: &[f32; WIDTH], c: usize) -> Self {
        Self {
            child: node.child[c],
            t: t[c],
        }
    }
}

/// Closest-hit traversal of the 8-wide BVH: hit children, leaves and inner nodes alike, are
/// visited nearest entry distance first, and stacked children that start beyond the shrunk
/// `tmax` are skipped, so leaves behind the closest hit are never tested.
/// [`ClosestRay::leaf`] tests a leaf child and may shrink `tmax`.
#[inline(always)]
fn traverse_closest<S: Simd>(
    s: S,
    bvh: &Bvh8,
    ray: &NodeRay<S::F>,
    stack: &mut [Entry],
    tmax: &mut f32,
    leaf: &mut ClosestRay<'_, S>,
) {
    // A fixed slice ([`Bvh8::stack_capacity`] entries) and a local depth `sp` (a register,
    // where a `Vec`'s length would be loaded and stored through memory at every push).
    let mut sp = 0usize;
    let nodes = &bvh.nodes;
    let mut cur = 0u32;
    loop {
        if cur & LEAF == 0 {
            let node = &nodes[cur as usize];
            let (mask, tnear) = intersect_node8(s, node, ray, *tmax);
            if mask != 0 {
                let c0 = mask.trailing_zeros() as usize & 7;
                let rest = mask & (mask - 1);
                if rest == 0 {
                    cur = node.child[c0];
                    continue;
                }
                let t = tnear.to_array();
                let c1 = rest.trailing_zeros() as usize & 7;
                let rest = rest & (rest - 1);
                if rest == 0 {
                    // Two children: stack the farther, visit the nearer.
                    let (near, far) = if t[c1] < t[c0] { (c1, c0) } else { (c0, c1) };
                    stack[sp] = Entry::new(node, &t, far);
                    sp += 1;
                    cur = node.child[near];
                    continue;
                }
                // Three or more: stack all, sorted far to near (insertion sort), and visit
                // the nearest.
                let base = sp;
                stack[sp] = Entry::new(node, &t, c0);
                stack[sp + 1] = Entry::new(node, &t, c1);
                sp += 2;
                let mut m = rest;
                while m != 0 {
                    let c = m.trailing_zeros() as usize & 7;
                    m &= m - 1;
                    stack[sp] = Entry::new(node, &t, c);
                    sp += 1;
                }
                let st = &mut stack[base..sp];
                for i in 1..st.len() {
                    let e = st[i];
                    let mut j = i;
                    while j > 0 && st[j - 1].t < e.t {
                        st[j] = st[j - 1];
                        j -= 1;
                    }
                    st[j] = e;
                }
            }
        } else {
            leaf.leaf(bvh, cur, tmax);
        }
        loop {
            if sp == 0 {
                return;
            }
            sp -= 1;
            let e = stack[sp];
            if e.t <= *tmax {
                cur = e.child;
                break;
            }
        }
    }
}

/// What a leaves-first traversal ([`traverse_leaves_first`]) does at a leaf child.
trait LeafVisitor<S: Simd> {
    /// Tests leaf child `child` against the segment up to `tmax` (which it may shrink);
    /// `true` ends the traversal.
    fn visit(&mut self, bvh: &Bvh8, child: u32, tmax: &mut f32) -> bool;
}

/// Traversal of the 8-wide BVH that tests the hit leaf children of a node as soon as the
/// node is visited (for shadow rays a blocker found early ends the ray, and testing them
/// costs less than stacking them), then visits the hit inner children nearest first.
/// Returns whether the visitor ended it.
#[inline(always)]
fn traverse_leaves_first<S: Simd, V: LeafVisitor<S>>(
    s: S,
    bvh: &Bvh8,
    ray: &NodeRay<S::F>,
    stack: &mut [u32],
    tmax: &mut f32,
    leaf: &mut V,
) -> bool {
    // As in `traverse_closest`: a fixed slice and a local depth.
    let mut sp = 0usize;
    let nodes = &bvh.nodes;
    let mut index = 0usize;
    loop {
        let node = &nodes[index];
        let (mask, tnear) = intersect_node8(s, node, ray, *tmax);
        let mut leaves = mask & node.leaf_mask;
        while leaves != 0 {
            let c = leaves.trailing_zeros() as usize & 7;
            leaves &= leaves - 1;
            if leaf.visit(bvh, node.child[c], tmax) {
                return true;
            }
        }
        let mut inner = mask & !node.leaf_mask;
        if inner != 0 {
            let c0 = inner.trailing_zeros() as usize & 7;
            inner &= inner - 1;
            if inner == 0 {
                index = node.child[c0] as usize;
                continue;
            }
            let t = tnear.to_array();
            // The hit inner children sorted far to near (insertion sort): all but the
            // nearest are stacked, so they are popped nearest first.
            let mut order = [0usize; WIDTH];
            order[0] = c0;
            let mut k = 1;
            while inner != 0 {
                let c = inner.trailing_zeros() as usize & 7;
                inner &= inner - 1;
                let mut j = k;
                while j > 0 && t[order[j - 1] & 7] < t[c] {
                    order[j] = order[j - 1];
                    j -= 1;
                }
                order[j] = c;
                k += 1;
            }
            for &c in &order[..k - 1] {
                stack[sp] = node.child[c & 7];
                sp += 1;
            }
            index = node.child[order[k - 1] & 7] as usize;
            continue;
        }
        if sp == 0 {
            return false;
        }
        sp -= 1;
        index = stack[sp] as usize;
    }
}

/// [`intersect_sphere`] on a sphere leaf; out of line, so that the traversal loops of
/// triangle-only scenes carry no sphere set-up.
#[inline(never)]
fn sphere_leaf_t(leaf: &SphereLeaf, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> f32 {
    let cr = leaf.center_radius;
    intersect_sphere(o, d, cr.truncate(), cr.w, tmin, tmax)
}

/// The double-precision root of [`sphere_leaf_t`] (closest-hit traversal keeps it for the
/// hit's direction).
#[inline(never)]
fn sphere_leaf_t64(leaf: &SphereLeaf, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> Option<f64> {
    let cr = leaf.center_radius;
    sphere_t64(o, d, cr.truncate(), cr.w, tmin, tmax)
}

/// `(b1, b2)` of the closest hit on a sphere: the f64 root's residual against its f32
/// rounding `t64 as f32` (so that `t + b1` is the root to ~48 bits) and 0. No division or
/// square root: the hit's direction, which needs both, is computed only for the hits that
/// get shaded ([`SceneGeometry::surface_at`]); most of a medium's hits do not.
#[inline(always)]
fn sphere_hit_params(t64: f64) -> (f32, f32) {
    ((t64 - (t64 as f32) as f64) as f32, 0.0)
}

#[inline(always)]
fn check_lengths(n: usize, lens: &[usize]) {
    assert!(
        lens.iter().all(|&l| l == n),
        "column lengths differ: {n} vs {lens:?}"
    );
}

/// The columns of [`intersect_closest`].
struct ClosestColumns<'a> {
    origin: &'a [Vec3],
    direction: &'a [Vec3],
    tmin: &'a [f32],
    tmax: &'a [f32],
    t: &'a mut [f32],
    prim: &'a mut [u32],
    b1: &'a mut [f32],
    b2: &'a mut [f32],
}

/// No sphere hit: the closest hit so far is a triangle or nothing.
const NO_SPHERE: u32 = u32::MAX;

/// A closest-hit ray during traversal: its constants and the closest hit so far.
struct ClosestRay<'a, S: Simd> {
    s: S,
    tri: PacketRay<'a, S::F>,
    tmin: f32,
    prim: u32,
    /// Sphere leaf of the closest hit, or [`NO_SPHERE`].
    sphere: u32,
    /// The double-precision root of the closest sphere hit (when `sphere` is one).
    sphere_t: f64,
    b1: f32,
    b2: f32,
}

impl<S: Simd> ClosestRay<'_, S> {
    /// Tests leaf child `child`, shrinking `tmax` to a closer hit.
    #[inline(always)]
    fn leaf(&mut self, bvh: &Bvh8, child: u32, tmax: &mut f32) {
        let index = (child & INDEX_MASK) as usize;
        if child & SPHERE != 0 {
            let leaf = &bvh.spheres[index];
            let (o, d) = (self.tri.origin(), self.tri.direction());
            if let Some(t64) = sphere_leaf_t64(leaf, o, d, self.tmin, *tmax) {
                let ts = t64 as f32;
                if ts < *tmax {
                    *tmax = ts;
                    self.prim = leaf.prim;
                    self.sphere = index as u32;
                    self.sphere_t = t64;
                }
            }
            return;
        }
        let p = &bvh.packets[index];
        let r = intersect_packet(self.s, &self.tri, p, self.tmin, *tmax);
        let mut lanes = (r.hit | r.fallback) & p.valid;
        if lanes == 0 {
            return;
        }
        let (t, b1, b2) = (r.t.to_array(), r.b1.to_array(), r.b2.to_array());
        // Lanes in order, each kept only if nearer than the best so far: the same hit as
        // testing the triangles one by one (ties go to the lower lane).
        while lanes != 0 {
            let l = lanes.trailing_zeros() as usize & 7;
            lanes &= lanes - 1;
            let h = if r.fallback & (1 << l) == 0 {
                TriangleHit {
                    t: t[l],
                    b1: b1[l],
                    b2: b2[l],
                }
            } else {
                let (o, d) = (self.tri.origin().into(), self.tri.direction().into());
                match packet_lane_scalar(p, l, o, d, self.tmin, *tmax) {
                    Some(h) => h,
                    None => continue,
                }
            };
            if h.t < *tmax {
                *tmax = h.t;
                self.prim = p.prim[l];
                self.sphere = NO_SPHERE;
                self.b1 = h.b1;
                self.b2 = h.b2;
            }
        }
    }
}

/// [`intersect_closest`] on the lanes of `s`.
#[inline(always)]
fn closest_kernel<S: Simd>(s: S, bvh: &Bvh8, c: ClosestColumns) {
    let mut stack = vec![Entry { child: 0, t: 0.0 }; bvh.stack_capacity()];
    let mut block = RayBlock::zero();
    // Every column cut to the same length, so that indexing needs no bounds checks.
    let n = c.origin.len();
    let (origin, direction) = (&c.origin[..n], &c.direction[..n]);
    let (tmin, tmax) = (&c.tmin[..n], &c.tmax[..n]);
    let (t, prim) = (&mut c.t[..n], &mut c.prim[..n]);
    let (b1, b2) = (&mut c.b1[..n], &mut c.b2[..n]);
    for start in (0..n).step_by(BLOCK) {
        let end = n.min(start + BLOCK);
        block.set(
            s,
            &origin[start..end],
            &direction[start..end],
            &tmin[start..end],
            bvh.max_abs,
        );
        for i in start..end {
            let (lane, ray_tmin) = (i - start, tmin[i]);
            let node_ray = NodeRay::new(s, &block, lane, ray_tmin);
            let mut ray = ClosestRay {
                s,
                tri: PacketRay::new(s, &block, lane),
                tmin: ray_tmin,
                prim: NO_HIT,
                sphere: NO_SPHERE,
                sphere_t: 0.0,
                b1: 0.0,
                b2: 0.0,
            };
            let mut best_t = tmax[i];
            traverse_closest(s, bvh, &node_ray, &mut stack, &mut best_t, &mut ray);
            if ray.prim == NO_HIT {
                t[i] = f32::INFINITY;
                prim[i] = NO_HIT;
                b1[i] = 0.0;
                b2[i] = 0.0;
            } else {
                if ray.sphere != NO_SPHERE {
                    (ray.b1, ray.b2) = sphere_hit_params(ray.sphere_t);
                }
                t[i] = best_t;
                prim[i] = ray.prim;
                b1[i] = ray.b1;
                b2[i] = ray.b2;
            }
        }
    }
}

/// The columns of [`intersect_occluded`].
struct OccludedColumns<'a> {
    origin: &'a [Vec3],
    direction: &'a [Vec3],
    tmin: &'a [f32],
    tmax: &'a [f32],
    occluded: &'a mut [bool],
}

/// A shadow ray's constants during traversal.
struct AnyRay<'a, S: Simd> {
    s: S,
    tri: PacketRay<'a, S::F>,
    tmin: f32,
}

impl<S: Simd> LeafVisitor<S> for AnyRay<'_, S> {
    /// Whether leaf child `child` has a hit before `tmax` (which stays).
    #[inline(always)]
    fn visit(&mut self, bvh: &Bvh8, child: u32, tmax: &mut f32) -> bool {
        let tmax = *tmax;
        let index = (child & INDEX_MASK) as usize;
        if child & SPHERE != 0 {
            let (o, d) = (self.tri.origin(), self.tri.direction());
            return sphere_leaf_t(&bvh.spheres[index], o, d, self.tmin, tmax) < f32::INFINITY;
        }
        let p = &bvh.packets[index];
        let r = intersect_packet(self.s, &self.tri, p, self.tmin, tmax);
        if r.hit != 0 {
            return true;
        }
        let mut fallback = r.fallback & p.valid;
        while fallback != 0 {
            let l = fallback.trailing_zeros() as usize & 7;
            fallback &= fallback - 1;
            let (o, d) = (self.tri.origin().into(), self.tri.direction().into());
            if packet_lane_scalar(p, l, o, d, self.tmin, tmax).is_some() {
                return true;
            }
        }
        false
    }
}

/// [`intersect_occluded`] on the lanes of `s`.
#[inline(always)]
fn occluded_kernel<S: Simd>(s: S, bvh: &Bvh8, c: OccludedColumns) {
    let mut stack = vec![0u32; bvh.stack_capacity()];
    let mut block = RayBlock::zero();
    // Every column cut to the same length, so that indexing needs no bounds checks.
    let n = c.origin.len();
    let (origin, direction) = (&c.origin[..n], &c.direction[..n]);
    let (tmin, tmax, occluded) = (&c.tmin[..n], &c.tmax[..n], &mut c.occluded[..n]);
    for start in (0..n).step_by(BLOCK) {
        let end = n.min(start + BLOCK);
        block.set(
            s,
            &origin[start..end],
            &direction[start..end],
            &tmin[start..end],
            bvh.max_abs,
        );
        for i in start..end {
            let (lane, ray_tmin) = (i - start, tmin[i]);
            let node_ray = NodeRay::new(s, &block, lane, ray_tmin);
            let mut ray = AnyRay {
                s,
                tri: PacketRay::new(s, &block, lane),
                tmin: ray_tmin,
            };
            let mut ray_tmax = tmax[i];
            occluded[i] =
                traverse_leaves_first(s, bvh, &node_ray, &mut stack, &mut ray_tmax, &mut ray);
        }
    }
}

/// Defines `$dispatch(backend, bvh, columns)`, which runs the kernel `$kernel` (generic over
/// the lanes) on `backend`: its portable instantiation, or the one compiled with AVX2 and
/// FMA enabled (`$avx2`, chosen only where the CPU has them).
macro_rules! kernel_dispatch {
    ($dispatch:ident, $avx2:ident, $kernel:ident, $columns:ident) => {
        #[cfg(target_arch = "x86_64")]
        #[allow(
            unsafe_code,
            reason = "enables AVX2 and FMA for the kernel instantiation"
        )]
        #[target_feature(enable = "avx2,fma")]
        unsafe fn $avx2(s: Avx2, bvh: &Bvh8, c: $columns) {
            $kernel(s, bvh, c)
        }

        #[allow(
            unsafe_code,
            reason = "calls the AVX2 kernel on a CPU checked to have AVX2"
        )]
        fn $dispatch(backend: Backend, bvh: &Bvh8, c: $columns) {
            #[inline(never)]
            fn portable(bvh: &Bvh8, c: $columns) {
                $kernel(Portable, bvh, c)
            }
            match backend {
                Backend::Portable => portable(bvh, c),
                #[cfg(target_arch = "x86_64")]
                // SAFETY: the token exists only if `Avx2::detect` found AVX2 and FMA on
                // this CPU.
                Backend::Avx2(s) => unsafe { $avx2(s, bvh, c) },
            }
        }
    };
}

kernel_dispatch!(
    closest_dispatch,
    closest_avx2,
    closest_kernel,
    ClosestColumns
);
kernel_dispatch!(
    occluded_dispatch,
    occluded_avx2,
    occluded_kernel,
    OccludedColumns
);

/// Closest hit of every ray `origin[i] + t * direction[i]` with `tmin[i] < t < tmax[i]`.
///
/// Writes the hit distance, the primitive index (see [`SceneGeometry`]) and the surface
/// parameters: barycentrics `(b1, b2)` for triangles, `(phi / 2pi, theta / pi)` for spheres
/// (as [`SceneGeometry::surface_at`] expects). A miss writes `prim = NO_HIT`,
/// `t = f32::INFINITY` and zero parameters. Of two hits at exactly the same distance either
/// may be reported. Runs the geometry's [`Kernel`].
///
/// # Panics
/// If the columns have different lengths.
#[allow(clippy::too_many_arguments, reason = "one slice per SoA column")]
pub fn intersect_closest(
    geom: &SceneGeometry,
    origin: &[Vec3],
    direction: &[Vec3],
    tmin: &[f32],
    tmax: &[f32],
    t: &mut [f32],
    prim: &mut [u32],
    b1: &mut [f32],
    b2: &mut [f32],
) {
    let n = origin.len();
    check_lengths(
        n,
        &[
            direction.len(),
            tmin.len(),
            tmax.len(),
            t.len(),
            prim.len(),
            b1.len(),
            b2.len(),
        ],
    );
    let Some((bvh, backend)) = geom.bvh8() else {
        t.fill(f32::INFINITY);
        prim.fill(NO_HIT);
        b1.fill(0.0);
        b2.fill(0.0);
        return;
    };
    closest_dispatch(
        backend,
        bvh,
        ClosestColumns {
            origin,
            direction,
            tmin,
            tmax,
            t,
            prim,
            b1,
            b2,
        },
    );
}

/// Whether each ray `origin[i] + t * direction[i]` hits anything with
/// `tmin[i] < t < tmax[i]` (shadow rays). Stops at the first hit found. Runs the
/// geometry's [`Kernel`].
///
/// # Panics
/// If the columns have different lengths.
pub fn intersect_occluded(
    geom: &SceneGeometry,
    origin: &[Vec3],
    direction: &[Vec3],
    tmin: &[f32],
    tmax: &[f32],
    occluded: &mut [bool],
) {
    let n = origin.len();
    check_lengths(
        n,
        &[direction.len(), tmin.len(), tmax.len(), occluded.len()],
    );
    let Some((bvh, backend)) = geom.bvh8() else {
        occluded.fill(false);
        return;
    };
    occluded_dispatch(
        backend,
        bvh,
        OccludedColumns {
            origin,
            direction,
            tmin,
            tmax,
            occluded,
        },
    );
}

mod all_hits;
pub use all_hits::{intersect_all, NextHit, RayHits, MAX_HITS};

#[cfg(test)]
mod tests;
