//! Medium coefficients given as patterns (`albedo`, the `g` of an `hg` phase function):
//! reading and checking them ([`crate::media_params`]; what they do at the scattering points
//! is the built-ins' `scatter_patterns`).

use crate::scene_file::{ColourParam, MaterialParams, SceneError};
use glam::Vec3;
use risotto_components::Rgb;
use risotto_systems::pattern::{self, PatternGraph};
use risotto_systems::phase::{PhaseFunction, PhaseFunctionError};
use std::sync::Arc;

/// The error for a medium pattern that reads `u` / `v`.
const WORLD_P_ONLY: &str =
    "a medium's pattern sees the world position P only (u and v belong to surfaces)";

/// Reads a medium's `albedo` key: a colour in `[0, 1]` (default 1), or a pattern of `P`
/// bounded in `[0, 1]`. Returns the constant albedo (1 with a pattern, which then gives it)
/// and the pattern.
pub(crate) fn parse_albedo(
    t: &MaterialParams,
) -> Result<(Rgb, Option<Arc<PatternGraph>>), SceneError> {
    match t.colour_or_pattern("albedo", Rgb::WHITE, [0.0, 1.0])? {
        ColourParam::Constant(c) => Ok((c, None)),
        ColourParam::Pattern(g) if g.reads_uv() => Err(t.error(Some("albedo"), WORLD_P_ONLY)),
        ColourParam::Pattern(g) => Ok((Rgb::WHITE, Some(Arc::new(g)))),
    }
}

/// Reads a medium's `phase` key (absent: isotropic). `g` of an `hg` phase may be a grey
/// pattern of `P` whose interval bounds lie in `(-1, 1)`: the phase function is then
/// Henyey-Greenstein with `g` read per scattering point: the returned function is HG with
/// `g = 0`, a placeholder no point uses, and the pattern is returned beside it.
pub(crate) fn parse_phase(
    t: &MaterialParams,
) -> Result<(PhaseFunction, Option<Arc<PatternGraph>>), SceneError> {
    let Some(p) = t.table("phase")? else {
        return Ok((PhaseFunction::Isotropic, None));
    };
    if !p.is_table("g") {
        if p.is_table("g1") || p.is_table("g2") || p.is_table("blend") {
            return Err(p.error(
                None,
                "a pattern is taken for the `g` of an `hg` phase function only; `double_hg` \
                 takes numbers",
            ));
        }
        return Ok((phase_function(&p)?, None));
    }
    let kind = p.string("type", None)?;
    if kind != "hg" {
        return Err(p.error(
            Some("g"),
            format!("a pattern `g` belongs to `type = \"hg\"`, not \"{kind}\""),
        ));
    }
    p.deny_unknown(&["type", "g"])?;
    let graph = p.pattern("g")?.expect("checked: a table");
    if graph.reads_uv() {
        return Err(p.error(Some("g"), WORLD_P_ONLY));
    }
    if !graph.is_grey() {
        return Err(p.error(
            Some("g"),
            "a `g` pattern must be grey (every colour in it a single number): g is one mean \
             cosine per point",
        ));
    }
    let (lo, hi) = pattern::bounds(&graph, Vec3::NEG_INFINITY, Vec3::INFINITY);
    // NaN reads as out of range.
    if !(lo.r > -1.0 && hi.r < 1.0) {
        return Err(p.error(
            Some("g"),
            format!(
                "the `g` pattern may reach [{}, {}] (interval bounds over all of space), but g \
                 must lie in (-1, 1): wrap it in `remap` (e.g. to = [-0.9, 0.9])",
                lo.r, hi.r
            ),
        ));
    }
    Ok((
        PhaseFunction::HenyeyGreenstein { g: 0.0 },
        Some(Arc::new(graph)),
    ))
}

/// `phase = { type = "isotropic" | "hg" | "double_hg", ... }`.
pub fn phase_function(p: &MaterialParams) -> Result<PhaseFunction, SceneError> {
    let kind = p.string("type", None)?;
    let checked = |r: Result<PhaseFunction, PhaseFunctionError>| {
        r.map_err(|e| p.error(Some(e.parameter), e.to_string()))
    };
    match kind.as_str() {
        "isotropic" => {
            p.deny_unknown(&["type"])?;
            Ok(PhaseFunction::Isotropic)
        }
        "hg" => {
            p.deny_unknown(&["type", "g"])?;
            checked(PhaseFunction::henyey_greenstein(p.f32("g", Some(0.0))?))
        }
        "double_hg" => {
            p.deny_unknown(&["type", "g1", "g2", "blend"])?;
            checked(PhaseFunction::double_henyey_greenstein(
                p.f32("g1", None)?,
                p.f32("g2", None)?,
                p.f32("blend", Some(0.5))?,
            ))
        }
        other => Err(p.error(
            Some("type"),
            format!("unknown phase function \"{other}\" (known: isotropic, hg, double_hg)"),
        )),
    }
}
