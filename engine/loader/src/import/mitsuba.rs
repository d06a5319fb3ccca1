//! Mitsuba 3 XML scenes, converted to risotto's TOML (`docs/import-mitsuba.md` lists every
//! element and parameter read, its mapping, and what is an error or a warning).
//!
//! The document is read and preprocessed first (`xml.rs`: defaults, substitution,
//! includes, references), then each top-level plugin is converted by its kind: the sensor
//! with its film and sampler and the integrator (`sensor.rs`), shapes (`shape.rs`) with their
//! BSDFs (`bsdf.rs`, textures in `texture.rs`), emitters and media (`emitter.rs`, `medium.rs`).

mod bsdf;
mod emitter;
mod medium;
mod sensor;
mod shape;
mod texture;
mod transform;
mod values;
mod xml;

use std::cell::RefCell;
use std::path::Path;
use std::rc::Rc;

use risotto_engine::diagnostics::SceneError;

use super::{ImportOptions, ImportedScene, TomlScene};
use risotto_engine::scene::NO_MEDIUM;
use values::{describe, Cx, Props};

/// Converts a Mitsuba 3 XML scene.
pub fn import(
    path: &Path,
    text: &str,
    options: &ImportOptions<'_>,
) -> Result<ImportedScene, SceneError> {
    let doc = xml::load(path, text, options.defines)?;
    let cx = Cx {
        doc,
        warnings: RefCell::new(Vec::new()),
    };
    let mut conv = Converter {
        cx: &cx,
        toml_dir: options.toml_dir,
        scene: TomlScene::default(),
        materials: Vec::new(),
        names: Vec::new(),
        has_media: false,
        sensor_medium: None,
        medium_holders: Vec::new(),
        exteriors: Vec::new(),
        no_medium_outside: Vec::new(),
        path_integrator: None,
        volumetric: false,
        clip_planes: None,
        shape_bounds: Vec::new(),
        groups: Vec::new(),
        group_shapes: None,
    };
    conv.scene.header.push(format!(
        "Converted from the Mitsuba 3 scene {} (docs/import-mitsuba.md).",
        path.display()
    ));
    let root = cx.doc.root.clone();
    conv.volumetric = conv.volumetric_integrator(&root)?;
    let mut integrators = Vec::new();
    let mut sensors = Vec::new();
    for child in &root.children {
        match child.tag.as_str() {
            "integrator" => integrators.push(child.clone()),
            "sensor" => sensors.push(child.clone()),
            "shape" => conv.shape(child)?,
            "emitter" => conv.emitter(child)?,
            // Defined here, used where referenced (an unused one is still checked when
            // referenced only; Mitsuba instantiates it, we leave it out).
            "bsdf" | "texture" | "medium" | "phase" | "volume" | "spectrum" | "rfilter"
            | "film" | "sampler" => {
                if child.attr("id").is_none() {
                    cx.warn(
                        child,
                        format!(
                            "{} at the top level without an id is unused",
                            describe(child)
                        ),
                    );
                }
            }
            other => {
                return Err(cx.error(
                    child,
                    None,
                    format!("<{other}> is not a Mitsuba 3 scene element the importer reads"),
                ))
            }
        }
    }
    if integrators.len() > 1 {
        return Err(cx.error(
            &integrators[1],
            None,
            "a scene has at most one <integrator>",
        ));
    }
    if sensors.len() > 1 {
        return Err(cx.error(
            &sensors[1],
            None,
            "the scene has more than one <sensor>; risotto renders one camera (remove the others)",
        ));
    }
    conv.integrator(integrators.first())?;
    match sensors.first() {
        Some(s) => conv.sensor(s)?,
        None => {
            return Err(SceneError::unlocated(
                path,
                risotto_engine::diagnostics::SceneErrorKind::MissingField,
                "the scene has no <sensor> (risotto needs a camera)",
            ))
        }
    }
    conv.finish_media()?;
    let warnings = cx.warnings.borrow().clone();
    Ok(ImportedScene {
        scene: conv.scene,
        warnings,
    })
}

/// A world-space box, min and max.
type Bounds = (glam::DVec3, glam::DVec3);

/// A material made: its BSDF element and interior medium (by identity) and its name.
struct MadeMaterial {
    bsdf: Option<Rc<xml::Node>>,
    interior: Option<Rc<xml::Node>>,
    name: String,
}

/// The conversion in progress.
struct Converter<'a> {
    cx: &'a Cx,
    toml_dir: &'a Path,
    scene: TomlScene,
    materials: Vec<MadeMaterial>,
    /// Shape names used so far (unique).
    names: Vec<String>,
    /// Whether some shape has an interior medium (for the `path` integrator's warning).
    has_media: bool,
    /// A medium the sensor sits in.
    sensor_medium: Option<Rc<xml::Node>>,
    /// Each top-level shape with an interior medium: the medium (by identity) and the
    /// shape's name.
    medium_holders: Vec<(Rc<xml::Node>, String)>,
    /// Each top-level shape with an exterior medium: the medium and the shape's index in
    /// `scene.shapes`.
    exteriors: Vec<(Rc<xml::Node>, usize)>,
    /// Each top-level shape bounding a volume with no exterior stated (Mitsuba: vacuum
    /// outside it, or the medium unchanged across it): its index in `scene.shapes`.
    no_medium_outside: Vec<usize>,
    /// The `path` integrator, when the scene uses it (it ignores media in Mitsuba).
    path_integrator: Option<Rc<xml::Node>>,
    /// The integrator is `volpath` or `volpathmis` (through `moment` / `aov` wrappers),
    /// which treat a `thindielectric`'s transmission as a null event.
    volumetric: bool,
    /// The sensor, its position and its near and far clip distances.
    clip_planes: Option<(Rc<xml::Node>, glam::DVec3, f64, f64)>,
    /// Each shape and its world bounds when known without reading files.
    shape_bounds: Vec<(Rc<xml::Node>, Option<Bounds>)>,
    /// The `shapegroup`s converted so far and the object each became.
    groups: Vec<(Rc<xml::Node>, String)>,
    /// While a `shapegroup` is converted: the shapes converted into it.
    group_shapes: Option<Vec<super::Entity>>,
}

impl Converter<'_> {
    /// The origin of a converted part.
    fn origin(&self, node: &xml::Node) -> Option<risotto_engine::diagnostics::Origin> {
        let (file, line) = self.cx.doc.origin(node);
        Some(super::origin(&file, line))
    }

    /// A path named by `node`'s plugin, as written in the TOML.
    fn file_path(&self, node: &xml::Node, name: &str) -> String {
        super::path_for_toml(&self.cx.doc.resolve(node, name), self.toml_dir)
    }

    /// A name not used before among `used`, from `base`.
    fn unique(used: &mut Vec<String>, base: &str) -> String {
        let mut name = base.to_owned();
        let mut k = 1;
        while used.contains(&name) {
            k += 1;
            name = format!("{base}_{k}");
        }
        used.push(name.clone());
        name
    }

    /// The media checks that need the whole scene.
    fn finish_media(&mut self) -> Result<(), SceneError> {
        if let (Some(node), true) = (&self.path_integrator, self.has_media) {
            self.cx.warn(
                node,
                "Mitsuba's `path` integrator ignores media; risotto renders them (use volpath \
                 in Mitsuba to compare)",
            );
        }
        if let Some((sensor, from, near, far)) = &self.clip_planes {
            for (shape, bounds) in &self.shape_bounds {
                match bounds {
                    Some((lo, hi)) => {
                        let nearest = from.clamp(*lo, *hi).distance(*from);
                        let farthest = (*from - (*lo + *hi) * 0.5).abs() + (*hi - *lo) * 0.5;
                        if nearest < *near {
                            self.cx.warn(
                                shape,
                                format!(
                                    "{} is closer to the camera than near_clip = {near}: Mitsuba \
                                 clips it there, risotto (which has no near clip) does not",
                                    describe(shape)
                                ),
                            );
                        } else if farthest.length() > *far {
                            self.cx.warn(
                                shape,
                                format!(
                                    "{} reaches beyond far_clip = {far}: Mitsuba clips it there, \
                                 risotto does not",
                                    describe(shape)
                                ),
                            );
                        }
                    }
                    None if *near > 1e-2 => self.cx.warn(
                        sensor,
                        format!(
                            "near_clip = {near} may cut {} in Mitsuba; risotto has no near clip",
                            describe(shape)
                        ),
                    ),
                    None => {}
                }
            }
        }
        // Mitsuba states the medium around the sensor and outside shapes; risotto infers
        // them from the closed shapes enclosing each point. Each statement becomes a
        // `within` check (the innermost volume there must be the interior of a shape holding
        // that medium), so geometry that disagrees is an error at load, not another image.
        let holders = |m: &Rc<xml::Node>| -> Vec<toml::Value> {
            self.medium_holders
                .iter()
                .filter(|(h, _)| Rc::ptr_eq(h, m))
                .map(|(_, name)| toml::Value::from(name.as_str()))
                .collect()
        };
        let unheld = |m: &Rc<xml::Node>, what: &str| {
            self.cx.error(
                m,
                None,
                format!(
                    "{what} is not the interior of any shape: risotto's media fill closed \
                     shapes, so a medium without a boundary (Mitsuba's medium filling all \
                     space) cannot be converted; give it as the interior of a closed shape \
                     enclosing that region (a null BSDF makes the boundary invisible) and \
                     refer to it from there"
                ),
            )
        };
        if let Some(m) = &self.sensor_medium {
            let within = holders(m);
            if within.is_empty() {
                return Err(unheld(m, "the sensor's medium"));
            }
            self.scene.camera.set("within", within);
        }
        for (m, shape) in &self.exteriors {
            let within = holders(m);
            if within.is_empty() {
                return Err(unheld(m, "this exterior medium"));
            }
            self.scene.shapes[*shape].set("within", within);
        }
        // Where Mitsuba leaves a medium unset (the sensor's, a volume boundary's exterior),
        // it means vacuum: checked when the scene has media at all.
        if !self.medium_holders.is_empty() {
            if self.sensor_medium.is_none() {
                self.scene.camera.set("within", NO_MEDIUM);
            }
            for &shape in &self.no_medium_outside {
                self.scene.shapes[shape].set("within", NO_MEDIUM);
            }
        }
        Ok(())
    }
}

/// Mitsuba's `Props` for a child of the converter's plugins.
fn props<'a>(cx: &'a Cx, node: &Rc<xml::Node>) -> Result<Props<'a>, SceneError> {
    Props::new(cx, node)
}

#[cfg(test)]
mod tests;
