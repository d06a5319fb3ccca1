//! Scenes in other formats: Mitsuba 3 XML ([`mitsuba`]) and pbrt-v4 ([`pbrt`]), converted
//! into risotto's TOML scene, which is then read like any TOML scene file.
//!
//! Why convert to TOML text rather than build a [`SceneDesc`](crate::scene_file::SceneDesc)
//! directly: TOML stays the one complete format (whatever an import can express, a TOML
//! file can), `risotto convert` writes exactly what `risotto render` reads, so the two give
//! byte-identical images, and every check of the TOML loader applies to imports unchanged.
//! The converted text carries the origin of each part ([`TomlScene`]), so an error the TOML
//! loader finds in it is reported at the original file and line
//! ([`Source::converted`](risotto_engine::diagnostics::Source::converted)).
//!
//! Command-line definitions (`-D name=value`) go to the importer when the name has no dot
//! (Mitsuba's `$name` parameters); a name with a dot is a TOML override applied to the
//! converted scene (`-D render.spp=16`), as for TOML scene files.

pub mod mitsuba;
pub mod pbrt;
pub mod spectrum;
mod toml_out;

use std::path::{Path, PathBuf};

pub use toml_out::{Entity, TomlScene};

use risotto_engine::diagnostics::{Origin, SceneError};

/// The formats a scene file can be written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneFormat {
    /// risotto's own TOML (`docs/scene-format.md`).
    Toml,
    /// Mitsuba 3 XML (`<scene version="3.0.0">`).
    MitsubaXml,
    /// pbrt-v4's scene description.
    Pbrt,
}

impl SceneFormat {
    /// The format of a scene file: by extension (`.xml`, `.pbrt`; anything else is TOML),
    /// and for a file without one (standard input), by its first non-blank character: `<`
    /// is XML, an uppercase letter begins a pbrt directive, anything else is TOML.
    pub fn detect(path: &Path, text: &str) -> SceneFormat {
        match path.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("xml") => return SceneFormat::MitsubaXml,
            Some(e) if e.eq_ignore_ascii_case("pbrt") => return SceneFormat::Pbrt,
            Some(_) => return SceneFormat::Toml,
            None => {}
        }
        // Skip blank lines and comments of either kind before deciding.
        let first = text
            .lines()
            .map(|l| l.trim_start_matches('\u{feff}').trim())
            .find(|l| !l.is_empty() && !l.starts_with('#'));
        match first.and_then(|l| l.chars().next()) {
            Some('<') => SceneFormat::MitsubaXml,
            Some(c) if c.is_ascii_uppercase() && !first.is_some_and(|l| l.contains('=')) => {
                SceneFormat::Pbrt
            }
            _ => SceneFormat::Toml,
        }
    }
}

/// What an importer is given besides the text.
#[derive(Clone, Debug)]
pub struct ImportOptions<'a> {
    /// `-D name=value` definitions for the importer (names without a dot; see the module
    /// documentation), in command-line order.
    pub defines: &'a [(String, String)],
    /// The directory the TOML is to live in: relative paths in the converted scene are
    /// written relative to it (`risotto convert` writes elsewhere than the scene's own
    /// directory; `render` reads the conversion in place).
    pub toml_dir: &'a Path,
}

/// A converted scene.
#[derive(Clone, Debug)]
pub struct ImportedScene {
    /// The scene as risotto TOML, with the origin of each part.
    pub scene: TomlScene,
    /// What the conversion did that a user should know without it being an error (an AOV
    /// integrator unwrapped, a parameter with no effect on the image ignored).
    pub warnings: Vec<String>,
}

/// `-D name=value` definitions for an importer, in command-line order.
pub type Defines = Vec<(String, String)>;

/// Splits `-D` arguments into the importer's definitions (no dot in the name) and TOML
/// overrides of the converted scene (a dotted path). An argument without `=` is an error
/// naming it.
pub fn split_defines(path: &Path, args: &[String]) -> Result<(Defines, Vec<String>), SceneError> {
    let mut defines = Vec::new();
    let mut overrides = Vec::new();
    for arg in args {
        let Some((name, value)) = arg.split_once('=') else {
            return Err(SceneError::unlocated(
                path,
                risotto_engine::diagnostics::SceneErrorKind::InvalidValue,
                &format!("command-line definition `-D {arg}` has no `=` (write -D name=value)"),
            ));
        };
        if name.contains('.') {
            overrides.push(arg.clone());
        } else {
            defines.push((name.trim().to_owned(), value.to_owned()));
        }
    }
    Ok((defines, overrides))
}

/// Converts the scene `text` of `path` in `format` (not [`SceneFormat::Toml`]).
pub fn import_scene(
    format: SceneFormat,
    path: &Path,
    text: &str,
    options: &ImportOptions<'_>,
) -> Result<ImportedScene, SceneError> {
    match format {
        SceneFormat::MitsubaXml => mitsuba::import(path, text, options),
        SceneFormat::Pbrt => pbrt::import(path, text, options),
        SceneFormat::Toml => Err(SceneError::unlocated(
            path,
            risotto_engine::diagnostics::SceneErrorKind::InvalidValue,
            "is already a risotto TOML scene (nothing to convert)",
        )),
    }
}

/// `file` written for a TOML scene in `toml_dir`: relative to it when `file` lies below it
/// (the common case: the conversion sits beside its scene), else absolute. Importers write
/// every path through this.
pub fn path_for_toml(file: &Path, toml_dir: &Path) -> String {
    let abs = |p: &Path| -> PathBuf {
        let p = if p.is_absolute() {
            p.to_path_buf()
        } else {
            std::env::current_dir().unwrap_or_default().join(p)
        };
        // Lexical normalisation only (`a/./b`, `a/x/../b`): the files may not exist yet.
        let mut out = PathBuf::new();
        for c in p.components() {
            match c {
                std::path::Component::CurDir => {}
                std::path::Component::ParentDir => {
                    out.pop();
                }
                other => out.push(other),
            }
        }
        out
    };
    let (file_abs, dir_abs) = (abs(file), abs(toml_dir));
    match file_abs.strip_prefix(&dir_abs) {
        Ok(rel) => rel.to_string_lossy().replace('\\', "/"),
        Err(_) => file_abs.to_string_lossy().into_owned(),
    }
}

/// The origin `file:line` of a part of a converted scene.
pub fn origin(file: &Path, line: usize) -> Origin {
    Origin {
        file: file.to_path_buf(),
        line,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_are_told_by_extension_then_by_content() {
        let d = |p: &str, t: &str| SceneFormat::detect(Path::new(p), t);
        assert_eq!(d("a.xml", ""), SceneFormat::MitsubaXml);
        assert_eq!(d("a.XML", ""), SceneFormat::MitsubaXml);
        assert_eq!(d("a.pbrt", ""), SceneFormat::Pbrt);
        assert_eq!(d("a.toml", "<scene>"), SceneFormat::Toml);
        assert_eq!(
            d("<stdin>", "\n  <?xml version='1.0'?>"),
            SceneFormat::MitsubaXml
        );
        assert_eq!(
            d("<stdin>", "# c\nLookAt 0 0 0  0 0 1  0 1 0"),
            SceneFormat::Pbrt
        );
        assert_eq!(d("<stdin>", "# c\n[render]\nspp = 4"), SceneFormat::Toml);
        assert_eq!(d("<stdin>", "Key = 1"), SceneFormat::Toml);
    }

    #[test]
    fn paths_are_written_relative_to_the_toml_when_below_it() {
        let dir = Path::new("/s/scenes");
        assert_eq!(
            path_for_toml(Path::new("/s/scenes/m/a.obj"), dir),
            "m/a.obj"
        );
        assert_eq!(
            path_for_toml(Path::new("/s/scenes/./m/../b.ply"), dir),
            "b.ply"
        );
        assert_eq!(
            path_for_toml(Path::new("/elsewhere/c.exr"), dir),
            "/elsewhere/c.exr"
        );
    }

    #[test]
    fn dotless_definitions_go_to_the_importer() {
        let (d, o) = split_defines(
            Path::new("s.xml"),
            &["spp=16".into(), "render.spp=8".into(), "name=a=b".into()],
        )
        .unwrap();
        assert_eq!(
            d,
            vec![("spp".into(), "16".into()), ("name".into(), "a=b".into())]
        );
        assert_eq!(o, vec!["render.spp=8".to_string()]);
        assert!(split_defines(Path::new("s.xml"), &["spp".into()]).is_err());
    }
}
