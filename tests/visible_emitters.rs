//! Emitters seen directly from the camera take `K + 1` pixel points per path sample
//! (`risotto::engine::path_tracer::visible_emitters`): the shares add up to the emission,
//! the extra points fall elsewhere in the pixel, and the estimate of an edge stays unbiased.

mod common;
use common::*;
use glam::Vec3;
use risotto::builtins::builtin::Surface;
use risotto::engine::path_tracer::visible_emitters::EXTRA_CAMERA_SAMPLES;
use risotto::engine::render::RenderOutput;
use risotto::engine::scene::Scene;
use risotto::engine::stats::System;
use risotto_components::Rgb;

const LE: f32 = 4.0;

/// `width` x 256 pixels of an orthographic view 2 units wide looking down -z at an emitter
/// facing the camera over `x < edge` and one facing away over `x > edge`, nothing behind;
/// one segment per path, so the image is the directly visible emission alone.
fn render_edge(width: u32, edge: f32, spp: u32) -> RenderOutput {
    let h = 256;
    let view = ortho_camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 2.0, width, h);
    let mut scene = Scene::new(view, settings(width, h, spp, 1));
    let black = scene.add_material(
        "black",
        0,
        mat(Surface::Diffuse {
            reflectance: Rgb::BLACK,
        }),
    );
    // The view is 2 units wide and 128 tall (square pixels).
    let tall = Vec3::Y * 200.0;
    // Front face along e1 x e2 = x x y = +z, towards the camera.
    let front = quad(Vec3::new(-2.0, -100.0, 0.0), Vec3::X * (edge + 2.0), tall);
    scene.add_shape("front", front, black, Some(Rgb::splat(LE)));
    // e1 x e2 = y x x = -z: its back faces the camera.
    let back = quad(Vec3::new(edge, -100.0, 0.0), tall, Vec3::X * (2.0 - edge));
    scene.add_shape("back", back, black, Some(Rgb::splat(LE)));
    render_default(&scene.compile().unwrap())
}

#[test]
fn an_emitter_filling_the_pixel_gives_its_emission_exactly() {
    const { assert!(EXTRA_CAMERA_SAMPLES > 0, "the extra camera samples are off") };
    let out = render_edge(4, 0.15, 1);
    for y in 0..256 {
        for (x, want) in [(0, LE), (1, LE), (3, 0.0)] {
            let v = out.beauty.get(x, y);
            assert!(
                (v.r - want).abs() <= 1e-5 * LE,
                "pixel ({x}, {y}) = {v:?}, want {want}: the camera rays' shares do not add up"
            );
        }
    }
}

#[test]
fn an_edge_pixel_counts_every_camera_point_of_the_sample() {
    // Column 2 spans x in [0, 0.5): the edge at 0.15 covers 0.3 of it.
    let out = render_edge(4, 0.15, 1);
    let k = (EXTRA_CAMERA_SAMPLES + 1) as f32;
    let values: Vec<f32> = (0..256).map(|y| out.beauty.get(2, y).r / LE).collect();
    for (y, v) in values.iter().enumerate() {
        // One path sample: a multiple of 1 / (K + 1) of the emission.
        assert!(
            ((v * k).round() - v * k).abs() < 1e-4,
            "row {y}: {v} is not a count of {k} camera points"
        );
    }
    // With the path's own point alone every value would be 0 or 1.
    assert!(
        values.iter().any(|&v| v > 0.01 && v < 0.99),
        "no edge pixel between 0 and the emission: the extra points are not used"
    );
    // Each pixel's estimate is unbiased: their mean is the covered fraction. Per pixel the
    // (0, 2)-net's four x strata leave a variance of at most 0.25^2 / 4, so the standard
    // error of the mean of 256 is below 0.008.
    let mean = values.iter().sum::<f32>() / values.len() as f32;
    assert!((mean - 0.3).abs() < 0.03, "mean coverage {mean}, want 0.3");
}

#[test]
fn more_samples_keep_the_edge_unbiased() {
    let out = render_edge(4, 0.15, 16);
    let mean = (0..256).map(|y| out.beauty.get(2, y).r / LE).sum::<f32>() / 256.0;
    assert!((mean - 0.3).abs() < 0.01, "mean coverage {mean}, want 0.3");
}

#[test]
fn the_paths_technique_leaves_the_emission_to_the_paths_own_camera_rays() {
    use risotto::engine::path_tracer::visible_emitters::VisibleEmitters;
    use risotto::engine::render::{render, RenderOptions};
    let h = 256;
    let view = ortho_camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 2.0, 4, h);
    let mut scene = Scene::new(view, settings(4, h, 1, 1));
    let black = scene.add_material(
        "black",
        0,
        mat(Surface::Diffuse {
            reflectance: Rgb::BLACK,
        }),
    );
    let tall = Vec3::Y * 200.0;
    let front = quad(Vec3::new(-2.0, -100.0, 0.0), Vec3::X * 2.15, tall);
    scene.add_shape("front", front, black, Some(Rgb::splat(LE)));
    let compiled = scene.compile().unwrap();
    let options = RenderOptions {
        visible_emitters: VisibleEmitters::Paths,
        ..RenderOptions::default()
    };
    let out = render(&compiled, &options, &|_| {}).unwrap();
    // One camera point per pixel sample: the edge column is the emission or nothing.
    for y in 0..h as usize {
        let v = out.beauty.get(2, y).r;
        assert!(v == 0.0 || (v - LE).abs() <= 1e-5 * LE, "row {y}: {v}");
    }
    // The stats show it: one camera ray per path, against K + 1 when supersampled.
    let camera = |o: &RenderOutput| o.stats.counters.system(System::Camera).items;
    let pixels = u64::from(4 * h);
    assert_eq!(camera(&out), pixels);
    let supersampled = render(&compiled, &RenderOptions::default(), &|_| {}).unwrap();
    assert_eq!(
        camera(&supersampled),
        pixels * u64::from(EXTRA_CAMERA_SAMPLES + 1)
    );
}

/// A small emitter off the centre of a perspective view, seen through a box filter of
/// radius 3 (a pixel's camera points fall up to two and a half pixels past its square):
/// only the pixels whose rays may reach it take the extra camera points (the stats count
/// them), and none that sees it is left out: the image's total emission is the same as
/// from the paths' own camera rays alone (`VisibleEmitters::Paths`). Leaving out the pixels
/// that see the emitter only through their filter's reach would take three quarters of
/// their share away.
#[test]
fn only_the_pixels_near_a_small_emitter_take_the_extra_points_and_all_that_see_it_do() {
    use risotto::engine::path_tracer::visible_emitters::VisibleEmitters;
    use risotto::engine::render::{render, RenderOptions};
    use risotto::systems::camera::PixelFilter;
    let (w, h, spp) = (64, 48, 64);
    let view = perspective(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, 40.0, w, h)
        .with_filter(PixelFilter::Box { radius: 3.0 });
    let mut scene = Scene::new(view, settings(w, h, spp, 1));
    let black = scene.add_material(
        "black",
        0,
        mat(Surface::Diffuse {
            reflectance: Rgb::BLACK,
        }),
    );
    // Facing the camera (e1 x e2 = +z), about 5 x 5 pixels, up and right of the centre.
    let lamp = quad(Vec3::new(0.6, 0.4, 0.0), Vec3::X * 0.3, Vec3::Y * 0.3);
    scene.add_shape("lamp", lamp, black, Some(Rgb::splat(LE)));
    let compiled = scene.compile().unwrap();
    let total = |out: &RenderOutput| {
        let mut sum = 0.0f64;
        for y in 0..h as usize {
            for x in 0..w as usize {
                sum += f64::from(out.beauty.get(x, y).r);
            }
        }
        sum
    };
    let paths_only = RenderOptions {
        visible_emitters: VisibleEmitters::Paths,
        ..RenderOptions::default()
    };
    let reference = total(&render(&compiled, &paths_only, &|_| {}).unwrap());
    let out = render(&compiled, &RenderOptions::default(), &|_| {}).unwrap();
    let supersampled = total(&out);
    assert!(reference > 0.0);
    assert!(
        (supersampled / reference - 1.0).abs() < 0.02,
        "total emission {supersampled} with the extra points, {reference} without"
    );
    // The extra points of the pixels near the lamp alone: more camera rays than paths, far
    // fewer than K + 1 a path.
    let paths = u64::from(w * h * spp);
    let camera = out.stats.counters.system(System::Camera).items;
    assert!(
        camera > paths && camera < paths + paths / 4,
        "{camera} camera points for {paths} paths"
    );
}
