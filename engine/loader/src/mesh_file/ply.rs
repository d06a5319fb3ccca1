//! Stanford PLY through `ply-rs-bw` (ascii, binary little and big endian): a `vertex`
//! element with `x, y, z` and optionally `nx, ny, nz` and `u, v` (or `s, t`, or
//! `texture_u, texture_v`), a `face` element with a `vertex_indices` (or `vertex_index`)
//! list; polygons are fan-triangulated.

use std::io::Cursor;
use std::path::Path;

use glam::{DVec3, Vec2};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{
    DefaultElement, ElementDef, Encoding, Header, Property, PropertyType, ScalarType,
};

use super::{check_normals, MeshData};

/// The texture-coordinate property names, in the order they are looked for.
const UV_NAMES: [(&str, &str); 3] = [("u", "v"), ("s", "t"), ("texture_u", "texture_v")];

/// Reads a PLY file. The error is a complete sentence naming the full path, the element
/// and the value.
pub fn load_ply(path: &Path) -> Result<MeshData, String> {
    let shown = path.display();
    let what = format!("cannot parse PLY file `{shown}`");
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read PLY file `{shown}`: {e}"))?;
    let mut reader = Reader::new(Cursor::new(&bytes[..]));
    let parser = Parser::<DefaultElement>::new();
    let header = parser
        .read_header(&mut reader)
        .map_err(|e| format!("{what}: bad header: {e}"))?;
    let body = bytes.len().saturating_sub(header_len(&bytes));
    let vertex_def = header
        .elements
        .get("vertex")
        .ok_or_else(|| format!("{what}: the header declares no `vertex` element"))?;
    for axis in ["x", "y", "z"] {
        if !vertex_def.properties.contains_key(axis) {
            return Err(format!(
                "{what}: the `vertex` element has no `{axis}` property"
            ));
        }
    }
    let face_def = header
        .elements
        .get("face")
        .ok_or_else(|| format!("{what}: the header declares no `face` element"))?;
    let index_name = ["vertex_indices", "vertex_index"]
        .into_iter()
        .find(|n| face_def.properties.contains_key(*n))
        .ok_or_else(|| {
            format!("{what}: the `face` element has no `vertex_indices` (or `vertex_index`) list")
        })?;
    check_counts(&header, body, &what)?;

    let mut mesh = MeshData::default();
    let has_normals = ["nx", "ny", "nz"]
        .iter()
        .all(|n| vertex_def.properties.contains_key(*n));
    let uv_names = UV_NAMES.into_iter().find(|(u, v)| {
        vertex_def.properties.contains_key(*u) && vertex_def.properties.contains_key(*v)
    });
    for (name, def) in &header.elements {
        let elements = parser
            .read_payload_for_element(&mut reader, def, &header)
            .map_err(|e| format!("{what}: cannot read the `{name}` elements: {e}"))?;
        match name.as_str() {
            "vertex" => {
                for (i, e) in elements.iter().enumerate() {
                    let s = |k: &str| scalar(e, k);
                    let p = DVec3::new(s("x"), s("y"), s("z"));
                    if !p.is_finite() {
                        return Err(format!("{what}: vertex {i} is not finite ({p})"));
                    }
                    mesh.positions.push(p);
                    if has_normals {
                        mesh.normals.push(DVec3::new(s("nx"), s("ny"), s("nz")));
                    }
                    if let Some((u, v)) = uv_names {
                        let t = Vec2::new(s(u) as f32, s(v) as f32);
                        if !t.is_finite() {
                            return Err(format!(
                                "{what}: vertex {i} has a texture coordinate that is not finite ({t})"
                            ));
                        }
                        mesh.uvs.push(t);
                    }
                }
            }
            "face" => {
                for (f, e) in elements.iter().enumerate() {
                    let indices = list(e, index_name).ok_or_else(|| {
                        format!("{what}: face {f}: `{index_name}` is not an integer list")
                    })?;
                    if indices.len() < 3 {
                        return Err(format!(
                            "{what}: face {f} has {} vertices (a face needs at least 3)",
                            indices.len()
                        ));
                    }
                    let n = vertex_def.count as i64;
                    if let Some(&bad) = indices.iter().find(|&&i| i < 0 || i >= n) {
                        return Err(format!(
                            "{what}: face {f} refers to vertex {bad} but the file has {n} (indices start at 0)"
                        ));
                    }
                    // Fan triangulation: (0, k, k + 1), as tobj does for OBJ polygons.
                    for k in 1..indices.len() - 1 {
                        mesh.triangles.push([
                            indices[0] as u32,
                            indices[k] as u32,
                            indices[k + 1] as u32,
                        ]);
                    }
                }
            }
            _ => {}
        }
    }
    check_normals(&mesh.normals, &what)?;
    if mesh.triangles.is_empty() {
        return Err(format!("PLY file `{shown}` contains no faces"));
    }
    Ok(mesh)
}

/// Bytes up to and including the `end_header` line.
fn header_len(bytes: &[u8]) -> usize {
    const END: &[u8] = b"end_header";
    let Some(at) = bytes.windows(END.len()).position(|w| w == END) else {
        return bytes.len();
    };
    let rest = &bytes[at + END.len()..];
    at + END.len()
        + rest
            .iter()
            .position(|&b| b == b'\n')
            .map_or(rest.len(), |p| p + 1)
}

/// Rejects a header whose element counts cannot fit in the `body` bytes after it, before
/// anything is read or allocated by those counts: each element takes at least the bytes of
/// its scalars and list lengths (binary), or two bytes per property (ascii: a digit and a
/// separator).
fn check_counts(header: &Header, body: usize, what: &str) -> Result<(), String> {
    let mut need: u128 = 0;
    for (name, def) in &header.elements {
        let per = min_element_bytes(def, header.encoding);
        need += per as u128 * def.count as u128;
        if need > body as u128 {
            return Err(format!(
                "{what}: the header declares {} `{name}` elements, more than the file's {body} \
                 bytes after the header can hold",
                def.count
            ));
        }
    }
    Ok(())
}

fn min_element_bytes(def: &ElementDef, encoding: Encoding) -> usize {
    def.properties
        .values()
        .map(|p| match encoding {
            Encoding::Ascii => 2,
            _ => match &p.data_type {
                PropertyType::Scalar(s) => scalar_size(s),
                PropertyType::List(count, _) => scalar_size(count),
            },
        })
        .sum()
}

fn scalar_size(s: &ScalarType) -> usize {
    match s {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

/// A scalar property as `f64` (NaN when absent or a list: the callers check finiteness).
fn scalar(e: &DefaultElement, key: &str) -> f64 {
    match e.get(key) {
        Some(Property::Char(v)) => f64::from(*v),
        Some(Property::UChar(v)) => f64::from(*v),
        Some(Property::Short(v)) => f64::from(*v),
        Some(Property::UShort(v)) => f64::from(*v),
        Some(Property::Int(v)) => f64::from(*v),
        Some(Property::UInt(v)) => f64::from(*v),
        Some(Property::Float(v)) => f64::from(*v),
        Some(Property::Double(v)) => *v,
        _ => f64::NAN,
    }
}

/// An integer list property as `i64`s.
fn list(e: &DefaultElement, key: &str) -> Option<Vec<i64>> {
    Some(match e.get(key)? {
        Property::ListChar(v) => v.iter().map(|&i| i64::from(i)).collect(),
        Property::ListUChar(v) => v.iter().map(|&i| i64::from(i)).collect(),
        Property::ListShort(v) => v.iter().map(|&i| i64::from(i)).collect(),
        Property::ListUShort(v) => v.iter().map(|&i| i64::from(i)).collect(),
        Property::ListInt(v) => v.iter().map(|&i| i64::from(i)).collect(),
        Property::ListUInt(v) => v.iter().map(|&i| i64::from(i)).collect(),
        _ => return None,
    })
}
