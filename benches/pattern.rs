//! Throughput of pattern evaluation (`risotto_systems::pattern::eval_with`): 4096 shading
//! points per iteration, a column shaped like a shade group, one graph per node kind that
//! costs something (noise octaves, the image lookup, the grid lookup) and the composite of
//! `scenes/patterns.toml`'s floor; plus the interval bounds over the cells of a coarse grid.

use criterion::{black_box, criterion_main, Criterion, Throughput};
use risotto::components::{Rgb, Vec3};
use risotto::systems::grid::DensityGrid;
use risotto::systems::pattern::{
    bounds, eval_with, Axis, Fbm, GridBorder, Node, PatternGraph, Space, Texture,
};
use risotto::systems::sampler::SplitMix64;
use std::sync::Arc;

const N: usize = 4096;

fn graphs() -> Vec<(&'static str, PatternGraph)> {
    let noise = |octaves| Node::Noise(Fbm::new(3.0, octaves, 2.0, 0.5, 3).unwrap());
    let texels = (0..64 * 64)
        .map(|i| Rgb::new((i % 64) as f32 / 64.0, (i / 64) as f32 / 64.0, 0.5))
        .collect();
    let texture = Texture::new(64, 64, texels).unwrap();
    let data = (0..32 * 32 * 32).map(|i| (i % 17) as f32).collect();
    let grid = DensityGrid::new([32, 32, 32], data).unwrap();
    let g = |nodes| PatternGraph::new(nodes).unwrap();
    vec![
        ("constant", g(vec![Node::Constant(Rgb::splat(0.5))])),
        ("noise_1_octave", g(vec![noise(1)])),
        ("fbm_5_octaves", g(vec![noise(5)])),
        (
            "image_bilinear",
            g(vec![Node::Image(Arc::new(texture), Default::default())]),
        ),
        (
            "grid_trilinear",
            g(vec![Node::Grid {
                grid: Arc::new(grid),
                min: Vec3::splat(-2.0),
                max: Vec3::splat(2.0),
                to_box: None,
                border: GridBorder::Clamp,
            }]),
        ),
        (
            "floor_mix_checker_remap_fbm",
            g(vec![
                Node::Checker {
                    scale: 2.0,
                    a: Rgb::new(0.75, 0.72, 0.65),
                    b: Rgb::new(0.2, 0.25, 0.35),
                    space: Space::P,
                },
                Node::Constant(Rgb::new(0.08, 0.07, 0.06)),
                noise(5),
                Node::Remap {
                    a: 2,
                    from: [0.2, 1.0],
                    to: [0.0, 0.8],
                },
                Node::Mix { a: 0, b: 1, t: 3 },
            ]),
        ),
        (
            "gradient_times_checker",
            g(vec![
                Node::Gradient {
                    axis: Axis::Y,
                    from: 0.0,
                    to: 1.0,
                    a: Rgb::BLACK,
                    b: Rgb::WHITE,
                },
                Node::Checker {
                    scale: 8.0,
                    a: Rgb::splat(0.2),
                    b: Rgb::splat(0.9),
                    space: Space::Uv,
                },
                Node::Multiply { a: 0, b: 1 },
            ]),
        ),
    ]
}

fn bench_pattern(c: &mut Criterion) {
    let mut rng = SplitMix64(0x9A77);
    let p: Vec<Vec3> = (0..N)
        .map(|_| (Vec3::new(rng.f32(), rng.f32(), rng.f32()) - 0.5) * 4.0)
        .collect();
    let u: Vec<f32> = (0..N).map(|_| rng.f32()).collect();
    let v: Vec<f32> = (0..N).map(|_| rng.f32()).collect();
    let mut out = vec![Rgb::BLACK; N];
    let graphs = graphs();
    let mut group = c.benchmark_group("pattern");
    group.throughput(Throughput::Elements(N as u64));
    for (name, graph) in &graphs {
        let mut scratch = vec![Rgb::BLACK; graph.scratch_len(N)];
        group.bench_function(*name, |b| {
            b.iter(|| {
                eval_with(black_box(graph), &p, &u, &v, &mut out, &mut scratch);
                black_box(&out);
            })
        });
    }
    group.finish();

    // Bounds over the 16^3 cells of a majorant grid on [-2, 2]^3 (per cell, not per point).
    let mut group = c.benchmark_group("pattern_bounds");
    group.throughput(Throughput::Elements(16 * 16 * 16));
    let (_, floor) = &graphs[5];
    group.bench_function("floor_16x16x16_cells", |b| {
        b.iter(|| {
            let mut hi = 0.0f32;
            for cell in 0..16 * 16 * 16 {
                let c = Vec3::new(
                    (cell % 16) as f32,
                    ((cell / 16) % 16) as f32,
                    (cell / 256) as f32,
                );
                let lo = c * 0.25 - 2.0;
                hi = hi.max(bounds(black_box(floor), lo, lo + 0.25).1.r);
            }
            black_box(hi)
        })
    });
    group.finish();
}

// criterion_group! expands to an undocumented `pub fn`; a private module keeps it out of the
// `missing_docs` lint without an allow attribute.
mod group {
    criterion::criterion_group!(benches, super::bench_pattern);
}
criterion_main!(group::benches);
