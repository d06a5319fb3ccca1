//! pbrt-v4 scenes.

use std::path::Path;

use risotto_engine::diagnostics::{SceneError, SceneErrorKind};

use super::{ImportOptions, ImportedScene};

/// Converts a pbrt-v4 scene.
pub fn import(
    path: &Path,
    _text: &str,
    _options: &ImportOptions<'_>,
) -> Result<ImportedScene, SceneError> {
    Err(SceneError::unlocated(
        path,
        SceneErrorKind::InvalidValue,
        "pbrt-v4 scenes are not read by this build",
    ))
}
