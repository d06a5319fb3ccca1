//! Typed, located reading of TOML tables: [`Reader`] (borrowed, used for every section of
//! the scene file) and [`MaterialParams`] (owned, handed to material factories).

use std::ops::Range;
use std::path::PathBuf;
use std::sync::Arc;

use glam::Vec3;
use risotto_components::Rgb;

use super::raw::{Key, Node, Value};
use risotto_engine::diagnostics::{SceneError, SceneErrorKind, Source};

/// Reads the fields of one table (one entity) with located errors.
#[derive(Clone, Copy)]
pub(crate) struct Reader<'a> {
    pub(crate) src: &'a Source,
    pub(crate) node: &'a Node,
    pub(crate) entity: &'a str,
    /// Keys consumed by the scene layer that a factory should not see (e.g. `type`).
    pub(crate) hidden: &'a [&'a str],
}

impl<'a> Reader<'a> {
    pub(crate) fn new(src: &'a Source, node: &'a Node, entity: &'a str) -> Reader<'a> {
        Reader {
            src,
            node,
            entity,
            hidden: &[],
        }
    }

    pub(crate) fn get(&self, key: &str) -> Option<&'a Node> {
        self.node.get(key).map(|(_, v)| v)
    }

    pub(crate) fn has(&self, key: &str) -> bool {
        self.node.get(key).is_some()
    }

    /// A located error about `field` (or the entity itself) at `span`.
    pub(crate) fn error(
        &self,
        kind: SceneErrorKind,
        span: &Range<usize>,
        field: Option<&str>,
        message: impl Into<String>,
    ) -> SceneError {
        self.src
            .error(kind, span, Some(self.entity), field, message)
    }

    /// "expected X, got Y `text`".
    pub(crate) fn wrong_type(&self, field: &str, node: &Node, expected: &str) -> SceneError {
        self.error(
            SceneErrorKind::WrongType,
            &node.span(),
            Some(field),
            format!(
                "expected {expected}, got {} `{}`",
                node.value.type_name(),
                self.src.quote(&node.span())
            ),
        )
    }

    /// "`requirement`, got `text`" for a value of the right type but outside its range.
    pub(crate) fn invalid(&self, field: &str, node: &Node, requirement: &str) -> SceneError {
        self.error(
            SceneErrorKind::InvalidValue,
            &node.span(),
            Some(field),
            format!("{requirement}, got `{}`", self.src.quote(&node.span())),
        )
    }

    /// The error for an absent required key, located at the entity's table.
    pub(crate) fn missing(&self, field: &str, expected: &str) -> SceneError {
        self.error(
            SceneErrorKind::MissingField,
            &self.node.span(),
            Some(field),
            format!("missing required field `{field}` ({expected})"),
        )
    }

    /// Rejects keys outside `allowed` (and the hidden ones), suggesting a near match.
    pub(crate) fn deny_unknown(&self, allowed: &[&str]) -> Result<(), SceneError> {
        for (key, _) in self.node.as_table().unwrap_or(&[]) {
            let name = key.name.as_str();
            if allowed.contains(&name) || self.hidden.contains(&name) {
                continue;
            }
            return Err(self.unknown_key(key, allowed));
        }
        Ok(())
    }

    fn unknown_key(&self, key: &Key, allowed: &[&str]) -> SceneError {
        let span = key.span.clone().unwrap_or_else(|| self.node.span());
        let mut message = format!("unknown field `{}`", key.name);
        if let Some(best) = suggestion(&key.name, allowed) {
            message.push_str(&format!(" (did you mean `{best}`?)"));
        }
        if !allowed.is_empty() {
            let list: Vec<String> = allowed.iter().map(|a| format!("`{a}`")).collect();
            message.push_str(&format!("; allowed here: {}", list.join(", ")));
        }
        self.error(
            SceneErrorKind::UnknownField,
            &span,
            Some(&key.name),
            message,
        )
    }

    /// A number (TOML integer or float) as f64, with its node.
    fn number_of(&self, field: &str, node: &'a Node) -> Result<f64, SceneError> {
        match node.value {
            Value::Integer(i) => Ok(i as f64),
            Value::Float(f) => Ok(f),
            _ => Err(self.wrong_type(field, node, "a number")),
        }
    }

    /// A finite f32 from a node.
    pub(crate) fn f32_of(&self, field: &str, node: &'a Node) -> Result<f32, SceneError> {
        let v = self.number_of(field, node)? as f32;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.invalid(field, node, "must be a finite number (in f32 range)"))
        }
    }

    pub(crate) fn f32_opt(&self, key: &str) -> Result<Option<f32>, SceneError> {
        self.get(key).map(|n| self.f32_of(key, n)).transpose()
    }

    pub(crate) fn f32(&self, key: &str, default: Option<f32>) -> Result<f32, SceneError> {
        match (self.f32_opt(key)?, default) {
            (Some(v), _) => Ok(v),
            (None, Some(d)) => Ok(d),
            (None, None) => Err(self.missing(key, "a number")),
        }
    }

    /// A number that must satisfy `ok`; `requirement` says how ("must be > 0").
    /// A default is returned unchecked.
    pub(crate) fn f32_where(
        &self,
        key: &str,
        default: Option<f32>,
        requirement: &str,
        ok: impl Fn(f32) -> bool,
    ) -> Result<f32, SceneError> {
        let v = self.f32(key, default)?;
        match self.get(key) {
            Some(node) if !ok(v) => Err(self.invalid(key, node, requirement)),
            _ => Ok(v),
        }
    }

    /// An integer with its node.
    pub(crate) fn int_opt(&self, key: &str) -> Result<Option<(i64, &'a Node)>, SceneError> {
        match self.get(key) {
            None => Ok(None),
            Some(node) => match node.value {
                Value::Integer(i) => Ok(Some((i, node))),
                _ => Err(self.wrong_type(key, node, "an integer")),
            },
        }
    }

    /// An integer in `[min, max]`.
    pub(crate) fn int_in(
        &self,
        key: &str,
        default: Option<i64>,
        min: i64,
        max: i64,
    ) -> Result<i64, SceneError> {
        match (self.int_opt(key)?, default) {
            (Some((v, node)), _) => {
                if (min..=max).contains(&v) {
                    Ok(v)
                } else {
                    Err(self.invalid(key, node, &format!("must be in [{min}, {max}]")))
                }
            }
            (None, Some(d)) => Ok(d),
            (None, None) => Err(self.missing(key, "an integer")),
        }
    }

    pub(crate) fn bool(&self, key: &str, default: Option<bool>) -> Result<bool, SceneError> {
        match (self.get(key), default) {
            (Some(node), _) => match node.value {
                Value::Boolean(b) => Ok(b),
                _ => Err(self.wrong_type(key, node, "a boolean")),
            },
            (None, Some(d)) => Ok(d),
            (None, None) => Err(self.missing(key, "a boolean")),
        }
    }

    pub(crate) fn str_opt(&self, key: &str) -> Result<Option<&'a str>, SceneError> {
        match self.get(key) {
            None => Ok(None),
            Some(node) => match &node.value {
                Value::String(s) => Ok(Some(s.as_str())),
                _ => Err(self.wrong_type(key, node, "a string")),
            },
        }
    }

    pub(crate) fn str_req(&self, key: &str) -> Result<&'a str, SceneError> {
        self.str_opt(key)?
            .ok_or_else(|| self.missing(key, "a string"))
    }

    /// An array of exactly three finite numbers.
    fn vec3_of(&self, field: &str, node: &'a Node) -> Result<Vec3, SceneError> {
        let expected = "an array of 3 numbers [x, y, z]";
        let Value::Array(items) = &node.value else {
            return Err(self.wrong_type(field, node, expected));
        };
        if items.len() != 3 {
            return Err(self.invalid(
                field,
                node,
                &format!("expected 3 numbers [x, y, z], got {} elements", items.len()),
            ));
        }
        Ok(Vec3::new(
            self.f32_of(field, &items[0])?,
            self.f32_of(field, &items[1])?,
            self.f32_of(field, &items[2])?,
        ))
    }

    pub(crate) fn vec3_opt(&self, key: &str) -> Result<Option<Vec3>, SceneError> {
        self.get(key).map(|n| self.vec3_of(key, n)).transpose()
    }

    pub(crate) fn vec3(&self, key: &str, default: Option<Vec3>) -> Result<Vec3, SceneError> {
        match (self.vec3_opt(key)?, default) {
            (Some(v), _) => Ok(v),
            (None, Some(d)) => Ok(d),
            (None, None) => Err(self.missing(key, "an array of 3 numbers [x, y, z]")),
        }
    }

    /// A colour: one number (grey) or `[r, g, b]`, every channel finite and >= 0.
    pub(crate) fn rgb_of(&self, field: &str, node: &'a Node) -> Result<Rgb, SceneError> {
        let c = match &node.value {
            Value::Integer(_) | Value::Float(_) => Rgb::splat(self.f32_of(field, node)?),
            Value::Array(items) if items.len() == 3 => Rgb::new(
                self.f32_of(field, &items[0])?,
                self.f32_of(field, &items[1])?,
                self.f32_of(field, &items[2])?,
            ),
            Value::Array(items) => {
                return Err(self.invalid(
                    field,
                    node,
                    &format!(
                        "expected 3 channels [r, g, b], got {} elements",
                        items.len()
                    ),
                ))
            }
            _ => return Err(self.wrong_type(field, node, "a colour [r, g, b] or a number")),
        };
        if c.r < 0.0 || c.g < 0.0 || c.b < 0.0 {
            return Err(self.invalid(field, node, "colour channels must be >= 0"));
        }
        Ok(c)
    }

    pub(crate) fn rgb_opt(&self, key: &str) -> Result<Option<Rgb>, SceneError> {
        self.get(key).map(|n| self.rgb_of(key, n)).transpose()
    }

    /// A light's colour (emission, radiance, irradiance, intensity): as [`Self::rgb_opt`],
    /// and every channel at most [`MAX_RADIANCE`](super::MAX_RADIANCE).
    pub(crate) fn radiance_opt(&self, key: &str) -> Result<Option<Rgb>, SceneError> {
        let Some(node) = self.get(key) else {
            return Ok(None);
        };
        let c = self.rgb_of(key, node)?;
        if c.max_channel() > super::MAX_RADIANCE {
            return Err(self.invalid(
                key,
                node,
                &format!(
                    "channels must be at most {:e}, the largest light value a scene may give \
                     (paths multiply it by weights that can exceed 1, and f32 ends at 3.4e38)",
                    super::MAX_RADIANCE
                ),
            ));
        }
        Ok(Some(c))
    }

    /// [`Self::radiance_opt`] with a default (not checked).
    pub(crate) fn radiance(&self, key: &str, default: Option<Rgb>) -> Result<Rgb, SceneError> {
        match (self.radiance_opt(key)?, default) {
            (Some(v), _) => Ok(v),
            (None, Some(d)) => Ok(d),
            (None, None) => Err(self.missing(key, "a colour [r, g, b]")),
        }
    }

    pub(crate) fn rgb(&self, key: &str, default: Option<Rgb>) -> Result<Rgb, SceneError> {
        match (self.rgb_opt(key)?, default) {
            (Some(v), _) => Ok(v),
            (None, Some(d)) => Ok(d),
            (None, None) => Err(self.missing(key, "a colour [r, g, b]")),
        }
    }

    pub(crate) fn array_opt(&self, key: &str) -> Result<Option<&'a [Node]>, SceneError> {
        match self.get(key) {
            None => Ok(None),
            Some(node) => match &node.value {
                Value::Array(items) => Ok(Some(items.as_slice())),
                _ => Err(self.wrong_type(key, node, "an array")),
            },
        }
    }

    pub(crate) fn table_opt(&self, key: &str) -> Result<Option<&'a Node>, SceneError> {
        match self.get(key) {
            None => Ok(None),
            Some(node) => match &node.value {
                Value::Table(_) => Ok(Some(node)),
                _ => Err(self.wrong_type(key, node, "a table")),
            },
        }
    }

    /// A path string resolved against the scene file's directory and made absolute.
    pub(crate) fn path_opt(&self, key: &str) -> Result<Option<(PathBuf, &'a Node)>, SceneError> {
        let Some(rel) = self.str_opt(key)? else {
            return Ok(None);
        };
        let node = self.get(key).unwrap_or(self.node);
        if rel.is_empty() {
            return Err(self.invalid(key, node, "a path must not be empty"));
        }
        let joined = self.src.dir.join(rel);
        let full = std::path::absolute(&joined).unwrap_or(joined);
        crate::side_file::check(&full).map_err(|message| {
            self.error(
                SceneErrorKind::ExternalFile,
                &node.span(),
                Some(key),
                message,
            )
        })?;
        self.src.files.add(&full);
        Ok(Some((full, node)))
    }
}

/// The closest allowed key within edit distance 2 (or equal ignoring case), if any.
pub(crate) fn suggestion<'k>(key: &str, allowed: &[&'k str]) -> Option<&'k str> {
    allowed
        .iter()
        .map(|a| (edit_distance(&key.to_lowercase(), &a.to_lowercase()), *a))
        .filter(|(d, _)| *d <= 2)
        .min_by_key(|(d, _)| *d)
        .map(|(_, a)| a)
}

/// Levenshtein distance (single-row dynamic programming).
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diag = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let above = row[j + 1];
            row[j + 1] = (above + 1)
                .min(row[j] + 1)
                .min(diag + usize::from(ca != *cb));
            diag = above;
        }
    }
    row[b.len()]
}

/// The parameters of one material (or of a nested table inside one, such as
/// `interior = { type = "beer", sigma_a = [...] }`), kept as raw TOML so that material
/// types registered by users can read whatever keys they define. Every accessor reports
/// errors with the scene file, line, column, the material (`materials.glass`), the key and
/// the offending value.
///
/// The scene layer consumes a material's `type` and `priority` keys (see
/// [`super::MaterialDesc`]); they are hidden from [`MaterialParams::keys`] and
/// [`MaterialParams::deny_unknown`] at the top level. Nested tables hide nothing, so a
/// nested `type` is read with [`MaterialParams::string`].
#[derive(Clone, Debug)]
pub struct MaterialParams {
    src: Arc<Source>,
    node: Node,
    entity: String,
    hidden: &'static [&'static str],
}

impl MaterialParams {
    pub(crate) fn new(
        src: Arc<Source>,
        node: Node,
        entity: String,
        hidden: &'static [&'static str],
    ) -> MaterialParams {
        MaterialParams {
            src,
            node,
            entity,
            hidden,
        }
    }

    pub(super) fn reader(&self) -> Reader<'_> {
        Reader {
            src: &self.src,
            node: &self.node,
            entity: &self.entity,
            hidden: self.hidden,
        }
    }

    /// The entity name used in messages, e.g. `materials.glass` or
    /// `materials.glass.interior`.
    pub fn entity(&self) -> &str {
        &self.entity
    }

    /// The same parameters with the keys every material has (`type`, `priority`,
    /// `opacity`) visible: what the loader reads those through.
    pub(crate) fn with_common_keys(&self) -> MaterialParams {
        MaterialParams {
            hidden: &[],
            ..self.clone()
        }
    }

    /// Whether the key is present.
    pub fn has(&self, key: &str) -> bool {
        !self.hidden.contains(&key) && self.reader().has(key)
    }

    /// Whether the key is present and holds a table (for keys that take either a value or
    /// a table, like a heterogeneous interior's `emission`).
    pub fn is_table(&self, key: &str) -> bool {
        self.has(key)
            && self
                .reader()
                .get(key)
                .is_some_and(|n| n.as_table().is_some())
    }

    /// The keys in file order (without the hidden `type` / `priority` of a material).
    pub fn keys(&self) -> Vec<&str> {
        self.node
            .as_table()
            .unwrap_or(&[])
            .iter()
            .map(|(k, _)| k.name.as_str())
            .filter(|k| !self.hidden.contains(k))
            .collect()
    }

    /// A finite number (TOML integer or float). Absent: `default`, or a missing-field
    /// error if `default` is `None`.
    pub fn f32(&self, key: &str, default: Option<f32>) -> Result<f32, SceneError> {
        self.reader().f32(key, default)
    }

    /// A finite number that must satisfy `ok`; `requirement` completes the message
    /// "`ior` must be > 0, got `-1.5`", e.g. `"must be > 0"`. A default is not checked.
    pub fn f32_where(
        &self,
        key: &str,
        default: Option<f32>,
        requirement: &str,
        ok: impl Fn(f32) -> bool,
    ) -> Result<f32, SceneError> {
        self.reader().f32_where(key, default, requirement, ok)
    }

    /// A finite number in the closed range `[min, max]`.
    pub fn f32_in(
        &self,
        key: &str,
        default: Option<f32>,
        min: f32,
        max: f32,
    ) -> Result<f32, SceneError> {
        self.reader()
            .f32_where(key, default, &format!("must be in [{min}, {max}]"), |v| {
                (min..=max).contains(&v)
            })
    }

    /// A non-negative integer that fits in `u32`.
    pub fn u32(&self, key: &str, default: Option<u32>) -> Result<u32, SceneError> {
        let v = self
            .reader()
            .int_in(key, default.map(i64::from), 0, i64::from(u32::MAX))?;
        // In range by the check above.
        Ok(u32::try_from(v).unwrap_or(u32::MAX))
    }

    /// A boolean.
    pub fn bool(&self, key: &str, default: Option<bool>) -> Result<bool, SceneError> {
        self.reader().bool(key, default)
    }

    /// A string.
    pub fn string(&self, key: &str, default: Option<&str>) -> Result<String, SceneError> {
        match (self.reader().str_opt(key)?, default) {
            (Some(s), _) => Ok(s.to_owned()),
            (None, Some(d)) => Ok(d.to_owned()),
            (None, None) => Err(self.reader().missing(key, "a string")),
        }
    }

    /// A colour, linear Rec.709 RGB: `[r, g, b]` or one number for grey; every channel
    /// finite and >= 0.
    pub fn rgb(&self, key: &str, default: Option<Rgb>) -> Result<Rgb, SceneError> {
        self.reader().rgb(key, default)
    }

    /// A colour that must satisfy `ok` (e.g. every channel <= 1 for an albedo);
    /// `requirement` completes the message. A default is not checked.
    pub fn rgb_where(
        &self,
        key: &str,
        default: Option<Rgb>,
        requirement: &str,
        ok: impl Fn(Rgb) -> bool,
    ) -> Result<Rgb, SceneError> {
        let r = self.reader();
        let v = r.rgb(key, default)?;
        match r.get(key) {
            Some(node) if !ok(v) => Err(r.invalid(key, node, requirement)),
            _ => Ok(v),
        }
    }

    /// Three finite numbers `[x, y, z]` (any sign).
    pub fn vec3(&self, key: &str, default: Option<Vec3>) -> Result<Vec3, SceneError> {
        self.reader().vec3(key, default)
    }

    /// A file path, resolved relative to the scene file's directory and made absolute;
    /// `None` if absent. Existence is not checked. The path joins the scene's
    /// [`ReferencedFiles`](super::ReferencedFiles).
    pub fn path(&self, key: &str) -> Result<Option<PathBuf>, SceneError> {
        Ok(self.reader().path_opt(key)?.map(|(p, _)| p))
    }

    /// The scene's decoded side files: a file named by many entities is read once
    /// ([`risotto_engine::side_files`]).
    pub fn side_files(&self) -> &risotto_engine::side_files::SideFiles {
        &self.src.side_files
    }

    /// Notes a file the material reads that no key names (e.g. a header found next to a
    /// data file), so that split renders hash it ([`ReferencedFiles`](super::ReferencedFiles)).
    pub fn note_file(&self, path: &std::path::Path) {
        self.src.files.add(path);
    }

    /// A nested table, e.g. `interior = { type = "beer", sigma_a = [1, 2, 3] }`, as
    /// parameters of its own (entity `materials.glass.interior`); `None` if absent, an error
    /// if the key holds something other than a table.
    pub fn table(&self, key: &str) -> Result<Option<MaterialParams>, SceneError> {
        Ok(self.reader().table_opt(key)?.map(|node| MaterialParams {
            src: Arc::clone(&self.src),
            node: node.clone(),
            entity: format!("{}.{key}", self.entity),
            hidden: &[],
        }))
    }

    /// Rejects any key not in `known` (besides the hidden ones), naming the key, a close
    /// match if there is one, and the accepted keys. Factories call this to catch typos.
    pub fn deny_unknown(&self, known: &[&str]) -> Result<(), SceneError> {
        self.reader().deny_unknown(known)
    }

    /// A located error for a check of the factory's own, e.g. "`tint` requires `ior`".
    /// With `Some(key)` the error points at that key's value (or at the material if the key
    /// is absent); with `None`, at the material.
    pub fn error(&self, key: Option<&str>, message: impl Into<String>) -> SceneError {
        self.location(key)
            .error(SceneErrorKind::InvalidValue, message)
    }

    /// Where `key`'s value is written (or the material, if `key` is `None` or absent), for
    /// errors of other kinds than [`Self::error`]'s or made later.
    pub fn location(&self, key: Option<&str>) -> super::Location {
        let r = self.reader();
        let span = key
            .and_then(|k| r.get(k))
            .map_or_else(|| self.node.span(), Node::span);
        super::Location::new(&self.src, span, &self.entity, key)
    }
}
