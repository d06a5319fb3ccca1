//! Patterns as heterogeneous-medium coefficients (issue 11): a constant pattern is the
//! constant density, a gradient density gives the closed-form transmittance along a ray
//! (the lookup convention: world `P`), noise densities get majorant grids from interval
//! bounds with no violation, bad patterns are located errors, and the stats show where
//! patterns are evaluated.

mod common;

use std::path::PathBuf;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("risotto-medpat-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The unit ball of medium of [`common::medium_ball_scene`], 16 x 16 pixels.
fn ball(interior: &str, spp: u32, seed: u64) -> String {
    common::medium_ball_scene(interior, 16, spp, seed, 3.0)
}

#[test]
fn a_constant_pattern_density_renders_the_constant_density_image_bit_for_bit() {
    // The same estimator and the same random numbers: one majorant cell holding the same
    // bound (the constant's interval bound is exact), the same density at every point. So
    // the images are compared exactly, for a free-flight estimator and each shadow one.
    let d = dir("constant");
    for tracking in ["ratio", "residual", "delta"] {
        let rest =
            format!(r#"scale = 2, albedo = 0.8, tracking = "{tracking}", majorant_grid = 1"#);
        let grid = common::render_scene_text(
            &d,
            &ball(
                &format!(
                    r#"{{ type = "heterogeneous", density = {{ constant = 0.75 }}, {rest} }}"#
                ),
                4,
                3,
            ),
        );
        let pattern = common::render_scene_text(
            &d,
            &ball(
                &format!(
                    r#"{{ type = "heterogeneous", density = {{ pattern = "constant", value = 0.75 }}, {rest} }}"#
                ),
                4,
                3,
            ),
        );
        assert_eq!(grid.beauty.pixels, pattern.beauty.pixels, "{tracking}");
        assert_eq!(pattern.stats.counters.majorant_violations, 0);
        // The grid medium evaluates no pattern; the pattern medium one per tentative
        // collision it looks up.
        assert_eq!(grid.stats.counters.pattern_evals, 0, "{tracking}");
        assert!(pattern.stats.counters.pattern_evals > 0, "{tracking}");
    }
}

/// A camera of a 1-pixel image looking down the ball's z axis (a 0.01 degree field: every
/// ray crosses the ball along its diameter within 1e-4), an environment of 1, no sun,
/// albedo 0: each sample is the transmittance estimate of the diameter.
fn diameter_scene(interior: &str, spp: u32, seed: u64) -> String {
    let text = common::medium_ball_scene(interior, 1, spp, seed, 0.0)
        .replace("fov = 40", "fov = 0.01")
        .replace("radiance = 0.5", "radiance = 1");
    assert!(text.contains("fov = 0.01") && text.contains("radiance = 1\n"));
    text
}

#[test]
fn a_gradient_density_along_the_ray_gives_the_closed_form_transmittance() {
    // density(P) = P.z + 1 on the ball (a gradient along world z from -1 to 1, 0 to 2),
    // scale 0.75: the diameter's optical depth is 0.75 int_{-1}^{1} (z + 1) dz = 1.5, so
    // T = exp(-1.5). Had the pattern seen the unit-cube coordinates of the shape's bounds
    // instead of world P, the depth would be 0.75 * 2 * int_0^1 (w + 1) dw = 2.25.
    // Camera rays take delta-tracking free flights (albedo 0: a collision ends the path);
    // the mean of 0/1 estimates within 3 standard errors, for two seeds and majorant grids
    // of 1 and 8 cells per axis.
    let d = dir("gradient");
    let expected = (-1.5f64).exp();
    for (seed, cells) in [(5, 8), (6, 1)] {
        let interior = format!(
            r#"{{ type = "heterogeneous", density = {{ pattern = "gradient", axis = "z", from = -1, to = 1, a = 0, b = 2 }}, scale = 0.75, albedo = 0, majorant_grid = {cells} }}"#
        );
        let n = 8192;
        let out = common::render_scene_text(&d, &diameter_scene(&interior, n, seed));
        let m = out.beauty.pixels[0].g as f64;
        let se = (expected * (1.0 - expected) / n as f64).sqrt();
        let z = (m - expected) / se;
        eprintln!("{cells} cells: T {m:.5} vs {expected:.5} (z {z:.2})");
        assert!(
            z.abs() < 3.0,
            "{cells} cells: {m} vs exp(-1.5) = {expected} (z {z:.2})"
        );
        assert_eq!(out.stats.counters.majorant_violations, 0);
    }
}

#[test]
fn noise_densities_track_against_pattern_bounds_without_violations() {
    // An fBm cloud (remapped to [0, 1], clamped), a pattern emission, every tracking: the
    // majorant grid from the graph's interval bounds (Lipschitz noise bounds per cell) holds
    // at every sampled point.
    let d = dir("noise");
    let density = r#"density = { pattern = "remap", a = { pattern = "noise", frequency = 2.5, octaves = 5, seed = 3 }, from = [-0.4, 0.6], to = [0, 1] }"#;
    for tracking in [
        "ratio",
        "residual",
        "delta",
        "ray_marching",
        "unbiased_ray_marching",
    ] {
        for emission in [
            "",
            r#", emission = { pattern = "gradient", axis = "y", from = -1, to = 1, a = [0, 0, 0], b = [2, 1, 0.5] }"#,
        ] {
            let interior = format!(
                r#"{{ type = "heterogeneous", {density}, scale = 6, albedo = 0.9, tracking = "{tracking}"{emission} }}"#
            );
            let out = common::render_scene_text(&d, &ball(&interior, 4, 1));
            let c = &out.stats.counters;
            assert_eq!(c.majorant_violations, 0, "{tracking} {emission}");
            assert!(c.pattern_evals > 0);
            // Every evaluation here is the medium's (no surface pattern in the scene).
            assert_eq!(
                c.volume_pattern_evals, c.pattern_evals,
                "{tracking} {emission}"
            );
            assert_eq!(c.nan_dropped, 0);
            assert!(out.beauty.pixels.iter().all(|p| p.is_finite()));
        }
    }
}

#[test]
fn media_without_patterns_evaluate_none() {
    // A homogeneous medium and a grid medium (no surface pattern either): the stats count no
    // pattern evaluation, and only a pattern density evaluates in a volume.
    let d = dir("none");
    for interior in [
        r#"{ type = "homogeneous", sigma_t = 2, albedo = 0.5 }"#,
        r#"{ type = "heterogeneous", density = { constant = 2 }, albedo = 0.5 }"#,
    ] {
        let out = common::render_scene_text(&d, &ball(interior, 2, 0));
        assert_eq!(out.stats.counters.pattern_evals, 0, "{interior}");
        assert_eq!(out.stats.counters.pattern_cache_hits, 0, "{interior}");
    }
}

#[test]
fn bad_medium_patterns_are_located_errors() {
    let d = dir("errors");
    let cases = [
        // Raw noise is signed.
        (
            r#"density = { pattern = "noise", frequency = 2 }"#,
            &["scene.toml", "density", "-2.8125", ">= 0"][..],
        ),
        // An upper bound that overflows.
        (
            r#"density = { pattern = "scale", a = 10, factor = 3e38 }"#,
            &["density", "inf", "finite"][..],
        ),
        // Colour densities are refused.
        (
            r#"density = { pattern = "constant", value = [1, 0.5, 0.2] }"#,
            &["density", "grey", "scale = [r, g, b]"][..],
        ),
        // u and v do not exist inside a medium.
        (
            r#"density = { pattern = "checker", space = "uv" }"#,
            &["density", "world position P"][..],
        ),
        // Emission below 0.
        (
            r#"density = { constant = 1 }, emission = { pattern = "gradient", a = -1, b = 1 }"#,
            &["emission", "-1"][..],
        ),
        // A bad node parameter inside the table.
        (
            r#"density = { pattern = "noise", octaves = 0 }"#,
            &["octaves", "0"][..],
        ),
    ];
    for (case, needles) in cases {
        let text = ball(&format!(r#"{{ type = "heterogeneous", {case} }}"#), 1, 0);
        let err = match common::load_scene_text(&d, &text) {
            Ok(_) => panic!("{case}: loaded"),
            Err(e) => e.to_string(),
        };
        for n in needles {
            assert!(err.contains(n), "{case}: `{n}` missing from: {err}");
        }
        // The line of the interior table.
        assert!(err.contains("scene.toml:16:"), "{case}: no line in {err}");
    }
}

#[test]
fn the_noise_cloud_scene_has_no_majorant_violation() {
    // scenes/noise-cloud.toml at a small size: every tentative collision's density is within
    // its cell's pattern bound, and the volume evaluates its pattern.
    let scenes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let text = std::fs::read_to_string(scenes.join("noise-cloud.toml")).unwrap();
    let small = text
        .replace("width = 160", "width = 40")
        .replace("height = 108", "height = 27")
        .replace("spp = 8", "spp = 2");
    assert_ne!(small, text);
    let out = common::render_scene_text(&scenes, &small);
    let c = &out.stats.counters;
    assert_eq!(c.majorant_violations, 0);
    assert!(c.pattern_evals > 0);
    assert_eq!(c.nan_dropped, 0);
    let json = serde_json::to_value(&out.stats).unwrap();
    assert_eq!(json["majorant_violations"], 0, "{json}");
}

/// `albedo = { pattern = .. }`: a constant pattern renders the constant albedo bit for bit
/// (grey and chromatic media), and a gradient along x makes one half of the ball darker and
/// the reversed gradient the other: the albedo is read at the scattering points' world P.
#[test]
fn an_albedo_pattern_is_read_at_each_scattering_point() {
    let d = dir("albedo");
    let render = |albedo: &str, scale: &str| {
        let interior = format!(
            r#"{{ type = "heterogeneous", density = {{ constant = 1 }}, scale = {scale}, albedo = {albedo} }}"#
        );
        common::render_scene_text(&d, &ball(&interior, 8, 5))
    };
    for scale in ["2", "[1, 2, 4]"] {
        let constant = render("[0.8, 0.5, 0.3]", scale);
        let pattern = render(
            r#"{ pattern = "constant", value = [0.8, 0.5, 0.3] }"#,
            scale,
        );
        assert_eq!(
            constant.beauty.pixels, pattern.beauty.pixels,
            "scale {scale}"
        );
        let c = &pattern.stats.counters;
        assert!(c.volume_pattern_evals > 0, "scale {scale}");
        assert_eq!(constant.stats.counters.volume_pattern_evals, 0);
    }
    // Mean of the left minus the right half of the 16-pixel-wide image.
    let halves = |img: &risotto::engine::output::Image| {
        let (w, h) = (img.width, img.height);
        let (mut left, mut right) = (0.0f64, 0.0f64);
        for y in 0..h {
            for x in 0..w {
                let v = img.pixels[y * w + x].average() as f64;
                if x < w / 2 {
                    left += v;
                } else {
                    right += v;
                }
            }
        }
        (left - right) / (w * h / 2) as f64
    };
    let up = halves(
        &render(
            r#"{ pattern = "gradient", axis = "x", from = -1, to = 1, a = 0, b = 1 }"#,
            "2",
        )
        .beauty,
    );
    let down = halves(
        &render(
            r#"{ pattern = "gradient", axis = "x", from = -1, to = 1, a = 1, b = 0 }"#,
            "2",
        )
        .beauty,
    );
    assert!(
        up * down < 0.0 && up.abs() > 0.01 && down.abs() > 0.01,
        "left - right: {up} and {down}"
    );
}
