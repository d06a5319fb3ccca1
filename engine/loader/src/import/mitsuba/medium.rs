//! Media to risotto interiors: `homogeneous` and `heterogeneous` (`gridvolume` `.vol`
//! files of 1 or 3 channels, `constvolume`), phase functions `isotropic` and `hg`.
//!
//! Mitsuba's heterogeneous medium exists only inside its `sigma_t` grid's box (the grid's
//! `to_world` image of the unit cube, or the `.vol` file's own bounds without one). risotto
//! fills the shape's object-space box with the grid: when the two boxes are the same the
//! grid is written as is; when the shape lies inside an axis-aligned grid box, as a
//! `grid` pattern placed by that box; otherwise the conversion is an error.

use std::io::Read;
use std::rc::Rc;

use glam::{DMat4, DVec3};
use risotto_engine::diagnostics::SceneError;

use super::bsdf::rgb;
use super::shape::Placement;
use super::values::{Colour, Props};
use super::xml::Node;
use super::{props, Converter};
use crate::import::spectrum::SpectrumUse;

/// Medium parameters that only choose a sampling strategy.
const SAMPLING_ONLY: &[&str] = &["sample_emitters"];

impl Converter<'_> {
    /// The `interior` table of `medium` filling the shape placed by `placement`.
    pub(super) fn medium_table(
        &self,
        medium: &Rc<Node>,
        placement: &Placement,
    ) -> Result<toml::Table, SceneError> {
        let p = props(self.cx, medium)?;
        let kind = p.kind()?;
        let mut t = toml::Table::new();
        let scale = p.float_or("scale", 1.0)?;
        match kind.as_str() {
            "homogeneous" => {
                t.insert("type".into(), "homogeneous".into());
                let c = |name: &str| self.medium_constant(&p, name);
                match (c("sigma_t")?, c("albedo")?, c("sigma_a")?, c("sigma_s")?) {
                    (st, al, None, None) => {
                        let st = st.unwrap_or([1.0; 3]).map(|x| x * scale);
                        t.insert("sigma_t".into(), grey_or_rgb(st));
                        t.insert("albedo".into(), grey_or_rgb(al.unwrap_or([0.75; 3])));
                    }
                    (None, None, sa, ss) => {
                        let sa = sa.unwrap_or([0.0; 3]).map(|x| x * scale);
                        let ss = ss.unwrap_or([0.0; 3]).map(|x| x * scale);
                        t.insert("sigma_a".into(), grey_or_rgb(sa));
                        t.insert("sigma_s".into(), grey_or_rgb(ss));
                    }
                    _ => {
                        return Err(p.error(
                            Some("sigma_a"),
                            "give sigma_t and albedo, or sigma_a and sigma_s, not a mix",
                        ))
                    }
                }
            }
            "heterogeneous" => {
                t.insert("type".into(), "heterogeneous".into());
                t.insert("scale".into(), toml::Value::Float(scale));
                let volume = |name: &str| -> Result<Option<Rc<Node>>, SceneError> {
                    if p.tag_of(name).as_deref() == Some("volume") {
                        p.object(name, "volume")
                    } else {
                        Ok(None)
                    }
                };
                let density = match volume("sigma_t")? {
                    Some(v) => {
                        let (density, factor) = self.density(&v, placement)?;
                        t.insert("scale".into(), grey_or_rgb(factor.map(|f| f * scale)));
                        density
                    }
                    None => {
                        let c = self.medium_constant(&p, "sigma_t")?.unwrap_or([1.0; 3]);
                        if c[0] != c[1] || c[1] != c[2] {
                            return Err(p.error(
                                Some("sigma_t"),
                                "a constant chromatic sigma_t of a heterogeneous medium: write \
                                 it as a homogeneous medium",
                            ));
                        }
                        toml::Value::Table(toml::Table::from_iter([(
                            "constant".to_owned(),
                            toml::Value::Float(c[0]),
                        )]))
                    }
                };
                t.insert("density".into(), density);
                let albedo = match volume("albedo")? {
                    Some(v) => self.volume_pattern(&v)?,
                    None => grey_or_rgb(self.medium_constant(&p, "albedo")?.unwrap_or([0.75; 3])),
                };
                t.insert("albedo".into(), albedo);
            }
            other => {
                return Err(p.error(
                    Some("type"),
                    format!(
                        "medium type \"{other}\" is not supported (homogeneous, heterogeneous)"
                    ),
                ))
            }
        }
        if let Some(ph) = p.object("phase", "phase")?.or(p.one_unnamed("phase")?) {
            let pp = props(self.cx, &ph)?;
            let mut phase = toml::Table::new();
            match pp.kind()?.as_str() {
                "isotropic" => {
                    phase.insert("type".into(), "isotropic".into());
                }
                "hg" => {
                    phase.insert("type".into(), "hg".into());
                    phase.insert("g".into(), toml::Value::Float(pp.float_or("g", 0.8)?));
                }
                other => {
                    return Err(pp.error(
                        Some("type"),
                        format!("phase type \"{other}\" is not supported (isotropic, hg)"),
                    ))
                }
            }
            pp.finish(&[])?;
            t.insert("phase".into(), toml::Value::Table(phase));
        }
        p.finish(SAMPLING_ONLY)?;
        Ok(t)
    }

    /// A constant medium coefficient (Mitsuba reads non-emitted spectra as reflectances:
    /// clamped to [0, 1]; an `<rgb>` or `<float>` is kept as given).
    fn medium_constant(&self, p: &Props<'_>, name: &str) -> Result<Option<[f64; 3]>, SceneError> {
        match p.colour(name, SpectrumUse::Reflectance)? {
            None => Ok(None),
            Some(Colour::Rgb(c)) => Ok(Some(c)),
            Some(Colour::Texture(_)) => {
                Err(p.error(Some(name), "a texture is not a medium coefficient"))
            }
        }
    }

    /// The `density` of a heterogeneous interior from its `sigma_t` volume, and the colour
    /// that multiplies the medium's `scale` (a chromatic `constvolume`; white otherwise).
    ///
    /// Mitsuba's heterogeneous medium exists only inside its `sigma_t` volume's box (the
    /// unit cube placed by the volume's `to_world`, or a `.vol` file's own box; measured with
    /// its bindings: `intersect_aabb` of a `constvolume` without `to_world` is `[0, 1]^3`),
    /// and clamps its lookups there. Where that box is the shape's own (or holds the whole
    /// untransformed shape) the grid, or the constant, is written as is; otherwise a
    /// world-space grid pattern with `border = "box"`, 0 outside the box.
    fn density(
        &self,
        volume: &Rc<Node>,
        placement: &Placement,
    ) -> Result<(toml::Value, [f64; 3]), SceneError> {
        let vp = props(self.cx, volume)?;
        // What the volume holds: a file's grid, or one constant (as a one-voxel grid), its
        // value split into a grey density and a colour factor.
        let (source, box_matrix, factor) = match vp.kind()?.as_str() {
            "constvolume" => {
                let c = match vp.colour("value", SpectrumUse::Reflectance)? {
                    Some(Colour::Rgb(c)) => c,
                    None => [1.0; 3],
                    Some(Colour::Texture(_)) => {
                        return Err(vp.error(Some("value"), "a constvolume's value is a constant"))
                    }
                };
                let m = vp
                    .transform("to_world")?
                    .map_or(DMat4::IDENTITY, |t| t.matrix);
                vp.finish(&[])?;
                (VolumeSource::Constant, m, c)
            }
            "gridvolume" => {
                let file = vp.string("filename")?.unwrap_or_default();
                let resolved = self.cx.doc.resolve(&vp.node, &file);
                let channels =
                    vol_channels(&resolved).map_err(|m| vp.error(Some("filename"), m))?;
                let (path, grid) = self.grid(&vp)?;
                (VolumeSource::Grid(path, channels), grid, [1.0; 3])
            }
            other => {
                return Err(vp.error(
                    Some("type"),
                    format!("volume type \"{other}\" is not supported (gridvolume, constvolume)"),
                ))
            }
        };
        let whole = |src: &VolumeSource| match src {
            VolumeSource::Grid(path, _) => {
                toml::Table::from_iter([("grid".to_owned(), toml::Value::String(path.clone()))])
            }
            VolumeSource::Constant => {
                toml::Table::from_iter([("constant".to_owned(), toml::Value::Float(1.0))])
            }
        };
        let axis_aligned = |m: &DMat4| {
            let c = m.to_cols_array_2d();
            (0..3).all(|i| (0..3).all(|j| i == j || c[i][j].abs() < 1e-12))
        };
        let (w0, w1) = (
            box_matrix.transform_point3(DVec3::ZERO),
            box_matrix.transform_point3(DVec3::ONE),
        );
        let (wlo, whi) = (w0.min(w1), w0.max(w1));
        if let Some((lo, hi)) = placement.bounds {
            // The volume's unit cube in the shape's object space.
            let a = placement.to_world.inverse() * box_matrix;
            let (g0, g1) = (
                a.transform_point3(DVec3::ZERO),
                a.transform_point3(DVec3::ONE),
            );
            let close =
                |x: DVec3, y: DVec3| (x - y).abs().max_element() <= 1e-9 * (hi - lo).max_element();
            if axis_aligned(&a) && close(g0, lo) && close(g1, hi) {
                return Ok((toml::Value::Table(whole(&source)), factor));
            }
            // An untransformed shape inside an axis-aligned box: a world-space grid pattern
            // (its clamp is never read outside the box), or the constant.
            let inside = placement.to_world == DMat4::IDENTITY
                && axis_aligned(&box_matrix)
                && lo.cmpge(wlo - 1e-9).all()
                && hi.cmple(whi + 1e-9).all();
            if inside {
                return Ok(match source {
                    VolumeSource::Grid(path, 3) => {
                        (colour_grid_pattern(&path, wlo, whi, false), factor)
                    }
                    VolumeSource::Grid(path, _) => (grid_pattern(path, wlo, whi), factor),
                    VolumeSource::Constant => (toml::Value::Table(whole(&source)), factor),
                });
            }
        }
        // Any other shape (a mesh, whose bounds are not known before it is read, or one
        // reaching beyond the box): a world-space grid pattern with `border = "box"`.
        if !axis_aligned(&box_matrix) {
            return Err(self.cx.error(
                volume,
                Some("to_world"),
                format!(
                    "the volume's box ({wlo} to {whi}) is turned and is not the shape's own \
                     box: only an axis-aligned box is converted for a shape it does not match"
                ),
            ));
        }
        let mut t = match source {
            // A density per channel (a colour graph, `sigma_t,c = scale_c density_c`), each
            // channel's grid bordered by the box.
            VolumeSource::Grid(path, 3) => {
                return Ok((colour_grid_pattern(&path, wlo, whi, true), factor))
            }
            VolumeSource::Grid(path, _) => grid_pattern(path, wlo, whi),
            VolumeSource::Constant => toml::Value::Table(toml::Table::from_iter([
                ("pattern".to_owned(), toml::Value::String("grid".into())),
                (
                    "values".to_owned(),
                    toml::Value::Array(vec![toml::Value::Float(1.0)]),
                ),
                (
                    "dims".to_owned(),
                    toml::Value::Array(vec![toml::Value::Integer(1); 3]),
                ),
                ("min".to_owned(), super::sensor::vec3(wlo)),
                ("max".to_owned(), super::sensor::vec3(whi)),
            ])),
        };
        if let toml::Value::Table(table) = &mut t {
            table.insert("border".into(), toml::Value::String("box".into()));
        }
        Ok((t, factor))
    }

    /// A volume read at scattering points (an albedo) as a world-space pattern.
    fn volume_pattern(&self, volume: &Rc<Node>) -> Result<toml::Value, SceneError> {
        let vp = props(self.cx, volume)?;
        match vp.kind()?.as_str() {
            "constvolume" => {
                let c = match vp.colour("value", SpectrumUse::Reflectance)? {
                    Some(Colour::Rgb(c)) => c,
                    None => [1.0; 3],
                    Some(Colour::Texture(_)) => {
                        return Err(vp.error(Some("value"), "a constvolume's value is a constant"))
                    }
                };
                vp.finish(&[])?;
                Ok(grey_or_rgb(c))
            }
            "gridvolume" => {
                let file = vp.string("filename")?.unwrap_or_default();
                let resolved = self.cx.doc.resolve(&vp.node, &file);
                let (path, grid) = self.grid(&vp)?;
                let (w0, w1) = (
                    grid.transform_point3(DVec3::ZERO),
                    grid.transform_point3(DVec3::ONE),
                );
                let (lo, hi) = (w0.min(w1), w0.max(w1));
                if vol_channels(&resolved).map_err(|m| vp.error(Some("filename"), m))? != 3 {
                    return Ok(grid_pattern(path, lo, hi));
                }
                // Clamped to [0, 1] (`remap`'s default): the sum's interval bounds carry
                // rounding slack past the file's largest value, which an albedo must not.
                Ok(toml::Value::Table(toml::Table::from_iter([
                    ("pattern".to_owned(), toml::Value::String("remap".into())),
                    ("a".to_owned(), colour_grid_pattern(&path, lo, hi, false)),
                ])))
            }
            other => Err(vp.error(
                Some("type"),
                format!("volume type \"{other}\" is not supported"),
            )),
        }
    }

    /// A `gridvolume`'s file (as written in the TOML) and the matrix placing its unit cube
    /// in the world (`to_world`, or the `.vol` file's bounding box without one).
    fn grid(&self, vp: &Props<'_>) -> Result<(String, DMat4), SceneError> {
        let file = vp
            .string("filename")?
            .ok_or_else(|| vp.error(Some("filename"), "a gridvolume needs a filename"))?;
        if let Some(f) = vp.string("filter_type")? {
            if f != "trilinear" {
                return Err(vp.error(
                    Some("filter_type"),
                    format!("filter_type \"{f}\": only trilinear is converted"),
                ));
            }
        }
        if let Some(w) = vp.string("wrap_mode")? {
            if w != "clamp" {
                return Err(vp.error(
                    Some("wrap_mode"),
                    format!("wrap_mode \"{w}\": only clamp is converted"),
                ));
            }
        }
        let resolved = self.cx.doc.resolve(&vp.node, &file);
        let m = match vp.transform("to_world")? {
            Some(t) => t.matrix,
            None => {
                let (lo, hi) = vol_bounds(&resolved).map_err(|m| vp.error(Some("filename"), m))?;
                DMat4::from_translation(lo) * DMat4::from_scale(hi - lo)
            }
        };
        vp.finish(&["raw", "accel", "use_grid_bbox"])?;
        Ok((self.file_path(&vp.node, &file), m))
    }
}

/// What a heterogeneous medium's `sigma_t` volume holds.
enum VolumeSource {
    /// A grid file, as written in the TOML, and its number of channels.
    Grid(String, i32),
    /// A constant (its value goes to the medium's `scale`).
    Constant,
}

/// A `grid` pattern of `path` over the world box `lo`..`hi`.
fn grid_pattern(path: String, lo: DVec3, hi: DVec3) -> toml::Value {
    toml::Value::Table(toml::Table::from_iter([
        ("pattern".to_owned(), toml::Value::String("grid".into())),
        ("path".to_owned(), toml::Value::String(path)),
        ("min".to_owned(), super::sensor::vec3(lo)),
        ("max".to_owned(), super::sensor::vec3(hi)),
    ]))
}

/// The 48-byte header of a Mitsuba `.vol` file (magic, version, encoding, resolution,
/// channels, bounding box).
fn vol_header(path: &std::path::Path) -> Result<[u8; 48], String> {
    let mut head = [0u8; 48];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut head))
        .map_err(|e| format!("cannot read the header of `{}`: {e}", path.display()))?;
    if &head[..3] != b"VOL" {
        return Err(format!("`{}` is not a Mitsuba .vol file", path.display()));
    }
    Ok(head)
}

/// The channel count stored in a Mitsuba `.vol` file's header (bytes 20 to 24, a
/// little-endian int32).
fn vol_channels(path: &std::path::Path) -> Result<i32, String> {
    let head = vol_header(path)?;
    Ok(i32::from_le_bytes([head[20], head[21], head[22], head[23]]))
}

/// The bounding box stored in a Mitsuba `.vol` file's header (bytes 24 to 48: six
/// little-endian float32, min then max).
fn vol_bounds(path: &std::path::Path) -> Result<(DVec3, DVec3), String> {
    let head = vol_header(path)?;
    let f = |i: usize| f32::from_le_bytes([head[i], head[i + 1], head[i + 2], head[i + 3]]) as f64;
    let lo = DVec3::new(f(24), f(28), f(32));
    let hi = DVec3::new(f(36), f(40), f(44));
    if !(lo.is_finite() && hi.is_finite() && lo.cmplt(hi).all()) {
        return Err(format!(
            "`{}`: the bounding box {lo} to {hi} in its header is empty or not finite",
            path.display()
        ));
    }
    Ok((lo, hi))
}

/// A colour written as one number when grey.
fn grey_or_rgb(c: [f64; 3]) -> toml::Value {
    if c[0] == c[1] && c[1] == c[2] {
        toml::Value::Float(c[0])
    } else {
        rgb(c)
    }
}

/// A 3-channel grid file over the world box `lo`..`hi` as a colour pattern: the sum of each
/// channel's grey `grid` pattern (`channel = "r" | "g" | "b"`) times its primary, each
/// bordered by the box (0 outside it) when `border`.
fn colour_grid_pattern(path: &str, lo: DVec3, hi: DVec3, border: bool) -> toml::Value {
    let channel = |name: &str, primary: [f64; 3]| {
        let mut g = grid_pattern(path.to_owned(), lo, hi);
        if let toml::Value::Table(t) = &mut g {
            t.insert("channel".into(), toml::Value::String(name.into()));
            if border {
                t.insert("border".into(), toml::Value::String("box".into()));
            }
        }
        toml::Value::Table(toml::Table::from_iter([
            ("pattern".to_owned(), toml::Value::String("multiply".into())),
            ("a".to_owned(), g),
            ("b".to_owned(), rgb(primary)),
        ]))
    };
    let add = |a: toml::Value, b: toml::Value| {
        toml::Value::Table(toml::Table::from_iter([
            ("pattern".to_owned(), toml::Value::String("add".into())),
            ("a".to_owned(), a),
            ("b".to_owned(), b),
        ]))
    };
    add(
        add(channel("r", [1.0, 0.0, 0.0]), channel("g", [0.0, 1.0, 0.0])),
        channel("b", [0.0, 0.0, 1.0]),
    )
}
