//! Scene-file parameters of the microfacet materials, `rough_conductor`,
//! `rough_dielectric` and `rough_plastic`, named as Mitsuba 3's `roughconductor` / `roughdielectric`
//! (`distribution`, `alpha`, `alpha_u`, `alpha_v`, `eta`, `k`, `material`,
//! `specular_reflectance`) in the project's TOML style.

use crate::scene_file::{ColourParam, MaterialParams, SceneError};
use crate::surface_params::{coat_eta, specular_reflectance};
use risotto_builtins::builtin::Surface;
use risotto_components::Rgb;
use risotto_systems::conductor::{metal, METALS};
use risotto_systems::microfacet::{Beckmann, Ggx, Microfacet};
use risotto_systems::rough_conductor::RoughConductor;
use risotto_systems::rough_dielectric::RoughDielectric;
use risotto_systems::rough_plastic::RoughPlastic;
use std::sync::Arc;

/// Roughness when a material gives none (Mitsuba's default).
const DEFAULT_ALPHA: f32 = 0.1;

/// The keys both microfacet materials share.
const ROUGHNESS_KEYS: [&str; 5] = [
    "distribution",
    "alpha",
    "alpha_u",
    "alpha_v",
    "energy_compensation",
];

/// The distribution's family: `distribution = "ggx"` (the default) or `"beckmann"`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Family {
    /// GGX (Trowbridge-Reitz).
    Ggx,
    /// Beckmann.
    Beckmann,
}

impl Family {
    /// The distribution of this family with roughnesses `alpha_u`, `alpha_v`.
    pub(crate) fn with(self, alpha_u: f32, alpha_v: f32) -> Microfacet {
        match self {
            Family::Ggx => Ggx::new(alpha_u, alpha_v).into(),
            Family::Beckmann => Beckmann::new(alpha_u, alpha_v).into(),
        }
    }
}

/// `distribution`: `"ggx"` (default) or `"beckmann"`.
pub(crate) fn family(p: &MaterialParams) -> Result<Family, SceneError> {
    match p.string("distribution", Some("ggx"))?.as_str() {
        "ggx" => Ok(Family::Ggx),
        "beckmann" => Ok(Family::Beckmann),
        other => Err(p.error(
            Some("distribution"),
            format!("unknown microfacet distribution \"{other}\" (known: ggx, beckmann)"),
        )),
    }
}

/// One roughness: a finite number in `(0, 1]`.
pub(crate) fn alpha(p: &MaterialParams, key: &str) -> Result<f32, SceneError> {
    p.f32_where(key, Some(DEFAULT_ALPHA), "must be in (0, 1]", |a| {
        a > 0.0 && a <= 1.0
    })
}

/// The distribution: its family ([`family`]) and `alpha` (isotropic), or `alpha_u` and
/// `alpha_v` together.
fn distribution(p: &MaterialParams) -> Result<Microfacet, SceneError> {
    let family = family(p)?;
    match (p.has("alpha"), p.has("alpha_u"), p.has("alpha_v")) {
        (true, false, false) | (false, false, false) => {
            let a = alpha(p, "alpha")?;
            Ok(family.with(a, a))
        }
        (false, true, true) => Ok(family.with(alpha(p, "alpha_u")?, alpha(p, "alpha_v")?)),
        (true, _, _) => {
            let key = if p.has("alpha_u") {
                "alpha_u"
            } else {
                "alpha_v"
            };
            Err(p.error(
                Some(key),
                "give either `alpha` (isotropic) or `alpha_u` and `alpha_v`, not both",
            ))
        }
        (false, u, _) => Err(p.error(
            Some(if u { "alpha_u" } else { "alpha_v" }),
            "an anisotropic roughness needs both `alpha_u` and `alpha_v`",
        )),
    }
}

/// `type = "rough_conductor"`: `distribution`, `alpha` or `alpha_u` + `alpha_v`; the complex index as
/// `material` (a name of [`METALS`], default `"none"`, a perfect reflector) or as `eta` and
/// `k` colours; `specular_reflectance` (a colour in [0, 1], default 1);
/// `energy_compensation` (default true). Returns the surface and the keys it read (the
/// registry adds `interior` and rejects any other key).
pub(crate) fn rough_conductor(
    p: &MaterialParams,
) -> Result<(Surface, Vec<&'static str>), SceneError> {
    let ggx = distribution(p)?;
    let non_negative = "every channel >= 0 and finite";
    let ok = |c: Rgb| c.min_channel() >= 0.0 && c.is_finite();
    let (eta, k) = match (p.has("material"), p.has("eta"), p.has("k")) {
        (true, false, false) | (false, false, false) => {
            let name = p.string("material", Some("none"))?;
            let m = metal(&name).ok_or_else(|| {
                let known: Vec<&str> = METALS.iter().map(|m| m.name).collect();
                p.error(
                    Some("material"),
                    format!("unknown metal \"{name}\" (known: {})", known.join(", ")),
                )
            })?;
            (Rgb::from_array(m.eta), Rgb::from_array(m.k))
        }
        (false, true, true) => (
            p.rgb_where("eta", None, non_negative, ok)?,
            p.rgb_where("k", None, non_negative, ok)?,
        ),
        (true, _, _) => {
            return Err(p.error(
                Some("material"),
                "give either `material` or `eta` and `k`, not both",
            ))
        }
        (false, e, _) => {
            return Err(p.error(
                Some(if e { "eta" } else { "k" }),
                "a complex index needs both `eta` and `k`",
            ))
        }
    };
    let tint = p.rgb_where(
        "specular_reflectance",
        Some(Rgb::WHITE),
        "every channel in [0, 1]",
        |c| c.min_channel() >= 0.0 && c.max_channel() <= 1.0,
    )?;
    let compensation = p.bool("energy_compensation", Some(true))?;
    let lobe = RoughConductor::new(ggx, eta, k, tint, compensation);
    let mut keys = ROUGHNESS_KEYS.to_vec();
    keys.extend(["material", "eta", "k", "specular_reflectance"]);
    Ok((Surface::RoughConductor(lobe), keys))
}

/// `type = "rough_dielectric"`: `distribution`, `alpha` or `alpha_u` + `alpha_v`; `ior` (> 0, default 1.5);
/// `tint` (a colour in [0, 1] multiplying transmitted light, default 1);
/// `energy_compensation` (default true). Returns the surface and the keys it read.
pub(crate) fn rough_dielectric(
    p: &MaterialParams,
) -> Result<(Surface, Vec<&'static str>), SceneError> {
    let ggx = distribution(p)?;
    let ior = p.f32_where("ior", Some(1.5), "must be > 0", |v| v > 0.0)?;
    let tint = p.rgb_where("tint", Some(Rgb::WHITE), "every channel in [0, 1]", |c| {
        c.min_channel() >= 0.0 && c.max_channel() <= 1.0
    })?;
    let compensation = p.bool("energy_compensation", Some(true))?;
    let lobe = RoughDielectric::new(ggx, ior, tint, compensation);
    let mut keys = ROUGHNESS_KEYS.to_vec();
    keys.extend(["ior", "tint"]);
    Ok((Surface::RoughDielectric(lobe), keys))
}

/// The keys of a `rough_plastic` material besides `interior` and `two_sided`.
pub(crate) const ROUGH_PLASTIC_KEYS: [&str; 7] = [
    "distribution",
    "alpha",
    "diffuse_reflectance",
    "specular_reflectance",
    "int_ior",
    "ext_ior",
    "nonlinear",
];

/// `type = "rough_plastic"`: Mitsuba 3's `roughplastic`. `distribution` (default `"ggx"`),
/// `alpha` (isotropic only, as Mitsuba's), `diffuse_reflectance` (a colour or a pattern in
/// [0, 1], default 0.5), `specular_reflectance`, `int_ior`, `ext_ior` and `nonlinear` as
/// the smooth `plastic`; `int_ior` must differ from `ext_ior`. No energy compensation (the
/// model's diffuse lobe is its own account of the coat's transmission).
pub(crate) fn rough_plastic(p: &MaterialParams) -> Result<Surface, SceneError> {
    for key in ["alpha_u", "alpha_v"] {
        if p.has(key) {
            return Err(p.error(
                Some(key),
                "rough_plastic is isotropic (its coat's transmittance is tabulated per \
                 cosine, as Mitsuba's): give `alpha`",
            ));
        }
    }
    if p.has("energy_compensation") {
        return Err(p.error(
            Some("energy_compensation"),
            "rough_plastic has no energy compensation: its diffuse lobe already accounts \
             for the light the rough coat transmits (Mitsuba 3's model)",
        ));
    }
    let family = family(p)?;
    let a = alpha(p, "alpha")?;
    let eta = coat_eta(p)?;
    if eta == 1.0 {
        return Err(p.error(
            Some("int_ior"),
            "int_ior equals ext_ior: an index-matched coat reflects nothing (use `diffuse`)",
        ));
    }
    let lobe = RoughPlastic::new(
        family.with(a, a),
        eta,
        specular_reflectance(p)?,
        p.bool("nonlinear", Some(false))?,
    );
    Ok(
        match p.colour_or_pattern("diffuse_reflectance", Rgb::splat(0.5), [0.0, 1.0])? {
            ColourParam::Constant(diffuse) => Surface::RoughPlastic { lobe, diffuse },
            ColourParam::Pattern(graph) => Surface::RoughPlasticPattern {
                lobe,
                diffuse: Arc::new(graph),
            },
        },
    )
}
