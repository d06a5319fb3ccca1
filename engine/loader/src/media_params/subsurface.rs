//! Reading a `type = "subsurface"` material.

use crate::scene_file::{ColourParam, MaterialParams, SceneError};
use glam::Vec3;
use risotto_builtins::subsurface::*;
use risotto_components::Rgb;
use risotto_engine::plugin::BxdfFactory;
use risotto_systems::pattern::{self, PatternGraph};
use std::sync::Arc;

/// Reads a `type = "subsurface"` material (keys and defaults in `docs/scene-format.md`);
/// `albedo` and `mean_free_path` must be constants here ([`parse_with_patterns`] takes
/// patterns too).
pub fn parse(p: &MaterialParams) -> Result<SubsurfaceParams, SceneError> {
    let (params, patterns) = parse_with_patterns(p)?;
    for (key, pattern) in [
        ("albedo", patterns.albedo.is_some()),
        ("mean_free_path", patterns.mean_free_path.is_some()),
    ] {
        if pattern {
            return Err(p.error(Some(key), "a pattern is not taken here: give a colour"));
        }
    }
    Ok(params)
}

/// Reads a `type = "subsurface"` material whose `albedo` and `mean_free_path` may be
/// patterns of `P` (the constants then hold the defaults, used by no ray).
pub fn parse_with_patterns(
    p: &MaterialParams,
) -> Result<(SubsurfaceParams, SubsurfacePatterns), SceneError> {
    p.deny_unknown(&[
        "ior",
        "albedo",
        "mean_free_path",
        "unit_length",
        "g",
        "mode",
    ])?;
    let positive_finite = |v: f32| v > 0.0 && v.is_finite();
    let ior = p.f32_where("ior", Some(1.4), "must be > 0 and finite", positive_finite)?;
    let mut patterns = SubsurfacePatterns::default();
    let albedo = match p.colour_or_pattern("albedo", Rgb::splat(0.8), [0.0, 1.0])? {
        ColourParam::Constant(c) => c,
        ColourParam::Pattern(g) => {
            patterns.albedo = Some(Arc::new(world_p_only(p, "albedo", g)?));
            Rgb::splat(0.8)
        }
    };
    let mean_free_path = if p.is_table("mean_free_path") {
        let g = world_p_only(
            p,
            "mean_free_path",
            p.pattern("mean_free_path")?.expect("a table"),
        )?;
        let (lo, hi) = pattern::bounds(&g, Vec3::NEG_INFINITY, Vec3::INFINITY);
        // NaN reads as out of range.
        if !(lo.min_channel() > 0.0 && hi.is_finite()) {
            return Err(p.error(
                Some("mean_free_path"),
                format!(
                    "the pattern must keep every channel > 0 and finite, but its values may \
                     reach [{}, {}, {}] .. [{}, {}, {}] (interval bounds over all of space): \
                     wrap it in `remap` with a positive range",
                    lo.r, lo.g, lo.b, hi.r, hi.g, hi.b
                ),
            ));
        }
        patterns.mean_free_path = Some(Arc::new(g));
        // The smallest mean free path the pattern reaches decides the overflow check.
        lo
    } else {
        p.rgb_where(
            "mean_free_path",
            Some(Rgb::splat(1.0)),
            "every channel > 0 and finite",
            |c| c.min_channel() > 0.0 && c.is_finite(),
        )?
    };
    let unit_length = p.f32_where(
        "unit_length",
        Some(1.0),
        "must be > 0 and finite",
        positive_finite,
    )?;
    let g = p.f32_where("g", Some(0.0), "must be in (-1, 1)", |g| g.abs() < 1.0)?;
    let sigma_t = mean_free_path.map(|l| 1.0 / (l * unit_length));
    if !sigma_t.is_finite() {
        return Err(p.error(
            Some("mean_free_path"),
            format!(
                "mean_free_path {mean_free_path:?} times unit_length {unit_length} is too \
                 small: 1 / (mean_free_path * unit_length) overflows"
            ),
        ));
    }
    let mode = match p.string("mode", Some("random_walk"))?.as_str() {
        "random_walk" => SubsurfaceMode::RandomWalk,
        "diffusion" => SubsurfaceMode::Diffusion,
        other => {
            return Err(p.error(
                Some("mode"),
                format!("unknown mode \"{other}\" (known: random_walk, diffusion)"),
            ))
        }
    };
    let params = SubsurfaceParams {
        ior,
        albedo,
        mean_free_path,
        unit_length,
        g,
        mode,
    };
    Ok((params, patterns))
}

/// `graph` if it reads `P` only, else an error at `key`.
fn world_p_only(
    p: &MaterialParams,
    key: &str,
    graph: PatternGraph,
) -> Result<PatternGraph, SceneError> {
    if graph.reads_uv() {
        return Err(p.error(
            Some(key),
            "a subsurface pattern is read at the entry point's world position P only (u and \
             v belong to surfaces)",
        ));
    }
    Ok(graph)
}

/// The registry's constructor for `type = "subsurface"`.
pub fn construct(p: &MaterialParams) -> Result<Box<dyn BxdfFactory>, SceneError> {
    let (params, patterns) = parse_with_patterns(p)?;
    Ok(Box::new(params.material_with(patterns)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_file::load_scene;
    use std::path::{Path, PathBuf};

    /// Every `.toml` file below `dir`.
    fn scene_files(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                scene_files(&path, out);
            } else if path.extension().is_some_and(|e| e == "toml") {
                out.push(path);
            }
        }
    }

    #[test]
    fn every_shipped_subsurface_material_parses() {
        let mut files = Vec::new();
        scene_files(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes"),
            &mut files,
        );
        let mut parsed = 0;
        for file in &files {
            let desc = load_scene(file).unwrap();
            for m in desc
                .materials
                .iter()
                .filter(|m| m.type_name == "subsurface")
            {
                parse_with_patterns(&m.params)
                    .unwrap_or_else(|e| panic!("{}: {e}", file.display()));
                parsed += 1;
            }
        }
        assert!(
            parsed > 0,
            "no subsurface material among {} scenes",
            files.len()
        );
    }
}
