//! The film's memory per pixel (issue 37): the figure the renderer checks a film against the
//! machine's memory with ([`FILM_BYTES_PER_PIXEL`]) is the one a render takes. Two renders of
//! a trivial scene (one sphere, sky, 1 spp) at 512^2 and 1024^2 pixels report their peak
//! resident memory (`--stats`, Linux `VmHWM`); the difference over the 786,432 extra pixels
//! is the film's cost per pixel, everything else (code, scene, threads) being the same. The
//! same with adaptive sampling measures what its estimates add
//! ([`ADAPTIVE_BYTES_PER_PIXEL`]), and with the unbiased rule what its pilot adds
//! ([`PILOT_BYTES_PER_PIXEL`]).

use risotto::engine::render::{render, RenderOptions};
use risotto::engine::render::{
    ADAPTIVE_BYTES_PER_PIXEL, AOV_BYTES_PER_PIXEL, FILM_BYTES_PER_PIXEL, PILOT_BYTES_PER_PIXEL,
};
use risotto::loader::load::{compile_scene, scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::parse_scene;
use std::path::Path;

mod common;
use common::cli::{ok, risotto};

const SCENE: &str = r#"[render]
width = SIZE
height = SIZE
spp = 1
[camera]
from = [0, 0, 5]
to = [0, 0, 0]
fov = 40
[materials.white]
type = "diffuse"
reflectance = [0.5, 0.5, 0.5]
[[shapes]]
type = "sphere"
material = "white"
center = [0, 0, 0]
radius = 1
[[lights]]
type = "environment"
radiance = [1, 1, 1]
"#;

/// Peak resident bytes of a render of the scene at `size`^2 (with the PNG preview, as a user
/// runs it) with the render options `extra`, or `None` where the platform does not report
/// it.
fn peak_resident(dir: &Path, size: u32, extra: &[&str]) -> Option<u64> {
    let scene = dir.join(format!("s{size}.toml"));
    std::fs::write(&scene, SCENE.replace("SIZE", &size.to_string())).unwrap();
    let (out, stats) = (
        dir.join(format!("s{size}.exr")),
        dir.join(format!("s{size}.json")),
    );
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--stats",
        stats.to_str().unwrap(),
        "--quiet",
        "-t",
        "1",
    ];
    args.extend_from_slice(extra);
    ok("render", risotto(&args));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    json["run"]["peak_resident_bytes"].as_u64()
}

/// Peak resident bytes a pixel of renders at 512^2 and 1024^2 with the options `extra`,
/// differenced, in `dir` (`None` where the platform reports no peak).
fn bytes_per_pixel(dir: &str, extra: &[&str]) -> Option<f64> {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(dir);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let small = peak_resident(&dir, 512, extra)?;
    let large = peak_resident(&dir, 1024, extra)?;
    Some(large.saturating_sub(small) as f64 / (1024.0 * 1024.0 - 512.0 * 512.0))
}

#[test]
fn a_renders_film_costs_the_documented_bytes_per_pixel() {
    let Some(per_pixel) = bytes_per_pixel("film-memory", &[]) else {
        eprintln!("no peak memory on this platform: nothing to measure");
        return;
    };
    eprintln!("film: {per_pixel:.0} bytes a pixel (documented {FILM_BYTES_PER_PIXEL})");
    let documented = FILM_BYTES_PER_PIXEL as f64;
    assert!(
        (0.8 * documented..=1.2 * documented).contains(&per_pixel),
        "a render's film takes {per_pixel:.0} bytes a pixel; FILM_BYTES_PER_PIXEL says \
         {FILM_BYTES_PER_PIXEL}: update it (and docs/scene-format.md) or the film"
    );
}

/// Keeping the first-hit AOVs (`--aovs`; `--denoise` too) adds what `AOV_BYTES_PER_PIXEL`
/// says; a render without them does not pay it (`FILM_BYTES_PER_PIXEL` is measured
/// without).
#[test]
fn the_aovs_cost_the_documented_bytes_per_pixel() {
    assert_added_bytes(
        "AOV_BYTES_PER_PIXEL",
        AOV_BYTES_PER_PIXEL,
        ("aov-memory-plain", &[]),
        ("aov-memory-kept", &["--aovs"]),
    );
}

/// Adaptive sampling's options with stopping rule `rule` (a loose target: the memory, not
/// the image, is measured).
fn adaptive(rule: &str) -> [&str; 6] {
    [
        "--noise-target",
        "0.5",
        "--min-spp",
        "4",
        "--stopping-rule",
        rule,
    ]
}

/// Asserts that `measured` bytes a pixel are within a quarter of `documented`, or 2 bytes
/// for the smallest constants (`what` names the constant).
fn assert_documented(measured: f64, documented: u64, what: &str) {
    eprintln!("{what}: {measured:.1} bytes a pixel (documented {documented})");
    let documented = documented as f64;
    let tolerance = (0.25 * documented).max(2.0);
    assert!(
        (documented - tolerance..=documented + tolerance).contains(&measured),
        "{what} is {documented} bytes a pixel, measured {measured:.0}: update it or the code"
    );
}

/// Asserts that renders with `with` (options, and a scratch directory) take `documented`
/// bytes a pixel more than renders with `base`, within a quarter (`what` names the
/// constant); nothing where the platform reports no peak.
fn assert_added_bytes(what: &str, documented: u64, base: (&str, &[&str]), with: (&str, &[&str])) {
    let (Some(base), Some(with)) = (
        bytes_per_pixel(base.0, base.1),
        bytes_per_pixel(with.0, with.1),
    ) else {
        eprintln!("no peak memory on this platform: nothing to measure");
        return;
    };
    assert_documented(with - base, documented, what);
}

/// An adaptive render's estimates and flags, beyond the film, are what
/// `ADAPTIVE_BYTES_PER_PIXEL` says.
#[test]
fn adaptive_sampling_costs_the_documented_bytes_per_pixel() {
    assert_added_bytes(
        "ADAPTIVE_BYTES_PER_PIXEL",
        ADAPTIVE_BYTES_PER_PIXEL,
        ("adaptive-memory-plain", &[]),
        ("adaptive-memory-window", &adaptive("window")),
    );
}

/// The unbiased stopping rule keeps of its pilot only the pooled errors (its tiles' films,
/// without AOVs, are dropped before the image's passes): it adds `PILOT_BYTES_PER_PIXEL` to
/// the window rule's render (with the films kept for the whole render it added 68, with
/// AOV sums in them 126: both fail this).
#[test]
fn the_unbiased_rules_pilot_costs_the_documented_bytes_per_pixel() {
    assert_added_bytes(
        "PILOT_BYTES_PER_PIXEL",
        PILOT_BYTES_PER_PIXEL,
        ("pilot-memory-window", &adaptive("window")),
        ("pilot-memory-unbiased", &adaptive("unbiased")),
    );
}

// ---------------------------------------------------------------------------------------
// Without AOVs the image is the same and no AOV sums are kept.

fn scene() -> risotto::engine::scene::CompiledScene {
    let desc = parse_scene(&SCENE.replace("SIZE", "16"), Path::new("aovs.toml"))
        .unwrap_or_else(|e| panic!("{e}"));
    let scene =
        scene_from_desc(desc, &MaterialRegistry::with_builtins()).unwrap_or_else(|e| panic!("{e}"));
    compile_scene(scene).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_render_without_aovs_is_the_same_image_with_no_aov_sums() {
    let scene = scene();
    let with = render(&scene, &RenderOptions::default(), &|_| {}).unwrap();
    let options = RenderOptions {
        aovs: false,
        ..RenderOptions::default()
    };
    let without = render(&scene, &options, &|_| {}).unwrap();
    let bits = |p: &[risotto_components::Rgb]| -> Vec<u32> {
        p.iter()
            .flat_map(|c| c.to_array().map(f32::to_bits))
            .collect()
    };
    assert_eq!(bits(&with.beauty.pixels), bits(&without.beauty.pixels));
    assert_eq!(bits(&with.variance.pixels), bits(&without.variance.pixels));
    assert_eq!(with.sample_count, without.sample_count);
    // Kept: a mean per pixel, the sphere's albedo where it is seen.
    assert!(with.aovs.holds_sums());
    assert_eq!(with.albedo.pixels.len(), 16 * 16);
    assert_eq!(with.depth.len(), 16 * 16);
    let centre = with.albedo.pixels[8 * 16 + 8];
    assert!((centre.r - 0.5).abs() < 1e-4, "{centre:?}");
    // Not kept: no sums and empty layers, and no layer written for them.
    assert!(!without.aovs.holds_sums());
    assert!(without.albedo.pixels.is_empty() && without.normal.pixels.is_empty());
    assert!(without.depth.is_empty());
    let layers = without.film_output(true);
    assert!(layers.albedo.is_none() && layers.normal.is_none() && layers.depth.is_none());
}

/// The names of the layers of an EXR's parts.
fn layer_names(path: &Path) -> Vec<String> {
    let image = exr::prelude::read_all_flat_layers_from_file(path).unwrap();
    image
        .layer_data
        .iter()
        .flat_map(|l| {
            let part = l
                .attributes
                .layer_name
                .as_ref()
                .map_or(String::new(), |n| n.to_string());
            l.channel_data
                .list
                .iter()
                .map(move |c| format!("{part}.{}", c.name))
        })
        .collect()
}

#[test]
fn the_driver_writes_aov_layers_with_aovs_only() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("aovs");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // `peak_resident` renders the scene at 16^2 into `s16.exr`.
    let layers = |extra: &[&str]| {
        peak_resident(&dir, 16, extra);
        layer_names(&dir.join("s16.exr"))
    };
    let (plain, kept) = (layers(&[]), layers(&["--aovs"]));
    let albedo = |names: &[String]| names.iter().any(|n| n.contains("albedo"));
    assert!(!albedo(&plain), "{plain:?}");
    assert!(albedo(&kept), "{kept:?}");
}
