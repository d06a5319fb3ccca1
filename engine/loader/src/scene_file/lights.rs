//! The `[[lights]]` of a scene file: distant, point, spot and environment lights.

use super::*;

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
                r.deny_unknown(&["type", "name", "radiance", "map"])?;
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
                let mut map_at = None;
                let map = match r.path_opt("map")? {
                    None => None,
                    Some((path, map_node)) => {
                        if !path.is_file() {
                            return Err(r.error(
                                SceneErrorKind::ExternalFile,
                                &map_node.span(),
                                Some("map"),
                                format!("environment map `{}` does not exist", path.display()),
                            ));
                        }
                        map_at = Some(Location::new(src, map_node.span(), r.entity, Some("map")));
                        Some(path)
                    }
                };
                let radiance = if map.is_some() {
                    r.radiance("radiance", Some(Rgb::WHITE))?
                } else {
                    r.radiance("radiance", None)?
                };
                LightDesc::Environment {
                    name,
                    radiance,
                    map,
                    map_at,
                }
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
    Ok(LightDesc::Spot {
        name,
        position,
        direction: axis / len,
        intensity: r.radiance("intensity", None)?,
        cutoff_angle,
        beam_width,
    })
}
