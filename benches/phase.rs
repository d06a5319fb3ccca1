//! Throughput of the volume-scattering math: 4096 phase-function samples and 4096 spectral-MIS
//! free flights per iteration, over columns shaped like the engine's volume batches.

use criterion::{black_box, criterion_main, Criterion, Throughput};
use risotto::components::{Rgb, Vec2, Vec3};
use risotto::systems::bxdf::sample_uniform_sphere;
use risotto::systems::medium::{equiangular_sample, sample_free_flights, FreeFlight};
use risotto::systems::phase::PhaseFunction;
use risotto::systems::sampler::SplitMix64;

const N: usize = 4096;

fn bench_phase(c: &mut Criterion) {
    let mut rng = SplitMix64(0xF10A7);
    let u: Vec<Vec2> = (0..N).map(|_| rng.vec2()).collect();
    let u_lobe: Vec<f32> = (0..N).map(|_| rng.f32()).collect();
    let wo: Vec<Vec3> = (0..N).map(|_| sample_uniform_sphere(rng.vec2())).collect();
    let mut out_dir: Vec<(Vec3, f32)> = vec![(Vec3::ZERO, 0.0); N];

    let mut group = c.benchmark_group("phase");
    group.throughput(Throughput::Elements(N as u64));
    for (name, phase) in [
        ("hg_sample_g0.9", PhaseFunction::HenyeyGreenstein { g: 0.9 }),
        (
            "double_hg_sample",
            PhaseFunction::DoubleHenyeyGreenstein {
                g1: 0.8,
                g2: -0.3,
                blend: 0.7,
            },
        ),
    ] {
        group.bench_function(name, |b| {
            b.iter(|| {
                let phase = black_box(phase);
                for i in 0..N {
                    out_dir[i] = phase.sample(wo[i], u[i], u_lobe[i]);
                }
                black_box(&out_dir);
            })
        });
    }

    // hg_sphere's chromatic medium; throughputs that have drifted apart per channel, and
    // a mix of bounded and unbounded segments.
    let sigma_t = Rgb::new(1.0, 2.0, 4.0);
    let sigma_s = sigma_t * 0.8;
    let throughput: Vec<Rgb> = (0..N)
        .map(|_| Rgb::new(rng.f32(), rng.f32(), rng.f32()))
        .collect();
    let u_channel: Vec<f32> = (0..N).map(|_| rng.f32()).collect();
    let u_distance: Vec<f32> = (0..N).map(|_| rng.f32()).collect();
    let tmax: Vec<f32> = (0..N)
        .map(|i| {
            if i % 4 == 0 {
                f32::INFINITY
            } else {
                2.0 * rng.f32()
            }
        })
        .collect();
    let mut flights = vec![FreeFlight::default(); N];
    group.bench_function("free_flight_spectral_mis", |b| {
        b.iter(|| {
            sample_free_flights(
                black_box(sigma_t),
                sigma_s,
                &throughput,
                &u_channel,
                &u_distance,
                &tmax,
                &mut flights,
            );
            black_box(&flights);
        })
    });

    let light = Vec3::new(0.3, 2.0, -0.5);
    let mut out_t: Vec<(f32, f32)> = vec![(0.0, 0.0); N];
    group.bench_function("equiangular_sample", |b| {
        b.iter(|| {
            for i in 0..N {
                out_t[i] =
                    equiangular_sample(Vec3::ZERO, wo[i], black_box(light), tmax[i], u_lobe[i]);
            }
            black_box(&out_t);
        })
    });
    group.finish();
}

// criterion_group! expands to an undocumented `pub fn`; a private module keeps it out of the
// `missing_docs` lint without an allow attribute.
mod group {
    criterion::criterion_group!(benches, super::bench_phase);
}
criterion_main!(group::benches);
