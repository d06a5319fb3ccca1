//! The shadow terminator of smooth-shaded coarse meshes: rays that leave a triangle of a
//! mesh with vertex normals start from the smooth surface those normals imply, not from the
//! flat triangle.
//!
//! A coarse mesh with vertex normals is shaded as if it were the smooth surface the normals
//! describe, but its rays leave from the flat triangles, which lie *inside* that surface on
//! a convex part. Near the terminator (where light arrives at grazing angles) a shadow ray
//! from the flat triangle is blocked by the neighbouring triangles although the smooth
//! surface would see the light: the lit side ends in hard, faceted shadow steps. Hanika
//! (2021, "Hacking the Shadow Terminator", *Ray Tracing Gems II*, ch. 4) moves the origin to
//! a point of a curved surface through the triangle's vertices: `p` is projected onto the
//! tangent plane of each vertex (the plane through `v_i` orthogonal to `n_i`), but only
//! where it lies below that plane, and the projections are blended with the hit's
//! barycentrics:
//!
//! `p' = sum_i b_i (p - n_i min(0, (p - v_i) . n_i))`
//!
//! The result is quadratic in the barycentrics, equals the vertices at the corners, is
//! continuous across edges shared with the same normals, and equals `p` where the mesh is
//! flat or concave (every `(p - v_i) . n_i >= 0`). Cycles implements the same construction
//! (`triangle_smooth_offset`, behind its per-object `shadow_terminator_geometry_offset`,
//! which blends it in only near the terminator); Mitsuba 3 and pbrt-v4 have none.
//!
//! Only rays leaving to the viewer's side of the triangle use `p'` (shadow rays and
//! reflected path rays): a transmitted ray must leave from the flat triangle, which is the
//! surface it crosses. For a viewer behind the triangle the normals are turned to its side,
//! so what is convex from there is lifted.

use crate::geometry::SceneGeometry;
use crate::primitive::gamma;
use glam::Vec3;
use risotto_components::{Hits, ShadingPoints};
use std::ops::Range;

/// The slope below which a vertex's tangent plane counts as the triangle's own: `1e-5`
/// (radians), above the disagreement of a face normal written to a file with six digits
/// (OBJ's usual precision, about `1e-6`) or mapped by a transform (a few `f32` ulps), and
/// far below any curvature a mesh means (a 0.1 degree bend is `1.7e-3`).
pub const FLAT: f32 = 1e-5;

/// Hanika's displacement `p' - p` of the point `p` (barycentrics `b`) of the triangle `v`
/// with unit vertex normals `n` (zero normals contribute nothing):
/// `sum_i b_i n_i max(0, -(p - v_i) . n_i)`, the blend of `p`'s projections onto the
/// tangent planes it lies below. A distance below a plane within `p`'s own error bound
/// along the triangle's normal (`p_offset`, the shading point's) plus [`FLAT`] times
/// `|p - v_i|` counts as on the plane, so a flat mesh (every normal the face's, as a file
/// can write it) gives exactly zero.
#[inline]
pub fn smooth_surface_offset(
    p: Vec3,
    p_offset: f32,
    v: [Vec3; 3],
    n: [Vec3; 3],
    b: [f32; 3],
) -> Vec3 {
    let mut d = Vec3::ZERO;
    for i in 0..3 {
        let to_p = p - v[i];
        let below = -to_p.dot(n[i]);
        if below > p_offset + FLAT * to_p.abs().dot(n[i].abs()) {
            d += n[i] * (b[i] * below);
        }
    }
    d
}

/// The displacement that moves a hit `p` (error bound `p_offset` along `ng`, barycentrics
/// `b`) on the triangle `v` with
/// vertex normals `n` (unit or zero, in the file's orientation), geometric normal `ng` and
/// direction to the viewer `vn`, to the smooth surface on the viewer's side: the origin
/// `p + lift` of rays leaving to that side.
///
/// The normals are first oriented as the shading normal is (their interpolation turned to
/// `ng`'s side, `crate::mesh_attributes`), then to the viewer's side; then
/// [`smooth_surface_offset`]. A displacement that is not strictly above the triangle on the
/// viewer's side (normals that disagree with each other, a degenerate triangle) or not
/// finite gives zero: the origin is never below the flat triangle. A non-zero one is
/// lengthened along the side's normal by the rounding error of computing it and adding it to
/// `p` (a few ulps of the coordinates), so that `p + lift`, computed in `f32`, is at least
/// as far above the triangle as `p` is: the ray spawn then moves it off by `p`'s own error
/// bound as for any surface point (`crate::ray::offset_origin`).
#[inline]
pub fn terminator_lift(
    p: Vec3,
    p_offset: f32,
    v: [Vec3; 3],
    n: [Vec3; 3],
    b: [f32; 3],
    ng: Vec3,
    vn: Vec3,
) -> Vec3 {
    let viewer_above = vn.dot(ng) >= 0.0;
    let interpolated = n[0] * b[0] + n[1] * b[1] + n[2] * b[2];
    let keep = (interpolated.dot(ng) >= 0.0) == viewer_above;
    let n = if keep { n } else { n.map(|n| -n) };
    let d = smooth_surface_offset(p, p_offset, v, n, b);
    let up = if viewer_above { ng } else { -ng };
    if d.dot(up) <= 0.0 || !d.is_finite() {
        return Vec3::ZERO;
    }
    // Rounding of `p - v_i`, the dot products, the blend and `p + d`, each bounded by a
    // few `gamma`s of the magnitudes involved.
    let spread: f32 = (0..3).map(|i| (p - v[i]).abs().dot(n[i].abs())).sum();
    let pad = gamma(8.0) * (ng.abs().dot(p.abs() + d.abs()) + spread);
    d + up * pad
}

/// The column system: for the shading points `range` of `points`, whose hits are the rows
/// `rows` of `hits` (primitive and barycentrics; `rows[k]` is point `range.start + k`'s),
/// writes `terminator_lift` = [`terminator_lift`] of the point (its `p`, `p_offset`, `ng`,
/// `vn`) on the points whose hit is a triangle of a mesh with vertex normals that asks for
/// the offset ([`SceneGeometry::terminator_triangle`]); other points are left as they are.
/// Returns the number of points given a non-zero lift.
///
/// # Panics
/// When `range` is not one of `points`' or has another length than `rows`, or a row is not
/// one of `hits`.
pub fn terminator_lifts(
    geometry: &SceneGeometry,
    hits: &Hits,
    rows: &[u32],
    points: &mut ShadingPoints,
    range: Range<usize>,
) -> usize {
    let m = rows.len();
    assert_eq!(range.len(), m, "one hit row per point");
    let (p, p_offset) = (&points.p[range.clone()], &points.p_offset[range.clone()]);
    let (ng, vn) = (&points.ng[range.clone()], &points.vn[range.clone()]);
    let lift = &mut points.terminator_lift[range];
    let n = hits.len();
    let (prims, b1, b2) = (&hits.prim[..n], &hits.b1[..n], &hits.b2[..n]);
    let mut lifted = 0;
    for k in 0..m {
        let i = rows[k] as usize;
        if let Some((v, normals)) = geometry.terminator_triangle(prims[i]) {
            let b = [1.0 - b1[i] - b2[i], b1[i], b2[i]];
            let d = terminator_lift(p[k], p_offset[k], v, normals, b, ng[k], vn[k]);
            lifted += (d != Vec3::ZERO) as usize;
            lift[k] = d;
        }
    }
    lifted
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A right triangle in `z = 0` whose vertex normals lean outwards from its centroid, as
    /// on a coarse sphere: by hand at the centroid and at an edge midpoint.
    #[test]
    fn the_offset_matches_a_hand_computation() {
        let v = [
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let s = 0.6f32;
        let c = 0.8f32;
        let n = [
            Vec3::new(-s, 0.0, c),
            Vec3::new(s, 0.0, c),
            Vec3::new(0.0, s, c),
        ];
        // Centroid p = (1/3, 1/3, 0): (p - v_i) . n_i = -0.2, -0.4, -0.4 (all below).
        // d = 1/3 (0.2 n0 + 0.4 n1 + 0.4 n2) = 1/3 (0.12, 0.24, 0.8).
        let third = 1.0 / 3.0;
        let p = Vec3::new(third, third, 0.0);
        let d = smooth_surface_offset(p, 0.0, v, n, [third; 3]);
        let want = Vec3::new(0.12, 0.24, 0.8) / 3.0;
        assert!((d - want).length() < 1e-6, "{d} against {want}");
        // Midpoint of v0 v1, p = (0.5, 0, 0), b = (0.5, 0.5, 0):
        // (p - v0) . n0 = -0.3 -> 0.5 * 0.3 n0; (p - v1) . n1 = -0.3 -> 0.5 * 0.3 n1;
        // d = 0.15 (n0 + n1) = (0, 0, 0.24).
        let d = smooth_surface_offset(Vec3::new(0.5, 0.0, 0.0), 0.0, v, n, [0.5, 0.5, 0.0]);
        assert!((d - Vec3::new(0.0, 0.0, 0.24)).length() < 1e-6, "{d}");
        // Vertices stay where they are.
        for i in 0..3 {
            let mut b = [0.0; 3];
            b[i] = 1.0;
            assert_eq!(smooth_surface_offset(v[i], 0.0, v, n, b), Vec3::ZERO);
        }
        // Only planes the point lies below count: tilt n0 so that p is above its plane.
        let n_up = [Vec3::new(s, 0.0, c), n[1], n[2]];
        // (p - v0) . n0' = +0.2 (above, no term); the others as before.
        let d = smooth_surface_offset(p, 0.0, v, n_up, [third; 3]);
        let want = (n[1] * 0.4 + n[2] * 0.4) / 3.0;
        assert!((d - want).length() < 1e-6, "{d} against {want}");
    }

    /// On a flat mesh (every normal the face's) the lift is exactly zero, at random points
    /// of a far-from-origin tilted triangle; on a curved one it is never below the
    /// triangle, on the viewer's side, and the ray's origin is at least as high as `p`.
    #[test]
    fn the_lift_is_zero_on_flat_meshes_and_never_below_the_triangle() {
        let mut rng = crate::sampler::SplitMix64(5);
        let c = Vec3::new(300.0, -20.0, 7.0);
        let v = [
            c,
            c + Vec3::new(0.7, 0.1, 0.3),
            c + Vec3::new(-0.2, 0.9, 0.4),
        ];
        let ng = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
        for _ in 0..2000 {
            let (x, y) = (rng.f32(), rng.f32());
            let (b1, b2) = if x + y > 1.0 {
                (1.0 - x, 1.0 - y)
            } else {
                (x, y)
            };
            let b = [1.0 - b1 - b2, b1, b2];
            // The point rounded once from f64, within half an ulp per component.
            let p64 = v[0].as_dvec3() * b[0] as f64
                + v[1].as_dvec3() * b[1] as f64
                + v[2].as_dvec3() * b[2] as f64;
            let p = p64.as_vec3();
            let p_offset = ng.abs().dot(p.abs()) * f32::EPSILON;
            for vn in [ng, -ng] {
                // Flat: exactly p, whichever orientation the file's normals have.
                for flat in [ng, -ng] {
                    assert_eq!(
                        terminator_lift(p, p_offset, v, [flat; 3], b, ng, vn),
                        Vec3::ZERO
                    );
                }
                // Curved: random normals within 60 degrees of ng (some leaning in, some out).
                let tilt = |rng: &mut crate::sampler::SplitMix64| {
                    (ng + Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5) * 1.5)
                        .normalize()
                };
                let n = [tilt(&mut rng), tilt(&mut rng), tilt(&mut rng)];
                let d = terminator_lift(p, p_offset, v, n, b, ng, vn);
                let up = if vn.dot(ng) >= 0.0 { ng } else { -ng };
                if d != Vec3::ZERO {
                    assert!(d.dot(up) > 0.0, "{d} below the triangle");
                    // The computed origin, in f64, above the plane through v0 at least as
                    // far as p (which is on the plane up to its own rounding).
                    let o = (p + d).as_dvec3();
                    let h = (o - v[0].as_dvec3()).dot(up.as_dvec3());
                    let hp = (p.as_dvec3() - v[0].as_dvec3()).dot(up.as_dvec3());
                    assert!(h >= hp, "origin {h} below p {hp}");
                }
            }
        }
    }

    /// The viewer's side decides: a convex bump seen from above is lifted upwards, and seen
    /// from below (where it is concave) not at all; normals written against the winding
    /// give the same lift as the shading normal is turned the same way.
    #[test]
    fn the_lift_goes_to_the_viewers_side() {
        let v = [
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let n = [
            Vec3::new(-0.6, 0.0, 0.8),
            Vec3::new(0.6, 0.0, 0.8),
            Vec3::new(0.0, 0.6, 0.8),
        ];
        let third = 1.0 / 3.0;
        let p = Vec3::new(third, third, 0.0);
        let above = terminator_lift(p, 0.0, v, n, [third; 3], Vec3::Z, Vec3::Z);
        assert!((above - Vec3::new(0.04, 0.08, 0.8 / 3.0)).length() < 1e-5);
        assert_eq!(
            terminator_lift(p, 0.0, v, n, [third; 3], Vec3::Z, -Vec3::Z),
            Vec3::ZERO
        );
        let flipped = n.map(|n| -n);
        assert_eq!(
            terminator_lift(p, 0.0, v, flipped, [third; 3], Vec3::Z, Vec3::Z),
            above
        );
        // A dent (normals leaning inwards) is lifted downwards for a viewer below.
        let dent = n.map(|n| Vec3::new(-n.x, -n.y, n.z));
        let below = terminator_lift(p, 0.0, v, dent, [third; 3], Vec3::Z, -Vec3::Z);
        assert!(below.z < -0.2, "{below}");
    }
}
