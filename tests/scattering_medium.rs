//! The `scattering_medium` example's medium (free flights returned as `VolumeScatter` points,
//! an HG phase function, exact transmission): a white furnace and the example scene.

mod common;
#[path = "../examples/scattering_medium.rs"]
mod example;

use common::*;
use example::{render_scene, smoke_scene, Smoke, SMOKE};
use glam::Vec3;
use risotto::engine::scene::{Scene, ShapeGeometry};
use risotto::systems::geometry::Sphere;
use risotto_components::Rgb;

#[test]
fn an_albedo_one_smoke_ball_vanishes_in_a_white_furnace() {
    // Albedo 1 behind an index-matched sphere under a constant environment of radiance 1:
    // every path ends in the environment with weight 1, whatever it scattered on the way.
    let smoke = Smoke {
        sigma_t: Rgb::new(1.0, 2.0, 4.0),
        sigma_s: Rgb::new(1.0, 2.0, 4.0),
        g: 0.5,
    };
    let (w, h) = (16, 16);
    let mut s = settings(w, h, 64, 1000);
    s.rr_depth = 1000;
    let mut scene = Scene::new(camera(40.0, 3.5, w, h), s);
    let m = scene.add_material("smoke", 0, Box::new(smoke));
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
    let out = render_default(&scene.compile().unwrap());
    assert_eq!(out.stats.counters.nan_dropped, 0);
    assert!(
        out.stats
            .counters
            .system(risotto::engine::stats::System::Volume)
            .calls
            > 0,
        "the medium was never entered"
    );
    let (mean, se) = image_mean(&out);
    eprintln!("furnace: {mean:?} +- {se:?}");
    for c in 0..3 {
        let (m, s) = (mean.to_array()[c], se.to_array()[c]);
        assert!((m - 1.0).abs() <= 3.0 * s + 1e-5, "channel {c}: {m} +- {s}");
        assert!(
            s < 0.01,
            "channel {c}: standard error {s} too large to tell"
        );
    }
    // Per 4 x 4 block, each channel within 3 sigma of 1 (pixels that see only the
    // environment are exactly 1).
    for by in 0..4 {
        for bx in 0..4 {
            let (m, s) = crop_mean(&out, bx * 4..bx * 4 + 4, by * 4..by * 4 + 4);
            for c in 0..3 {
                let (m, s) = (m.to_array()[c], s.to_array()[c]);
                assert!(
                    (m - 1.0).abs() <= 3.0 * s + 1e-5,
                    "block ({bx}, {by}) channel {c}: {m} +- {s}"
                );
            }
        }
    }
}

#[test]
fn the_example_scene_renders_a_visible_smoke_ball() {
    let out = render_scene(&smoke_scene(SMOKE, 40, 30, 8));
    assert_eq!(out.stats.counters.nan_dropped, 0);
    assert!(out.beauty.pixels.iter().all(|p| p.is_finite()));
    // The ball (image centre) is lit smoke: brighter than the sky behind it at the top.
    let (ball, _) = crop_mean(&out, 18..22, 12..16);
    let (sky, _) = crop_mean(&out, 0..40, 0..2);
    assert!(
        ball.average() > 1.15 * sky.average(),
        "ball {ball:?}, sky {sky:?}"
    );
}
