//! `within` on the camera and on shapes: statements of the volume they sit in, checked when
//! the scene is compiled ([`risotto_engine::scene::WithinCheck`]). Importers of formats that
//! name media explicitly (Mitsuba 3's sensor medium and shape `exterior`) write them.

use super::raw::Value;
use super::{section, Arc, Location, Reader, SceneError, SceneErrorKind, ShapeDesc, Source};
use risotto_engine::scene::{WithinCheck, NO_MEDIUM};

/// The checks of `camera.within` and of every `shapes[i].within`, in file order (the camera
/// first).
pub(super) fn read_within(
    top: &Reader<'_>,
    shapes: &[ShapeDesc],
    src: &Arc<Source>,
) -> Result<Vec<WithinCheck>, SceneError> {
    let mut checks = Vec::new();
    if let Some(node) = section(top, "camera")? {
        let r = Reader::new(top.src, node, "camera");
        if let Some((names, no_medium)) = names(&r, shapes)? {
            checks.push(WithinCheck {
                subject: None,
                within: names,
                no_medium,
                at: located(&r, src, "camera"),
            });
        }
    }
    let Some(items) = top.array_opt("shapes")? else {
        return Ok(checks);
    };
    for (i, node) in items.iter().enumerate() {
        let bare = Reader::new(top.src, node, "shapes");
        let name = match bare.get("name").map(|n| &n.value) {
            Some(Value::String(n)) => n.clone(),
            _ => format!("shapes[{i}]"),
        };
        let entity = format!("shapes[{i}] \"{name}\"");
        let r = Reader::new(top.src, node, &entity);
        if let Some((within, no_medium)) = names(&r, shapes)? {
            checks.push(WithinCheck {
                subject: Some(name),
                within,
                no_medium,
                at: located(&r, src, &entity),
            });
        }
    }
    Ok(checks)
}

/// Where `within` is written in `r`'s table.
fn located(r: &Reader<'_>, src: &Arc<Source>, entity: &str) -> Option<Location> {
    r.get("within")
        .map(|node| Location::new(src, node.span(), entity, Some("within")))
}

/// `within = ["shape", ...]`: names of shapes of the scene, no repeats; or `within = "no
/// medium"` (the names empty and the flag set).
fn names(r: &Reader<'_>, shapes: &[ShapeDesc]) -> Result<Option<(Vec<String>, bool)>, SceneError> {
    if let Some(node) = r.get("within") {
        if let Value::String(s) = &node.value {
            if s == NO_MEDIUM {
                return Ok(Some((Vec::new(), true)));
            }
            return Err(r.error(
                SceneErrorKind::InvalidValue,
                &node.span(),
                Some("within"),
                format!("must be an array of shape names or \"{NO_MEDIUM}\", got \"{s}\""),
            ));
        }
    }
    let Some(items) = r.array_opt("within")? else {
        return Ok(None);
    };
    let mut out: Vec<String> = Vec::with_capacity(items.len());
    for item in items {
        let Value::String(name) = &item.value else {
            return Err(r.wrong_type("within", item, "a shape name (string)"));
        };
        if !shapes.iter().any(|s| &s.name == name) {
            return Err(r.error(
                SceneErrorKind::UnknownReference,
                &item.span(),
                Some("within"),
                format!("unknown shape `{name}`"),
            ));
        }
        if out.contains(name) {
            return Err(r.error(
                SceneErrorKind::Duplicate,
                &item.span(),
                Some("within"),
                format!("shape `{name}` is listed twice"),
            ));
        }
        out.push(name.clone());
    }
    Ok(Some((out, false)))
}
