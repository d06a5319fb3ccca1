//! Criterion benches of the systems that are not benched elsewhere: camera ray generation,
//! light sampling, partition and splat. Realistic batch size (4096 items), black_box on
//! inputs and outputs, throughput in elements.

use criterion::{black_box, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::{Vec2, Vec3};
use risotto::engine::load::{scene_from_desc, MaterialRegistry};
use risotto::engine::scene_file::load_scene;
use risotto::systems::camera::{generate_camera_rays, Camera, Projection};
use risotto::systems::film::{splat, Film};
use risotto::systems::lights::sample_lights;
use risotto::systems::partition::partition_by_key;
use risotto::systems::sampler::{pixel_seed, sample_1d, sample_2d};
use risotto_components::Rgb;
use std::path::Path;

const N: usize = 4096;

fn camera(c: &mut Criterion) {
    let cam = Camera::look_at(
        Projection::Perspective { fov_deg: 40.0 },
        Vec3::new(0.0, 0.0, 3.9),
        Vec3::ZERO,
        Vec3::Y,
        256,
        256,
    )
    .unwrap();
    let pixel: Vec<u32> = (0..N as u32).map(|i| (i / 16) % (256 * 256)).collect();
    let sample: Vec<u32> = (0..N as u32).map(|i| i % 16).collect();
    let seed: Vec<u32> = pixel.iter().map(|&p| pixel_seed(0, p)).collect();
    let mut origin = vec![Vec3::ZERO; N];
    let mut direction = vec![Vec3::ZERO; N];
    let mut g = c.benchmark_group("camera");
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("perspective_4096", |b| {
        b.iter(|| {
            generate_camera_rays(
                black_box(&cam),
                black_box(&pixel),
                black_box(&sample),
                black_box(&seed),
                &mut origin,
                &mut direction,
            );
            black_box(&direction);
        })
    });
    g.finish();
}

fn lights(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let desc = load_scene(&root.join("scenes/mitsuba-suite/cornell.toml")).unwrap();
    let scene = scene_from_desc(desc, &MaterialRegistry::with_builtins())
        .unwrap()
        .compile()
        .unwrap();
    let p: Vec<Vec3> = (0..N)
        .map(|i| {
            let u = sample_2d(1, i as u32, 0);
            Vec3::new(u.x * 2.0 - 1.0, -1.0, u.y * 2.0 - 1.0)
        })
        .collect();
    let u_select: Vec<f32> = (0..N).map(|i| sample_1d(2, i as u32, 0)).collect();
    let u: Vec<Vec2> = (0..N).map(|i| sample_2d(3, i as u32, 0)).collect();
    let mut out = vec![None; N];
    let mut g = c.benchmark_group("lights");
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("cornell_area_light_4096", |b| {
        b.iter(|| {
            sample_lights(
                &scene.lights,
                &scene.geometry,
                black_box(&p),
                black_box(&u_select),
                black_box(&u),
                &mut out,
            );
            black_box(&out);
        })
    });
    g.finish();
}

fn partition(c: &mut Criterion) {
    let mut g = c.benchmark_group("partition");
    g.throughput(Throughput::Elements(N as u64));
    for keys_n in [2usize, 8] {
        let keys: Vec<u32> = (0..N as u32)
            .map(|i| pixel_seed(5, i) % keys_n as u32)
            .collect();
        let (mut order, mut runs) = (Vec::new(), Vec::new());
        g.bench_with_input(BenchmarkId::new("by_key", keys_n), &keys, |b, keys| {
            b.iter(|| {
                partition_by_key(black_box(keys), keys_n, &mut order, &mut runs);
                black_box(&order);
            })
        });
    }
    g.finish();
}

fn splat_bench(c: &mut Criterion) {
    let mut film = Film::new(256, 256);
    let pixel: Vec<u32> = (0..N as u32).map(|i| (i * 7919) % (256 * 256)).collect();
    let radiance: Vec<Rgb> = (0..N).map(|i| Rgb::splat(i as f32 * 1e-3)).collect();
    let mut g = c.benchmark_group("splat");
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("film_4096", |b| {
        b.iter(|| black_box(splat(&mut film, black_box(&pixel), black_box(&radiance))))
    });
    g.finish();
}

// criterion_group! expands to an undocumented `pub fn`; a private module keeps it out of the
// `missing_docs` lint without an allow attribute.
mod group {
    criterion::criterion_group!(
        benches,
        super::camera,
        super::lights,
        super::partition,
        super::splat_bench
    );
}
criterion_main!(group::benches);
