//! The scalar watertight ray/triangle test (Woop, Benthin and Wald 2013) and the error
//! bound of its `t`: the reference the packet test reproduces lane by lane, and the
//! double-precision fallback it hands the lanes it cannot decide.

use super::*;

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
pub(super) enum Axis {
    X = 0,
    Y = 1,
    Z = 2,
}

/// The ray transform of the watertight test (Woop et al. 2013, sec. 3): the axis
/// permutation `(kx, ky, kz)` with `kz` the dominant direction axis, `kx = (kz + 1) % 3`,
/// `ky = (kx + 1) % 3`, the origin permuted to `(kx, ky, kz)`, and the shear constants
/// `(Sx, Sy, Sz) = (d[kx] / d[kz], d[ky] / d[kz], 1 / d[kz])` (paper eq. (2)).
#[inline(always)]
pub(super) fn shear(origin: Vec3A, direction: Vec3A) -> (Axis, Axis, Axis, Vec3A, Vec3A) {
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
    pub(super) ox: Vec4,
    pub(super) oy: Vec4,
    pub(super) oz: Vec4,
    /// The shear constants `Sx = d[kx] / d[kz]`, `Sy = d[ky] / d[kz]`, `Sz = 1 / d[kz]`
    /// (paper eq. (2)), in every lane.
    pub(super) sx: Vec4,
    pub(super) sy: Vec4,
    pub(super) sz: Vec4,
    /// `|d[kx]|` and `|d[ky]|`, for the error bound of the sheared coordinates (see
    /// [`t_error_bound`]).
    pub(super) adx: f32,
    pub(super) ady: f32,
    /// The paper's axis permutation: `kz` is the dominant direction axis,
    /// `kx = (kz + 1) % 3`, `ky = (kx + 1) % 3`.
    pub(super) kx: Axis,
    pub(super) ky: Axis,
    pub(super) kz: Axis,
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
    pub(super) fn intersect_rows(
        &self,
        rows: &[Vec4; 3],
        tmin: f32,
        tmax: f32,
    ) -> Option<TriangleHit> {
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
    pub(super) fn near_hit_f64(
        &self,
        rows: &[Vec4; 3],
        tmin: f32,
        tmax: f32,
    ) -> Option<TriangleHit> {
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
pub(super) fn from_free_origin(tmin: f32) -> bool {
    tmin.to_bits() == FREE_ORIGIN.to_bits()
}

/// `gamma(n) = n eps / (1 - n eps)` with `eps = 2^-24` (unit roundoff): the relative error
/// bound of `n` chained f32 operations (Higham; pbrt-v4 sec. 6.8.1).
#[inline(always)]
pub(super) fn gamma(n: f32) -> f32 {
    let e = f32::EPSILON * 0.5;
    n * e / (1.0 - n * e)
}

/// Largest magnitude among lanes 0..3 (the three vertices).
#[inline(always)]
pub(super) fn max_abs3(v: Vec4) -> f32 {
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
/// rays through boundaries, `engine/core/src/transmission.rs`) had exit hits 0.03 beyond `tmin`
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
pub(super) fn t_error_bound(
    x: Vec4,
    y: Vec4,
    z: Vec4,
    t: f32,
    inv_det: f32,
    adx: f32,
    ady: f32,
) -> f32 {
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
pub(super) fn edge_functions_f64(x: Vec4, y: Vec4) -> Option<Vec4> {
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
