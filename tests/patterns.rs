//! Patterns in scene files (issue 11): pattern tables load into graphs with located errors,
//! their files join the scene's referenced files, they evaluate through the shading
//! context's cache (counted in the stats), the constant fast path is untouched, and the
//! albedo AOV of a patterned surface is the pattern.

mod common;
use common::scratch_dir;
use risotto::engine::plugin::ParamValue;
use risotto::engine::render::{render, RenderOptions, RenderOutput};
use risotto::loader::load::{compile_scene, load_scene_file, MaterialRegistry};
use std::path::Path;

/// An orthographic 4 x 4 view of a 6 x 6 quad at z = 0.5 (mid-cell of a unit checker), facing the
/// camera, with `reflectance` as its material's value; lit by a constant sky.
fn flat_scene(reflectance: &str, spp: u32) -> String {
    flat_material_scene(
        &format!("type = \"diffuse\"\nreflectance = {reflectance}"),
        spp,
    )
}

/// [`flat_scene`] with the quad's material table given whole (`material`: its lines).
fn flat_material_scene(material: &str, spp: u32) -> String {
    format!(
        r#"[render]
width = 8
height = 8
spp = {spp}
max_depth = 2

[camera]
projection = "orthographic"
width = 4
from = [0, 0, 5]
to = [0, 0, 0]

[materials.wall]
{material}

[[shapes]]
name = "wall"
type = "quad"
material = "wall"
corner = [-3, -3, 0.5]
edge1 = [6, 0, 0]
edge2 = [0, 6, 0]

[[lights]]
type = "environment"
radiance = 1
"#
    )
}

fn load_text(dir: &Path, text: &str) -> Result<risotto::engine::scene::Scene, String> {
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    load_scene_file(&path, &MaterialRegistry::with_builtins()).map_err(|e| e.to_string())
}

fn render_text(dir: &Path, text: &str) -> RenderOutput {
    let scene = load_text(dir, text).unwrap_or_else(|e| panic!("{e}"));
    let compiled = compile_scene(scene).unwrap();
    render(&compiled, &RenderOptions::default(), &|_| {}).unwrap()
}

fn write_png(path: &Path, w: u32, h: u32, rgb: &[u8]) {
    let mut e = png::Encoder::new(std::fs::File::create(path).unwrap(), w, h);
    e.set_color(png::ColorType::Rgb);
    e.set_depth(png::BitDepth::Eight);
    e.write_header().unwrap().write_image_data(rgb).unwrap();
}

#[test]
fn pattern_tables_load_into_graphs_and_name_their_files() {
    let dir = scratch_dir("patterns", "load");
    write_png(&dir.join("tex.png"), 2, 1, &[255, 0, 0, 0, 0, 255]);
    let reflectance = r#"{ pattern = "mix", a = { pattern = "image", path = "tex.png" }, b = 0.25, t = { pattern = "checker", scale = 2, space = "uv" } }"#;
    let scene = load_text(&dir, &flat_scene(reflectance, 1)).unwrap();
    let factory = &scene.materials[0].factory;
    let Some(ParamValue::Pattern(graph)) = factory.param("reflectance") else {
        panic!("reflectance is not a pattern");
    };
    // image, constant 0.25, checker, mix: children first, the root last.
    assert_eq!(graph.nodes().len(), 4);
    assert!(graph.reads_uv());
    let files = scene.files.paths();
    assert!(
        files.iter().any(|f| f.ends_with("tex.png")),
        "the texture is a referenced file: {files:?}"
    );
    // A constant stays a constant (the fast path).
    let scene = load_text(&dir, &flat_scene("[0.1, 0.2, 0.3]", 1)).unwrap();
    assert!(matches!(
        scene.materials[0].factory.param("reflectance"),
        Some(ParamValue::Color(_))
    ));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_patterns_are_located_errors_naming_key_and_value() {
    let dir = scratch_dir("patterns", "errors");
    // (reflectance, expected pieces of the message). The reflectance is on line 15.
    let cases: &[(&str, &[&str])] = &[
        (
            r#"{ pattern = "plaid" }"#,
            &[
                "scene.toml:15:",
                "`pattern`",
                "unknown pattern \"plaid\"",
                "checker",
            ],
        ),
        (
            r#"{ pattern = "noise", frequncy = 2 }"#,
            &[
                "scene.toml:15:",
                "unknown field `frequncy`",
                "did you mean `frequency`",
            ],
        ),
        (
            r#"{ pattern = "remap", a = { pattern = "noise", octaves = 0 }, from = [-1, 1] }"#,
            &[
                "scene.toml:15:",
                "reflectance.a",
                "`octaves`",
                "[1, 16], got `0`",
            ],
        ),
        (
            r#"{ pattern = "remap", a = { pattern = "noise", octaves = 17 } }"#,
            &["`octaves`", "got `17`"],
        ),
        (
            r#"{ pattern = "remap", a = { pattern = "noise", frequency = -2 } }"#,
            &["`frequency`", "must be >= 0, got `-2`"],
        ),
        (
            r#"{ pattern = "remap", a = 0.5, from = [0.3, 0.3] }"#,
            &["`from`", "must not be empty", "[0.3, 0.3]"],
        ),
        (
            r#"{ pattern = "image", path = "missing.png" }"#,
            &["scene.toml:15:", "`path`", "missing.png"],
        ),
        (
            r#"{ pattern = "grid", path = "missing.vol" }"#,
            &["`path`", "missing.vol"],
        ),
        (
            r#"{ pattern = "grid", values = [1, 2, 3], dims = [2, 1, 1] }"#,
            &[
                "scene.toml:15:",
                "`values`",
                "has 3 numbers; dims [2, 1, 1] need 2",
            ],
        ),
        (
            r#"{ pattern = "grid", values = [1, 2], dims = [2, 1] }"#,
            &["`dims`", "expected 3 integers"],
        ),
        (
            r#"{ pattern = "grid", values = [1, 2], dims = [2, 0, 1] }"#,
            &["`dims`", "integer >= 1"],
        ),
        (
            r#"{ pattern = "grid", values = [1, -2], dims = [2, 1, 1] }"#,
            &["`values`", "-2"],
        ),
        (
            r#"{ pattern = "grid", values = [1], dims = [1, 1, 1], path = "g.vol" }"#,
            &["give `path` or `values`, not both"],
        ),
        (
            r#"{ pattern = "grid", values = [1], dims = [1, 1, 1], name = "density" }"#,
            &["`name`", "belongs to a grid file"],
        ),
        (
            r#"{ pattern = "grid", values = [1], dims = [1, 1, 1], border = "wrap" }"#,
            &["`border`", "unknown border `wrap`"],
        ),
        (
            r#"{ pattern = "grid", values = [1], dims = [1, 1, 1], transform = [{ scale = 0 }] }"#,
            &["`transform`", "singular"],
        ),
        (
            r#"{ pattern = "fraction", a = 0.5 }"#,
            &["missing required field `b`"],
        ),
        (
            r#"{ pattern = "add", a = 0.5, b = 0.6 }"#,
            &["`reflectance`", "every channel in [0, 1]"],
        ),
        (
            r#"{ pattern = "grid" }"#,
            &["needs `path = \"file.vol\"` or `values = [..]` with `dims`"],
        ),
        (
            r#"{ pattern = "noise" }"#,
            &[
                "`reflectance`",
                "every channel in [0, 1]",
                "-2.8125",
                "remap",
            ],
        ),
        (
            r#"{ pattern = "checker", a = 2 }"#,
            &["`reflectance`", "every channel in [0, 1]"],
        ),
        (
            r#"{ pattern = "mix", a = 0.1, b = 0.2 }"#,
            &["missing required field `t`"],
        ),
    ];
    for (reflectance, pieces) in cases {
        let e = match load_text(&dir, &flat_scene(reflectance, 1)) {
            Ok(_) => panic!("{reflectance}: loaded"),
            Err(e) => e,
        };
        for piece in *pieces {
            assert!(e.contains(piece), "{reflectance}: `{piece}` not in\n{e}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_constant_pattern_renders_bit_identical_to_the_constant_and_is_counted() {
    let dir = scratch_dir("patterns", "identical");
    let constant = render_text(&dir, &flat_scene("[0.3, 0.5, 0.7]", 4));
    let pattern = render_text(
        &dir,
        &flat_scene(r#"{ pattern = "constant", value = [0.3, 0.5, 0.7] }"#, 4),
    );
    assert_eq!(constant.beauty.pixels, pattern.beauty.pixels);
    assert_eq!(constant.albedo.pixels, pattern.albedo.pixels);
    // The constant never touches the cache; the pattern is evaluated once per shade group.
    let (c, p) = (&constant.stats.counters, &pattern.stats.counters);
    assert_eq!((c.pattern_evals, c.pattern_cache_hits), (0, 0));
    assert!(p.pattern_evals > 0, "{p:?}");
    assert_eq!(constant.stats.features, pattern.stats.features);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_shipped_patterns_scene_evaluates_patterns_and_cornell_does_not() {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let registry = MaterialRegistry::with_builtins();
    let tiny = |name: &str| {
        let file = scenes.join(name);
        let mut scene = load_scene_file(&file, &registry).unwrap();
        let s = &mut scene.settings;
        let h = ((32 * s.height) / s.width).max(1);
        (s.width, s.height, s.spp) = (32, h, 2);
        (scene.camera.width, scene.camera.height) = (32, h);
        let compiled = compile_scene(scene).unwrap();
        render(&compiled, &RenderOptions::default(), &|_| {}).unwrap()
    };
    let patterns = tiny("patterns.toml");
    assert!(patterns.stats.counters.pattern_evals > 0);
    // Surface patterns only: none of the evaluations is a volume's (the scene has no
    // heterogeneous medium).
    assert_eq!(patterns.stats.counters.volume_pattern_evals, 0);
    assert!(!patterns
        .stats
        .features
        .iter()
        .any(|f| f == "heterogeneous_media"));
    assert_eq!(patterns.stats.counters.nan_dropped, 0);
    let cornell = tiny("cornell-box.toml");
    let c = &cornell.stats.counters;
    assert_eq!((c.pattern_evals, c.pattern_cache_hits), (0, 0));
    assert!(
        !cornell.stats.features.iter().any(|f| f == "surface_uv"),
        "{:?}",
        cornell.stats.features
    );
}

#[test]
fn the_albedo_aov_of_a_patterned_surface_is_the_pattern() {
    let dir = scratch_dir("patterns", "albedo");
    // Unit cells by P: the 8 x 8 pixels of the 4 x 4 view hold 2 x 2 pixels per cell, and the
    // wall at z = 0.5 lies inside one layer of cells.
    let (a, b) = (0.2f32, 0.8f32);
    let out = render_text(
        &dir,
        &flat_scene(
            &format!(r#"{{ pattern = "checker", scale = 1, a = {a}, b = {b} }}"#),
            4,
        ),
    );
    for y in 0..8 {
        for x in 0..8 {
            // Pixel (x, y) covers world x in [-2 + x / 2, ..], world y downwards from 2.
            let (cx, cy) = ((x / 2) as i32 - 2, 1 - (y / 2) as i32);
            let expected = if (cx + cy).rem_euclid(2) == 0 { a } else { b };
            let got = out.albedo.pixels[y * 8 + x];
            assert!(
                (got.r - expected).abs() < 1e-5 && got.r == got.g && got.g == got.b,
                "pixel ({x}, {y}): {got:?}, expected {expected}"
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Renders [`flat_material_scene`] with `material` and checks that each pixel is the colour of
/// a unit checker by P at its point, red (`[0.9, 0.1, 0.1]`) on even cells and blue
/// (`[0.1, 0.1, 0.9]`) on odd ones: the 0.5-wide pixels each lie in one cell, and the
/// pixels centred at (x, y) = (+-0.75, 0.75) in cells of opposite parity, whichever way the
/// image's rows and columns run.
fn assert_checker_quad(name: &str, material: &str) {
    let dir = scratch_dir("patterns", name);
    let out = render_text(&dir, &flat_material_scene(material, 1));
    let px = |x: usize, y: usize| out.beauty.pixels[y * 8 + x];
    let near = |c: risotto_components::Rgb, r: f32, b: f32| {
        (c.r - r).abs() < 1e-3 && (c.g - 0.1).abs() < 1e-3 && (c.b - b).abs() < 1e-3
    };
    let red = |c| near(c, 0.9, 0.1);
    let blue = |c| near(c, 0.1, 0.9);
    let (a, b) = (px(5, 2), px(2, 2));
    assert!(
        (red(a) && blue(b)) || (blue(a) && red(b)),
        "{name}: {a:?} {b:?}"
    );
    // Diagonal neighbours share a parity.
    assert_eq!(red(px(5, 2)), red(px(2, 5)), "{name}");
    let reds = out.beauty.pixels.iter().filter(|&&c| red(c)).count();
    let blues = out.beauty.pixels.iter().filter(|&&c| blue(c)).count();
    assert_eq!((reds, blues), (32, 32), "{name}");
    assert!(out.stats.counters.pattern_evals > 0, "{name}");
}

#[test]
fn a_checker_patterned_mirror_reflects_both_colours_where_expected() {
    // The camera sees the sky (1) mirrored: each pixel is the reflectance.
    assert_checker_quad(
        "mirror",
        "type = \"mirror\"\nreflectance = { pattern = \"checker\", a = [0.9, 0.1, 0.1], b = [0.1, 0.1, 0.9] }",
    );
}

#[test]
fn a_checker_tinted_dielectric_transmits_both_colours_where_expected() {
    // ior 1: no Fresnel reflection, every path refracts straight through with weight tint.
    assert_checker_quad(
        "tint",
        "type = \"dielectric\"\nior = 1\ntint = { pattern = \"checker\", a = [0.9, 0.1, 0.1], b = [0.1, 0.1, 0.9] }",
    );
}

#[test]
fn a_tint_pattern_with_cheap_shadows_is_a_located_error() {
    let dir = scratch_dir("patterns", "cheap");
    let text = flat_material_scene(
        "type = \"dielectric\"\ntint = { pattern = \"checker\" }\ncheap_shadows = true",
        1,
    );
    let err = load_text(&dir, &text).err().expect("refused");
    assert!(
        err.contains("cheap_shadows") && err.contains("scene.toml:"),
        "{err}"
    );
}

/// A Mitsuba `.vol` of `dims` voxels and `channels` interleaved values per voxel over the
/// box [0, 1]^3.
fn write_vol(path: &Path, dims: [i32; 3], channels: i32, values: &[f32]) {
    let mut b = b"VOL\x03".to_vec();
    for v in [1i32, dims[0], dims[1], dims[2], channels] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0].iter().chain(values) {
        b.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(path, b).unwrap();
}

#[test]
fn a_grid_pattern_reads_one_channel_of_a_three_channel_file() {
    use risotto::systems::pattern::{eval, Node};
    let dir = scratch_dir("patterns", "grid_channel");
    // One voxel, (r, g, b) = (0.2, 0.5, 0.9).
    write_vol(&dir.join("rgb.vol"), [1, 1, 1], 3, &[0.2, 0.5, 0.9]);
    write_vol(&dir.join("grey.vol"), [1, 1, 1], 1, &[0.4]);
    for (channel, want) in [("r", 0.2f32), ("g", 0.5), ("b", 0.9)] {
        let reflectance = format!(
            r#"{{ pattern = "grid", path = "rgb.vol", channel = "{channel}", min = [0, 0, 0], max = [1, 1, 1] }}"#
        );
        let scene = load_text(&dir, &flat_scene(&reflectance, 1)).unwrap();
        let Some(ParamValue::Pattern(graph)) = scene.materials[0].factory.param("reflectance")
        else {
            panic!("reflectance is not a pattern");
        };
        assert!(matches!(graph.nodes()[0], Node::Grid { .. }));
        let mut out = [risotto::components::Rgb::BLACK];
        eval(graph, &[glam::Vec3::splat(0.5)], &[0.0], &[0.0], &mut out);
        assert_eq!(
            out[0],
            risotto::components::Rgb::splat(want),
            "channel {channel}"
        );
    }
    // Without `channel` a 3-channel file is refused; with it, a 1-channel file and inline
    // values are; an unknown channel is named.
    for (reflectance, piece) in [
        (r#"{ pattern = "grid", path = "rgb.vol" }"#, "3 channels"),
        (
            r#"{ pattern = "grid", path = "grey.vol", channel = "r" }"#,
            "1 channel",
        ),
        (
            r#"{ pattern = "grid", values = [1], dims = [1, 1, 1], channel = "r" }"#,
            "`channel`",
        ),
        (
            r#"{ pattern = "grid", path = "rgb.vol", channel = "alpha" }"#,
            "\"alpha\"",
        ),
    ] {
        let e = match load_text(&dir, &flat_scene(reflectance, 1)) {
            Ok(_) => panic!("{reflectance}: loaded"),
            Err(e) => e,
        };
        assert!(
            e.contains(piece) && e.contains("scene.toml:15:"),
            "{reflectance}: {e}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}
