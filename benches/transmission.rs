//! Transmission system bench: `engine::transmission::trace_shadow_rays` on 4096 shadow rays
//! per iteration, throughput in shadow rays.
//!
//! The rays are made the way the path tracer makes them: camera rays hit the scene, and from
//! every hit on a surface outside all volumes a light sample gives a shadow ray towards the
//! light. Three scenes cover the system's three regimes:
//! - `opaque`: `scenes/mitsuba-suite/cornell.toml`, opaque surfaces only, so shadow rays take
//!   the any-hit fast path;
//! - `absorbers`: `scenes/overlapping-absorbers.toml`, index-matched boundaries with Beer
//!   interiors, so every shadow ray walks surface to surface and each interval inside a
//!   volume is attenuated by that volume's integrator;
//! - `glass`: `scenes/mitsuba-suite/glass_beer.toml`, a dielectric with a Beer interior whose
//!   surface blocks shadow rays (the walk stops at the glass).

mod common;
use bumpalo::Bump;
use common::compile;
use criterion::{black_box, criterion_main, Criterion, Throughput};
use glam::{Vec2, Vec3};
use risotto::engine::integrator::PathBatch;
use risotto::engine::scene::CompiledScene;
use risotto::engine::stats::SystemStats;
use risotto::engine::transmission::trace_shadow_rays;
use risotto::systems::camera::generate_camera_rays;
use risotto::systems::intersect::intersect_closest;
use risotto::systems::sampler::{pixel_seed, sample_4d};
use risotto_components::{Paths, Rgb, ShadowRayRow, ShadowRays, NO_HIT};

const N: usize = 4096;

/// `N` shadow rays from camera hits on surfaces outside every volume towards light samples.
fn shadow_rays(scene: &CompiledScene) -> ShadowRays {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let mut shadow = ShadowRays::default();
    let mut batch = 0u32;
    while shadow.len() < N {
        // One camera sample per pixel of a strided subset, a new sample index per round.
        let pixel: Vec<u32> = (0..N as u32).map(|i| (i * 7919) % (w * h)).collect();
        let sample = vec![batch; N];
        let seed: Vec<u32> = pixel.iter().map(|&p| pixel_seed(1, p)).collect();
        let (mut origin, mut direction) = (vec![Vec3::ZERO; N], vec![Vec3::Z; N]);
        generate_camera_rays(
            &scene.camera,
            &pixel,
            &sample,
            &seed,
            &mut origin,
            &mut direction,
        );
        let (mut t, mut prim, mut b1, mut b2) =
            (vec![0.0; N], vec![NO_HIT; N], vec![0.0; N], vec![0.0; N]);
        intersect_closest(
            &scene.geometry,
            &origin,
            &direction,
            &vec![0.0; N],
            &vec![f32::INFINITY; N],
            &mut t,
            &mut prim,
            &mut b1,
            &mut b2,
        );
        for i in 0..N {
            if prim[i] == NO_HIT || shadow.len() == N {
                continue;
            }
            let shape = scene.prim_shape[prim[i] as usize];
            if scene.tracks_interior(shape) {
                continue;
            }
            let s = scene
                .geometry
                .surface_at(prim[i], origin[i], direction[i], t[i], b1[i], b2[i]);
            let [u0, u1, sel, _] = sample_4d(seed[i], batch, 1);
            let Some(ls) = scene
                .lights
                .sample(&scene.geometry, s.p, sel, Vec2::new(u0, u1))
            else {
                continue;
            };
            let side = if ls.wi.dot(s.ng) >= 0.0 { s.ng } else { -s.ng };
            let offset = s.p.abs().max_element() * 4e-6 + 1e-9;
            shadow.push(ShadowRayRow {
                origin: s.p + side * offset,
                direction: ls.wi,
                tmax: if ls.distance.is_finite() {
                    ls.distance * (1.0 - 1e-4) - offset
                } else {
                    f32::INFINITY
                },
                contribution: Rgb::WHITE,
                weight: Rgb::WHITE,
                path: shadow.len() as u32,
                dimension: 8,
                volume_stack: scene.camera_stack.clone(),
            });
        }
        batch += 1;
    }
    shadow
}

fn bench_transmission(c: &mut Criterion) {
    let mut g = c.benchmark_group("transmission");
    g.throughput(Throughput::Elements(N as u64));
    for (name, file) in [
        ("opaque", "scenes/mitsuba-suite/cornell.toml"),
        ("absorbers", "scenes/overlapping-absorbers.toml"),
        ("glass", "scenes/mitsuba-suite/glass_beer.toml"),
    ] {
        let scene = compile(file);
        let shadow = shadow_rays(&scene);
        // The walk may draw samples for volume integrators; they are addressed by path.
        let mut paths = Paths::default();
        for i in 0..N as u32 {
            paths.push(risotto_components::PathRow {
                pixel: i,
                sample: 0,
                radiance: Rgb::BLACK,
                albedo: Rgb::BLACK,
                normal: Vec3::ZERO,
                depth: f32::INFINITY,
            });
        }
        let seeds: Vec<u32> = (0..N as u32).map(|p| pixel_seed(1, p)).collect();
        let batch = PathBatch {
            paths,
            seeds,
            trace: None,
        };
        let mut contribution = vec![Rgb::WHITE; N];
        let mut stats = SystemStats::default();
        let mut arena = Bump::new();
        // The workload mix, for reading the figure: how many shadow rays reach the light.
        trace_shadow_rays(
            &scene,
            &shadow,
            &batch,
            Default::default(),
            &mut contribution,
            &mut stats,
            &arena,
        );
        let lit = contribution.iter().filter(|c| !c.is_black()).count();
        eprintln!("transmission/{name}: {lit} of {N} shadow rays reach the light");
        arena.reset();
        g.bench_function(name, |b| {
            b.iter(|| {
                contribution.copy_from_slice(&shadow.contribution);
                trace_shadow_rays(
                    black_box(&scene),
                    black_box(&shadow),
                    &batch,
                    Default::default(),
                    &mut contribution,
                    &mut stats,
                    &arena,
                );
                arena.reset();
                black_box(&contribution);
            })
        });
    }
    g.finish();
}

// criterion_group! expands to an undocumented `pub fn`; a private module keeps it out of the
// `missing_docs` lint without an allow attribute.
mod group {
    criterion::criterion_group!(benches, super::bench_transmission);
}
criterion_main!(group::benches);
