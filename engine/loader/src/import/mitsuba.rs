//! Mitsuba 3 XML scenes.

use std::path::Path;

use risotto_engine::diagnostics::{SceneError, SceneErrorKind};

use super::{ImportOptions, ImportedScene};

/// Converts a Mitsuba 3 XML scene.
pub fn import(
    path: &Path,
    _text: &str,
    _options: &ImportOptions<'_>,
) -> Result<ImportedScene, SceneError> {
    Err(SceneError::unlocated(
        path,
        SceneErrorKind::InvalidValue,
        "Mitsuba 3 XML scenes are not read by this build",
    ))
}
