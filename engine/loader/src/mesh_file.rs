//! Mesh files: OBJ ([`obj`]) and PLY ([`ply`]) read into one indexed form, [`MeshData`],
//! with the per-vertex normals and texture coordinates they carry.
//!
//! Errors are complete sentences naming the full path and, where the format has them, the
//! line (OBJ) or element (PLY) and the offending value; the scene loader locates them at
//! the shape's `path`.

pub mod obj;
pub mod ply;

use std::path::Path;

use glam::{DVec3, Vec2};
use rayon::slice::ParallelSliceMut;

/// An indexed triangle mesh in its file's (object) space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// Vertex positions (finite).
    pub positions: Vec<DVec3>,
    /// One normal per vertex (finite; not necessarily unit), or empty.
    pub normals: Vec<DVec3>,
    /// One texture coordinate pair per vertex, or empty.
    pub uvs: Vec<Vec2>,
    /// Vertex indices of each triangle (every index below `positions.len()`), polygons
    /// fan-triangulated; the geometric normal is along `(v1 - v0) x (v2 - v0)`.
    pub triangles: Vec<[u32; 3]>,
    /// Elements of the file that are not surfaces and were skipped: OBJ points (`p`) and
    /// lines (`l`), counted.
    pub skipped: Skipped,
}

/// Counts of a mesh file's elements that are not surfaces (skipped, with a warning).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Skipped {
    /// OBJ `p` statements.
    pub points: usize,
    /// OBJ `l` statements.
    pub lines: usize,
}

impl MeshData {
    /// Whether the mesh is closed: once vertices at the same place are merged (files repeat
    /// a vertex along texture seams and at poles, with coordinates that differ in the last
    /// digits; positions are compared on a grid of `1e-6` of the mesh's extent), every edge
    /// is shared by exactly two triangles that run along it in opposite directions.
    /// Degenerate triangles (two corners merged) are skipped. An empty mesh is not closed.
    /// What the shadow-terminator offset needs (`risotto_systems::terminator`): a ray
    /// leaving a closed mesh's smooth surface towards a light behind it is stopped by the
    /// mesh; past the border of an open one it is not.
    pub fn is_closed(&self) -> bool {
        let Some(&first) = self.positions.first() else {
            return false;
        };
        let ids = self.welded_ids(first);
        // Closed and consistently wound iff every undirected edge is there exactly twice,
        // once in each direction. The directed edges are grouped by their smaller welded
        // vertex (a counting sort: two passes over the triangles, 4 bytes an edge), and
        // each vertex's few keys `(larger vertex, direction)` are sorted and paired (issue
        // 36: sorting all the 64-bit keys at once was a fifth of a 2M-triangle PLY's load,
        // and hashing them 2.4 s and about 200 MB of tables before that).
        let welded = ids.iter().max().map_or(0, |&m| u64::from(m) + 1);
        if welded > 1 << 31 {
            return self.is_closed_wide(&ids);
        }
        pairs_up_by_vertex(&self.triangles, &ids, welded as usize)
    }

    /// The welded vertex of each position (see [`Self::is_closed`]): positions in the same
    /// cell of the grid of `1e-6` of the extent get the same id, by sorting the cells.
    fn welded_ids(&self, first: DVec3) -> Vec<u32> {
        let (lo, hi) = self
            .positions
            .iter()
            .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let cell = ((hi - lo).max_element() * 1e-6).max(f64::MIN_POSITIVE);
        let mut cells: Vec<([i64; 3], u32)> = self
            .positions
            .iter()
            .enumerate()
            .map(|(i, &p)| {
                let q = ((p - lo) / cell).round();
                ([q.x as i64, q.y as i64, q.z as i64], i as u32)
            })
            .collect();
        // On rayon's threads: with the edge sort below, a third of a 2M-triangle PLY's
        // load was these two sorts on one thread (issue 36).
        cells.par_sort_unstable();
        let mut ids = vec![0u32; self.positions.len()];
        let mut id = 0u32;
        for (k, &(c, i)) in cells.iter().enumerate() {
            if k > 0 && cells[k - 1].0 != c {
                id += 1;
            }
            ids[i as usize] = id;
        }
        ids
    }

    /// [`Self::is_closed`]'s edge test with 128-bit keys, for meshes of more than 2^31
    /// welded vertices (whose two ids and a bit do not fit 64 bits).
    fn is_closed_wide(&self, ids: &[u32]) -> bool {
        let mut edges = self.edge_keys(ids, |a, b| {
            (u128::from(a.min(b)) << 64) | (u128::from(a.max(b)) << 1) | u128::from(a > b)
        });
        !edges.is_empty() && pairs_up(&mut edges)
    }
}

impl MeshData {
    /// `key(a, b)` of each directed edge `(a, b)` of the welded vertices `ids`, three a
    /// triangle, degenerate triangles skipped.
    fn edge_keys<K>(&self, ids: &[u32], key: impl Fn(u32, u32) -> K) -> Vec<K> {
        let mut edges = Vec::with_capacity(3 * self.triangles.len());
        for t in &self.triangles {
            let v = t.map(|i| ids[i as usize]);
            if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
                continue;
            }
            for k in 0..3 {
                edges.push(key(v[k], v[(k + 1) % 3]));
            }
        }
        edges
    }
}

/// [`MeshData::is_closed`] on triangles of welded vertices `ids` (fewer than `welded` <=
/// 2^31 of them): the directed edges `(a, b)` bucketed by `min(a, b)`, each bucket's keys
/// `(max(a, b) << 1) | (a > b)` paired as in [`pairs_up`]. Degenerate triangles are
/// skipped; no edges at all is not closed.
fn pairs_up_by_vertex(triangles: &[[u32; 3]], ids: &[u32], welded: usize) -> bool {
    let edges = |t: &[u32; 3]| {
        let v = t.map(|i| ids[i as usize]);
        let degenerate = v[0] == v[1] || v[1] == v[2] || v[0] == v[2];
        (!degenerate).then(|| [(v[0], v[1]), (v[1], v[2]), (v[2], v[0])])
    };
    // `end[v + 1]` first counts bucket `v`'s keys; after the prefix sums `end[v]` is where
    // bucket `v` starts, and after the scatter where it ends.
    let mut end = vec![0usize; welded + 1];
    for e in triangles.iter().filter_map(edges) {
        for (a, b) in e {
            end[a.min(b) as usize + 1] += 1;
        }
    }
    for v in 1..=welded {
        end[v] += end[v - 1];
    }
    let total = end[welded];
    if total == 0 || !total.is_multiple_of(2) {
        return false;
    }
    let mut keys = vec![0u32; total];
    for e in triangles.iter().filter_map(edges) {
        for (a, b) in e {
            let slot = &mut end[a.min(b) as usize];
            keys[*slot] = (a.max(b) << 1) | u32::from(a > b);
            *slot += 1;
        }
    }
    let mut begin = 0;
    end[..welded].iter().all(|&stop| {
        let bucket = &mut keys[begin..stop];
        begin = stop;
        pairs_up(bucket)
    })
}

/// Whether the edge keys (undirected edge above bit 0, direction in bit 0), once sorted,
/// come in pairs of one edge in both directions: `(k, k | 1)` with `k`'s bit 0 clear. A
/// third key of an edge, or a lone one, breaks the pairing.
fn pairs_up<K>(edges: &mut [K]) -> bool
where
    K: Ord + Copy + std::ops::BitAnd<Output = K> + std::ops::BitOr<Output = K> + From<u8>,
{
    edges.sort_unstable();
    let (zero, one) = (K::from(0), K::from(1));
    edges.len().is_multiple_of(2)
        && edges
            .chunks_exact(2)
            .all(|p| p[0] & one == zero && p[1] == p[0] | one)
}

/// Reads an OBJ or PLY file, chosen by its extension (`.ply`, any case, is PLY; anything
/// else is read as OBJ). The error is a complete sentence naming the full path.
pub fn load_mesh(path: &Path) -> Result<MeshData, String> {
    let is_ply = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    if is_ply {
        ply::load_ply(path)
    } else {
        obj::load_obj(path)
    }
}

/// Checks that a mesh file's normals are finite (`what` names the file for the message):
/// a NaN normal would otherwise become a NaN shading frame at every hit near it.
pub(crate) fn check_normals(normals: &[DVec3], what: &str) -> Result<(), String> {
    match normals.iter().position(|n| !n.is_finite()) {
        None => Ok(()),
        Some(i) => Err(format!(
            "{what}: normal {} is not finite ({}, {}, {})",
            i + 1,
            normals[i].x,
            normals[i].y,
            normals[i].z
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tetrahedron is closed, also with a vertex repeated a rounding error away (as at a
    /// texture seam); without a face, or with a face wound the wrong way, it is not.
    #[test]
    fn closed_meshes_are_recognised() {
        let p = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
        ];
        let faces = vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
        let mesh = |positions: Vec<DVec3>, triangles: Vec<[u32; 3]>| MeshData {
            positions,
            triangles,
            ..Default::default()
        };
        assert!(mesh(p.to_vec(), faces.clone()).is_closed());
        // Vertex 4 repeats vertex 3 within 1e-9: the seam is welded.
        let mut seam = p.to_vec();
        seam.push(p[3] + DVec3::splat(1e-9));
        let mut seamed = faces.clone();
        seamed[2] = [1, 2, 4];
        assert!(mesh(seam, seamed).is_closed());
        assert!(!mesh(p.to_vec(), faces[..3].to_vec()).is_closed());
        let mut flipped = faces.clone();
        flipped[1] = [0, 3, 1];
        assert!(!mesh(p.to_vec(), flipped.clone()).is_closed());
        assert!(!MeshData::default().is_closed());
        // A face listed twice: its edges run three times.
        let mut doubled = faces.clone();
        doubled.push(faces[0]);
        assert!(!mesh(p.to_vec(), doubled).is_closed());
        // Only degenerate triangles: nothing to be closed.
        assert!(!mesh(p.to_vec(), vec![[0, 0, 1], [2, 3, 3]]).is_closed());
        // The 128-bit keys of more than 2^31 welded vertices decide the same way.
        for (tris, closed) in [(faces.clone(), true), (flipped.clone(), false)] {
            let m = mesh(p.to_vec(), tris);
            assert_eq!(m.is_closed_wide(&m.welded_ids(p[0])), closed);
        }
    }
}
