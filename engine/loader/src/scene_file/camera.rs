//! The `[camera]` section: projection, placement and the volume stack at the camera.

use glam::Vec3;

use super::raw::{Node, Value};
use super::{
    section, Arc, CameraDesc, Location, Projection, Reader, SceneError, SceneErrorKind, ShapeDesc,
    ShapeGeometry, Source,
};

type CameraParts = (CameraDesc, Option<Vec<String>>, Option<Location>);

pub(super) fn read_camera(
    top: &Reader<'_>,
    shapes: &[ShapeDesc],
    src: &Arc<Source>,
) -> Result<CameraParts, SceneError> {
    let Some(node) = section(top, "camera")? else {
        return Err(top.error(
            SceneErrorKind::MissingField,
            &(0..0),
            Some("camera"),
            "missing required table [camera] (with at least `from`, `to` and `fov`)",
        ));
    };
    let r = Reader::new(top.src, node, "camera");
    let from = r.vec3("from", None)?;
    let to = r.vec3("to", None)?;
    let up = r.vec3("up", Some(Vec3::Y))?;
    let forward = to - from;
    let distance = forward.length();
    let projection_name = r.str_opt("projection")?.unwrap_or("perspective");
    const COMMON: [&str; 5] = ["from", "to", "up", "inside", "within"];
    let fov = || {
        r.f32_where(
            "fov",
            None,
            "must be in (0, 180) degrees (full horizontal field of view)",
            |v| v > 0.0 && v < 180.0,
        )
    };
    let projection = match projection_name {
        "perspective" => {
            r.deny_unknown(&[&["projection", "fov"][..], &COMMON].concat())?;
            Projection::Perspective { fov_deg: fov()? }
        }
        "orthographic" => {
            r.deny_unknown(&[&["projection", "width"][..], &COMMON].concat())?;
            Projection::Orthographic {
                width: r.f32_where("width", None, "must be > 0 (world units)", |v| v > 0.0)?,
            }
        }
        "thin_lens" => {
            let keys = ["projection", "fov", "aperture_radius", "focus_distance"];
            r.deny_unknown(&[&keys[..], &COMMON].concat())?;
            Projection::ThinLens {
                fov_deg: fov()?,
                aperture_radius: r.f32_where(
                    "aperture_radius",
                    None,
                    "must be finite and >= 0 (world units; 0 = pinhole)",
                    |v| v.is_finite() && v >= 0.0,
                )?,
                // The default puts `to` in focus (checked finite and > 0 below).
                focus_distance: r.f32_where(
                    "focus_distance",
                    Some(distance),
                    "must be finite and > 0 (world units, along the view direction)",
                    |v| v.is_finite() && v > 0.0,
                )?,
            }
        }
        other => {
            return Err(r.error(
                SceneErrorKind::InvalidValue,
                &r.get("projection").unwrap_or(node).span(),
                Some("projection"),
                format!(
                    "unknown projection `{other}`; expected `perspective`, `orthographic` or \
                     `thin_lens`"
                ),
            ))
        }
    };
    if distance == 0.0 || !distance.is_finite() {
        return Err(r.invalid(
            "to",
            r.get("to").unwrap_or(node),
            "must differ from `from` (at a distance that fits in f32)",
        ));
    }
    // The image's right axis is normalize(cross(forward, up)); it must exist.
    let right = (forward / distance).cross(up).length();
    let up_len = up.length();
    if up_len == 0.0 || !up_len.is_finite() || right <= 1e-6 * up_len {
        return Err(r.invalid(
            "up",
            r.get("up").unwrap_or(node),
            "must be non-zero and not parallel to the view direction `to - from`",
        ));
    }
    let inside = match r.array_opt("inside")? {
        None => None,
        Some(items) => Some(read_inside(&r, items, shapes)?),
    };
    let inside_at = r
        .get("inside")
        .map(|node| Location::new(src, node.span(), "camera", Some("inside")));
    Ok((
        CameraDesc {
            projection,
            from,
            to,
            up,
        },
        inside,
        inside_at,
    ))
}

/// `camera.inside`: shape names, outermost first, each a closed shape, no repeats.
fn read_inside(
    r: &Reader<'_>,
    items: &[Node],
    shapes: &[ShapeDesc],
) -> Result<Vec<String>, SceneError> {
    let mut out: Vec<String> = Vec::with_capacity(items.len());
    for item in items {
        let Value::String(name) = &item.value else {
            return Err(r.wrong_type("inside", item, "a shape name (string)"));
        };
        let Some(shape) = shapes.iter().find(|s| &s.name == name) else {
            return Err(r.error(
                SceneErrorKind::UnknownReference,
                &item.span(),
                Some("inside"),
                format!("unknown shape `{name}`"),
            ));
        };
        if let ShapeGeometry::Triangles {
            kind: kind @ ("quad" | "disk"),
            ..
        } = shape.geometry
        {
            return Err(r.invalid(
                "inside",
                item,
                &format!("shape `{name}` is a {kind}, which has no inside"),
            ));
        }
        if out.contains(name) {
            return Err(r.error(
                SceneErrorKind::Duplicate,
                &item.span(),
                Some("inside"),
                format!("shape `{name}` is listed twice"),
            ));
        }
        out.push(name.clone());
    }
    Ok(out)
}
