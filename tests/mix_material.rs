//! `type = "mix"` (pbrt-v4's `mix`, Mitsuba's `blendbsdf`): `(1 - t) a + t b`, checked
//! against what is not itself: a sphere under a white environment shows its directional
//! albedo exactly (one bounce, nothing else to see), so a mix of a diffuse 0.8 and a mirror
//! is `0.8 (1 - t) + t` per pixel; a mix of two diffuse materials equals the diffuse of the
//! mean reflectance; each component reads its own patterns.

mod common;

use common::images::block_z;
use common::{image_mean, load_scene_text, render_scene_text, scratch_dir};

/// A unit sphere filling most of a 32 x 32 view under a white environment, its material
/// `sphere` (other materials in `materials`, TOML).
fn scene(materials: &str, spp: u32) -> String {
    format!(
        r#"
[render]
width = 32
height = 32
spp = {spp}
max_depth = 4

[camera]
projection = "orthographic"
width = 1.2
from = [0, 0, 5]
to = [0, 0, 0]

[[lights]]
type = "environment"
radiance = 1

{materials}

[[shapes]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "sphere"
"#
    )
}

#[test]
fn a_mix_of_diffuse_and_mirror_reflects_the_blend_of_their_albedos() {
    let dir = scratch_dir("mix", "albedo");
    for t in [0.0f32, 0.25, 0.7, 1.0] {
        let text = scene(
            &format!(
                r#"
[materials.matte]
type = "diffuse"
reflectance = 0.8

[materials.mirror]
type = "conductor"

[materials.sphere]
type = "mix"
a = "matte"
b = "mirror"
amount = {t}
"#
            ),
            64,
        );
        let out = render_scene_text(&dir, &text);
        let (mean, se) = image_mean(&out);
        let want = 0.8 * (1.0 - t) + t;
        // The view (1.2 wide) lies inside the sphere's disk: every pixel sees the sphere.
        assert!(
            (mean.g - want).abs() < 4.0 * se.g + 2e-3,
            "t = {t}: {mean:?} +- {se:?} vs {want}"
        );
        assert_eq!(out.stats.counters.nan_dropped, 0);
    }
}

#[test]
fn a_mix_of_two_diffuse_materials_is_the_diffuse_of_their_mean() {
    let dir = scratch_dir("mix", "diffuse");
    // Lit by a small distant light too, so the light-sampling (evaluate) path counts.
    let light = "[[lights]]\ntype = \"distant\"\ndirection = [0.3, -0.5, -1]\nirradiance = 2\n";
    let mixed = scene(
        &format!(
            "{light}
[materials.dark]
type = \"diffuse\"
reflectance = [0.1, 0.2, 0.3]

[materials.light]
type = \"diffuse\"
reflectance = [0.9, 0.6, 0.5]

[materials.sphere]
type = \"mix\"
a = \"dark\"
b = \"light\"
amount = 0.25
"
        ),
        128,
    );
    let plain = scene(
        &format!(
            "{light}\n[materials.sphere]\ntype = \"diffuse\"\nreflectance = [0.3, 0.3, 0.35]\n"
        ),
        128,
    );
    let (a, b) = (
        render_scene_text(&dir, &mixed),
        render_scene_text(&dir, &plain),
    );
    let worst = block_z(&a, &b)
        .into_iter()
        .fold(0.0f64, |m, z| m.max(z.abs()));
    assert!(worst < 4.5, "max block |z| {worst}");
}

#[test]
fn each_component_reads_its_own_patterns() {
    // Two diffuse materials with different checkers on `reflectance`: the mix at amount 1 is
    // b alone and at 0 a alone (if the components shared one parameter cache, one would
    // show the other's checker).
    let dir = scratch_dir("mix", "patterns");
    let materials = |sphere: &str| {
        format!(
            r#"
[materials.red_checks]
type = "diffuse"
reflectance = {{ pattern = "checker", scale = 4, a = [0.8, 0.1, 0.1], b = [0.1, 0.1, 0.1] }}

[materials.blue_checks]
type = "diffuse"
reflectance = {{ pattern = "checker", scale = 2, a = [0.1, 0.1, 0.1], b = [0.1, 0.1, 0.8] }}

[materials.sphere]
{sphere}
"#
        )
    };
    for (t, alone) in [(0.0, "red_checks"), (1.0, "blue_checks")] {
        let mix = materials(&format!(
            "type = \"mix\"\na = \"red_checks\"\nb = \"blue_checks\"\namount = {t}"
        ));
        let one = materials(&format!(
            "type = \"mix\"\na = \"{alone}\"\nb = \"{alone}\"\namount = 0.5"
        ));
        let (a, b) = (
            render_scene_text(&dir, &scene(&mix, 32)),
            render_scene_text(&dir, &scene(&one, 32)),
        );
        let worst = block_z(&a, &b)
            .into_iter()
            .fold(0.0f64, |m, z| m.max(z.abs()));
        assert!(worst < 4.5, "amount {t}: max block |z| {worst}");
    }
}

#[test]
fn bad_mixes_are_located_errors() {
    let dir = scratch_dir("mix", "errors");
    let base =
        "[materials.matte]\ntype = \"diffuse\"\n\n[materials.glass]\ntype = \"dielectric\"\n";
    for (sphere, want) in [
        (
            "type = \"mix\"\na = \"matte\"\nb = \"glass\"",
            "`b`: a mix component must only reflect",
        ),
        (
            "type = \"mix\"\na = \"matte\"\nb = \"nope\"",
            "unknown material `nope`",
        ),
        (
            "type = \"mix\"\na = \"matte\"\nb = \"sphere\"",
            "cannot contain itself",
        ),
        (
            "type = \"mix\"\na = \"matte\"\nb = \"matte\"\namount = 2",
            "`amount`",
        ),
        (
            "type = \"mix\"\na = \"matte\"\nb = \"matte\"\nc = \"matte\"",
            "`c`",
        ),
        ("type = \"mix\"\na = \"matte\"", "`b`"),
    ] {
        let text = scene(&format!("{base}\n[materials.sphere]\n{sphere}\n"), 1);
        let e = match load_scene_text(&dir, &text) {
            Ok(_) => panic!("{sphere}: loaded"),
            Err(e) => e.to_string(),
        };
        assert!(
            e.contains(want) && e.contains("scene.toml:"),
            "{sphere}: {e}"
        );
    }
    // Mixes nest three deep at most.
    let nested = "[materials.m1]\ntype = \"mix\"\na = \"matte\"\nb = \"matte\"\n\
                  [materials.m2]\ntype = \"mix\"\na = \"m1\"\nb = \"matte\"\n\
                  [materials.m3]\ntype = \"mix\"\na = \"m2\"\nb = \"matte\"\n";
    let text = scene(
        &format!("{base}{nested}\n[materials.sphere]\ntype = \"mix\"\na = \"m2\"\nb = \"matte\"\n"),
        1,
    );
    load_scene_text(&dir, &text).unwrap();
    let text = scene(
        &format!("{base}{nested}\n[materials.sphere]\ntype = \"mix\"\na = \"m3\"\nb = \"matte\"\n"),
        1,
    );
    let e = load_scene_text(&dir, &text)
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(e.contains("nest at most 3 deep"), "{e}");
}
