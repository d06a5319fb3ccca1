//! The BVH build's primitives: what the build reads of them ([`PrimBoxes`], a box by
//! primitive index) and the set the geometry hands it ([`BuildPrims`]): the triangles over
//! shared vertices, then the boxes of the spheres and instances.
//!
//! A mesh reaches the build indexed ([`TriangleMesh`]: 12 bytes a corner index and 12 a
//! position, about 18 bytes a triangle on a closed mesh, half as many vertices as
//! triangles), as its file held it; triangles given one `[Vec3; 3]` each (36 bytes) are
//! welded by bit-equal position into that form, or kept as given where that saves nothing.
//! The build's peak comes on top of whatever is alive at that point (issue 36). A triangle
//! read back ([`BuildPrims::triangle`]) has exactly the vertices it was given: welding only
//! merges bit-equal positions.

use glam::{Vec3, Vec3A};
use obvhs::{aabb::Aabb, Boundable};

use crate::triangle_mesh::{TriangleMesh, TriangleSet};

/// Primitive boxes by index, as the binary BVH builds read them (`0..count()`).
pub(crate) trait PrimBoxes {
    /// Number of primitives.
    fn count(&self) -> usize;
    /// The box of primitive `i`.
    fn aabb(&self, i: usize) -> Aabb;
}

impl<B: Boundable> PrimBoxes for [B] {
    fn count(&self) -> usize {
        self.len()
    }

    #[inline]
    fn aabb(&self, i: usize) -> Aabb {
        self[i].aabb()
    }
}

impl<B: Boundable> PrimBoxes for Vec<B> {
    fn count(&self) -> usize {
        self.len()
    }

    #[inline]
    fn aabb(&self, i: usize) -> Aabb {
        self[i].aabb()
    }
}

/// The build's primitives: triangles `0..num_triangles()`, then boxes `(min, max)` (the
/// spheres' and instances' padded boxes).
#[derive(Debug)]
pub(crate) struct BuildPrims {
    /// A mesh; a soup only where welding it would not save memory (its vertices hardly
    /// shared: more than two distinct positions a triangle).
    triangles: TriangleSet,
    boxes: Vec<(Vec3, Vec3)>,
}

impl BuildPrims {
    /// The triangles welded by bit-equal positions (or kept as given when that saves
    /// nothing), then `boxes`.
    pub(crate) fn new(triangles: Vec<[Vec3; 3]>, boxes: Vec<(Vec3, Vec3)>) -> Self {
        // Two distinct positions a triangle: the welded form (12 + 24 bytes) no smaller.
        let triangles = match TriangleMesh::weld(&triangles, 2 * triangles.len()) {
            Some(mesh) => TriangleSet::Mesh(mesh),
            None => TriangleSet::Soup(triangles),
        };
        BuildPrims { triangles, boxes }
    }

    /// The triangles of `mesh` over its vertices as given (no weld: a mesh file's vertices
    /// are shared already), then `boxes`.
    pub(crate) fn from_mesh(mesh: TriangleMesh, boxes: Vec<(Vec3, Vec3)>) -> Self {
        BuildPrims {
            triangles: TriangleSet::Mesh(mesh),
            boxes,
        }
    }

    /// The triangles' vertex indices, the positions freed (empty for a soup kept as given).
    pub(crate) fn into_corners(self) -> Vec<[u32; 3]> {
        match self.triangles {
            TriangleSet::Mesh(mesh) => mesh.triangles,
            TriangleSet::Soup(_) => Vec::new(),
        }
    }

    /// Number of triangles (primitives `0..num_triangles()`).
    pub(crate) fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// The vertices of triangle `i`, exactly as given.
    #[inline]
    pub(crate) fn triangle(&self, i: usize) -> [Vec3; 3] {
        self.triangles.triangle(i)
    }
}

impl PrimBoxes for BuildPrims {
    fn count(&self) -> usize {
        self.num_triangles() + self.boxes.len()
    }

    /// A triangle's exact box (min/max of its vertices), or the box given.
    #[inline]
    fn aabb(&self, i: usize) -> Aabb {
        let tris = self.num_triangles();
        let (lo, hi) = if i < tris {
            let t = self.triangle(i);
            (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]))
        } else {
            self.boxes[i - tris]
        };
        Aabb::new(Vec3A::from(lo), Vec3A::from(hi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Welding keeps every vertex bit for bit (signed zeros apart), shares bit-equal ones,
    /// and a soup of unshared triangles is kept as given.
    #[test]
    fn welding_keeps_every_vertex() {
        let a = Vec3::new(0.0, 0.0, 0.0);
        let b = Vec3::new(-0.0, 0.0, 0.0);
        let c = Vec3::new(1.0, 2.0, 3.0);
        let d = Vec3::new(1.0, 2.0, 3.0 + f32::EPSILON * 4.0);
        let tris = vec![[a, c, d], [b, c, d], [a, d, c], [c, a, b]];
        let p = BuildPrims::new(tris.clone(), vec![(Vec3::splat(-1.0), Vec3::ONE)]);
        assert!(matches!(p.triangles, TriangleSet::Mesh(ref m) if m.positions.len() == 4));
        for (i, t) in tris.iter().enumerate() {
            let got = p.triangle(i).map(|v| v.to_array().map(f32::to_bits));
            assert_eq!(got, t.map(|v| v.to_array().map(f32::to_bits)));
        }
        assert_eq!(p.count(), 5);
        let last = p.aabb(4);
        assert_eq!(
            (Vec3::from(last.min), Vec3::from(last.max)),
            (Vec3::splat(-1.0), Vec3::ONE)
        );
        let first = p.aabb(0);
        assert_eq!((Vec3::from(first.min), Vec3::from(first.max)), (a, d));

        let soup: Vec<[Vec3; 3]> = (0..10)
            .map(|i| [0.0, 1.0, 2.0].map(|k| Vec3::splat(3.0 * i as f32 + k)))
            .collect();
        let p = BuildPrims::new(soup.clone(), Vec::new());
        assert!(matches!(p.triangles, TriangleSet::Soup(_)));
        assert_eq!((0..10).map(|i| p.triangle(i)).collect::<Vec<_>>(), soup);
    }
}
