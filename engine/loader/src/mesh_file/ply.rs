//! Stanford PLY through `ply-rs-bw` (ascii, binary little and big endian): a `vertex`
//! element with `x, y, z` and optionally `nx, ny, nz` and `u, v` (or `s, t`, or
//! `texture_u, texture_v`), a `face` element with a `vertex_indices` (or `vertex_index`)
//! list; polygons are fan-triangulated.
//!
//! The file is streamed (issue 36): the header is parsed by `ply-rs-bw`, then every element
//! is read one at a time into a small typed record (`VertexRecord`, `FaceRecord`;
//! others are read and dropped) and appended to the mesh at once. Neither the file's bytes
//! nor a table of parsed elements (`ply-rs-bw`'s default element is a map of named
//! properties, several hundred bytes a vertex) is ever held whole. Binary bodies are decoded
//! by the `binary` module from the header's layout, ascii ones by `ply-rs-bw`.

use std::fs::File;
use std::io::{BufRead, BufReader, Seek};
use std::path::Path;

use glam::{DVec3, Vec2};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{
    BeginList, ElementDef, Encoding, Header, Property, PropertyAccess, PropertyAccessResult,
    PropertyType, ScalarType,
};

use super::{check_normals, MeshData};

mod binary;
use binary::{BinaryDecoder, ByteOrder, Element, ElementLayout};

/// The texture-coordinate property names, in the order they are looked for.
const UV_NAMES: [(&str, &str); 3] = [("u", "v"), ("s", "t"), ("texture_u", "texture_v")];

/// The face-index list property names, in the order they are looked for.
const INDEX_NAMES: [&str; 2] = ["vertex_indices", "vertex_index"];

/// Reads a PLY file. The error is a complete sentence naming the full path, the element
/// and the value.
pub fn load_ply(path: &Path) -> Result<MeshData, String> {
    let shown = path.display();
    let what = format!("cannot parse PLY file `{shown}`");
    let unreadable = |e: std::io::Error| format!("cannot read PLY file `{shown}`: {e}");
    let file = File::open(path).map_err(unreadable)?;
    let file_len = file.metadata().map_err(unreadable)?.len();
    let mut reader = Reader::new(BufReader::with_capacity(1 << 16, file));
    let header = Parser::<IgnoredRecord>::new()
        .read_header(&mut reader)
        .map_err(|e| format!("{what}: bad header: {e}"))?;
    let header_end = reader.get_mut().stream_position().map_err(unreadable)?;
    let body = usize::try_from(file_len.saturating_sub(header_end)).unwrap_or(usize::MAX);
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
    let index_name = INDEX_NAMES
        .into_iter()
        .find(|n| face_def.properties.contains_key(*n))
        .ok_or_else(|| {
            format!("{what}: the `face` element has no `vertex_indices` (or `vertex_index`) list")
        })?;
    // Every count below is now known to fit in the file: the reservations are bounded by it.
    check_counts(&header, body, &what)?;

    let mut mesh = MeshData::default();
    let has_normals = ["nx", "ny", "nz"]
        .iter()
        .all(|n| vertex_def.properties.contains_key(*n));
    // Which pair of [`UV_NAMES`] the vertices carry, by its place there.
    let uv_pair = UV_NAMES.iter().position(|(u, v)| {
        vertex_def.properties.contains_key(*u) && vertex_def.properties.contains_key(*v)
    });
    let n_vertices = vertex_def.count;
    mesh.positions.reserve(n_vertices);
    if has_normals {
        mesh.normals.reserve(n_vertices);
    }
    if uv_pair.is_some() {
        mesh.uvs.reserve(n_vertices);
    }
    mesh.triangles.reserve(face_def.count);
    let mut elements = ElementReader {
        reader,
        encoding: header.encoding,
        line: String::new(),
        binary: match header.encoding {
            Encoding::Ascii => None,
            Encoding::BinaryLittleEndian => Some(BinaryDecoder::new(ByteOrder::Little)),
            Encoding::BinaryBigEndian => Some(BinaryDecoder::new(ByteOrder::Big)),
        },
    };
    for (name, def) in &header.elements {
        let what = what.as_str();
        let count = def.count;
        let cannot = |i: usize, e: String| {
            format!("{what}: cannot read `{name}` element {i} (of {count}): {e}")
        };
        let layout = ElementLayout::of(def, (name == "face").then_some(index_name));
        match name.as_str() {
            "vertex" => elements.for_each(def, &layout, cannot, |i, v| {
                let [x, y, z, nx, ny, nz] = [0, 1, 2, 3, 4, 5].map(|k| v.values[k]);
                let p = DVec3::new(x, y, z);
                if !p.is_finite() {
                    return Err(format!("{what}: vertex {i} is not finite ({p})"));
                }
                mesh.positions.push(p);
                if has_normals {
                    mesh.normals.push(DVec3::new(nx, ny, nz));
                }
                if let Some(k) = uv_pair {
                    let uv = &v.values[6 + 2 * k..];
                    let t = Vec2::new(uv[0] as f32, uv[1] as f32);
                    if !t.is_finite() {
                        return Err(format!(
                            "{what}: vertex {i} has a texture coordinate that is not finite ({t})"
                        ));
                    }
                    mesh.uvs.push(t);
                }
                Ok(())
            })?,
            "face" => elements.for_each(def, &layout, cannot, |f, face| {
                let indices = &face.indices;
                if !face.integer_list {
                    return Err(format!(
                        "{what}: face {f}: `{index_name}` is not an integer list"
                    ));
                }
                if indices.len() < 3 {
                    return Err(format!(
                        "{what}: face {f} has {} vertices (a face needs at least 3)",
                        indices.len()
                    ));
                }
                let n = n_vertices as i64;
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
                Ok(())
            })?,
            _ => elements.for_each(def, &layout, cannot, |_, _| Ok(()))?,
        }
    }
    check_normals(&mesh.normals, &what)?;
    if mesh.triangles.is_empty() {
        return Err(format!("PLY file `{shown}` contains no faces"));
    }
    Ok(mesh)
}

/// Reads a PLY body one element at a time, in the file's encoding.
struct ElementReader<R: BufRead> {
    reader: Reader<R>,
    encoding: Encoding,
    /// An ascii element's line.
    line: String,
    /// The decoder of a binary body (`None` for ascii).
    binary: Option<BinaryDecoder>,
}

impl<R: BufRead> ElementReader<R> {
    /// Reads the `def.count` elements of `def` (laid out as `layout`), handing each to `f`
    /// with its number: decoded by [`BinaryDecoder`] from a binary body, parsed by
    /// `ply-rs-bw` from an ascii one. A read error is `cannot(number, reason)`.
    fn for_each(
        &mut self,
        def: &ElementDef,
        layout: &ElementLayout,
        cannot: impl Fn(usize, String) -> String,
        mut f: impl FnMut(usize, &Element) -> Result<(), String>,
    ) -> Result<(), String> {
        if let Some(binary) = &mut self.binary {
            let reader = self.reader.get_mut();
            return binary.for_each(reader, layout, def.count, cannot, f);
        }
        let mut element = Element::new();
        for i in 0..def.count {
            match def.name.as_str() {
                "vertex" => {
                    let v = self.next(&Parser::<VertexRecord>::new(), def);
                    element.values = v.map_err(|e| cannot(i, e))?.values;
                }
                "face" => {
                    let face = self.next(&Parser::<FaceRecord>::new(), def);
                    let face = face.map_err(|e| cannot(i, e))?;
                    let name = layout.index_name.unwrap_or_default();
                    element.integer_list = face.indices_into(name, &mut element.indices);
                }
                _ => {
                    let ignored = self.next(&Parser::<IgnoredRecord>::new(), def);
                    ignored.map_err(|e| cannot(i, e))?;
                }
            }
            f(i, &element)?;
        }
        Ok(())
    }

    /// The next element of an ascii body, as `def` declares it.
    fn next<E: PropertyAccess>(
        &mut self,
        parser: &Parser<E>,
        def: &ElementDef,
    ) -> Result<E, String> {
        let input = self.reader.get_mut();
        let read = match self.encoding {
            Encoding::Ascii => {
                self.line.clear();
                match input.read_line(&mut self.line) {
                    Ok(0) => return Err("the file ends before it".into()),
                    Ok(_) => parser.read_ascii_element(self.line.trim_end(), def),
                    Err(e) => return Err(e.to_string()),
                }
            }
            Encoding::BinaryLittleEndian => parser.read_little_endian_element(input, def),
            Encoding::BinaryBigEndian => parser.read_big_endian_element(input, def),
        };
        read.map_err(|e| e.to_string())
    }
}

/// The properties of a `vertex` element the mesh uses; any scalar type, as `f64` (NaN where
/// a property is absent: the callers check finiteness).
struct VertexRecord {
    /// `x, y, z, nx, ny, nz`, then the texture coordinates under each of [`UV_NAMES`]'
    /// names, pair by pair ([`vertex_slot`]).
    values: [f64; 12],
}

/// The [`VertexRecord::values`] entry of vertex property `name`.
fn vertex_slot(name: &str) -> Option<usize> {
    let uv = UV_NAMES.iter().flat_map(|(u, v)| [*u, *v]);
    ["x", "y", "z", "nx", "ny", "nz"]
        .into_iter()
        .chain(uv)
        .position(|n| n == name)
}

impl PropertyAccess for VertexRecord {
    fn new() -> Self {
        VertexRecord {
            values: [f64::NAN; 12],
        }
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        if let Some(k) = vertex_slot(name) {
            self.values[k] = scalar(&property);
        }
        PropertyAccessResult::Ignored
    }
}

/// The index list of a `face` element (under either of [`INDEX_NAMES`]), as read.
#[derive(Default)]
struct FaceRecord {
    /// Which name the list had, and its entries; `None`: no integer list under either name
    /// (absent, a scalar or a list of floats).
    indices: Option<(&'static str, Vec<i64>)>,
    /// `int` and `uint` lists, filled in place by the parser.
    ints: Vec<i32>,
    uints: Vec<u32>,
    /// Which of the two the parser filled, under which name.
    filled: Option<(&'static str, bool)>,
}

impl FaceRecord {
    /// Replaces `out` with the list under `name`; false when there was no integer list
    /// under that name.
    fn indices_into(&self, name: &str, out: &mut Vec<i64>) -> bool {
        out.clear();
        match (self.filled, &self.indices) {
            (Some((n, true)), _) if n == name => {
                out.extend(self.ints.iter().map(|&i| i64::from(i)))
            }
            (Some((n, false)), _) if n == name => {
                out.extend(self.uints.iter().map(|&i| i64::from(i)))
            }
            (_, Some((n, list))) if *n == name => out.extend_from_slice(list),
            _ => return false,
        }
        true
    }

    fn index_name(name: &str) -> Option<&'static str> {
        INDEX_NAMES.into_iter().find(|n| *n == name)
    }
}

impl PropertyAccess for FaceRecord {
    fn new() -> Self {
        FaceRecord::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let Some(name) = Self::index_name(name) else {
            return PropertyAccessResult::Ignored;
        };
        let list: Option<Vec<i64>> = match property {
            Property::ListChar(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListUChar(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListShort(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListUShort(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListInt(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListUInt(v) => Some(v.into_iter().map(i64::from).collect()),
            _ => None,
        };
        if let Some(list) = list {
            self.indices = Some((name, list));
        }
        PropertyAccessResult::Ignored
    }

    fn begin_list_int(&mut self, name: &str, _len: usize) -> BeginList<'_, i32> {
        match Self::index_name(name) {
            Some(n) => {
                self.filled = Some((n, true));
                BeginList::Fill(&mut self.ints)
            }
            None => BeginList::UseSetter,
        }
    }

    fn begin_list_uint(&mut self, name: &str, _len: usize) -> BeginList<'_, u32> {
        match Self::index_name(name) {
            Some(n) => {
                self.filled = Some((n, false));
                BeginList::Fill(&mut self.uints)
            }
            None => BeginList::UseSetter,
        }
    }
}

/// An element the mesh does not use: read past, every property ignored.
struct IgnoredRecord;

impl PropertyAccess for IgnoredRecord {
    fn new() -> Self {
        IgnoredRecord
    }
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

/// A scalar property as `f64` (NaN for a list: the callers check finiteness).
fn scalar(p: &Property) -> f64 {
    match p {
        Property::Char(v) => f64::from(*v),
        Property::UChar(v) => f64::from(*v),
        Property::Short(v) => f64::from(*v),
        Property::UShort(v) => f64::from(*v),
        Property::Int(v) => f64::from(*v),
        Property::UInt(v) => f64::from(*v),
        Property::Float(v) => f64::from(*v),
        Property::Double(v) => *v,
        _ => f64::NAN,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Writes `bytes` to file `name` in a temporary directory of this process.
    pub(super) fn write(name: &str, bytes: &[u8]) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("risotto-ply-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        path
    }

    /// An ascii file with what the mesh does not use around what it does: a colour and a
    /// `confidence` per vertex, `s, t` texture coordinates, an element before the
    /// vertices and one after the faces, a quad (fanned) and a `uint` index list.
    #[test]
    fn unused_elements_and_properties_are_read_past() {
        let text = "ply\nformat ascii 1.0\ncomment made by hand\nelement camera 1\n\
                    property float view_px\nproperty float view_py\n\
                    element vertex 4\nproperty float x\nproperty uchar red\nproperty float y\n\
                    property float z\nproperty float s\nproperty float t\nproperty double confidence\n\
                    element face 2\nproperty uchar flags\nproperty list uchar uint vertex_indices\n\
                    element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n\
                    5 6\n\
                    0 255 0 0 0.25 0.5 1\n1 0 0 0 0.75 0.5 1\n1 9 1 0 1 1 0.5\n0 9 1 0 0 1 0.5\n\
                    7 4 0 1 2 3\n0 3 2 1 0\n\
                    0 1\n";
        let mesh = load_ply(&write("extra.ply", text.as_bytes())).unwrap();
        assert_eq!(mesh.positions.len(), 4);
        assert_eq!(mesh.positions[2], DVec3::new(1.0, 1.0, 0.0));
        assert_eq!(mesh.uvs[0], Vec2::new(0.25, 0.5));
        assert!(mesh.normals.is_empty());
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [2, 1, 0]]);
    }

    /// Index lists of every integer type (`ushort` through the parser's setter path, `int`
    /// filled in place), big-endian, with `double` positions and normals.
    #[test]
    fn binary_index_lists_of_any_integer_type() {
        for (list, bytes_of) in [
            (
                "ushort",
                (|i: u32| (i as u16).to_be_bytes().to_vec()) as fn(u32) -> Vec<u8>,
            ),
            ("int", |i: u32| (i as i32).to_be_bytes().to_vec()),
            ("uint", |i: u32| i.to_be_bytes().to_vec()),
            ("char", |i: u32| vec![i as u8]),
        ] {
            let mut b = format!(
                "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\n\
                 property double y\nproperty double z\nproperty double nx\nproperty double ny\n\
                 property double nz\nelement face 1\nproperty list uchar {list} vertex_index\n\
                 end_header\n"
            )
            .into_bytes();
            for p in [[0.0f64, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
                for c in p.iter().chain(&[0.0, 0.0, 1.0]) {
                    b.extend(c.to_be_bytes());
                }
            }
            b.push(3);
            for i in [2, 1, 0] {
                b.extend(bytes_of(i));
            }
            let mesh = load_ply(&write(&format!("{list}.ply"), &b)).unwrap();
            assert_eq!(mesh.triangles, vec![[2, 1, 0]], "{list}");
            assert_eq!(mesh.normals[1], DVec3::Z, "{list}");
            assert_eq!(mesh.positions[1], DVec3::X, "{list}");
        }
    }

    /// Indices that are no integer list, and a body shorter than its header says, are
    /// errors naming the file, the face and the property.
    #[test]
    fn bad_index_lists_and_short_bodies_are_errors() {
        let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\
                    property float y\nproperty float z\nelement face 1\n";
        let verts = "0 0 0\n1 0 0\n0 1 0\n";
        let floats =
            format!("{head}property list uchar float vertex_indices\nend_header\n{verts}3 0 1 2\n");
        let e = load_ply(&write("floats.ply", floats.as_bytes())).unwrap_err();
        assert!(
            e.contains("floats.ply")
                && e.contains("face 0: `vertex_indices` is not an integer list"),
            "{e}"
        );
        let scalar = format!("{head}property int vertex_indices\nend_header\n{verts}1\n");
        let e = load_ply(&write("scalar.ply", scalar.as_bytes())).unwrap_err();
        assert!(e.contains("is not an integer list"), "{e}");
        // Long enough for the header's counts (trailing blanks), without the face's line.
        let short =
            format!("{head}property list uchar int vertex_indices\nend_header\n{verts}      \n");
        let e = load_ply(&write("short.ply", short.as_bytes())).unwrap_err();
        assert!(
            e.contains("short.ply") && e.contains("`face` element 0 (of 1)"),
            "{e}"
        );
        // Without even the blank line: the file ends before the face.
        let cut = format!(
            "{head}property list uchar int vertex_indices\nend_header\n0 0 0 \n1 0 0 \n0 1 0 "
        );
        let e = load_ply(&write("cut.ply", cut.as_bytes())).unwrap_err();
        assert!(
            e.contains("`face` element 0 (of 1): the file ends before it"),
            "{e}"
        );
    }
}
