//! Wavefront OBJ through tobj: positions, `vn` normals and `vt` texture coordinates, with
//! every `(v, vt, vn)` combination a face uses made one vertex (tobj's `single_index`), so
//! the position, normal and uv streams share one index and stay in step.
//!
//! The file is streamed into tobj line by line, never held whole: a 2-million-triangle
//! mesh is about 150 MB of text, as much again as its parsed form (issue 36, peak memory).

use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use glam::{DVec3, Vec2};

use super::{check_normals, MeshData};

/// Reads an OBJ file (every object in it; polygons fan-triangulated by tobj; points and
/// lines ignored; `mtllib` not read: the scene assigns the material). The error is a
/// complete sentence naming the full path, and for a face index to a `vn` or `vt` that does
/// not exist, the line and the index.
pub fn load_obj(path: &Path) -> Result<MeshData, String> {
    let shown = path.display();
    let file =
        std::fs::File::open(path).map_err(|e| format!("cannot read OBJ file `{shown}`: {e}"))?;
    let mut lines = Lines::new(BufReader::with_capacity(1 << 16, file));
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) = tobj::load_obj_buf(&mut lines, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| {
        if let Some(e) = lines.error.take() {
            return format!("cannot read OBJ file `{shown}`: {e}");
        }
        // Located by a second reading of the file, on this error path only.
        let text = || std::fs::read(path).map(|b| lossy_text(&b)).ok();
        let located = match e {
            tobj::LoadError::FaceTexCoordOutOfBounds => {
                text().and_then(|t| bad_face_index(&t, "vt", 1))
            }
            tobj::LoadError::FaceNormalOutOfBounds => {
                text().and_then(|t| bad_face_index(&t, "vn", 2))
            }
            _ => None,
        };
        match located {
            Some(at) => format!("cannot parse OBJ file `{shown}`: {at}"),
            None => format!("cannot parse OBJ file `{shown}`: {e}"),
        }
    })?;
    let mut mesh = MeshData {
        skipped: lines.skipped,
        ..MeshData::default()
    };
    let what = format!("cannot parse OBJ file `{shown}`");
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len();
        let n_vertices = m.positions.len() / 3;
        let base32 = u32::try_from(base + n_vertices)
            .map_err(|_| format!("{what}: more than 2^32 vertices"))
            .map(|_| base as u32)?;
        for (i, p) in m.positions.chunks_exact(3).enumerate() {
            let v = DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]));
            if !v.is_finite() {
                return Err(format!("{what}: vertex {} is not finite", base + i + 1));
            }
            mesh.positions.push(v);
        }
        // With `single_index`, a mesh has normals (uvs) for every vertex or for none; an
        // object where only some faces give them cannot be shaded consistently.
        let has_normals = !m.normals.is_empty();
        let has_uvs = !m.texcoords.is_empty();
        for (has, len, per, kind) in [
            (has_normals, m.normals.len(), 3, "normals (`vn`)"),
            (has_uvs, m.texcoords.len(), 2, "texture coordinates (`vt`)"),
        ] {
            if has && len != per * n_vertices {
                return Err(format!(
                    "{what}: object `{}` gives {kind} on some faces but not on others",
                    model.name
                ));
            }
        }
        // Attributes are per file: objects without them next to objects with them get
        // zero normals (the renderer then uses the face normal) and uv (0, 0).
        if has_normals || !mesh.normals.is_empty() {
            mesh.normals.resize(base, DVec3::ZERO);
            if has_normals {
                mesh.normals.extend(
                    m.normals
                        .chunks_exact(3)
                        .map(|n| DVec3::new(f64::from(n[0]), f64::from(n[1]), f64::from(n[2]))),
                );
            } else {
                mesh.normals.resize(base + n_vertices, DVec3::ZERO);
            }
        }
        if has_uvs || !mesh.uvs.is_empty() {
            mesh.uvs.resize(base, Vec2::ZERO);
            if has_uvs {
                mesh.uvs
                    .extend(m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], t[1])));
            } else {
                mesh.uvs.resize(base + n_vertices, Vec2::ZERO);
            }
        }
        for f in m.indices.chunks_exact(3) {
            let mut tri = [0u32; 3];
            for (k, &i) in f.iter().enumerate() {
                if i as usize >= n_vertices {
                    return Err(format!(
                        "{what}: object `{}` refers to vertex {} but has {n_vertices}",
                        model.name,
                        i + 1
                    ));
                }
                tri[k] = base32 + i;
            }
            mesh.triangles.push(tri);
        }
    }
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

/// The first face corner whose `vt` (`slot` 1) or `vn` (`slot` 2) index names no such
/// entry, as "line N: face corner `a/b/c` refers to vn 7 but the file has 6": tobj reports
/// only that some index was out of bounds. Negative indices count back from the entries
/// read so far (the OBJ specification's relative indices).
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

/// The file as tobj reads it, one line at a time: files written on Windows may start with
/// a UTF-8 byte-order mark, and comments in Latin-1 are common, so the mark is dropped and
/// bytes that are not UTF-8 become U+FFFD (harmless in a comment, still an error in a
/// number; per line as for the whole file, since a newline never belongs to a multi-byte
/// sequence). On the way, the statements tobj is told to ignore are counted.
struct Lines<R> {
    inner: R,
    /// The current line (UTF-8) and how much of it tobj has consumed.
    line: Vec<u8>,
    at: usize,
    first: bool,
    /// Points (`p`) and lines (`l`): not surfaces, counted so the scene can warn that they
    /// were skipped.
    skipped: super::Skipped,
    /// The read error, if any: tobj reports it only as a failed line.
    error: Option<std::io::Error>,
}

/// `bytes` as [`Lines`] reads them: byte-order mark dropped, invalid UTF-8 replaced.
fn lossy_text(bytes: &[u8]) -> String {
    let bytes = bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(bytes);
    String::from_utf8_lossy(bytes).into_owned()
}

impl<R: BufRead> Lines<R> {
    fn new(inner: R) -> Self {
        Lines {
            inner,
            line: Vec::new(),
            at: 0,
            first: true,
            skipped: super::Skipped::default(),
            error: None,
        }
    }

    /// Reads the next line into `self.line` (empty at the end of the file).
    fn next_line(&mut self) -> std::io::Result<()> {
        self.line.clear();
        self.at = 0;
        self.inner.read_until(b'\n', &mut self.line)?;
        if self.first {
            self.first = false;
            if self.line.starts_with(b"\xef\xbb\xbf") {
                self.line.drain(..3);
            }
        }
        if std::str::from_utf8(&self.line).is_err() {
            self.line = String::from_utf8_lossy(&self.line)
                .into_owned()
                .into_bytes();
        }
        let mut words = self
            .line
            .split(u8::is_ascii_whitespace)
            .filter(|w| !w.is_empty());
        match words.next() {
            Some(b"p") => self.skipped.points += 1,
            Some(b"l") => self.skipped.lines += 1,
            _ => {}
        }
        Ok(())
    }
}

impl<R: BufRead> Read for Lines<R> {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        let n = {
            let available = self.fill_buf()?;
            let n = available.len().min(out.len());
            out[..n].copy_from_slice(&available[..n]);
            n
        };
        self.consume(n);
        Ok(n)
    }
}

impl<R: BufRead> BufRead for Lines<R> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        if self.at == self.line.len() {
            if let Err(e) = self.next_line() {
                let kind = e.kind();
                self.error = Some(e);
                return Err(std::io::Error::new(kind, "read error"));
            }
        }
        Ok(&self.line[self.at..])
    }

    fn consume(&mut self, n: usize) {
        self.at = (self.at + n).min(self.line.len());
    }
}
