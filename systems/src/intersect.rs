//! Ray/scene intersection systems: closest hit and occlusion over columns of rays.
//!
//! Traversal is the CWBVH stack machine of Ylitie et al. 2017 (the same visiting order as
//! obvhs' `traverse!`, written out here so the per-node work stays branch-free) with our own
//! node test, which (unlike obvhs' `CwBvhNode::intersect_ray`) honours the ray's `tmin`
//! instead of a fixed `1e-4` and widens every slab by a bound on its floating-point error,
//! so a box is never culled when the primitive test would report a hit inside it (obvhs'
//! test loses rays grazing box faces, e.g. along the edges of an axis-aligned mesh). The
//! node test picks each axis' near planes by address, widens the quantized planes to f32
//! in SIMD registers and builds the traversal hit mask without a branch per child.
//! Primitive tests:
//! - triangles: watertight test of Woop, Benthin and Wald 2013 ("Watertight Ray/Triangle
//!   Intersection", JCGT 2(1)), two-sided, on triangles stored coordinate by coordinate
//!   ([`PackedTriangle`]) so the three vertices are sheared and the three edge functions
//!   evaluated together; rays through shared edges and vertices of a closed mesh cannot
//!   slip through;
//! - spheres: the quadratic in the form of Haines et al. 2019 ("Precision Improvements for
//!   Ray/Sphere Intersection", Ray Tracing Gems ch. 7), evaluated in double precision so
//!   tiny spheres far away and huge spheres seen from close by stay accurate.
//!
//! Hits are accepted for `tmin < t < tmax`; a triangle hit must also be farther beyond
//! `tmin` than the rounding-error bound of its computed `t` (pbrt-v4's conservative t), so
//! that rays spawned on a large triangle, or walks that restart just past a hit, do not find
//! the same surface again.

use std::mem::offset_of;

use glam::{BVec4A, DVec3, UVec4, Vec3, Vec3A, Vec3Swizzles, Vec4, Vec4Swizzles};
use obvhs::cwbvh::node::CwBvhNode;
use risotto_components::NO_HIT;

use crate::bvh4::{Bvh4, Bvh4Node};
use crate::geometry::{sphere_uv, LeafPrim, SceneGeometry};

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
        let a = direction.abs();
        // Origin and direction permuted to (kx, ky, kz).
        let (kx, ky, kz, o, d) = if a.x > a.y {
            if a.x > a.z {
                (Axis::Y, Axis::Z, Axis::X, origin.yzx(), direction.yzx())
            } else {
                (Axis::X, Axis::Y, Axis::Z, origin, direction)
            }
        } else if a.y > a.z {
            (Axis::Z, Axis::X, Axis::Y, origin.zxy(), direction.zxy())
        } else {
            (Axis::X, Axis::Y, Axis::Z, origin, direction)
        };
        // (Sx, Sy, Sz) = (d[kx] / d[kz], d[ky] / d[kz], 1 / d[kz]), each one division.
        let s = Vec3A::new(d.x, d.y, 1.0) / d.z;
        Self {
            ox: Vec4::splat(o.x),
            oy: Vec4::splat(o.y),
            oz: Vec4::splat(o.z),
            sx: Vec4::splat(s.x),
            sy: Vec4::splat(s.y),
            sz: Vec4::splat(s.z),
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
            return None;
        }
        // The computed `t` is only known to within `delta_t`; a hit that close to `tmin`
        // may lie on the wrong side of it (a ray spawned on this very triangle, or a walk
        // re-finding the triangle it just crossed, would hit it again). Reject it, as
        // pbrt-v4 does for `tmin = 0` ("Physically Based Rendering", 4th ed., sec. 6.8.7,
        // conservative ray-triangle t: bounds on the rounding of the transformed vertices,
        // the edge functions and the scaled t).
        if t - tmin <= t_error_bound(x, y, z, u, v, w, inv_det) {
            return None;
        }
        Some(TriangleHit {
            t,
            b1: v * inv_det,
            b2: w * inv_det,
        })
    }
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
/// the transformed vertices (coordinates `x, y, z`, one vertex per lane) and the edge
/// functions `u, v, w` (pbrt-v4 sec. 6.8.7:
/// delta_t = 3 (gamma(3) max|e| max|z| + delta_e max|z| + delta_z max|e|) / |det|).
#[inline(always)]
fn t_error_bound(x: Vec4, y: Vec4, z: Vec4, u: f32, v: f32, w: f32, inv_det: f32) -> f32 {
    let max_x = max_abs3(x);
    let max_y = max_abs3(y);
    let max_z = max_abs3(z);
    let delta_z = gamma(3.0) * max_z;
    let delta_x = gamma(5.0) * (max_x + max_z);
    let delta_y = gamma(5.0) * (max_y + max_z);
    let delta_e = 2.0 * (gamma(2.0) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    let max_e = u.abs().max(v.abs()).max(w.abs());
    3.0 * (gamma(3.0) * max_e * max_z + delta_e * max_z + delta_z * max_e) * inv_det.abs()
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
    let f = o.as_dvec3() - center.as_dvec3();
    let d = d.as_dvec3();
    let r = radius as f64;
    // |o + t d - c|^2 = r^2  <=>  a t^2 + 2 b t + cc = 0.
    let a = d.length_squared();
    let b = f.dot(d);
    // Ray Tracing Gems ch. 7 eq. (12): b^2 - a cc = a (r^2 - |l|^2) with l = f - (b/a) d the
    // perpendicular from the centre to the ray line; (r - |l|)(r + |l|) avoids the
    // catastrophic cancellation of b^2 - a cc for distant spheres.
    let l = f - d * (b / a);
    let ll = l.length();
    let disc = a * ((r - ll) * (r + ll));
    // Also rejects NaN (zero direction).
    if disc.is_nan() || disc < 0.0 {
        return None;
    }
    // Numerically stable root pair (eq. (13)-(14)): q has no cancellation; the small root
    // is cc / q, with cc = (|f| - r)(|f| + r) accurate for origins near the surface.
    let q = -(b + disc.sqrt().copysign(b));
    let fl = f.length();
    let cc = (fl - r) * (fl + r);
    let (t0, t1) = if q == 0.0 {
        // b = 0 and disc = 0: the origin is on the sphere, moving tangentially.
        (0.0, 0.0)
    } else {
        let (x, y) = (cc / q, q / a);
        (x.min(y), x.max(y))
    };
    for t in [t0, t1] {
        let t32 = t as f32;
        if t32 > tmin && t32 < tmax {
            return Some(t);
        }
    }
    None
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

/// Relative slab widening of the node test. The slab distance is computed as
/// `q * (e / d) + (p - o) / d` (quantized plane `q`, node origin `p`, scale `e`); each term
/// carries at most two roundings, the sum one more and the quantization in obvhs one more,
/// so the error is below `5 u (255 e + |p - o|) / |d|` with unit roundoff `u = 2^-24`
/// (standard model, Higham 2002 ch. 3). We widen by `8 u`.
const NODE_SLACK: f32 = 4.0 * f32::EPSILON;

/// Smallest direction component used in the slab test; `1/d` is clamped to `1e20` so no
/// infinities (and `0 * inf` NaNs) arise for axis-parallel rays.
const MIN_DIR: f32 = 1e-20;

/// Per-ray constants of the node test.
struct NodeRay {
    origin: Vec3A,
    inv_dir: Vec3A,
    /// `NODE_SLACK * |1/d|`: turns a distance bound into a `t` bound per axis.
    slack_scale: Vec3A,
    /// Per axis: 8 where the direction is negative, else 0: the byte offset of the near
    /// plane array (max instead of min) from the axis' min plane array.
    near: [usize; 3],
    tmin: f32,
    /// obvhs' octant code of the direction (`7 - octant` in every byte), which orders the
    /// hit children front to back (see `CwBvhNode::get_child_and_index_bits`).
    oct_inv4: u32,
}

impl NodeRay {
    #[inline(always)]
    fn new(origin: Vec3, direction: Vec3, tmin: f32) -> Self {
        let d = Vec3A::from(direction);
        let tiny = d.abs().cmplt(Vec3A::splat(MIN_DIR));
        let inv_dir = Vec3A::select(
            tiny,
            Vec3A::splat(1.0 / MIN_DIR).copysign(d),
            Vec3A::ONE / d,
        );
        // From inv_dir, so -0.0 components pick planes consistently with their inverse.
        let neg = inv_dir.cmplt(Vec3A::ZERO).bitmask() as usize;
        let oct_inv4 = (if direction.x < 0.0 { 0 } else { 0x0404_0404 })
            | (if direction.y < 0.0 { 0 } else { 0x0202_0202 })
            | (if direction.z < 0.0 { 0 } else { 0x0101_0101 });
        Self {
            origin: origin.into(),
            inv_dir,
            slack_scale: inv_dir.abs() * NODE_SLACK,
            near: [(neg & 1) << 3, (neg & 2) << 2, (neg & 4) << 1],
            tmin,
            oct_inv4,
        }
    }
}

/// Byte offsets into obvhs' `repr(C)` `CwBvhNode`, which the node test reads as bytes so
/// that the ray picks each child's near plane by address instead of by a branch or a
/// select per node.
const NODE_E: usize = offset_of!(CwBvhNode, e);
const NODE_META: usize = offset_of!(CwBvhNode, child_meta);
const NODE_PLANES: usize = offset_of!(CwBvhNode, child_min_x);
const _: () = {
    // Plane arrays: min x, max x, min y, max y, min z, max z, 8 bytes each, contiguous.
    assert!(offset_of!(CwBvhNode, child_max_x) == NODE_PLANES + 8);
    assert!(offset_of!(CwBvhNode, child_min_y) == NODE_PLANES + 16);
    assert!(offset_of!(CwBvhNode, child_max_y) == NODE_PLANES + 24);
    assert!(offset_of!(CwBvhNode, child_min_z) == NODE_PLANES + 32);
    assert!(offset_of!(CwBvhNode, child_max_z) == NODE_PLANES + 40);
    assert!(size_of::<CwBvhNode>() == NODE_PLANES + 48);
};

/// Four bytes as floats (the compiler widens u8 -> u16 -> u32 -> f32 in SIMD registers).
#[inline(always)]
fn widen4(q: &[u8]) -> Vec4 {
    Vec4::new(q[0] as f32, q[1] as f32, q[2] as f32, q[3] as f32)
}

/// Four bytes as `u32` lanes.
#[inline(always)]
fn widen4_u32(q: &[u8]) -> UVec4 {
    UVec4::new(q[0] as u32, q[1] as u32, q[2] as u32, q[3] as u32)
}

/// `2^k` for integer lanes `k` in `0..128`, built in the f32 exponent field.
#[inline(always)]
fn exp2i(k: UVec4) -> Vec4 {
    let e = (k + UVec4::splat(127)) << 23u32;
    Vec4::new(
        f32::from_bits(e.x),
        f32::from_bits(e.y),
        f32::from_bits(e.z),
        f32::from_bits(e.w),
    )
}

/// Eight bytes as floats, children 0..4 and 4..8.
#[inline(always)]
fn widen8(q: &[u8]) -> (Vec4, Vec4) {
    (widen4(&q[..4]), widen4(&q[4..8]))
}

/// The quantized near and far planes of the 8 children along axis `a`, as floats:
/// `((near 0..4, near 4..8), (far 0..4, far 4..8))`.
#[inline(always)]
fn near_far_planes(b: &[u8; 80], ray: &NodeRay, a: usize) -> ((Vec4, Vec4), (Vec4, Vec4)) {
    // `& 8` lets the compiler see the offsets stay inside the node.
    let near = NODE_PLANES + 16 * a + (ray.near[a] & 8);
    let far = NODE_PLANES + 16 * a + (ray.near[a] & 8 ^ 8);
    (widen8(&b[near..][..8]), widen8(&b[far..][..8]))
}

/// `XOR_PERM[o][m]`: the byte `m` with bit `c` moved to bit `c ^ o`.
const XOR_PERM: [[u8; 256]; 8] = {
    let mut t = [[0u8; 256]; 8];
    let mut o = 0;
    while o < 8 {
        let mut m = 0;
        while m < 256 {
            let mut c = 0;
            while c < 8 {
                if m & (1 << c) != 0 {
                    t[o][m] |= 1 << (c ^ o);
                }
                c += 1;
            }
            m += 1;
        }
        o += 1;
    }
    t
};

/// The obvhs traversal hit mask (see `CwBvhNode::intersect_ray`) from the per-child slab
/// hits (`hit[0]` children 0..4, `hit[1]` children 4..8), without a branch per child:
/// - bits 24..32, hit inner children: child `c` (an inner child's meta byte is `24 + c`,
///   see obvhs' `bvh2_to_cwbvh`) goes to bit `24 + (c ^ octant code)`, a table lookup;
/// - bits 0..24, primitives of hit leaf children: child `c` owns `count` primitives from
///   `offset` on (meta byte: unary count in bits 5..8, offset in bits 0..5), i.e. adds
///   `unary_count * 2^offset`, computed in f32: exact integers below 2^24 whose sum over
///   the (disjoint) children is the bitwise OR. Inner children give `2^(24..32)` and are
///   dropped by the `< 2^24` test.
#[cfg(test)]
fn child_hit_mask(b: &[u8; 80], imask: u8, oct: u32, hit: [BVec4A; 2]) -> u32 {
    child_hit_mask_owned(&leaf_owned_bytes(b), imask, oct, hit)
}

/// The leaf-primitive bits each child of a node owns (children 0..4, 4..8): `unary_count *
/// 2^offset` from its meta byte as an exact f32 integer below `2^24`, zero for inner and
/// empty children. Precomputed per node by [`SceneGeometry`] so the traversal loads it.
pub(crate) fn leaf_owned(node: &CwBvhNode) -> [Vec4; 2] {
    leaf_owned_bytes(
        bytemuck::bytes_of(node)
            .try_into()
            .expect("CwBvhNode is 80 bytes"),
    )
}

#[inline(always)]
fn leaf_owned_bytes(b: &[u8; 80]) -> [Vec4; 2] {
    let owned = |q: &[u8]| {
        let meta = widen4_u32(q);
        let owned = (meta >> 5u32).as_vec4() * exp2i(meta & UVec4::splat(31));
        Vec4::select(owned.cmplt(Vec4::splat(16_777_216.0)), owned, Vec4::ZERO)
    };
    [owned(&b[NODE_META..][..4]), owned(&b[NODE_META + 4..][..4])]
}

/// [`child_hit_mask`] with the leaf bits of [`leaf_owned`].
#[inline(always)]
fn child_hit_mask_owned(owned: &[Vec4; 2], imask: u8, oct: u32, hit: [BVec4A; 2]) -> u32 {
    let m = (hit[0].bitmask() | hit[1].bitmask() << 4) as u8;
    let inner = (XOR_PERM[(oct & 7) as usize][(m & imask) as usize] as u32) << 24;
    let sum =
        Vec4::select(hit[0], owned[0], Vec4::ZERO) + Vec4::select(hit[1], owned[1], Vec4::ZERO);
    // The sum is an integer below 2^24: adding 2^52 in f64 leaves it in the low mantissa
    // bits (exact, and cheaper than a saturating float-to-int conversion).
    let leaf_bits = (sum.element_sum() as f64 + 4_503_599_627_370_496.0).to_bits() as u32;
    inner | leaf_bits
}

/// Slab test of the ray against the 8 children of a CWBVH node, four at a time. Returns
/// the obvhs hit mask (child bits in traversal order; see `CwBvhNode::intersect_ray`).
#[cfg(test)]
fn intersect_node(node: &CwBvhNode, ray: &NodeRay, tmax: f32) -> u32 {
    intersect_node_owned(node, &leaf_owned(node), ray, tmax)
}

/// [`intersect_node`] with the node's [`leaf_owned`] bits given.
#[inline(always)]
fn intersect_node_owned(node: &CwBvhNode, owned: &[Vec4; 2], ray: &NodeRay, tmax: f32) -> u32 {
    let b: &[u8; 80] = bytemuck::bytes_of(node)
        .try_into()
        .expect("CwBvhNode is 80 bytes");
    // obvhs' `compute_extent`: the exponent bytes moved into the f32 exponent field (the
    // fourth byte, imask, is masked out).
    let e =
        u32::from_le_bytes([b[NODE_E], b[NODE_E + 1], b[NODE_E + 2], b[NODE_E + 3]]) & 0xff_ffff;
    let e = widen4_u32(&e.to_le_bytes()) << 23u32;
    let e = Vec3A::new(
        f32::from_bits(e.x),
        f32::from_bits(e.y),
        f32::from_bits(e.z),
    );
    let diff = Vec3A::from(node.p) - ray.origin;
    let adj_dir = e * ray.inv_dir;
    let adj_orig = diff * ray.inv_dir;
    let slack = (e * 255.0 + diff.abs()) * ray.slack_scale;
    let near_orig = adj_orig - slack;
    let far_orig = adj_orig + slack;
    let tmin4 = Vec4::splat(ray.tmin);
    let tmax4 = Vec4::splat(tmax);
    let ((nx0, nx1), (fx0, fx1)) = near_far_planes(b, ray, 0);
    let ((ny0, ny1), (fy0, fy1)) = near_far_planes(b, ray, 1);
    let ((nz0, nz1), (fz0, fz1)) = near_far_planes(b, ray, 2);
    let slab = |nx: Vec4, fx: Vec4, ny: Vec4, fy: Vec4, nz: Vec4, fz: Vec4| {
        let tnear_x = nx * adj_dir.x + near_orig.x;
        let tfar_x = fx * adj_dir.x + far_orig.x;
        let tnear_y = ny * adj_dir.y + near_orig.y;
        let tfar_y = fy * adj_dir.y + far_orig.y;
        let tnear_z = nz * adj_dir.z + near_orig.z;
        let tfar_z = fz * adj_dir.z + far_orig.z;
        let tnear = tnear_x.max(tnear_y).max(tnear_z.max(tmin4));
        let tfar = tfar_x.min(tfar_y).min(tfar_z.min(tmax4));
        tnear.cmple(tfar)
    };
    let hit = [
        slab(nx0, fx0, ny0, fy0, nz0, fz0),
        slab(nx1, fx1, ny1, fy1, nz1, fz1),
    ];
    child_hit_mask_owned(owned, node.imask, ray.oct_inv4, hit)
}

/// Bits 24..32 of a traversal group: the hit inner children still to visit.
const INNER_HITS: u32 = 0xff00_0000;

/// Population count of a byte (x86-64 without `popcnt` would spend a dozen instructions).
const POPCOUNT8: [u8; 256] = {
    let mut t = [0u8; 256];
    let mut i = 0;
    while i < 256 {
        t[i] = (i as u32).count_ones() as u8;
        i += 1;
    }
    t
};

/// Front-to-back CWBVH traversal (Ylitie, Karras and Laine 2017, "Efficient Incoherent Ray
/// Traversal on GPUs Through Compressed Wide BVHs", sec. 3 and Algorithm 1; the same stack
/// machine and visiting order as obvhs' `traverse!`). `leaf(slot, tmax)` tests the
/// primitive in leaf slot `slot`, may shrink `tmax` (closest hit) and returns true to stop.
#[inline(always)]
fn traverse(
    nodes: &[CwBvhNode],
    owned: &[[Vec4; 2]],
    ray: &NodeRay,
    stack: &mut Vec<(u32, u32)>,
    tmax: &mut f32,
    mut leaf: impl FnMut(u32, &mut f32) -> bool,
) {
    stack.clear();
    let oct = ray.oct_inv4 & 0b111;
    // A node group: the first child index of a node, and in its bits the hit inner children
    // not yet visited (bits 24..32, by traversal priority) and the node's imask (bits 0..8).
    // The root is the single hit child (bit 31) of a node with an empty imask.
    let (mut base, mut group) = (0u32, 1u32 << 31);
    // The hit leaf primitives of the last node: first slot and hits (bits 0..24).
    let (mut prim_base, mut prims) = (0u32, 0u32);
    loop {
        while prims != 0 {
            let i = 31 - prims.leading_zeros();
            prims &= !(1 << i);
            if leaf(prim_base + i, tmax) {
                return;
            }
        }
        if group & INNER_HITS == 0 {
            match stack.pop() {
                Some(g) => (base, group) = g,
                None => return,
            }
        }
        let bit = 31 - group.leading_zeros();
        let rest = group & !(1 << bit);
        if rest & INNER_HITS != 0 {
            stack.push((base, rest));
        }
        // Undo the octant ordering to get the child slot; inner children are stored in slot
        // order, so the node index is the base plus the inner children before the slot.
        let slot = (bit - 24) ^ oct;
        let index = (base + POPCOUNT8[(group & ((1 << slot) - 1) & 0xff) as usize] as u32) as usize;
        let node = &nodes[index];
        let hits = intersect_node_owned(node, &owned[index], ray, *tmax);
        (base, group) = (node.child_base_idx, (hits & INNER_HITS) | node.imask as u32);
        (prim_base, prims) = (node.primitive_base_idx, hits & !INNER_HITS);
    }
}

/// Relative slab widening of the 4-wide node test. A slab distance is computed as
/// `b * inv + near_orig` with `inv = fl(1/d)` and `near_orig = fl(fl(-o * inv) -+ s)`: with
/// unit roundoff `u = 2^-24` its error against `(b - o) / d` is below
/// `u (3 |b| + 4 |o|) / |d| + 2 u s` (standard model, Higham 2002 ch. 3: two roundings in
/// `b * inv`, two in `-o * inv`, one in the widening and one in the sum), and `|b|` is at
/// most the largest box coordinate magnitude `B` on that axis. Widening by
/// `s = 8 u (B + |o|) |inv|` therefore covers it on every axis, for every node of the tree,
/// so the widening is a per-ray constant folded into `near_orig`/`far_orig`.
const NODE4_SLACK: f32 = 4.0 * f32::EPSILON;

/// Per-ray constants of the 4-wide node test, each splat across the four child lanes.
struct Ray4 {
    /// `1 / d` per axis (clamped like [`NodeRay`]).
    inv: [Vec4; 3],
    /// `-o / d - s` and `-o / d + s` per axis: slab distance offsets with the widening.
    near_orig: [Vec4; 3],
    far_orig: [Vec4; 3],
    /// Per axis 1 where the direction is negative (the near plane is the box maximum).
    neg: [usize; 3],
    tmin: Vec4,
}

impl Ray4 {
    #[inline(always)]
    fn new(origin: Vec3, direction: Vec3, tmin: f32, max_abs: Vec3A) -> Self {
        let d = Vec3A::from(direction);
        let o = Vec3A::from(origin);
        let tiny = d.abs().cmplt(Vec3A::splat(MIN_DIR));
        let inv_dir = Vec3A::select(
            tiny,
            Vec3A::splat(1.0 / MIN_DIR).copysign(d),
            Vec3A::ONE / d,
        );
        let c = -(o * inv_dir);
        let slack = (max_abs + o.abs()) * (inv_dir.abs() * NODE4_SLACK);
        let near_orig = c - slack;
        let far_orig = c + slack;
        // From inv_dir, so -0.0 components pick planes consistently with their inverse.
        let neg = inv_dir.cmplt(Vec3A::ZERO).bitmask() as usize;
        Self {
            inv: [
                Vec4::splat(inv_dir.x),
                Vec4::splat(inv_dir.y),
                Vec4::splat(inv_dir.z),
            ],
            near_orig: [
                Vec4::splat(near_orig.x),
                Vec4::splat(near_orig.y),
                Vec4::splat(near_orig.z),
            ],
            far_orig: [
                Vec4::splat(far_orig.x),
                Vec4::splat(far_orig.y),
                Vec4::splat(far_orig.z),
            ],
            neg: [neg & 1, (neg >> 1) & 1, (neg >> 2) & 1],
            tmin: Vec4::splat(tmin),
        }
    }
}

/// Slab test of the ray against the four children of a 4-wide node: the hit mask (bit `c`
/// for child `c`) and the entry distances.
#[inline(always)]
fn intersect_node4(node: &Bvh4Node, ray: &Ray4, tmax: f32) -> (u32, Vec4) {
    let b = &node.bounds;
    let slab = |a: usize| {
        // `& 1` keeps the row indices provably inside the array.
        let near = b[2 * a + (ray.neg[a] & 1)];
        let far = b[2 * a + ((ray.neg[a] & 1) ^ 1)];
        (
            near * ray.inv[a] + ray.near_orig[a],
            far * ray.inv[a] + ray.far_orig[a],
        )
    };
    let (nx, fx) = slab(0);
    let (ny, fy) = slab(1);
    let (nz, fz) = slab(2);
    let tnear = nx.max(ny).max(nz.max(ray.tmin));
    let tfar = fx.min(fy).min(fz.min(Vec4::splat(tmax)));
    (tnear.cmple(tfar).bitmask(), tnear)
}

/// A stacked child of the 4-wide traversal: an inner node (`count == 0`, `index` the node)
/// or a leaf (`index` its first leaf slot), with its entry distance.
#[derive(Clone, Copy)]
struct Entry4 {
    index: u32,
    count: u32,
    t: f32,
}

/// Traversal of the 4-wide BVH: hit children, leaves and inner nodes alike, are visited
/// nearest entry distance first, and stacked children that start beyond the shrunk `tmax`
/// are skipped, so leaves behind the closest hit are never tested (and shadow rays, which
/// stop at the first hit, find blockers near the origin first). `leaf(slot, tmax)` tests
/// the primitive in leaf slot `slot`, may shrink `tmax` and returns true to stop.
#[inline(always)]
fn traverse4(
    bvh: &Bvh4,
    ray: &Ray4,
    stack: &mut Vec<Entry4>,
    tmax: &mut f32,
    mut leaf: impl FnMut(u32, &mut f32) -> bool,
) {
    stack.clear();
    let nodes = &bvh.nodes;
    let mut cur = Entry4 {
        index: 0,
        count: 0,
        t: 0.0,
    };
    loop {
        if cur.count == 0 {
            let node = &nodes[cur.index as usize];
            let (mask, tnear) = intersect_node4(node, ray, *tmax);
            if mask != 0 {
                let t = tnear.to_array();
                let entry = |c: usize| Entry4 {
                    index: node.child[c],
                    count: node.count[c] as u32,
                    t: t[c],
                };
                let c0 = mask.trailing_zeros() as usize & 3;
                let rest = mask & (mask - 1);
                if rest == 0 {
                    cur = entry(c0);
                    continue;
                }
                let c1 = rest.trailing_zeros() as usize & 3;
                let rest = rest & (rest - 1);
                if rest == 0 {
                    // Two children: stack the farther, visit the nearer.
                    let (near, far) = if t[c1] < t[c0] { (c1, c0) } else { (c0, c1) };
                    stack.push(entry(far));
                    cur = entry(near);
                    continue;
                }
                // Three or four: stack all, sorted far to near (insertion sort of at most
                // four), and visit the nearest.
                let base = stack.len();
                stack.push(entry(c0));
                stack.push(entry(c1));
                let mut m = rest;
                while m != 0 {
                    let c = m.trailing_zeros() as usize & 3;
                    m &= m - 1;
                    stack.push(entry(c));
                }
                let s = &mut stack[base..];
                for i in 1..s.len() {
                    let e = s[i];
                    let mut j = i;
                    while j > 0 && s[j - 1].t < e.t {
                        s[j] = s[j - 1];
                        j -= 1;
                    }
                    s[j] = e;
                }
            }
        } else {
            for slot in cur.index..cur.index + cur.count {
                if leaf(slot, tmax) {
                    return;
                }
            }
        }
        loop {
            match stack.pop() {
                Some(e) => {
                    if e.t <= *tmax {
                        cur = e;
                        break;
                    }
                }
                None => return,
            }
        }
    }
}

/// Any-hit traversal of the 4-wide BVH for shadow rays: the hit leaf children of a node are
/// tested as soon as the node is visited (a blocker found early ends the ray, and testing
/// them costs less than stacking them), then the nearest hit inner child is visited and the
/// others are stacked unsorted. `leaf(slot)` returns true to stop.
#[inline(always)]
fn traverse4_any(
    bvh: &Bvh4,
    ray: &Ray4,
    stack: &mut Vec<u32>,
    tmax: f32,
    mut leaf: impl FnMut(u32) -> bool,
) {
    stack.clear();
    let nodes = &bvh.nodes;
    let mut index = 0usize;
    loop {
        let node = &nodes[index];
        let (mask, tnear) = intersect_node4(node, ray, tmax);
        let mut leaves = mask & node.leaf_mask;
        while leaves != 0 {
            let c = leaves.trailing_zeros() as usize & 3;
            leaves &= leaves - 1;
            let first = node.child[c];
            for slot in first..first + node.count[c] as u32 {
                if leaf(slot) {
                    return;
                }
            }
        }
        let mut inner = mask & !node.leaf_mask;
        if inner != 0 {
            let t = tnear.to_array();
            let mut near = inner.trailing_zeros() as usize & 3;
            inner &= inner - 1;
            while inner != 0 {
                let c = inner.trailing_zeros() as usize & 3;
                inner &= inner - 1;
                let far = if t[c] < t[near] {
                    std::mem::replace(&mut near, c)
                } else {
                    c
                };
                stack.push(node.child[far]);
            }
            index = node.child[near] as usize;
            continue;
        }
        match stack.pop() {
            Some(n) => index = n as usize,
            None => return,
        }
    }
}

/// [`intersect_sphere`] on a sphere leaf; out of line, so that the traversal loops of
/// triangle-only scenes carry no sphere set-up.
#[inline(never)]
fn sphere_leaf_t(leaf: &LeafPrim, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> f32 {
    let (c, r) = leaf.sphere_center_radius();
    intersect_sphere(o, d, c, r, tmin, tmax)
}

/// Surface parameters of the closest hit on a sphere leaf, from the double-precision root.
#[inline(never)]
fn sphere_leaf_uv(leaf: &LeafPrim, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> (f32, f32) {
    let (c, r) = leaf.sphere_center_radius();
    let uv = sphere_t64(o, d, c, r, tmin, tmax)
        .map(|t64| sphere_uv((o.as_dvec3() - c.as_dvec3()) + d.as_dvec3() * t64))
        .unwrap_or_else(|| sphere_uv(DVec3::Z));
    (uv.x, uv.y)
}

#[inline(always)]
fn check_lengths(n: usize, lens: &[usize]) {
    assert!(
        lens.iter().all(|&l| l == n),
        "column lengths differ: {n} vs {lens:?}"
    );
}

/// Closest hit of every ray `origin[i] + t * direction[i]` with `tmin[i] < t < tmax[i]`.
///
/// Writes the hit distance, the primitive index (see [`SceneGeometry`]) and the surface
/// parameters: barycentrics `(b1, b2)` for triangles, `(phi / 2pi, theta / pi)` for spheres
/// (as [`SceneGeometry::surface_at`] expects). A miss writes `prim = NO_HIT`,
/// `t = f32::INFINITY` and zero parameters. Of two hits at exactly the same distance either
/// may be reported.
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
    let Some((bvh, leaves)) = geom.bvh4() else {
        t.fill(f32::INFINITY);
        prim.fill(NO_HIT);
        b1.fill(0.0);
        b2.fill(0.0);
        return;
    };
    let mut stack = Vec::with_capacity(64);
    for i in 0..n {
        let (o, d, ray_tmin) = (origin[i], direction[i], tmin[i]);
        let node_ray = Ray4::new(o, d, ray_tmin, bvh.max_abs);
        let tri_ray = WatertightRay::new(o, d);
        let mut best_t = tmax[i];
        let mut best_slot = u32::MAX;
        let (mut hit_b1, mut hit_b2) = (0.0f32, 0.0f32);
        traverse4(bvh, &node_ray, &mut stack, &mut best_t, |slot, best_t| {
            let leaf = &leaves[slot as usize];
            if !leaf.is_sphere() {
                if let Some(h) = tri_ray.intersect_rows(&leaf.rows, ray_tmin, *best_t) {
                    *best_t = h.t;
                    best_slot = slot;
                    hit_b1 = h.b1;
                    hit_b2 = h.b2;
                }
            } else {
                let ts = sphere_leaf_t(leaf, o, d, ray_tmin, *best_t);
                if ts < *best_t {
                    *best_t = ts;
                    best_slot = slot;
                }
            }
            false
        });
        if best_slot == u32::MAX {
            t[i] = f32::INFINITY;
            prim[i] = NO_HIT;
            b1[i] = 0.0;
            b2[i] = 0.0;
        } else {
            let leaf = &leaves[best_slot as usize];
            if leaf.is_sphere() {
                (hit_b1, hit_b2) = sphere_leaf_uv(leaf, o, d, ray_tmin, tmax[i]);
            }
            t[i] = best_t;
            prim[i] = bvh.prim_indices[best_slot as usize];
            b1[i] = hit_b1;
            b2[i] = hit_b2;
        }
    }
}

/// Whether each ray `origin[i] + t * direction[i]` hits anything with
/// `tmin[i] < t < tmax[i]` (shadow rays). Stops at the first hit found.
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
    let Some((bvh, leaves)) = geom.bvh4() else {
        occluded.fill(false);
        return;
    };
    let mut stack = Vec::with_capacity(64);
    for i in 0..n {
        let (o, d, ray_tmin, ray_tmax) = (origin[i], direction[i], tmin[i], tmax[i]);
        let node_ray = Ray4::new(o, d, ray_tmin, bvh.max_abs);
        let tri_ray = WatertightRay::new(o, d);
        let mut hit = false;
        traverse4_any(bvh, &node_ray, &mut stack, ray_tmax, |slot| {
            let leaf = &leaves[slot as usize];
            hit = if !leaf.is_sphere() {
                tri_ray
                    .intersect_rows(&leaf.rows, ray_tmin, ray_tmax)
                    .is_some()
            } else {
                sphere_leaf_t(leaf, o, d, ray_tmin, ray_tmax) < f32::INFINITY
            };
            hit
        });
        occluded[i] = hit;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Sphere;
    use obvhs::cwbvh::node::extract_byte64;

    /// SplitMix64.
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        }
        fn f32(&mut self) -> f32 {
            (self.next() >> 40) as f32 / (1u64 << 24) as f32
        }
        fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
            Vec3::new(self.f32(), self.f32(), self.f32()) * (hi - lo) + Vec3::splat(lo)
        }
    }

    /// The hit mask the straightforward way (obvhs' `intersect_ray_basic` layout): one child
    /// at a time, near/far planes chosen by the direction's sign, the traversal bits of hit
    /// children ORed in with a branch (`get_child_and_index_bits`, `extract_byte64`).
    fn child_mask_reference(node: &CwBvhNode, oct_inv4: u32, hit: [bool; 8]) -> u32 {
        let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
        let mut mask = 0;
        for (c, &h) in hit.iter().enumerate() {
            if h {
                mask |= extract_byte64(child_bits8, c) << extract_byte64(bit_index8, c);
            }
        }
        mask
    }

    /// The slab test of one child in scalar code, with the roundings of the node test
    /// (`q * (e / d) + ((p - o) / d -+ slack)`).
    fn child_hit_reference(
        node: &CwBvhNode,
        c: usize,
        o: Vec3,
        d: Vec3,
        tmin: f32,
        tmax: f32,
    ) -> bool {
        let e = node.compute_extent();
        let inv = |x: f32| {
            if x.abs() < MIN_DIR {
                (1.0 / MIN_DIR).copysign(x)
            } else {
                1.0 / x
            }
        };
        let inv_dir = [inv(d.x), inv(d.y), inv(d.z)];
        let p = node.p.to_array();
        let o = o.to_array();
        let planes = [
            (node.child_min_x[c], node.child_max_x[c]),
            (node.child_min_y[c], node.child_max_y[c]),
            (node.child_min_z[c], node.child_max_z[c]),
        ];
        let (mut tnear, mut tfar) = ([0.0f32; 3], [0.0f32; 3]);
        for a in 0..3 {
            let diff = p[a] - o[a];
            let adj_dir = e[a] * inv_dir[a];
            let adj_orig = diff * inv_dir[a];
            let slack = (e[a] * 255.0 + diff.abs()) * (inv_dir[a].abs() * NODE_SLACK);
            let (lo, hi) = planes[a];
            let (n, f) = if inv_dir[a] < 0.0 { (hi, lo) } else { (lo, hi) };
            tnear[a] = n as f32 * adj_dir + (adj_orig - slack);
            tfar[a] = f as f32 * adj_dir + (adj_orig + slack);
        }
        tnear[0].max(tnear[1]).max(tnear[2].max(tmin))
            <= tfar[0].min(tfar[1]).min(tfar[2].min(tmax))
    }

    #[test]
    fn node_test_matches_per_child_reference() {
        let mut rng = Rng(3);
        let tris: Vec<[Vec3; 3]> = (0..3000)
            .map(|_| {
                let c = rng.vec(-10.0, 10.0);
                [
                    c + rng.vec(-0.5, 0.5),
                    c + rng.vec(-0.5, 0.5),
                    c + rng.vec(-0.5, 0.5),
                ]
            })
            .collect();
        let spheres = vec![Sphere {
            center: Vec3::ONE,
            radius: 0.3,
        }];
        let geom = SceneGeometry::build(tris, spheres);
        let nodes = &geom.bvh().unwrap().nodes;
        let (mut hits, mut misses) = (0, 0);
        for k in 0..400 {
            let o = rng.vec(-12.0, 12.0);
            // Aimed at a triangle, so that deep nodes get hits too.
            let target = geom.triangle((rng.next() % 3000) as usize)[0];
            let mut d = target - o + rng.vec(-0.1, 0.1);
            // Axis-parallel directions, including negative zeros.
            match k % 5 {
                0 => d.x = 0.0,
                1 => d.y = -0.0,
                2 => d = Vec3::new(0.0, -0.0, d.z),
                _ => {}
            }
            let (tmin, tmax) = if k % 2 == 0 {
                (0.0, f32::INFINITY)
            } else {
                (rng.f32(), 5.0 * rng.f32())
            };
            let ray = NodeRay::new(o, d, tmin);
            for node in nodes {
                let hit: [bool; 8] =
                    std::array::from_fn(|c| child_hit_reference(node, c, o, d, tmin, tmax));
                let want = child_mask_reference(node, ray.oct_inv4, hit);
                assert_eq!(
                    intersect_node(node, &ray, tmax),
                    want,
                    "ray {k}: o={o:?} d={d:?} node {node:?}"
                );
                let n = hit.iter().filter(|&&h| h).count();
                hits += n;
                misses += 8 - n;
            }
        }
        assert!(
            hits > 4_000 && misses > 4_000,
            "{hits} child hits, {misses} misses"
        );
    }

    #[test]
    fn precomputed_leaf_bits_match_per_child_reference() {
        let mut rng = Rng(5);
        let tris: Vec<[Vec3; 3]> = (0..2000)
            .map(|_| {
                let c = rng.vec(-10.0, 10.0);
                [c, c + rng.vec(-0.5, 0.5), c + rng.vec(-0.5, 0.5)]
            })
            .collect();
        let geom = SceneGeometry::build(tris, Vec::new());
        let nodes = &geom.bvh().unwrap().nodes;
        assert_eq!(geom.node_owned().len(), nodes.len());
        for (node, owned) in nodes.iter().zip(geom.node_owned()) {
            // Each child alone: its leaf bits (bits 0..24 of obvhs' mask) as an integer.
            for c in 0..8 {
                let hit: [bool; 8] = std::array::from_fn(|k| k == c);
                let want = child_mask_reference(node, 0, hit) & 0x00ff_ffff;
                assert_eq!(owned[c / 4][c % 4], want as f32, "node {node:?} child {c}");
            }
        }
    }

    #[test]
    fn child_hit_mask_matches_per_child_reference() {
        let mut rng = Rng(11);
        for k in 0..20_000 {
            // A node's children: empty, inner (meta 24 + c) or leaves owning 1..3 primitives
            // from a running offset, up to obvhs' 24 per node.
            let mut node = CwBvhNode::default();
            let mut offset = 0u8;
            for c in 0..8 {
                match rng.next() % 4 {
                    0 => {}
                    1 => {
                        node.imask |= 1 << c;
                        node.child_meta[c] = (24 + c as u8) | 0b0010_0000;
                    }
                    _ => {
                        let count = (1 + rng.next() % 3) as u8;
                        if offset + count <= 24 {
                            node.child_meta[c] =
                                offset | [0, 0b0010_0000, 0b0110_0000, 0b1110_0000][count as usize];
                            offset += count;
                        }
                    }
                }
            }
            let hit: [bool; 8] = std::array::from_fn(|_| !rng.next().is_multiple_of(3));
            let oct_inv4 = (k % 8) * 0x0101_0101;
            let b: &[u8; 80] = bytemuck::bytes_of(&node).try_into().unwrap();
            let lanes = [
                BVec4A::new(hit[0], hit[1], hit[2], hit[3]),
                BVec4A::new(hit[4], hit[5], hit[6], hit[7]),
            ];
            assert_eq!(
                child_hit_mask(b, node.imask, oct_inv4, lanes),
                child_mask_reference(&node, oct_inv4, hit),
                "node {node:?} hits {hit:?} octant code {oct_inv4:#x}"
            );
        }
    }
}
