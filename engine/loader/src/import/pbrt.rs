//! pbrt-v4 scenes, converted to risotto's TOML (`docs/import-pbrt.md` lists every
//! directive, parameter and convention).
//!
//! A parser of our own (`lexer`, `params`): the `pbrt4` crate (0.2) parses the format
//! but its errors carry no file positions, and every error here must name `file:line:col`.
//! The directives are interpreted as pbrt-v4 does (`src/pbrt/scene.cpp`,
//! `BasicSceneBuilder`): a current transformation matrix (CTM) post-multiplied by each
//! transform directive, a graphics state saved by `AttributeBegin`, named coordinate
//! systems, materials, textures and media, and shapes that take the state current when
//! they are written.

mod convert;
mod lexer;
mod loop_subdiv;
mod materials;
mod media;
mod params;
mod roughness;
mod shapes;
mod spectra;

use std::path::Path;

use risotto_engine::diagnostics::SceneError;

use super::{ImportOptions, ImportedScene};

/// Converts a pbrt-v4 scene (`text` of the file `path`).
pub fn import(
    path: &Path,
    text: &str,
    options: &ImportOptions<'_>,
) -> Result<ImportedScene, SceneError> {
    convert::Converter::new(path, text, options).run()
}

#[cfg(test)]
mod tests;
