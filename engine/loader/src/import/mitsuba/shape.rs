//! Shapes: `obj`, `ply` (meshes), `cube`, `sphere`, `rectangle`, `disk`, with their BSDF,
//! area emitter and interior medium; `shapegroup` and `instance` as TOML objects and
//! instances.

use std::rc::Rc;

use glam::{DMat3, DVec3};
use risotto_engine::diagnostics::SceneError;

use super::transform::Transform;
use super::xml::Node;
use super::{props, Converter};
use crate::import::spectrum::SpectrumUse;
use crate::import::Entity;

/// Shape parameters that cannot change the image.
const HARMLESS: &[&str] = &["optimize"];

/// What a medium needs to know of the shape it fills: its object-space box and transform.
pub(super) struct Placement {
    /// Object-space bounds (`None`: not known without reading the mesh).
    pub bounds: Option<(DVec3, DVec3)>,
    /// Object to world.
    pub to_world: glam::DMat4,
}

impl Converter<'_> {
    /// A `shapegroup` (its shapes defined once, placed by `instance`s) as a TOML object,
    /// converted once however often it is referenced; returns the object's name.
    fn shapegroup(&mut self, node: &Rc<Node>) -> Result<String, SceneError> {
        if let Some((_, name)) = self.groups.iter().find(|(n, _)| Rc::ptr_eq(n, node)) {
            return Ok(name.clone());
        }
        let p = props(self.cx, node)?;
        if self.group_shapes.is_some() {
            return Err(p.error(None, "a shapegroup inside a shapegroup is not supported"));
        }
        let shapes = p.unnamed("shape")?;
        if shapes.is_empty() {
            return Err(p.error(None, "an empty shapegroup"));
        }
        self.group_shapes = Some(Vec::new());
        let converted: Result<(), SceneError> =
            shapes.iter().try_for_each(|child| self.shape(child));
        let entities = self.group_shapes.take().unwrap_or_default();
        converted?;
        p.finish(&[])?;
        let base = node.attr("id").unwrap_or("shapegroup").to_owned();
        let mut name = base.clone();
        let mut k = 1;
        while self.scene.objects.iter().any(|(n, _)| *n == name) {
            k += 1;
            name = format!("{base}_{k}");
        }
        let list: Vec<toml::Value> = entities
            .into_iter()
            .map(|mut e| {
                // Names are for shapes placed once; an object's shapes have none.
                e.table.remove("name");
                toml::Value::Table(e.table)
            })
            .collect();
        let object = Entity::new(self.origin(node)).with("shapes", list);
        self.scene.objects.push((name.clone(), object));
        self.groups.push((node.clone(), name.clone()));
        Ok(name)
    }

    /// An `instance` of a `shapegroup` (by reference or nested): a TOML `instance` shape.
    fn instance(&mut self, node: &Rc<Node>) -> Result<(), SceneError> {
        let p = props(self.cx, node)?;
        if self.group_shapes.is_some() {
            return Err(p.error(None, "an instance inside a shapegroup is not supported"));
        }
        let group = p
            .one_unnamed("shape")?
            .ok_or_else(|| p.error(None, "an instance needs the shapegroup it places"))?;
        let group = self.cx.deref(&group)?;
        let gp = props(self.cx, &group)?;
        if gp.kind()? != "shapegroup" {
            return Err(gp.error(Some("type"), "an instance places a shapegroup"));
        }
        let object = self.shapegroup(&group)?;
        let mut e = Entity::new(self.origin(node))
            .with("type", "instance")
            .with("object", object);
        if let Some(t) = p.transform("to_world")? {
            e.set("transform", t.toml());
        }
        if let Some(id) = node.attr("id") {
            let name = Converter::unique(&mut self.names, id);
            e.set("name", name);
        }
        p.finish(&[])?;
        self.scene.shapes.push(e);
        Ok(())
    }

    /// One `<shape>`.
    pub(super) fn shape(&mut self, node: &Rc<Node>) -> Result<(), SceneError> {
        let p = props(self.cx, node)?;
        let kind = p.kind()?;
        match kind.as_str() {
            "shapegroup" => return self.shapegroup(node).map(|_| ()),
            "instance" => return self.instance(node),
            _ => {}
        }
        let mut e = Entity::new(self.origin(node));
        let to_world = p.transform("to_world")?;
        let flip = p.boolean("flip_normals")?.unwrap_or(false);
        let flip_error = || {
            p.error(
                Some("flip_normals"),
                format!("flip_normals on a {kind} is not converted (risotto's closed shapes face outwards)"),
            )
        };
        let mut placement = Placement {
            bounds: None,
            to_world: to_world
                .as_ref()
                .map_or(glam::DMat4::IDENTITY, |t| t.matrix),
        };
        let set_transform = |e: &mut Entity, t: &Option<Transform>| {
            if let Some(t) = t {
                e.set("transform", t.toml());
            }
        };
        match kind.as_str() {
            "rectangle" | "disk" => {
                e.set("type", kind.as_str());
                // A mirror along local z turns the normal and keeps the (symmetric) shape.
                let t = if flip {
                    let mirror = Transform {
                        steps: vec![toml::Value::Table(toml::Table::from_iter([(
                            "scale".to_owned(),
                            super::bsdf::rgb([1.0, 1.0, -1.0]),
                        )]))],
                        matrix: glam::DMat4::from_scale(DVec3::new(1.0, 1.0, -1.0)),
                    };
                    Some(mirror.then(&to_world.clone().unwrap_or_default()))
                } else {
                    to_world.clone()
                };
                set_transform(&mut e, &t);
            }
            "cube" => {
                if flip {
                    return Err(flip_error());
                }
                e.set("type", "box");
                set_transform(&mut e, &to_world);
                placement.bounds = Some((DVec3::splat(-1.0), DVec3::splat(1.0)));
                if to_world.is_none() {
                    placement.to_world = glam::DMat4::IDENTITY;
                }
            }
            "sphere" => {
                if flip {
                    return Err(flip_error());
                }
                let c = DVec3::from(p.vec3("center")?.unwrap_or([0.0; 3]));
                let r = p.float_or("radius", 1.0)?;
                // Mitsuba: to_world * translate(center) * scale(radius); risotto's sphere
                // has no transform, so the product must be a uniform scale and translation.
                let m = placement.to_world;
                let lin = DMat3::from_mat4(m);
                let s = lin.x_axis.x;
                let tol = 1e-9 * s.abs().max(1e-300);
                let diagonal = (lin - DMat3::from_diagonal(DVec3::splat(s)))
                    .to_cols_array()
                    .iter()
                    .all(|v| v.abs() <= tol);
                if !diagonal || s <= 0.0 {
                    return Err(p.error(
                        Some("to_world"),
                        "a sphere's to_world must be a uniform scale and translation (risotto's \
                         sphere is not transformed; a rotation would turn its texture \
                         coordinates, other scales make an ellipsoid)",
                    ));
                }
                let center = m.transform_point3(c);
                let radius = s * r;
                e.set("type", "sphere");
                e.set("center", super::sensor::vec3(center));
                e.set("radius", radius);
                placement.bounds = Some((center - radius, center + radius));
                placement.to_world = glam::DMat4::IDENTITY;
            }
            "obj" | "ply" => {
                let file = p.string("filename")?.ok_or_else(|| {
                    p.error(Some("filename"), format!("a {kind} shape needs a filename"))
                })?;
                e.set("type", "mesh");
                e.set("path", self.file_path(node, &file));
                if p.boolean("face_normals")? == Some(true) {
                    e.set("face_normals", true);
                }
                if flip {
                    e.set("flip_normals", true);
                }
                // Mitsuba reads an OBJ's texture coordinates upside down unless told not to
                // (`flip_tex_coords`, default true for `obj`, false for `ply`).
                if p.boolean("flip_tex_coords")?.unwrap_or(kind == "obj") {
                    e.set("flip_tex_coords", true);
                }
                // Mitsuba has no shadow-terminator offset: render as it does.
                e.set("shadow_terminator_offset", false);
                set_transform(&mut e, &to_world);
            }
            other => {
                return Err(p.error(
                    Some("type"),
                    format!(
                        "shape type \"{other}\" is not supported (obj, ply, cube, sphere, \
                         rectangle, disk, shapegroup, instance)"
                    ),
                ))
            }
        }
        let bsdf = p.one_unnamed("bsdf")?;
        let interior = match p.object("interior", "medium")? {
            Some(m) => {
                if kind == "rectangle" || kind == "disk" {
                    return Err(p.error(
                        Some("interior"),
                        format!("a {kind} is open: it cannot hold an interior medium"),
                    ));
                }
                self.has_media = true;
                let table = self.medium_table(&m, &placement)?;
                Some((m, table))
            }
            None => None,
        };
        let exterior = p.object("exterior", "medium")?;
        if let (Some(ext), Some(_)) = (&exterior, &self.group_shapes) {
            return Err(self.cx.error(
                ext,
                Some("exterior"),
                "a shape in a shapegroup cannot state an exterior medium (its instances may \
                 sit anywhere)",
            ));
        }
        // A shape that holds or borders a medium is named, so that `within` checks can
        // refer to it (finish_media).
        let name = match node.attr("id") {
            Some(id) => Some(Converter::unique(&mut self.names, id)),
            None if self.group_shapes.is_none() && (interior.is_some() || exterior.is_some()) => {
                let line = self.cx.doc.origin(node).1;
                Some(Converter::unique(
                    &mut self.names,
                    &format!("{kind} at line {line}"),
                ))
            }
            None => None,
        };
        if let Some(name) = &name {
            e.set("name", name.as_str());
        }
        let interior_medium = interior.as_ref().map(|(m, _)| m.clone());
        let has_interior = interior.is_some();
        let material = self.material(bsdf, interior, node)?;
        // Mitsuba leaves the medium unchanged across a shape without media, and switches to
        // vacuum leaving a shape whose exterior is unset; risotto nests volumes. The two
        // agree when no medium surrounds such a shape that bounds a volume (a medium's
        // boundary, a glass, a null boundary): finish_media writes that check (`within =
        // "no medium"`) when the scene has media, so a scene where they disagree is an
        // error at load, not another image.
        let bounds_volume = has_interior || self.scene.bounds_clear_volume(&material);
        let mut name = name;
        if self.group_shapes.is_none() && bounds_volume && exterior.is_none() {
            if name.is_none() {
                let line = self.cx.doc.origin(node).1;
                let n = Converter::unique(&mut self.names, &format!("{kind} at line {line}"));
                e.set("name", n.as_str());
                name = Some(n);
            }
            self.no_medium_outside.push(self.scene.shapes.len());
        }
        e.set("material", material);
        if let Some(em) = p.one_unnamed("emitter")? {
            let ep = props(self.cx, &em)?;
            if ep.kind()? != "area" {
                return Err(ep.error(
                    Some("type"),
                    "only an area emitter can be attached to a shape",
                ));
            }
            let radiance = self
                .constant_use(&ep, "radiance", SpectrumUse::Emission)?
                .ok_or_else(|| ep.error(Some("radiance"), "an area emitter needs a radiance"))?;
            ep.finish(&["sampling_weight"])?;
            e.set("emission", super::bsdf::rgb(radiance));
        }
        p.finish(HARMLESS)?;
        // World bounds of analytic shapes, for the near-clip check.
        let local = match kind.as_str() {
            "rectangle" | "disk" => Some((DVec3::new(-1.0, -1.0, 0.0), DVec3::new(1.0, 1.0, 0.0))),
            "cube" => Some((DVec3::splat(-1.0), DVec3::splat(1.0))),
            _ => None,
        };
        let world = match (kind.as_str(), local) {
            ("sphere", _) => placement.bounds,
            (_, Some((lo, hi))) => {
                let m = to_world
                    .as_ref()
                    .map_or(glam::DMat4::IDENTITY, |t| t.matrix);
                let mut b = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
                for i in 0..8 {
                    let c = DVec3::new(
                        if i & 1 == 0 { lo.x } else { hi.x },
                        if i & 2 == 0 { lo.y } else { hi.y },
                        if i & 4 == 0 { lo.z } else { hi.z },
                    );
                    let w = m.transform_point3(c);
                    b = (b.0.min(w), b.1.max(w));
                }
                Some(b)
            }
            _ => None,
        };
        match &mut self.group_shapes {
            Some(group) => group.push(e),
            None => {
                if let (Some(m), Some(name)) = (interior_medium, &name) {
                    self.medium_holders.push((m, name.clone()));
                }
                if let Some(m) = exterior {
                    self.exteriors.push((m, self.scene.shapes.len()));
                }
                self.shape_bounds.push((node.clone(), world));
                self.scene.shapes.push(e);
            }
        }
        Ok(())
    }
}
