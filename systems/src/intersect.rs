//! Ray/scene intersection systems: closest hit and occlusion over columns of rays.
//!
//! Traversal runs over the uncompressed 4-wide BVH of [`SceneGeometry`] (f32 child boxes
//! stored as SoA rows, see `crate::bvh4`): one ray against four child boxes is a dozen SIMD
//! multiply-adds and min/max with no decoding. The node test honours the ray's `tmin` and
//! widens every slab by a bound on its floating-point error (a per-ray constant, see
//! [`NODE_SLACK`]), so a box is never culled when the primitive test would report a hit
//! inside it (a plain slab test loses rays grazing box faces, e.g. along the edges of an
//! axis-aligned mesh). Closest-hit rays visit hit children, leaves included, nearest entry
//! distance first and skip stacked ones beyond the closest hit so far; shadow rays test a
//! node's hit leaves at once and stop at the first hit.
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

use glam::{DVec3, Vec3, Vec3A, Vec3Swizzles, Vec4, Vec4Swizzles};
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

/// Smallest direction component used in the slab test; `1/d` is clamped to `1e20` so no
/// infinities (and `0 * inf` NaNs) arise for axis-parallel rays.
const MIN_DIR: f32 = 1e-20;

/// Relative slab widening of the 4-wide node test. A slab distance is computed as
/// `b * inv + near_orig` with `inv = fl(1/d)` and `near_orig = fl(fl(-o * inv) -+ s)`: with
/// unit roundoff `u = 2^-24` its error against `(b - o) / d` is below
/// `u (3 |b| + 4 |o|) / |d| + 2 u s` (standard model, Higham 2002 ch. 3: two roundings in
/// `b * inv`, two in `-o * inv`, one in the widening and one in the sum), and `|b|` is at
/// most the largest box coordinate magnitude `B` on that axis. Widening by
/// `s = 8 u (B + |o|) |inv|` therefore covers it on every axis, for every node of the tree,
/// so the widening is a per-ray constant folded into `near_orig`/`far_orig`.
const NODE_SLACK: f32 = 4.0 * f32::EPSILON;

/// Per-ray constants of the 4-wide node test, each splat across the four child lanes.
struct Ray4 {
    /// `1 / d` per axis, with components below [`MIN_DIR`] clamped.
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
        let slack = (max_abs + o.abs()) * (inv_dir.abs() * NODE_SLACK);
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

/// Closest-hit traversal of the 4-wide BVH: hit children, leaves and inner nodes alike, are
/// visited nearest entry distance first, and stacked children that start beyond the shrunk
/// `tmax` are skipped, so leaves behind the closest hit are never tested. `leaf(slot, tmax)`
/// tests the primitive in leaf slot `slot`, may shrink `tmax` and returns true to stop.
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
/// them costs less than stacking them), then the hit inner children are visited nearest
/// first. `leaf(slot)` returns true to stop.
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
            // The hit inner children sorted far to near (insertion sort of at most four):
            // all but the nearest are stacked, so they are popped nearest first.
            let mut order = [0usize; 4];
            let mut k = 0;
            while inner != 0 {
                let c = inner.trailing_zeros() as usize & 3;
                inner &= inner - 1;
                let mut j = k;
                while j > 0 && t[order[j - 1]] < t[c] {
                    order[j] = order[j - 1];
                    j -= 1;
                }
                order[j] = c;
                k += 1;
            }
            for &c in &order[..k - 1] {
                stack.push(node.child[c]);
            }
            index = node.child[order[k - 1]] as usize;
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

    use crate::sampler::SplitMix64 as Rng;

    /// Test-input helpers on top of the shared generator.
    trait RngExt {
        fn vec(&mut self, lo: f32, hi: f32) -> Vec3;
    }

    impl RngExt for Rng {
        fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
            Vec3::new(self.f32(), self.f32(), self.f32()) * (hi - lo) + Vec3::splat(lo)
        }
    }

    /// The 4-wide node test against an exact slab test in f64 on the same clamped inverse
    /// direction: every child box the ray truly meets within `[tmin, tmax]` must be hit
    /// (conservative), and boxes it misses by more than the widening must not be.
    #[test]
    fn node4_test_is_conservative_and_tight() {
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
        let (bvh, _) = geom.bvh4().unwrap();
        let (mut hits, mut misses, mut touching) = (0, 0, 0);
        for k in 0..3000 {
            let o = rng.vec(-12.0, 12.0);
            // Mostly aimed at a box corner, so the ray grazes that box (without the widening
            // rounding culls some of these boxes; checked), else near a triangle.
            let node = &bvh.nodes[(rng.next_u64() % bvh.nodes.len() as u64) as usize];
            let c = (rng.next_u64() % 4) as usize;
            let target = if k % 3 != 2 && node.bounds[0][c].is_finite() {
                Vec3::new(node.bounds[0][c], node.bounds[3][c], node.bounds[4][c])
            } else {
                geom.triangle((rng.next_u64() % 3000) as usize)[0] + rng.vec(-0.1, 0.1)
            };
            let mut d = target - o;
            // Axis-parallel directions, including negative zeros.
            match k % 7 {
                1 => d.x = 0.0,
                2 => d.y = -0.0,
                4 => d = Vec3::new(0.0, -0.0, d.z),
                _ => {}
            }
            let (tmin, tmax) = if k % 2 == 0 {
                (0.0, f32::INFINITY)
            } else {
                (rng.f32() * 0.5, 0.5 + rng.f32())
            };
            let ray = Ray4::new(o, d, tmin, bvh.max_abs);
            let inv = |x: f32| -> f64 {
                if x.abs() < MIN_DIR {
                    (1.0 / MIN_DIR as f64).copysign(x as f64)
                } else {
                    1.0 / x as f64
                }
            };
            let inv = [inv(d.x), inv(d.y), inv(d.z)];
            let (o64, b64) = (o.as_dvec3().to_array(), bvh.max_abs.as_dvec3().to_array());
            for node in &bvh.nodes {
                let (mask, _) = intersect_node4(node, &ray, tmax);
                for c in 0..4 {
                    if !node.bounds[0][c].is_finite() {
                        assert_eq!(mask & (1 << c), 0, "empty slot hit");
                        continue;
                    }
                    let (mut tn, mut tf) = (tmin as f64, tmax as f64);
                    let mut margin = 0.0f64;
                    for a in 0..3 {
                        let lo = (node.bounds[2 * a][c] as f64 - o64[a]) * inv[a];
                        let hi = (node.bounds[2 * a + 1][c] as f64 - o64[a]) * inv[a];
                        tn = tn.max(lo.min(hi));
                        tf = tf.min(lo.max(hi));
                        margin = margin.max(1e-5 * (b64[a] + o64[a].abs()) * inv[a].abs());
                    }
                    let got = mask & (1 << c) != 0;
                    if tn <= tf {
                        assert!(got, "ray {k}: o={o:?} d={d:?} misses child {c} of {node:?}");
                        hits += 1;
                        touching += (tn == tf) as usize;
                    } else if tn > tf + margin {
                        assert!(!got, "ray {k}: o={o:?} d={d:?} hits child {c} of {node:?}");
                        misses += 1;
                    }
                }
            }
        }
        assert!(
            hits > 3_000 && misses > 100_000 && touching > 10,
            "{hits} child hits ({touching} touching), {misses} misses"
        );
    }

    /// The collapse keeps every primitive exactly once, every child box contains what it
    /// holds, and every node is reachable from the root exactly once.
    #[test]
    fn bvh4_collapse_is_a_complete_bounding_tree() {
        let mut rng = Rng(5);
        for n in [1usize, 2, 3, 5, 17, 2000] {
            let tris: Vec<[Vec3; 3]> = (0..n)
                .map(|_| {
                    let c = rng.vec(-10.0, 10.0);
                    [c, c + rng.vec(-0.5, 0.5), c + rng.vec(-3.0, 3.0)]
                })
                .collect();
            let geom = SceneGeometry::build(tris.clone(), Vec::new());
            let (bvh, leaves) = geom.bvh4().unwrap();
            let mut seen = vec![0u32; n];
            for &p in &bvh.prim_indices {
                seen[p as usize] += 1;
            }
            assert!(seen.iter().all(|&s| s == 1), "n = {n}: {seen:?}");
            assert_eq!(leaves.len(), n);
            let mut reached = vec![0u32; bvh.nodes.len()];
            let mut stack = vec![0usize];
            reached[0] = 1;
            let child_box = |node: &Bvh4Node, c: usize| {
                (
                    Vec3::new(node.bounds[0][c], node.bounds[2][c], node.bounds[4][c]),
                    Vec3::new(node.bounds[1][c], node.bounds[3][c], node.bounds[5][c]),
                )
            };
            while let Some(i) = stack.pop() {
                let node = &bvh.nodes[i];
                for c in 0..4 {
                    let (lo, hi) = child_box(node, c);
                    if !lo.is_finite() {
                        continue;
                    }
                    if node.leaf_mask & (1 << c) != 0 {
                        let first = node.child[c] as usize;
                        assert!(node.count[c] >= 1);
                        for s in first..first + node.count[c] as usize {
                            let tri = tris[bvh.prim_indices[s] as usize];
                            for v in tri {
                                assert!(v.cmpge(lo).all() && v.cmple(hi).all());
                            }
                            assert_eq!(
                                leaves[s].rows,
                                PackedTriangle::new(tri[0], tri[1], tri[2]).rows
                            );
                        }
                    } else {
                        let k = node.child[c] as usize;
                        reached[k] += 1;
                        stack.push(k);
                        for cc in 0..4 {
                            let (clo, chi) = child_box(&bvh.nodes[k], cc);
                            if clo.is_finite() {
                                assert!(clo.cmpge(lo).all() && chi.cmple(hi).all());
                            }
                        }
                    }
                }
            }
            assert!(reached.iter().all(|&r| r == 1), "n = {n}: {reached:?}");
        }
    }
}
