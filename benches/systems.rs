//! Criterion benches of the systems that are not benched elsewhere: camera ray generation,
//! partition and splat (the tile film and the light tracer's shared `SplatFilm`), the
//! bidirectional integrators' camera connection and hash grid, adaptive sampling's error
//! estimates over a 1920x1080 film (light sampling is in
//! `benches/path.rs`, with the other per-vertex
//! systems). Realistic batch size (4096 items), black_box on
//! inputs and outputs, throughput in elements.

use criterion::{black_box, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::{Vec2, Vec3};
use risotto::systems::adaptive::{pooled_relative_error, windowed_relative_error, Neighbourhood};
use risotto::systems::camera::{generate_camera_rays, Camera, Projection};
use risotto::systems::film::{splat, Film, SplatFilm};
use risotto::systems::hash_grid::HashGrid;
use risotto::systems::partition::partition_by_key;
use risotto::systems::pixel_filter::PixelFilter;
use risotto::systems::sampler::pixel_seed;
use risotto_components::Rgb;

const N: usize = 4096;

fn camera(c: &mut Criterion) {
    let look = |projection| {
        Camera::look_at(
            projection,
            Vec3::new(0.0, 0.0, 3.9),
            Vec3::ZERO,
            Vec3::Y,
            256,
            256,
        )
        .unwrap()
    };
    // The pinhole's SIMD kernel, and the thin lens (rays one at a time, two more sampler
    // dimensions per ray for the lens point).
    let cameras = [
        (
            "perspective_4096",
            look(Projection::Perspective { fov_deg: 40.0 }),
        ),
        (
            "thin_lens_4096",
            look(Projection::ThinLens {
                fov_deg: 40.0,
                aperture_radius: 0.1,
                focus_distance: 3.9,
            }),
        ),
    ];
    let pixel: Vec<u32> = (0..N as u32).map(|i| (i / 16) % (256 * 256)).collect();
    let sample: Vec<u32> = (0..N as u32).map(|i| i % 16).collect();
    let seed: Vec<u32> = pixel.iter().map(|&p| pixel_seed(0, p)).collect();
    let mut origin = vec![Vec3::ZERO; N];
    let mut direction = vec![Vec3::ZERO; N];
    let mut g = c.benchmark_group("camera");
    g.throughput(Throughput::Elements(N as u64));
    for (name, cam) in &cameras {
        g.bench_function(*name, |b| {
            b.iter(|| {
                generate_camera_rays(
                    black_box(cam),
                    black_box(&pixel),
                    black_box(&sample),
                    black_box(&seed),
                    &mut origin,
                    &mut direction,
                );
                black_box(&direction);
            })
        });
    }
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
    // The light tracer's shared film: fixed-point atomic additions (a compare-and-swap per
    // channel) at scattered pixels, one thread; and through a tent filter of radius 1 (four
    // pixels per splat, most of the time).
    let shared = SplatFilm::new(256, 256).unwrap();
    g.bench_function("splat_film_add_4096", |b| {
        b.iter(|| {
            for (&p, &l) in pixel.iter().zip(&radiance) {
                shared.add(black_box(p), black_box(l));
            }
        })
    });
    let films: Vec<Vec2> = pixel
        .iter()
        .map(|&p| Vec2::new((p % 256) as f32 + 0.37, (p / 256) as f32 + 0.61))
        .collect();
    let tent = PixelFilter::Tent { radius: 1.0 };
    g.bench_function("splat_film_add_filtered_tent_4096", |b| {
        b.iter(|| {
            for (&f, &l) in films.iter().zip(&radiance) {
                shared.add_filtered(black_box(&tent), black_box(f), black_box(l));
            }
        })
    });
    black_box(shared.sum(0));
    g.finish();
}

/// The bidirectional integrators' systems: a scene point connected to the camera (light
/// tracing), and the hash grid of light vertices merging builds and queries (4096 points in a
/// unit cube, radius 0.02: a few neighbours each).
fn bidirectional(c: &mut Criterion) {
    let mut g = c.benchmark_group("bidirectional");
    g.throughput(Throughput::Elements(N as u64));
    let camera = Camera::look_at(
        Projection::Perspective { fov_deg: 40.0 },
        Vec3::new(0.0, 0.0, 3.9),
        Vec3::ZERO,
        Vec3::Y,
        256,
        256,
    )
    .unwrap();
    let mut state = 1u64;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 40) as f32) / (1u64 << 24) as f32
    };
    let points: Vec<Vec3> = (0..N).map(|_| Vec3::new(next(), next(), next())).collect();
    let scene_points: Vec<Vec3> = points.iter().map(|p| *p * 2.0 - 1.0).collect();
    g.bench_function("camera_connect_4096", |b| {
        b.iter(|| {
            let mut hits = 0u32;
            for &p in &scene_points {
                hits += camera.connect(black_box(p), Vec2::splat(0.5)).is_some() as u32;
            }
            black_box(hits)
        })
    });
    let mut grid = HashGrid::default();
    g.bench_function("hash_grid_build_4096", |b| {
        b.iter(|| grid.build(black_box(&points), 0.02))
    });
    grid.build(&points, 0.02);
    g.bench_function("hash_grid_query_4096", |b| {
        b.iter(|| {
            let mut found = 0usize;
            for &p in &points {
                grid.query(black_box(p), |_| found += 1);
            }
            black_box(found)
        })
    });
    // An iteration's worth of light vertices (vcm at 256 x 256: about 200,000), several
    // megabytes, so that queries miss the cache as in a render: 4096 queries at other
    // points, about one point within the radius each.
    let many: Vec<Vec3> = (0..1u32 << 18)
        .map(|i| {
            // splitmix64 of (point, axis): uniform in [0, 1).
            let h = |k: u64| {
                let mut z = (u64::from(i) * 3 + k).wrapping_mul(0x9e37_79b9_7f4a_7c15);
                z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
                z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
                ((z ^ (z >> 31)) >> 40) as f32 / (1u32 << 24) as f32
            };
            Vec3::new(h(0), h(1), h(2))
        })
        .collect();
    let mut big = HashGrid::default();
    big.build(&many, 0.01);
    g.bench_function("hash_grid_query_4096_in_262144", |b| {
        b.iter(|| {
            let mut found = 0usize;
            for &p in &points {
                big.query(black_box(p), |_| found += 1);
            }
            black_box(found)
        })
    });
    g.finish();
}

/// Adaptive sampling's per-pass error estimates over a 1920x1080 film: the window rule's
/// 3 x 3 worst, and the unbiased rule's pooled estimates (its pilot's 9 x 9 square, its
/// preceding pixels at radius 8). Throughput in pixels.
fn adaptive(c: &mut Criterion) {
    let (w, h) = (1920usize, 1080usize);
    let value: Vec<[f32; 3]> = (0..w * h)
        .map(|i| [0.2 + (pixel_seed(1, i as u32) % 1000) as f32 * 1e-3; 3])
        .collect();
    let variance: Vec<[f32; 3]> = (0..w * h)
        .map(|i| [(pixel_seed(2, i as u32) % 1000) as f32 * 1e-4; 3])
        .collect();
    let mut error = vec![0.0f32; w * h];
    let mut g = c.benchmark_group("adaptive");
    g.throughput(Throughput::Elements((w * h) as u64));
    g.sample_size(10);
    g.bench_function("windowed_3x3", |b| {
        b.iter(|| {
            windowed_relative_error(
                w,
                h,
                black_box(&value),
                black_box(&variance),
                [0.01; 3],
                &mut error,
            );
            black_box(&error);
        })
    });
    for (name, neighbourhood) in [
        ("pooled_square_r4", Neighbourhood::Square(4)),
        ("pooled_preceding_r8", Neighbourhood::Preceding(8)),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| {
                pooled_relative_error(
                    w,
                    h,
                    black_box(&value),
                    black_box(&variance),
                    neighbourhood,
                    [0.01; 3],
                    &mut error,
                );
                black_box(&error);
            })
        });
    }
    g.finish();
}

// criterion_group! expands to an undocumented `pub fn`; a private module keeps it out of the
// `missing_docs` lint without an allow attribute.
mod group {
    criterion::criterion_group!(
        benches,
        super::camera,
        super::partition,
        super::splat_bench,
        super::bidirectional,
        super::adaptive
    );
}
criterion_main!(group::benches);
