//! The `custom_volume_integrator` example's registration path: a user-defined material type
//! (`smoky_glass`: dielectric surface + a Beer-like volume integrator written outside the
//! engine), registered in a `MaterialRegistry`, used from scene text and rendered.

mod common;
#[path = "../examples/custom_volume_integrator.rs"]
mod example;

use common::image_mean;
use example::{registry, render_text, SmokyGlass, SCENE};
use risotto::loader::load::scene_from_desc;
use risotto::loader::scene_file::parse_scene;
use risotto_components::Rgb;
use std::path::Path;

#[test]
fn example_scene_renders_with_the_registered_type() {
    // The example's own scene, smaller.
    let text = SCENE
        .replace("width = 160", "width = 40")
        .replace("height = 120", "height = 30")
        .replace("spp = 32", "spp = 8");
    let out = render_text(&text, "example.toml").unwrap();
    assert_eq!(out.stats.counters.nan_dropped, 0);
    assert!(out.beauty.pixels.iter().all(|p| p.is_finite()));
    let m = out.beauty.mean();
    assert!(m.iter().all(|&c| c > 0.05), "image mean {m:?}");
    // The sphere's middle (the ball covers the image centre) is seen through the smoke,
    // which absorbs blue most and red least.
    let mut c = Rgb::BLACK;
    for y in 13..17 {
        for x in 18..22 {
            c += out.beauty.get(x, y);
        }
    }
    assert!(c.r > c.g && c.g > c.b, "centre of the ball {c:?}");
}

#[test]
fn registry_knows_smoky_glass_and_checks_its_parameters() {
    let reg = registry();
    assert!(reg.contains("smoky_glass") && reg.contains("dielectric"));
    let bad = SCENE.replace("distance = 0.5", "distance = -1");
    let desc = parse_scene(&bad, Path::new("bad.toml")).unwrap();
    let err = match scene_from_desc(desc, &reg) {
        Ok(_) => panic!("a negative distance was accepted"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("bad.toml") && err.contains("distance"),
        "message: {err}"
    );
    // exp(-sigma_a * distance) = color.
    let s = SmokyGlass::sigma_a_for(Rgb::new(0.9, 0.6, 0.3), 0.5);
    let back = s.map(|v| (-v * 0.5).exp());
    assert!((back.r - 0.9).abs() < 1e-6 && (back.b - 0.3).abs() < 1e-6);
}

#[test]
fn smoky_slab_at_normal_incidence_matches_the_airy_sum() {
    // An orthographic camera looks through a smoky-glass slab of thickness d at an emitter L.
    // At normal incidence the Fresnel reflectance is R = ((n - 1) / (n + 1))^2; summing the
    // internal reflections (each round trip R^2 tau^2) the expected radiance is
    // L (1 - R)^2 tau / (1 - R^2 tau^2) with tau = exp(-sigma_a d) (the 1/eta^2 radiance
    // scalings of entering and leaving cancel).
    let (n, d) = (1.5f32, 0.4f32);
    let text = r#"
        [render]
        width = 16
        height = 16
        spp = 16
        max_depth = -1
        rr_depth = 64

        [camera]
        projection = "orthographic"
        width = 1
        from = [0, 0, 5]
        to = [0, 0, 0]

        [materials.smoke]
        type = "smoky_glass"
        ior = 1.5
        color = [0.9, 0.6, 0.3]
        distance = 0.5

        [materials.black]
        type = "diffuse"
        reflectance = 0

        [[shapes]]
        type = "box"
        material = "smoke"
        min = [-3, -3, -0.2]
        max = [3, 3, 0.2]

        [[shapes]]
        type = "quad"
        material = "black"
        emission = [2, 3, 4]
        corner = [-5, -5, -2]
        edge1 = [10, 0, 0]
        edge2 = [0, 10, 0]
    "#;
    let out = render_text(text, "slab.toml").unwrap();
    assert_eq!(out.stats.counters.nan_dropped, 0);
    let r = ((n - 1.0) / (n + 1.0)).powi(2);
    let tau = SmokyGlass::sigma_a_for(Rgb::new(0.9, 0.6, 0.3), 0.5).map(|s| (-s * d).exp());
    let l = Rgb::new(2.0, 3.0, 4.0);
    let expected = Rgb::from_array([0, 1, 2].map(|c| {
        let t = tau.to_array()[c];
        l.to_array()[c] * (1.0 - r).powi(2) * t / (1.0 - r * r * t * t)
    }));
    let (mean, se) = image_mean(&out);
    for c in 0..3 {
        let (m, s, e) = (mean.to_array()[c], se.to_array()[c], expected.to_array()[c]);
        assert!(
            (m - e).abs() <= 4.0 * s + 1e-4 * e,
            "channel {c}: mean {m} +- {s}, expected {e}"
        );
        // The test can fail: the noise is far below the effect of the absorption.
        assert!(s < 0.02 * e, "channel {c}: standard error {s} too large");
    }
}
