//! `subsurface` materials whose `albedo` or `mean_free_path` is a pattern (issue 11): read
//! at each ray's entry point, in both modes. A constant pattern renders the constant's image
//! bit for bit, a step in the albedo darkens the side it covers, and bad patterns are
//! located errors.

mod common;
use common::scratch_dir;

use risotto::components::Rgb;

/// The subsurface ball of [`common::medium_ball_scene`] (16 x 16 pixels, sun and sky), its
/// material's keys `keys` one per line after `type` (line 16 on).
fn scene(keys: &[&str], spp: u32, seed: u64) -> String {
    let ball = common::medium_ball_scene("X", 16, spp, seed, 3.0);
    let material = format!("type = \"subsurface\"\n{}", keys.join("\n"));
    let text = ball.replace("type = \"interface\"\ninterior = X", &material);
    assert_ne!(text, ball);
    text
}

/// Asserts two images are equal bit for bit, saying how many pixels differ otherwise.
fn same_image(a: &[Rgb], b: &[Rgb], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}");
    let differ = a.iter().zip(b).filter(|(x, y)| x != y).count();
    assert_eq!(differ, 0, "{what}: {differ} of {} pixels differ", a.len());
}

#[test]
fn constant_patterns_render_the_constant_parameters_bit_for_bit() {
    let d = scratch_dir("sss-pattern", "constant");
    for mode in ["random_walk", "diffusion"] {
        let render = |albedo: &str, mfp: &str| {
            let keys = [
                format!(r#"mode = "{mode}""#),
                "unit_length = 0.1".to_string(),
                format!("albedo = {albedo}"),
                format!("mean_free_path = {mfp}"),
            ];
            let keys: Vec<&str> = keys.iter().map(String::as_str).collect();
            common::render_scene_text(&d, &scene(&keys, 4, 3))
        };
        let constant = render("[0.8, 0.5, 0.3]", "[1, 0.5, 0.25]");
        assert_eq!(constant.stats.counters.volume_pattern_evals, 0, "{mode}");
        for (albedo, mfp) in [
            (
                r#"{ pattern = "constant", value = [0.8, 0.5, 0.3] }"#,
                "[1, 0.5, 0.25]",
            ),
            (
                "[0.8, 0.5, 0.3]",
                r#"{ pattern = "constant", value = [1, 0.5, 0.25] }"#,
            ),
        ] {
            let pattern = render(albedo, mfp);
            let what = format!("{mode}: albedo {albedo}, mean_free_path {mfp}");
            same_image(&constant.beauty.pixels, &pattern.beauty.pixels, &what);
            assert!(pattern.stats.counters.volume_pattern_evals > 0, "{what}");
            assert_eq!(pattern.stats.counters.nan_dropped, 0, "{what}");
        }
    }
}

/// Mean of the left and of the right half of a 16-pixel-wide image (channel average).
fn halves(px: &[Rgb]) -> (f64, f64) {
    let (mut l, mut r) = (0.0, 0.0);
    for (k, p) in px.iter().enumerate() {
        if k % 16 < 8 {
            l += p.average() as f64;
        } else {
            r += p.average() as f64;
        }
    }
    (l / 128.0, r / 128.0)
}

#[test]
fn a_stepped_albedo_is_read_where_light_enters() {
    // Albedo 0.9 on the ball's left half (x < 0), 0.2 on its right, mean free path 0.05 of
    // a ball of radius 1 (walks stay near where they enter): the left half of the image is
    // as bright as the constant 0.9 ball's left half and the right as the 0.2 ball's, within
    // a tolerance far below the difference between the two.
    let d = scratch_dir("sss-pattern", "step");
    for mode in ["random_walk", "diffusion"] {
        let render = |albedo: &str| {
            let keys = [
                format!(r#"mode = "{mode}""#),
                "unit_length = 0.1".to_string(),
                format!("albedo = {albedo}"),
                "mean_free_path = 0.5".to_string(),
            ];
            let keys: Vec<&str> = keys.iter().map(String::as_str).collect();
            common::render_scene_text(&d, &scene(&keys, 64, 4))
        };
        let bright = halves(&render("0.9").beauty.pixels);
        let dark = halves(&render("0.2").beauty.pixels);
        let step =
            r#"{ pattern = "gradient", axis = "x", from = -1e-3, to = 1e-3, a = 0.9, b = 0.2 }"#;
        let stepped = halves(&render(step).beauty.pixels);
        let gap = bright.0 - dark.0;
        assert!(gap > 0.05, "{mode}: bright {bright:?} vs dark {dark:?}");
        assert!(
            (stepped.0 - bright.0).abs() < 0.1 * gap,
            "{mode}: left {} vs {}",
            stepped.0,
            bright.0
        );
        assert!(
            (stepped.1 - dark.1).abs() < 0.1 * gap,
            "{mode}: right {} vs {}",
            stepped.1,
            dark.1
        );
    }
}

#[test]
fn bad_subsurface_patterns_are_located_errors() {
    let d = scratch_dir("sss-pattern", "errors");
    let cases: [(&str, &[&str]); 3] = [
        (
            r#"albedo = { pattern = "checker", space = "uv" }"#,
            &["albedo", "world position P"],
        ),
        (
            r#"mean_free_path = { pattern = "gradient", a = 0, b = 1 }"#,
            &["mean_free_path", "> 0"],
        ),
        (
            r#"albedo = { pattern = "gradient", a = 0, b = 3 }"#,
            &["albedo", "[0, 1]"],
        ),
    ];
    for (keys, needles) in cases {
        let err = match common::load_scene_text(&d, &scene(&[keys], 1, 0)) {
            Ok(_) => panic!("{keys}: loaded"),
            Err(e) => e.to_string(),
        };
        for n in needles {
            assert!(err.contains(n), "{keys}: `{n}` missing from: {err}");
        }
        assert!(err.contains("scene.toml:16:"), "{keys}: no line in {err}");
    }
}
