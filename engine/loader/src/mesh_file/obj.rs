//! Wavefront OBJ, read in blocks of whole lines (their entries and triangles parsed in
//! parallel, then every line applied in order): positions, `vn` normals and `vt` texture
//! coordinates, with every `(v, vt, vn)` combination an object's faces use made one vertex,
//! so the position, normal and uv streams share one index and stay in step.
//!
//! Our own reader (it replaced tobj, issue 36): tobj keeps every face of the file as a list
//! of `(v, vt, vn)` corners (an enum of 80 bytes a face, plus its index map) until the end
//! of each object, about 160 bytes a triangle and the load's peak (a 2-million-triangle
//! mesh: 384 MiB resident). Here a corner becomes its vertex id as its line is read, and only
//! the ids (12 bytes a triangle) wait for the object's end. What tobj accepted is accepted
//! and gives the same mesh, bit for bit (f32 parsing, vertex order, fan triangulation,
//! `v x y z w`, vertex colours, relative indices, indices checked at the object's end against
//! the entries read by then); what it rejected is rejected, now with the line and the text.
//! One difference: `l` (polyline) statements are skipped like `p` (tobj made triangles of
//! those with three or more corners while they were counted as skipped).

use rayon::prelude::*;
use std::io::{BufRead, BufReader};
use std::path::Path;

use glam::{DVec3, Vec2};

use super::{check_normals, MeshData};

/// Reads an OBJ file (every object in it; polygons fan-triangulated; points and lines
/// skipped and counted; `mtllib` and `usemtl` not read: the scene assigns the material).
/// The error is a complete sentence naming the full path and, for a malformed statement or
/// a face index to an entry that does not exist, the line and its text.
pub fn load_obj(path: &Path) -> Result<MeshData, String> {
    load_obj_in_blocks(path, BLOCK_BYTES)
}

/// [`load_obj`] reading about `block_bytes` of whole lines at a time (the result does not
/// depend on it; the tests read every file in blocks of one line too).
fn load_obj_in_blocks(path: &Path, block_bytes: usize) -> Result<MeshData, String> {
    let shown = path.display();
    let file =
        std::fs::File::open(path).map_err(|e| format!("cannot read OBJ file `{shown}`: {e}"))?;
    let mut input = BufReader::with_capacity(1 << 16, file);
    let what = format!("cannot parse OBJ file `{shown}`");
    let mut obj = ObjReader::default();
    // Whole lines, about `BLOCK_BYTES` at a time: their positions, normals and texture
    // coordinates are parsed in parallel, then every line is applied in order.
    let (mut block, mut ends) = (Vec::new(), Vec::new());
    let mut number = 0usize;
    loop {
        block.clear();
        ends.clear();
        while block.len() < block_bytes {
            let read = input
                .read_until(b'\n', &mut block)
                .map_err(|e| format!("cannot read OBJ file `{shown}`: {e}"))?;
            if read == 0 {
                break;
            }
            ends.push(block.len());
        }
        if ends.is_empty() {
            break;
        }
        let line_bytes = |k: usize| &block[if k == 0 { 0 } else { ends[k - 1] }..ends[k]];
        let first = number + 1;
        let parsed: Vec<Parsed> = (0..ends.len())
            .into_par_iter()
            .map(|k| match first + k {
                1 => Parsed::Other,
                _ => parse_entry(line_bytes(k)),
            })
            .collect();
        for (k, entry) in parsed.into_iter().enumerate() {
            number += 1;
            match entry {
                Parsed::Position(p) => obj.position(p),
                Parsed::Normal(n) => obj.normals.push(n),
                Parsed::Texcoord(t) => obj.texcoords.push(t),
                Parsed::Triangle(raw) => obj.triangle(raw),
                Parsed::Other => {
                    let bytes = line_bytes(k);
                    // Files written on Windows may start with a UTF-8 byte-order mark, and
                    // comments in Latin-1 are common: the mark is dropped and bytes that are
                    // not UTF-8 become U+FFFD (harmless in a comment, still an error in a
                    // number).
                    let text = if number == 1 {
                        bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(bytes)
                    } else {
                        bytes
                    };
                    let line = match std::str::from_utf8(text) {
                        Ok(line) => std::borrow::Cow::Borrowed(line),
                        Err(_) => String::from_utf8_lossy(text),
                    };
                    let line = line.strip_suffix('\n').unwrap_or(&line);
                    let line = line.strip_suffix('\r').unwrap_or(line);
                    obj.statement(line).map_err(|e| match e {
                        Error::Line(e) => {
                            format!("{what}: line {number}: {e} in `{}`", line.trim())
                        }
                        Error::Index(e) => e.located(path, &what),
                    })?;
                }
            }
        }
    }
    obj.end_object().map_err(|e| e.located(path, &what))?;
    // Errors in the vertices found at an object's end wait for the whole file to be read,
    // as they did behind tobj: a malformed line or a bad index anywhere comes first.
    if let Some(e) = obj.deferred {
        return Err(format!("{what}: {e}"));
    }
    let mut mesh = obj.mesh;
    // Objects after the last one with normals (uvs) get theirs too.
    if !mesh.normals.is_empty() {
        mesh.normals.resize(mesh.positions.len(), DVec3::ZERO);
    }
    if !mesh.uvs.is_empty() {
        mesh.uvs.resize(mesh.positions.len(), Vec2::ZERO);
    }
    check_normals(&mesh.normals, &what)?;
    if let Some(i) = mesh.uvs.iter().position(|t| !t.is_finite()) {
        return Err(format!(
            "{what}: texture coordinate {} is not finite ({}, {})",
            i + 1,
            mesh.uvs[i].x,
            mesh.uvs[i].y
        ));
    }
    if mesh.triangles.is_empty() {
        return Err(format!("OBJ file `{shown}` contains no faces"));
    }
    Ok(mesh)
}

/// About how many bytes of whole lines are read, and their entries parsed in parallel, at a
/// time (the file is never held whole: issue 36).
const BLOCK_BYTES: usize = 1 << 22;

/// A line as the parallel pass reads it: a plain position (`v x y z`, nothing after), normal,
/// texture coordinate or triangle, parsed as [`ObjReader::statement`] parses them (a
/// triangle's indices resolved later, in order, against the entries read by then); anything
/// else (other faces, objects, a position with a weight or a colour, the first line, text
/// that is not UTF-8, a malformed entry) is left to `statement`, in order.
enum Parsed {
    Position([f32; 3]),
    Normal([f32; 3]),
    Texcoord([f32; 2]),
    /// `f` with three corners, each `(v, vt, vn)` as written (0: absent).
    Triangle([[isize; 3]; 3]),
    Other,
}

/// The [`Parsed`] form of one line (with its line break).
fn parse_entry(bytes: &[u8]) -> Parsed {
    let Ok(line) = std::str::from_utf8(bytes) else {
        return Parsed::Other;
    };
    let line = line.strip_suffix('\n').unwrap_or(line);
    let line = line.strip_suffix('\r').unwrap_or(line);
    let mut words = line.split_whitespace();
    let parsed = match words.next() {
        Some("v") => floats::<3>(&mut words)
            .filter(|_| words.next().is_none())
            .map(Parsed::Position),
        Some("vn") => floats::<3>(&mut words).map(Parsed::Normal),
        Some("vt") => floats::<2>(&mut words).map(Parsed::Texcoord),
        Some("f") => triangle_corners(&mut words).map(Parsed::Triangle),
        _ => None,
    };
    parsed.unwrap_or(Parsed::Other)
}

/// The three corners of a triangle's `f` line as written (0 for an absent index, which
/// [`resolve`] takes for none, as it takes a written 0); `None` unless there are exactly
/// three, each `v`, `v/vt`, `v//vn` or `v/vt/vn` of integers (as [`ObjReader::face`] reads
/// them: empty fields skipped, a fourth non-empty one an error).
fn triangle_corners<'a>(words: &mut impl Iterator<Item = &'a str>) -> Option<[[isize; 3]; 3]> {
    let mut raw = [[0isize; 3]; 3];
    for corner in &mut raw {
        for (slot, field) in words.next()?.split('/').enumerate() {
            if field.is_empty() {
                continue;
            }
            *corner.get_mut(slot)? = field.parse().ok()?;
        }
    }
    words.next().is_none().then_some(raw)
}

/// The 0-based entry of a face index (1-based; negative counts back from the `count`
/// entries read so far; 0, as an absent one, resolves to [`MISSING`]).
fn resolve(index: isize, count: usize) -> u32 {
    let resolved = if index < 0 {
        (count as isize).wrapping_add(index) as usize
    } else {
        (index as usize).wrapping_sub(1)
    };
    if resolved == usize::MAX {
        MISSING
    } else {
        resolved.min(MISSING as usize - 1) as u32
    }
}

/// A corner's index that names no entry: the face gave none (`1//3` has no `vt`), or an
/// index resolved to `usize::MAX` (`0`, or a relative index one before the first entry),
/// which OBJ readers like tobj take for "none" as well.
const MISSING: u32 = u32::MAX;

/// The file's state between lines: the entries read so far (as f32, what the file's
/// numbers are parsed to) and the current object, whose triangles hold object-local vertex
/// ids until its end, when its vertices are checked and gathered into `mesh`.
#[derive(Default)]
struct ObjReader {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    texcoords: Vec<[f32; 2]>,
    /// Components of `v x y z r g b` colours read (a colour that fails to parse stops at
    /// the bad component): only checked, every used vertex must have one if any has.
    colour_components: usize,
    mesh: MeshData,
    /// The current object's name (`o` / `g`), for messages.
    name: Option<String>,
    /// The current object's vertices, `(v, vt, vn)` (0-based or [`MISSING`]), in order of
    /// first use, and its first triangle in `mesh.triangles` (ids local until its end).
    keys: Vec<[u32; 3]>,
    first_triangle: usize,
    /// For each position, the id of the current object's first vertex using it (tagged by
    /// `object`, so objects need not clear it); other vertices of a position, and indices
    /// past the positions read, are found in `more`.
    by_position: Vec<(u32, u32)>,
    more: std::collections::HashMap<[u32; 3], u32, std::hash::BuildHasherDefault<KeyHasher>>,
    /// Whether `more` holds a vertex named before its position was read.
    forward: bool,
    object: u32,
    /// The current face's vertex ids.
    corners: Vec<u32>,
    /// The first problem with an object's vertices (not finite, attributes on only some),
    /// reported once the file is read.
    deferred: Option<String>,
}

/// Why a line is rejected.
enum Error {
    /// What is wrong with the line itself.
    Line(String),
    /// An index of an object ended by this line (`o`, `g`) names no entry.
    Index(IndexError),
}

impl From<&str> for Error {
    fn from(e: &str) -> Self {
        Error::Line(e.to_owned())
    }
}

impl From<String> for Error {
    fn from(e: String) -> Self {
        Error::Line(e)
    }
}

/// An error found at an object's end: an index past the entries read by then.
enum IndexError {
    /// The entry kind (`v`, `vt`, `vn`) and the corner slot its index is in.
    Missing(&'static str, usize),
    /// A vertex without a colour while others have one.
    Colour,
}

impl IndexError {
    /// The message, with the offending corner's line found by reading the file again (only
    /// on this error path).
    fn located(self, path: &Path, what: &str) -> String {
        match self {
            IndexError::Missing(kind, slot) => {
                let text = std::fs::read(path).map(|b| lossy_text(&b)).ok();
                match text.and_then(|t| bad_face_index(&t, kind, slot)) {
                    Some(at) => format!("{what}: {at}"),
                    None => format!("{what}: a face refers to a `{kind}` that does not exist"),
                }
            }
            IndexError::Colour => {
                format!("{what}: a face uses a vertex without a colour while others have one")
            }
        }
    }
}

impl ObjReader {
    /// A position read (`v`).
    fn position(&mut self, p: [f32; 3]) {
        self.positions.push(p);
        self.by_position.push((0, 0));
    }

    /// Reads one line (without its line break). The error names what is wrong; the caller
    /// adds the line.
    fn statement(&mut self, line: &str) -> Result<(), Error> {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let p = floats::<3>(&mut words).ok_or("a position needs three numbers")?;
                self.position(p);
                self.vertex_extra(&mut words)?;
            }
            Some("vt") => {
                let t = floats::<2>(&mut words).ok_or("a texture coordinate needs two numbers")?;
                self.texcoords.push(t);
            }
            Some("vn") => {
                let n = floats::<3>(&mut words).ok_or("a normal needs three numbers")?;
                self.normals.push(n);
            }
            Some("f") => self.face(words)?,
            Some("p") => self.mesh.skipped.points += 1,
            Some("l") => self.mesh.skipped.lines += 1,
            Some("o" | "g") => {
                if self.mesh.triangles.len() > self.first_triangle {
                    self.end_object().map_err(Error::Index)?;
                }
                // The name is the line after its first character, as tobj took it.
                let rest = line.char_indices().nth(1).map_or("", |(i, _)| &line[i..]);
                self.name = Some(rest.trim().to_owned()).filter(|n| !n.is_empty());
            }
            // The material name is what follows the first space (tobj's reading).
            Some("usemtl")
                if line
                    .split_once(' ')
                    .is_none_or(|(_, m)| m.trim().is_empty()) =>
            {
                return Err("`usemtl` names no material".into());
            }
            _ => {}
        }
        Ok(())
    }

    /// What may follow a position's three numbers: nothing, `w` (the position is divided
    /// by it) or an RGB colour.
    fn vertex_extra<'a>(
        &mut self,
        words: &mut impl Iterator<Item = &'a str>,
    ) -> Result<(), String> {
        let Some(first) = words.next() else {
            return Ok(());
        };
        match (words.next(), words.next()) {
            (None, _) => {
                let w: f32 = first
                    .parse()
                    .map_err(|_| "the weight `w` is not a number")?;
                if w == 0.0 {
                    return Err("the weight `w` is 0".into());
                }
                let p = self.positions.last_mut().expect("just pushed");
                *p = p.map(|c| c / w);
            }
            (Some(second), Some(third)) if words.next().is_none() => {
                self.colour_components += [first, second, third]
                    .iter()
                    .take_while(|c| c.parse::<f32>().is_ok())
                    .count();
            }
            _ => return Err("a position is followed by 1 or 3 numbers at most".into()),
        }
        Ok(())
    }

    /// A face: each corner `v`, `v/vt`, `v//vn` or `v/vt/vn` (negative indices count back
    /// from the entries read so far) made a vertex id; fan-triangulated. Faces of one or two
    /// corners are points and lines: skipped, as tobj skips them.
    fn face<'a>(&mut self, corners: impl Iterator<Item = &'a str>) -> Result<(), String> {
        let counts = [
            self.positions.len(),
            self.texcoords.len(),
            self.normals.len(),
        ];
        let mut keys = [[MISSING; 3]; 3];
        let mut n = 0usize;
        self.corners.clear();
        for corner in corners {
            let mut key = [MISSING; 3];
            for (slot, field) in corner.split('/').enumerate() {
                if field.is_empty() {
                    continue;
                }
                let index = field
                    .parse::<isize>()
                    .ok()
                    .filter(|_| slot < 3)
                    .ok_or_else(|| {
                        format!("face corner `{corner}` is not v, v/vt, v//vn or v/vt/vn")
                    })?;
                key[slot] = resolve(index, counts[slot]);
            }
            // The first three corners wait: a face of fewer is not a surface.
            if n < 3 {
                keys[n] = key;
            } else {
                if n == 3 {
                    for k in keys {
                        let id = self.vertex(k);
                        self.corners.push(id);
                    }
                }
                let id = self.vertex(key);
                self.corners.push(id);
            }
            n += 1;
        }
        match n {
            0 => return Err("a face has no corners".into()),
            1 | 2 => return Ok(()),
            3 => {
                for k in keys {
                    let id = self.vertex(k);
                    self.corners.push(id);
                }
            }
            _ => {}
        }
        let c = &self.corners;
        for k in 2..c.len() {
            self.mesh.triangles.push([c[0], c[k - 1], c[k]]);
        }
        Ok(())
    }

    /// A triangle `f a b c` whose corners the parallel pass read ([`Parsed::Triangle`]):
    /// as [`Self::face`] makes it.
    fn triangle(&mut self, raw: [[isize; 3]; 3]) {
        let counts = [
            self.positions.len(),
            self.texcoords.len(),
            self.normals.len(),
        ];
        let keys = raw.map(|c| [0, 1, 2].map(|slot| resolve(c[slot], counts[slot])));
        let ids = keys.map(|k| self.vertex(k));
        self.mesh.triangles.push(ids);
    }

    /// The current object's vertex id of `key`, a new one on its first use.
    fn vertex(&mut self, key: [u32; 3]) -> u32 {
        let next = self.keys.len() as u32;
        let tag = self.object + 1;
        match self.by_position.get_mut(key[0] as usize) {
            // A position's first vertex in this object, unless an earlier face named it
            // before its `v` line (then it is in `more`).
            Some(slot) if slot.0 != tag => {
                if !(self.forward && self.more.contains_key(&key)) {
                    *slot = (tag, next);
                    self.keys.push(key);
                    return next;
                }
            }
            Some(slot) if self.keys[slot.1 as usize] == key => return slot.1,
            Some(_) => {}
            None => self.forward = true,
        }
        *self.more.entry(key).or_insert_with(|| {
            self.keys.push(key);
            next
        })
    }

    /// Ends the current object: its vertices checked against the entries read so far and
    /// gathered into `mesh` (f64), its triangles made global.
    fn end_object(&mut self) -> Result<(), IndexError> {
        let mesh = &mut self.mesh;
        let base = mesh.positions.len();
        let n = self.keys.len();
        let (mut uvs, mut normals) = (0usize, 0usize);
        mesh.positions.reserve(n);
        for &[v, vt, vn] in &self.keys {
            let p = *self
                .positions
                .get(v as usize)
                .ok_or(IndexError::Missing("v", 0))?;
            let uv = attribute(&self.texcoords, vt, IndexError::Missing("vt", 1))?;
            let normal = attribute(&self.normals, vn, IndexError::Missing("vn", 2))?;
            if self.colour_components > 0 && 3 * v as usize + 2 >= self.colour_components {
                return Err(IndexError::Colour);
            }
            mesh.positions.push(DVec3::from(p.map(f64::from)));
            // Attributes are per file: objects without them next to objects with them get
            // zero normals (the renderer then uses the face normal) and uv (0, 0).
            if let Some(nm) = normal {
                mesh.normals.resize(base + normals, DVec3::ZERO);
                mesh.normals.push(DVec3::from(nm.map(f64::from)));
                normals += 1;
            }
            if let Some(t) = uv {
                mesh.uvs.resize(base + uvs, Vec2::ZERO);
                mesh.uvs.push(Vec2::from(t));
                uvs += 1;
            }
        }
        let name = self.name.as_deref().unwrap_or("unnamed_object");
        if let Some(i) = mesh.positions[base..].iter().position(|p| !p.is_finite()) {
            self.deferred
                .get_or_insert(format!("vertex {} is not finite", base + i + 1));
        }
        // A mesh has normals (uvs) for every vertex of an object or for none; an object where
        // only some faces give them cannot be shaded consistently.
        for (count, kind) in [
            (normals, "normals (`vn`)"),
            (uvs, "texture coordinates (`vt`)"),
        ] {
            if count != 0 && count != n {
                self.deferred.get_or_insert(format!(
                    "object `{name}` gives {kind} on some faces but not on others"
                ));
            }
        }
        if u32::try_from(mesh.positions.len()).is_err() {
            self.deferred
                .get_or_insert("more than 2^32 vertices".into());
        }
        let base32 = base as u32;
        for t in &mut mesh.triangles[self.first_triangle..] {
            *t = t.map(|i| base32.wrapping_add(i));
        }
        self.first_triangle = mesh.triangles.len();
        self.keys.clear();
        self.more.clear();
        self.forward = false;
        self.object += 1;
        Ok(())
    }
}

/// Entry `i` of a file's `vt` or `vn` list for a vertex: none if the face gave no index or
/// the file has no such entries at all (tobj's reading: `vt` indices in a file without `vt`
/// lines are ignored), `missing` if the index is past the list.
fn attribute<T: Copy>(list: &[T], i: u32, missing: IndexError) -> Result<Option<T>, IndexError> {
    if list.is_empty() || i == MISSING {
        return Ok(None);
    }
    list.get(i as usize).copied().map(Some).ok_or(missing)
}

/// The next `N` words as f32 (`None` if fewer or one is not a number); further words are
/// left to the caller.
fn floats<'a, const N: usize>(words: &mut impl Iterator<Item = &'a str>) -> Option<[f32; N]> {
    let mut out = [0.0; N];
    for o in &mut out {
        *o = words.next()?.parse().ok()?;
    }
    Some(out)
}

/// FxHash's multiply-rotate (rustc's hasher): the vertex keys are small integers, hashed
/// millions of times where a mesh has seams; SipHash's resistance to chosen keys buys
/// nothing for a file's indices and costs several times as much.
#[derive(Default)]
struct KeyHasher(u64);

impl std::hash::Hasher for KeyHasher {
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(4) {
            let mut word = [0u8; 4];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u32(u32::from_le_bytes(word));
        }
    }

    fn write_u32(&mut self, i: u32) {
        self.0 = (self.0.rotate_left(5) ^ u64::from(i)).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }

    fn finish(&self) -> u64 {
        self.0
    }
}

/// The first face corner whose `v` (`slot` 0), `vt` (1) or `vn` (2) index names no such
/// entry, as "line N: face corner `a/b/c` refers to vn 7 but the file has 6". Negative
/// indices count back from the entries read so far (the OBJ specification's relative
/// indices).
fn bad_face_index(text: &str, kind: &str, slot: usize) -> Option<String> {
    let total = text
        .lines()
        .filter(|l| l.split_whitespace().next() == Some(kind))
        .count() as i64;
    let mut so_far = 0i64;
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some(k) if k == kind => so_far += 1,
            Some("f") => {
                for corner in words {
                    let Some(field) = corner.split('/').nth(slot) else {
                        continue;
                    };
                    if field.is_empty() {
                        continue;
                    }
                    let Ok(i) = field.parse::<i64>() else {
                        continue;
                    };
                    let resolved = if i < 0 { so_far + 1 + i } else { i };
                    if resolved < 1 || resolved > total {
                        return Some(format!(
                            "line {}: face corner `{corner}` refers to {kind} {i} but the file \
                             has {total}",
                            n + 1
                        ));
                    }
                }
            }
            _ => {}
        }
    }
    None
}

/// `bytes` as [`load_obj`] reads them: byte-order mark dropped, invalid UTF-8 replaced.
fn lossy_text(bytes: &[u8]) -> String {
    let bytes = bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(bytes);
    String::from_utf8_lossy(bytes).into_owned()
}

#[cfg(test)]
mod tests;
