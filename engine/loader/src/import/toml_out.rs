//! The converted scene as TOML: sections and entities, each remembering the element or
//! directive it came from, written in the layout of the shipped scenes (one `[[shapes]]`
//! table per shape, nested values inline) with a comment naming each origin.

use std::fmt::Write as _;
use std::ops::Range;

use risotto_engine::diagnostics::Origin;

/// One table of the converted scene and where it came from.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Entity {
    /// The keys and values (nested tables and arrays are written inline).
    pub table: toml::Table,
    /// The element or directive it was converted from (`None`: made up by the importer,
    /// e.g. the default camera).
    pub origin: Option<Origin>,
}

impl Entity {
    /// An empty table converted from `origin`.
    pub fn new(origin: Option<Origin>) -> Entity {
        Entity {
            table: toml::Table::new(),
            origin,
        }
    }

    /// Sets `key` (builder style).
    pub fn with(mut self, key: &str, value: impl Into<toml::Value>) -> Entity {
        self.table.insert(key.to_owned(), value.into());
        self
    }

    /// Sets `key`.
    pub fn set(&mut self, key: &str, value: impl Into<toml::Value>) {
        self.table.insert(key.to_owned(), value.into());
    }
}

/// A whole converted scene, in the sections of `docs/scene-format.md`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TomlScene {
    /// Comment lines written at the top (without `#`): what the scene was converted from,
    /// notes on what the conversion changed.
    pub header: Vec<String>,
    /// `[render]`.
    pub render: Entity,
    /// `[camera]`.
    pub camera: Entity,
    /// `[materials.NAME]` in order (names unique; the importer makes them so).
    pub materials: Vec<(String, Entity)>,
    /// `[objects.NAME]` (instanced shape groups) in order.
    pub objects: Vec<(String, Entity)>,
    /// `[[shapes]]` in order.
    pub shapes: Vec<Entity>,
    /// `[[lights]]` in order.
    pub lights: Vec<Entity>,
}

/// Keys written first in a table, in this order, when present (the rest sorted).
const LEADING_KEYS: &[&str] = &["type", "name", "object", "material", "pattern"];

impl TomlScene {
    /// Whether material `name` (written already) makes a closed shape a volume of its own
    /// without a medium: a `dielectric`, `rough_dielectric` or `interface` (risotto's glass
    /// and index-matched boundaries). Formats that switch media only at a shape's stated
    /// medium interface keep the surrounding medium inside such a shape, which risotto's
    /// nested volumes agree with only where no medium surrounds it (the importers'
    /// `within = "no medium"` statements).
    pub(crate) fn bounds_clear_volume(&self, name: &str) -> bool {
        self.materials
            .iter()
            .find(|(n, _)| n == name)
            .and_then(|(_, m)| m.table.get("type"))
            .and_then(|t| t.as_str())
            .is_some_and(|t| matches!(t, "dielectric" | "rough_dielectric" | "interface"))
    }

    /// The TOML text and, for each entity with an origin, the byte range of its text (for
    /// [`Source::converted`](risotto_engine::diagnostics::Source::converted)).
    pub fn write(&self) -> (String, Vec<(Range<usize>, Origin)>) {
        // A first line outside every entity, so an error about the whole document (its
        // span starts at 0) is not attributed to the first entity's origin.
        let mut out = String::from(
            "# A risotto scene converted from another format; each table names where it was \
             written.\n",
        );
        let mut origins = Vec::new();
        for line in &self.header {
            for l in line.lines() {
                let _ = writeln!(out, "# {l}");
            }
        }
        let mut section = |out: &mut String, header: &str, e: &Entity| {
            if !out.is_empty() {
                out.push('\n');
            }
            let start = out.len();
            if let Some(o) = &e.origin {
                let _ = writeln!(out, "# {}:{}", o.file.display(), o.line);
            }
            let _ = writeln!(out, "{header}");
            write_body(out, &e.table);
            if let Some(o) = &e.origin {
                origins.push((start..out.len(), o.clone()));
            }
        };
        if !self.render.table.is_empty() {
            section(&mut out, "[render]", &self.render);
        }
        if !self.camera.table.is_empty() {
            section(&mut out, "[camera]", &self.camera);
        }
        for (name, e) in &self.materials {
            section(&mut out, &format!("[materials.{}]", key(name)), e);
        }
        for (name, e) in &self.objects {
            section(&mut out, &format!("[objects.{}]", key(name)), e);
        }
        for e in &self.shapes {
            section(&mut out, "[[shapes]]", e);
        }
        for e in &self.lights {
            section(&mut out, "[[lights]]", e);
        }
        (out, origins)
    }
}

/// `key = value` lines of a table, leading keys first.
fn write_body(out: &mut String, table: &toml::Table) {
    let leading = LEADING_KEYS.iter().filter_map(|k| table.get_key_value(*k));
    let rest = table
        .iter()
        .filter(|(k, _)| !LEADING_KEYS.contains(&k.as_str()));
    for (k, v) in leading.chain(rest) {
        let _ = writeln!(out, "{} = {}", key(k), value(v));
    }
}

/// A key, bare when TOML allows it, else quoted.
fn key(name: &str) -> String {
    let bare = !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if bare {
        name.to_owned()
    } else {
        toml::Value::String(name.to_owned()).to_string()
    }
}

/// A value in inline form (tables as `{ k = v }`), floats with enough digits to round-trip
/// and always with a decimal point or exponent, so they read back as floats.
fn value(v: &toml::Value) -> String {
    match v {
        toml::Value::Table(t) => {
            if t.is_empty() {
                return "{}".to_owned();
            }
            let items: Vec<String> = t
                .iter()
                .map(|(k, v)| format!("{} = {}", key(k), value(v)))
                .collect();
            format!("{{ {} }}", items.join(", "))
        }
        toml::Value::Array(a) => {
            let items: Vec<String> = a.iter().map(value).collect();
            format!("[{}]", items.join(", "))
        }
        toml::Value::Float(f) => float(*f),
        other => other.to_string(),
    }
}

/// Shortest text that reads back as the same f64 (Rust's `{:?}` round-trips), in TOML's
/// syntax (`inf`, `nan`, a `.0` on integral values).
fn float(f: f64) -> String {
    if f.is_nan() {
        "nan".to_owned()
    } else if f.is_infinite() {
        if f > 0.0 { "inf" } else { "-inf" }.to_owned()
    } else {
        let s = format!("{f:?}");
        if s.contains(['.', 'e', 'E']) {
            s
        } else {
            format!("{s}.0")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    #[test]
    fn written_scene_reads_back_with_origins_at_each_entity() {
        let o = |line| {
            Some(Origin {
                file: PathBuf::from("s.xml"),
                line,
            })
        };
        let mut inner = toml::Table::new();
        inner.insert("type".into(), "dielectric".into());
        inner.insert("sigma_t".into(), toml::Value::Float(0.1));
        let scene = TomlScene {
            header: vec!["converted from s.xml".into()],
            render: Entity::new(o(3)).with("spp", 16).with("width", 64),
            camera: Entity::new(None)
                .with("fov", 39.5)
                .with("from", vec![0.0, 1.0, 1e-30]),
            materials: vec![(
                "glass.1 x".into(),
                Entity::new(o(7))
                    .with("type", "interface")
                    .with("interior", inner),
            )],
            objects: vec![],
            shapes: vec![Entity::new(o(9))
                .with("type", "sphere")
                .with("material", "glass.1 x")
                .with("radius", 1.0)],
            lights: vec![],
        };
        let (text, origins) = scene.write();
        let parsed: toml::Table = toml::from_str(&text).expect(&text);
        assert_eq!(parsed["render"]["spp"].as_integer(), Some(16));
        assert_eq!(parsed["camera"]["fov"].as_float(), Some(39.5));
        assert_eq!(parsed["camera"]["from"][2].as_float(), Some(1e-30));
        assert_eq!(
            parsed["materials"]["glass.1 x"]["interior"]["sigma_t"].as_float(),
            Some(0.1)
        );
        assert_eq!(parsed["shapes"][0]["radius"].as_float(), Some(1.0));
        // Three origins, each pointing at its own comment line.
        assert_eq!(origins.len(), 3);
        assert!(text[origins[0].0.clone()].starts_with("# s.xml:3\n[render]"));
        assert!(text[origins[1].0.clone()].starts_with("# s.xml:7\n[materials.\"glass.1 x\"]"));
        assert!(text[origins[2].0.clone()].starts_with("# s.xml:9\n[[shapes]]\ntype = \"sphere\""));
    }

    #[test]
    fn floats_round_trip_exactly() {
        for f in [0.1, 1.0 / 3.0, 1e300, -2.5e-310, 7.0, -0.0] {
            let text = format!("x = {}", float(f));
            let t: toml::Table = toml::from_str(&text).unwrap();
            assert_eq!(t["x"].as_float().unwrap().to_bits(), f.to_bits(), "{text}");
        }
    }
}
