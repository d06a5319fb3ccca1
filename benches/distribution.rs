//! Environment-map importance sampling throughput: 4096 direction samples per iteration
//! from a 512x256 equirectangular map (sky gradient plus a small bright sun), looked up
//! nearest-texel and unrotated (the original map), and bilinearly under a rotation (the
//! scene file's default filter with a `transform`).
#![allow(
    missing_docs,
    reason = "criterion's macros generate undocumented items"
)]

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use glam::{Mat3, Vec3};
use risotto::components::{Rgb, Vec2};
use risotto::systems::environment_map::{EnvFilter, EnvironmentMap};

const W: usize = 512;
const H: usize = 256;
const N: usize = 4096;

fn sky_map(filter: EnvFilter, to_world: Mat3) -> EnvironmentMap {
    let mut px = Vec::with_capacity(W * H);
    for y in 0..H {
        for x in 0..W {
            let t = y as f32 / H as f32;
            let mut p = if t < 0.5 {
                Rgb::new(0.3, 0.5, 1.0) * (1.0 - t)
            } else {
                Rgb::splat(0.1)
            };
            // a 4x4-texel sun, ~10^4 brighter than the sky
            if (300..304).contains(&x) && (60..64).contains(&y) {
                p = Rgb::new(5000.0, 4500.0, 4000.0);
            }
            px.push(p);
        }
    }
    EnvironmentMap::with_filter(px, W, H, filter, to_world)
}

/// Low-discrepancy-ish inputs: the 2D R2 sequence (Roberts 2018), precomputed so the bench
/// measures sampling only.
fn inputs() -> Vec<Vec2> {
    let g = 1.324_717_957_244_746_f64;
    let (a1, a2) = (1.0 / g, 1.0 / (g * g));
    (0..N)
        .map(|i| {
            let i = i as f64;
            Vec2::new((0.5 + a1 * i).fract() as f32, (0.5 + a2 * i).fract() as f32)
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let tilt = Mat3::from_axis_angle(Vec3::new(0.6, 0.8, 0.0), 1.2);
    let cases = [
        ("", EnvFilter::Nearest, Mat3::IDENTITY),
        ("bilinear_rotated_", EnvFilter::Bilinear, tilt),
    ];
    let us = inputs();
    for (tag, filter, to_world) in cases {
        let map = sky_map(filter, to_world);
        let mut group = c.benchmark_group("env_map");
        group.throughput(Throughput::Elements(N as u64));
        group.bench_function(format!("{tag}sample_4096_512x256"), |b| {
            b.iter(|| {
                let mut acc = 0.0f32;
                for &u in &us {
                    let (dir, l, pdf) = map.sample(black_box(u));
                    acc += dir.x + l.r + pdf;
                }
                black_box(acc)
            })
        });
        let dirs: Vec<_> = us.iter().map(|&u| map.sample(u).0).collect();
        group.bench_function(format!("{tag}pdf_4096_512x256"), |b| {
            b.iter(|| {
                let mut acc = 0.0f32;
                for &d in &dirs {
                    acc += map.pdf(black_box(d));
                }
                black_box(acc)
            })
        });
        group.bench_function(format!("{tag}eval_4096_512x256"), |b| {
            b.iter(|| {
                let mut acc = 0.0f32;
                for &d in &dirs {
                    acc += map.eval(black_box(d)).g;
                }
                black_box(acc)
            })
        });
        group.finish();
        c.bench_function(&format!("env_map/{tag}build_512x256"), |b| {
            b.iter(|| sky_map(filter, to_world))
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
