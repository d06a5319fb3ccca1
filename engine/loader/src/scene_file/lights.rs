//! The `[[lights]]` of a scene file: distant, point, spot and environment lights.

use super::geometry::read_transform;
use super::*;
use glam::{DMat3, Mat3};
use risotto_systems::environment_map::{EnvFilter, EnvProjection};

/// A light that is not a shape.
#[derive(Clone, Debug, PartialEq)]
pub enum LightDesc {
    /// A directional light at infinity (e.g. the sun).
    Distant {
        /// `name` (default `lights[i]`).
        name: String,
        /// Unit direction the light *travels* (from the light into the scene).
        direction: Vec3,
        /// Irradiance on a surface perpendicular to `direction`, W m^-2 per channel.
        irradiance: Rgb,
    },
    /// An isotropic point light.
    Point {
        /// `name` (default `lights[i]`).
        name: String,
        /// Position.
        position: Vec3,
        /// Radiant intensity, W sr^-1 per channel.
        intensity: Rgb,
    },
    /// A spot light (Mitsuba 3's `spot`): a point light whose intensity falls off away from
    /// its axis, linearly in the angle from `beam_width` to `cutoff_angle`.
    Spot {
        /// `name` (default `lights[i]`).
        name: String,
        /// Position.
        position: Vec3,
        /// Unit direction of the axis (`direction`, or `to - position`).
        direction: Vec3,
        /// Radiant intensity on the axis, W sr^-1 per channel.
        intensity: Rgb,
        /// Half-angle of the lit cone, degrees, in `(0, 90]` (default 20).
        cutoff_angle: f32,
        /// Half-angle of the fully lit beam, degrees, in `(0, cutoff_angle]` (default
        /// `3/4 cutoff_angle`).
        beam_width: f32,
        /// `texture` (an image projected through the cone, Mitsuba's spot `texture`) and the
        /// `up` that orients it (default `[0, 1, 0]`).
        texture: Option<(Arc<risotto_systems::pattern::Texture>, Vec3)>,
    },
    /// Radiance arriving from every direction at infinity (seen by every escaping ray).
    Environment {
        /// `name` (default `lights[i]`).
        name: String,
        /// Constant radiance, or the scale of the map if there is one (default 1).
        radiance: Rgb,
        /// An equirectangular EXR map, resolved against the scene file (absolute); the
        /// engine loads it. The file exists at load time.
        map: Option<PathBuf>,
        /// Where `map` is written, for the errors of reading the map (`None` without one).
        map_at: Option<Location>,
        /// How the map is looked up between texels (`filter`, default bilinear; nearest
        /// for an equal-area map).
        filter: EnvFilter,
        /// How the map's texels lie on the sphere (`projection`, default latitude-longitude).
        projection: EnvProjection,
        /// The map's frame to world: the rotation of `transform`, composed with the half
        /// turn about `y` of `convention = "mitsuba"` (identity by default).
        to_world: Mat3,
    },
}

impl LightDesc {
    /// The light's name.
    pub fn name(&self) -> &str {
        match self {
            LightDesc::Distant { name, .. }
            | LightDesc::Point { name, .. }
            | LightDesc::Spot { name, .. }
            | LightDesc::Environment { name, .. } => name,
        }
    }
}

const LIGHT_TYPES: &[&str] = &["distant", "point", "spot", "environment"];

pub(super) fn read_lights(
    top: &Reader<'_>,
    src: &Arc<Source>,
) -> Result<Vec<LightDesc>, SceneError> {
    let Some(items) = top.array_opt("lights")? else {
        return Ok(Vec::new());
    };
    let mut names = Names::new("light");
    let mut environment_seen: Option<usize> = None;
    let mut out = Vec::with_capacity(items.len());
    for (i, node) in items.iter().enumerate() {
        if node.as_table().is_none() {
            return Err(top.wrong_type("lights", node, "a table (write lights as [[lights]])"));
        }
        let bare = element_entity("lights", i, None);
        let name = Reader::new(top.src, node, &bare).str_opt("name")?;
        let entity = element_entity("lights", i, name);
        let r = Reader::new(top.src, node, &entity);
        let name = name.map_or_else(|| bare.clone(), str::to_owned);
        names.insert(&r, &name, r.get("name").unwrap_or(node))?;

        let type_node = r.get("type").unwrap_or(node);
        let light = match r.str_req("type")? {
            "distant" => {
                r.deny_unknown(&["type", "name", "direction", "irradiance"])?;
                let direction = r.vec3("direction", None)?;
                let len = direction.length();
                if !(len > 0.0 && len.is_finite()) {
                    return Err(r.invalid(
                        "direction",
                        r.get("direction").unwrap_or(node),
                        "must be a non-zero vector (the direction the light travels)",
                    ));
                }
                LightDesc::Distant {
                    name,
                    direction: direction / len,
                    irradiance: r.radiance("irradiance", None)?,
                }
            }
            "point" => {
                r.deny_unknown(&["type", "name", "position", "intensity"])?;
                LightDesc::Point {
                    name,
                    position: r.vec3("position", None)?,
                    intensity: r.radiance("intensity", None)?,
                }
            }
            "spot" => read_spot(&r, node, name)?,
            "environment" => {
                if let Some(first) = environment_seen {
                    return Err(r.invalid(
                        "type",
                        type_node,
                        &format!(
                            "at most one environment light is allowed (lights[{first}] is one)"
                        ),
                    ));
                }
                environment_seen = Some(i);
                read_environment(&r, src, name)?
            }
            other => {
                return Err(r.error(
                    SceneErrorKind::InvalidValue,
                    &type_node.span(),
                    Some("type"),
                    format!(
                        "unknown light type `{other}`; expected one of {} (area lights are \
                         shapes with `emission`)",
                        LIGHT_TYPES.join(", ")
                    ),
                ))
            }
        };
        out.push(light);
    }
    Ok(out)
}

/// Keys of an environment light that only mean something with a `map`.
const MAP_KEYS: &[&str] = &["filter", "transform", "convention", "projection"];

/// An `environment` light's keys: `radiance`, and with a `map` its `filter`, `transform`
/// (a rotation), `convention` and `projection`.
fn read_environment(
    r: &Reader<'_>,
    src: &Arc<Source>,
    name: String,
) -> Result<LightDesc, SceneError> {
    r.deny_unknown(&[
        "type",
        "name",
        "radiance",
        "map",
        "filter",
        "transform",
        "convention",
        "projection",
    ])?;
    let Some((path, map_node)) = r.path_opt("map")? else {
        if let Some(key) = MAP_KEYS.iter().find(|k| r.has(k)) {
            let node = r.get(key).unwrap_or(r.node);
            return Err(r.invalid(
                key,
                node,
                "only applies to an environment `map` (this environment is a constant)",
            ));
        }
        return Ok(LightDesc::Environment {
            name,
            radiance: r.radiance("radiance", None)?,
            map: None,
            map_at: None,
            filter: EnvFilter::default(),
            projection: EnvProjection::default(),
            to_world: Mat3::IDENTITY,
        });
    };
    if !path.is_file() {
        return Err(r.error(
            SceneErrorKind::ExternalFile,
            &map_node.span(),
            Some("map"),
            format!("environment map `{}` does not exist", path.display()),
        ));
    }
    let map_at = Some(Location::new(src, map_node.span(), r.entity, Some("map")));
    let projection = match r.str_opt("projection")? {
        None | Some("latlong") => EnvProjection::LatLong,
        Some("equal_area") => EnvProjection::EqualArea,
        Some(_) => {
            let node = r.get("projection").unwrap_or(r.node);
            return Err(r.invalid(
                "projection",
                node,
                "must be \"latlong\" or \"equal_area\" (pbrt-v4's octahedral square)",
            ));
        }
    };
    let filter = match (r.str_opt("filter")?, projection) {
        (None | Some("nearest"), EnvProjection::EqualArea) => EnvFilter::Nearest,
        (Some("bilinear"), EnvProjection::EqualArea) => {
            let node = r.get("filter").unwrap_or(r.node);
            return Err(r.invalid(
                "filter",
                node,
                "an equal_area map is looked up nearest-texel, as pbrt-v4 does (bilinear \
                 would blend across the octahedron's folds)",
            ));
        }
        (None | Some("bilinear"), _) => EnvFilter::Bilinear,
        (Some("nearest"), _) => EnvFilter::Nearest,
        (Some(_), _) => {
            let node = r.get("filter").unwrap_or(r.node);
            return Err(r.invalid("filter", node, "must be \"bilinear\" or \"nearest\""));
        }
    };
    // Mitsuba 3's `u = 0` is at -z, ours at +z: its map is ours turned half about y.
    let half_turn = match r.str_opt("convention")? {
        None | Some("risotto") => false,
        Some("mitsuba") if projection == EnvProjection::EqualArea => {
            let node = r.get("convention").unwrap_or(r.node);
            return Err(r.invalid(
                "convention",
                node,
                "Mitsuba's maps are latitude-longitude: \"mitsuba\" does not apply to an \
                 equal_area map",
            ));
        }
        Some("mitsuba") => true,
        Some(_) => {
            let node = r.get("convention").unwrap_or(r.node);
            return Err(r.invalid("convention", node, "must be \"risotto\" or \"mitsuba\""));
        }
    };
    let mut to_world = read_rotation(r)?;
    if half_turn {
        to_world *= DMat3::from_rotation_y(std::f64::consts::PI);
    }
    Ok(LightDesc::Environment {
        name,
        radiance: r.radiance("radiance", Some(Rgb::WHITE))?,
        map: Some(path),
        map_at,
        filter,
        projection,
        to_world: to_world.as_mat3(),
    })
}

/// The environment's `transform`: its linear part must be orthonormal (a rotation, or a
/// rotation with a mirror), since a scale or shear would bend the directions the map is
/// seen in. A translation is ignored: the environment is at infinity, so moving it changes
/// nothing (as in Mitsuba 3, whose `envmap` applies `to_world` to directions only).
fn read_rotation(r: &Reader<'_>) -> Result<DMat3, SceneError> {
    let m = read_transform(r)?.matrix3;
    let gram = m.transpose() * m - DMat3::IDENTITY;
    let off = gram
        .to_cols_array()
        .iter()
        .fold(0.0f64, |a, &e| a.max(e.abs()));
    if off.is_nan() || off > 1e-5 {
        let node = r.get("transform").unwrap_or(r.node);
        let rows = [m.row(0), m.row(1), m.row(2)]
            .map(|v| format!("[{:.4}, {:.4}, {:.4}]", v.x, v.y, v.z))
            .join(", ");
        return Err(r.error(
            SceneErrorKind::InvalidValue,
            &node.span(),
            Some("transform"),
            format!(
                "an environment's transform must be a rotation (no scale or shear, which \
                 would bend the directions), got the linear part [{rows}] (|MᵀM - I| = \
                 {off:.2e})"
            ),
        ));
    }
    Ok(m)
}

/// A `spot` light's keys: `position`, the axis as `direction` or as a target point `to`
/// (exactly one), `intensity`, `cutoff_angle` and `beam_width` (degrees, Mitsuba 3's
/// defaults and ranges).
fn read_spot(r: &Reader<'_>, node: &Node, name: String) -> Result<LightDesc, SceneError> {
    r.deny_unknown(&[
        "type",
        "name",
        "position",
        "direction",
        "to",
        "intensity",
        "cutoff_angle",
        "beam_width",
        "texture",
        "up",
    ])?;
    let position = r.vec3("position", None)?;
    let (key, axis) = match (r.vec3_opt("direction")?, r.vec3_opt("to")?) {
        (Some(d), None) => ("direction", d),
        (None, Some(to)) => ("to", to - position),
        (Some(_), Some(_)) => {
            return Err(r.invalid(
                "to",
                r.get("to").unwrap_or(node),
                "give the axis as `direction` or as `to`, not both",
            ))
        }
        (None, None) => {
            return Err(r.missing(
                "direction",
                "a direction [x, y, z] (or a target point `to`)",
            ))
        }
    };
    let len = axis.length();
    if !(len > 0.0 && len.is_finite()) {
        let requirement = if key == "to" {
            "must differ from `position` (the light points from `position` to `to`)"
        } else {
            "must be a non-zero vector (the direction the spot points to)"
        };
        return Err(r.invalid(key, r.get(key).unwrap_or(node), requirement));
    }
    let cutoff_angle = r.f32_where(
        "cutoff_angle",
        Some(20.0),
        "must be in (0, 90] degrees",
        |v| v > 0.0 && v <= 90.0,
    )?;
    let beam_width = r.f32_where(
        "beam_width",
        Some(0.75 * cutoff_angle),
        &format!("must be in (0, cutoff_angle] = (0, {cutoff_angle}] degrees"),
        |v| v > 0.0 && v <= cutoff_angle,
    )?;
    let direction = axis / len;
    let texture = match r.path_opt("texture")? {
        None => {
            if let Some(up) = r.get("up") {
                return Err(r.invalid("up", up, "only orients a `texture`"));
            }
            None
        }
        Some((path, path_node)) => {
            let image = r
                .src
                .side_files
                .get_or_load(&path, "texture Rgb", || {
                    crate::texture_file::read_texture(&path)
                })
                .map_err(|message| {
                    r.error(
                        SceneErrorKind::ExternalFile,
                        &path_node.span(),
                        Some("texture"),
                        message,
                    )
                })?;
            let up = r.vec3("up", Some(Vec3::Y))?;
            if up.cross(direction).length() <= 1e-6 * up.length() {
                return Err(r.invalid(
                    "up",
                    r.get("up").unwrap_or(node),
                    "must not be parallel to the spot's direction (it orients the texture)",
                ));
            }
            Some((image, up))
        }
    };
    Ok(LightDesc::Spot {
        name,
        position,
        direction,
        intensity: r.radiance("intensity", None)?,
        cutoff_angle,
        beam_width,
        texture,
    })
}
