//! The plastic, thin dielectric and two-sided materials through the renderer: a pane in
//! front of a light passes `T' = 1 - R'`, a two-sided surface looks the same from both
//! sides (a one-sided one is black from behind), a white plastic in a white furnace is
//! white, and the scene-file errors of these materials are located.

use risotto::engine::render::{render, RenderOptions};
use risotto::loader::load::{scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::parse_scene;
use std::path::PathBuf;

/// Where the inline scenes say they are (they read no files).
fn scene_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/plastic_and_panes.toml")
}

/// Renders `text` (16 x 16 pixels, `spp`) and returns the mean of each channel over the
/// image.
fn render_mean(text: &str, spp: u32) -> [f64; 3] {
    let mut desc = parse_scene(text, &scene_path()).unwrap();
    desc.render.spp = spp;
    let scene = scene_from_desc(desc, &MaterialRegistry::with_builtins())
        .unwrap()
        .compile()
        .unwrap();
    let out = render(&scene, &RenderOptions::default(), &|_| {}).unwrap();
    assert_eq!(out.stats.counters.nan_dropped, 0);
    let n = out.beauty.pixels.len() as f64;
    let mut mean = [0.0; 3];
    for p in &out.beauty.pixels {
        mean[0] += p.r as f64 / n;
        mean[1] += p.g as f64 / n;
        mean[2] += p.b as f64 / n;
    }
    mean
}

/// An orthographic camera at `from` looking at the origin (every ray parallel), a 16 x 16
/// image, then `rest`.
fn scene(from: [f32; 3], max_depth: u32, rest: &str) -> String {
    format!(
        r#"
[render]
width = 16
height = 16
spp = 16
max_depth = {max_depth}
seed = 3

[camera]
projection = "orthographic"
width = 0.5
from = [{}, {}, {}]
to = [0, 0, 0]
up = [0, 1, 0]

{rest}
"#,
        from[0], from[1], from[2]
    )
}

/// Unpolarized Fresnel reflectance of one interface from the angle forms (Born and Wolf eq.
/// 1.5.(21)), f64: not the code under test.
fn fresnel(theta_i: f64, eta: f64) -> f64 {
    if theta_i == 0.0 {
        return ((eta - 1.0) / (eta + 1.0)).powi(2);
    }
    let theta_t = (theta_i.sin() / eta).asin();
    let rs = ((theta_i - theta_t).sin() / (theta_i + theta_t).sin()).powi(2);
    let rp = ((theta_i - theta_t).tan() / (theta_i + theta_t).tan()).powi(2);
    0.5 * (rs + rp)
}

/// A thin pane of index 1.5 (with the extra keys `glass`) at the origin facing +z, placed by
/// the transform list entries `transform`, in front of a light of radiance `emission` 2
/// units behind it that fills the view.
fn pane_before_light(glass: &str, transform: &str, emission: &str) -> String {
    format!(
        r#"
[materials.glass]
type = "thin_dielectric"
ior = 1.5
{glass}

[materials.black]
type = "diffuse"
reflectance = 0

[[shapes]]
name = "pane"
type = "rectangle"
material = "glass"
transform = [{transform}]

[[shapes]]
name = "light"
type = "rectangle"
material = "black"
emission = {emission}
transform = [{{ translate = [0, 0, -2] }}]
"#
    )
}

#[test]
fn a_pane_in_front_of_a_light_passes_one_minus_r_prime() {
    // The camera looks along -z through a pane turned by `angle` about +y at a light
    // (radiance 1, 2, 4) that fills the view; nothing else is in the scene, so a camera ray
    // reflected by the pane sees black and each pixel's expectation is T' * Le.
    for angle in [0.0f64, 60.0] {
        let rest = pane_before_light(
            "",
            &format!("{{ rotate = {{ axis = [0, 1, 0], angle = {angle} }} }}"),
            "[1, 2, 4]",
        );
        let spp = 4096;
        let mean = render_mean(&scene([0.0, 0.0, 5.0], 8, &rest), spp);
        let r = fresnel(angle.to_radians(), 1.5);
        let r_prime = r + (1.0 - r) * (1.0 - r) * r / (1.0 - r * r);
        let t_prime = 1.0 - r_prime;
        // Each sample is Le or 0: binomial noise over 16 x 16 x spp samples.
        let n = (16 * 16 * spp) as f64;
        let sigma = (t_prime * (1.0 - t_prime) / n).sqrt();
        for (c, le) in [1.0, 2.0, 4.0].into_iter().enumerate() {
            let got = mean[c] / le;
            assert!(
                (got - t_prime).abs() < 5.0 * sigma,
                "angle {angle}: channel {c} passes {got}, T' = {t_prime} (sigma {sigma})"
            );
        }
        // The test tells T' from the single interface's 1 - R, and at 60 degrees also from
        // two interfaces without the internal bounces, (1 - R)^2.
        assert!((t_prime - (1.0 - r)).abs() > 10.0 * sigma);
        if angle > 0.0 {
            assert!((t_prime - (1.0 - r) * (1.0 - r)).abs() > 10.0 * sigma);
        }
    }
}

#[test]
fn a_null_transmission_is_no_bounce() {
    // A pane in front of a light, at max_depth = 1 (only what the camera sees directly):
    // with `null_transmission` (Mitsuba's volumetric path tracers) the passage through the
    // pane is no bounce, so the light shows through it, dimmed by T'; without, the pane is
    // the path's one vertex and nothing reaches the light.
    let rest = |null: bool| pane_before_light(&format!("null_transmission = {null}"), "", "1");
    let spp = 1024;
    let r = fresnel(0.0, 1.5);
    let t_prime = 1.0 - 2.0 * r / (1.0 + r);
    let sigma = (t_prime * (1.0 - t_prime) / (16 * 16 * spp) as f64).sqrt();
    let null = render_mean(&scene([0.0, 0.0, 5.0], 1, &rest(true)), spp);
    assert!(
        (null[0] - t_prime).abs() < 5.0 * sigma,
        "{} against T' = {t_prime}",
        null[0]
    );
    let counted = render_mean(&scene([0.0, 0.0, 5.0], 1, &rest(false)), spp);
    assert_eq!(counted, [0.0; 3]);
}

#[test]
fn light_samples_pass_a_null_pane_attenuated_by_its_t_prime() {
    // A point light 2 above a diffuse floor (reflectance 0.5), a pane between them at
    // height 1 turned by `angle` about +y, and an orthographic camera under the pane seeing
    // a 0.002-wide patch of the floor: only the light sample lights it (a point light is
    // never hit), so each pixel is exactly `0.5 / pi * I / 4 * T'(angle)` for a pane whose
    // transmission is a null event (Mitsuba's `eval_null_transmission`, `1 - R'` at the
    // light ray's angle to the pane) and black for a pane that blocks shadow rays.
    let rest = |null: bool, angle: f64| {
        format!(
            r#"
[materials.glass]
type = "thin_dielectric"
ior = 1.5
null_transmission = {null}

[materials.floor]
type = "diffuse"
reflectance = 0.5

[[shapes]]
name = "floor"
type = "rectangle"
material = "floor"

[[shapes]]
name = "pane"
type = "rectangle"
material = "glass"
transform = [{{ rotate = {{ axis = [0, 1, 0], angle = {angle} }} }}, {{ translate = [0, 0, 1] }}]

[[lights]]
type = "point"
position = [0, 0, 2]
intensity = 3
"#
        )
    };
    let camera =
        |rest: &str| scene([0.0, 0.0, 0.5], 2, rest).replace("width = 0.5", "width = 0.002");
    for angle in [0.0f64, 60.0, 80.0] {
        let r = fresnel(angle.to_radians(), 1.5);
        let t_prime = 1.0 - 2.0 * r / (1.0 + r);
        let expected = 0.5 / std::f64::consts::PI * 3.0 / 4.0 * t_prime;
        let got = render_mean(&camera(&rest(true, angle)), 4)[0];
        assert!(
            (got - expected).abs() < 1e-4 * expected,
            "angle {angle}: {got} against {expected} (T' = {t_prime})"
        );
        // The angle matters: T' at 80 degrees is far from its value at normal incidence.
        if angle == 80.0 {
            let r0 = fresnel(0.0, 1.5);
            assert!((t_prime - (1.0 - 2.0 * r0 / (1.0 + r0))).abs() > 0.1);
        }
        let blocked = render_mean(&camera(&rest(false, angle)), 4);
        assert_eq!(blocked, [0.0; 3]);
    }
}

#[test]
fn panes_around_an_absorbing_interior_pass_it_into_the_volume() {
    // A unit cube of thin panes around a Beer interior (Mitsuba's thindielectric bounding a
    // medium), seen along -z at normal incidence in front of a light: a path crosses the
    // front pane, the interior (exp(-sigma)), the back pane, or bounces between the two
    // panes 2k more times, so the light passes
    // `T'^2 e^-sigma / (1 - R'^2 e^-2 sigma)` of its radiance. Panes that did not let the
    // path into the interior would pass `T'^2 / (1 - R'^2)`.
    let sigma = [0.2f64, 1.0, 2.5];
    let rest = format!(
        r#"
[materials.glass]
type = "thin_dielectric"
ior = 1.5
interior = {{ type = "beer", sigma_a = [{}, {}, {}] }}

[materials.black]
type = "diffuse"
reflectance = 0

[[shapes]]
name = "box"
type = "box"
material = "glass"
min = [-0.5, -0.5, -0.5]
max = [0.5, 0.5, 0.5]

[[shapes]]
name = "light"
type = "rectangle"
material = "black"
emission = 1
transform = [{{ translate = [0, 0, -2] }}]
"#,
        sigma[0], sigma[1], sigma[2]
    );
    let spp = 1024;
    let mean = render_mean(&scene([0.0, 0.0, 5.0], 64, &rest), spp);
    let r = fresnel(0.0, 1.5);
    let r_prime = r + (1.0 - r) * (1.0 - r) * r / (1.0 - r * r);
    let t_prime = 1.0 - r_prime;
    for (c, &s) in sigma.iter().enumerate() {
        let a = (-s).exp();
        let want = t_prime * t_prime * a / (1.0 - r_prime * r_prime * a * a);
        let without = t_prime * t_prime / (1.0 - r_prime * r_prime);
        // Each sample passes one of a few weights; the spread is below 0.5 want per sample.
        let sigma_mean = 0.5 * want / ((16 * 16 * spp) as f64).sqrt();
        assert!(
            (mean[c] - want).abs() < 5.0 * sigma_mean,
            "channel {c}: {} against {want} (sigma {sigma_mean}; without the interior \
             {without})",
            mean[c]
        );
    }
}

/// A 2 x 2 quad at the origin facing +z with material `material`, in a constant environment
/// of radiance 0.5, seen along its normal from the front or from behind.
fn lone_quad(material: &str, from_front: bool) -> [f64; 3] {
    let rest = format!(
        r#"
[materials.m]
{material}

[[shapes]]
name = "quad"
type = "rectangle"
material = "m"

[[lights]]
name = "sky"
type = "environment"
radiance = 0.5
"#
    );
    let z = if from_front { 5.0 } else { -5.0 };
    render_mean(&scene([0.0, 0.0, z], 4, &rest), 64)
}

#[test]
fn a_two_sided_surface_looks_the_same_from_both_sides() {
    // A lone diffuse quad in a constant environment L reflects exactly reflectance * L
    // (nothing occludes its hemisphere), from whichever side it is lit and seen when
    // two-sided.
    let diffuse = "type = \"diffuse\"\nreflectance = [0.2, 0.5, 0.8]";
    let two_sided = format!("{diffuse}\ntwo_sided = true");
    let want = [0.1, 0.25, 0.4];
    for (material, front) in [
        (diffuse, true),
        (two_sided.as_str(), true),
        (&two_sided, false),
    ] {
        let got = lone_quad(material, front);
        for c in 0..3 {
            assert!(
                (got[c] - want[c]).abs() < 0.01 * want[c],
                "{material:?} front {front}: {got:?} vs {want:?}"
            );
        }
    }
    // One-sided: black from behind.
    assert_eq!(lone_quad(diffuse, false), [0.0; 3]);
    // A two-sided plastic, white base and clear coat (nonlinear = false: albedo
    // F + (1 - F) d = 1): a white furnace from both sides.
    let plastic = "type = \"plastic\"\ndiffuse_reflectance = 1\ntwo_sided = true";
    for front in [true, false] {
        let got = lone_quad(plastic, front);
        for c in got {
            assert!((c - 0.5).abs() < 0.005, "front {front}: {got:?}");
        }
    }
    // The same with the base as a pattern (white cells on white: any loss of the pattern,
    // such as the default 0.5 or black, would show), read through the two-sided wrapper.
    let pattern = "type = \"plastic\"\ntwo_sided = true\n\
                   diffuse_reflectance = { pattern = \"checker\", scale = 3, a = 1, b = 1 }";
    let got = lone_quad(pattern, false);
    for c in got {
        assert!((c - 0.5).abs() < 0.005, "pattern: {got:?}");
    }
    let one_sided_plastic = "type = \"plastic\"\ndiffuse_reflectance = 1";
    assert_eq!(lone_quad(one_sided_plastic, false), [0.0; 3]);
    // A white rough conductor (energy-compensated: a white furnace within 1 %) is one-sided
    // as Mitsuba's `roughconductor`, and the same from both sides with `two_sided = true`.
    let metal = "type = \"rough_conductor\"\nmaterial = \"none\"\nalpha = 0.3";
    let two_sided_metal = format!("{metal}\ntwo_sided = true");
    for (material, front) in [
        (metal, true),
        (&two_sided_metal, true),
        (&two_sided_metal, false),
    ] {
        let got = lone_quad(material, front);
        for c in got {
            assert!(
                (c - 0.5).abs() < 0.01,
                "{material:?} front {front}: {got:?}"
            );
        }
    }
    assert_eq!(lone_quad(metal, false), [0.0; 3]);
}

/// The error building `material` (a TOML table body) into a scene, as text.
fn material_error(material: &str) -> String {
    let rest = format!(
        r#"
[materials.m]
{material}

[[shapes]]
name = "quad"
type = "rectangle"
material = "m"
"#
    );
    let text = scene([0.0, 0.0, 5.0], 4, &rest);
    let desc = match parse_scene(&text, &scene_path()) {
        Ok(d) => d,
        Err(e) => return e.to_string(),
    };
    match scene_from_desc(desc, &MaterialRegistry::with_builtins()) {
        Ok(_) => panic!("{material}: accepted"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_plastic_pane_and_two_sided_values_are_located_errors() {
    // The line of `[materials.m]` is 17 in `scene`'s text; the key's line follows.
    for (material, parts) in [
        (
            "type = \"plastic\"\nint_ior = 0",
            &[
                "plastic_and_panes.toml:19",
                "materials.m",
                "int_ior",
                "`0`",
                "> 0",
            ][..],
        ),
        (
            "type = \"plastic\"\next_ior = -1.2",
            &["plastic_and_panes.toml:19", "ext_ior", "`-1.2`", "> 0"],
        ),
        (
            "type = \"plastic\"\nint_ior = nan",
            &["plastic_and_panes.toml:19", "int_ior", "nan", "finite"],
        ),
        (
            "type = \"plastic\"\ndiffuse_reflectance = [0.5, 1.5, 0.5]",
            &[
                "plastic_and_panes.toml:19",
                "diffuse_reflectance",
                "1.5",
                "[0, 1]",
            ],
        ),
        (
            "type = \"plastic\"\nspecular_reflectance = -0.1",
            &[
                "plastic_and_panes.toml:19",
                "specular_reflectance",
                "-0.1",
                ">= 0",
            ],
        ),
        (
            "type = \"plastic\"\nspecular_reflectance = 1.5",
            &[
                "plastic_and_panes.toml:19",
                "specular_reflectance",
                "1.5",
                "[0, 1]",
            ],
        ),
        (
            "type = \"thin_dielectric\"\nior = 0",
            &["plastic_and_panes.toml:19", "ior", "`0`", "> 0"],
        ),
        (
            "type = \"thin_dielectric\"\ntint = 0.5",
            &["plastic_and_panes.toml:19", "tint"],
        ),
        (
            "type = \"dielectric\"\ntwo_sided = true",
            &[
                "plastic_and_panes.toml:19",
                "two_sided",
                "`dielectric` transmits",
            ],
        ),
        (
            "type = \"thin_dielectric\"\ntwo_sided = true",
            &[
                "plastic_and_panes.toml:19",
                "two_sided",
                "`thin_dielectric` transmits",
            ],
        ),
        (
            "type = \"interface\"\ntwo_sided = true",
            &["two_sided", "`interface` transmits"],
        ),
        (
            "type = \"subsurface\"\ntwo_sided = true",
            &["two_sided", "`subsurface` transmits"],
        ),
        (
            "type = \"diffuse\"\ntwo_sided = 1",
            &["plastic_and_panes.toml:19", "two_sided"],
        ),
    ] {
        let err = material_error(material);
        for part in parts {
            assert!(err.contains(part), "{material:?}: {err:?} lacks {part:?}");
        }
    }
}
