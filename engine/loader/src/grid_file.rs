//! Reading density grids: the reference harness's raw float32 + JSON header, and Mitsuba's
//! `.vol` (and, through [`read_grid_named`], OpenVDB: [`crate::grid_file::vdb`]). Each gives a
//! [`DensityGrid`] (x fastest, cell-centred; see [`risotto_systems::grid`]).
//!
//! # Formats
//! - **raw + JSON** (`*.raw`): little-endian float32 values, x fastest
//!   (`value(ix, iy, iz) = data[ix + nx (iy + ny iz)]`), nothing else in the file. The header
//!   is a JSON object in a file next to it with the same stem and extension `.json` (or given
//!   explicitly): `"dims": [nx, ny, nz]` (required, each >= 1); `"dtype"` (optional; when
//!   given it must name `float32` and `little-endian`); `"channels"` (optional, 1 or 3,
//!   default 1: with 3 the values are RGB interleaved per voxel, `3 (ix + nx (iy + ny iz))
//!   + c`, as in a 3-channel `.vol`). Other keys (`bbox_min`, `min`,
//!   `sha256`, ...) are informative and ignored: the grid is placed in its shape's bounds.
//! - **Mitsuba `.vol`** (version 3): bytes `'V' 'O' 'L' 3`; int32 encoding (1 = float32, the
//!   only one accepted); int32 `nx`, `ny`, `nz`; int32 channels (1, or 3 for a density per
//!   RGB channel); six float32 bounding-box values (informative, ignored); then `nx ny nz
//!   channels` float32 values, x fastest and the channel fastest of all. Every number
//!   little-endian; 48 header bytes.
//!
//! A 3-channel grid is read by [`read_grid_channels`] as [`DensityChannels`] (a
//! heterogeneous medium's per-channel density); the readers of one density refuse it.
//!
//! Every value must be finite and >= 0. Sizes are checked against the file's length before
//! anything is allocated; errors name the file and the byte offset (and voxel) of what is
//! wrong, with the value.

use risotto_systems::grid::{voxel_of, DensityChannels, DensityGrid, GridValueError};
use std::path::{Path, PathBuf};

#[cfg(feature = "vdb")]
pub mod vdb;

/// Largest grid accepted (voxels): 2^28, i.e. 1 GiB of float32 (e.g. 640^3).
pub const MAX_VOXELS: usize = 1 << 28;

/// The largest JSON header of a raw grid read (1 MiB; a real one is a line).
const MAX_HEADER_BYTES: u64 = 1 << 20;

/// Bytes before the data of a `.vol` file.
const VOL_HEADER: u64 = 48;

/// A grid file that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum GridFileError {
    /// The file (or its header) cannot be read.
    #[error("{}: cannot read: {cause}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Cause (part of the message, so not also `source()`, which would repeat it).
        cause: std::io::Error,
    },
    /// The file's format is not what it should be (magic, version, encoding, header keys).
    #[error("{}: {message}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong, with the byte offset or key and the value found.
        message: String,
    },
    /// The file's length does not match its dimensions and channel count.
    #[error("{}: {dims:?} voxels of {channels} channel(s) need {expected} bytes, the file has {actual}", path.display())]
    Size {
        /// The file.
        path: PathBuf,
        /// Dimensions.
        dims: [usize; 3],
        /// Values per voxel (1 or 3).
        channels: usize,
        /// Expected length.
        expected: u64,
        /// Actual length.
        actual: u64,
    },
    /// A voxel is negative or not finite.
    #[error("{}: byte {offset}: voxel ({}, {}, {}){}: value {value} is {}", path.display(), voxel[0], voxel[1], voxel[2], channel.map(|c| format!(" channel {c}")).unwrap_or_default(), if value.is_finite() { "negative (densities must be >= 0)" } else { "not finite" })]
    Value {
        /// The file.
        path: PathBuf,
        /// Byte offset of the value.
        offset: u64,
        /// `(ix, iy, iz)`.
        voxel: [usize; 3],
        /// The channel (0 red, 1 green, 2 blue) of a 3-channel grid; `None` for one channel.
        channel: Option<usize>,
        /// The value.
        value: f32,
    },
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> GridFileError + '_ {
    move |cause| GridFileError::Io {
        path: path.to_path_buf(),
        cause,
    }
}

/// A [`GridFileError::Format`] of `path`.
pub(crate) fn format(path: &Path, message: impl Into<String>) -> GridFileError {
    GridFileError::Format {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Reads a grid by extension: `.vol` as Mitsuba's format, anything else as raw float32 with
/// `header` (default: the same path with extension `.json`).
pub fn read_grid(path: &Path, header: Option<&Path>) -> Result<DensityGrid, GridFileError> {
    read_grid_named(path, header, None)
}

/// Whether `path` names an OpenVDB file (extension `.vdb`).
pub fn is_vdb(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("vdb"))
}

/// [`read_grid`], and `.vdb` files as OpenVDB, reading float grid `name`
/// ([`crate::grid_file::vdb::read_vdb`]). One channel only: a 3-channel file is an error
/// (it is read by [`read_grid_channels`] where a density per channel is allowed).
pub fn read_grid_named(
    path: &Path,
    header: Option<&Path>,
    name: Option<&str>,
) -> Result<DensityGrid, GridFileError> {
    match read_grid_channels(path, header, name)? {
        GridChannels::One(g) => Ok(g),
        GridChannels::Three(_) => Err(format(
            path,
            "3 channels: a density per RGB channel is read only as a heterogeneous \
             medium's `density` (here one value per voxel is needed)",
        )),
    }
}

/// A grid file's values: one density, or one per RGB channel.
#[derive(Clone, Debug, PartialEq)]
pub enum GridChannels {
    /// One value per voxel.
    One(DensityGrid),
    /// Three values per voxel (`.vol` with 3 channels, raw with `"channels": 3`).
    Three(DensityChannels),
}

/// [`read_grid_named`], accepting 3-channel `.vol` and raw files as well (OpenVDB files: one
/// float grid).
pub fn read_grid_channels(
    path: &Path,
    header: Option<&Path>,
    name: Option<&str>,
) -> Result<GridChannels, GridFileError> {
    if is_vdb(path) {
        read_vdb(path, name).map(GridChannels::One)
    } else if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("vol"))
    {
        read_vol_channels(path)
    } else {
        let default = path.with_extension("json");
        read_raw_channels(path, header.unwrap_or(&default))
    }
}

/// An OpenVDB file's float grid `name` ([`crate::grid_file::vdb::read_vdb`]).
#[cfg(feature = "vdb")]
fn read_vdb(path: &Path, name: Option<&str>) -> Result<DensityGrid, GridFileError> {
    crate::grid_file::vdb::read_vdb(path, name)
}

/// Without the `vdb` feature an OpenVDB file is an error that says so.
#[cfg(not(feature = "vdb"))]
fn read_vdb(path: &Path, _name: Option<&str>) -> Result<DensityGrid, GridFileError> {
    Err(format(
        path,
        "OpenVDB files are not read by this build (risotto-loader without its `vdb` feature)",
    ))
}

/// Voxel count of `dims`, checked against [`MAX_VOXELS`].
fn voxel_count(path: &Path, what: &str, dims: [usize; 3]) -> Result<usize, GridFileError> {
    if dims.contains(&0) {
        return Err(format(
            path,
            format!("{what}: dimensions {dims:?} contain 0"),
        ));
    }
    dims.iter()
        .try_fold(1usize, |a, &d| a.checked_mul(d))
        .filter(|&n| n <= MAX_VOXELS)
        .ok_or_else(|| {
            format(
                path,
                format!("{what}: dimensions {dims:?} exceed {MAX_VOXELS} voxels"),
            )
        })
}

/// Checks the file length against `dims` voxels of `channels` (1 or 3) values, then reads
/// them as float32 from byte `offset` on (nothing is allocated before the length matches).
fn read_values(
    path: &Path,
    dims: [usize; 3],
    channels: usize,
    offset: u64,
) -> Result<GridChannels, GridFileError> {
    let n = voxel_count(path, "dims", dims)?;
    let size_error = |actual| GridFileError::Size {
        path: path.to_path_buf(),
        dims,
        channels,
        expected: offset + 4 * (n * channels) as u64,
        actual,
    };
    if n.checked_mul(channels).is_none_or(|v| v > MAX_VOXELS) {
        return Err(format(
            path,
            format!("dims: {dims:?} voxels of {channels} channels exceed {MAX_VOXELS} values"),
        ));
    }
    let expected = offset + 4 * (n * channels) as u64;
    let actual = std::fs::metadata(path).map_err(io(path))?.len();
    if actual != expected {
        return Err(size_error(actual));
    }
    // Streamed into the values in blocks, so the file's bytes and the grid are never held
    // at once (a 512^3 grid peaked at twice its 537 MB when the file was read whole).
    let data = {
        use std::io::{Read, Seek, SeekFrom};
        let mut f = std::fs::File::open(path).map_err(io(path))?;
        f.seek(SeekFrom::Start(offset)).map_err(io(path))?;
        let count = n * channels;
        let mut data: Vec<f32> = Vec::with_capacity(count);
        // A multiple of 4 bytes, so no value straddles two blocks.
        let mut block = vec![0u8; (4 * count).min(1 << 20)];
        let mut remaining = 4 * count;
        while remaining > 0 {
            let take = remaining.min(block.len());
            f.read_exact(&mut block[..take]).map_err(|e| {
                if e.kind() == std::io::ErrorKind::UnexpectedEof {
                    // The file shrank after its length was checked.
                    size_error(expected - (remaining - take) as u64)
                } else {
                    io(path)(e)
                }
            })?;
            data.extend(
                block[..take]
                    .chunks_exact(4)
                    .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])),
            );
            remaining -= take;
        }
        data
    };
    let located = |e: GridValueError| match e {
        GridValueError::Value { index, value, .. } => GridFileError::Value {
            path: path.to_path_buf(),
            offset: offset + 4 * index as u64,
            voxel: voxel_of(dims, index / channels),
            channel: (channels > 1).then_some(index % channels),
            value,
        },
        GridValueError::Size { .. } => format(path, e.to_string()),
    };
    if channels == 3 {
        DensityChannels::new(dims, &data)
            .map(GridChannels::Three)
            .map_err(located)
    } else {
        DensityGrid::new(dims, data)
            .map(GridChannels::One)
            .map_err(located)
    }
}

/// Channels other than 1 or 3, as an error at `what` (a byte offset or header key).
fn channel_count(path: &Path, what: &str, channels: i64) -> Result<usize, GridFileError> {
    match channels {
        1 => Ok(1),
        3 => Ok(3),
        _ => Err(format(
            path,
            format!(
                "{what}: {channels} channels, expected 1 (a density) or 3 (a density per RGB \
                 channel)"
            ),
        )),
    }
}

/// [`GridChannels::One`]'s grid, or an error naming the channels found.
fn one(path: &Path, g: GridChannels) -> Result<DensityGrid, GridFileError> {
    match g {
        GridChannels::One(g) => Ok(g),
        GridChannels::Three(_) => Err(format(
            path,
            "3 channels: a density per RGB channel is read with `read_grid_channels`",
        )),
    }
}

/// Reads a one-channel raw float32 grid with its JSON header (see the module docs).
pub fn read_raw(path: &Path, header: &Path) -> Result<DensityGrid, GridFileError> {
    one(path, read_raw_channels(path, header)?)
}

/// Reads a raw float32 grid of 1 or 3 channels with its JSON header (see the module docs).
pub fn read_raw_channels(path: &Path, header: &Path) -> Result<GridChannels, GridFileError> {
    // The header is named by no key when it sits beside the data, so the scene's check of
    // named files has not seen it: a FIFO would block, a device read forever.
    crate::side_file::check(header).map_err(|m| format(header, m))?;
    let size = std::fs::metadata(header).map_err(io(header))?.len();
    if size > MAX_HEADER_BYTES {
        return Err(format(
            header,
            format!(
                "a {size}-byte header; a raw grid's JSON header has at most {MAX_HEADER_BYTES}"
            ),
        ));
    }
    let text = std::fs::read_to_string(header).map_err(io(header))?;
    let json: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format(header, format!("not JSON: {e}")))?;
    let dims = json
        .get("dims")
        .ok_or_else(|| format(header, "missing \"dims\": [nx, ny, nz]"))?;
    let parsed: Option<Vec<usize>> = dims.as_array().and_then(|a| {
        a.iter()
            .map(|v| v.as_u64().and_then(|u| usize::try_from(u).ok()))
            .collect()
    });
    let dims: [usize; 3] = parsed.and_then(|v| v.try_into().ok()).ok_or_else(|| {
        format(
            header,
            format!("\"dims\" must be three non-negative integers [nx, ny, nz], got {dims}"),
        )
    })?;
    if let Some(dtype) = json.get("dtype") {
        let ok = dtype
            .as_str()
            .is_some_and(|s| s.contains("float32") && s.contains("little"));
        if !ok {
            return Err(format(
                header,
                format!("\"dtype\" must be float32, little-endian, got {dtype}"),
            ));
        }
    }
    voxel_count(header, "\"dims\"", dims)?;
    let channels = match json.get("channels") {
        None => 1,
        Some(c) => match c.as_i64() {
            Some(c) => channel_count(header, "\"channels\"", c)?,
            None => {
                return Err(format(
                    header,
                    format!("\"channels\" must be 1 or 3, got {c}"),
                ))
            }
        },
    };
    read_values(path, dims, channels, 0)
}

/// Reads a one-channel Mitsuba `.vol` grid (see the module docs).
pub fn read_vol(path: &Path) -> Result<DensityGrid, GridFileError> {
    one(path, read_vol_channels(path)?)
}

/// Reads a Mitsuba `.vol` grid of 1 or 3 channels (see the module docs).
pub fn read_vol_channels(path: &Path) -> Result<GridChannels, GridFileError> {
    use std::io::Read;
    let mut f = std::fs::File::open(path).map_err(io(path))?;
    let mut h = [0u8; VOL_HEADER as usize];
    let len = f.metadata().map_err(io(path))?.len();
    if len < VOL_HEADER {
        return Err(format(
            path,
            format!("{len} bytes: shorter than the {VOL_HEADER}-byte .vol header"),
        ));
    }
    f.read_exact(&mut h).map_err(io(path))?;
    if &h[0..3] != b"VOL" {
        return Err(format(
            path,
            format!(
                "byte 0: magic {:?}, expected \"VOL\" (a Mitsuba .vol file)",
                String::from_utf8_lossy(&h[0..3])
            ),
        ));
    }
    if h[3] != 3 {
        return Err(format(
            path,
            format!("byte 3: version {}, expected 3", h[3]),
        ));
    }
    let int = |k: usize| i32::from_le_bytes([h[k], h[k + 1], h[k + 2], h[k + 3]]);
    let encoding = int(4);
    if encoding != 1 {
        return Err(format(
            path,
            format!("byte 4: encoding {encoding}, only 1 (float32) is supported"),
        ));
    }
    let mut dims = [0usize; 3];
    for (a, d) in dims.iter_mut().enumerate() {
        let v = int(8 + 4 * a);
        *d = usize::try_from(v).ok().filter(|&d| d > 0).ok_or_else(|| {
            format(
                path,
                format!("byte {}: dimension {} must be >= 1", 8 + 4 * a, v),
            )
        })?;
    }
    let channels = channel_count(path, "byte 20", int(20).into())?;
    drop(f);
    read_values(path, dims, channels, VOL_HEADER)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scratch directory for this test's files, removed when dropped.
    fn dir(name: &str) -> risotto_engine::scratch_dir::ScratchDir {
        risotto_engine::scratch_dir::ScratchDir::new(&format!("grid-{name}"))
    }

    fn floats(v: &[f32]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_le_bytes()).collect()
    }

    fn vol(dims: [i32; 3], channels: i32, values: &[f32]) -> Vec<u8> {
        let mut b = b"VOL\x03".to_vec();
        for v in [1, dims[0], dims[1], dims[2], channels] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend(floats(&[0.0, 0.0, 0.0, 1.0, 1.0, 1.0]));
        b.extend(floats(values));
        b
    }

    #[test]
    fn raw_and_vol_read_the_same_grid() {
        let d = dir("ok");
        let values: Vec<f32> = (0..24).map(|i| i as f32 * 0.25).collect();
        std::fs::write(d.join("g.raw"), floats(&values)).unwrap();
        std::fs::write(
            d.join("g.json"),
            r#"{"dims": [2, 3, 4], "dtype": "float32, little-endian, 1 channel"}"#,
        )
        .unwrap();
        std::fs::write(d.join("g.vol"), vol([2, 3, 4], 1, &values)).unwrap();
        let a = read_grid(&d.join("g.raw"), None).unwrap();
        let b = read_grid(&d.join("g.vol"), None).unwrap();
        assert_eq!(a, b);
        assert_eq!(a.dims(), [2, 3, 4]);
        assert_eq!(a.voxel(1, 2, 3), 23.0 * 0.25);
    }

    /// The header beside a raw grid is named by no scene key: a FIFO there (found by the
    /// file fuzzer, `tests/fuzz_files.rs`) blocked the load forever; a directory or an
    /// oversized header is refused as well, each naming the header.
    #[cfg(unix)]
    #[test]
    fn a_raw_header_that_is_not_a_small_regular_file_is_refused() {
        let d = dir("raw-header");
        std::fs::write(d.join("g.raw"), floats(&[1.0; 24])).unwrap();
        let made = std::process::Command::new("mkfifo")
            .arg(d.join("g.json"))
            .status();
        if made.is_ok_and(|s| s.success()) {
            let e = read_grid(&d.join("g.raw"), None).unwrap_err().to_string();
            assert!(
                e.contains("g.json") && e.contains("not a regular file"),
                "{e}"
            );
        }
        std::fs::create_dir(d.join("h.json")).unwrap();
        let e = read_grid(&d.join("g.raw"), Some(&d.join("h.json")))
            .unwrap_err()
            .to_string();
        assert!(e.contains("h.json") && e.contains("a directory"), "{e}");
        let big = format!("{{\"dims\": [2, 3, 4]}}{}", " ".repeat(1 << 20));
        std::fs::write(d.join("big.json"), big).unwrap();
        let e = read_grid(&d.join("g.raw"), Some(&d.join("big.json")))
            .unwrap_err()
            .to_string();
        assert!(e.contains("big.json") && e.contains("at most"), "{e}");
    }

    #[test]
    fn bad_files_are_located() {
        let d = dir("bad");
        let msg = |r: Result<DensityGrid, GridFileError>| r.unwrap_err().to_string();
        // Wrong size: named with both lengths.
        std::fs::write(d.join("short.raw"), floats(&[0.0; 7])).unwrap();
        std::fs::write(d.join("short.json"), r#"{"dims": [2, 2, 2]}"#).unwrap();
        let m = msg(read_grid(&d.join("short.raw"), None));
        assert!(
            m.contains("short.raw") && m.contains("32 bytes") && m.contains("has 28"),
            "{m}"
        );
        // A negative voxel: byte offset, voxel and value.
        let mut v = vec![0.5f32; 8];
        v[5] = -1.25;
        std::fs::write(d.join("neg.raw"), floats(&v)).unwrap();
        std::fs::write(d.join("neg.json"), r#"{"dims": [2, 2, 2]}"#).unwrap();
        let m = msg(read_grid(&d.join("neg.raw"), None));
        assert!(
            m.contains("neg.raw")
                && m.contains("byte 20")
                && m.contains("voxel (1, 0, 1)")
                && m.contains("-1.25")
                && m.contains("negative"),
            "{m}"
        );
        // NaN in a .vol: the offset counts the header.
        let mut v = vec![0.5f32; 8];
        v[2] = f32::NAN;
        std::fs::write(d.join("nan.vol"), vol([2, 2, 2], 1, &v)).unwrap();
        let m = msg(read_grid(&d.join("nan.vol"), None));
        assert!(m.contains("byte 56") && m.contains("not finite"), "{m}");
        // Bad magic, version, channels; a huge size claimed by a tiny file (no allocation).
        let mut b = vol([2, 2, 2], 1, &[0.0; 8]);
        b[0] = b'X';
        std::fs::write(d.join("magic.vol"), &b).unwrap();
        assert!(msg(read_grid(&d.join("magic.vol"), None)).contains("magic"));
        let mut b = vol([2, 2, 2], 1, &[0.0; 8]);
        b[3] = 2;
        std::fs::write(d.join("version.vol"), &b).unwrap();
        assert!(msg(read_grid(&d.join("version.vol"), None)).contains("version 2"));
        std::fs::write(d.join("rgb.vol"), vol([2, 2, 2], 3, &[0.0; 24])).unwrap();
        assert!(msg(read_grid(&d.join("rgb.vol"), None)).contains("3 channels"));
        std::fs::write(d.join("huge.vol"), vol([60000, 60000, 60000], 1, &[0.0; 8])).unwrap();
        let m = msg(read_grid(&d.join("huge.vol"), None));
        assert!(m.contains("exceed"), "{m}");
        std::fs::write(d.join("big.vol"), vol([100, 100, 100], 1, &[0.0; 8])).unwrap();
        let m = msg(read_grid(&d.join("big.vol"), None));
        assert!(m.contains("4000048 bytes") && m.contains("has 80"), "{m}");
        std::fs::write(d.join("tiny.vol"), b"VOL").unwrap();
        assert!(msg(read_grid(&d.join("tiny.vol"), None)).contains("shorter"));
        // Header problems.
        std::fs::write(d.join("h.raw"), floats(&[0.0; 8])).unwrap();
        std::fs::write(d.join("h.json"), r#"{"dims": [2, 2]}"#).unwrap();
        let m = msg(read_grid(&d.join("h.raw"), None));
        assert!(m.contains("h.json") && m.contains("[2,2]"), "{m}");
        std::fs::write(
            d.join("h.json"),
            r#"{"dims": [2, 2, 2], "dtype": "float64"}"#,
        )
        .unwrap();
        assert!(msg(read_grid(&d.join("h.raw"), None)).contains("float64"));
        let m = msg(read_grid(&d.join("missing.raw"), None));
        assert!(
            m.contains("missing.json") && m.contains("cannot read"),
            "{m}"
        );
    }

    #[test]
    fn three_channel_vol_and_raw_read_the_same_channels() {
        let d = dir("rgb");
        // 2 x 3 x 4 voxels, RGB interleaved.
        let values: Vec<f32> = (0..72).map(|i| i as f32 * 0.125).collect();
        std::fs::write(d.join("c.vol"), vol([2, 3, 4], 3, &values)).unwrap();
        std::fs::write(d.join("c.raw"), floats(&values)).unwrap();
        std::fs::write(d.join("c.json"), r#"{"dims": [2, 3, 4], "channels": 3}"#).unwrap();
        let a = read_grid_channels(&d.join("c.vol"), None, None).unwrap();
        let b = read_grid_channels(&d.join("c.raw"), None, None).unwrap();
        assert_eq!(a, b);
        let GridChannels::Three(g) = a else {
            panic!("3 channels read as one")
        };
        // Voxel (1, 2, 3) = index 23: values 69, 70, 71 (x 0.125), one per channel.
        for c in 0..3 {
            assert_eq!(g.channel(c).voxel(1, 2, 3), (69 + c) as f32 * 0.125);
        }
        // One channel reads as before through the same entry point.
        std::fs::write(d.join("one.vol"), vol([2, 3, 4], 1, &values[..24])).unwrap();
        let one = read_grid_channels(&d.join("one.vol"), None, None).unwrap();
        assert_eq!(
            one,
            GridChannels::One(read_vol(&d.join("one.vol")).unwrap())
        );
    }

    #[test]
    fn bad_channel_counts_and_values_are_located() {
        let d = dir("rgb-bad");
        let msg = |r: Result<GridChannels, GridFileError>| r.unwrap_err().to_string();
        // A channel count other than 1 or 3, in a .vol and in a raw header.
        for channels in [0, 2, 4, -1] {
            std::fs::write(d.join("c.vol"), vol([2, 2, 2], channels, &[0.0; 16])).unwrap();
            let m = msg(read_grid_channels(&d.join("c.vol"), None, None));
            assert!(
                m.contains("c.vol")
                    && m.contains("byte 20")
                    && m.contains(&format!("{channels} channels")),
                "{m}"
            );
        }
        std::fs::write(d.join("r.raw"), floats(&[0.0; 16])).unwrap();
        std::fs::write(d.join("r.json"), r#"{"dims": [2, 2, 2], "channels": 2}"#).unwrap();
        let m = msg(read_grid_channels(&d.join("r.raw"), None, None));
        assert!(m.contains("r.json") && m.contains("2 channels"), "{m}");
        // A header count that disagrees with the file's length (one channel's worth of
        // data under a 3-channel header, and a huge claim): the size error, nothing read.
        std::fs::write(d.join("short.vol"), vol([2, 2, 2], 3, &[0.0; 8])).unwrap();
        let m = msg(read_grid_channels(&d.join("short.vol"), None, None));
        assert!(
            m.contains("3 channel(s) need 144 bytes") && m.contains("has 80"),
            "{m}"
        );
        std::fs::write(d.join("huge.vol"), vol([1000, 1000, 100], 3, &[0.0; 8])).unwrap();
        let m = msg(read_grid_channels(&d.join("huge.vol"), None, None));
        assert!(m.contains("exceed"), "{m}");
        // A negative and a NaN value: byte offset, voxel and channel.
        let mut v = vec![0.5f32; 24];
        v[7] = -3.0; // voxel 2 = (0, 1, 0), green
        std::fs::write(d.join("neg.vol"), vol([2, 2, 2], 3, &v)).unwrap();
        let m = msg(read_grid_channels(&d.join("neg.vol"), None, None));
        assert!(
            m.contains("byte 76") && m.contains("voxel (0, 1, 0) channel 1") && m.contains("-3"),
            "{m}"
        );
        v[7] = 0.5;
        v[23] = f32::NAN;
        std::fs::write(d.join("nan.vol"), vol([2, 2, 2], 3, &v)).unwrap();
        let m = msg(read_grid_channels(&d.join("nan.vol"), None, None));
        assert!(m.contains("channel 2") && m.contains("not finite"), "{m}");
        // The one-density readers refuse a 3-channel file by name.
        std::fs::write(d.join("ok.vol"), vol([2, 2, 2], 3, &[0.5; 24])).unwrap();
        let m = read_grid(&d.join("ok.vol"), None).unwrap_err().to_string();
        assert!(m.contains("ok.vol") && m.contains("3 channels"), "{m}");
    }
}
