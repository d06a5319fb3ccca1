//! Scene-file parameters of pbrt-v4's layered materials, `coated_diffuse` and
//! `coated_conductor` (keys, defaults and ranges in `docs/scene-format.md`; the names are
//! pbrt-v4's with `_` for `.`, which the pbrt importer emits as they are).

use crate::scene_file::{ColourParam, MaterialParams, SceneError};
use risotto_builtins::builtin::{CoatedBase, CoatedReflectance, CoatedSurface, Surface};
use risotto_components::Rgb;
use risotto_systems::conductor::metal;
use risotto_systems::layered::{Coat, Layered, SMOOTH_ALPHA};
use risotto_systems::microfacet::Ggx;
use risotto_systems::rough_conductor::RoughConductor;
use std::sync::Arc;

/// Longest walk a scene may ask for: the walk runs per evaluation, so its length is time.
const MAX_DEPTH_LIMIT: u32 = 1000;
/// Most walks per evaluation a scene may ask for.
const N_SAMPLES_LIMIT: u32 = 256;

/// The keys of the slab and the walk, shared by both materials.
const LAYER_KEYS: [&str; 7] = [
    "thickness",
    "albedo",
    "g",
    "max_depth",
    "n_samples",
    "remap_roughness",
    "two_sided",
];

/// A GGX distribution from `{prefix}roughness` or `{prefix}uroughness` /
/// `{prefix}vroughness` (each defaulting to the isotropic one, which defaults to 0), every
/// value >= 0; with `remap` the roughness is mapped to `alpha = sqrt(roughness)` (pbrt-v4's
/// `TrowbridgeReitzDistribution::RoughnessToAlpha`). `None` when the larger `alpha` is
/// below [`SMOOTH_ALPHA`] (a specular interface).
fn roughness(p: &MaterialParams, prefix: &str, remap: bool) -> Result<Option<Ggx>, SceneError> {
    let read = |key: &str, default: f32| {
        p.f32_where(key, Some(default), "must be >= 0 and finite", |r| {
            r >= 0.0 && r.is_finite()
        })
    };
    let iso = read(&format!("{prefix}roughness"), 0.0)?;
    let u = read(&format!("{prefix}uroughness"), iso)?;
    let v = read(&format!("{prefix}vroughness"), iso)?;
    let alpha = |r: f32| if remap { r.sqrt() } else { r };
    let (au, av) = (alpha(u), alpha(v));
    Ok((au.max(av) >= SMOOTH_ALPHA).then(|| Ggx::new(au, av)))
}

/// An index of refraction at `key` (> 0 and finite, default 1.5).
fn eta(p: &MaterialParams, key: &str) -> Result<f32, SceneError> {
    p.f32_where(key, Some(1.5), "must be > 0 and finite", |v| {
        v > 0.0 && v.is_finite()
    })
}

/// The slab and walk over `coat`: `thickness` (>= 0, default 0.01; 0 is taken as the
/// smallest positive float, as pbrt-v4 does), `albedo` (a colour in [0, 1], default 0), `g`
/// (in [-1, 1], default 0), `max_depth` (0 to 1000, default 10), `n_samples` (1 to 256,
/// default 1). `two_sided` may only be `true`: the layered Bxdf is two-sided.
fn layered(p: &MaterialParams, coat: Coat) -> Result<Layered, SceneError> {
    if p.has("two_sided") && !p.bool("two_sided", None)? {
        return Err(p.error(
            Some("two_sided"),
            "pbrt-v4's layered materials are two-sided (the layers are mirrored seen from \
             behind); `two_sided = false` is not available",
        ));
    }
    let thickness = p.f32_where("thickness", Some(0.01), "must be >= 0 and finite", |t| {
        t >= 0.0 && t.is_finite()
    })?;
    let albedo = p.rgb_where("albedo", Some(Rgb::BLACK), "every channel in [0, 1]", |c| {
        c.min_channel() >= 0.0 && c.max_channel() <= 1.0
    })?;
    let g = p.f32_in("g", Some(0.0), -1.0, 1.0)?;
    let max_depth = p.u32("max_depth", Some(10))?;
    if max_depth > MAX_DEPTH_LIMIT {
        return Err(p.error(
            Some("max_depth"),
            format!("must be at most {MAX_DEPTH_LIMIT} (the walk runs at every evaluation), got {max_depth}"),
        ));
    }
    let n_samples = p.u32("n_samples", Some(1))?;
    if !(1..=N_SAMPLES_LIMIT).contains(&n_samples) {
        return Err(p.error(
            Some("n_samples"),
            format!("must be in [1, {N_SAMPLES_LIMIT}], got {n_samples}"),
        ));
    }
    Ok(Layered {
        coat,
        thickness: thickness.max(f32::MIN_POSITIVE),
        albedo,
        g,
        max_depth,
        n_samples,
    })
}

/// The coat of index `eta` and distribution `ggx` (`None`: smooth).
fn coat(ggx: Option<Ggx>, eta: f32) -> Coat {
    // Below SMOOTH_ALPHA `Coat::new` takes the specular branch.
    Coat::new(ggx.unwrap_or(Ggx::isotropic(0.0)), eta)
}

/// `type = "coated_diffuse"`: pbrt-v4's `coateddiffuse`. `reflectance` (a colour or a
/// pattern in [0, 1], default 0.5), the coat's `roughness` / `uroughness` / `vroughness`
/// and `eta`, and the slab and walk keys of [`layered`]. Returns the surface and the keys it
/// read.
pub(crate) fn coated_diffuse(
    p: &MaterialParams,
) -> Result<(Surface, Vec<&'static str>), SceneError> {
    let remap = p.bool("remap_roughness", Some(true))?;
    let coat = coat(roughness(p, "", remap)?, eta(p, "eta")?);
    let reflectance = match p.colour_or_pattern("reflectance", Rgb::splat(0.5), [0.0, 1.0])? {
        ColourParam::Constant(c) => CoatedReflectance::Color(c),
        ColourParam::Pattern(graph) => CoatedReflectance::Pattern(Arc::new(graph)),
    };
    let surface = Surface::Coated(Box::new(CoatedSurface {
        layered: layered(p, coat)?,
        base: CoatedBase::Diffuse,
        reflectance,
    }));
    let mut keys = LAYER_KEYS.to_vec();
    keys.extend([
        "reflectance",
        "roughness",
        "uroughness",
        "vroughness",
        "eta",
    ]);
    Ok((surface, keys))
}

/// `type = "coated_conductor"`: pbrt-v4's `coatedconductor`. The coat's
/// `interface_roughness` (or `interface_uroughness` / `interface_vroughness`, default 0)
/// and `interface_eta` (default 1.5); the base's `conductor_eta` and `conductor_k` (colours,
/// default copper, the `Cu` of the metal table) or `reflectance` (a colour in [0, 1]: the
/// index `1 + i 2 sqrt(r) / sqrt(1 - r)` of that normal reflectance, pbrt-v4's), both
/// divided by the coat's index (the base sits in the coat's medium), and
/// `conductor_roughness` (or u/v, default 0); the slab and walk keys of [`layered`].
pub(crate) fn coated_conductor(
    p: &MaterialParams,
) -> Result<(Surface, Vec<&'static str>), SceneError> {
    let remap = p.bool("remap_roughness", Some(true))?;
    let interface_eta = eta(p, "interface_eta")?;
    let coat = coat(roughness(p, "interface_", remap)?, interface_eta);
    let non_negative = "every channel >= 0 and finite";
    let ok = |c: Rgb| c.min_channel() >= 0.0 && c.is_finite();
    let (cond_eta, cond_k) = match (
        p.has("reflectance"),
        p.has("conductor_eta"),
        p.has("conductor_k"),
    ) {
        (false, false, false) => {
            // pbrt-v4's default is "metal-Cu-eta" / "metal-Cu-k": the metal table's copper.
            let cu = metal("Cu").ok_or_else(|| p.error(None, "the metal table has no `Cu`"))?;
            (Rgb::from_array(cu.eta), Rgb::from_array(cu.k))
        }
        (false, true, true) => (
            p.rgb_where("conductor_eta", None, non_negative, ok)?,
            p.rgb_where("conductor_k", None, non_negative, ok)?,
        ),
        (true, false, false) => {
            let r = p.rgb_where("reflectance", None, "every channel in [0, 1]", |c| {
                c.min_channel() >= 0.0 && c.max_channel() <= 1.0
            })?;
            // pbrt-v4 clamps r to 0.9999 (r = 1 has no finite k).
            let k = r.map(|r| {
                let r = r.clamp(0.0, 0.9999);
                2.0 * r.sqrt() / (1.0 - r).sqrt()
            });
            (Rgb::WHITE, k)
        }
        (true, _, _) => {
            return Err(p.error(
                Some("reflectance"),
                "give either `reflectance` or `conductor_eta` and `conductor_k`, not both",
            ))
        }
        (false, e, _) => {
            return Err(p.error(
                Some(if e { "conductor_eta" } else { "conductor_k" }),
                "a complex index needs both `conductor_eta` and `conductor_k`",
            ))
        }
    };
    let (cond_eta, cond_k) = (
        cond_eta * (1.0 / interface_eta),
        cond_k * (1.0 / interface_eta),
    );
    let base = match roughness(p, "conductor_", remap)? {
        None => CoatedBase::SmoothConductor {
            eta: cond_eta,
            k: cond_k,
        },
        Some(ggx) => CoatedBase::RoughConductor(RoughConductor::new(
            ggx,
            cond_eta,
            cond_k,
            Rgb::WHITE,
            false,
        )),
    };
    let surface = Surface::Coated(Box::new(CoatedSurface {
        layered: layered(p, coat)?,
        base,
        reflectance: CoatedReflectance::Color(Rgb::BLACK),
    }));
    let mut keys = LAYER_KEYS.to_vec();
    keys.extend([
        "interface_roughness",
        "interface_uroughness",
        "interface_vroughness",
        "interface_eta",
        "conductor_eta",
        "conductor_k",
        "reflectance",
        "conductor_roughness",
        "conductor_uroughness",
        "conductor_vroughness",
    ]);
    Ok((surface, keys))
}
