//! The scene file format (TOML) and its loader.
//!
//! [`load_scene`] / [`parse_scene`] turn a scene file into a validated, resolved
//! [`SceneDesc`]: every field checked, names resolved to indices, quads, boxes and OBJ
//! meshes turned into world-space triangles, relative paths resolved against the scene
//! file. The format is documented field by field in `docs/scene-format.md`.
//!
//! Materials are the exception to "validated": users register their own material types,
//! so a material's `type` and parameters are kept as raw TOML ([`MaterialParams`]) for its
//! factory to read, with the same located error messages.
//!
//! Every error is a [`SceneError`] whose message names the file, line and column, the
//! entity (`shapes[3] "tall_box"`, `materials.glass`, `camera`), the field and the offending
//! value. No input makes the loader panic.
//!
//! Conventions: right-handed coordinates, +y up; colours are linear Rec.709 RGB;
//! transforms apply in the order written (`p_world = T_n ... T_1 p_local`).

mod camera;
mod disk;
mod geometry;
mod lights;
mod objects;
mod overrides;
mod params;
mod pattern;
mod pixel_filter;
mod raw;
mod render;
#[cfg(test)]
mod tests;
mod within;

use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Affine3A, Vec3};
use render::read_render;
pub use render::RenderSettings;
use risotto_components::Rgb;
use risotto_engine::scene::TriangleMesh;
pub use risotto_systems::mesh_attributes::VertexAttributes;
pub use risotto_systems::pixel_filter::PixelFilter;

pub use lights::LightDesc;
pub use objects::{InstanceDesc, ObjectDesc};
pub use params::MaterialParams;
pub use pattern::ColourParam;
pub use risotto_engine::diagnostics::{Location, ReferencedFiles, SceneError, SceneErrorKind};

use crate::import::{self, ImportOptions, SceneFormat};
use lights::read_lights;
use params::Reader;
use raw::Node;
use risotto_engine::diagnostics::Source;

/// The largest light value a scene file accepts, per channel: shape `emission`, environment
/// `radiance`, distant `irradiance`, point `intensity`. Paths multiply it by weights that
/// can exceed 1 (MIS, roulette survivors, refraction), and f32 ends at 3.4e38; above this
/// the loader reports the value (`docs/scene-format.md`).
pub const MAX_RADIANCE: f32 = 1e30;

/// A loaded scene file: everything the engine needs to build the render world.
#[derive(Clone, Debug)]
pub struct SceneDesc {
    /// The scene file's path as given to the loader.
    pub path: PathBuf,
    /// The files the scene reads (see [`ReferencedFiles`]).
    pub files: ReferencedFiles,
    /// What reading the scene and its files found that is worth a warning but not an error
    /// (an OBJ's points and lines, which are skipped).
    pub warnings: Vec<String>,
    /// Image size, sample count, path depth, seed.
    pub render: RenderSettings,
    /// The camera.
    pub camera: CameraDesc,
    /// Materials in file order; shapes refer to them by index.
    pub materials: Vec<MaterialDesc>,
    /// Objects (`[objects.NAME]`) in file order: shapes defined once in object space,
    /// rendered where instances place them.
    pub objects: Vec<ObjectDesc>,
    /// Shapes in file order (but instances).
    pub shapes: Vec<ShapeDesc>,
    /// The `type = "instance"` entries of `shapes`, in file order.
    pub instances: Vec<InstanceDesc>,
    /// Lights other than emissive shapes, in file order (at most one environment).
    pub lights: Vec<LightDesc>,
    /// The volume stack at the camera given explicitly (`camera.inside`): names of the
    /// closed shapes containing the camera, outermost first. `None`: the engine finds it.
    pub camera_volume: Option<Vec<String>>,
    /// Where `camera.inside` is written, for the compiler's check of it against the volumes
    /// the camera is really in (`None` when the key is absent).
    pub camera_volume_at: Option<Location>,
    /// `within` statements of the camera and the shapes, checked when compiling.
    pub within: Vec<risotto_engine::scene::WithinCheck>,
}

/// How the camera maps image positions to rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// A pinhole camera.
    Perspective {
        /// Full *horizontal* field of view in degrees, in (0, 180).
        fov_deg: f32,
    },
    /// Parallel rays along the view direction.
    Orthographic {
        /// World-space width of the view (the height follows from the aspect ratio).
        width: f32,
    },
    /// A perspective camera with a thin lens (depth of field), as Mitsuba 3's `thinlens`
    /// sensor: `projection = "thin_lens"`.
    ThinLens {
        /// Full *horizontal* field of view in degrees, in (0, 180).
        fov_deg: f32,
        /// Radius of the lens in world units, finite and >= 0 (0 = the pinhole camera).
        aperture_radius: f32,
        /// Distance of the plane in focus from the lens, along the view direction, in world
        /// units, finite and > 0 (default: the distance from `from` to `to`).
        focus_distance: f32,
    },
}

/// The camera: placed by look-at. Right = `normalize(cross(forward, up))`, image up =
/// `cross(right, forward)`, pixel (0, 0) is the top-left corner of the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraDesc {
    /// Perspective or orthographic.
    pub projection: Projection,
    /// Eye position.
    pub from: Vec3,
    /// A point the camera looks at (`to != from`).
    pub to: Vec3,
    /// Up hint, not parallel to `to - from` (default +y); need not be unit or orthogonal.
    pub up: Vec3,
}

/// A named material: its type (resolved by the engine's material registry), its
/// priority for nested volumes and its raw parameters.
#[derive(Clone, Debug)]
pub struct MaterialDesc {
    /// The table key in `[materials.NAME]`.
    pub name: String,
    /// `type = "..."`: `diffuse`, `dielectric`, `conductor`, `mirror`, `interface`, or any
    /// type registered by the user (not checked here).
    pub type_name: String,
    /// `priority` for nested dielectrics/volumes (default 0; higher wins).
    pub priority: i32,
    /// Every other key, for the material's factory.
    pub params: MaterialParams,
}

/// A shape with its material and optional area emission.
#[derive(Clone, Debug)]
pub struct ShapeDesc {
    /// `name` (default `shapes[i]`), unique among shapes.
    pub name: String,
    /// Index into [`SceneDesc::materials`].
    pub material: usize,
    /// Area light: radiance leaving the *front* side (the side the geometric normal points
    /// to); the back emits nothing. `None` if absent or black.
    pub emission: Option<Rgb>,
    /// The geometry in world space.
    pub geometry: ShapeGeometry,
    /// The shape's object-to-world transform: its `transform` (a `quad`, `rectangle`,
    /// `disk`, `box` or `mesh`; the object space is the one its corner and edges, unit disk,
    /// `min` / `max`, unit square or file were written in), the identity for a `sphere` and for shapes without
    /// one. A volume's `u, v, w` and grids are measured in object space.
    pub transform: Affine3A,
    /// A `mesh`'s vertex normals and texture coordinates in world space (one corner triple
    /// per triangle of [`ShapeGeometry::Mesh`]), a `disk`'s polar texture coordinates;
    /// empty for other shapes and for meshes whose file has neither (or normals only, with
    /// `face_normals = true`).
    pub attributes: VertexAttributes,
}

/// Shape geometry, resolved to world space.
#[derive(Clone, Debug, PartialEq)]
pub enum ShapeGeometry {
    /// A sphere (normal points outwards).
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius (> 0).
        radius: f32,
    },
    /// Triangles in world space; the geometric normal of `[v0, v1, v2]` is along
    /// `(v1 - v0) x (v2 - v0)`. Boxes and meshes keep their outward orientation under any
    /// transform; a quad's normal is `normalize(edge1 x edge2)`.
    Triangles {
        /// Where they came from: `"quad"` (also `rectangle`), `"disk"`, `"box"` or `"mesh"`.
        kind: &'static str,
        /// The triangles.
        triangles: Vec<[Vec3; 3]>,
    },
    /// A `mesh` (file) or `triangles` shape: triangles over shared vertices in world space,
    /// as the file indexes them, wound as [`Self::Triangles`] (issue 36: no triangle is
    /// copied out of the mesh).
    Mesh(TriangleMesh),
}

impl ShapeGeometry {
    /// The world-space vertices of each triangle, in order (none for a sphere).
    pub fn world_triangles(&self) -> Vec<[Vec3; 3]> {
        match self {
            ShapeGeometry::Sphere { .. } => Vec::new(),
            ShapeGeometry::Triangles { triangles, .. } => triangles.clone(),
            ShapeGeometry::Mesh(m) => (0..m.len()).map(|i| m.triangle(i)).collect(),
        }
    }
}

/// Reads and parses a scene file.
pub fn load_scene(path: &Path) -> Result<SceneDesc, SceneError> {
    load_scene_with(path, &[])
}

/// Reads and parses a scene file with command-line overrides `KEY.PATH=VALUE` (the
/// driver's `-D`; see [`parse_scene_with`]).
pub fn load_scene_with(path: &Path, overrides: &[String]) -> Result<SceneDesc, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|e| SceneError::io(path, &e))?;
    parse_scene_with(&text, path, overrides)
}

/// Parses scene text; `path` is used in messages and to resolve relative paths (against
/// its directory). The file at `path` itself is not read.
pub fn parse_scene(text: &str, path: &Path) -> Result<SceneDesc, SceneError> {
    parse_scene_with(text, path, &[])
}

/// [`parse_scene`] with overrides: each `KEY.PATH=VALUE` replaces (or adds) the value at
/// that TOML path before anything is read, so it is checked as if the file said it, and an
/// error in it quotes the argument. Paths are dot-separated keys, arrays of tables indexed
/// from 0 (`shapes.2.radius=0.5`); values are TOML, a bare word a string
/// (`materials.glass.type=dielectric`). Documented in `docs/scene-format.md`, "Overrides".
pub fn parse_scene_with(
    text: &str,
    path: &Path,
    overrides: &[String],
) -> Result<SceneDesc, SceneError> {
    let format = SceneFormat::detect(path, text);
    if format != SceneFormat::Toml {
        // Another format: converted to TOML, then read as TOML with each part's errors
        // located at the original (`crate::import`).
        let (defines, toml_overrides) = import::split_defines(path, overrides)?;
        let dir = path.parent().unwrap_or(Path::new(""));
        let options = ImportOptions {
            defines: &defines,
            toml_dir: dir,
        };
        let imported = import::import_scene(format, path, text, &options)?;
        return parse_imported(imported, path, &toml_overrides);
    }
    let (src, override_lines) = Source::with_overrides(path, text, overrides);
    parse_source(Arc::new(src), text, path, overrides, &override_lines)
}

/// Reads a converted scene (`path` the original file, whose directory relative paths are
/// written against) with TOML `overrides` (dotted `-D` paths) applied to the conversion:
/// what [`parse_scene_with`] does after an importer ran, and what an embedder's own importer
/// (a [`TomlScene`](crate::import::TomlScene) with origins) calls to be read as TOML.
pub fn parse_imported(
    imported: import::ImportedScene,
    path: &Path,
    overrides: &[String],
) -> Result<SceneDesc, SceneError> {
    let (toml, origins) = imported.scene.write();
    let mut src = Source::converted(path, &toml, origins);
    let override_lines = src.append_overrides(overrides);
    for w in imported.warnings {
        src.warnings.add(w);
    }
    parse_source(Arc::new(src), &toml, path, overrides, &override_lines)
}

/// Converts a scene in another format ([`SceneFormat::detect`]) to the TOML text of a file
/// to be written at `out`, with relative paths written relative to `out`'s directory, and
/// checks that the TOML reads back (an error is located at the original file and line).
/// `defines` are the command line's `-D name=value`; a TOML override (a dotted name) is an
/// error here: it applies when rendering the converted file. Returns the text and the
/// conversion's warnings.
pub fn convert_scene(
    text: &str,
    path: &Path,
    defines: &[String],
    out: &Path,
) -> Result<(String, Vec<String>), SceneError> {
    let format = SceneFormat::detect(path, text);
    let (defines, toml_overrides) = import::split_defines(path, defines)?;
    if let Some(o) = toml_overrides.first() {
        return Err(SceneError::unlocated(
            path,
            SceneErrorKind::InvalidValue,
            &format!(
                "`-D {o}` is a TOML override (a dotted name); give it when rendering the \
                 converted scene"
            ),
        ));
    }
    let dir = out.parent().unwrap_or(Path::new(""));
    let options = ImportOptions {
        defines: &defines,
        toml_dir: dir,
    };
    let imported = import::import_scene(format, path, text, &options)?;
    let (toml, origins) = imported.scene.write();
    // Checked as the file will be read: from `out`'s directory.
    let src = Source::converted(out, &toml, origins);
    parse_source(Arc::new(src), &toml, out, &[], &[])?;
    Ok((toml, imported.warnings))
}

/// Reads the TOML `text` of `src` (with `overrides` appended at `override_lines`).
fn parse_source(
    src: Arc<Source>,
    text: &str,
    path: &Path,
    overrides: &[String],
    override_lines: &[usize],
) -> Result<SceneDesc, SceneError> {
    let mut root = raw::parse_document(text).map_err(|e| {
        let span = e.span().unwrap_or(0..0);
        src.error(
            SceneErrorKind::Syntax,
            &span,
            None,
            None,
            format!(
                "TOML syntax error: {}",
                e.message().trim().lines().collect::<Vec<_>>().join("; ")
            ),
        )
    })?;
    overrides::apply_overrides(&src, &mut root, overrides, override_lines)?;
    let top = Reader::new(&src, &root, "scene");
    top.deny_unknown(&[
        "render",
        "camera",
        "materials",
        "objects",
        "shapes",
        "lights",
    ])?;

    let render = read_render(&top)?;
    let materials = read_materials(&top, &src)?;
    let objects = objects::read_objects(&top, &materials)?;
    let (shapes, instances) = read_shapes(&top, &materials, &objects)?;
    objects::warn_unused(&src, &objects, &instances);
    let lights = read_lights(&top, &src)?;
    let (camera, camera_volume, camera_volume_at) = camera::read_camera(&top, &shapes, &src)?;
    let within = within::read_within(&top, &shapes, &src)?;
    Ok(SceneDesc {
        path: path.to_path_buf(),
        files: src.files.clone(),
        warnings: src.warnings.list(),
        render,
        camera,
        materials,
        objects,
        shapes,
        instances,
        lights,
        camera_volume,
        camera_volume_at,
        within,
    })
}

/// A section table (`[render]`, `[camera]`, ...), type-checked.
fn section<'a>(top: &Reader<'a>, key: &str) -> Result<Option<&'a Node>, SceneError> {
    top.table_opt(key)
}

/// Keys of a material that the scene layer consumes.
const MATERIAL_HIDDEN: &[&str] = &["type", "priority", "opacity"];

fn read_materials(top: &Reader<'_>, src: &Arc<Source>) -> Result<Vec<MaterialDesc>, SceneError> {
    let Some(node) = section(top, "materials")? else {
        return Ok(Vec::new());
    };
    let mut out = Vec::new();
    for (key, value) in node.as_table().unwrap_or(&[]) {
        let entity = format!("materials.{}", key.name);
        if value.as_table().is_none() {
            let r = Reader::new(top.src, node, "materials");
            return Err(r.wrong_type(
                &key.name,
                value,
                "a table such as `{ type = \"diffuse\", reflectance = 0.5 }`",
            ));
        }
        let r = Reader::new(top.src, value, &entity);
        let type_name = r.str_req("type")?;
        if type_name.is_empty() {
            return Err(r.invalid("type", r.get("type").unwrap_or(value), "must not be empty"));
        }
        let priority = r.int_in(
            "priority",
            Some(0),
            i64::from(i32::MIN),
            i64::from(i32::MAX),
        )? as i32;
        out.push(MaterialDesc {
            name: key.name.clone(),
            type_name: type_name.to_owned(),
            priority,
            params: MaterialParams::new(Arc::clone(src), value.clone(), entity, MATERIAL_HIDDEN),
        });
    }
    Ok(out)
}

/// Checks name uniqueness within one kind of entity, remembering where each was defined.
struct Names {
    what: &'static str,
    seen: HashMap<String, Range<usize>>,
}

impl Names {
    fn new(what: &'static str) -> Names {
        Names {
            what,
            seen: HashMap::new(),
        }
    }

    fn insert(&mut self, r: &Reader<'_>, name: &str, at: &Node) -> Result<(), SceneError> {
        if let Some(first) = self.seen.get(name) {
            let (line, col) = r.src.line_col(first.start);
            return Err(r.error(
                SceneErrorKind::Duplicate,
                &at.span(),
                Some("name"),
                format!(
                    "duplicate {} name `{name}` (first defined at line {line}, column {col}); \
                     names must be unique",
                    self.what
                ),
            ));
        }
        self.seen.insert(name.to_owned(), at.span());
        Ok(())
    }
}

/// The entity label of an element of `shapes` / `lights`: `shapes[3] "tall_box"`.
fn element_entity(list: &str, i: usize, name: Option<&str>) -> String {
    match name {
        Some(n) => format!("{list}[{i}] \"{n}\""),
        None => format!("{list}[{i}]"),
    }
}

const SHAPE_TYPES: &[&str] = &[
    "sphere",
    "quad",
    "rectangle",
    "disk",
    "box",
    "mesh",
    "triangles",
    "instance",
];

/// The `[[shapes]]` list: shapes, and the instances of objects (`type = "instance"`).
type ShapesAndInstances = (Vec<ShapeDesc>, Vec<InstanceDesc>);

fn read_shapes(
    top: &Reader<'_>,
    materials: &[MaterialDesc],
    objects: &[ObjectDesc],
) -> Result<ShapesAndInstances, SceneError> {
    let Some(items) = top.array_opt("shapes")? else {
        return Ok((Vec::new(), Vec::new()));
    };
    let mut names = Names::new("shape");
    let mut out = Vec::with_capacity(items.len());
    let mut instances = Vec::new();
    for (i, node) in items.iter().enumerate() {
        if node.as_table().is_none() {
            return Err(top.wrong_type("shapes", node, "a table (write shapes as [[shapes]])"));
        }
        let bare = element_entity("shapes", i, None);
        let name = Reader::new(top.src, node, &bare).str_opt("name")?;
        let entity = element_entity("shapes", i, name);
        let r = Reader::new(top.src, node, &entity);
        let name = name.map_or_else(|| bare.clone(), str::to_owned);
        names.insert(&r, &name, r.get("name").unwrap_or(node))?;

        let type_name = r.str_req("type")?;
        if type_name == "instance" {
            instances.push(objects::read_instance(&r, node, name, objects)?);
            continue;
        }
        out.push(read_shape(
            &r,
            node,
            type_name,
            name,
            materials,
            &["within"],
        )?);
    }
    Ok((out, instances))
}

/// One shape (any type but `instance`) of `[[shapes]]` or of an object, its type and name
/// read.
fn read_shape(
    r: &Reader<'_>,
    node: &Node,
    type_name: &str,
    name: String,
    materials: &[MaterialDesc],
    extra: &[&str],
) -> Result<ShapeDesc, SceneError> {
    let common = ["type", "name", "material", "emission"];
    let specific: &[&str] = match type_name {
        "sphere" => &["center", "radius"],
        "quad" => &["corner", "edge1", "edge2", "transform"],
        "rectangle" => &["transform"],
        "disk" => &["radius", "inner_radius", "transform"],
        "box" => &["min", "max", "transform"],
        "mesh" => &[
            "path",
            "transform",
            "face_normals",
            "flip_normals",
            "flip_tex_coords",
            "shadow_terminator_offset",
        ],
        "triangles" => &[
            "positions",
            "indices",
            "normals",
            "uv",
            "transform",
            "face_normals",
            "shadow_terminator_offset",
        ],
        other => {
            return Err(r.error(
                SceneErrorKind::InvalidValue,
                &r.get("type").unwrap_or(node).span(),
                Some("type"),
                format!(
                    "unknown shape type `{other}`; expected one of {}",
                    SHAPE_TYPES.join(", ")
                ),
            ))
        }
    };
    let allowed: Vec<&str> = common
        .iter()
        .chain(specific)
        .chain(extra)
        .copied()
        .collect();
    r.deny_unknown(&allowed)?;

    let material_name = r.str_req("material")?;
    let material = materials
        .iter()
        .position(|m| m.name == material_name)
        .ok_or_else(|| {
            let known: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
            let mut message = format!("unknown material `{material_name}`");
            if let Some(near) = params::suggestion(material_name, &known) {
                message.push_str(&format!(" (did you mean `{near}`?)"));
            }
            if known.is_empty() {
                message.push_str("; no materials are defined (add a [materials.NAME] table)");
            } else {
                message.push_str(&format!("; defined materials: {}", known.join(", ")));
            }
            r.error(
                SceneErrorKind::UnknownReference,
                &r.get("material").unwrap_or(node).span(),
                Some("material"),
                message,
            )
        })?;
    let emission = r.radiance_opt("emission")?.filter(|e| !e.is_black());

    let mut transform = glam::DAffine3::IDENTITY;
    let mut attributes = VertexAttributes::default();
    let mut triangles_of = |(triangles, m): (Vec<[Vec3; 3]>, glam::DAffine3)| {
        transform = m;
        triangles
    };
    let geometry = match type_name {
        "sphere" => {
            let center = r.vec3("center", None)?;
            let radius = r.f32_where("radius", None, "must be > 0", |v| v > 0.0)?;
            ShapeGeometry::Sphere { center, radius }
        }
        "quad" => ShapeGeometry::Triangles {
            kind: "quad",
            triangles: triangles_of(geometry::quad(r)?),
        },
        "rectangle" => {
            let (triangles, m, a) = geometry::rectangle(r)?;
            attributes = a;
            ShapeGeometry::Triangles {
                kind: "quad",
                triangles: triangles_of((triangles, m)),
            }
        }
        "box" => ShapeGeometry::Triangles {
            kind: "box",
            triangles: triangles_of(geometry::cuboid(r)?),
        },
        "disk" => {
            let (triangles, m, a) = disk::disk(r)?;
            attributes = a;
            ShapeGeometry::Triangles {
                kind: "disk",
                triangles: triangles_of((triangles, m)),
            }
        }
        "triangles" => {
            let (mesh, m, a) = geometry::triangles(r)?;
            attributes = a;
            transform = m;
            ShapeGeometry::Mesh(mesh)
        }
        _ => {
            let (mesh, m, a) = geometry::mesh(r)?;
            attributes = a;
            transform = m;
            ShapeGeometry::Mesh(mesh)
        }
    };
    let transform = Affine3A::from_mat3_translation(
        transform.matrix3.as_mat3(),
        transform.translation.as_vec3(),
    );
    let finite = match &geometry {
        ShapeGeometry::Sphere { .. } => true,
        ShapeGeometry::Triangles { triangles, .. } => {
            triangles.iter().flatten().all(|v| v.is_finite())
        }
        // The vertices the triangles use (a file may list others).
        ShapeGeometry::Mesh(m) => m
            .triangles
            .iter()
            .flatten()
            .all(|&k| m.positions[k as usize].is_finite()),
    };
    if !finite {
        let at = r.get("transform").unwrap_or(node);
        return Err(r.error(
            SceneErrorKind::InvalidValue,
            &at.span(),
            None,
            "vertex coordinates overflow f32 (values too large)",
        ));
    }
    Ok(ShapeDesc {
        name,
        material,
        emission,
        geometry,
        transform,
        attributes,
    })
}
