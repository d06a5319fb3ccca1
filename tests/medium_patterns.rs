//! Patterns as heterogeneous-medium coefficients (issue 11): a constant pattern is the
//! constant density, a gradient density gives the closed-form transmittance along a ray
//! (the lookup convention: world `P`), noise densities get majorant grids from interval
//! bounds with no violation, bad patterns are located errors, and the stats show where
//! patterns are evaluated.

mod common;
use common::scratch_dir;

/// The unit ball of medium of [`common::medium_ball_scene`], 16 x 16 pixels.
fn ball(interior: &str, spp: u32, seed: u64) -> String {
    common::medium_ball_scene(interior, 16, spp, seed, 3.0)
}

#[test]
fn a_constant_pattern_density_renders_the_constant_density_image_bit_for_bit() {
    // The same estimator and the same random numbers: one majorant cell holding the same
    // bound (the constant's interval bound is exact), the same density at every point. So
    // the images are compared exactly, for a free-flight estimator and each shadow one.
    let d = scratch_dir("medpat", "constant");
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
    let d = scratch_dir("medpat", "gradient");
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
    let d = scratch_dir("medpat", "noise");
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
    let d = scratch_dir("medpat", "none");
    for interior in [
        r#"{ type = "homogeneous", sigma_t = 2, albedo = 0.5 }"#,
        r#"{ type = "heterogeneous", density = { constant = 2 }, albedo = 0.5 }"#,
    ] {
        let out = common::render_scene_text(&d, &ball(interior, 2, 0));
        assert_eq!(out.stats.counters.pattern_evals, 0, "{interior}");
        assert_eq!(out.stats.counters.pattern_cache_hits, 0, "{interior}");
    }
}

/// Each interior table's keys `case` fail to load with an error holding every needle and
/// the line of the interior table.
fn assert_located_errors(d: &std::path::Path, cases: &[(String, &[&str])]) {
    for (case, needles) in cases {
        let text = ball(&format!("{{ {case} }}"), 1, 0);
        let err = match common::load_scene_text(d, &text) {
            Ok(_) => panic!("{case}: loaded"),
            Err(e) => e.to_string(),
        };
        for n in needles.iter() {
            assert!(err.contains(n), "{case}: `{n}` missing from: {err}");
        }
        assert!(err.contains("scene.toml:16:"), "{case}: no line in {err}");
    }
}

#[test]
fn bad_medium_patterns_are_located_errors() {
    let d = scratch_dir("medpat", "errors");
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
        // A colour density (one per channel) is bounded below in every channel...
        (
            r#"density = { pattern = "multiply", a = { pattern = "noise", frequency = 2 }, b = { pattern = "constant", value = [1, 0.5, 0.2] } }"#,
            &["scene.toml", "density", ">= 0", "remap"][..],
        ),
        // ... and has no one density for a colour emission to follow.
        (
            r#"density = { pattern = "constant", value = [1, 0.5, 0.2] }, emission = [1, 1, 1]"#,
            &["emission", "one density per channel", "pattern"][..],
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
        // An extinction bound no tracker can walk: it would render for ever.
        (
            r#"density = { pattern = "constant", value = 1 }, scale = 1e30"#,
            &["density", "1e30", "at most 1e6", "grid"][..],
        ),
    ];
    let cases =
        cases.map(|(case, needles)| (format!(r#"type = "heterogeneous", {case}"#), needles));
    assert_located_errors(&d, &cases);
    // The same bound for a homogeneous interior's sigma_t pattern.
    assert_located_errors(
        &d,
        &[(
            r#"type = "homogeneous", sigma_t = { pattern = "constant", value = 2e6 }"#.into(),
            &["sigma_t", "2e6", "at most 1e6"][..],
        )],
    );
    // At the bound, a pattern density loads.
    let at_bound = ball(
        r#"{ type = "heterogeneous", density = { pattern = "constant", value = 1 }, scale = 1e6 }"#,
        1,
        0,
    );
    assert!(common::load_scene_text(&d, &at_bound).is_ok());
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
    let d = scratch_dir("medpat", "albedo");
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

/// Asserts two images are equal bit for bit, saying how many pixels differ otherwise.
fn same_image(a: &[risotto::components::Rgb], b: &[risotto::components::Rgb], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}");
    let differ = a.iter().zip(b).filter(|(x, y)| x != y).count();
    assert_eq!(differ, 0, "{what}: {differ} of {} pixels differ", a.len());
}

/// A homogeneous interior of the ball with `rest` (its other keys).
fn homogeneous(rest: &str) -> String {
    format!(r#"{{ type = "homogeneous", {rest} }}"#)
}

/// `albedo` and the HG `g` of a homogeneous medium as patterns: a constant pattern renders
/// the constant's image bit for bit in every scattering mode (the flights run at albedo 1
/// and a power-of-two albedo scales their weights exactly; `g` is read per event), for a
/// grey and a chromatic medium; the heterogeneous medium's `g` likewise.
#[test]
fn constant_albedo_and_g_patterns_render_their_constants_bit_for_bit() {
    let d = scratch_dir("medpat", "constant-scatter");
    let media = [("2", "0.5"), ("[1, 2, 4]", "[0.5, 0.25, 1]")];
    for scattering in ["bounce", "walk", "single"] {
        for (sigma_t, albedo) in media {
            let render = |albedo: &str, g: &str| {
                let interior = homogeneous(&format!(
                    r#"sigma_t = {sigma_t}, albedo = {albedo}, phase = {{ type = "hg", g = {g} }}, scattering = "{scattering}""#
                ));
                common::render_scene_text(&d, &ball(&interior, 4, 7))
            };
            let constant = render(albedo, "0.7");
            assert_eq!(constant.stats.counters.volume_pattern_evals, 0);
            let cases = [
                (
                    format!(r#"{{ pattern = "constant", value = {albedo} }}"#),
                    "0.7".to_string(),
                ),
                (
                    albedo.to_string(),
                    r#"{ pattern = "constant", value = 0.7 }"#.to_string(),
                ),
            ];
            for (a, g) in &cases {
                let pattern = render(a, g);
                let what = format!("{scattering}, sigma_t {sigma_t}, albedo {a}, g {g}");
                same_image(&constant.beauty.pixels, &pattern.beauty.pixels, &what);
                assert!(pattern.stats.counters.volume_pattern_evals > 0, "{what}");
                assert_eq!(pattern.stats.counters.nan_dropped, 0, "{what}");
            }
        }
    }
    let render = |g: &str| {
        let interior = format!(
            r#"{{ type = "heterogeneous", density = {{ constant = 1 }}, scale = 2, albedo = 0.8, phase = {{ type = "hg", g = {g} }} }}"#
        );
        common::render_scene_text(&d, &ball(&interior, 4, 8))
    };
    // Pattern colours are >= 0: a negative g comes from `remap` (exactly -0.5 here).
    let constant = render("-0.5");
    let pattern = render(r#"{ pattern = "remap", a = 0, to = [-0.5, 0.75] }"#);
    same_image(
        &constant.beauty.pixels,
        &pattern.beauty.pixels,
        "heterogeneous g",
    );
    assert!(pattern.stats.counters.volume_pattern_evals > 0);
    assert_eq!(constant.stats.counters.volume_pattern_evals, 0);
}

/// Single scattering is local to each camera ray: seen from the camera on the z axis, the
/// rays of the image's left half stay at x < 0 inside the ball and those of the right half
/// at x > 0. So with an `albedo` or `g` pattern that steps at x = 0, the left half of the
/// image is the left half of the render with the left value everywhere, bit for bit, and
/// the right half that of the right value: the pattern is read at each scattering point,
/// in world space.
#[test]
fn stepped_albedo_and_g_patterns_are_read_at_each_scattering_point() {
    let d = scratch_dir("medpat", "step");
    let step = |a: &str, b: &str| {
        format!(
            r#"{{ pattern = "gradient", axis = "x", from = -1e-4, to = 1e-4, a = {a}, b = {b} }}"#
        )
    };
    let render = |albedo: &str, g: &str| {
        let interior = homogeneous(&format!(
            r#"sigma_t = [1, 2, 4], albedo = {albedo}, phase = {{ type = "hg", g = {g} }}, scattering = "single""#
        ));
        common::render_scene_text(&d, &ball(&interior, 4, 9))
    };
    let halves_match = |stepped: &[risotto::components::Rgb],
                        left: &[risotto::components::Rgb],
                        right: &[risotto::components::Rgb],
                        what: &str| {
        let w = 16;
        let mut differs = 0;
        for (k, px) in stepped.iter().enumerate() {
            let want = if k % w < w / 2 { left[k] } else { right[k] };
            assert!(*px == want, "{what}: pixel {k} is {px:?}, not {want:?}");
            differs += (left[k] != right[k]) as usize;
        }
        // The two values do change the image (the test could fail).
        assert!(
            differs > 50,
            "{what}: only {differs} pixels differ between the halves' media"
        );
    };
    let (left, right) = (render("0.5", "0.3"), render("0.25", "0.3"));
    let stepped = render(&step("0.5", "0.25"), "0.3");
    halves_match(
        &stepped.beauty.pixels,
        &left.beauty.pixels,
        &right.beauty.pixels,
        "albedo",
    );
    // 0 and 1 remapped to exactly -0.5 and 0.75.
    let (left, right) = (render("0.5", "-0.5"), render("0.5", "0.75"));
    let g = format!(
        r#"{{ pattern = "remap", a = {}, to = [-0.5, 0.75] }}"#,
        step("0", "1")
    );
    let stepped = render("0.5", &g);
    halves_match(
        &stepped.beauty.pixels,
        &left.beauty.pixels,
        &right.beauty.pixels,
        "g",
    );
}

/// A homogeneous interior with a pattern `sigma_t` or `emission` is built as a
/// heterogeneous medium: a gradient extinction along the diameter gives the closed-form
/// transmittance (as the heterogeneous density does), and an emission pattern over a
/// constant extinction the closed-form emission of the absorbing, emitting ball,
/// `T + j (1 - T) / sigma_t` with `T = exp(-2 sigma_t)` (environment 1 behind it).
#[test]
fn pattern_extinction_and_emission_make_a_homogeneous_interior_heterogeneous() {
    let d = scratch_dir("medpat", "homogeneous-heterogeneous");
    // sigma_t(P) = 0.75 (z + 1): optical depth 1.5 along the diameter.
    let interior = homogeneous(
        r#"sigma_t = { pattern = "gradient", axis = "z", from = -1, to = 1, a = 0, b = 1.5 }, albedo = 0"#,
    );
    let expected = (-1.5f64).exp();
    let n = 8192;
    let out = common::render_scene_text(&d, &diameter_scene(&interior, n, 11));
    let m = out.beauty.pixels[0].g as f64;
    let se = (expected * (1.0 - expected) / n as f64).sqrt();
    assert!(
        ((m - expected) / se).abs() < 3.0,
        "T {m} vs exp(-1.5) = {expected} (se {se})"
    );
    assert_eq!(out.stats.counters.majorant_violations, 0);
    assert!(out.stats.counters.volume_pattern_evals > 0);
    // Emission j = (0.6, 0.3, 0.9) by a pattern, sigma_t = 1.5, a black environment: means
    // over 8 seeds within 4 standard errors of the closed form j (1 - T) / sigma_t; the
    // constant emission (the homogeneous integrator's exact segment integral) matches it to
    // rounding.
    let sigma = 1.5f64;
    let t = (-2.0 * sigma).exp();
    let want = [0.6f64, 0.3, 0.9].map(|j| j * (1.0 - t) / sigma);
    let dark = |interior: &str, spp: u32, seed: u64| {
        let text = diameter_scene(interior, spp, seed).replace("radiance = 1\n", "radiance = 0\n");
        assert!(text.contains("radiance = 0\n"));
        common::render_scene_text(&d, &text)
    };
    let exact = dark(
        &homogeneous("sigma_t = 1.5, albedo = 0, emission = [0.6, 0.3, 0.9]"),
        4,
        1,
    );
    for (c, w) in exact.beauty.pixels[0].to_array().into_iter().zip(want) {
        assert!(
            (c as f64 - w).abs() < 1e-4 * w,
            "constant emission {c} vs {w}"
        );
    }
    let interior = homogeneous(
        r#"sigma_t = 1.5, albedo = 0, emission = { pattern = "constant", value = [0.6, 0.3, 0.9] }"#,
    );
    let runs: Vec<[f64; 3]> = (0..8)
        .map(|seed| {
            let out = dark(&interior, 512, 100 + seed);
            out.beauty.pixels[0].to_array().map(|c| c as f64)
        })
        .collect();
    for c in 0..3 {
        let mean = runs.iter().map(|r| r[c]).sum::<f64>() / 8.0;
        let var = runs.iter().map(|r| (r[c] - mean).powi(2)).sum::<f64>() / 7.0;
        let se = (var / 8.0).sqrt().max(1e-6);
        assert!(
            ((mean - want[c]) / se).abs() < 4.0,
            "channel {c}: {mean} +- {se} vs {}",
            want[c]
        );
    }
}

#[test]
fn bad_scattering_patterns_are_located_errors() {
    let d = scratch_dir("medpat", "scatter-errors");
    let cases = [
        (
            r#"type = "homogeneous", sigma_t = 1, albedo = { pattern = "checker", space = "uv" }"#,
            &["albedo", "world position P"][..],
        ),
        (
            r#"type = "homogeneous", sigma_t = 1, albedo = { pattern = "gradient", a = 0, b = 2 }"#,
            &["albedo", "[0, 1]", "2"][..],
        ),
        (
            r#"type = "homogeneous", sigma_t = 1, phase = { type = "hg", g = { pattern = "constant", value = 1 } }"#,
            &["phase", "g", "(-1, 1)"][..],
        ),
        (
            r#"type = "homogeneous", sigma_t = 1, phase = { type = "hg", g = { pattern = "constant", value = [0.1, 0.2, 0.3] } }"#,
            &["g", "grey"][..],
        ),
        (
            r#"type = "heterogeneous", density = { constant = 1 }, phase = { type = "double_hg", g1 = { pattern = "constant", value = 0.5 }, g2 = 0.1 }"#,
            &["phase", "`hg`", "double_hg"][..],
        ),
        (
            r#"type = "homogeneous", sigma_a = { pattern = "constant", value = 1 }"#,
            &["sigma_a", "sigma_t"][..],
        ),
        (
            r#"type = "homogeneous", sigma_t = { pattern = "constant", value = 1 }, scattering = "walk""#,
            &["scattering", "walk", "heterogeneous"][..],
        ),
        (
            r#"type = "homogeneous", sigma_t = 1, emission = { grid = "x.vol" }"#,
            &["emission", "heterogeneous"][..],
        ),
    ];
    assert_located_errors(
        &d,
        &cases.map(|(case, needles)| (case.to_string(), needles)),
    );
}
