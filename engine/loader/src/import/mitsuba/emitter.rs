//! Emitters that are not on shapes: `constant`, `envmap`, `point`, `spot`, `directional`.

use std::rc::Rc;

use glam::DVec3;
use risotto_engine::diagnostics::SceneError;

use super::bsdf::rgb;
use super::sensor::vec3;
use super::xml::Node;
use super::{props, Converter};
use crate::import::spectrum::SpectrumUse;
use crate::import::Entity;

/// Emitter parameters that only change how it is sampled.
const SAMPLING_ONLY: &[&str] = &["sampling_weight", "mis_compensation"];

impl Converter<'_> {
    /// One top-level `<emitter>`.
    pub(super) fn emitter(&mut self, node: &Rc<Node>) -> Result<(), SceneError> {
        let p = props(self.cx, node)?;
        let kind = p.kind()?;
        let mut e = Entity::new(self.origin(node));
        if let Some(id) = node.attr("id") {
            let mut used: Vec<String> = self
                .scene
                .lights
                .iter()
                .filter_map(|l| {
                    l.table
                        .get("name")
                        .and_then(|n| n.as_str())
                        .map(str::to_owned)
                })
                .collect();
            e.set("name", Converter::unique(&mut used, id));
        }
        let to_world = p.transform("to_world")?;
        let m = to_world
            .as_ref()
            .map_or(glam::DMat4::IDENTITY, |t| t.matrix);
        let emission = |name: &str| -> Result<Option<[f64; 3]>, SceneError> {
            self.constant_use(&p, name, SpectrumUse::Emission)
        };
        match kind.as_str() {
            "constant" | "envmap" => {
                if self
                    .scene
                    .lights
                    .iter()
                    .any(|l| l.table.get("type").and_then(|t| t.as_str()) == Some("environment"))
                {
                    return Err(p.error(
                        Some("type"),
                        "a second constant or envmap emitter: risotto has one environment",
                    ));
                }
                e.set("type", "environment");
                if kind == "constant" {
                    let r = emission("radiance")?.unwrap_or([1.0; 3]);
                    e.set("radiance", rgb(r));
                } else {
                    let file = p
                        .string("filename")?
                        .ok_or_else(|| p.error(Some("filename"), "an envmap needs a filename"))?;
                    if !file.to_ascii_lowercase().ends_with(".exr") {
                        return Err(p.error(
                            Some("filename"),
                            format!("`{file}`: only EXR environment maps are read"),
                        ));
                    }
                    e.set("map", self.file_path(node, &file));
                    e.set("convention", "mitsuba");
                    let scale = p.float_or("scale", 1.0)?;
                    if scale != 1.0 {
                        e.set("radiance", scale);
                    }
                    if let Some(t) = &to_world {
                        e.set("transform", t.toml());
                    }
                    if let Some(f) = p.string("filter_type")? {
                        match f.as_str() {
                            "bilinear" => {}
                            "nearest" => e.set("filter", "nearest"),
                            other => {
                                return Err(p.error(
                                    Some("filter_type"),
                                    format!("filter_type \"{other}\" is not bilinear or nearest"),
                                ))
                            }
                        }
                    }
                }
            }
            "point" => {
                e.set("type", "point");
                let pos = match p.vec3("position")? {
                    Some(v) if to_world.is_none() => DVec3::from(v),
                    Some(_) => {
                        return Err(p.error(Some("position"), "give position or to_world, not both"))
                    }
                    None => m.transform_point3(DVec3::ZERO),
                };
                e.set("position", vec3(pos));
                e.set("intensity", rgb(emission("intensity")?.unwrap_or([1.0; 3])));
            }
            "spot" => {
                e.set("type", "spot");
                let pos = m.transform_point3(DVec3::ZERO);
                let dir = m.transform_vector3(DVec3::Z);
                e.set("position", vec3(pos));
                e.set("direction", vec3(dir.normalize()));
                e.set("intensity", rgb(emission("intensity")?.unwrap_or([1.0; 3])));
                let cutoff = p.float_or("cutoff_angle", 20.0)?;
                let beam = p.float_or("beam_width", cutoff * 0.75)?;
                e.set("cutoff_angle", cutoff);
                e.set("beam_width", beam);
                if let Some(t) = p.object("texture", "texture")? {
                    let tp = props(self.cx, &t)?;
                    let file = (tp.kind()? == "bitmap")
                        .then(|| tp.string("filename"))
                        .transpose()?
                        .flatten()
                        .ok_or_else(|| {
                            tp.error(
                                Some("filename"),
                                "a spot's texture must be a bitmap with a filename",
                            )
                        })?;
                    tp.finish(&["filter_type", "wrap_mode", "raw"])?;
                    e.set("texture", self.file_path(&t, &file));
                    e.set("up", vec3(m.transform_vector3(DVec3::Y).normalize()));
                }
            }
            "directional" => {
                e.set("type", "distant");
                let dir = match p.vec3("direction")? {
                    Some(d) if to_world.is_none() => DVec3::from(d),
                    Some(_) => {
                        return Err(
                            p.error(Some("direction"), "give direction or to_world, not both")
                        )
                    }
                    None => m.transform_vector3(DVec3::Z),
                };
                if dir.length() == 0.0 {
                    return Err(p.error(Some("direction"), "the direction is zero"));
                }
                e.set("direction", vec3(dir));
                e.set(
                    "irradiance",
                    rgb(emission("irradiance")?.unwrap_or([1.0; 3])),
                );
            }
            "area" => return Err(p.error(Some("type"), "an area emitter belongs inside a <shape>")),
            other => {
                return Err(p.error(
                    Some("type"),
                    format!(
                        "emitter type \"{other}\" is not supported (area, constant, envmap, \
                         point, spot, directional)"
                    ),
                ))
            }
        }
        p.finish(SAMPLING_ONLY)?;
        self.scene.lights.push(e);
        Ok(())
    }
}
