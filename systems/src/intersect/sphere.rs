//! Ray/sphere roots in double precision (Haines et al. 2019, Ray Tracing Gems ch. 7) and
//! the sphere leaves of the traversals.

use super::*;

/// The nearest root of the ray/sphere quadratic with `tmin < t < tmax` (compared after
/// rounding `t` to f32), in double precision.
pub(super) fn sphere_t64(
    o: Vec3,
    d: Vec3,
    center: Vec3,
    radius: f32,
    tmin: f32,
    tmax: f32,
) -> Option<f64> {
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
pub(super) fn sphere_root_in_range(t: f64, tmin: f32, tmax: f32) -> bool {
    let t32 = t as f32;
    t32 > tmin && t32 < tmax
}

/// Both roots `t0 <= t1` of the ray/sphere quadratic in double precision, or `None` where
/// neither can lie in `(tmin, tmax)` (the early rejections below decide only that) or the
/// ray misses the sphere. The caller picks the roots in range
/// ([`sphere_root_in_range`]).
#[inline(always)]
pub(super) fn sphere_roots64(
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

/// [`intersect_sphere`] on a sphere leaf; out of line, so that the traversal loops of
/// triangle-only scenes carry no sphere set-up.
#[inline(never)]
pub(super) fn sphere_leaf_t(leaf: &SphereLeaf, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> f32 {
    let cr = leaf.center_radius;
    intersect_sphere(o, d, cr.truncate(), cr.w, tmin, tmax)
}

/// The double-precision root of [`sphere_leaf_t`] (closest-hit traversal keeps it for the
/// hit's direction).
#[inline(never)]
pub(super) fn sphere_leaf_t64(
    leaf: &SphereLeaf,
    o: Vec3,
    d: Vec3,
    tmin: f32,
    tmax: f32,
) -> Option<f64> {
    let cr = leaf.center_radius;
    sphere_t64(o, d, cr.truncate(), cr.w, tmin, tmax)
}

/// `(b1, b2)` of the closest hit on a sphere: the f64 root's residual against its f32
/// rounding `t64 as f32` (so that `t + b1` is the root to ~48 bits) and 0. No division or
/// square root: the hit's direction, which needs both, is computed only for the hits that
/// get shaded ([`SceneGeometry::surface_at`]); most of a medium's hits do not.
#[inline(always)]
pub(super) fn sphere_hit_params(t64: f64) -> (f32, f32) {
    ((t64 - (t64 as f32) as f64) as f32, 0.0)
}
