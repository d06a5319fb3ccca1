//! The files a scene names (meshes, grids, textures, environment maps, and for imported
//! formats included scene files and spectra): what may be read, checked before reading.

use std::path::Path;

/// The largest file a scene may name (meshes, grids, textures, environment maps): 16 GiB,
/// documented in `docs/scene-format.md` ("Conventions"). Larger files are refused before
/// anything is read.
pub const MAX_SIDE_FILE_BYTES: u64 = 16 << 30;

/// Checks that `path`, if it exists, is a regular file (after symbolic links) within
/// [`MAX_SIDE_FILE_BYTES`]: `/dev/zero` or a FIFO would be read forever, a directory gives
/// an obscure error later. A missing file passes (its reader reports it). The error is a
/// sentence naming the file.
pub fn check(path: &Path) -> Result<(), String> {
    let Ok(meta) = std::fs::metadata(path) else {
        return Ok(());
    };
    if !meta.is_file() {
        let kind = if meta.is_dir() {
            "a directory"
        } else {
            "not a regular file (a device, FIFO or socket)"
        };
        return Err(format!("`{}` is {kind}", path.display()));
    }
    if meta.len() > MAX_SIDE_FILE_BYTES {
        return Err(format!(
            "`{}` is {} bytes, more than the {MAX_SIDE_FILE_BYTES} a file the scene reads may \
             have",
            path.display(),
            meta.len()
        ));
    }
    Ok(())
}
