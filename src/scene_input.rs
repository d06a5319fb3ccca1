//! The scene a command reads: a file, or standard input (`-`), with the command line's
//! `-D KEY.PATH=VALUE` overrides and `--size WxH`.

use anyhow::{Context, Result};
use risotto::engine::render::MAX_FILM_PIXELS;
use risotto::engine::scene::Scene;
use risotto::loader::load::{scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::parse_scene_with;
use std::io::Read;
use std::path::{Path, PathBuf};

/// How the scene is named in messages when it comes from standard input; relative paths in
/// it resolve against the current directory.
pub(crate) const STDIN_NAME: &str = "<stdin>";

/// The largest scene text read from standard input (a file is read whole, as the loader
/// does; a pipe that never ends must not exhaust memory).
const MAX_STDIN_BYTES: u64 = 1 << 30;

/// A scene's text, where it came from, and the overrides to apply.
pub(crate) struct SceneInput {
    /// The path messages name (`<stdin>` for `-`), against whose directory relative paths in
    /// the scene resolve.
    pub(crate) path: PathBuf,
    /// The scene text.
    pub(crate) text: String,
    /// `KEY.PATH=VALUE` overrides, applied in order (the later wins).
    pub(crate) overrides: Vec<String>,
}

impl SceneInput {
    /// Reads the scene `arg` (a file, or `-` for standard input) with the `-D` overrides
    /// `defines` and, after them, the image size of `--size WxH`.
    pub(crate) fn read(arg: &Path, defines: &[String], size: Option<&str>) -> Result<Self> {
        let (path, text) = if arg == Path::new("-") {
            let mut text = String::new();
            let read = std::io::stdin()
                .lock()
                .take(MAX_STDIN_BYTES + 1)
                .read_to_string(&mut text)
                .context("cannot read the scene from standard input")?;
            anyhow::ensure!(
                read as u64 <= MAX_STDIN_BYTES,
                "the scene on standard input is larger than {MAX_STDIN_BYTES} bytes"
            );
            (PathBuf::from(STDIN_NAME), text)
        } else {
            let text = std::fs::read_to_string(arg)
                .with_context(|| format!("{}: cannot read scene file", arg.display()))?;
            (arg.to_path_buf(), text)
        };
        let mut overrides = defines.to_vec();
        if let Some(size) = size {
            let (w, h) = parse_size(size)?;
            overrides.push(format!("render.width={w}"));
            overrides.push(format!("render.height={h}"));
        }
        Ok(SceneInput {
            path,
            text,
            overrides,
        })
    }

    /// Parses and builds the scene world with the materials of `registry`.
    pub(crate) fn load(&self, registry: &MaterialRegistry) -> Result<Scene> {
        let desc = parse_scene_with(&self.text, &self.path, &self.overrides)?;
        Ok(scene_from_desc(desc, registry)?)
    }

    /// What identifies the scene's own text for a partial render's hash: the text and every
    /// override, each on its own line after a separator no TOML line can be.
    pub(crate) fn hashed_text(&self) -> Vec<u8> {
        let mut bytes = self.text.clone().into_bytes();
        for o in &self.overrides {
            bytes.extend_from_slice(b"\n\0-D ");
            bytes.extend_from_slice(o.as_bytes());
        }
        bytes
    }

    /// The default output EXR: the scene file's stem in the current directory, `render.exr`
    /// for a scene from standard input.
    pub(crate) fn default_output(&self) -> PathBuf {
        if self.path == Path::new(STDIN_NAME) {
            return PathBuf::from("render.exr");
        }
        let stem = self
            .path
            .file_stem()
            .map_or_else(|| "render".into(), |s| s.to_os_string());
        PathBuf::from(stem).with_extension("exr")
    }
}

/// Parses `--size WxH` (also `W,H` or `WXH`), each side 1 to 65536 and the pixel count
/// within the film's limit, as the scene file's `width` and `height` are checked.
pub(crate) fn parse_size(s: &str) -> Result<(u32, u32)> {
    let bad = || anyhow::anyhow!("--size {s}: expected WIDTHxHEIGHT, e.g. --size 640x480");
    let (w, h) = s.split_once(['x', 'X', ',']).ok_or_else(bad)?;
    let w: u32 = w.trim().parse().map_err(|_| bad())?;
    let h: u32 = h.trim().parse().map_err(|_| bad())?;
    const MAX_SIDE: u32 = 1 << 16;
    anyhow::ensure!(
        (1..=MAX_SIDE).contains(&w) && (1..=MAX_SIDE).contains(&h),
        "--size {s}: each side must be 1 to {MAX_SIDE} pixels"
    );
    anyhow::ensure!(
        u64::from(w) * u64::from(h) <= MAX_FILM_PIXELS,
        "--size {s}: {} pixels, more than the {} a film may have",
        u64::from(w) * u64::from(h),
        MAX_FILM_PIXELS
    );
    Ok((w, h))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_and_are_bounded() {
        assert_eq!(parse_size("640x480").unwrap(), (640, 480));
        assert_eq!(parse_size("32X16").unwrap(), (32, 16));
        assert_eq!(parse_size("8,4").unwrap(), (8, 4));
        for bad in [
            "640",
            "x480",
            "0x10",
            "10x-1",
            "70000x1",
            "65536x65536",
            "axb",
        ] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn overrides_change_the_hashed_text() {
        let a = SceneInput {
            path: PathBuf::from("s.toml"),
            text: "x = 1".into(),
            overrides: vec![],
        };
        let b = SceneInput {
            overrides: vec!["render.spp=2".into()],
            ..SceneInput {
                path: a.path.clone(),
                text: a.text.clone(),
                overrides: vec![],
            }
        };
        assert_ne!(a.hashed_text(), b.hashed_text());
        assert_eq!(a.default_output(), PathBuf::from("s.exr"));
        let stdin = SceneInput {
            path: PathBuf::from(STDIN_NAME),
            ..a
        };
        assert_eq!(stdin.default_output(), PathBuf::from("render.exr"));
    }
}
