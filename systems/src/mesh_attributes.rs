//! Per-vertex shading normals and texture coordinates of meshes, and the shading frame they
//! give at a hit.
//!
//! Layout (compact, as issue 36 asks): per-vertex arrays (`normals`, `uvs`) and per-triangle
//! vertex indices (`corners`), only for the meshes that have attributes. Each such mesh is
//! one attribute range over its contiguous primitive indices; a scene without attributes
//! stores nothing and never looks here (the engine checks [`MeshAttributes::is_empty`]).

use glam::{Vec2, Vec3};

/// The attributes of one mesh as a loader produces them (world space).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VertexAttributes {
    /// Unit shading normal per vertex (world space, transformed by the inverse transpose), or
    /// empty when the mesh has none (it is then shaded flat).
    pub normals: Vec<Vec3>,
    /// Texture coordinates per vertex, or empty when the mesh has none (hits then report the
    /// barycentrics, as meshes without attributes do).
    pub uvs: Vec<Vec2>,
    /// The vertex indices of each triangle into `normals` / `uvs`, in the order of the
    /// mesh's triangles (corner `k` of a triangle is its vertex `v_k`).
    pub corners: Vec<[u32; 3]>,
    /// Whether rays leaving the mesh towards the viewer's side start from the smooth surface
    /// its normals imply rather than from the flat triangle ([`crate::terminator`]): the
    /// shadow-terminator fix. Only meshes with normals use it, and it is meant for closed
    /// meshes only (past the border of an open one, a ray from the smooth surface can see
    /// light from behind; the scene loader sets it only for closed meshes). Defaults to
    /// `false` here; the scene file's `shadow_terminator_offset` defaults to `true`.
    pub shadow_terminator_offset: bool,
}

/// `to` followed by `from`: `from` itself when `to` is empty.
fn append<T>(to: &mut Vec<T>, from: Vec<T>) {
    if to.is_empty() {
        *to = from;
    } else {
        to.extend(from);
    }
}

impl VertexAttributes {
    /// Whether the mesh has neither normals nor texture coordinates (nothing to store).
    pub fn is_empty(&self) -> bool {
        self.normals.is_empty() && self.uvs.is_empty()
    }
}

/// Which primitives one mesh's attributes belong to, and where they start.
#[derive(Clone, Copy, Debug, PartialEq)]
struct AttributeRange {
    /// First primitive index of the mesh.
    first: u32,
    /// One past its last primitive index.
    end: u32,
    /// Offset of the mesh's first triangle in `corners`.
    corners: u32,
    /// Offset of its first normal in `normals`, `NONE` without normals.
    normals: u32,
    /// Offset of its first uv in `uvs`, `NONE` without uvs.
    uvs: u32,
    /// [`VertexAttributes::shadow_terminator_offset`], for a mesh with normals.
    terminator: bool,
}

const NONE: u32 = u32::MAX;

/// The attributes of every mesh of a compiled scene that has some.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshAttributes {
    /// Sorted by `first`, disjoint.
    ranges: Vec<AttributeRange>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    corners: Vec<[u32; 3]>,
}

/// What the attributes give at a hit on a triangle of an attributed mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshShading {
    /// The interpolated, normalised shading normal, on the side of `ng` (`ng` itself when
    /// the mesh has no normals or the interpolation degenerates).
    pub nn: Vec3,
    /// Interpolated texture coordinates, `None` when the mesh has none.
    pub uv: Option<Vec2>,
    /// Unit tangent orthogonal to `nn`: `dp/du` of the uv parameterisation made orthogonal
    /// to `nn` when the mesh has uvs (and they are not degenerate on this triangle), else
    /// [`arbitrary_tangent`] of `nn`.
    pub tangent: Vec3,
}

/// A tangent of the unit normal `n` that varies continuously with `n` (except across
/// `n.z = 0` with `n.z` changing sign): glam's `any_orthonormal_vector`, the first axis of
/// Duff et al. 2017's branchless frame (the same construction as
/// [`crate::bxdf::Frame::from_normal`]; also what
/// `risotto_components::ShadingPointRow::in_volume` uses). What points without a
/// parameterisation use.
#[inline]
pub fn arbitrary_tangent(n: Vec3) -> Vec3 {
    n.any_orthonormal_vector()
}

/// The tangent of a sphere at outward unit normal `n`: the direction of increasing `phi`
/// (azimuth from `+x` towards `+y`), `(-n.y, n.x, 0)` normalised; at the poles, where it is
/// undefined, [`arbitrary_tangent`].
#[inline]
pub fn sphere_tangent(n: Vec3) -> Vec3 {
    let t = Vec3::new(-n.y, n.x, 0.0);
    let len2 = t.length_squared();
    if len2 > 1e-12 {
        t / len2.sqrt()
    } else {
        arbitrary_tangent(n)
    }
}

impl MeshAttributes {
    /// No mesh has attributes.
    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    /// Adds the attributes of the mesh whose triangles are the primitives `first..first +
    /// attrs.corners.len()` (call in increasing `first`, ranges disjoint). A mesh without
    /// attributes ([`VertexAttributes::is_empty`]) adds nothing.
    ///
    /// # Panics
    /// When the ranges are out of order or overlap, a corner indexes past the mesh's
    /// normals or uvs, or the sizes overflow `u32` (loaders check their input first).
    pub fn push(&mut self, first: u32, attrs: VertexAttributes) {
        if attrs.is_empty() {
            return;
        }
        let end = first
            .checked_add(u32::try_from(attrs.corners.len()).expect("too many triangles"))
            .expect("too many triangles");
        assert!(
            self.ranges.last().is_none_or(|r| r.end <= first),
            "attribute ranges must be pushed in order"
        );
        let max = attrs.corners.iter().flatten().copied().max().unwrap_or(0) as usize;
        let offset = |len: usize, have: usize| -> u32 {
            if have == 0 {
                NONE
            } else {
                assert!(max < have, "a corner indexes past the mesh's attributes");
                u32::try_from(len).expect("too many attributes")
            }
        };
        let range = AttributeRange {
            first,
            end,
            corners: u32::try_from(self.corners.len()).expect("too many triangles"),
            normals: offset(self.normals.len(), attrs.normals.len()),
            uvs: offset(self.uvs.len(), attrs.uvs.len()),
            terminator: attrs.shadow_terminator_offset && !attrs.normals.is_empty(),
        };
        self.ranges.push(range);
        // The first mesh's arrays are moved, not copied: a large mesh's corners would
        // otherwise be held twice for a moment (issue 36, peak memory).
        append(&mut self.normals, attrs.normals);
        append(&mut self.uvs, attrs.uvs);
        append(&mut self.corners, attrs.corners);
    }

    /// One past the last primitive with attributes (0 when empty).
    pub fn max_prim_end(&self) -> usize {
        self.ranges.last().map_or(0, |r| r.end as usize)
    }

    /// Bytes held: 12 per triangle for the corners, 12 per vertex for normals and 8 for uvs.
    pub fn bytes(&self) -> usize {
        self.ranges.len() * size_of::<AttributeRange>()
            + self.normals.len() * size_of::<Vec3>()
            + self.uvs.len() * size_of::<Vec2>()
            + self.corners.len() * size_of::<[u32; 3]>()
    }

    /// Whether some mesh has vertex normals.
    pub fn any_normals(&self) -> bool {
        self.ranges.iter().any(|r| r.normals != NONE)
    }

    /// Whether primitive `prim` belongs to a mesh with vertex normals.
    pub fn has_normals(&self, prim: u32) -> bool {
        self.range_of(prim).is_some_and(|r| r.normals != NONE)
    }

    /// Whether some mesh with vertex normals asks for the shadow-terminator offset.
    pub fn any_terminator_offset(&self) -> bool {
        self.ranges.iter().any(|r| r.terminator)
    }

    /// The stored vertex normals of triangle `prim` (corners in the triangle's vertex
    /// order, as the file gave them: unit or zero, not turned to any side) when its mesh
    /// has normals and asks for the shadow-terminator offset; `None` otherwise.
    #[inline]
    pub fn terminator_normals(&self, prim: u32) -> Option<[Vec3; 3]> {
        let r = self.range_of(prim).filter(|r| r.terminator)?;
        let c = self.corners[(r.corners + (prim - r.first)) as usize];
        Some(c.map(|k| self.normals[(r.normals + k) as usize]))
    }

    #[inline]
    fn range_of(&self, prim: u32) -> Option<&AttributeRange> {
        // Usually one or a few meshes: a binary search over their first primitives.
        let i = self.ranges.partition_point(|r| r.first <= prim);
        let r = self.ranges.get(i.checked_sub(1)?)?;
        (prim < r.end).then_some(r)
    }

    /// The shading normal, texture coordinates and tangent at the hit `(b1, b2)` (the
    /// barycentrics of `v1` and `v2`) on triangle `prim` with vertices `v` and unit geometric
    /// normal `ng`; `None` when the triangle's mesh has no attributes.
    ///
    /// The normal is `normalize(b0 n0 + b1 n1 + b2 n2)` flipped to the side of `ng` (a file
    /// whose normals point against its winding still shades the side the winding says). The
    /// tangent is pbrt-v4's `dpdu` of the triangle (sec. 6.5.3: solve `p_i - p_2 = (u_i -
    /// u_2) dpdu + (v_i - v_2) dpdv` for `i = 0, 1`), made orthogonal to `nn` by one
    /// Gram-Schmidt step.
    #[inline]
    pub fn shading(
        &self,
        prim: u32,
        b1: f32,
        b2: f32,
        v: [Vec3; 3],
        ng: Vec3,
    ) -> Option<MeshShading> {
        self.shading_mapped(prim, b1, b2, v, ng, |n| n)
    }

    /// [`Self::shading`] of a mesh stored in another space than the hit's (an instance's
    /// object space): `v` and `ng` are in the hit's space, and `map_normal` maps the
    /// interpolated stored normal there before it is normalised (for an instance, the
    /// inverse transpose of its map). The tangent is then `dpdu` of the mapped vertices,
    /// which is the mapped `dpdu` (it is linear in the vertices), made orthogonal to the
    /// mapped normal.
    #[inline(always)]
    pub fn shading_mapped(
        &self,
        prim: u32,
        b1: f32,
        b2: f32,
        v: [Vec3; 3],
        ng: Vec3,
        map_normal: impl Fn(Vec3) -> Vec3,
    ) -> Option<MeshShading> {
        let r = self.range_of(prim)?;
        let c = self.corners[(r.corners + (prim - r.first)) as usize];
        let b0 = 1.0 - b1 - b2;
        let nn = if r.normals == NONE {
            ng
        } else {
            let n = |k: usize| self.normals[(r.normals + c[k]) as usize];
            let n = map_normal(n(0) * b0 + n(1) * b1 + n(2) * b2);
            let len2 = n.length_squared();
            if len2 > 1e-20 && len2.is_finite() {
                let n = n / len2.sqrt();
                if n.dot(ng) < 0.0 {
                    -n
                } else {
                    n
                }
            } else {
                ng
            }
        };
        let (uv, tangent) = if r.uvs == NONE {
            (None, arbitrary_tangent(nn))
        } else {
            let t = |k: usize| self.uvs[(r.uvs + c[k]) as usize];
            let (t0, t1, t2) = (t(0), t(1), t(2));
            let uv = t0 * b0 + t1 * b1 + t2 * b2;
            let (duv02, duv12) = (t0 - t2, t1 - t2);
            let (dp02, dp12) = (v[0] - v[2], v[1] - v[2]);
            let det = duv02.x * duv12.y - duv02.y * duv12.x;
            let dpdu = (dp02 * duv12.y - dp12 * duv02.y) / det;
            let ortho = dpdu - nn * nn.dot(dpdu);
            let len2 = ortho.length_squared();
            let tangent = if det != 0.0 && len2 > 1e-20 * dpdu.length_squared() && len2.is_finite()
            {
                ortho / len2.sqrt()
            } else {
                arbitrary_tangent(nn)
            };
            (Some(uv), tangent)
        };
        Some(MeshShading { nn, uv, tangent })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad_attrs() -> VertexAttributes {
        // Two triangles of the unit square in z = 0, uv = (x, y), normals tilted.
        VertexAttributes {
            normals: vec![
                Vec3::new(-0.6, 0.0, 0.8),
                Vec3::new(0.6, 0.0, 0.8),
                Vec3::new(0.6, 0.0, 0.8),
                Vec3::new(-0.6, 0.0, 0.8),
            ],
            uvs: vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(1.0, 1.0),
                Vec2::new(0.0, 1.0),
            ],
            corners: vec![[0, 1, 2], [0, 2, 3]],
            shadow_terminator_offset: false,
        }
    }

    const P: [Vec3; 4] = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];

    #[test]
    fn interpolates_normals_uvs_and_tangents() {
        let mut a = MeshAttributes::default();
        a.push(5, quad_attrs());
        assert!(a
            .shading(4, 0.2, 0.2, [P[0], P[1], P[2]], Vec3::Z)
            .is_none());
        assert!(a
            .shading(7, 0.2, 0.2, [P[0], P[1], P[2]], Vec3::Z)
            .is_none());
        // The centre of the square's second triangle [0, 2, 3] at b = (1/3, 1/3, 1/3).
        let third = 1.0 / 3.0;
        let s = a
            .shading(6, third, third, [P[0], P[2], P[3]], Vec3::Z)
            .unwrap();
        let want_uv = (P[0] + P[2] + P[3]).truncate() / 3.0;
        assert!((s.uv.unwrap() - want_uv).length() < 1e-6, "{s:?}");
        let n = (Vec3::new(-0.6, 0.0, 0.8) * 2.0 + Vec3::new(0.6, 0.0, 0.8)).normalize();
        assert!((s.nn - n).length() < 1e-6, "{s:?}");
        // uv = (x, y): dp/du = +x, made orthogonal to the tilted normal.
        let t = (Vec3::X - n * n.x).normalize();
        assert!((s.tangent - t).length() < 1e-5, "{s:?}");
        assert!(s.tangent.dot(s.nn).abs() < 1e-6);
    }

    #[test]
    fn normals_against_the_winding_are_flipped_to_ng() {
        let mut attrs = quad_attrs();
        for n in &mut attrs.normals {
            *n = -*n;
        }
        let mut a = MeshAttributes::default();
        a.push(0, attrs);
        let s = a.shading(0, 0.0, 0.0, [P[0], P[1], P[2]], Vec3::Z).unwrap();
        assert!((s.nn - Vec3::new(-0.6, 0.0, 0.8)).length() < 1e-6, "{s:?}");
    }

    #[test]
    fn without_uvs_the_tangent_is_an_orthogonal_unit_vector() {
        let mut attrs = quad_attrs();
        attrs.uvs.clear();
        let mut a = MeshAttributes::default();
        a.push(0, attrs);
        let s = a.shading(1, 0.3, 0.3, [P[0], P[2], P[3]], Vec3::Z).unwrap();
        assert_eq!(s.uv, None);
        assert!((s.tangent.length() - 1.0).abs() < 1e-6 && s.tangent.dot(s.nn).abs() < 1e-6);
        // Degenerate uvs fall back the same way.
        let mut attrs = quad_attrs();
        attrs.uvs = vec![Vec2::ZERO; 4];
        let mut a = MeshAttributes::default();
        a.push(0, attrs);
        let s = a.shading(0, 0.3, 0.3, [P[0], P[1], P[2]], Vec3::Z).unwrap();
        assert!((s.tangent.length() - 1.0).abs() < 1e-6 && s.tangent.dot(s.nn).abs() < 1e-6);
    }

    #[test]
    fn sphere_tangent_points_along_phi() {
        let n = Vec3::new(1.0, 0.0, 0.0);
        assert!((sphere_tangent(n) - Vec3::Y).length() < 1e-6);
        let pole = sphere_tangent(Vec3::Z);
        assert!((pole.length() - 1.0).abs() < 1e-6 && pole.z.abs() < 1e-6);
    }
}
