//! Reproducibility: every sample's random numbers depend only on (seed, pixel, sample index,
//! dimension), and each pixel's samples reach the film in sample order, so the image must be
//! bit-identical whatever the thread count, batch size or tiling; the seed must matter.

mod common;
use common::*;
use glam::Vec3;
use risotto::builtins::builtin::{Interior, Surface};
use risotto::engine::integrator::LightingTechnique;
use risotto::engine::render::{render, RenderError, RenderOptions, RenderOutput, MAX_THREADS};
use risotto::engine::scene::{CompiledScene, Scene, ShapeGeometry};
use risotto::systems::geometry::Sphere;
use risotto_components::Rgb;

/// A scene that exercises most stages: diffuse and absorbing-glass surfaces, an area light, an
/// environment, Russian roulette after two bounces, an odd image size (partial tiles).
fn scene(seed: u64) -> CompiledScene {
    let (w, h) = (21, 19);
    let cam = perspective(
        Vec3::new(0.0, 1.0, 3.0),
        Vec3::new(0.0, 0.5, 0.0),
        45.0,
        w,
        h,
    );
    let mut scene = Scene::new(cam, settings(w, h, 64, 12));
    scene.settings.seed = seed;
    scene.settings.rr_depth = 2;
    let white = scene.add_material(
        "white",
        0,
        mat(Surface::Diffuse {
            reflectance: Rgb::new(0.7, 0.6, 0.5),
        }),
    );
    let black = scene.add_material(
        "emitter",
        0,
        mat(Surface::Diffuse {
            reflectance: Rgb::BLACK,
        }),
    );
    let glass = scene.add_material(
        "glass",
        0,
        mat_in(
            Surface::Dielectric {
                ior: 1.5,
                tint: Rgb::WHITE,
                cheap_shadows: false,
            },
            Interior::Beer {
                sigma_a: Rgb::new(0.2, 0.8, 1.6),
            },
        ),
    );
    let c = Vec3::new(-3.0, 0.0, -3.0);
    scene.add_shape("floor", quad(c, 6.0 * Vec3::Z, 6.0 * Vec3::X), white, None);
    scene.add_shape(
        "ball",
        ShapeGeometry::Sphere(Sphere {
            center: Vec3::new(-0.3, 0.5, 0.0),
            radius: 0.5,
        }),
        glass,
        None,
    );
    scene.add_shape(
        "diffuse_ball",
        ShapeGeometry::Sphere(Sphere {
            center: Vec3::new(0.7, 0.3, -0.4),
            radius: 0.3,
        }),
        white,
        None,
    );
    scene.add_shape(
        "lamp",
        quad(Vec3::new(-0.5, 2.0, -0.5), Vec3::X, Vec3::Z),
        black,
        Some(Rgb::splat(8.0)),
    );
    environment(&mut scene, Rgb::new(0.2, 0.3, 0.4));
    scene.compile().unwrap()
}

fn run(scene: &CompiledScene, threads: usize, batch_size: usize, tile_size: u32) -> RenderOutput {
    let options = RenderOptions {
        threads: Some(threads),
        batch_size,
        tile_size,
        technique: LightingTechnique::Mis,
        ..RenderOptions::default()
    };
    render(scene, &options, &|_| {}).unwrap()
}

fn bits(out: &RenderOutput) -> Vec<u32> {
    out.beauty
        .pixels
        .iter()
        .chain(&out.variance.pixels)
        .flat_map(|p| p.to_array())
        .chain(out.sample_count.iter().copied())
        .map(f32::to_bits)
        .collect()
}

#[test]
fn thread_count_batch_size_and_tiling_do_not_change_the_image() {
    let s = scene(7);
    let reference = run(&s, 1, 4096, 16);
    // The scene really is lit and has a glass volume (not a trivially black image).
    assert!(reference.beauty.pixels.iter().all(|p| p.is_finite()));
    let (mean, _) = image_mean(&reference);
    assert!(mean.average() > 0.05, "{mean:?}");
    assert!(reference.stats.features.iter().any(|f| f == "volumes"));
    let expected = bits(&reference);
    for (threads, batch, tile) in [(2, 4096, 16), (2, 97, 16), (1, 1, 16), (2, 1000, 7)] {
        let other = run(&s, threads, batch, tile);
        assert!(
            bits(&other) == expected,
            "threads {threads}, batch {batch}, tile {tile}: image differs"
        );
        assert_eq!(
            other.stats.counters.samples,
            reference.stats.counters.samples
        );
        assert_eq!(other.stats.counters.rays, reference.stats.counters.rays);
    }
}

#[test]
fn a_different_seed_gives_a_different_image() {
    let a = run(&scene(7), 2, 4096, 16);
    let b = run(&scene(8), 2, 4096, 16);
    let differing = a
        .beauty
        .pixels
        .iter()
        .zip(&b.beauty.pixels)
        .filter(|(x, y)| x != y)
        .count();
    // Nearly every pixel is noisy (only pixels that see the uniform sky straight on agree).
    let n = a.beauty.pixels.len();
    assert!(differing * 2 > n, "only {differing} of {n} pixels differ");
    // ... but both estimate the same image.
    let ((ma, sa), (mb, sb)) = (image_mean(&a), image_mean(&b));
    for c in 0..3 {
        let se = (sa.to_array()[c].powi(2) + sb.to_array()[c].powi(2)).sqrt();
        assert!((ma.to_array()[c] - mb.to_array()[c]).abs() <= 4.0 * se);
    }
}

/// A thread count the machine cannot start is an error for a library caller, not an abort
/// (100 000 threads aborted the process when their stacks ran out).
#[test]
fn an_impossible_thread_count_is_an_error() {
    let s = scene(7);
    for threads in [0, MAX_THREADS + 1, 100_000] {
        let options = RenderOptions {
            threads: Some(threads),
            ..RenderOptions::default()
        };
        match render(&s, &options, &|_| {}) {
            Err(e @ RenderError::ThreadPool { .. }) => {
                let message = e.to_string();
                assert!(message.contains(&threads.to_string()), "{message}");
                assert!(message.contains(&MAX_THREADS.to_string()), "{message}");
            }
            Err(e) => panic!("{threads} threads: {e}"),
            Ok(_) => panic!("{threads} threads rendered"),
        }
    }
}
