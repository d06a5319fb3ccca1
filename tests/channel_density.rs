//! Colour-varying density (issue 32): a heterogeneous medium whose grid has 3 channels,
//! `sigma_t,c = scale_c density_c`, tracked by the per-channel spectral estimators against
//! one grey majorant (`risotto_systems::spectral_tracking`, `PerChannel`). Checked against
//! what is not itself: Beer-Lambert's closed form through an absorbing slab, the homogeneous
//! medium of the same per-channel extinction (its own exact transmittance and free flights),
//! and located errors for bad files and keys. The spatially varying case is compared with
//! Mitsuba 3 in `tests/mitsuba_reference.rs`. A colour density **pattern** is the same per
//! point: checked against Beer-Lambert (constant and linear) and against its grey pattern
//! under a colour scale (the chromatic-scale estimators).

mod common;

use common::scratch_dir;
use risotto::engine::render::{render, RenderOptions, RenderOutput};
use risotto::loader::load::{scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::parse_scene;
use std::path::Path;

/// Writes a Mitsuba `.vol` of `dims` voxels with `channels` values per voxel, voxel `i`'s
/// values `value(i)` (only the first `channels` used).
fn write_vol(path: &Path, dims: [i32; 3], channels: i32, value: impl Fn(usize) -> [f32; 3]) {
    let mut b = b"VOL\x03".to_vec();
    for v in [1, dims[0], dims[1], dims[2], channels] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for i in 0..dims.iter().product::<i32>() as usize {
        for v in &value(i)[..channels as usize] {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    std::fs::write(path, b).unwrap();
}

fn render_text(dir: &Path, text: &str) -> RenderOutput {
    let desc = parse_scene(text, &dir.join("scene.toml")).unwrap();
    let scene = scene_from_desc(desc, &MaterialRegistry::with_builtins())
        .unwrap()
        .compile()
        .unwrap();
    render(&scene, &RenderOptions::default(), &|_| {}).unwrap()
}

/// Per channel: the image mean and its standard error (from the film's variances).
fn channel_means(out: &RenderOutput) -> [(f64, f64); 3] {
    let n = out.beauty.pixels.len() as f64;
    [0, 1, 2].map(|c| {
        let at = |img: &[risotto_components::Rgb]| {
            img.iter().map(|p| p.to_array()[c] as f64).sum::<f64>()
        };
        let m = at(&out.beauty.pixels) / n;
        let v = at(&out.variance.pixels) / (n * n);
        (m, v.sqrt())
    })
}

/// Every channel's image mean is `exp(-2 sigma_t)` (the slab's transmittance) within 3
/// standard errors, converged to 6 %, with no non-finite sample.
fn assert_transmits(label: &str, out: &RenderOutput, sigma: [f64; 3]) {
    let means = channel_means(out);
    for c in 0..3 {
        let exact: f64 = (-2.0 * sigma[c]).exp();
        let (m, se) = means[c];
        eprintln!("{label}, channel {c}: {m:.5} +- {se:.5} vs {exact:.5}");
        assert!(
            (m - exact).abs() < 3.0 * se.max(1e-4),
            "{label}, channel {c}: {m} +- {se} vs exp(-2 sigma_t) = {exact}"
        );
        assert!(se < 0.06 * exact, "converged enough to test: {se}");
    }
    assert_eq!(out.stats.counters.nan_dropped, 0);
}

/// The five transmittance estimators a heterogeneous medium's `tracking` names.
const TRACKINGS: [&str; 5] = [
    "ratio",
    "residual",
    "delta",
    "ray_marching",
    "unbiased_ray_marching",
];

/// `out`'s channel means agree with `reference`'s within 3 combined standard errors (the
/// reference converged to 2 %), with no non-finite sample and no majorant violated.
fn assert_agrees(label: &str, reference: &[(f64, f64); 3], out: &RenderOutput) {
    let means = channel_means(out);
    for c in 0..3 {
        let ((m0, s0), (m1, s1)) = (reference[c], means[c]);
        let z = (m1 - m0) / (s0 * s0 + s1 * s1).sqrt();
        eprintln!("{label}, channel {c}: {m1:.5} +- {s1:.5} vs {m0:.5} +- {s0:.5}, z {z:.2}");
        assert!(
            z.abs() < 3.0,
            "{label}, channel {c}: {m1} +- {s1} vs {m0} +- {s0}"
        );
        assert!(s0 < 0.02 * m0, "converged enough to test: {m0} +- {s0}");
    }
    assert_eq!(out.stats.counters.nan_dropped, 0, "{label}");
    assert_eq!(out.stats.counters.majorant_violations, 0, "{label}");
}

/// The absorbing cube `[-1, 1]^3` (index-matched, albedo 0) seen along z by a 16 x 16
/// orthographic camera narrower than the cube, in front of a white environment: every
/// pixel is the transmittance through 2 world units, `exp(-2 sigma_t)` per channel.
fn slab_scene(interior: &str, spp: u32, seed: u64) -> String {
    format!(
        r#"
[render]
width = 16
height = 16
spp = {spp}
max_depth = -1
seed = {seed}

[camera]
projection = "orthographic"
width = 1.5
from = [0, 0, 4]
to = [0, 0, 0]

[materials.medium]
type = "interface"
interior = {interior}

[[shapes]]
name = "slab"
type = "box"
material = "medium"

[[lights]]
type = "environment"
radiance = 1
"#
    )
}

#[test]
fn three_channel_grids_transmit_beer_lamberts_closed_form() {
    // (a) three equal channels of 0.5, scale 2: sigma_t = 1, T = exp(-2) in every channel;
    // (b) channels (0.25, 0.5, 1), scale 2: sigma_t = (0.5, 1, 2); and channels
    // (0.25, 1, 4) under a colour scale (2, 1, 0.5): the same sigma_t by another split.
    // 8^3 voxels through 4^3 majorant cells (the DDA crosses cells). Channel means within
    // 3 standard errors of the closed form.
    let d = scratch_dir("channels", "slab");
    write_vol(&d.join("grey.vol"), [8, 8, 8], 3, |_| [0.5; 3]);
    write_vol(&d.join("rgb.vol"), [8, 8, 8], 3, |_| [0.25, 0.5, 1.0]);
    write_vol(&d.join("split.vol"), [8, 8, 8], 3, |_| [0.25, 1.0, 4.0]);
    let cases = [
        (r#"grid = "grey.vol" }, scale = 2"#, [1.0f64, 1.0, 1.0]),
        (r#"grid = "rgb.vol" }, scale = 2"#, [0.5, 1.0, 2.0]),
        (
            r#"grid = "split.vol" }, scale = [2, 1, 0.5]"#,
            [0.5, 1.0, 2.0],
        ),
    ];
    for (k, (density, sigma)) in cases.iter().enumerate() {
        let interior = format!(
            r#"{{ type = "heterogeneous", density = {{ {density}, albedo = 0, majorant_grid = 4 }}"#
        );
        let out = render_text(&d, &slab_scene(&interior, 128, 1 + k as u64));
        assert_transmits(density, &out, *sigma);
    }
}

#[test]
fn a_constant_three_channel_grid_renders_the_homogeneous_colour_medium() {
    // A scattering ball (albedo (0.9, 0.8, 0.6), HG 0.3) lit by a sun through the medium
    // (shadow rays: every transmittance estimator) and an environment: the 3-channel grid
    // (0.5, 1, 2) x scale 2 against the homogeneous sigma_t = (1, 2, 4). Channel means
    // within 3 combined standard errors.
    let d = scratch_dir("channels", "homogeneous");
    write_vol(&d.join("rgb.vol"), [8, 8, 8], 3, |_| [0.5, 1.0, 2.0]);
    let common = r#"albedo = [0.9, 0.8, 0.6], phase = { type = "hg", g = 0.3 }"#;
    let scene = |interior: &str, seed| common::medium_ball_scene(interior, 16, 64, seed, 3.0);
    let homogeneous = render_text(
        &d,
        &scene(
            &format!(r#"{{ type = "homogeneous", sigma_t = [1, 2, 4], {common} }}"#),
            1,
        ),
    );
    let reference = channel_means(&homogeneous);
    for (k, tracking) in TRACKINGS.iter().enumerate() {
        let interior = format!(
            r#"{{ type = "heterogeneous", density = {{ grid = "rgb.vol" }}, scale = 2, majorant_grid = 4, tracking = "{tracking}", {common} }}"#
        );
        let out = render_text(&d, &scene(&interior, 2 + k as u64));
        assert_agrees(tracking, &reference, &out);
    }
}

#[test]
fn colour_density_patterns_transmit_beer_lamberts_closed_form() {
    // A colour pattern as the density is a density per channel, `sigma_t,c = scale_c P_c`:
    // (a) a constant (0.5, 1, 2); (b) a constant (0.25, 1, 4) under a colour scale
    // (2, 1, 0.5), the same sigma_t by another split (the majorants' channel weights);
    // (c) a gradient along the view axis z from (0.25, 0.5, 1) at z = -1 to (0.75, 1.5, 3)
    // at z = 1, whose integral through the slab is 2 x its mean (0.5, 1, 2): the same
    // closed form, spatially varying across the 4^3 majorant cells. Channel means within 3
    // standard errors of `exp(-2 sigma_t)`, and no majorant violated.
    let d = scratch_dir("channels", "pattern-slab");
    // (d) the homogeneous interior's `sigma_t` as a colour pattern (built as (a)).
    let cases = [
        r#"type = "heterogeneous", density = { pattern = "constant", value = [0.5, 1, 2] }"#,
        r#"type = "heterogeneous", density = { pattern = "constant", value = [0.25, 1, 4] }, scale = [2, 1, 0.5]"#,
        r#"type = "heterogeneous", density = { pattern = "gradient", axis = "z", from = -1, to = 1, a = [0.25, 0.5, 1], b = [0.75, 1.5, 3] }, majorant_grid = 4"#,
        r#"type = "homogeneous", sigma_t = { pattern = "constant", value = [0.5, 1, 2] }"#,
    ];
    let sigma = [0.5f64, 1.0, 2.0];
    for (k, density) in cases.iter().enumerate() {
        let interior = format!(r#"{{ {density}, albedo = 0 }}"#);
        let out = render_text(&d, &slab_scene(&interior, 128, 11 + k as u64));
        assert_transmits(density, &out, sigma);
        assert_eq!(out.stats.counters.majorant_violations, 0, "{density}");
    }
}

#[test]
fn a_colour_density_pattern_renders_its_grey_pattern_times_colour_twin() {
    // A scattering ball lit by a sun (shadow rays: every transmittance estimator): the
    // colour gradient (0.5, 1, 2) -> (1.5, 3, 6) along y is the grey gradient 0.5 -> 1.5
    // times the colour (1, 2, 4). As a colour density it takes the per-channel estimators;
    // as a grey density under `scale = [1, 2, 4]` the chromatic-scale ones (another code
    // path, `risotto_systems::spectral_tracking`'s `k` ratios). Channel means within 3
    // combined standard errors, for each tracking.
    let d = scratch_dir("channels", "pattern-twin");
    let common = r#"albedo = [0.9, 0.8, 0.6], phase = { type = "hg", g = 0.3 }, majorant_grid = 4"#;
    let scene = |interior: &str, seed| common::medium_ball_scene(interior, 16, 64, seed, 3.0);
    for (k, tracking) in TRACKINGS.iter().enumerate() {
        let twin = format!(
            r#"{{ type = "heterogeneous", density = {{ pattern = "gradient", axis = "y", from = -1, to = 1, a = 0.5, b = 1.5 }}, scale = [1, 2, 4], tracking = "{tracking}", {common} }}"#
        );
        let colour = format!(
            r#"{{ type = "heterogeneous", density = {{ pattern = "gradient", axis = "y", from = -1, to = 1, a = [0.5, 1, 2], b = [1.5, 3, 6] }}, tracking = "{tracking}", {common} }}"#
        );
        let reference = channel_means(&render_text(&d, &scene(&twin, 40 + k as u64)));
        let out = render_text(&d, &scene(&colour, 50 + k as u64));
        assert_agrees(tracking, &reference, &out);
    }
}

#[test]
fn bad_three_channel_files_and_keys_are_located_errors() {
    let d = scratch_dir("channels", "errors");
    write_vol(&d.join("two.vol"), [2, 2, 2], 2, |_| [1.0; 3]);
    write_vol(&d.join("rgb.vol"), [2, 2, 2], 3, |_| [1.0; 3]);
    write_vol(&d.join("ten.vol"), [2, 2, 2], 3, |_| [10.0; 3]);
    write_vol(&d.join("neg.vol"), [2, 2, 2], 3, |i| {
        if i == 5 {
            [1.0, 1.0, -0.5]
        } else {
            [1.0; 3]
        }
    });
    // A 3-channel header over one channel's worth of values.
    let mut short = std::fs::read(d.join("rgb.vol")).unwrap();
    short.truncate(48 + 8 * 4);
    std::fs::write(d.join("short.vol"), short).unwrap();
    let cases: [(&str, &[&str]); 6] = [
        (
            r#"density = { grid = "two.vol" }"#,
            &[
                "scene.toml",
                "interior.density",
                "two.vol",
                "2 channels",
                "1 (a density) or 3",
            ],
        ),
        (
            r#"density = { grid = "neg.vol" }"#,
            &["neg.vol", "byte 116", "voxel (1, 0, 1) channel 2", "-0.5"],
        ),
        (
            r#"density = { grid = "short.vol" }"#,
            &["short.vol", "3 channel(s) need 144 bytes", "has 80"],
        ),
        (
            r#"density = { grid = "rgb.vol" }, emission = [1, 1, 1]"#,
            &["scene.toml", "emission", "3 channels"],
        ),
        (
            r#"density = { constant = 1 }, emission = { grid = "rgb.vol" }"#,
            &["rgb.vol", "3 channels", "one value per voxel"],
        ),
        (
            r#"density = { grid = "ten.vol" }, scale = [1, 3e38, 1]"#,
            &["scale", "overflows"],
        ),
    ];
    for (params, needles) in cases {
        let interior = format!(r#"{{ type = "heterogeneous", {params} }}"#);
        let text = common::medium_ball_scene(&interior, 4, 1, 1, 1.0);
        let desc = parse_scene(&text, &d.join("scene.toml")).unwrap();
        let e = match scene_from_desc(desc, &MaterialRegistry::with_builtins()) {
            Ok(_) => panic!("{params}: accepted"),
            Err(e) => e.to_string(),
        };
        for n in needles {
            assert!(e.contains(n), "{params}: {e:?} lacks {n:?}");
        }
    }
}
