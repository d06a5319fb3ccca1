//! A walk over an OpenVDB file's structure that checks every count and size the file
//! declares against the bytes it has, before `vdb-rs` reads it.
//!
//! `vdb-rs` 0.6 allocates what the file says it needs before reading it: a string of the
//! declared length, a metadata blob, `num_compressed_bytes` of a node buffer (an `i64`:
//! one flipped bit asks for petabytes, and an allocation failure aborts the process where no
//! `catch_unwind` reaches), and a Blosc destination of the size written in the Blosc header
//! (whose compressed size `blosc_decompress_ctx` trusts too, reading past the buffer). This
//! walk follows the reader's own order (`vdb-rs` `src/reader.rs`: archive header, grid
//! descriptors, then for the grid read its transform, tree topology and leaf buffers) and
//! refuses any length past the end of the file, any count that the remaining bytes cannot
//! hold, and any Blosc header whose sizes differ from the node's value count. What it lets
//! through, the crate reads with allocations bounded by the file's length (a few times it,
//! for decompressed node buffers, each at most 32^3 values).
//!
//! Byte layout: OpenVDB `io/Archive.cc` (header, descriptors), `tree/RootNode.h`,
//! `InternalNode.h`, `LeafNode.h` and `io/Compression.h` (`readCompressedValues`, the
//! per-node metadata byte and the Blosc / zlib byte counts), as `vdb-rs` reads them.

use std::collections::HashMap;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

/// The first file version `vdb-rs` reads without reaching a `todo!` (UUID as text).
const MIN_VERSION: u32 = 218;
/// From this version on, node masks are compressed and a metadata byte leads each buffer.
const NODE_MASK_COMPRESSION: u32 = 222;
/// Versions `[SELECTIVE_COMPRESSION, NODE_MASK_COMPRESSION)` store one compression byte.
const SELECTIVE_COMPRESSION: u32 = 220;
/// Before this version ZIP was the default compression.
const BLOSC_COMPRESSION: u32 = 223;

/// Compression flags (`io/Compression.h`).
const ZIP: u32 = 0x1;
const ACTIVE_MASK: u32 = 0x2;
const BLOSC: u32 = 0x4;

/// What the walk learnt of one grid's descriptor.
#[derive(Clone, Debug)]
struct Descriptor {
    grid_pos: u64,
    block_pos: u64,
    compression: u32,
    half: bool,
}

/// The archive's header, checked: the version and every grid's descriptor by name.
#[derive(Debug)]
pub(super) struct Archive {
    version: u32,
    grids: HashMap<String, Descriptor>,
}

/// A reader that knows the file's length and refuses to go past it.
struct Bytes {
    inner: BufReader<File>,
    pos: u64,
    len: u64,
}

impl Bytes {
    fn open(path: &Path) -> Result<Self, String> {
        let file = File::open(path).map_err(|e| format!("cannot read: {e}"))?;
        let len = file
            .metadata()
            .map_err(|e| format!("cannot read: {e}"))?
            .len();
        Ok(Bytes {
            inner: BufReader::new(file),
            pos: 0,
            len,
        })
    }

    fn left(&self) -> u64 {
        self.len - self.pos
    }

    /// Checks that `n` bytes (`what`) remain.
    fn need(&self, n: u64, what: &str) -> Result<(), String> {
        if n > self.left() {
            return Err(format!(
                "byte {}: {what} needs {n} bytes, the file has {} left",
                self.pos,
                self.left()
            ));
        }
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], what: &str) -> Result<(), String> {
        self.need(buf.len() as u64, what)?;
        self.inner
            .read_exact(buf)
            .map_err(|e| format!("byte {}: {what}: {e}", self.pos))?;
        self.pos += buf.len() as u64;
        Ok(())
    }

    fn u8(&mut self, what: &str) -> Result<u8, String> {
        let mut b = [0; 1];
        self.read(&mut b, what)?;
        Ok(b[0])
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        let mut b = [0; 4];
        self.read(&mut b, what)?;
        Ok(u32::from_le_bytes(b))
    }

    fn u64(&mut self, what: &str) -> Result<u64, String> {
        let mut b = [0; 8];
        self.read(&mut b, what)?;
        Ok(u64::from_le_bytes(b))
    }

    fn i64(&mut self, what: &str) -> Result<i64, String> {
        Ok(self.u64(what)? as i64)
    }

    /// Skips `n` bytes that must be in the file.
    fn skip(&mut self, n: u64, what: &str) -> Result<(), String> {
        self.need(n, what)?;
        self.seek(self.pos + n, what)
    }

    fn seek(&mut self, to: u64, what: &str) -> Result<(), String> {
        if to > self.len {
            return Err(format!(
                "{what} at byte {to}, past the end of the file ({} bytes)",
                self.len
            ));
        }
        self.inner
            .seek(SeekFrom::Start(to))
            .map_err(|e| format!("{what}: {e}"))?;
        self.pos = to;
        Ok(())
    }

    /// A length-prefixed string (`u32` length), returned as the crate reads it (one `char`
    /// per byte).
    fn string(&mut self, what: &str) -> Result<String, String> {
        let n = self.u32(what)? as u64;
        self.need(n, what)?;
        let mut b = vec![0; n as usize];
        self.read(&mut b, what)?;
        Ok(b.into_iter().map(char::from).collect())
    }

    /// A bit mask of `bits` bits stored as `u64` words; returns the words.
    fn mask(&mut self, bits: usize, what: &str) -> Result<Vec<u64>, String> {
        let words = bits.div_ceil(64);
        let mut b = vec![0; words * 8];
        self.read(&mut b, what)?;
        Ok(b.chunks_exact(8)
            .map(|w| u64::from_le_bytes(w.try_into().expect("8 bytes")))
            .collect())
    }
}

fn ones(mask: &[u64]) -> impl Iterator<Item = usize> + '_ {
    mask.iter().enumerate().flat_map(|(i, &w)| {
        (0..64)
            .filter(move |b| w >> b & 1 == 1)
            .map(move |b| 64 * i + b)
    })
}

fn count_ones(mask: &[u64]) -> usize {
    mask.iter().map(|w| w.count_ones() as usize).sum()
}

/// Walks a metadata block (the crate's `read_metadata`); returns whether it says the grid
/// is stored as half floats.
fn metadata(b: &mut Bytes) -> Result<bool, String> {
    let count = b.u32("metadata count")? as u64;
    // Each entry holds at least three u32 lengths.
    b.need(
        count.saturating_mul(12),
        &format!("{count} metadata entries"),
    )?;
    let mut half = false;
    for _ in 0..count {
        let name = b.string("metadata name")?;
        let kind = b.string("metadata type")?;
        let len = b.u32("metadata length")? as u64;
        let size = match kind.as_str() {
            "bool" => {
                let v = b.u8("metadata value")?;
                if name == "is_saved_as_half_float" {
                    half = v != 0;
                }
                continue;
            }
            "int32" | "float" => 4,
            "int64" => 8,
            "vec3i" => 12,
            // "string" and unknown types: `len` bytes.
            _ => len,
        };
        b.skip(size, &format!("metadata \"{name}\""))?;
    }
    Ok(half)
}

/// Checks the archive header and every grid descriptor of the file at `path`.
pub(super) fn check_archive(path: &Path) -> Result<Archive, String> {
    let mut b = Bytes::open(path)?;
    if b.u64("magic")? != 0x5644_4220 {
        return Err("not an OpenVDB file (no \" BDV\" magic)".into());
    }
    let version = b.u32("file version")?;
    if version < MIN_VERSION {
        return Err(format!(
            "OpenVDB file version {version}; versions from {MIN_VERSION} on are read"
        ));
    }
    b.skip(8, "library version")?;
    if b.u8("grid offsets flag")? != 1 {
        return Err("the file has no grid offsets (not written by OpenVDB 2 or later)".into());
    }
    let mut compression = if version < BLOSC_COMPRESSION {
        ZIP | ACTIVE_MASK
    } else {
        BLOSC | ACTIVE_MASK
    };
    if (SELECTIVE_COMPRESSION..NODE_MASK_COMPRESSION).contains(&version) {
        compression = if b.u8("compression flag")? == 1 {
            ZIP
        } else {
            0
        };
    }
    b.skip(36, "UUID")?;
    metadata(&mut b)?;
    let count = b.u32("grid count")? as u64;
    // A descriptor holds three strings' lengths and three u64 offsets.
    b.need(
        count.saturating_mul(36),
        &format!("{count} grid descriptors"),
    )?;
    let mut grids = HashMap::new();
    for _ in 0..count {
        let name = b.string("grid name")?;
        b.string("grid type")?;
        b.string("instance parent")?;
        let grid_pos = b.u64("grid offset")?;
        let block_pos = b.u64("block offset")?;
        let end_pos = b.u64("end offset")?;
        let what = format!("grid \"{name}\"");
        b.seek(grid_pos, &what)?;
        let mut c = compression;
        if version >= NODE_MASK_COMPRESSION {
            c = b.u32("grid compression")?;
            if c > (ZIP | ACTIVE_MASK | BLOSC) {
                return Err(format!("{what}: compression flags {c} are not OpenVDB's"));
            }
        }
        let half = metadata(&mut b)?;
        b.seek(block_pos, &format!("{what}: leaf data"))?;
        b.seek(end_pos, &format!("{what}: end"))?;
        let d = Descriptor {
            grid_pos,
            block_pos,
            compression: c,
            half,
        };
        if grids.insert(name.clone(), d).is_some() {
            return Err(format!("two grids are named \"{name}\""));
        }
    }
    Ok(Archive { version, grids })
}

/// Checks the transform, tree topology and leaf buffers of float grid `name` (a name
/// [`check_archive`] found) of the file at `path`.
pub(super) fn check_float_grid(path: &Path, archive: &Archive, name: &str) -> Result<(), String> {
    let d = archive
        .grids
        .get(name)
        .ok_or_else(|| format!("no grid named \"{name}\""))?;
    let what = format!("grid \"{name}\"");
    let walk = Walk {
        version: archive.version,
        d,
    };
    let mut b = Bytes::open(path)?;
    b.seek(d.grid_pos, &what)?;
    if archive.version >= NODE_MASK_COMPRESSION {
        b.u32("grid compression")?;
    }
    metadata(&mut b)?;
    let map = b.string("transform type")?;
    let vectors = match map.as_str() {
        "UniformScaleMap" => 5,
        "UniformScaleTranslateMap" | "ScaleTranslateMap" => 6,
        other => {
            return Err(format!(
                "{what}: transform \"{other}\" is not read (only scale and translate maps)"
            ))
        }
    };
    b.skip(vectors * 24, "transform")?;
    if b.u32("buffer count")? != 1 {
        return Err(format!("{what}: multi-buffer trees are not read"));
    }
    b.skip(4, "background")?;
    let tiles = b.u32("root tile count")? as u64;
    let roots = b.u32("root child count")? as u64;
    // A root tile: origin, value, active flag; a root child: origin and two 4096-byte masks.
    b.skip(tiles.saturating_mul(17), &format!("{tiles} root tiles"))?;
    b.need(
        roots.saturating_mul(12 + 8192),
        &format!("{roots} root children"),
    )?;
    let mut leaves = 0u64;
    for _ in 0..roots {
        b.skip(12, "node origin")?;
        let children5 = walk.internal(&mut b, 5)?;
        for _ in 0..children5 {
            let children4 = walk.internal(&mut b, 4)?;
            // Each leaf's value mask, repeated before its buffer.
            b.skip(children4 as u64 * 64, "leaf masks")?;
            leaves += children4 as u64;
        }
    }
    b.seek(d.block_pos, &format!("{what}: leaf data"))?;
    b.need(leaves.saturating_mul(64), &format!("{leaves} leaves"))?;
    for _ in 0..leaves {
        let mask = b.mask(512, "leaf value mask")?;
        if archive.version < NODE_MASK_COMPRESSION {
            b.skip(12, "leaf origin")?;
            if b.u8("leaf buffer count")? != 1 {
                return Err(format!("{what}: multi-buffer leaves are not read"));
            }
        }
        walk.values(&mut b, 512, &mask)?;
    }
    Ok(())
}

/// The grid's version and descriptor, for the node walks.
struct Walk<'a> {
    version: u32,
    d: &'a Descriptor,
}

impl Walk<'_> {
    /// An internal node of `8^log2` children (masks and buffer); returns its child count.
    fn internal(&self, b: &mut Bytes, log2: u32) -> Result<usize, String> {
        let n = 1usize << (3 * log2);
        let children = b.mask(n, "child mask")?;
        let values = b.mask(n, "value mask")?;
        let stored = if self.version < NODE_MASK_COMPRESSION {
            n - count_ones(&children)
        } else {
            n
        };
        self.values(b, stored, &values)?;
        Ok(count_ones(&children))
    }

    /// A node's value buffer of `n` values (the crate's `read_compressed`).
    fn values(&self, b: &mut Bytes, n: usize, value_mask: &[u64]) -> Result<(), String> {
        let mut meta = 6; // all values stored
        if self.version >= NODE_MASK_COMPRESSION {
            meta = b.u8("node metadata")?;
            if meta > 6 {
                return Err(format!(
                    "byte {}: node metadata {meta} is not OpenVDB's (0..=6)",
                    b.pos - 1
                ));
            }
        }
        // One or two inactive values (f32, the grid's value type), then a selection mask.
        match meta {
            2 | 4 => b.skip(4, "inactive value")?,
            5 => b.skip(8, "inactive values")?,
            _ => {}
        }
        if matches!(meta, 3..=5) {
            b.skip(n.div_ceil(64) as u64 * 8, "selection mask")?;
        }
        let c = self.d.compression;
        let count = if c & ACTIVE_MASK != 0 && meta != 6 && self.version >= NODE_MASK_COMPRESSION {
            ones(value_mask).filter(|&i| i < n).count()
        } else {
            n
        };
        let size: u64 = if self.d.half { 2 } else { 4 };
        let expected = count as u64 * size;
        if c & (BLOSC | ZIP) == 0 {
            return b.skip(expected, "node values");
        }
        let at = b.pos;
        let bytes = b.i64("compressed size")?;
        if bytes <= 0 {
            // Stored uncompressed: `-bytes` of them.
            let stored = bytes.unsigned_abs() / size;
            if stored != count as u64 {
                return Err(format!(
                    "byte {at}: a node of {count} values stores {stored} uncompressed"
                ));
            }
            return b.skip(stored * size, "node values");
        }
        let bytes = bytes as u64;
        b.need(bytes, "compressed node values")?;
        if c & BLOSC != 0 && count > 0 {
            // The Blosc header: version, versionlz, flags, typesize, then u32 nbytes
            // (decompressed), blocksize, cbytes (compressed, header included).
            if bytes < 16 {
                return Err(format!("byte {at}: a Blosc buffer of {bytes} bytes"));
            }
            let mut h = [0u8; 16];
            b.read(&mut h, "Blosc header")?;
            let word = |i: usize| u32::from_le_bytes(h[i..i + 4].try_into().expect("4")) as u64;
            let (nbytes, cbytes) = (word(4), word(12));
            if nbytes != expected || cbytes > bytes || cbytes < 16 {
                return Err(format!(
                    "byte {at}: Blosc header says {nbytes} bytes from {cbytes}, a node of \
                     {count} values has {expected} from a {bytes}-byte buffer"
                ));
            }
            return b.skip(bytes - 16, "compressed node values");
        }
        b.skip(bytes, "compressed node values")
    }
}
