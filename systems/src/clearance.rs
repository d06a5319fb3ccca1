//! Clearance: the distance from a point to the nearest surface of the scene (capped), over
//! the 8-wide BVH. A walk inside a medium that knows the ball around its position is empty
//! may take every step that stays in the ball without tracing a ray
//! (`risotto_engine::random_walk`): no surface can be crossed by a segment whose two ends lie
//! in a ball that contains no surface point (the ball is convex).
//!
//! The query is a best-first-free depth-first traversal: a child is visited only if its box
//! is nearer than the nearest surface found so far (the squared point-box distance, per
//! lane of the node's box rows); a triangle's distance is Ericson's closest point on a
//! triangle (*Real-Time Collision Detection*, 2005, sec. 5.1.5), a sphere's
//! `| |p - c| - r |`. The result is exact up to f32 rounding (a few ulps of the scene's
//! coordinates); callers that need a strict bound shrink it by a margin. An instance's
//! object is searched in object space and its distance divided by the Frobenius norm of
//! the world-to-object map (at least its largest singular value, the most the map can
//! stretch a distance): a lower bound of the world distance, exact for rigid placements up
//! to the norm's overestimate of 1 by `sqrt(3)`.

use crate::bvh8::{Bvh8, Node8, INDEX_MASK, INSTANCE, LEAF, SPHERE, WIDTH};
use crate::geometry::SceneGeometry;
use glam::{Vec3, Vec3A};

/// The distance from `p` to the nearest surface (triangle or sphere) of `geometry`, or `cap`
/// if none is nearer than `cap`. An empty scene has clearance `cap`.
pub fn clearance(geometry: &SceneGeometry, p: Vec3, cap: f32) -> f32 {
    let Some((bvh, _)) = geometry.bvh8() else {
        return cap;
    };
    clearance_in(bvh, Vec3A::from(p), cap)
}

/// [`clearance`] over `bvh` (the top level or an object's).
fn clearance_in(bvh: &Bvh8, p: Vec3A, cap: f32) -> f32 {
    let mut best2 = cap * cap;
    let mut stack: Vec<u32> = Vec::with_capacity(bvh.stack_capacity());
    stack.push(0);
    while let Some(n) = stack.pop() {
        let node: &Node8 = &bvh.nodes[n as usize];
        for c in 0..WIDTH {
            if node.valid & (1 << c) == 0 {
                continue;
            }
            let d2 = box_distance2(node, c, p);
            if d2 >= best2 {
                continue;
            }
            let child = node.child[c];
            if child & LEAF == 0 {
                stack.push(child);
            } else if child & INSTANCE != 0 {
                let leaf = &bvh.instances[(child & INDEX_MASK) as usize];
                let m = leaf.to_object.matrix3;
                let norm = (m.x_axis.length_squared()
                    + m.y_axis.length_squared()
                    + m.z_axis.length_squared())
                .sqrt();
                let q = leaf.to_object.transform_point3a(p);
                let object = &bvh.objects[leaf.object as usize];
                let d = clearance_in(object, q, best2.sqrt() * norm) / norm;
                best2 = best2.min(d * d);
            } else if child & SPHERE != 0 {
                let s = bvh.spheres[(child & INDEX_MASK) as usize].center_radius;
                let d = (p - Vec3A::from(s.truncate())).length() - s.w;
                best2 = best2.min(d * d);
            } else {
                let packet = &bvh.packets[(child & INDEX_MASK) as usize];
                for l in 0..WIDTH {
                    if packet.valid & (1 << l) == 0 {
                        continue;
                    }
                    let v = |i: usize| {
                        Vec3A::new(
                            packet.v[i][0].0[l],
                            packet.v[i][1].0[l],
                            packet.v[i][2].0[l],
                        )
                    };
                    let q = closest_on_triangle(p, v(0), v(1), v(2));
                    best2 = best2.min((p - q).length_squared());
                }
            }
        }
    }
    best2.sqrt().min(cap)
}

/// [`clearance`] for a column of points: `out[i] = clearance(geometry, p[i], cap[i])`.
pub fn clearance_column(geometry: &SceneGeometry, p: &[Vec3], cap: &[f32], out: &mut [f32]) {
    for ((o, &p), &cap) in out.iter_mut().zip(p).zip(cap) {
        *o = clearance(geometry, p, cap);
    }
}

/// Squared distance from `p` to child `c`'s box (0 inside; an empty slot's inverted box is
/// never asked for).
#[inline]
fn box_distance2(node: &Node8, c: usize, p: Vec3A) -> f32 {
    let lo = Vec3A::new(
        node.bounds[0].0[c],
        node.bounds[2].0[c],
        node.bounds[4].0[c],
    );
    let hi = Vec3A::new(
        node.bounds[1].0[c],
        node.bounds[3].0[c],
        node.bounds[5].0[c],
    );
    let d = (lo - p).max(p - hi).max(Vec3A::ZERO);
    d.length_squared()
}

/// The point of triangle `abc` closest to `p` (Ericson 2005, sec. 5.1.5: Voronoi regions of
/// the vertices, then the edges, then the face).
fn closest_on_triangle(p: Vec3A, a: Vec3A, b: Vec3A, c: Vec3A) -> Vec3A {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    if !denom.is_finite() {
        // A degenerate triangle: its nearest vertex is a conservative stand-in only if it is
        // no farther than the segment's points; take the nearest of the three edges' ends
        // and midpoints instead of dividing by zero.
        return [a, b, c, (a + b) * 0.5, (b + c) * 0.5, (a + c) * 0.5]
            .into_iter()
            .min_by(|x, y| {
                (p - *x)
                    .length_squared()
                    .total_cmp(&(p - *y).length_squared())
            })
            .unwrap_or(a);
    }
    a + ab * (vb * denom) + ac * (vc * denom)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Sphere;
    use crate::sampler::SplitMix64;

    /// Against brute force over random points: a unit sphere, a far sphere and a few
    /// triangles; the clearance equals the smallest distance to any primitive (by dense
    /// sampling of each triangle and the exact sphere distance) and respects the cap.
    #[test]
    fn clearance_matches_brute_force() {
        let tris = vec![
            [
                Vec3::new(-2.0, -1.0, -2.0),
                Vec3::new(2.0, -1.0, -2.0),
                Vec3::new(2.0, -1.0, 2.0),
            ],
            [
                Vec3::new(-2.0, -1.0, -2.0),
                Vec3::new(2.0, -1.0, 2.0),
                Vec3::new(-2.0, -1.0, 2.0),
            ],
            [
                Vec3::new(0.5, 0.5, 3.0),
                Vec3::new(1.5, 0.2, 3.5),
                Vec3::new(0.7, 1.9, 2.5),
            ],
        ];
        let spheres = vec![
            Sphere {
                center: Vec3::ZERO,
                radius: 1.0,
            },
            Sphere {
                center: Vec3::new(5.0, 0.0, 0.0),
                radius: 0.5,
            },
        ];
        let geometry = SceneGeometry::build(tris.clone(), spheres.clone());
        let mut rng = SplitMix64(3);
        for _ in 0..500 {
            let p = Vec3::new(
                rng.f32() * 8.0 - 3.0,
                rng.f32() * 4.0 - 2.0,
                rng.f32() * 8.0 - 3.0,
            );
            let mut want = f32::INFINITY;
            for s in &spheres {
                want = want.min(((p - s.center).length() - s.radius).abs());
            }
            for t in &tris {
                // Dense barycentric sampling: an upper bound within ~1e-2 of the distance.
                let n = 200;
                for i in 0..=n {
                    for j in 0..=(n - i) {
                        let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
                        let q = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v;
                        want = want.min((p - q).length());
                    }
                }
            }
            let got = clearance(&geometry, p, f32::INFINITY);
            assert!(got <= want + 1e-4, "{p}: {got} above {want}");
            assert!(got >= want - 0.03, "{p}: {got} far below {want}");
            let capped = clearance(&geometry, p, 0.1);
            assert!((capped - got.min(0.1)).abs() < 1e-6, "{p}: cap");
        }
    }
}
