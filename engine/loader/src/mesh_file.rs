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
