//! Chromatic heterogeneous media (issue 11): a colour density `scale` is tracked against one
//! grey majorant with one-sample spectral MIS (`risotto_systems::spectral_tracking`). A
//! constant grid must render the homogeneous medium of the same RGB extinction (scattering
//! and emitting), a grey scale must render exactly as before, and spectral MIS must remove
//! the fireflies of tracking one channel.

mod common;

use common::{
    constant_vol, environment, mat_in, ortho_camera, render_default, scratch_dir, settings,
};
use glam::Vec3;
use risotto::builtins::builtin::{Interior, Surface};
use risotto::builtins::heterogeneous::{HeterogeneousMedium, Tracking};
use risotto::engine::render::{render, RenderOptions, RenderOutput};
use risotto::engine::scene::{Scene, ShapeGeometry};
use risotto::loader::load::{scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::parse_scene;
use risotto::systems::geometry::Sphere;
use risotto::systems::grid::DensityGrid;
use risotto::systems::phase::PhaseFunction;
use risotto_components::Rgb;
use std::path::{Path, PathBuf};
use std::sync::Arc;

fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// [`common::medium_ball_scene`] under a sun of 3.
fn sphere_scene(interior: &str, n: u32, spp: u32, seed: u64) -> String {
    common::medium_ball_scene(interior, n, spp, seed, 3.0)
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
        let m = out
            .beauty
            .pixels
            .iter()
            .map(|p| p.to_array()[c] as f64)
            .sum::<f64>()
            / n;
        let v = out
            .variance
            .pixels
            .iter()
            .map(|p| p.to_array()[c] as f64)
            .sum::<f64>()
            / (n * n);
        (m, v.sqrt())
    })
}

/// Asserts every channel's image mean agrees within 3 combined standard errors.
fn assert_same_means(what: &str, a: &RenderOutput, b: &RenderOutput) {
    let (ma, mb) = (channel_means(a), channel_means(b));
    for c in 0..3 {
        let ((m0, s0), (m1, s1)) = (ma[c], mb[c]);
        let z = (m1 - m0) / (s0 * s0 + s1 * s1).sqrt();
        eprintln!("{what}, channel {c}: {m1:.5} +- {s1:.5} vs {m0:.5} +- {s0:.5}, z {z:.2}");
        assert!(
            z.abs() < 3.0,
            "{what}, channel {c}: {m1} +- {s1} vs {m0} +- {s0}"
        );
        assert!(s0 < 0.02 * m0, "converged enough to test: {m0} +- {s0}");
    }
    assert_eq!(b.stats.counters.nan_dropped, 0, "{what}");
}

#[test]
fn a_constant_chromatic_grid_renders_the_homogeneous_medium() {
    // sigma_t = (1, 2, 4), albedo (0.9, 0.8, 0.6), HG 0.3: the homogeneous interior against
    // the heterogeneous one with a constant density and a colour scale (one voxel, and an
    // 8^3 file of 0.5 through a 4^3 majorant grid, so the DDA crosses cells), with every
    // transmittance estimator. Channel means within 3 combined standard errors.
    let d = scratch_dir("chroma", "constant");
    constant_vol(&d.join("half.vol"), [8, 8, 8], 0.5);
    let common = r#"albedo = [0.9, 0.8, 0.6], phase = { type = "hg", g = 0.3 }"#;
    let homogeneous = render_text(
        &d,
        &sphere_scene(
            &format!(r#"{{ type = "homogeneous", sigma_t = [1, 2, 4], {common} }}"#),
            16,
            64,
            1,
        ),
    );
    let cases = [
        r#"density = { constant = 1 }, scale = [1, 2, 4], tracking = "ratio""#,
        r#"density = { grid = "half.vol" }, scale = [2, 4, 8], majorant_grid = 4, tracking = "ratio""#,
        r#"density = { grid = "half.vol" }, scale = [2, 4, 8], majorant_grid = 4, tracking = "residual""#,
        r#"density = { grid = "half.vol" }, scale = [2, 4, 8], majorant_grid = 1, tracking = "delta""#,
        r#"density = { grid = "half.vol" }, scale = [2, 4, 8], tracking = "ray_marching""#,
        r#"density = { grid = "half.vol" }, scale = [2, 4, 8], tracking = "unbiased_ray_marching""#,
    ];
    for (k, case) in cases.iter().enumerate() {
        let interior = format!(r#"{{ type = "heterogeneous", {case}, {common} }}"#);
        let out = render_text(&d, &sphere_scene(&interior, 16, 64, 2 + k as u64));
        assert_same_means(case, &homogeneous, &out);
    }
}

#[test]
fn a_chromatic_emitting_grid_renders_the_homogeneous_emitting_medium() {
    // j = (1, 0.5, 0.2) (the colour times a density of 1) in sigma_t = (1, 2, 4): the
    // emission estimator must carry the flights' per-channel weights, along path rays
    // (delta tracking) and shadow rays (ratio / residual / delta tracking).
    let d = scratch_dir("chroma", "emission");
    let common = r#"albedo = [0.9, 0.8, 0.6], emission = [1, 0.5, 0.2]"#;
    let homogeneous = render_text(
        &d,
        &sphere_scene(
            &format!(r#"{{ type = "homogeneous", sigma_t = [1, 2, 4], {common} }}"#),
            16,
            64,
            1,
        ),
    );
    for (k, tracking) in ["ratio", "residual", "delta"].iter().enumerate() {
        let interior = format!(
            r#"{{ type = "heterogeneous", density = {{ constant = 1 }}, scale = [1, 2, 4], tracking = "{tracking}", {common} }}"#
        );
        let out = render_text(&d, &sphere_scene(&interior, 16, 64, 2 + k as u64));
        assert_same_means(&format!("emitting, {tracking}"), &homogeneous, &out);
    }
}

/// FNV-1a over the bits of every beauty pixel.
fn image_hash(out: &RenderOutput) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for p in &out.beauty.pixels {
        for c in p.to_array() {
            for b in c.to_bits().to_le_bytes() {
                h = (h ^ b as u64).wrapping_mul(0x0100_0000_01b3);
            }
        }
    }
    h
}

#[test]
fn a_grey_scale_renders_exactly_as_before_spectral_tracking() {
    // The 64^3 harness grid at scale 10, every tracking, and an emissive case: the image
    // hashes were taken with the engine before the chromatic scale existed (the grey path
    // must keep its random numbers and results bit for bit). A grey colour `[10, 10, 10]`
    // is the number 10.
    let d = scratch_dir("chroma", "grey");
    let grid = scenes().join("mitsuba-suite/hetero_grid_density.vol");
    let g = grid.display();
    let cases = [
        ("ratio", ""),
        ("residual", ""),
        ("delta", ""),
        ("ray_marching", ""),
        ("unbiased_ray_marching", ""),
        ("ratio", ", emission = [1, 0.5, 0.2]"),
        ("delta", ", emission = [1, 0.5, 0.2]"),
    ];
    let mut hashes = Vec::new();
    for (tracking, extra) in cases {
        let interior = |scale: &str| {
            format!(
                r#"{{ type = "heterogeneous", density = {{ grid = "{g}" }}, scale = {scale}, albedo = [0.9, 0.6, 0.3], tracking = "{tracking}"{extra} }}"#
            )
        };
        let out = render_text(&d, &sphere_scene(&interior("10"), 12, 8, 3));
        let grey = render_text(&d, &sphere_scene(&interior("[10, 10, 10]"), 12, 8, 3));
        assert_eq!(image_hash(&out), image_hash(&grey), "{tracking}{extra}");
        hashes.push(image_hash(&out));
    }
    eprintln!("hashes: {hashes:#x?}");
    assert_eq!(hashes, GREY_HASHES);
}

/// [`a_grey_scale_renders_exactly_as_before_spectral_tracking`]'s image hashes. First taken
/// with the engine before spectral tracking (commit 1106d47) and matched by the chromatic
/// code's grey path; re-taken when the trackers began carrying one exponential draw across
/// majorant segments (397d628), which changed the grey trackers' random numbers on purpose
/// (ray marching, which draws none there, kept its hash). The two emissive cases were
/// re-taken when emissive heterogeneous media became lights under MIS (the ball is
/// light-sampled and its path rays' emission MIS-weighted: a new estimator, checked
/// analytically by `tests/volume_lights.rs` and the equilibrium spheres of
/// `tests/emissive_media.rs`). The estimator-level equality of the
/// grey and `k = 1` spectral trackers is `a_grey_k_reproduces_the_grey_estimators_bit_for_bit`
/// in `systems/src/spectral_tracking.rs`. The emissive cases changed again when shadow rays
/// stopped gathering the emission the path tracer drops (`IntegratorContext::emission_wanted`:
/// their transmittance now comes from the plain trackers, another unbiased estimate). All
/// seven were re-taken when the path tracer's Russian roulette became Cycles' square-root
/// survival (`risotto_systems::path::survival_probability`): other paths survive, by design;
/// and again when the camera's sample set became a digitally shifted Sobol sequence instead
/// of an Owen-scrambled one (`risotto_systems::sampler`): other pixel positions. The ratio,
/// residual and emissive-ratio cases were re-taken when ratio tracking began playing Russian
/// roulette on low transmittance estimates (`risotto_systems::tracking::roulette`): other
/// random numbers per shadow ray, the same expectation.
const GREY_HASHES: [u64; 7] = [
    0xff4e_0bcf_2461_48da,
    0x4b1a_304c_9ed7_4c8e,
    0xb410_f773_d2b3_0cf9,
    0xc2c6_89d4_315e_64f0,
    0x9f6a_db64_742e_5e9e,
    0x0930_b679_efe7_fe51,
    0x1afd_3340_4f08_681f,
];

/// A unit ball of constant density 1 with extinction `scale` per channel, albedo 0.95,
/// isotropic, under a white environment, seen by a 16 x 16 orthographic camera.
fn ball(scale: Rgb, single_channel: Option<usize>, spp: u32) -> RenderOutput {
    let medium = HeterogeneousMedium {
        single_channel,
        ..HeterogeneousMedium::new(
            DensityGrid::constant([1, 1, 1], 1.0).unwrap(),
            1,
            1.0,
            Rgb::splat(0.95),
            PhaseFunction::Isotropic,
            Tracking::Ratio,
        )
        .with_scale(scale)
    };
    let cam = ortho_camera(Vec3::new(0.0, 0.0, 20.0), Vec3::ZERO, Vec3::Y, 2.2, 16, 16);
    let mut scene = Scene::new(cam, settings(16, 16, spp, u32::MAX));
    let m = scene.add_material(
        "ball",
        1,
        mat_in(
            Surface::Interface,
            Interior::Heterogeneous(Arc::new(medium)),
        ),
    );
    scene.add_shape(
        "ball",
        ShapeGeometry::Sphere(Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        }),
        m,
        None,
    );
    environment(&mut scene, Rgb::WHITE);
    render_default(&scene.compile().unwrap())
}

#[test]
fn spectral_mis_removes_the_fireflies_of_tracking_one_channel() {
    // sigma_t = (0.5, 2, 8): tracking red alone (the thinnest channel: unbiased, its null
    // probability is the largest) multiplies blue's weight by k_b / k_r = 16 at every real
    // collision, so blue's few long walks carry 16^n. Spectral MIS bounds every flight's
    // weight by 1 / p_c. The blue channel's largest pixel and its mean film variance must
    // both be far smaller with MIS.
    let scale = Rgb::new(0.5, 2.0, 8.0);
    let stats = |out: &RenderOutput| {
        let max = out.beauty.pixels.iter().map(|p| p.b).fold(0.0f32, f32::max);
        let var = out.variance.pixels.iter().map(|p| p.b as f64).sum::<f64>()
            / out.variance.pixels.len() as f64;
        (max, var)
    };
    let mis = ball(scale, None, 32);
    let red = ball(scale, Some(0), 32);
    let ((mis_max, mis_var), (red_max, red_var)) = (stats(&mis), stats(&red));
    eprintln!(
        "blue: MIS max pixel {mis_max:.3}, mean variance {mis_var:.3e}; red only max pixel \
         {red_max:.3}, mean variance {red_var:.3e}"
    );
    assert_eq!(mis.stats.counters.nan_dropped, 0);
    assert!(red_max > 5.0 * mis_max, "{red_max} vs {mis_max}");
    assert!(red_var > 20.0 * mis_var, "{red_var} vs {mis_var}");
    // The albedo-0.95 ball under a white sky is at most white (in expectation): with MIS
    // no pixel strays far above it.
    assert!(mis_max < 1.5, "{mis_max}");
}

#[test]
fn bad_chromatic_scales_are_located_errors() {
    let d = scratch_dir("chroma", "errors");
    for (scale, want) in [
        ("[1, -2, 3]", "-2"),
        ("[1, inf, 3]", "inf"),
        ("[1, nan, 3]", "nan"),
        ("[1, 2]", "3 channels"),
        ("[1, 3e38, 1]", "overflows"),
    ] {
        let interior = format!(
            r#"{{ type = "heterogeneous", density = {{ constant = 2 }}, scale = {scale} }}"#
        );
        let text = sphere_scene(&interior, 4, 1, 0);
        let desc = parse_scene(&text, &d.join("scene.toml")).unwrap();
        let err = match scene_from_desc(desc, &MaterialRegistry::with_builtins()) {
            Ok(_) => panic!("{scale}: accepted"),
            Err(e) => e.to_string(),
        };
        for part in ["scene.toml:16", "scale", want] {
            assert!(err.contains(part), "{scale}: {err:?} lacks {part:?}");
        }
    }
}
