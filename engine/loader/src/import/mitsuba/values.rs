//! Typed properties of a Mitsuba plugin element (`<float>`, `<integer>`, `<boolean>`,
//! `<string>`, `<rgb>`, `<spectrum>`, `<point>`, `<vector>`, `<transform>`, nested and
//! referenced objects), read as Mitsuba reads them, with the record of which were queried:
//! Mitsuba refuses a plugin with unqueried properties, and so does the importer
//! ([`Props::finish`]), except those listed as not changing the image (then a warning).

use std::cell::RefCell;
use std::rc::Rc;

use risotto_engine::diagnostics::{SceneError, SceneErrorKind};

use super::transform::Transform;
use super::xml::{Document, Node};
use crate::import::spectrum::{sampled_to_rgb, SpectrumUse};

/// Parameters that choose only how an output file is written (risotto writes its own
/// EXR): accepted without a word.
const SILENT: &[&str] = &["pixel_format", "component_format", "file_format"];

/// A colour input: a constant RGB or a texture element.
#[derive(Clone, Debug)]
pub enum Colour {
    /// Linear Rec.709 RGB.
    Rgb([f64; 3]),
    /// A `<texture>` (nested or referenced).
    Texture(Rc<Node>),
}

/// The conversion state shared by every plugin: the document and the warnings.
pub struct Cx {
    /// The document.
    pub doc: Document,
    /// Warnings so far.
    pub warnings: RefCell<Vec<String>>,
}

impl Cx {
    /// Adds a warning located at `node`.
    pub fn warn(&self, node: &Node, message: impl AsRef<str>) {
        let (file, line) = self.doc.origin(node);
        self.warnings
            .borrow_mut()
            .push(format!("{}:{line}: {}", file.display(), message.as_ref()));
    }

    /// A located error at `node` about the plugin `entity`.
    pub fn error(
        &self,
        node: &Node,
        field: Option<&str>,
        message: impl Into<String>,
    ) -> SceneError {
        self.doc.error(
            node,
            SceneErrorKind::InvalidValue,
            Some(&describe(node)),
            field,
            message,
        )
    }

    /// `node` itself, or the element a `<ref>` names.
    pub fn deref(&self, node: &Rc<Node>) -> Result<Rc<Node>, SceneError> {
        if node.tag != "ref" {
            return Ok(node.clone());
        }
        let Some(id) = node.attr("id") else {
            return Err(self.error(node, Some("id"), "<ref> needs an `id`"));
        };
        self.doc.ids.get(id).cloned().ok_or_else(|| {
            self.doc.error(
                node,
                SceneErrorKind::UnknownReference,
                None,
                Some("id"),
                format!("<ref id=\"{id}\"> names no element (no element has this id)"),
            )
        })
    }
}

/// `bsdf "white" (diffuse)`-style name of a plugin element for messages.
pub fn describe(node: &Node) -> String {
    let mut s = node.tag.clone();
    if let Some(id) = node.attr("id") {
        s.push_str(&format!(" \"{id}\""));
    }
    if let Some(t) = node.attr("type") {
        s.push_str(&format!(" ({t})"));
    }
    s
}

/// The properties of one plugin element.
pub struct Props<'a> {
    /// The conversion state.
    pub cx: &'a Cx,
    /// The plugin element.
    pub node: Rc<Node>,
    used: RefCell<Vec<bool>>,
}

impl<'a> Props<'a> {
    /// The properties of `node` (a `<ref>` is followed first).
    pub fn new(cx: &'a Cx, node: &Rc<Node>) -> Result<Props<'a>, SceneError> {
        let node = cx.deref(node)?;
        let n = node.children.len();
        Ok(Props {
            cx,
            node,
            used: RefCell::new(vec![false; n]),
        })
    }

    /// The plugin's `type` attribute.
    pub fn kind(&self) -> Result<String, SceneError> {
        self.node.attr("type").map(str::to_owned).ok_or_else(|| {
            self.cx.error(
                &self.node,
                Some("type"),
                format!("<{}> needs a `type`", self.node.tag),
            )
        })
    }

    /// A located error at the plugin.
    pub fn error(&self, field: Option<&str>, message: impl Into<String>) -> SceneError {
        self.cx.error(&self.node, field, message)
    }

    /// A located error at one property element.
    fn error_at(&self, prop: &Node, field: &str, message: impl Into<String>) -> SceneError {
        self.cx.doc.error(
            prop,
            SceneErrorKind::InvalidValue,
            Some(&describe(&self.node)),
            Some(field),
            message,
        )
    }

    /// The child named `name` (marked as queried).
    fn named(&self, name: &str) -> Option<Rc<Node>> {
        let i = self
            .node
            .children
            .iter()
            .position(|c| c.attr("name") == Some(name))?;
        self.used.borrow_mut()[i] = true;
        Some(self.node.children[i].clone())
    }

    /// The tag of property `name` (after following a `<ref>`), without marking it read.
    pub fn tag_of(&self, name: &str) -> Option<String> {
        let c = self
            .node
            .children
            .iter()
            .find(|c| c.attr("name") == Some(name))?;
        Some(
            self.cx
                .deref(c)
                .map_or_else(|_| c.tag.clone(), |n| n.tag.clone()),
        )
    }

    /// Whether a property `name` is given.
    pub fn has(&self, name: &str) -> bool {
        self.node
            .children
            .iter()
            .any(|c| c.attr("name") == Some(name))
    }

    /// The `value` attribute of a property element.
    fn value<'n>(&self, prop: &'n Node, name: &str) -> Result<&'n str, SceneError> {
        prop.attr("value")
            .ok_or_else(|| self.error_at(prop, name, format!("<{}> has no `value`", prop.tag)))
    }

    /// A number (`<float>` or `<integer>`).
    pub fn float(&self, name: &str) -> Result<Option<f64>, SceneError> {
        let Some(p) = self.named(name) else {
            return Ok(None);
        };
        if p.tag != "float" && p.tag != "integer" {
            return Err(self.wrong_type(&p, name, "a <float>"));
        }
        parse_number(self.value(&p, name)?)
            .map(Some)
            .map_err(|m| self.error_at(&p, name, m))
    }

    /// A number with a default.
    pub fn float_or(&self, name: &str, default: f64) -> Result<f64, SceneError> {
        Ok(self.float(name)?.unwrap_or(default))
    }

    /// An `<integer>`.
    pub fn int(&self, name: &str) -> Result<Option<i64>, SceneError> {
        let Some(p) = self.named(name) else {
            return Ok(None);
        };
        if p.tag != "integer" {
            return Err(self.wrong_type(&p, name, "an <integer>"));
        }
        let v = self.value(&p, name)?;
        v.trim()
            .parse::<i64>()
            .map(Some)
            .map_err(|_| self.error_at(&p, name, format!("`{v}` is not an integer")))
    }

    /// A `<boolean>`.
    pub fn boolean(&self, name: &str) -> Result<Option<bool>, SceneError> {
        let Some(p) = self.named(name) else {
            return Ok(None);
        };
        if p.tag != "boolean" {
            return Err(self.wrong_type(&p, name, "a <boolean>"));
        }
        let v = self.value(&p, name)?;
        match v.trim().to_ascii_lowercase().as_str() {
            "true" => Ok(Some(true)),
            "false" => Ok(Some(false)),
            _ => Err(self.error_at(&p, name, format!("`{v}` is not true or false"))),
        }
    }

    /// A `<string>`.
    pub fn string(&self, name: &str) -> Result<Option<String>, SceneError> {
        let Some(p) = self.named(name) else {
            return Ok(None);
        };
        if p.tag != "string" {
            return Err(self.wrong_type(&p, name, "a <string>"));
        }
        Ok(Some(self.value(&p, name)?.to_owned()))
    }

    /// A `<point>` or `<vector>`: `x`, `y`, `z` attributes (each default 0) or `value`.
    pub fn vec3(&self, name: &str) -> Result<Option<[f64; 3]>, SceneError> {
        let Some(p) = self.named(name) else {
            return Ok(None);
        };
        if p.tag != "point" && p.tag != "vector" {
            return Err(self.wrong_type(&p, name, "a <point> or <vector>"));
        }
        xyz(&p, 0.0)
            .map(Some)
            .map_err(|m| self.error_at(&p, name, m))
    }

    /// A colour: `<rgb>`, `<spectrum>` (one value or `wavelength:value` pairs, converted
    /// for `use_`), a `<float>` (grey), or a texture (nested or `<ref>`).
    pub fn colour(&self, name: &str, use_: SpectrumUse) -> Result<Option<Colour>, SceneError> {
        let Some(p) = self.named(name) else {
            return Ok(None);
        };
        let p = self.cx.deref(&p)?;
        match p.tag.as_str() {
            "rgb" => {
                let v = self.value(&p, name)?;
                let n = parse_list(v).map_err(|m| self.error_at(&p, name, m))?;
                match n[..] {
                    [g] => Ok(Some(Colour::Rgb([g; 3]))),
                    [r, g, b] => Ok(Some(Colour::Rgb([r, g, b]))),
                    _ => Err(self.error_at(
                        &p,
                        name,
                        format!("<rgb value=\"{v}\"> needs 1 or 3 numbers"),
                    )),
                }
            }
            "float" | "integer" => {
                let v =
                    parse_number(self.value(&p, name)?).map_err(|m| self.error_at(&p, name, m))?;
                Ok(Some(Colour::Rgb([v; 3])))
            }
            "spectrum" => self.spectrum(&p, name, use_).map(|c| Some(Colour::Rgb(c))),
            "texture" => Ok(Some(Colour::Texture(p))),
            _ => Err(self.wrong_type(
                &p,
                name,
                "a colour (<rgb>, <spectrum>, <float> or <texture>)",
            )),
        }
    }

    /// A `<spectrum>` property as RGB (see [`crate::import::spectrum`]): one number is a
    /// constant spectrum (kept as is for reflectances; emission as Mitsuba's RGB variants
    /// turn a uniform emitted spectrum into RGB: equal-energy white), pairs are a sampled
    /// spectrum.
    fn spectrum(&self, p: &Node, name: &str, use_: SpectrumUse) -> Result<[f64; 3], SceneError> {
        if p.attr("type").is_some() || p.attr("filename").is_some() {
            return Err(self.error_at(
                p,
                name,
                "only spectra given by `value` are read (a spectrum file or plugin is not)",
            ));
        }
        let v = self.value(p, name)?;
        if !v.contains(':') {
            let x = parse_number(v).map_err(|m| self.error_at(p, name, m))?;
            return Ok(match use_ {
                SpectrumUse::Emission => sampled_to_rgb(&[(360.0, x), (830.0, x)], use_)
                    .map_err(|m| self.error_at(p, name, m))?,
                _ => [x; 3],
            });
        }
        let mut samples = Vec::new();
        for pair in v.split(',') {
            let (l, x) = pair.split_once(':').ok_or_else(|| {
                self.error_at(
                    p,
                    name,
                    format!("`{}` is not wavelength:value", pair.trim()),
                )
            })?;
            let l = parse_number(l).map_err(|m| self.error_at(p, name, m))?;
            let x = parse_number(x).map_err(|m| self.error_at(p, name, m))?;
            samples.push((l, x));
        }
        sampled_to_rgb(&samples, use_).map_err(|m| self.error_at(p, name, m))
    }

    /// A `<transform name=...>`.
    pub fn transform(&self, name: &str) -> Result<Option<Transform>, SceneError> {
        let Some(p) = self.named(name) else {
            return Ok(None);
        };
        if p.tag != "transform" {
            return Err(self.wrong_type(&p, name, "a <transform>"));
        }
        Transform::read(self.cx, &p, &describe(&self.node)).map(Some)
    }

    /// A named object (`<medium name="interior">` or `<ref name="interior" id=..>`),
    /// which must be a `tag` element.
    pub fn object(&self, name: &str, tag: &str) -> Result<Option<Rc<Node>>, SceneError> {
        let Some(p) = self.named(name) else {
            return Ok(None);
        };
        let o = self.cx.deref(&p)?;
        if o.tag != tag {
            return Err(self.wrong_type(&p, name, &format!("a <{tag}>")));
        }
        Ok(Some(o))
    }

    /// The unnamed child objects with tag `tag` (nested, or `<ref>`s to one).
    pub fn unnamed(&self, tag: &str) -> Result<Vec<Rc<Node>>, SceneError> {
        let mut out = Vec::new();
        for (i, c) in self.node.children.iter().enumerate() {
            if c.attr("name").is_some() || self.used.borrow()[i] {
                continue;
            }
            let o = if c.tag == "ref" {
                self.cx.deref(c)?
            } else {
                c.clone()
            };
            if o.tag == tag {
                self.used.borrow_mut()[i] = true;
                out.push(o);
            }
        }
        Ok(out)
    }

    /// At most one unnamed `tag` child.
    pub fn one_unnamed(&self, tag: &str) -> Result<Option<Rc<Node>>, SceneError> {
        let mut v = self.unnamed(tag)?;
        if v.len() > 1 {
            return Err(self.cx.error(
                &v[1],
                None,
                format!("{} has more than one <{tag}>", describe(&self.node)),
            ));
        }
        Ok(v.pop())
    }

    /// Marks `name` as read without reading it.
    pub fn ignore(&self, name: &str) {
        let _ = self.named(name);
    }

    /// Every child not queried: an error at it, or, when its name is in `harmless` (the
    /// parameters that cannot change risotto's image), a warning.
    pub fn finish(&self, harmless: &[&str]) -> Result<(), SceneError> {
        let used = self.used.borrow();
        for (i, c) in self.node.children.iter().enumerate() {
            if used[i] {
                continue;
            }
            let what = match c.attr("name") {
                Some(n) => format!("parameter `{n}`"),
                None => format!("<{}>", c.tag),
            };
            if c.attr("name").is_some_and(|n| SILENT.contains(&n)) {
                continue;
            }
            if c.attr("name").is_some_and(|n| harmless.contains(&n)) {
                self.cx.warn(
                    c,
                    format!(
                        "{} of {}: ignored (it does not change the image)",
                        what,
                        describe(&self.node)
                    ),
                );
                continue;
            }
            return Err(self.cx.doc.error(
                c,
                SceneErrorKind::UnknownField,
                Some(&describe(&self.node)),
                c.attr("name"),
                format!(
                    "{what} of {} is not supported by the importer (Mitsuba refuses unused \
                     parameters too)",
                    describe(&self.node)
                ),
            ));
        }
        Ok(())
    }

    fn wrong_type(&self, p: &Node, name: &str, expected: &str) -> SceneError {
        self.error_at(
            p,
            name,
            format!("`{name}` must be {expected}, got a <{}>", p.tag),
        )
    }
}

/// One finite number (Mitsuba's float syntax).
pub fn parse_number(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("`{}` is not a finite number", text.trim())),
    }
}

/// Numbers separated by commas and/or whitespace.
pub fn parse_list(text: &str) -> Result<Vec<f64>, String> {
    text.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .map(parse_number)
        .collect()
}

/// `x`, `y`, `z` attributes (each `default` when absent), or `value="x, y, z"`.
pub fn xyz(node: &Node, default: f64) -> Result<[f64; 3], String> {
    if let Some(v) = node.attr("value") {
        let n = parse_list(v)?;
        return match n[..] {
            [a] => Ok([a; 3]),
            [a, b, c] => Ok([a, b, c]),
            _ => Err(format!("`{v}` needs 1 or 3 numbers")),
        };
    }
    let mut out = [default; 3];
    for (i, axis) in ["x", "y", "z"].iter().enumerate() {
        if let Some(v) = node.attr(axis) {
            out[i] = parse_number(v)?;
        }
    }
    Ok(out)
}

/// Mitsuba 3's named indices of refraction (`src/render/ior.h`, from its documentation's
/// table of dielectric IORs, at 589 nm).
const NAMED_IORS: &[(&str, f64)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// The index `name` (a number, or one of Mitsuba's names, any case).
pub fn named_ior(name: &str) -> Result<f64, String> {
    if let Ok(v) = parse_number(name) {
        return if v > 0.0 {
            Ok(v)
        } else {
            Err(format!("index of refraction {v} must be > 0"))
        };
    }
    let lower = name.trim().to_ascii_lowercase();
    NAMED_IORS
        .iter()
        .find(|(n, _)| *n == lower)
        .map(|(_, v)| *v)
        .ok_or_else(|| {
            let names: Vec<&str> = NAMED_IORS.iter().map(|(n, _)| *n).collect();
            format!(
                "`{name}` is not a number or one of Mitsuba's named indices ({})",
                names.join(", ")
            )
        })
}

impl Props<'_> {
    /// An index of refraction: a `<float>` or a `<string>` naming one; `default` when absent.
    pub fn ior(&self, name: &str, default: &str) -> Result<f64, SceneError> {
        let Some(p) = self.named(name) else {
            return named_ior(default).map_err(|m| self.error(Some(name), m));
        };
        let v = self.value(&p, name)?;
        match p.tag.as_str() {
            "float" | "integer" | "string" => named_ior(v).map_err(|m| self.error_at(&p, name, m)),
            _ => Err(self.wrong_type(&p, name, "a <float> or <string>")),
        }
    }
}
