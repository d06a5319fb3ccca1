//! The integrator, the sensor (camera), its film (image size, reconstruction filter) and
//! its sampler (samples per pixel, seed).

use std::rc::Rc;

use glam::DVec3;
use risotto_engine::diagnostics::SceneError;
use risotto_engine::scene::ShadingNormals;

use super::values::describe;
use super::xml::Node;
use super::{props, Converter};
use crate::import::Entity;

/// Film parameters that only choose the output file's format.
const FILM_HARMLESS: &[&str] = &["banner", "compensate", "sample_border"];

impl Converter<'_> {
    /// `<integrator>`: `path`, `volpath`, `volpathmis` (`max_depth`, `rr_depth`); `moment`
    /// and `aov` are unwrapped to the integrator they hold (a warning: they only add
    /// outputs). No integrator: Mitsuba's default, `path`.
    pub(super) fn integrator(&mut self, node: Option<&Rc<Node>>) -> Result<(), SceneError> {
        let mut render = Entity::new(None);
        let (max_depth, rr_depth) = match node {
            None => (-1, 5),
            Some(node) => {
                let mut node = node.clone();
                loop {
                    let p = props(self.cx, &node)?;
                    let kind = p.kind()?;
                    if kind == "moment" || kind == "aov" {
                        let inner = p.unnamed("integrator")?;
                        p.ignore("aovs");
                        p.finish(&[])?;
                        let [inner] = &inner[..] else {
                            return Err(p.error(
                                None,
                                format!("a `{kind}` integrator must hold exactly one integrator"),
                            ));
                        };
                        self.cx.warn(
                            &node,
                            format!(
                                "the `{kind}` integrator only adds outputs: rendering the \
                                 integrator inside it"
                            ),
                        );
                        node = inner.clone();
                        continue;
                    }
                    if kind == "direct" {
                        // Emitted light and one scattering vertex lit by emitter and BSDF
                        // samples: a path of at most 2 segments, in expectation.
                        p.finish(&["emitter_samples", "bsdf_samples", "shading_samples"])?;
                        render.origin = self.origin(&node);
                        break (2, 5);
                    }
                    if !matches!(kind.as_str(), "path" | "volpath" | "volpathmis") {
                        return Err(p.error(
                            Some("type"),
                            format!(
                                "integrator type \"{kind}\" is not supported (path, volpath, \
                                 volpathmis, direct; moment and aov wrappers)"
                            ),
                        ));
                    }
                    let max_depth = p.int("max_depth")?.unwrap_or(-1);
                    let rr_depth = p.int("rr_depth")?.unwrap_or(5);
                    if p.boolean("hide_emitters")? == Some(true) {
                        return Err(p.error(
                            Some("hide_emitters"),
                            "hide_emitters = true is not supported (risotto shows emitters \
                             seen directly)",
                        ));
                    }
                    p.finish(&[])?;
                    if kind == "path" {
                        self.path_integrator = Some(node.clone());
                    }
                    render.origin = self.origin(&node);
                    break (max_depth, rr_depth);
                }
            }
        };
        if max_depth < -1 || max_depth == 0 {
            return Err(self.cx.error(
                node.expect("a bad max_depth comes from a node"),
                Some("max_depth"),
                format!("max_depth must be -1 (unbounded) or >= 1, got {max_depth}"),
            ));
        }
        render.set("max_depth", max_depth);
        render.set("rr_depth", rr_depth.max(1));
        // Mitsuba evaluates its BSDFs in the shading frame alone and keeps every sampled
        // direction (risotto's default discards those the two normals disagree on).
        render.set("shading_normals", ShadingNormals::ShadingFrame.name());
        self.scene.render = render;
        Ok(())
    }

    /// Whether the scene's first `<integrator>` (through `moment` / `aov` wrappers) is
    /// `volpath` or `volpathmis`; read before the shapes, whose thin dielectrics depend on it
    /// (the integrator itself is converted, and checked, by [`Self::integrator`]).
    pub(super) fn volumetric_integrator(&self, root: &Rc<Node>) -> Result<bool, SceneError> {
        let Some(mut node) = root
            .children
            .iter()
            .find(|c| c.tag == "integrator")
            .cloned()
        else {
            return Ok(false);
        };
        loop {
            let kind = props(self.cx, &node)?.kind()?;
            if kind == "moment" || kind == "aov" {
                match node.children.iter().find(|c| c.tag == "integrator") {
                    Some(inner) => node = inner.clone(),
                    None => return Ok(false),
                }
                continue;
            }
            return Ok(matches!(kind.as_str(), "volpath" | "volpathmis"));
        }
    }

    /// `<sensor>`: `perspective`, `thinlens`, `orthographic`, with `<film>` and `<sampler>`.
    pub(super) fn sensor(&mut self, node: &Rc<Node>) -> Result<(), SceneError> {
        let p = props(self.cx, node)?;
        let kind = p.kind()?;
        let mut cam = Entity::new(self.origin(node));
        // The film first: the field of view's axis needs the aspect ratio.
        let (width, height) = match p.one_unnamed("film")? {
            Some(film) => self.film(&film)?,
            None => (768, 576),
        };
        let aspect = width as f64 / height as f64;
        match p.one_unnamed("sampler")? {
            Some(s) => self.sampler(&s)?,
            None => {
                self.scene.render.set("spp", 4);
                self.scene.render.set("seed", 0);
            }
        }
        let to_world = p.transform("to_world")?.unwrap_or_default();
        let m = to_world.matrix;
        let from = m.transform_point3(DVec3::ZERO);
        let (x, y, z) = (
            m.transform_vector3(DVec3::X),
            m.transform_vector3(DVec3::Y),
            m.transform_vector3(DVec3::Z),
        );
        let orthonormal = |a: DVec3, b: DVec3| (a.dot(b)).abs() < 1e-6;
        // Mitsuba's camera looks down its local +z with +y up and local +x to the image's
        // left: exactly risotto's frame (right = forward x up) when the matrix is a rotation.
        let rigid = orthonormal(x, y) && orthonormal(y, z) && orthonormal(x, z);
        let det = m.determinant();
        if !rigid || det <= 0.0 {
            return Err(p.error(
                Some("to_world"),
                "the sensor's to_world must be a rotation and translation (a look-at): a \
                 mirror, scale or shear of the camera frame is not converted",
            ));
        }
        let unit = |v: DVec3| (v.length() - 1.0).abs() < 1e-6;
        if kind != "orthographic" && !(unit(x) && unit(y) && unit(z)) {
            return Err(p.error(
                Some("to_world"),
                "the sensor's to_world scales the camera frame (Mitsuba refuses it too)",
            ));
        }
        // A lone look-at is written as given (the same frame: risotto's right is
        // forward x up, Mitsuba's local +x is up x forward, to the image's left).
        let look_at = match &to_world.steps[..] {
            [toml::Value::Table(t)] => t.get("look_at").and_then(|l| l.as_table()).cloned(),
            _ => None,
        };
        match look_at {
            Some(l) => {
                for (key, value) in l {
                    cam.set(&key, value);
                }
            }
            None => {
                cam.set("from", vec3(from));
                cam.set("to", vec3(from + z.normalize()));
                cam.set("up", vec3(y.normalize()));
            }
        }
        match kind.as_str() {
            "perspective" | "thinlens" => {
                let fov = x_fov(&p, aspect)?;
                cam.set("fov", fov);
                if kind == "thinlens" {
                    cam.set("projection", "thin_lens");
                    let r = p.float("aperture_radius")?.ok_or_else(|| {
                        p.error(
                            Some("aperture_radius"),
                            "a thinlens sensor needs aperture_radius",
                        )
                    })?;
                    let d = p.float("focus_distance")?.ok_or_else(|| {
                        p.error(
                            Some("focus_distance"),
                            "a thinlens sensor needs focus_distance",
                        )
                    })?;
                    cam.set("aperture_radius", r);
                    cam.set("focus_distance", d);
                } else {
                    cam.set("projection", "perspective");
                }
            }
            "orthographic" => {
                // Mitsuba's orthographic view is [-1, 1] along local x before to_world;
                // its scale sets the world width.
                if (x.length() - y.length()).abs() > 1e-9 * x.length() || !unit(z) {
                    return Err(p.error(
                        Some("to_world"),
                        "an orthographic sensor's to_world may scale x and y equally only",
                    ));
                }
                cam.set("projection", "orthographic");
                cam.set("width", 2.0 * x.length());
            }
            other => {
                return Err(p.error(
                    Some("type"),
                    format!(
                        "sensor type \"{other}\" is not supported (perspective, thinlens, \
                         orthographic)"
                    ),
                ))
            }
        }
        let near = p.float("near_clip")?.unwrap_or(1e-2);
        let far = p.float("far_clip")?.unwrap_or(1e4);
        self.clip_planes = Some((node.clone(), from, near, far));
        if let Some(m) = p.object("medium", "medium")? {
            self.sensor_medium = Some(m);
        }
        p.finish(&[])?;
        self.scene.camera = cam;
        Ok(())
    }

    /// `<film type="hdrfilm">`: size and reconstruction filter.
    fn film(&mut self, node: &Rc<Node>) -> Result<(i64, i64), SceneError> {
        let p = props(self.cx, node)?;
        let kind = p.kind()?;
        if kind != "hdrfilm" && kind != "specfilm" {
            return Err(p.error(
                Some("type"),
                format!("film type \"{kind}\" is not supported (hdrfilm)"),
            ));
        }
        let width = p.int("width")?.unwrap_or(768);
        let height = p.int("height")?.unwrap_or(576);
        for (v, name) in [(width, "width"), (height, "height")] {
            if !(1..=65536).contains(&v) {
                return Err(p.error(Some(name), format!("{name} must be in [1, 65536], got {v}")));
            }
        }
        for crop in [
            "crop_offset_x",
            "crop_offset_y",
            "crop_width",
            "crop_height",
        ] {
            if p.has(crop) {
                return Err(p.error(
                    Some(crop),
                    "a cropped film is not converted (render the whole image and crop it)",
                ));
            }
        }
        self.scene.render.set("width", width);
        self.scene.render.set("height", height);
        // Mitsuba's default reconstruction filter is a Gaussian of standard deviation 0.5.
        match p.one_unnamed("rfilter")? {
            Some(f) => self.rfilter(&f)?,
            None => {
                self.scene.render.set("filter", "gaussian");
            }
        }
        p.finish(FILM_HARMLESS)?;
        Ok((width, height))
    }

    /// `<rfilter>`: `box` (risotto's default, the pixel box), `tent`, `gaussian`.
    fn rfilter(&mut self, node: &Rc<Node>) -> Result<(), SceneError> {
        let p = props(self.cx, node)?;
        let kind = p.kind()?;
        match kind.as_str() {
            "box" => {
                if let Some(r) = p.float("radius")? {
                    if r != 0.5 {
                        self.scene.render.set("filter", "box");
                        self.scene.render.set("filter_radius", r);
                    }
                }
            }
            "tent" => {
                self.scene.render.set("filter", "tent");
                if let Some(r) = p.float("radius")? {
                    self.scene.render.set("filter_radius", r);
                }
            }
            "gaussian" => {
                self.scene.render.set("filter", "gaussian");
                if let Some(s) = p.float("stddev")? {
                    self.scene.render.set("filter_stddev", s);
                }
            }
            other => {
                return Err(p.error(
                    Some("type"),
                    format!("rfilter type \"{other}\" is not supported (box, tent, gaussian)"),
                ))
            }
        }
        p.finish(&[])
    }

    /// `<sampler>`: `sample_count` and `seed`; its type is not (risotto's own sampler).
    fn sampler(&mut self, node: &Rc<Node>) -> Result<(), SceneError> {
        let p = props(self.cx, node)?;
        let spp = p.int("sample_count")?.unwrap_or(4);
        let seed = p.int("seed")?.unwrap_or(0);
        if spp < 1 || seed < 0 {
            return Err(p.error(
                Some("sample_count"),
                format!("sample_count must be >= 1 and seed >= 0, got {spp} and {seed}"),
            ));
        }
        self.scene.render.set("spp", spp);
        self.scene.render.set("seed", seed);
        p.finish(&["jitter"])?;
        let _ = describe(node);
        Ok(())
    }
}

/// The full horizontal field of view of a perspective sensor, degrees, from Mitsuba's
/// `fov` and `fov_axis` (`x`, `y`, `diagonal`, `smaller`, `larger`) or its `focal_length`
/// (a 35 mm film, 36 x 24 mm, whose diagonal the focal length sets; default "50mm").
fn x_fov(p: &super::values::Props<'_>, aspect: f64) -> Result<f64, SceneError> {
    let (fov, axis) = match p.float("fov")? {
        Some(fov) => {
            if p.has("focal_length") {
                return Err(p.error(Some("focal_length"), "give fov or focal_length, not both"));
            }
            (fov, p.string("fov_axis")?.unwrap_or_else(|| "x".into()))
        }
        None => {
            let f = p.string("focal_length")?.unwrap_or_else(|| "50mm".into());
            let mm = f.trim().trim_end_matches("mm");
            let mm = super::values::parse_number(mm)
                .ok()
                .filter(|v| *v > 0.0)
                .ok_or_else(|| {
                    p.error(Some("focal_length"), format!("`{f}` is not a length in mm"))
                })?;
            let diagonal = (36.0f64 * 36.0 + 24.0 * 24.0).sqrt();
            (
                (2.0 * (diagonal / (2.0 * mm)).atan()).to_degrees(),
                "diagonal".to_owned(),
            )
        }
    };
    if !(fov > 0.0 && fov < 180.0) {
        return Err(p.error(Some("fov"), format!("fov must be in (0, 180), got {fov}")));
    }
    if axis.eq_ignore_ascii_case("x") {
        // Exactly as given (no round trip through the tangent).
        return Ok(fov);
    }
    let half = (fov.to_radians() / 2.0).tan();
    let from_y = |half_y: f64| half_y * aspect;
    let half_x = match axis.to_ascii_lowercase().as_str() {
        "x" => half,
        "y" => from_y(half),
        "diagonal" => half / (1.0 + 1.0 / (aspect * aspect)).sqrt(),
        "smaller" => {
            if aspect > 1.0 {
                from_y(half)
            } else {
                half
            }
        }
        "larger" => {
            if aspect > 1.0 {
                half
            } else {
                from_y(half)
            }
        }
        other => {
            return Err(p.error(
                Some("fov_axis"),
                format!("fov_axis \"{other}\" is not x, y, diagonal, smaller or larger"),
            ))
        }
    };
    Ok((2.0 * half_x.atan()).to_degrees())
}

/// A TOML vector.
pub(super) fn vec3(v: DVec3) -> toml::Value {
    toml::Value::Array(
        v.to_array()
            .iter()
            .map(|x| toml::Value::Float(*x))
            .collect(),
    )
}
