//! Reading the `plastic` and `thin_dielectric` materials and the `two_sided` switch of the
//! one-sided reflectors (keys and defaults in `docs/scene-format.md`).

use crate::scene_file::{ColourParam, MaterialParams, SceneError};
use risotto_builtins::builtin::Surface;
use risotto_components::Rgb;
use risotto_systems::bxdf::PlasticCoat;
use std::sync::Arc;

/// The requirement of an index of refraction.
const POSITIVE_FINITE: &str = "must be > 0 and finite";

/// An index of refraction at `key`: positive and finite (NaN is refused by the number
/// reader already).
fn ior(p: &MaterialParams, key: &str, default: f32) -> Result<f32, SceneError> {
    p.f32_where(key, Some(default), POSITIVE_FINITE, |v| {
        v > 0.0 && v.is_finite()
    })
}

/// `type = "plastic"`: Mitsuba 3's smooth plastic. `diffuse_reflectance` (a colour or a
/// pattern in [0, 1], default 0.5), `specular_reflectance` (a colour in [0, 1], default 1),
/// `int_ior` (default 1.49, polypropylene) and `ext_ior` (default 1), `nonlinear` (default
/// false). The keys it read, for `deny_unknown`, are [`PLASTIC_KEYS`].
pub fn plastic(p: &MaterialParams) -> Result<Surface, SceneError> {
    let eta = coat_eta(p)?;
    let specular = specular_reflectance(p)?;
    let coat = PlasticCoat::new(eta, specular, p.bool("nonlinear", Some(false))?);
    Ok(
        match p.colour_or_pattern("diffuse_reflectance", Rgb::splat(0.5), [0.0, 1.0])? {
            ColourParam::Constant(diffuse) => Surface::Plastic { coat, diffuse },
            ColourParam::Pattern(graph) => Surface::PlasticPattern {
                coat,
                diffuse: Arc::new(graph),
            },
        },
    )
}

/// A plastic's relative index `int_ior / ext_ior` (defaults 1.49, polypropylene, and 1):
/// each positive and finite, and their ratio usable.
pub(crate) fn coat_eta(p: &MaterialParams) -> Result<f32, SceneError> {
    let int_ior = ior(p, "int_ior", 1.49)?;
    let ext_ior = ior(p, "ext_ior", 1.0)?;
    let eta = int_ior / ext_ior;
    if !(eta > 0.0 && eta.is_finite()) {
        return Err(p.error(
            Some("int_ior"),
            format!("int_ior / ext_ior = {int_ior} / {ext_ior} is not a usable ratio"),
        ));
    }
    Ok(eta)
}

/// A plastic's `specular_reflectance`: a colour in [0, 1], default 1.
pub(crate) fn specular_reflectance(p: &MaterialParams) -> Result<Rgb, SceneError> {
    p.rgb_where(
        "specular_reflectance",
        Some(Rgb::WHITE),
        "every channel in [0, 1]",
        |c| c.min_channel() >= 0.0 && c.max_channel() <= 1.0,
    )
}

/// The keys of a `plastic` material besides `interior` and `two_sided`.
pub const PLASTIC_KEYS: [&str; 5] = [
    "diffuse_reflectance",
    "specular_reflectance",
    "int_ior",
    "ext_ior",
    "nonlinear",
];

/// `type = "thin_dielectric"`: a thin pane, `ior` (default 1.5). With an `interior`, the
/// closed shape it covers bounds a volume whose index is the vacuum's (Mitsuba's
/// thindielectric around a medium): the pane reflects and passes light as anywhere else, and
/// a ray it passes enters or leaves the volume.
pub fn thin_dielectric(p: &MaterialParams) -> Result<Surface, SceneError> {
    reject_two_sided(p, "thin_dielectric")?;
    Ok(Surface::ThinDielectric {
        ior: ior(p, "ior", 1.5)?,
        null_transmission: p.bool("null_transmission", Some(false))?,
    })
}

/// `two_sided = true` (default false) wraps the one-sided reflector `surface` so that it is
/// shaded on whichever side the viewer is.
pub fn two_sided(p: &MaterialParams, surface: Surface) -> Result<Surface, SceneError> {
    Ok(match p.bool("two_sided", Some(false))? {
        true => Surface::TwoSided(Box::new(surface)),
        false => surface,
    })
}

/// An error when a material of type `kind`, which transmits light, says `two_sided`: the
/// wrapper mirrors a reflecting lobe to the viewer's side, and a surface that transmits is
/// seen from both sides already (its two sides differ by which medium is inside).
pub fn reject_two_sided(p: &MaterialParams, kind: &str) -> Result<(), SceneError> {
    if p.has("two_sided") {
        return Err(p.error(
            Some("two_sided"),
            format!(
                "`two_sided` applies to surfaces that only reflect (diffuse, plastic, rough_plastic, \
                 rough_conductor); a \
                 `{kind}` transmits light and is already seen from both sides"
            ),
        ));
    }
    Ok(())
}
