//! Scene-file parameters of the microfacet materials, `rough_conductor`,
//! `rough_dielectric` and `rough_plastic`, named as Mitsuba 3's `roughconductor` / `roughdielectric`
//! (`distribution`, `alpha`, `alpha_u`, `alpha_v`, `eta`, `k`, `material`,
//! `specular_reflectance`) in the project's TOML style.

use crate::scene_file::{ColourParam, MaterialParams, SceneError};
use crate::surface_params::{coat_eta, specular_reflectance};
use glam::Vec3;
use risotto_builtins::builtin::{
    Surface, Varying, VaryingConductor, VaryingDielectric, VaryingPlastic, VaryingRoughness,
};
use risotto_components::Rgb;
use risotto_systems::conductor::{metal, METALS};
use risotto_systems::energy_compensation::AlbedoTable;
use risotto_systems::microfacet::{Beckmann, Ggx, Masking, Microfacet};
use risotto_systems::pattern::{self, PatternGraph};
use risotto_systems::rough_conductor::RoughConductor;
use risotto_systems::rough_dielectric::RoughDielectric;
use risotto_systems::rough_plastic::{CoatTables, RoughPlastic};
use risotto_systems::roughness_grid::{RoughnessAxis, RoughnessGrid, POINTS_1D, POINTS_2D};
use std::sync::Arc;

/// Roughness when a material gives none (Mitsuba's default).
const DEFAULT_ALPHA: f32 = 0.1;

/// The keys both microfacet materials share.
const ROUGHNESS_KEYS: [&str; 6] = [
    "distribution",
    "masking",
    "alpha",
    "alpha_u",
    "alpha_v",
    "energy_compensation",
];

/// The distribution's family (`distribution = "ggx"`, the default, or `"beckmann"`) and
/// its masking-shadowing function (`masking = "height_correlated"`, the default, or
/// `"separable"`, Mitsuba 3's).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Family {
    /// Beckmann rather than GGX (Trowbridge-Reitz).
    beckmann: bool,
    /// `G2`'s form.
    masking: Masking,
}

impl Family {
    /// The distribution of this family with roughnesses `alpha_u`, `alpha_v`.
    pub(crate) fn with(self, alpha_u: f32, alpha_v: f32) -> Microfacet {
        let d: Microfacet = if self.beckmann {
            Beckmann::new(alpha_u, alpha_v).into()
        } else {
            Ggx::new(alpha_u, alpha_v).into()
        };
        d.with_masking(self.masking)
    }
}

/// `distribution`: `"ggx"` (default) or `"beckmann"`; `masking`: `"height_correlated"`
/// (default) or `"separable"`.
pub(crate) fn family(p: &MaterialParams) -> Result<Family, SceneError> {
    let beckmann = match p.string("distribution", Some("ggx"))?.as_str() {
        "ggx" => false,
        "beckmann" => true,
        other => {
            return Err(p.error(
                Some("distribution"),
                format!("unknown microfacet distribution \"{other}\" (known: ggx, beckmann)"),
            ))
        }
    };
    let masking = match p.string("masking", Some("height_correlated"))?.as_str() {
        "height_correlated" => Masking::HeightCorrelated,
        "separable" => Masking::Separable,
        other => {
            return Err(p.error(
                Some("masking"),
                format!(
                    "unknown masking-shadowing function \"{other}\" (known: \
                     height_correlated, separable)"
                ),
            ))
        }
    };
    Ok(Family { beckmann, masking })
}

/// One roughness: a finite number in `(0, 1]`.
pub(crate) fn alpha(p: &MaterialParams, key: &str) -> Result<f32, SceneError> {
    p.f32_where(key, Some(DEFAULT_ALPHA), "must be in (0, 1]", |a| {
        a > 0.0 && a <= 1.0
    })
}

/// The interval bounds of `graph`'s values over all of space ([`pattern::bounds`]).
fn bounds_everywhere(graph: &PatternGraph) -> (Rgb, Rgb) {
    pattern::bounds(graph, Vec3::NEG_INFINITY, Vec3::INFINITY)
}

/// One roughness that may be a pattern: a number in `(0, 1]` ([`alpha`]) or a grey pattern
/// table whose values lie in `(0, 1]` everywhere by its interval bounds.
fn varying_alpha(p: &MaterialParams, key: &str) -> Result<Varying<f32>, SceneError> {
    if !p.is_table(key) {
        return alpha(p, key).map(Varying::Constant);
    }
    let graph = p.pattern(key)?.expect("checked: a table");
    if !graph.is_grey() {
        return Err(p.error(
            Some(key),
            "a roughness is one number per point: the pattern must be grey (every colour \
             in it, and every texel of an image in it, with equal channels)",
        ));
    }
    let (lo, hi) = bounds_everywhere(&graph);
    if !(lo.r > 0.0 && hi.r <= 1.0) {
        return Err(p.error(
            Some(key),
            format!(
                "the pattern must keep the roughness in (0, 1], but its values may reach \
                 {} .. {} (interval bounds over all of space): wrap it in `remap` or `scale`",
                lo.r, hi.r
            ),
        ));
    }
    Ok(Varying::Pattern(Arc::new(graph)))
}

/// The interval a roughness takes: its value, or its pattern's bounds.
fn alpha_interval(a: &Varying<f32>) -> (f32, f32) {
    match a {
        Varying::Constant(a) => (*a, *a),
        Varying::Pattern(g) => {
            let (lo, hi) = bounds_everywhere(g);
            (lo.r, hi.r)
        }
    }
}

/// A material's roughness as read: constant, or with a pattern on at least one axis.
enum Roughness {
    /// Every roughness a number: the distribution.
    Constant(Microfacet),
    /// At least one pattern.
    Varying(VaryingRoughness),
}

impl Roughness {
    /// The grid of `table(distribution)` over the roughness interval: along `alpha` for an
    /// isotropic roughness, over `(alpha_u, alpha_v)` otherwise (one point along an axis
    /// that is a number).
    fn grid<T: risotto_systems::roughness_grid::Lerp + Clone>(
        r: &VaryingRoughness,
        table: impl Fn(&Microfacet) -> T,
    ) -> RoughnessGrid<T> {
        let (ulo, uhi) = alpha_interval(&r.alpha_u);
        let make = |au, av| table(&r.family.with_alphas(au, av));
        match &r.alpha_v {
            None => RoughnessGrid::new(RoughnessAxis::new(ulo, uhi, POINTS_1D), None, make),
            Some(v) => {
                let (vlo, vhi) = alpha_interval(v);
                let both = ulo < uhi && vlo < vhi;
                let n = if both { POINTS_2D } else { POINTS_1D };
                RoughnessGrid::new(
                    RoughnessAxis::new(ulo, uhi, n),
                    Some(RoughnessAxis::new(vlo, vhi, n)),
                    make,
                )
            }
        }
    }
}

/// The distribution: its family ([`family`]) and `alpha` (isotropic), or `alpha_u` and
/// `alpha_v` together; each a number or a grey pattern ([`varying_alpha`]).
fn distribution(p: &MaterialParams) -> Result<Roughness, SceneError> {
    let family = family(p)?;
    let (alpha_u, alpha_v) = match (p.has("alpha"), p.has("alpha_u"), p.has("alpha_v")) {
        (true, false, false) | (false, false, false) => (varying_alpha(p, "alpha")?, None),
        (false, true, true) => (
            varying_alpha(p, "alpha_u")?,
            Some(varying_alpha(p, "alpha_v")?),
        ),
        (true, _, _) => {
            let key = if p.has("alpha_u") {
                "alpha_u"
            } else {
                "alpha_v"
            };
            return Err(p.error(
                Some(key),
                "give either `alpha` (isotropic) or `alpha_u` and `alpha_v`, not both",
            ));
        }
        (false, u, _) => {
            return Err(p.error(
                Some(if u { "alpha_u" } else { "alpha_v" }),
                "an anisotropic roughness needs both `alpha_u` and `alpha_v`",
            ))
        }
    };
    Ok(match (alpha_u, alpha_v) {
        (Varying::Constant(a), None) => Roughness::Constant(family.with(a, a)),
        (Varying::Constant(u), Some(Varying::Constant(v))) => {
            Roughness::Constant(family.with(u, v))
        }
        (alpha_u, alpha_v) => Roughness::Varying(VaryingRoughness {
            family: family.with(DEFAULT_ALPHA, DEFAULT_ALPHA),
            alpha_u,
            alpha_v,
        }),
    })
}

/// One part of a complex index, `eta` or `k`: a colour with every channel `>= 0` and
/// finite, or a colour pattern whose interval bounds keep it so.
fn index_part(p: &MaterialParams, key: &str) -> Result<Varying<Rgb>, SceneError> {
    let non_negative = "every channel >= 0 and finite";
    let ok = |c: Rgb| c.min_channel() >= 0.0 && c.is_finite();
    if !p.is_table(key) {
        return p
            .rgb_where(key, None, non_negative, ok)
            .map(Varying::Constant);
    }
    let graph = p.pattern(key)?.expect("checked: a table");
    let (lo, hi) = bounds_everywhere(&graph);
    if !(ok(lo) && ok(hi)) {
        return Err(p.error(
            Some(key),
            format!(
                "the pattern must keep {non_negative}, but its values may reach \
                 [{}, {}, {}] .. [{}, {}, {}] (interval bounds over all of space): wrap it \
                 in `remap` or `scale`",
                lo.r, lo.g, lo.b, hi.r, hi.g, hi.b
            ),
        ));
    }
    Ok(Varying::Pattern(Arc::new(graph)))
}

/// `type = "rough_conductor"`: `distribution`, `alpha` or `alpha_u` + `alpha_v`; the complex index as
/// `material` (a name of [`METALS`], default `"none"`, a perfect reflector) or as `eta` and
/// `k` colours; `specular_reflectance` (a colour in [0, 1], default 1);
/// `energy_compensation` (default true). Returns the surface and the keys it read (the
/// registry adds `interior` and rejects any other key).
pub(crate) fn rough_conductor(
    p: &MaterialParams,
) -> Result<(Surface, Vec<&'static str>), SceneError> {
    let roughness = distribution(p)?;
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
            (
                Varying::Constant(Rgb::from_array(m.eta)),
                Varying::Constant(Rgb::from_array(m.k)),
            )
        }
        (false, true, true) => (index_part(p, "eta")?, index_part(p, "k")?),
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
    let mut keys = ROUGHNESS_KEYS.to_vec();
    keys.extend(["material", "eta", "k", "specular_reflectance"]);
    let surface = match (roughness, eta, k) {
        (Roughness::Constant(ggx), Varying::Constant(eta), Varying::Constant(k)) => {
            Surface::RoughConductor(RoughConductor::new(ggx, eta, k, tint, compensation))
        }
        (roughness, eta, k) => {
            let roughness = match roughness {
                Roughness::Varying(r) => r,
                Roughness::Constant(d) => VaryingRoughness {
                    family: d,
                    alpha_u: Varying::Constant(d.alpha_u()),
                    alpha_v: Some(Varying::Constant(d.alpha_v())),
                },
            };
            let grid = compensation.then(|| Roughness::grid(&roughness, AlbedoTable::conductor));
            Surface::RoughConductorPattern(Box::new(VaryingConductor {
                roughness,
                eta,
                k,
                tint,
                grid,
            }))
        }
    };
    Ok((surface, keys))
}

/// `type = "rough_dielectric"`: `distribution`, `alpha` or `alpha_u` + `alpha_v`; `ior` (> 0, default 1.5);
/// `tint` (a colour in [0, 1] multiplying transmitted light, default 1);
/// `energy_compensation` (default true). Returns the surface and the keys it read.
pub(crate) fn rough_dielectric(
    p: &MaterialParams,
) -> Result<(Surface, Vec<&'static str>), SceneError> {
    let roughness = distribution(p)?;
    let ior = p.f32_where("ior", Some(1.5), "must be > 0", |v| v > 0.0)?;
    let tint = p.rgb_where("tint", Some(Rgb::WHITE), "every channel in [0, 1]", |c| {
        c.min_channel() >= 0.0 && c.max_channel() <= 1.0
    })?;
    let compensation = p.bool("energy_compensation", Some(true))?;
    let mut keys = ROUGHNESS_KEYS.to_vec();
    keys.extend(["ior", "tint"]);
    let surface = match roughness {
        Roughness::Constant(ggx) => {
            Surface::RoughDielectric(RoughDielectric::new(ggx, ior, tint, compensation))
        }
        Roughness::Varying(roughness) => {
            let grid = (compensation && ior != 1.0).then(|| {
                Roughness::grid(&roughness, |d| {
                    [
                        AlbedoTable::dielectric(d, ior),
                        AlbedoTable::dielectric(d, 1.0 / ior),
                    ]
                })
            });
            Surface::RoughDielectricPattern(Box::new(VaryingDielectric {
                roughness,
                eta: ior,
                tint,
                grid,
            }))
        }
    };
    Ok((surface, keys))
}

/// The keys of a `rough_plastic` material besides `interior` and `two_sided`.
pub(crate) const ROUGH_PLASTIC_KEYS: [&str; 8] = [
    "distribution",
    "masking",
    "alpha",
    "diffuse_reflectance",
    "specular_reflectance",
    "int_ior",
    "ext_ior",
    "nonlinear",
];

/// `type = "rough_plastic"`: Mitsuba 3's `roughplastic`. `distribution` (default `"ggx"`),
/// `alpha` (isotropic only, as Mitsuba's; a number or a grey pattern, whose coat tables
/// are interpolated per point from a grid over its bounds), `diffuse_reflectance` (a colour or a pattern in
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
    let alpha = varying_alpha(p, "alpha")?;
    let eta = coat_eta(p)?;
    if eta == 1.0 {
        return Err(p.error(
            Some("int_ior"),
            "int_ior equals ext_ior: an index-matched coat reflects nothing (use `diffuse`)",
        ));
    }
    let specular = specular_reflectance(p)?;
    let nonlinear = p.bool("nonlinear", Some(false))?;
    let diffuse = p.colour_or_pattern("diffuse_reflectance", Rgb::splat(0.5), [0.0, 1.0])?;
    let a = match alpha {
        Varying::Constant(a) => a,
        alpha => {
            let roughness = VaryingRoughness {
                family: family.with(DEFAULT_ALPHA, DEFAULT_ALPHA),
                alpha_u: alpha,
                alpha_v: None,
            };
            let grid = Roughness::grid(&roughness, |d| CoatTables::new(d, eta));
            let diffuse = match diffuse {
                ColourParam::Constant(c) => Varying::Constant(c),
                ColourParam::Pattern(g) => Varying::Pattern(Arc::new(g)),
            };
            return Ok(Surface::RoughPlasticVarying(Box::new(VaryingPlastic {
                roughness,
                eta,
                specular,
                nonlinear,
                grid,
                diffuse,
            })));
        }
    };
    let lobe = RoughPlastic::new(family.with(a, a), eta, specular, nonlinear);
    Ok(match diffuse {
        ColourParam::Constant(diffuse) => Surface::RoughPlastic { lobe, diffuse },
        ColourParam::Pattern(graph) => Surface::RoughPlasticPattern {
            lobe,
            diffuse: Arc::new(graph),
        },
    })
}
