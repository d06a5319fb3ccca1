//! Ray/scene intersection systems: closest hit and occlusion over columns of rays.
//!
//! Traversal uses obvhs' CWBVH stack machine (`traverse!`) with our own node test, which
//! (unlike obvhs' `CwBvhNode::intersect_ray`) honours the ray's `tmin` instead of a fixed
//! `1e-4` and widens every slab by a bound on its floating-point error, so a box is never
//! culled when the primitive test would report a hit inside it (obvhs' test loses rays
//! grazing box faces, e.g. along the edges of an axis-aligned mesh). The widening costs ~5%
//! of closest-hit throughput (benches/README.md). Primitive tests:
//! - triangles: watertight test of Woop, Benthin and Wald 2013 ("Watertight Ray/Triangle
//!   Intersection", JCGT 2(1)), two-sided; rays through shared edges and vertices of a
//!   closed mesh cannot slip through;
//! - spheres: the quadratic in the form of Haines et al. 2019 ("Precision Improvements for
//!   Ray/Sphere Intersection", Ray Tracing Gems ch. 7), evaluated in double precision so
//!   tiny spheres far away and huge spheres seen from close by stay accurate.
//!
//! Hits are accepted for `tmin < t < tmax`; a triangle hit must also be farther beyond
//! `tmin` than the rounding-error bound of its computed `t` (pbrt-v4's conservative t), so
//! that rays spawned on a large triangle, or walks that restart just past a hit, do not find
//! the same surface again.

use glam::{DVec3, Mat3A, UVec2, Vec3, Vec3A, Vec4};
use obvhs::{
    cwbvh::node::{extract_byte64, CwBvhNode},
    traverse,
};
use risotto_components::NO_HIT;

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

/// Per-ray precomputation of the watertight ray/triangle test (Woop et al. 2013, sec. 3):
/// the affine map that moves the origin to zero, makes the dominant direction axis `z` and
/// shears the ray onto the `+z` axis, so the 2D edge functions of the transformed vertices
/// decide the hit. A vertex shared by two triangles is transformed identically in both and
/// edge functions of a shared edge are exact negatives, which is what makes it watertight.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    origin: Vec3A,
    /// Rows: `e_kx - Sx e_kz`, `e_ky - Sy e_kz`, `Sz e_kz` (paper's permutation + shear).
    shear: Mat3A,
}

impl WatertightRay {
    /// Precomputes the transform for the ray `origin + t * direction` (direction non-zero,
    /// not necessarily unit).
    #[inline]
    pub fn new(origin: Vec3, direction: Vec3) -> Self {
        let a = direction.abs();
        let kz = if a.x > a.y {
            if a.x > a.z {
                0
            } else {
                2
            }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let kx = (kz + 1) % 3;
        let ky = (kx + 1) % 3;
        let d = direction.to_array();
        let sx = d[kx] / d[kz];
        let sy = d[ky] / d[kz];
        let sz = 1.0 / d[kz];
        let mut rx = [0.0f32; 3];
        let mut ry = [0.0f32; 3];
        let mut rz = [0.0f32; 3];
        rx[kx] = 1.0;
        rx[kz] = -sx;
        ry[ky] = 1.0;
        ry[kz] = -sy;
        rz[kz] = sz;
        // Each output coordinate is v[kx] + (-Sx * v[kz]) plus exact zeros, i.e. the
        // paper's `A[kx] - Sx * A[kz]` with the same single rounding per operation.
        let shear = Mat3A::from_cols(rx.into(), ry.into(), rz.into()).transpose();
        Self {
            origin: origin.into(),
            shear,
        }
    }

    /// Two-sided watertight intersection with triangle `(v0, v1, v2)`, accepting
    /// `tmin < t < tmax` where `t - tmin` also exceeds the error bound of the computed `t`.
    /// Degenerate triangles and rays in the triangle's plane miss.
    #[inline(always)]
    pub fn intersect_triangle(
        &self,
        v0: Vec3A,
        v1: Vec3A,
        v2: Vec3A,
        tmin: f32,
        tmax: f32,
    ) -> Option<TriangleHit> {
        let a = self.shear * (v0 - self.origin);
        let b = self.shear * (v1 - self.origin);
        let c = self.shear * (v2 - self.origin);
        // Scaled barycentrics (2D edge functions), paper eq. (4)-(6).
        let mut u = c.x * b.y - c.y * b.x;
        let mut v = a.x * c.y - a.y * c.x;
        let mut w = b.x * a.y - b.y * a.x;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            (u, v, w) = edge_functions_f64(a, b, c);
        }
        // Two-sided: all edge functions must share a sign (zeros are on the edge: a hit).
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let scaled_t = u * a.z + v * b.z + w * c.z;
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
        if t - tmin <= t_error_bound(a, b, c, u, v, w, inv_det) {
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

/// Absolute error bound of the `t` computed by [`WatertightRay::intersect_triangle`] from
/// the transformed vertices `a, b, c` and the edge functions `u, v, w` (pbrt-v4 sec. 6.8.7:
/// delta_t = 3 (gamma(3) max|e| max|z| + delta_e max|z| + delta_z max|e|) / |det|).
#[inline(always)]
fn t_error_bound(a: Vec3A, b: Vec3A, c: Vec3A, u: f32, v: f32, w: f32, inv_det: f32) -> f32 {
    let max_x = a.x.abs().max(b.x.abs()).max(c.x.abs());
    let max_y = a.y.abs().max(b.y.abs()).max(c.y.abs());
    let max_z = a.z.abs().max(b.z.abs()).max(c.z.abs());
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
#[cold]
#[inline(never)]
fn edge_functions_f64(a: Vec3A, b: Vec3A, c: Vec3A) -> (f32, f32, f32) {
    let (ax, ay) = (a.x as f64, a.y as f64);
    let (bx, by) = (b.x as f64, b.y as f64);
    let (cx, cy) = (c.x as f64, c.y as f64);
    (
        (cx * by - cy * bx) as f32,
        (ax * cy - ay * cx) as f32,
        (bx * ay - by * ax) as f32,
    )
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
    neg: [bool; 3],
    tmin: f32,
}

impl NodeRay {
    #[inline(always)]
    fn new(origin: Vec3, direction: Vec3, tmin: f32) -> Self {
        let safe = |x: f32| {
            if x.abs() < MIN_DIR {
                (1.0 / MIN_DIR).copysign(x)
            } else {
                1.0 / x
            }
        };
        let inv_dir = Vec3A::new(safe(direction.x), safe(direction.y), safe(direction.z));
        Self {
            origin: origin.into(),
            inv_dir,
            slack_scale: inv_dir.abs() * NODE_SLACK,
            // From inv_dir, so -0.0 components pick planes consistently with their inverse.
            neg: [inv_dir.x < 0.0, inv_dir.y < 0.0, inv_dir.z < 0.0],
            tmin,
        }
    }
}

#[inline(always)]
fn quantized4(q: &[u8; 8], i: usize) -> Vec4 {
    Vec4::new(
        q[4 * i] as f32,
        q[4 * i + 1] as f32,
        q[4 * i + 2] as f32,
        q[4 * i + 3] as f32,
    )
}

/// Slab test of the ray against the 8 children of a CWBVH node, four at a time. Returns
/// the obvhs hit mask (child bits in traversal order; see `CwBvhNode::intersect_ray`).
#[inline(always)]
fn intersect_node(node: &CwBvhNode, ray: &NodeRay, oct_inv4: u32, tmax: f32) -> u32 {
    let e = node.compute_extent();
    let diff = Vec3A::from(node.p) - ray.origin;
    let adj_dir = e * ray.inv_dir;
    let adj_orig = diff * ray.inv_dir;
    let slack = (e * 255.0 + diff.abs()) * ray.slack_scale;
    let near_orig = adj_orig - slack;
    let far_orig = adj_orig + slack;
    let tmin4 = Vec4::splat(ray.tmin);
    let tmax4 = Vec4::splat(tmax);
    let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
    let mut hit_mask = 0u32;
    for i in 0..2 {
        let lo = quantized4(&node.child_min_x, i);
        let hi = quantized4(&node.child_max_x, i);
        let (n, f) = if ray.neg[0] { (hi, lo) } else { (lo, hi) };
        let tnear_x = n * adj_dir.x + near_orig.x;
        let tfar_x = f * adj_dir.x + far_orig.x;

        let lo = quantized4(&node.child_min_y, i);
        let hi = quantized4(&node.child_max_y, i);
        let (n, f) = if ray.neg[1] { (hi, lo) } else { (lo, hi) };
        let tnear_y = n * adj_dir.y + near_orig.y;
        let tfar_y = f * adj_dir.y + far_orig.y;

        let lo = quantized4(&node.child_min_z, i);
        let hi = quantized4(&node.child_max_z, i);
        let (n, f) = if ray.neg[2] { (hi, lo) } else { (lo, hi) };
        let tnear_z = n * adj_dir.z + near_orig.z;
        let tfar_z = f * adj_dir.z + far_orig.z;

        let tnear = tnear_x.max(tnear_y).max(tnear_z.max(tmin4));
        let tfar = tfar_x.min(tfar_y).min(tfar_z.min(tmax4));
        let mask = tnear.cmple(tfar).bitmask();
        for j in 0..4 {
            if mask & (1 << j) != 0 {
                let child = i * 4 + j;
                hit_mask |= extract_byte64(child_bits8, child) << extract_byte64(bit_index8, child);
            }
        }
    }
    hit_mask
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
    let Some(bvh) = geom.bvh() else {
        t.fill(f32::INFINITY);
        prim.fill(NO_HIT);
        b1.fill(0.0);
        b2.fill(0.0);
        return;
    };
    let leaves: &[LeafPrim] = geom.leaves();
    let num_tri = geom.num_triangles() as u32;
    let mut state = bvh.new_traversal(Vec3A::Z);
    for i in 0..n {
        let (o, d, ray_tmin) = (origin[i], direction[i], tmin[i]);
        let node_ray = NodeRay::new(o, d, ray_tmin);
        let tri_ray = WatertightRay::new(o, d);
        let mut best_t = tmax[i];
        let mut best_leaf = u32::MAX;
        let (mut hit_b1, mut hit_b2) = (0.0f32, 0.0f32);
        state.reinit(d.into());
        let mut node;
        traverse!(
            bvh,
            node,
            state,
            intersect_node(node, &node_ray, state.oct_inv4, best_t),
            {
                let leaf = &leaves[state.primitive_id as usize];
                if leaf.prim < num_tri {
                    if let Some(h) = tri_ray.intersect_triangle(
                        leaf.v0.into(),
                        leaf.v1.into(),
                        leaf.v2.into(),
                        ray_tmin,
                        best_t,
                    ) {
                        best_t = h.t;
                        best_leaf = state.primitive_id;
                        hit_b1 = h.b1;
                        hit_b2 = h.b2;
                    }
                } else {
                    let ts = intersect_sphere(o, d, leaf.v0.into(), leaf.v1[0], ray_tmin, best_t);
                    if ts < best_t {
                        best_t = ts;
                        best_leaf = state.primitive_id;
                    }
                }
            }
        );
        if best_leaf == u32::MAX {
            t[i] = f32::INFINITY;
            prim[i] = NO_HIT;
            b1[i] = 0.0;
            b2[i] = 0.0;
        } else {
            let leaf = &leaves[best_leaf as usize];
            if leaf.prim >= num_tri {
                // Surface parameters from the double-precision root (rare: spheres only).
                let c = Vec3::from(leaf.v0);
                let uv = sphere_t64(o, d, c, leaf.v1[0], ray_tmin, tmax[i])
                    .map(|t64| sphere_uv((o.as_dvec3() - c.as_dvec3()) + d.as_dvec3() * t64))
                    .unwrap_or_else(|| sphere_uv(DVec3::Z));
                hit_b1 = uv.x;
                hit_b2 = uv.y;
            }
            t[i] = best_t;
            prim[i] = leaf.prim;
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
    let Some(bvh) = geom.bvh() else {
        occluded.fill(false);
        return;
    };
    let leaves: &[LeafPrim] = geom.leaves();
    let num_tri = geom.num_triangles() as u32;
    let mut state = bvh.new_traversal(Vec3A::Z);
    for i in 0..n {
        let (o, d, ray_tmin, ray_tmax) = (origin[i], direction[i], tmin[i], tmax[i]);
        let node_ray = NodeRay::new(o, d, ray_tmin);
        let tri_ray = WatertightRay::new(o, d);
        let mut hit = false;
        state.reinit(d.into());
        let mut node;
        'traversal: {
            traverse!(
                bvh,
                node,
                state,
                intersect_node(node, &node_ray, state.oct_inv4, ray_tmax),
                {
                    let leaf = &leaves[state.primitive_id as usize];
                    hit = if leaf.prim < num_tri {
                        tri_ray
                            .intersect_triangle(
                                leaf.v0.into(),
                                leaf.v1.into(),
                                leaf.v2.into(),
                                ray_tmin,
                                ray_tmax,
                            )
                            .is_some()
                    } else {
                        sphere_t64(o, d, leaf.v0.into(), leaf.v1[0], ray_tmin, ray_tmax).is_some()
                    };
                    if hit {
                        break 'traversal;
                    }
                }
            );
        }
        occluded[i] = hit;
    }
}
