//! Objects (`[objects.NAME]`: shapes defined once, in object space) and their instances
//! (`type = "instance"` entries of `[[shapes]]`), as `docs/scene-format.md` ("Objects and
//! instances") describes them.

use glam::Affine3A;

use super::geometry::read_transform;
use super::params::{suggestion, Reader};
use super::raw::Node;
use super::{element_entity, read_shape, section, MaterialDesc, Names, ShapeDesc};
use risotto_engine::diagnostics::{SceneError, SceneErrorKind, Source};

/// An object: shapes in object space (their `transform`s map into it), not rendered by
/// itself.
#[derive(Clone, Debug)]
pub struct ObjectDesc {
    /// The table key in `[objects.NAME]`.
    pub name: String,
    /// Its shapes (at least one; none emits, none has a material with an interior), their
    /// geometry in object space.
    pub shapes: Vec<ShapeDesc>,
    /// The line of the scene file where the object is defined (for the warning when
    /// nothing instances it).
    pub line: usize,
}

/// A placement of an object (`type = "instance"` in `[[shapes]]`).
#[derive(Clone, Debug)]
pub struct InstanceDesc {
    /// `name` (default `shapes[i]`), unique among shapes.
    pub name: String,
    /// Index into [`super::SceneDesc::objects`].
    pub object: usize,
    /// Object space to world (the entry's `transform`; the identity when absent).
    pub transform: Affine3A,
}

/// Why shapes inside objects may not emit or hold volumes.
const NOT_IN_OBJECTS: &str = "area lights / volumes inside objects are not supported; pbrt-v4 \
                              does not support area lights in instances either (place the \
                              shape directly in [[shapes]])";

/// Reads `[objects]`.
pub(super) fn read_objects(
    top: &Reader<'_>,
    materials: &[MaterialDesc],
) -> Result<Vec<ObjectDesc>, SceneError> {
    let Some(node) = section(top, "objects")? else {
        return Ok(Vec::new());
    };
    let mut out = Vec::new();
    for (key, value) in node.as_table().unwrap_or(&[]) {
        let name = key.name.as_str();
        let entity = format!("objects.{name}");
        let r = Reader::new(top.src, value, &entity);
        if value.as_table().is_none() {
            return Err(top.wrong_type(
                &entity,
                value,
                "a table such as [objects.tree] with a `shapes` array",
            ));
        }
        r.deny_unknown(&["shapes"])?;
        let items = r.array_opt("shapes")?.unwrap_or(&[]);
        if items.is_empty() {
            return Err(r.error(
                SceneErrorKind::InvalidValue,
                &value.span(),
                Some("shapes"),
                "an object needs at least one shape (`shapes = [{ type = \"mesh\", ... }]`)",
            ));
        }
        let mut names = Names::new("object shape");
        let mut shapes = Vec::with_capacity(items.len());
        for (i, item) in items.iter().enumerate() {
            if item.as_table().is_none() {
                return Err(r.wrong_type("shapes", item, "a table (a shape)"));
            }
            let list = format!("objects.{name}.shapes");
            let bare = element_entity(&list, i, None);
            let shape_name = Reader::new(top.src, item, &bare).str_opt("name")?;
            let shape_entity = element_entity(&list, i, shape_name);
            let s = Reader::new(top.src, item, &shape_entity);
            let shape_name = shape_name.map_or_else(|| bare.clone(), str::to_owned);
            names.insert(&s, &shape_name, s.get("name").unwrap_or(item))?;
            let type_name = s.str_req("type")?;
            if type_name == "instance" {
                return Err(s.error(
                    SceneErrorKind::InvalidValue,
                    &s.get("type").unwrap_or(item).span(),
                    Some("type"),
                    "nested instances are not supported: an object's shapes may not be \
                     instances (instancing has two levels: objects hold shapes, [[shapes]] \
                     hold instances)",
                ));
            }
            if let Some(e) = s.get("emission") {
                return Err(s.error(
                    SceneErrorKind::InvalidValue,
                    &e.span(),
                    Some("emission"),
                    NOT_IN_OBJECTS,
                ));
            }
            let shape = read_shape(&s, item, type_name, shape_name, materials, &[])?;
            let m = &materials[shape.material];
            if m.params.has("interior") || m.type_name == "subsurface" {
                return Err(s.error(
                    SceneErrorKind::InvalidValue,
                    &s.get("material").unwrap_or(item).span(),
                    Some("material"),
                    format!("material `{}` has an interior: {NOT_IN_OBJECTS}", m.name),
                ));
            }
            shapes.push(shape);
        }
        out.push(ObjectDesc {
            name: name.to_owned(),
            shapes,
            line: top
                .src
                .line_col(key.span.clone().unwrap_or(value.span()).start)
                .0,
        });
    }
    Ok(out)
}

/// Reads a `type = "instance"` entry of `[[shapes]]` (its name read).
pub(super) fn read_instance(
    r: &Reader<'_>,
    node: &Node,
    name: String,
    objects: &[ObjectDesc],
) -> Result<InstanceDesc, SceneError> {
    r.deny_unknown(&["type", "name", "object", "transform"])?;
    let object_name = r.str_req("object")?;
    let object = objects
        .iter()
        .position(|o| o.name == object_name)
        .ok_or_else(|| {
            let known: Vec<&str> = objects.iter().map(|o| o.name.as_str()).collect();
            let mut message = format!("unknown object `{object_name}`");
            if let Some(near) = suggestion(object_name, &known) {
                message.push_str(&format!(" (did you mean `{near}`?)"));
            }
            if known.is_empty() {
                message.push_str("; no objects are defined (add an [objects.NAME] table)");
            } else {
                message.push_str(&format!("; defined objects: {}", known.join(", ")));
            }
            r.error(
                SceneErrorKind::UnknownReference,
                &r.get("object").unwrap_or(node).span(),
                Some("object"),
                message,
            )
        })?;
    let m = read_transform(r)?;
    let transform = Affine3A::from_mat3_translation(m.matrix3.as_mat3(), m.translation.as_vec3());
    if !transform.is_finite() {
        return Err(r.error(
            SceneErrorKind::InvalidValue,
            &r.get("transform").unwrap_or(node).span(),
            Some("transform"),
            "the transform overflows f32 (values too large)",
        ));
    }
    Ok(InstanceDesc {
        name,
        object,
        transform,
    })
}

/// Warns of objects no instance places (they render nothing).
pub(super) fn warn_unused(src: &Source, objects: &[ObjectDesc], instances: &[InstanceDesc]) {
    for (o, object) in objects.iter().enumerate() {
        if !instances.iter().any(|i| i.object == o) {
            src.warnings.add(format!(
                "{}:{}: objects.{} is never instanced (no [[shapes]] entry with type = \
                 \"instance\" and object = \"{}\"): it renders nothing",
                src.path.display(),
                object.line,
                object.name,
                object.name
            ));
        }
    }
}
