//! Textures to risotto patterns: `bitmap` (an `image` pattern) and `checkerboard` (a `uv`
//! `checker`).

use std::rc::Rc;

use risotto_engine::diagnostics::SceneError;

use super::values::Colour;
use super::xml::Node;
use super::{props, Converter};
use crate::import::spectrum::SpectrumUse;

impl Converter<'_> {
    /// The pattern table of a `<texture>` read as a float (a roughness, a mask's opacity, a
    /// blend weight: Mitsuba's `eval_1`). Mitsuba 3.9.1's `checkerboard` answers `eval_1`
    /// with the colours the other way round from its `eval` (`color1` where `u mod 1` and
    /// `v mod 1` are both below or both above 1/2, measured with its Python bindings at the
    /// four cell centres), so a checkerboard read as a float swaps `a` and `b` to render as
    /// Mitsuba does.
    pub(super) fn float_texture(&self, node: &Rc<Node>) -> Result<toml::Value, SceneError> {
        let mut t = self.texture(node)?;
        if let toml::Value::Table(table) = &mut t {
            if table.get("pattern").and_then(|v| v.as_str()) == Some("checker") {
                let (a, b) = (table.remove("a"), table.remove("b"));
                if let (Some(a), Some(b)) = (a, b) {
                    table.insert("a".into(), b);
                    table.insert("b".into(), a);
                }
            }
        }
        Ok(t)
    }

    /// The pattern table of a `<texture>` read as a colour (Mitsuba's `eval`).
    pub(super) fn texture(&self, node: &Rc<Node>) -> Result<toml::Value, SceneError> {
        let p = props(self.cx, node)?;
        let kind = p.kind()?;
        let mut t = toml::Table::new();
        // to_uv: Mitsuba keeps the 2D affine part of the 4x4 (`Transform4f::extract`):
        // u' = m00 u + m01 v + m03, v' = m10 u + m11 v + m13. A bitmap takes any of it; a
        // checkerboard only a uniform scale (the checker pattern's frequency).
        let to_uv = p.transform("to_uv")?.map(|tr| {
            let m = tr.matrix;
            (
                [m.x_axis.x, m.y_axis.x, m.w_axis.x],
                [m.x_axis.y, m.y_axis.y, m.w_axis.y],
            )
        });
        let uv_scale = match to_uv {
            Some((u, v)) if kind == "checkerboard" => {
                let s = u[0];
                let uniform = v[1] == s && u[1] == 0.0 && v[0] == 0.0 && u[2] == 0.0 && v[2] == 0.0;
                if !uniform || s <= 0.0 {
                    return Err(p.error(
                        Some("to_uv"),
                        "a checkerboard's to_uv is converted only as a uniform positive scale",
                    ));
                }
                s
            }
            _ => 1.0,
        };
        match kind.as_str() {
            "bitmap" => {
                let file = p.string("filename")?.ok_or_else(|| {
                    p.error(Some("filename"), "a bitmap texture needs a filename")
                })?;
                let lower = file.to_ascii_lowercase();
                let known = [".png", ".exr", ".jpg", ".jpeg"];
                if !known.iter().any(|ext| lower.ends_with(ext)) {
                    return Err(p.error(
                        Some("filename"),
                        format!("`{file}`: only PNG, JPEG and EXR bitmaps are read"),
                    ));
                }
                let raw = p.boolean("raw")?.unwrap_or(false);
                let filter = p
                    .string("filter_type")?
                    .unwrap_or_else(|| "bilinear".into());
                if !["bilinear", "nearest"].contains(&filter.as_str()) {
                    return Err(p.error(
                        Some("filter_type"),
                        format!("filter_type \"{filter}\" is not supported (bilinear, nearest)"),
                    ));
                }
                let wrap = p.string("wrap_mode")?.unwrap_or_else(|| "repeat".into());
                if !["repeat", "mirror", "clamp"].contains(&wrap.as_str()) {
                    return Err(p.error(
                        Some("wrap_mode"),
                        format!("wrap_mode \"{wrap}\" is not supported (repeat, mirror, clamp)"),
                    ));
                }
                t.insert("pattern".into(), "image".into());
                t.insert("path".into(), self.file_path(&p.node, &file).into());
                // Mitsuba's bitmap has v = 0 at the image's top row (measured with its
                // Python bindings); risotto's image pattern at the bottom row by default.
                t.insert("v_origin".into(), "top".into());
                if raw {
                    t.insert("raw".into(), true.into());
                }
                if filter != "bilinear" {
                    t.insert("filter".into(), filter.into());
                }
                if wrap != "repeat" {
                    t.insert("wrap".into(), wrap.into());
                }
                if let Some((u, v)) = to_uv {
                    let row = |r: [f64; 3]| toml::Value::Array(r.map(toml::Value::Float).to_vec());
                    let mut m = toml::Table::new();
                    m.insert("u".into(), row(u));
                    m.insert("v".into(), row(v));
                    t.insert("uv_transform".into(), toml::Value::Table(m));
                }
            }
            "checkerboard" => {
                let c = |name: &str, default: f64| -> Result<toml::Value, SceneError> {
                    match p.colour(name, SpectrumUse::Reflectance)? {
                        None => Ok(super::bsdf::rgb([default; 3])),
                        Some(Colour::Rgb(c)) => Ok(super::bsdf::rgb(c)),
                        Some(Colour::Texture(_)) => {
                            Err(p.error(Some(name), "a checkerboard colour cannot be a texture"))
                        }
                    }
                };
                // Mitsuba's `eval`: color0 where u mod 1 and v mod 1 are both below or both
                // above 1/2, i.e. even parity of floor(2u) + floor(2v): risotto's `a` at
                // scale 2 (its `eval_1` is the other way round: `float_texture`).
                t.insert("pattern".into(), "checker".into());
                t.insert("space".into(), "uv".into());
                t.insert("scale".into(), toml::Value::Float(2.0 * uv_scale));
                t.insert("a".into(), c("color0", 0.4)?);
                t.insert("b".into(), c("color1", 0.2)?);
            }
            other => {
                return Err(p.error(
                    Some("type"),
                    format!("texture type \"{other}\" is not supported (bitmap, checkerboard)"),
                ))
            }
        }
        p.finish(&[])?;
        Ok(toml::Value::Table(t))
    }
}
