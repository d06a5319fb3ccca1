//! Command-line overrides of scene values, `-D KEY.PATH=VALUE` (Mitsuba's `-D name=value`
//! habit, addressed by the value's TOML path): `-D render.spp=16`,
//! `-D materials.glass.ior=1.33`, `-D shapes.0.radius=2`, `-D 'camera.from=[0, 1, 5]'`.
//!
//! An override replaces (or adds) one value in the parsed document before anything reads
//! it, so it is checked exactly as if the file said it, and its errors quote the argument
//! (the overrides are appended to the [`Source`] text after the file's, one per line).
//!
//! - The path is dot-separated keys; an array of tables (`[[shapes]]`, `[[lights]]`) is
//!   indexed by a number from 0. Missing tables along the path are created, so
//!   `-D render.seed=7` works in a file without `[render]`; an unknown key is then reported
//!   by the section that does not know it, as in a file.
//! - The value is TOML (`16`, `1.33`, `true`, `"a b"`, `[0, 1, 5]`, `{ pattern = ... }`);
//!   a bare word that is not TOML (`dielectric`) is taken as a string.

use super::raw::{parse_document, Key, Node, Value};
use risotto_engine::diagnostics::{SceneError, SceneErrorKind, Source};
use std::ops::Range;

/// Applies the overrides `args` (`KEY.PATH=VALUE`, as given after `-D`) to `root`, the
/// document parsed from `src`'s text; `line_starts[i]` is where [`Source::with_overrides`]
/// put `-D args[i]` in that text.
pub(super) fn apply_overrides(
    src: &Source,
    root: &mut Node,
    args: &[String],
    line_starts: &[usize],
) -> Result<(), SceneError> {
    for (arg, &line) in args.iter().zip(line_starts) {
        apply_one(src, root, arg, line + "-D ".len())?;
    }
    Ok(())
}

/// One override; `at` is the byte offset of `arg`'s first character in `src.text` (after
/// the `-D `; line breaks in `arg` became spaces there, one byte for one).
fn apply_one(src: &Source, root: &mut Node, arg: &str, at: usize) -> Result<(), SceneError> {
    let whole = at..at + arg.len();
    let fail = |span: Range<usize>, message: String| {
        src.error(SceneErrorKind::Syntax, &span, None, None, message)
    };
    let Some(eq) = arg.find('=') else {
        return Err(fail(
            whole,
            "expected KEY.PATH=VALUE (e.g. render.spp=16 or materials.glass.ior=1.33)".into(),
        ));
    };
    let (key, text) = (&arg[..eq], &arg[eq + 1..]);
    let mut segments = Vec::new();
    let mut offset = at;
    for name in key.split('.') {
        let span = offset..offset + name.len();
        offset += name.len() + 1;
        let name = name.trim();
        if name.is_empty() {
            return Err(fail(
                at..at + key.len().max(1),
                format!("`{key}` has an empty key; write KEY.PATH=VALUE"),
            ));
        }
        segments.push((name, span));
    }
    let value_at = at + eq + 1;
    let value = parse_value(text, value_at).map_err(|m| {
        fail(
            value_at..value_at + text.len().max(1),
            format!("value `{}`: {m}", text.trim()),
        )
    })?;
    set_path(root, &segments, 0, value).map_err(|(span, m)| fail(span, m))
}

/// The TOML value `text` (at byte `at` of the source), or a string when it is a bare word
/// that is not TOML. Spans are moved to where `text` sits in the source.
fn parse_value(text: &str, at: usize) -> Result<Node, String> {
    const PREFIX: &str = "v = ";
    match parse_document(&format!("{PREFIX}{text}")) {
        Ok(mut doc) => {
            let Value::Table(entries) = &mut doc.value else {
                unreachable!("a document is a table")
            };
            match entries.pop() {
                Some((key, mut node)) if key.name == "v" && entries.is_empty() => {
                    // `at - PREFIX.len()` can be negative for spans inside the prefix (none
                    // are kept); shift with wrapping arithmetic on the offsets that are.
                    shift_spans(&mut node, at as isize - PREFIX.len() as isize);
                    Ok(node)
                }
                // `x = 1\ny = 2` smuggled in one argument: not one value.
                _ => Err("must be one TOML value".into()),
            }
        }
        Err(e) => {
            let t = text.trim();
            let structured = t.starts_with(['[', '{', '"', '\'']);
            if structured || t.is_empty() {
                Err(format!(
                    "not a TOML value: {}",
                    e.message().trim().lines().collect::<Vec<_>>().join("; ")
                ))
            } else {
                Ok(Node {
                    span: Some(at..at + text.len()),
                    value: Value::String(t.to_owned()),
                })
            }
        }
    }
}

/// Moves every span of `node` (and its keys) by `by` bytes.
fn shift_spans(node: &mut Node, by: isize) {
    let shift = |r: &mut Option<Range<usize>>| {
        if let Some(r) = r {
            *r = r.start.saturating_add_signed(by)..r.end.saturating_add_signed(by);
        }
    };
    shift(&mut node.span);
    match &mut node.value {
        Value::Array(items) => items.iter_mut().for_each(|n| shift_spans(n, by)),
        Value::Table(entries) => {
            for (k, n) in entries {
                shift(&mut k.span);
                shift_spans(n, by);
            }
        }
        _ => {}
    }
}

/// Puts `value` at the path `segments[depth..]` under `node` (the value at
/// `segments[..depth]`), creating missing tables.
fn set_path(
    node: &mut Node,
    segments: &[(&str, Range<usize>)],
    depth: usize,
    value: Node,
) -> Result<(), (Range<usize>, String)> {
    let Some((name, span)) = segments.get(depth) else {
        *node = value;
        return Ok(());
    };
    let here = || {
        let names: Vec<&str> = segments[..depth].iter().map(|(n, _)| *n).collect();
        names.join(".")
    };
    let type_name = node.value.type_name();
    match &mut node.value {
        Value::Table(entries) => {
            let i = match entries.iter().position(|(k, _)| k.name == *name) {
                Some(i) => i,
                None => {
                    let key = Key {
                        span: Some(span.clone()),
                        name: (*name).to_owned(),
                    };
                    let empty = Node {
                        span: Some(span.clone()),
                        value: Value::Table(Vec::new()),
                    };
                    entries.push((key, empty));
                    entries.len() - 1
                }
            };
            set_path(&mut entries[i].1, segments, depth + 1, value)
        }
        Value::Array(items) => {
            let len = items.len();
            match name.parse::<usize>() {
                Ok(i) if i < len => set_path(&mut items[i], segments, depth + 1, value),
                _ => Err((
                    span.clone(),
                    format!(
                        "`{name}`: `{}` has {len} entries, so the index must be a number from 0 \
                         to {}",
                        here(),
                        len.saturating_sub(1)
                    ),
                )),
            }
        }
        _ => Err((
            span.clone(),
            format!(
                "`{name}`: `{}` is {type_name}, not a table or an array",
                here()
            ),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::super::{parse_scene, parse_scene_with, SceneDesc, ShapeGeometry};
    use risotto_engine::diagnostics::SceneError;
    use std::path::Path;

    const FILE: &str = "test-scenes/overridden.toml";

    const SCENE: &str = r#"[materials.white]
type = "diffuse"
reflectance = [0.8, 0.8, 0.8]

[materials.glass]
type = "dielectric"
ior = 1.5

[[shapes]]
type = "sphere"
material = "glass"
center = [0, 1, 0]
radius = 1

[camera]
fov = 40
from = [0, 2, 6]
to = [0, 0.5, 0]
"#;

    fn with(overrides: &[&str]) -> Result<SceneDesc, SceneError> {
        let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        parse_scene_with(SCENE, Path::new(FILE), &o)
    }

    fn err(overrides: &[&str]) -> String {
        match with(overrides) {
            Ok(_) => panic!("{overrides:?} should be refused"),
            Err(e) => e.to_string(),
        }
    }

    fn radius(d: &SceneDesc) -> f32 {
        match d.shapes[0].geometry {
            ShapeGeometry::Sphere { radius, .. } => radius,
            _ => panic!("shape 0 is the sphere"),
        }
    }

    #[test]
    fn overrides_replace_and_add_values() {
        let base = parse_scene(SCENE, Path::new(FILE)).unwrap();
        let d = with(&[
            "render.spp=16",
            "render.seed=7",
            "shapes.0.radius=2.5",
            "camera.from=[0, 3, 9]",
            "materials.glass.type=diffuse",
        ])
        .unwrap_or_else(|e| panic!("{e}"));
        // No [render] in the file: the table is created and both values land in it.
        assert_eq!((d.render.spp, d.render.seed), (16, 7));
        assert_ne!(base.render.spp, 16);
        assert_eq!((radius(&base), radius(&d)), (1.0, 2.5));
        // A bare word is a string.
        let glass = d.materials.iter().find(|m| m.name == "glass").unwrap();
        assert_eq!(glass.type_name, "diffuse");
        // The camera moved: a different view.
        assert_ne!(format!("{:?}", base.camera), format!("{:?}", d.camera));
    }

    #[test]
    fn an_override_is_checked_as_the_file_would_be_and_quoted() {
        // The loader's own range check, located on the argument rather than a file line.
        let m = err(&["render.spp=0"]);
        assert!(m.contains("command-line override `-D render.spp=0`"), "{m}");
        assert!(m.contains("spp"), "{m}");
        assert!(m.contains("-D | -D render.spp=0"), "{m}");
        // Wrong type.
        let m = err(&["shapes.0.radius=big"]);
        assert!(m.contains("`-D shapes.0.radius=big`"), "{m}");
        // An unknown key added by an override is reported by its section.
        let m = err(&["render.sp=4"]);
        assert!(m.contains("`-D render.sp=4`") && m.contains("sp"), "{m}");
        let e = with(&["render.spp=0"]).unwrap_err();
        assert_eq!(e.line(), None, "an override has no file line");
    }

    #[test]
    fn malformed_overrides_are_errors_naming_them() {
        let cases: [(&str, &str); 5] = [
            ("render.spp", "expected KEY.PATH=VALUE"),
            ("render..spp=3", "empty key"),
            ("shapes.3.radius=1", "index must be a number from 0 to 0"),
            (
                "shapes.0.radius.x=1",
                "`shapes.0.radius` is an integer, not a table",
            ),
            ("render.spp=[1,", "not a TOML value"),
        ];
        for (arg, fragment) in cases {
            let m = err(&[arg]);
            assert!(m.contains(fragment), "{arg}: {m}");
            assert!(m.contains(&format!("`-D {arg}`")), "{arg}: {m}");
            assert!(m.starts_with(FILE), "{arg}: {m}");
        }
        // Two values in one argument are not one value.
        let m = err(&["render.spp=4\nseed = 3"]);
        assert!(m.contains("one TOML value"), "{m}");
    }

    #[test]
    fn file_errors_keep_their_lines_with_overrides() {
        let bad = SCENE.replace("radius = 1", "radius = -1");
        let o = vec!["render.spp=4".to_string()];
        let e = parse_scene_with(&bad, Path::new(FILE), &o).unwrap_err();
        assert_eq!(e.line(), Some(13), "{e}");
        // And an override can fix it.
        let o = vec!["shapes.0.radius=1".to_string()];
        assert!(parse_scene_with(&bad, Path::new(FILE), &o).is_ok());
    }
}
