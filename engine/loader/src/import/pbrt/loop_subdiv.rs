//! Loop subdivision of a triangle mesh, as pbrt-v4's `loopsubdiv` shape does it: `levels`
//! rounds of Loop's scheme, then every vertex moved to its limit position.
//!
//! Charles Loop, "Smooth Subdivision Surfaces Based on Triangles", M.S. thesis, University
//! of Utah, 1987; the boundary rules and the limit masks as in pbrt-v4 (`loopsubdiv.cpp`,
//! and *Physically Based Rendering*, 3rd ed., sec. 3.8): an interior vertex of valence `n`
//! moves to `(1 - n b) v + b sum(ring)` with `b = 3/16` for `n = 3`, else `3 / (8 n)`; a
//! boundary vertex to `3/4 v + 1/8 (b0 + b1)` (its two boundary neighbours); a new vertex
//! on an interior edge `(a, b)` with opposite vertices `c`, `d` is
//! `3/8 (a + b) + 1/8 (c + d)`, on a boundary edge `(a + b) / 2`. Limit positions: interior
//! `(1 - n g) v + g sum(ring)` with `g = 1 / (n + 3 / (8 b))`, boundary
//! `3/5 v + 1/5 (b0 + b1)`. Normals are the area-weighted face normals of the limit mesh
//! at each vertex (pbrt computes the limit tangents instead; both converge to the surface
//! normal as the mesh is refined).

use std::collections::HashMap;

use glam::DVec3;

/// The most triangles a subdivision may make (memory is bounded before it is allocated).
pub(super) const MAX_TRIANGLES: usize = 1 << 25;

/// A subdivided mesh.
pub(super) struct Subdivided {
    /// Vertex positions on the limit surface.
    pub positions: Vec<DVec3>,
    /// One normal per vertex.
    pub normals: Vec<DVec3>,
    /// Triangles, wound as the input.
    pub triangles: Vec<[u32; 3]>,
}

/// Edge -> the faces' third vertices (one for a boundary edge, two inside).
fn edges(tris: &[[u32; 3]]) -> Result<HashMap<(u32, u32), Vec<u32>>, String> {
    let mut map: HashMap<(u32, u32), Vec<u32>> = HashMap::with_capacity(tris.len() * 2);
    for t in tris {
        for k in 0..3 {
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let opp = map.entry((a.min(b), a.max(b))).or_default();
            opp.push(c);
            if opp.len() > 2 {
                return Err(format!(
                    "the edge between vertices {a} and {b} is shared by more than two triangles \
                     (Loop subdivision needs a manifold mesh)"
                ));
            }
        }
    }
    Ok(map)
}

/// Per vertex, a list of vertices.
type PerVertex = Vec<Vec<u32>>;

/// Per vertex: its ring (neighbours) and its boundary neighbours.
fn rings(
    n: usize,
    edges: &HashMap<(u32, u32), Vec<u32>>,
) -> Result<(PerVertex, PerVertex), String> {
    let mut ring = vec![Vec::new(); n];
    let mut boundary = vec![Vec::new(); n];
    for (&(a, b), opp) in edges {
        ring[a as usize].push(b);
        ring[b as usize].push(a);
        if opp.len() == 1 {
            boundary[a as usize].push(b);
            boundary[b as usize].push(a);
        }
    }
    if let Some(v) = boundary.iter().position(|b| !b.is_empty() && b.len() != 2) {
        return Err(format!(
            "vertex {v} lies on {} boundary edges (Loop subdivision needs a manifold mesh)",
            boundary[v].len()
        ));
    }
    Ok((ring, boundary))
}

fn beta(n: usize) -> f64 {
    if n == 3 {
        3.0 / 16.0
    } else {
        3.0 / (8.0 * n as f64)
    }
}

/// Subdivides `tris` over `positions` `levels` times and moves the vertices to the limit
/// surface. Unused vertices are kept (they move nowhere).
pub(super) fn loop_subdivide(
    positions: &[DVec3],
    tris: &[[u32; 3]],
    levels: u32,
) -> Result<Subdivided, String> {
    let count = (tris.len() as u128) << (2 * levels.min(40));
    if count > MAX_TRIANGLES as u128 {
        return Err(format!(
            "{levels} levels of subdivision of {} triangles would make {count} triangles, more \
             than {MAX_TRIANGLES}",
            tris.len()
        ));
    }
    let mut p = positions.to_vec();
    let mut t = tris.to_vec();
    for _ in 0..levels {
        let e = edges(&t)?;
        let (ring, boundary) = rings(p.len(), &e)?;
        // Even (old) vertices.
        let mut next: Vec<DVec3> = (0..p.len())
            .map(|v| {
                if boundary[v].len() == 2 {
                    0.75 * p[v] + 0.125 * (p[boundary[v][0] as usize] + p[boundary[v][1] as usize])
                } else if ring[v].is_empty() {
                    p[v]
                } else {
                    let n = ring[v].len();
                    let b = beta(n);
                    let sum: DVec3 = ring[v].iter().map(|&u| p[u as usize]).sum();
                    (1.0 - n as f64 * b) * p[v] + b * sum
                }
            })
            .collect();
        // Odd (edge) vertices.
        let mut edge_vertex: HashMap<(u32, u32), u32> = HashMap::with_capacity(e.len());
        for (&(a, b), opp) in &e {
            let (pa, pb) = (p[a as usize], p[b as usize]);
            let q = if opp.len() == 2 {
                0.375 * (pa + pb) + 0.125 * (p[opp[0] as usize] + p[opp[1] as usize])
            } else {
                0.5 * (pa + pb)
            };
            edge_vertex.insert((a, b), next.len() as u32);
            next.push(q);
        }
        let mid = |a: u32, b: u32| edge_vertex[&(a.min(b), a.max(b))];
        let mut split = Vec::with_capacity(t.len() * 4);
        for &[a, b, c] in &t {
            let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
            split.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        p = next;
        t = split;
    }
    // Limit positions.
    let e = edges(&t)?;
    let (ring, boundary) = rings(p.len(), &e)?;
    let limit: Vec<DVec3> = (0..p.len())
        .map(|v| {
            if boundary[v].len() == 2 {
                0.6 * p[v] + 0.2 * (p[boundary[v][0] as usize] + p[boundary[v][1] as usize])
            } else if ring[v].is_empty() {
                p[v]
            } else {
                let n = ring[v].len();
                let g = 1.0 / (n as f64 + 3.0 / (8.0 * beta(n)));
                let sum: DVec3 = ring[v].iter().map(|&u| p[u as usize]).sum();
                (1.0 - n as f64 * g) * p[v] + g * sum
            }
        })
        .collect();
    let mut normals = vec![DVec3::ZERO; limit.len()];
    for &[a, b, c] in &t {
        let (pa, pb, pc) = (limit[a as usize], limit[b as usize], limit[c as usize]);
        // Twice the area times the unit normal: area weighting for free.
        let n = (pb - pa).cross(pc - pa);
        for v in [a, b, c] {
            normals[v as usize] += n;
        }
    }
    for n in &mut normals {
        *n = n.normalize_or_zero();
    }
    Ok(Subdivided {
        positions: limit,
        normals,
        triangles: t,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetrahedron() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let p = vec![
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(1.0, -1.0, -1.0),
            DVec3::new(-1.0, 1.0, -1.0),
            DVec3::new(-1.0, -1.0, 1.0),
        ];
        // Outward winding.
        let t = vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]];
        (p, t)
    }

    #[test]
    fn level_zero_moves_a_regular_tetrahedron_to_a_fifth_of_its_size() {
        // Valence 3: b = 3/16, g = 1 / (3 + 2) = 1/5; the ring of a vertex v of a regular
        // tetrahedron centred at the origin sums to -v, so the limit is
        // (1 - 3/5) v - v / 5 = v / 5.
        let (p, t) = tetrahedron();
        let s = loop_subdivide(&p, &t, 0).unwrap();
        for (a, b) in s.positions.iter().zip(&p) {
            assert!((*a - *b / 5.0).length() < 1e-12, "{a} vs {b}");
        }
        // Normals point outwards (along the vertex direction, by symmetry).
        for (n, v) in s.normals.iter().zip(&p) {
            assert!((*n - v.normalize()).length() < 1e-12, "{n}");
        }
    }

    #[test]
    fn subdivision_quadruples_triangles_and_keeps_symmetry_and_planes() {
        let (p, t) = tetrahedron();
        let s = loop_subdivide(&p, &t, 2).unwrap();
        assert_eq!(s.triangles.len(), 4 * 16);
        assert_eq!(s.positions.len(), 4 + 6 + 24);
        // The centroid stays at the origin (the scheme is affine and the mesh symmetric).
        let c: DVec3 = s.positions.iter().sum::<DVec3>() / s.positions.len() as f64;
        assert!(c.length() < 1e-12);
        // A flat open square stays in its plane, and its straight boundary edges stay on
        // their lines (boundary masks are 1-D: 1/8 6/8 1/8, then 1/5 3/5 1/5).
        let p = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        let s = loop_subdivide(&p, &[[0, 1, 2], [0, 2, 3]], 3).unwrap();
        assert_eq!(s.triangles.len(), 2 * 64);
        for q in &s.positions {
            assert_eq!(q.z, 0.0);
            assert!(q.x >= -1e-12 && q.x <= 1.0 + 1e-12 && q.y >= -1e-12 && q.y <= 1.0 + 1e-12);
        }
        assert!(s.normals.iter().all(|n| (*n - DVec3::Z).length() < 1e-12));
        // Too many levels is an error, not an allocation.
        assert!(loop_subdivide(&p, &[[0, 1, 2]], 30).is_err());
        // A non-manifold edge is an error.
        assert!(loop_subdivide(&p, &[[0, 1, 2], [0, 1, 3], [1, 0, 2]], 1).is_err());
    }
}
