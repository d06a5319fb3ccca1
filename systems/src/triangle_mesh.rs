//! [`TriangleMesh`]: triangles as shared vertex positions and three indices each, the form a
//! mesh file holds, given to the build as it is ([`TriangleSet`],
//! [`SceneGeometry::build_set_with_instances`]) rather than as one `[Vec3; 3]` per triangle
//! that the build would weld back (issue 36: the triangles stored once, and the weld's hash
//! table and its serial stretch of a large mesh's build saved).
//!
//! [`SceneGeometry::build_set_with_instances`]: crate::geometry::SceneGeometry::build_set_with_instances

use std::collections::HashMap;
use std::hash::Hasher;

use glam::Vec3;

/// FxHash's step (rustc's hasher): a rotate, a xor and a multiply a word; the keys are
/// float bit patterns, and std's SipHash took most of the weld's time.
#[derive(Default)]
struct BitsHasher(u64);

impl Hasher for BitsHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(word));
        }
    }

    #[inline]
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

/// Triangles over shared vertices, in world space: triangle `i` has the vertices
/// `positions[triangles[i][k]]`, wound so `(v1 - v0) x (v2 - v0)` is its front (as a
/// `[Vec3; 3]` triangle given to [`crate::geometry::SceneGeometry::build`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Three indices into `positions` a triangle.
    pub triangles: Vec<[u32; 3]>,
}

impl TriangleMesh {
    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The vertices of triangle `i`.
    ///
    /// # Panics
    /// If `i` is not a triangle or one of its indices is not a vertex.
    #[inline]
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        self.triangles[i].map(|k| self.positions[k as usize])
    }

    /// The triangles of `soup` over their distinct positions: vertices bit for bit equal are
    /// shared (so `0.0` and `-0.0` are not), and every triangle keeps exactly the vertices
    /// it was given.
    ///
    /// # Panics
    /// With `u32::MAX` or more distinct positions (their indices are `u32`).
    pub fn from_soup(soup: &[[Vec3; 3]]) -> Self {
        Self::weld(soup, usize::MAX).expect("no limit on the positions")
    }

    /// [`Self::from_soup`], or `None` as soon as more than `max_positions` distinct
    /// positions are found (where sharing them would save no memory).
    pub(crate) fn weld(soup: &[[Vec3; 3]], max_positions: usize) -> Option<Self> {
        let mut index: HashMap<(u64, u32), u32, std::hash::BuildHasherDefault<BitsHasher>> =
            HashMap::default();
        let mut positions = Vec::new();
        let mut triangles = Vec::with_capacity(soup.len());
        let bits = |v: Vec3| {
            let [x, y, z] = v.to_array().map(f32::to_bits);
            ((u64::from(x) << 32) | u64::from(y), z)
        };
        for t in soup {
            triangles.push(t.map(|v| {
                *index.entry(bits(v)).or_insert_with(|| {
                    positions.push(v);
                    (positions.len() - 1) as u32
                })
            }));
            if positions.len() > max_positions || positions.len() >= u32::MAX as usize {
                return None;
            }
        }
        drop(index);
        positions.shrink_to_fit();
        Some(TriangleMesh {
            positions,
            triangles,
        })
    }

    /// Appends the triangles of `other` after this mesh's (its indices moved past this
    /// mesh's vertices). The first non-empty mesh is moved, not copied.
    ///
    /// # Panics
    /// If the vertices would number `u32::MAX` or more.
    pub fn append(&mut self, other: TriangleMesh) {
        if self.positions.is_empty() && self.triangles.is_empty() {
            *self = other;
            return;
        }
        let base = self.positions.len();
        assert!(
            base + other.positions.len() < u32::MAX as usize,
            "too many vertices: {}",
            base + other.positions.len()
        );
        let base = base as u32;
        self.positions.extend(other.positions);
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|k| k + base)));
    }

    /// Whether every index names a vertex.
    pub fn indices_in_range(&self) -> bool {
        let n = self.positions.len();
        self.triangles.iter().flatten().all(|&k| (k as usize) < n)
    }
}

/// The triangles of a build, gathered shape by shape in primitive order: one `[Vec3; 3]`
/// each (welded by the build, [`crate::geometry::SceneGeometry::build`]) while every shape is such a
/// soup, one [`TriangleMesh`] once a shape is a mesh (the soups before and after it welded
/// into it, each on its own).
#[derive(Clone, Debug)]
pub enum TriangleSet {
    /// One `[Vec3; 3]` a triangle.
    Soup(Vec<[Vec3; 3]>),
    /// Shared vertices.
    Mesh(TriangleMesh),
}

impl Default for TriangleSet {
    fn default() -> Self {
        TriangleSet::Soup(Vec::new())
    }
}

impl TriangleSet {
    /// Number of triangles.
    pub fn len(&self) -> usize {
        match self {
            TriangleSet::Soup(t) => t.len(),
            TriangleSet::Mesh(m) => m.len(),
        }
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Appends the triangles `soup` (the first soup is moved, not copied).
    pub fn push_soup(&mut self, soup: Vec<[Vec3; 3]>) {
        match self {
            TriangleSet::Soup(t) if t.is_empty() => *t = soup,
            TriangleSet::Soup(t) => t.extend(soup),
            TriangleSet::Mesh(m) => m.append(TriangleMesh::from_soup(&soup)),
        }
    }

    /// Appends the triangles of `mesh` (the first mesh is moved, not copied); returns the
    /// number the set gives its first vertex (the set's indices of its triangles are its
    /// own plus that).
    pub fn push_mesh(&mut self, mesh: TriangleMesh) -> u32 {
        if let TriangleSet::Soup(soup) = self {
            *self = TriangleSet::Mesh(TriangleMesh::from_soup(soup));
        }
        match self {
            TriangleSet::Mesh(m) => {
                let base = m.positions.len() as u32;
                m.append(mesh);
                base
            }
            TriangleSet::Soup(_) => unreachable!("made a mesh above"),
        }
    }

    /// The vertices of triangle `i`.
    ///
    /// # Panics
    /// If `i` is not a triangle (or, of a mesh, one of its indices is not a vertex).
    #[inline]
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        match self {
            TriangleSet::Soup(t) => t[i],
            TriangleSet::Mesh(m) => m.triangle(i),
        }
    }

    /// Calls `f` with each triangle's vertices, in order.
    pub fn for_each(&self, mut f: impl FnMut([Vec3; 3])) {
        (0..self.len()).for_each(|i| f(self.triangle(i)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A soup welds to its distinct positions and reads back bit for bit; appending moves
    /// the second mesh's indices past the first's vertices.
    #[test]
    fn soups_weld_and_meshes_append() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let d = Vec3::new(1.0, 1.0, f32::EPSILON);
        let soup = [[a, b, c], [c, b, d]];
        let mesh = TriangleMesh::from_soup(&soup);
        assert_eq!(mesh.positions.len(), 4);
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [2, 1, 3]]);
        for (i, t) in soup.iter().enumerate() {
            assert_eq!(mesh.triangle(i), *t);
        }
        let mut joined = TriangleMesh::default();
        joined.append(mesh.clone());
        assert_eq!(joined, mesh);
        joined.append(TriangleMesh::from_soup(&[[d, c, a]]));
        assert_eq!(joined.positions.len(), 7);
        assert_eq!(joined.triangles[2], [4, 5, 6]);
        assert_eq!(joined.triangle(2), [d, c, a]);
        assert!(joined.indices_in_range());
        joined.triangles.push([0, 1, 7]);
        assert!(!joined.indices_in_range());
        // A set stays a soup until a mesh comes, then keeps every triangle in order.
        let mut set = TriangleSet::default();
        set.push_soup(vec![[a, b, c]]);
        assert!(matches!(set, TriangleSet::Soup(ref t) if t.len() == 1));
        set.push_mesh(TriangleMesh::from_soup(&[[c, b, d]]));
        set.push_soup(vec![[d, c, a]]);
        let mut all = Vec::new();
        set.for_each(|t| all.push(t));
        assert_eq!(all, vec![[a, b, c], [c, b, d], [d, c, a]]);
    }
}
