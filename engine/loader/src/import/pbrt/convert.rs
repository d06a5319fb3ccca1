//! The directive loop: graphics state, transforms, the camera and the render settings.
//! Shapes are in [`super::shapes`], materials, textures, media and lights in
//! [`super::materials`].

mod camera;

use camera::{camera_frame, look_at};

use std::collections::HashMap;
use std::path::Path;

use glam::{DMat4, DVec3, DVec4};
use risotto_engine::diagnostics::{Origin, SceneError, SceneErrorKind};
use risotto_engine::scene::{ShadingNormals, NO_MEDIUM};

use super::lexer::{At, Lexer, Tok};
use super::params::Params;
use crate::import::{origin, Entity, ImportOptions, ImportedScene, TomlScene};

/// The material a shape gets.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum MaterialRef {
    /// pbrt's default, `diffuse` with reflectance 0.5.
    Default,
    /// A `Material` directive's material (index into `Converter::anonymous`).
    Anonymous(usize),
    /// `NamedMaterial "name"` (looked up when a shape uses it, as pbrt does).
    Named(String, At),
}

/// An `AreaLightSource "diffuse"`: the radiance of the shapes that follow.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct AreaLight {
    /// `L * scale`, linear RGB.
    pub radiance: [f64; 3],
    /// Where it was written.
    pub at: At,
}

/// pbrt-v4's graphics state (what `AttributeBegin` saves).
#[derive(Clone, Debug)]
pub(super) struct GraphicsState {
    /// The current transformation matrix: object to world (or to camera before
    /// `WorldBegin`).
    pub ctm: DMat4,
    /// `ReverseOrientation` in effect.
    pub reverse: bool,
    /// The current material.
    pub material: MaterialRef,
    /// The current area light.
    pub area_light: Option<AreaLight>,
    /// `MediumInterface`'s inside and outside media (`""` is none).
    pub inside: String,
    /// See `inside`.
    pub outside: String,
    /// `Attribute "target"` defaults by target (`shape`, `light`, `material`, `medium`,
    /// `texture`).
    pub attributes: HashMap<String, Vec<super::params::Param>>,
}

/// A converted material definition, written into the scene when a shape first uses it.
#[derive(Clone, Debug)]
pub(super) struct MaterialDef {
    /// The TOML table (without an interior).
    pub table: toml::Table,
    /// A name for it in the TOML.
    pub name: String,
    /// Where it was defined.
    pub origin: Origin,
    /// Whether it transmits (dielectrics, interfaces): may hold a medium.
    pub transmits: bool,
}

/// The converter's state.
pub(super) struct Converter<'o> {
    /// The `alpha` of the shape being converted, as the `opacity` its material takes
    /// (taken by `material_for_shape`; `None`: opaque).
    pub shape_opacity: Option<toml::Value>,
    pub lx: Lexer,
    pub options: &'o ImportOptions<'o>,
    pub scene: TomlScene,
    pub warnings: Vec<String>,
    pub gs: GraphicsState,
    /// Saved states: (state, `true` for `AttributeBegin`, `false` for `TransformBegin`, where).
    stack: Vec<(GraphicsState, bool, At)>,
    named_coords: HashMap<String, DMat4>,
    /// Applied after every world-space transform: the mirror that turns pbrt's image x
    /// into risotto's (see [`Converter::camera`]), or the identity.
    pub world_root: DMat4,
    in_world: bool,
    camera_seen: bool,
    /// `Material` definitions.
    pub anonymous: Vec<MaterialDef>,
    /// `MakeNamedMaterial` definitions.
    pub named_materials: HashMap<String, MaterialDef>,
    /// Emitted materials: (definition name, interior medium) -> TOML name.
    pub emitted: HashMap<(String, String), String>,
    /// Named textures, as pattern values.
    pub textures: HashMap<String, toml::Value>,
    /// Named media, as `interior` tables.
    pub media: HashMap<String, (toml::Table, At)>,
    /// Media some shape holds (for the camera's medium check).
    pub media_used: Vec<String>,
    /// Each top-level shape holding a medium: the medium and the shape's name.
    pub medium_holders: Vec<(String, String)>,
    /// Each top-level shape with an outside medium other than its inside: the medium, the
    /// shape's index in `scene.shapes` and where it was written.
    pub outsides: Vec<(String, usize, At)>,
    /// Each top-level shape bounding a volume with no outside medium (vacuum outside it, or
    /// the medium unchanged across it): its index in `scene.shapes`.
    pub no_medium_outside: Vec<usize>,
    /// The object being defined: name, shapes, where.
    pub object: Option<(String, Vec<toml::Value>, At)>,
    /// The camera's medium (`MediumInterface` outside at `Camera`) and where it was set.
    camera_medium: Option<(String, At)>,
    names: HashMap<String, usize>,
}

impl<'o> Converter<'o> {
    /// A converter for the top-level file.
    pub fn new(path: &Path, text: &str, options: &'o ImportOptions<'o>) -> Converter<'o> {
        Converter {
            shape_opacity: None,
            lx: Lexer::new(path, text),
            options,
            scene: TomlScene::default(),
            warnings: Vec::new(),
            gs: GraphicsState {
                ctm: DMat4::IDENTITY,
                reverse: false,
                material: MaterialRef::Default,
                area_light: None,
                inside: String::new(),
                outside: String::new(),
                attributes: HashMap::new(),
            },
            stack: Vec::new(),
            named_coords: HashMap::new(),
            world_root: DMat4::IDENTITY,
            in_world: false,
            camera_seen: false,
            anonymous: Vec::new(),
            named_materials: HashMap::new(),
            emitted: HashMap::new(),
            textures: HashMap::new(),
            media: HashMap::new(),
            media_used: Vec::new(),
            object: None,
            camera_medium: None,
            medium_holders: Vec::new(),
            outsides: Vec::new(),
            no_medium_outside: Vec::new(),
            names: HashMap::new(),
        }
    }

    /// A name not used before, from `base` (`base`, `base_2`, ...).
    pub fn unique(&mut self, base: &str) -> String {
        let n = self.names.entry(base.to_owned()).or_insert(0);
        *n += 1;
        if *n == 1 {
            base.to_owned()
        } else {
            format!("{base}_{n}")
        }
    }

    /// The origin of `at` for a converted entity.
    pub fn origin(&self, at: &At) -> Origin {
        origin(self.lx.path(at), self.lx.line(at))
    }

    /// A located error at `at`.
    pub fn error(&self, at: &At, entity: &str, message: impl Into<String>) -> SceneError {
        self.lx
            .error(SceneErrorKind::InvalidValue, at, entity, message)
    }

    /// Reads every directive and returns the converted scene.
    pub fn run(mut self) -> Result<ImportedScene, SceneError> {
        let mut render = Entity::new(None)
            .with("width", 1280)
            .with("height", 720)
            .with("spp", 16)
            .with("max_depth", 6)
            // pbrt-v4 evaluates its BSDFs in the shading frame alone and keeps every sampled
            // direction (risotto's default discards those the two normals disagree on).
            .with("shading_normals", ShadingNormals::ShadingFrame.name())
            .with("filter", "gaussian")
            .with("filter_radius", 1.5)
            .with("filter_stddev", 0.5);
        let mut camera: Option<(Params, String, At, DMat4)> = None;
        let mut last_at = None;
        while let Some(tok) = self.lx.next()? {
            let at = tok.at.clone();
            last_at = Some(at.clone());
            let Tok::Word(name) = tok.tok else {
                return Err(self.lx.error(
                    SceneErrorKind::Syntax,
                    &at,
                    "directive",
                    "expected a directive (such as Shape or WorldBegin)",
                ));
            };
            // pbrt-v4's two blocks: options before WorldBegin, the world after it.
            let options = [
                "Camera",
                "Film",
                "Sampler",
                "Integrator",
                "PixelFilter",
                "Accelerator",
                "ColorSpace",
                "Option",
            ];
            let world = [
                "Shape",
                "LightSource",
                "AreaLightSource",
                "Material",
                "MakeNamedMaterial",
                "NamedMaterial",
                "Texture",
                "ObjectBegin",
                "ObjectEnd",
                "ObjectInstance",
                "AttributeBegin",
                "AttributeEnd",
                "Attribute",
            ];
            if self.in_world && options.contains(&name.as_str()) {
                return Err(self.error(&at, &name, format!("{name} must come before WorldBegin")));
            }
            if !self.in_world && world.contains(&name.as_str()) {
                return Err(self.error(&at, &name, format!("{name} must come after WorldBegin")));
            }
            match name.as_str() {
                "Translate" => {
                    let v = self.numbers(&at, &name, 3)?;
                    self.concat(DMat4::from_translation(DVec3::new(v[0], v[1], v[2])));
                }
                "Scale" => {
                    let v = self.numbers(&at, &name, 3)?;
                    self.concat(DMat4::from_scale(DVec3::new(v[0], v[1], v[2])));
                }
                "Rotate" => {
                    let v = self.numbers(&at, &name, 4)?;
                    let axis = DVec3::new(v[1], v[2], v[3]);
                    if axis.length_squared() == 0.0 {
                        return Err(self.error(&at, &name, "the rotation axis is zero"));
                    }
                    // Right-handed rotation by an angle in degrees about the axis (pbrt-v4
                    // `Rotate`, Rodrigues' formula).
                    self.concat(DMat4::from_axis_angle(axis.normalize(), v[0].to_radians()));
                }
                "LookAt" => {
                    let v = self.numbers(&at, &name, 9)?;
                    let m = look_at(&v).ok_or_else(|| {
                        self.error(&at, &name, "eye and look-at point coincide, or up is parallel to the view direction")
                    })?;
                    self.concat(m);
                }
                "Identity" => self.gs.ctm = DMat4::IDENTITY,
                "Transform" | "ConcatTransform" => {
                    let v = self.matrix(&at, &name)?;
                    let m = DMat4::from_cols_array(&v);
                    if name == "Transform" {
                        self.gs.ctm = m;
                    } else {
                        self.concat(m);
                    }
                }
                "CoordinateSystem" => {
                    let n = self.string_arg(&at, &name)?;
                    self.named_coords.insert(n, self.gs.ctm);
                }
                "CoordSysTransform" => {
                    let n = self.string_arg(&at, &name)?;
                    match self.named_coords.get(&n) {
                        Some(m) => self.gs.ctm = *m,
                        None => {
                            return Err(self.error(
                                &at,
                                &name,
                                format!("no coordinate system named \"{n}\" (name one with CoordinateSystem, or \"camera\" after Camera)"),
                            ))
                        }
                    }
                }
                "ReverseOrientation" => self.gs.reverse = !self.gs.reverse,
                "AttributeBegin" | "TransformBegin" => {
                    self.stack
                        .push((self.gs.clone(), name == "AttributeBegin", at.clone()));
                }
                "AttributeEnd" | "TransformEnd" => {
                    let attribute = name == "AttributeEnd";
                    match self.stack.pop() {
                        Some((saved, was_attribute, _)) if was_attribute == attribute => {
                            if attribute {
                                self.gs = saved;
                            } else {
                                self.gs.ctm = saved.ctm;
                            }
                        }
                        Some((_, _, begin)) => {
                            return Err(self.error(
                                &at,
                                &name,
                                format!(
                                    "does not match the {} at line {}",
                                    if attribute {
                                        "TransformBegin"
                                    } else {
                                        "AttributeBegin"
                                    },
                                    self.lx.line(&begin)
                                ),
                            ))
                        }
                        None => return Err(self.error(&at, &name, "has no matching Begin")),
                    }
                }
                "ActiveTransform" => {
                    let Some(t) = self.lx.next()? else {
                        return Err(self.error(&at, &name, "expects StartTime, EndTime or All"));
                    };
                    match t.tok {
                        Tok::Word(w) if w == "All" => {}
                        _ => {
                            return Err(self.error(
                                &t.at,
                                &name,
                                "animated transforms (motion blur) are not supported: only `ActiveTransform All`",
                            ))
                        }
                    }
                }
                "TransformTimes" => {
                    self.numbers(&at, &name, 2)?;
                }
                "Option" => {
                    let p = Params::read(&mut self.lx, "Option")?;
                    if let Some(first) = p.list.first() {
                        let ignorable = ["disablepixeljitter", "disablewavelengthjitter", "seed"];
                        if !ignorable.contains(&first.name.as_str()) || p.list.len() > 1 {
                            return Err(p.error(&self.lx, first, "this Option is not supported"));
                        }
                        p.ignore(&first.name.clone());
                    }
                }
                "ColorSpace" => {
                    let n = self.string_arg(&at, &name)?;
                    if n != "srgb" {
                        return Err(self.error(
                            &at,
                            &name,
                            format!("color space \"{n}\" is not supported (risotto renders linear Rec.709 / sRGB primaries)"),
                        ));
                    }
                }
                "Camera" => {
                    let ty = self.string_arg(&at, &name)?;
                    let p = Params::read(&mut self.lx, &format!("Camera \"{ty}\""))?;
                    let ctm = self.gs.ctm;
                    if ctm.determinant() == 0.0 || !ctm.is_finite() {
                        return Err(self.error(&at, &name, "the camera transform is singular"));
                    }
                    self.named_coords.insert("camera".into(), ctm.inverse());
                    if !self.gs.outside.is_empty() {
                        self.camera_medium = Some((self.gs.outside.clone(), at.clone()));
                    }
                    self.camera_seen = true;
                    camera = Some((p, ty, at, ctm));
                }
                "Film" | "Sampler" | "Integrator" | "PixelFilter" | "Accelerator" => {
                    let ty = self.string_arg(&at, &name)?;
                    let p = Params::read(&mut self.lx, &format!("{name} \"{ty}\""))?;
                    self.render_setting(&name, &ty, &p, &at, &mut render)?;
                    p.finish(&self.lx)?;
                }
                "WorldBegin" => {
                    if self.in_world {
                        return Err(self.error(&at, &name, "WorldBegin is given twice"));
                    }
                    self.in_world = true;
                    self.named_coords.insert("world".into(), DMat4::IDENTITY);
                    self.gs.ctm = DMat4::IDENTITY;
                    self.begin_world(camera.as_ref().map(|c| c.3))?;
                }
                "WorldEnd" => {}
                "Include" | "Import" => {
                    let file = self.string_arg(&at, &name)?;
                    let path = self.lx.resolve(&at, &file);
                    self.lx.push_file(&path, &at, &name)?;
                }
                "MakeNamedMedium" => {
                    let n = self.string_arg(&at, &name)?;
                    let p = Params::read(&mut self.lx, &format!("MakeNamedMedium \"{n}\""))?
                        .with_defaults(self.gs.attributes.get("medium"));
                    let medium_space = self.world_root * self.gs.ctm;
                    let table = self.medium(&p, &at, &medium_space)?;
                    p.finish(&self.lx)?;
                    self.media.insert(n, (table, at));
                }
                "MediumInterface" => {
                    let inside = self.string_arg(&at, &name)?;
                    let outside = match self.lx.peek()? {
                        Some(t) if matches!(t.tok, Tok::Str(_)) => self.string_arg(&at, &name)?,
                        _ => inside.clone(),
                    };
                    for m in [&inside, &outside] {
                        if !m.is_empty() && !self.media.contains_key(m) {
                            return Err(self.error(&at, &name, format!("no medium named \"{m}\" (define it with MakeNamedMedium first)")));
                        }
                    }
                    self.gs.inside = inside;
                    self.gs.outside = outside;
                }
                "Attribute" => {
                    let target = self.string_arg(&at, &name)?;
                    let targets = ["shape", "light", "material", "medium", "texture"];
                    if !targets.contains(&target.as_str()) {
                        return Err(self.error(
                            &at,
                            &name,
                            format!(
                                "unknown target \"{target}\"; expected one of {}",
                                targets.join(", ")
                            ),
                        ));
                    }
                    let p = Params::read(&mut self.lx, &format!("Attribute \"{target}\""))?;
                    let list = self.gs.attributes.entry(target).or_default();
                    for q in p.list {
                        list.retain(|old| old.name != q.name);
                        list.push(q);
                    }
                }
                "Material" => {
                    let ty = self.string_arg(&at, &name)?;
                    let entity = format!("Material \"{ty}\"");
                    let p = Params::read(&mut self.lx, &entity)?
                        .with_defaults(self.gs.attributes.get("material"));
                    let def =
                        self.material(&ty, &p, &at, &format!("{ty}_{}", self.lx.line(&at)))?;
                    p.finish(&self.lx)?;
                    self.anonymous.push(def);
                    self.gs.material = MaterialRef::Anonymous(self.anonymous.len() - 1);
                }
                "MakeNamedMaterial" => {
                    let n = self.string_arg(&at, &name)?;
                    let entity = format!("MakeNamedMaterial \"{n}\"");
                    let p = Params::read(&mut self.lx, &entity)?
                        .with_defaults(self.gs.attributes.get("material"));
                    let ty = match p.string(&self.lx, "type")? {
                        Some((t, _)) => t.to_owned(),
                        None => return Err(self.error(&at, &entity, "needs \"string type\"")),
                    };
                    let def = self.material(&ty, &p, &at, &n)?;
                    p.finish(&self.lx)?;
                    self.named_materials.insert(n, def);
                }
                "NamedMaterial" => {
                    let n = self.string_arg(&at, &name)?;
                    self.gs.material = MaterialRef::Named(n, at);
                }
                "Texture" => {
                    let n = self.string_arg(&at, &name)?;
                    let class = self.string_arg(&at, &name)?;
                    let ty = self.string_arg(&at, &name)?;
                    let entity = format!("Texture \"{n}\"");
                    let p = Params::read(&mut self.lx, &entity)?
                        .with_defaults(self.gs.attributes.get("texture"));
                    let v = self.texture(&class, &ty, &p, &at, &entity)?;
                    p.finish(&self.lx)?;
                    self.textures.insert(n, v);
                }
                "LightSource" => {
                    let ty = self.string_arg(&at, &name)?;
                    let p = Params::read(&mut self.lx, &format!("LightSource \"{ty}\""))?
                        .with_defaults(self.gs.attributes.get("light"));
                    self.light(&ty, &p, &at)?;
                    p.finish(&self.lx)?;
                }
                "AreaLightSource" => {
                    let ty = self.string_arg(&at, &name)?;
                    let entity = format!("AreaLightSource \"{ty}\"");
                    let p = Params::read(&mut self.lx, &entity)?
                        .with_defaults(self.gs.attributes.get("light"));
                    self.area_light(&ty, &p, &at)?;
                    p.finish(&self.lx)?;
                }
                "Shape" => {
                    let ty = self.string_arg(&at, &name)?;
                    let p = Params::read(&mut self.lx, &format!("Shape \"{ty}\""))?
                        .with_defaults(self.gs.attributes.get("shape"));
                    self.shape(&ty, &p, &at)?;
                    p.finish(&self.lx)?;
                }
                "ObjectBegin" => {
                    let n = self.string_arg(&at, &name)?;
                    if let Some((open, _, begin)) = &self.object {
                        return Err(self.error(
                            &at,
                            &name,
                            format!(
                                "object \"{open}\" (line {}) is still open",
                                self.lx.line(begin)
                            ),
                        ));
                    }
                    if self.scene.objects.iter().any(|(o, _)| *o == n) {
                        return Err(self.error(
                            &at,
                            &name,
                            format!("object \"{n}\" is defined twice"),
                        ));
                    }
                    self.stack.push((self.gs.clone(), true, at.clone()));
                    self.object = Some((n, Vec::new(), at));
                }
                "ObjectEnd" => {
                    let Some((n, shapes, begin)) = self.object.take() else {
                        return Err(self.error(&at, &name, "has no matching ObjectBegin"));
                    };
                    if let Some((saved, _, _)) = self.stack.pop() {
                        self.gs = saved;
                    }
                    let e = Entity::new(Some(self.origin(&begin))).with("shapes", shapes);
                    self.scene.objects.push((n, e));
                }
                "ObjectInstance" => {
                    let n = self.string_arg(&at, &name)?;
                    if !self.scene.objects.iter().any(|(o, _)| *o == n) {
                        return Err(self.error(
                            &at,
                            &name,
                            format!("no object named \"{n}\" (define it with ObjectBegin before)"),
                        ));
                    }
                    let m = self.world_root * self.gs.ctm;
                    let e = Entity::new(Some(self.origin(&at)))
                        .with("type", "instance")
                        .with("object", n.as_str())
                        .with("transform", self.transform_value(&m, &at, &name)?);
                    self.scene.shapes.push(e);
                }
                other => {
                    return Err(self.lx.error(
                        SceneErrorKind::InvalidValue,
                        &at,
                        "directive",
                        format!(
                            "unknown or unsupported directive `{other}` (see docs/import-pbrt.md)"
                        ),
                    ))
                }
            }
        }
        if let Some((_, _, begin)) = self.stack.last() {
            return Err(self.error(begin, "AttributeBegin", "is never ended"));
        }
        if !self.in_world {
            return Err(match last_at {
                Some(at) => self.error(&at, "scene", "the file has no WorldBegin"),
                None => SceneError::unlocated(
                    &self.lx.files[0].path,
                    SceneErrorKind::InvalidValue,
                    "the pbrt file is empty (no WorldBegin)",
                ),
            });
        }
        if let Some((p, ty, at, _)) = camera {
            self.camera(&ty, &p, &at, &render)?;
            p.finish(&self.lx)?;
        } else {
            self.default_camera(&render);
        }
        // pbrt states the medium around the camera and outside each shape; risotto infers
        // both from the closed shapes enclosing a point, so each statement becomes a
        // `within` check of the geometry (docs/scene-format.md).
        let holders = |m: &str| -> Vec<toml::Value> {
            self.medium_holders
                .iter()
                .filter(|(h, _)| h == m)
                .map(|(_, name)| toml::Value::from(name.as_str()))
                .collect()
        };
        if let Some((m, at)) = self.camera_medium.clone() {
            let within = holders(&m);
            if within.is_empty() {
                return Err(self.error(&at, "Camera", format!("the camera is in medium \"{m}\", but no shape has it inside (risotto's media are the interiors of closed shapes: put the camera inside a shape with `MediumInterface \"{m}\" \"\"`)")));
            }
            self.scene.camera.set("within", within);
        }
        for (m, shape, at) in &self.outsides {
            let within = holders(m);
            if within.is_empty() {
                return Err(self.error(at, "Shape", format!("the shape's outside medium \"{m}\" is no shape's inside (risotto's media are the interiors of closed shapes: enclose the shape in one with `MediumInterface \"{m}\" \"\"`)")));
            }
            self.scene.shapes[*shape].set("within", within);
        }
        // Where pbrt leaves a medium unset (no camera medium, a volume's boundary without
        // an outside medium), it means vacuum: checked when the scene has media at all.
        if !self.medium_holders.is_empty() {
            if self.camera_medium.is_none() {
                self.scene.camera.set("within", NO_MEDIUM);
            }
            for &shape in &self.no_medium_outside {
                self.scene.shapes[shape].set("within", NO_MEDIUM);
            }
        }
        self.scene.render = render;
        self.scene.header = vec![format!(
            "converted from the pbrt-v4 scene {}",
            self.lx.files[0].path.display()
        )];
        Ok(ImportedScene {
            scene: self.scene,
            warnings: self.warnings,
        })
    }

    /// `ctm = ctm * m` (pbrt post-multiplies).
    fn concat(&mut self, m: DMat4) {
        self.gs.ctm *= m;
    }

    /// `n` numbers following a directive.
    fn numbers(&mut self, at: &At, name: &str, n: usize) -> Result<Vec<f64>, SceneError> {
        let mut out = Vec::with_capacity(n);
        while out.len() < n {
            match self.lx.next()? {
                Some(t) => match t.tok {
                    Tok::Num(v) => out.push(v),
                    _ => {
                        return Err(self.lx.error(
                            SceneErrorKind::Syntax,
                            &t.at,
                            name,
                            format!(
                                "{name} expects {n} numbers, found {} and then this",
                                out.len()
                            ),
                        ))
                    }
                },
                None => {
                    return Err(self.lx.error(
                        SceneErrorKind::Syntax,
                        at,
                        name,
                        format!(
                            "{name} expects {n} numbers, the file ends after {}",
                            out.len()
                        ),
                    ))
                }
            }
        }
        Ok(out)
    }

    /// 16 numbers, bracketed or not (column by column: the translation is 13-15).
    fn matrix(&mut self, at: &At, name: &str) -> Result<[f64; 16], SceneError> {
        let bracketed = matches!(self.lx.peek()?, Some(t) if t.tok == Tok::Open);
        if bracketed {
            self.lx.next()?;
        }
        let v = self.numbers(at, name, 16)?;
        if bracketed {
            match self.lx.next()? {
                Some(t) if t.tok == Tok::Close => {}
                _ => {
                    return Err(self.lx.error(
                        SceneErrorKind::Syntax,
                        at,
                        name,
                        format!("{name} expects 16 numbers and a closing `]`"),
                    ))
                }
            }
        }
        let mut m = [0.0; 16];
        m.copy_from_slice(&v);
        Ok(m)
    }

    /// One quoted string after a directive (or a one-string list `[ "x" ]`).
    pub fn string_arg(&mut self, at: &At, name: &str) -> Result<String, SceneError> {
        let t = self.lx.next()?;
        match t {
            Some(t) => match t.tok {
                Tok::Str(s) => Ok(s),
                _ => Err(self.lx.error(
                    SceneErrorKind::Syntax,
                    &t.at,
                    name,
                    format!("{name} expects a quoted string here"),
                )),
            },
            None => Err(self.lx.error(
                SceneErrorKind::Syntax,
                at,
                name,
                format!("{name} expects a quoted string; the file ends"),
            )),
        }
    }

    /// `m` as a TOML transform list (one `matrix` step), checking it is affine and
    /// invertible.
    pub fn transform_value(
        &self,
        m: &DMat4,
        at: &At,
        entity: &str,
    ) -> Result<toml::Value, SceneError> {
        let row3 = m.row(3);
        if (row3 - DVec4::new(0.0, 0.0, 0.0, 1.0)).abs().max_element() > 1e-9 {
            return Err(self.error(
                at,
                entity,
                "the transform is projective (its last row is not 0 0 0 1)",
            ));
        }
        if !m.is_finite() || m.determinant() == 0.0 {
            return Err(self.error(at, entity, "the transform is singular or not finite"));
        }
        let rows: Vec<toml::Value> = (0..3)
            .map(|i| {
                let r = m.row(i);
                toml::Value::Array(vec![r.x.into(), r.y.into(), r.z.into(), r.w.into()])
            })
            .collect();
        let mut step = toml::Table::new();
        step.insert("matrix".into(), toml::Value::Array(rows));
        Ok(toml::Value::Array(vec![toml::Value::Table(step)]))
    }

    /// `WorldBegin`: decides the world mirror from the camera (see [`Converter::camera`]).
    fn begin_world(&mut self, camera_from_world: Option<DMat4>) -> Result<(), SceneError> {
        let world_from_camera = camera_from_world.unwrap_or(DMat4::IDENTITY).inverse();
        let (pos, fwd, up, right) = camera_frame(&world_from_camera);
        // risotto's image right is cross(forward, up); pbrt's is the camera's +x. When they
        // are opposite (pbrt's plain LookAt, whose camera space is left-handed), the whole
        // world is mirrored across the plane through the eye spanned by the view direction
        // and up: the camera then sees what pbrt's does, with its x axis where pbrt's is.
        let risotto_right = fwd.cross(up).normalize();
        if right.dot(risotto_right) < 0.0 {
            let n = risotto_right;
            // Householder reflection about the plane {p : (p - pos) . n = 0}.
            let r = glam::DMat3::IDENTITY - 2.0 * glam::DMat3::from_cols(n * n.x, n * n.y, n * n.z);
            let t = pos - r * pos;
            self.world_root = DMat4::from_cols(
                r.x_axis.extend(0.0),
                r.y_axis.extend(0.0),
                r.z_axis.extend(0.0),
                t.extend(1.0),
            );
        }
        Ok(())
    }
}
