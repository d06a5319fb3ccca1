//! Transforms and shape geometry: transform lists, quads, rectangles, boxes and OBJ meshes
//! resolved to world-space triangles
//! (with a mesh's vertex normals and texture coordinates).

use glam::{DAffine3, DMat3, DVec3, Vec2, Vec3};

use super::params::Reader;
use super::raw::{Node, Value};
use crate::mesh_file::load_mesh;
use risotto_engine::diagnostics::{SceneError, SceneErrorKind};
use risotto_engine::scene::TriangleMesh;
use risotto_systems::mesh_attributes::VertexAttributes;

/// A triangle `[v0, v1, v2]`; its geometric normal is along `(v1 - v0) x (v2 - v0)`.
pub(crate) type Triangle = [Vec3; 3];

/// Reads the optional `transform` key of an entity: a list of steps applied in order,
/// `p_world = T_n ... T_2 T_1 p_local` (Mitsuba's `to_world`). Absent = identity.
/// Singular (non-invertible) results are rejected.
pub(crate) fn read_transform(r: &Reader<'_>) -> Result<DAffine3, SceneError> {
    let Some(node) = r.get("transform") else {
        return Ok(DAffine3::IDENTITY);
    };
    let Value::Array(steps) = &node.value else {
        return Err(r.wrong_type(
            "transform",
            node,
            "an array of steps such as [{ scale = 2 }, { translate = [0, 1, 0] }]",
        ));
    };
    let mut m = DAffine3::IDENTITY;
    for (i, step) in steps.iter().enumerate() {
        let entity = format!("{} transform[{i}]", r.entity);
        let s = Reader::new(r.src, step, &entity);
        m = read_step(&s, step)? * m;
    }
    // Singular is a matter of shape, not size: the determinant relative to the cube of the
    // longest axis (1 for any uniform scale, whatever its size; ~0 when some axis collapses
    // or lies in the plane of the others).
    let det = m.matrix3.determinant();
    let a = &m.matrix3;
    let longest = a
        .x_axis
        .length()
        .max(a.y_axis.length())
        .max(a.z_axis.length());
    let relative = det.abs() / (longest * longest * longest);
    if !det.is_finite() || det == 0.0 || relative.is_nan() || relative < 1e-12 {
        return Err(r.error(
            SceneErrorKind::InvalidValue,
            &node.span(),
            Some("transform"),
            format!(
                "the transform is singular (determinant {det:.3e}, {relative:.3e} relative to \
                 its longest axis cubed); it must be invertible"
            ),
        ));
    }
    Ok(m)
}

const STEP_KINDS: &[&str] = &["scale", "rotate", "translate", "matrix", "look_at"];

/// One transform step: a table with exactly one of [`STEP_KINDS`].
fn read_step(s: &Reader<'_>, step: &Node) -> Result<DAffine3, SceneError> {
    let expected = "a table with exactly one of `scale`, `rotate`, `translate`, `matrix`, \
                    `look_at`";
    let Some(entries) = step.as_table() else {
        return Err(s.wrong_type("transform", step, expected));
    };
    s.deny_unknown(STEP_KINDS)?;
    if entries.len() != 1 {
        return Err(s.invalid(
            "transform",
            step,
            &format!(
                "each step must hold exactly one operation (got {}); write several steps to \
                 chain them",
                entries.len()
            ),
        ));
    }
    let (key, value) = &entries[0];
    Ok(match key.name.as_str() {
        "scale" => match value.value {
            Value::Integer(_) | Value::Float(_) => {
                DAffine3::from_scale(DVec3::splat(f64::from(s.f32("scale", None)?)))
            }
            _ => DAffine3::from_scale(s.vec3("scale", None)?.as_dvec3()),
        },
        "translate" => DAffine3::from_translation(s.vec3("translate", None)?.as_dvec3()),
        "rotate" => {
            let entity = format!("{} rotate", s.entity);
            let t = table_reader(s, "rotate", value, &entity)?;
            t.deny_unknown(&["axis", "angle"])?;
            let axis = t.vec3("axis", None)?.as_dvec3();
            let angle = f64::from(t.f32("angle", None)?);
            if axis.length_squared() == 0.0 {
                return Err(t.invalid("axis", t.get("axis").unwrap_or(value), "must not be zero"));
            }
            // Right-handed rotation by `angle` degrees (Rodrigues' formula in glam).
            DAffine3::from_axis_angle(axis.normalize(), angle.to_radians())
        }
        "look_at" => {
            let entity = format!("{} look_at", s.entity);
            let t = table_reader(s, "look_at", value, &entity)?;
            t.deny_unknown(&["from", "to", "up"])?;
            let from = t.vec3("from", None)?.as_dvec3();
            let to = t.vec3("to", None)?.as_dvec3();
            let up = t.vec3("up", Some(Vec3::Y))?.as_dvec3();
            look_at(&t, from, to, up)?
        }
        _ => read_matrix(s, value)?,
    })
}

fn table_reader<'a>(
    s: &Reader<'a>,
    key: &str,
    value: &'a Node,
    entity: &'a str,
) -> Result<Reader<'a>, SceneError> {
    if value.as_table().is_none() {
        return Err(s.wrong_type(key, value, "a table"));
    }
    Ok(Reader::new(s.src, value, entity))
}

/// Mitsuba's look-at frame for shapes: local +z maps to `normalize(to - from)`, local +x to
/// `normalize(cross(up, dir))`, local +y to `cross(dir, x)`, the origin to `from`.
fn look_at(t: &Reader<'_>, from: DVec3, to: DVec3, up: DVec3) -> Result<DAffine3, SceneError> {
    let dir = to - from;
    if dir.length_squared() == 0.0 {
        return Err(t.invalid(
            "to",
            t.get("to").unwrap_or(t.node),
            "must differ from `from`",
        ));
    }
    let dir = dir.normalize();
    let left = up.cross(dir);
    if up.length_squared() == 0.0 || left.length_squared() <= 1e-12 * up.length_squared() {
        return Err(t.invalid(
            "up",
            t.get("up").unwrap_or(t.node),
            "must not be zero or parallel to `to - from`",
        ));
    }
    let left = left.normalize();
    let new_up = dir.cross(left);
    Ok(DAffine3::from_mat3_translation(
        DMat3::from_cols(left, new_up, dir),
        from,
    ))
}

/// `matrix = [[a, b, c, tx], [d, e, f, ty], [g, h, i, tz]]` (rows; an optional fourth row
/// must be `[0, 0, 0, 1]`).
fn read_matrix(s: &Reader<'_>, value: &Node) -> Result<DAffine3, SceneError> {
    let expected = "3 (or 4) rows of 4 numbers, e.g. [[1, 0, 0, tx], [0, 1, 0, ty], [0, 0, 1, tz]]";
    let Value::Array(rows) = &value.value else {
        return Err(s.wrong_type("matrix", value, expected));
    };
    if rows.len() != 3 && rows.len() != 4 {
        return Err(s.invalid(
            "matrix",
            value,
            &format!("expected {expected}; got {} rows", rows.len()),
        ));
    }
    let mut m = [[0.0f64; 4]; 4];
    for (i, row) in rows.iter().enumerate() {
        let Value::Array(cells) = &row.value else {
            return Err(s.wrong_type("matrix", row, "a row of 4 numbers"));
        };
        if cells.len() != 4 {
            return Err(s.invalid(
                "matrix",
                row,
                &format!("each row must have 4 numbers, got {}", cells.len()),
            ));
        }
        for (j, cell) in cells.iter().enumerate() {
            m[i][j] = match cell.value {
                Value::Integer(v) => v as f64,
                Value::Float(v) if v.is_finite() => v,
                Value::Float(_) => return Err(s.invalid("matrix", cell, "must be finite")),
                _ => return Err(s.wrong_type("matrix", cell, "a number")),
            };
        }
    }
    if rows.len() == 4 && m[3] != [0.0, 0.0, 0.0, 1.0] {
        return Err(s.invalid(
            "matrix",
            &rows[3],
            "the fourth row must be [0, 0, 0, 1] (projective transforms are not supported)",
        ));
    }
    Ok(DAffine3::from_mat3_translation(
        DMat3::from_cols(
            DVec3::new(m[0][0], m[1][0], m[2][0]),
            DVec3::new(m[0][1], m[1][1], m[2][1]),
            DVec3::new(m[0][2], m[1][2], m[2][2]),
        ),
        DVec3::new(m[0][3], m[1][3], m[2][3]),
    ))
}

/// The two triangles of the parallelogram `corner, corner + e1, corner + e1 + e2,
/// corner + e2` (local space), both with normal along `e1 x e2`.
fn quad_local(corner: DVec3, e1: DVec3, e2: DVec3) -> [[DVec3; 3]; 2] {
    let (v0, v1, v2, v3) = (corner, corner + e1, corner + e1 + e2, corner + e2);
    [[v0, v1, v2], [v0, v2, v3]]
}

/// Transforms local triangles to world space. A mirroring transform (negative
/// determinant) would turn the winding inside out; normals transform with the inverse
/// transpose, which keeps the surface's orientation, so the winding is swapped to keep
/// `(v1 - v0) x (v2 - v0)` along the transformed normal.
pub(crate) fn to_world(m: &DAffine3, local: impl IntoIterator<Item = [DVec3; 3]>) -> Vec<Triangle> {
    let flip = mirrors(m);
    local
        .into_iter()
        .map(|t| wound(t.map(|v| m.transform_point3(v).as_vec3()), flip))
        .collect()
}

/// Whether `m` mirrors (a negative determinant): [`to_world`] then swaps each triangle's
/// winding.
pub(crate) fn mirrors(m: &DAffine3) -> bool {
    m.matrix3.determinant() < 0.0
}

/// A triangle's corners (vertices, or their attribute indices) with the second and third
/// swapped when `flip`: the winding swap of [`to_world`], which attribute corners follow.
pub(crate) fn wound<T>([a, b, c]: [T; 3], flip: bool) -> [T; 3] {
    if flip {
        [a, c, b]
    } else {
        [a, b, c]
    }
}

/// Rejects a quad whose (world-space) edges span no area.
pub(crate) fn check_area(r: &Reader<'_>, tris: &[Triangle], node: &Node) -> Result<(), SceneError> {
    let area2: f32 = tris
        .iter()
        .map(|[a, b, c]| (*b - *a).cross(*c - *a).length())
        .sum();
    if !(area2 > 0.0 && area2.is_finite()) {
        return Err(r.invalid(
            "edge2",
            node,
            "the quad has no area (edges are zero or parallel)",
        ));
    }
    Ok(())
}

/// `quad`: corner + edge1 + edge2 (+ optional transform).
pub(crate) fn quad(r: &Reader<'_>) -> Result<(Vec<Triangle>, DAffine3), SceneError> {
    let corner = r.vec3("corner", None)?.as_dvec3();
    let e1 = r.vec3("edge1", None)?.as_dvec3();
    let e2 = r.vec3("edge2", None)?.as_dvec3();
    let m = read_transform(r)?;
    let tris = to_world(&m, quad_local(corner, e1, e2));
    check_area(r, &tris, r.get("edge2").unwrap_or(r.node))?;
    Ok((tris, m))
}

/// `rectangle`: Mitsuba's rectangle, the square [-1, 1]^2 in the local xy plane with
/// normal +z, placed by `transform`, with Mitsuba's texture coordinates `(u, v) = ((x + 1) / 2,
/// (y + 1) / 2)` of the local point (mitsuba3 `src/shapes/rectangle.cpp`) as attributes
/// (corners swapped under a mirroring transform, as [`to_world`] swaps the vertices).
pub(crate) fn rectangle(
    r: &Reader<'_>,
) -> Result<(Vec<Triangle>, DAffine3, VertexAttributes), SceneError> {
    let m = read_transform(r)?;
    let tris = to_world(
        &m,
        quad_local(
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
        ),
    );
    // quad_local's vertices: (-1, -1), (1, -1), (1, 1), (-1, 1); triangles (0, 1, 2), (0, 2, 3).
    let flip = mirrors(&m);
    let attributes = VertexAttributes {
        normals: Vec::new(),
        uvs: vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ],
        corners: vec![wound([0, 1, 2], flip), wound([0, 2, 3], flip)],
        shadow_terminator_offset: false,
    };
    Ok((tris, m, attributes))
}

/// The 12 triangles of the axis-aligned box [lo, hi], outward winding.
pub(crate) fn box_local(lo: DVec3, hi: DVec3) -> Vec<[DVec3; 3]> {
    let d = hi - lo;
    let (x, y, z) = (DVec3::X * d.x, DVec3::Y * d.y, DVec3::Z * d.z);
    // (corner, e1, e2) with e1 x e2 pointing out of the box.
    let faces = [
        (lo, z, y),     // -x
        (lo + x, y, z), // +x
        (lo, x, z),     // -y
        (lo + y, z, x), // +y
        (lo, y, x),     // -z
        (lo + z, x, y), // +z
    ];
    faces
        .iter()
        .flat_map(|&(c, e1, e2)| quad_local(c, e1, e2))
        .collect()
}

/// `box`: the cube [-1, 1]^3 (or [min, max]) placed by `transform`.
pub(crate) fn cuboid(r: &Reader<'_>) -> Result<(Vec<Triangle>, DAffine3), SceneError> {
    let (lo, hi) = match (r.vec3_opt("min")?, r.vec3_opt("max")?) {
        (None, None) => (DVec3::splat(-1.0), DVec3::splat(1.0)),
        (Some(lo), Some(hi)) => {
            if !(lo.cmplt(hi).all()) {
                return Err(r.invalid(
                    "max",
                    r.get("max").unwrap_or(r.node),
                    "every component of `max` must be greater than `min`'s",
                ));
            }
            (lo.as_dvec3(), hi.as_dvec3())
        }
        (Some(_), None) => return Err(r.missing("max", "given together with `min`")),
        (None, Some(_)) => return Err(r.missing("min", "given together with `max`")),
    };
    let m = read_transform(r)?;
    Ok((to_world(&m, box_local(lo, hi)), m))
}

/// `mesh`: the triangles of an OBJ or PLY file (chosen by the extension; every object of
/// an OBJ, polygons fan-triangulated), placed by `transform`, with the file's vertex normals
/// (unless `face_normals = true`) and texture coordinates in world space: positions by the
/// transform, normals by its inverse transpose; a mirroring transform swaps the corners of
/// each triangle as [`to_world`] swaps its vertices. `flip_normals = true` (Mitsuba's
/// `flip_normals`) reverses every triangle's winding, so the front is the other side, and
/// the file's normals with it. `shadow_terminator_offset` (default true) lets rays leave
/// a closed mesh from the smooth surface the normals imply (`risotto_systems::terminator`;
/// an open mesh never does, [`MeshData::is_closed`](crate::mesh_file::MeshData::is_closed)).
/// `flip_tex_coords = true` (Mitsuba's OBJ default) reads each texture coordinate `v` as
/// `1 - v`.
pub(crate) fn mesh(
    r: &Reader<'_>,
) -> Result<(TriangleMesh, DAffine3, VertexAttributes), SceneError> {
    let (path, node) = r
        .path_opt("path")?
        .ok_or_else(|| r.missing("path", "an OBJ or PLY file path relative to the scene file"))?;
    let face_normals = r.bool("face_normals", Some(false))?;
    let flip_normals = r.bool("flip_normals", Some(false))?;
    let m = read_transform(r)?;
    // Parsed once per scene load, however many shapes name the file.
    let data = r
        .src
        .side_files
        .get_or_load(&path, "mesh", || load_mesh(&path))
        .map_err(|msg| {
            r.error(
                SceneErrorKind::ExternalFile,
                &node.span(),
                Some("path"),
                msg,
            )
        })?;
    let terminator = r.bool("shadow_terminator_offset", Some(true))?;
    let flip_tex_coords = r.bool("flip_tex_coords", Some(false))?;
    let (triangles, m, mut attributes) =
        mesh_from_data(r, &path, &data, face_normals, flip_normals, m)?;
    attributes.shadow_terminator_offset =
        terminator && !attributes.normals.is_empty() && data.is_closed();
    if flip_tex_coords {
        // Mitsuba's OBJ convention (`flip_tex_coords`, on by default there): v = 1 - v.
        for uv in &mut attributes.uvs {
            uv.y = 1.0 - uv.y;
        }
    }
    Ok((triangles, m, attributes))
}

/// `triangles`: an indexed mesh written in the scene itself (a converted pbrt
/// `trianglemesh`): `positions` (flat x, y, z), `indices` (three per triangle, each below
/// the vertex count), optional `normals` (one per vertex) and `uv` (one pair per vertex),
/// with the checks of the mesh files (finite values, indices in range) and the same
/// treatment as `mesh` (transform, `face_normals`).
pub(crate) fn triangles(
    r: &Reader<'_>,
) -> Result<(TriangleMesh, DAffine3, VertexAttributes), SceneError> {
    let numbers = |key: &str, per: usize| -> Result<Option<(Vec<f64>, &Node)>, SceneError> {
        let Some(node) = r.get(key) else {
            return Ok(None);
        };
        let Value::Array(items) = &node.value else {
            return Err(r.wrong_type(key, node, "a flat array of numbers"));
        };
        let mut out = Vec::with_capacity(items.len());
        for item in items {
            match item.value {
                Value::Integer(v) => out.push(v as f64),
                Value::Float(v) if v.is_finite() => out.push(v),
                Value::Float(_) => return Err(r.invalid(key, item, "must be finite")),
                _ => return Err(r.wrong_type(key, item, "a number")),
            }
        }
        if out.is_empty() || out.len() % per != 0 {
            return Err(r.invalid(
                key,
                node,
                &format!(
                    "expected a non-empty multiple of {per} numbers, got {}",
                    out.len()
                ),
            ));
        }
        Ok(Some((out, node)))
    };
    let (positions, _) = numbers("positions", 3)?
        .ok_or_else(|| r.missing("positions", "a flat array [x, y, z, ...]"))?;
    let nv = positions.len() / 3;
    let (indices, inode) = numbers("indices", 3)?
        .ok_or_else(|| r.missing("indices", "three vertex indices per triangle"))?;
    let mut tris = Vec::with_capacity(indices.len() / 3);
    for t in indices.chunks_exact(3) {
        let mut tri = [0u32; 3];
        for (k, &i) in t.iter().enumerate() {
            if i.fract() != 0.0 || i < 0.0 || i >= nv as f64 {
                return Err(r.invalid(
                    "indices",
                    inode,
                    &format!("index {i} is not a vertex (there are {nv}, counted from 0)"),
                ));
            }
            tri[k] = i as u32;
        }
        tris.push(tri);
    }
    let vec3s = |v: &[f64]| -> Vec<DVec3> {
        v.chunks_exact(3)
            .map(|c| DVec3::new(c[0], c[1], c[2]))
            .collect()
    };
    let normals = match numbers("normals", 3)? {
        Some((n, node)) if n.len() != positions.len() => {
            return Err(r.invalid("normals", node, "expected one normal per vertex"))
        }
        n => n.map(|(n, _)| vec3s(&n)).unwrap_or_default(),
    };
    let uvs = match numbers("uv", 2)? {
        Some((u, node)) if u.len() / 2 != nv => {
            return Err(r.invalid("uv", node, "expected one (u, v) pair per vertex"))
        }
        u => u
            .map(|(u, _)| {
                u.chunks_exact(2)
                    .map(|c| Vec2::new(c[0] as f32, c[1] as f32))
                    .collect()
            })
            .unwrap_or_default(),
    };
    let face_normals = r.bool("face_normals", Some(false))?;
    let m = read_transform(r)?;
    let data = crate::mesh_file::MeshData {
        positions: vec3s(&positions),
        normals,
        uvs,
        triangles: tris,
        skipped: Default::default(),
    };
    let terminator = r.bool("shadow_terminator_offset", Some(true))?;
    let (triangles, m, mut attributes) = mesh_from_data(
        r,
        std::path::Path::new("triangles"),
        &data,
        face_normals,
        false,
        m,
    )?;
    attributes.shadow_terminator_offset =
        terminator && !attributes.normals.is_empty() && data.is_closed();
    Ok((triangles, m, attributes))
}

/// A mesh's triangles and attributes placed by `m`, their winding reversed with
/// `flip_normals` (see [`mesh`]): its vertices mapped to the world one by one and its
/// triangles kept as indices (issue 36: no triangle is copied out of the mesh), each
/// vertex the point [`to_world`] would make of it and each triangle wound as there.
fn mesh_from_data(
    r: &Reader<'_>,
    path: &std::path::Path,
    data: &crate::mesh_file::MeshData,
    face_normals: bool,
    flip_normals: bool,
    m: DAffine3,
) -> Result<(TriangleMesh, DAffine3, VertexAttributes), SceneError> {
    let skipped = data.skipped;
    if skipped.points + skipped.lines > 0 {
        r.src.warnings.add(format!(
            "{}: {} point and {} line statements skipped (only faces are surfaces)",
            path.display(),
            skipped.points,
            skipped.lines
        ));
    }
    // `flip_normals` reverses the winding, and a mirroring `m` reverses it again.
    let flip = mirrors(&m) != flip_normals;
    let triangles = TriangleMesh {
        positions: data
            .positions
            .iter()
            .map(|&p| m.transform_point3(p).as_vec3())
            .collect(),
        triangles: data.triangles.iter().map(|&t| wound(t, flip)).collect(),
    };
    let normal_matrix = if flip_normals {
        -m.matrix3.inverse().transpose()
    } else {
        m.matrix3.inverse().transpose()
    };
    let normals = if face_normals {
        Vec::new()
    } else {
        data.normals
            .iter()
            .map(|&n| (normal_matrix * n).normalize_or_zero().as_vec3())
            .collect()
    };
    let mut attributes = VertexAttributes {
        normals,
        uvs: data.uvs.clone(),
        corners: Vec::new(),
        shadow_terminator_offset: false,
    };
    if !attributes.is_empty() {
        attributes.corners = data.triangles.iter().map(|&t| wound(t, flip)).collect();
    }
    Ok((triangles, m, attributes))
}
