//! Throughput of the heterogeneous-media systems, each alone: the majorant-grid DDA, delta
//! tracking of free flights, delta / ratio / residual ratio tracking of transmittance,
//! spectral tracking of a chromatic medium, and fixed-step and unbiased ray marching.
//!
//! The medium is `hetero_grid`'s (`scenes/mitsuba-suite/hetero_grid.toml`): its 64^3
//! density in the unit cube, `sigma_t = 10 density`, a 16^3 majorant grid as the engine
//! builds by default, and for comparison one global majorant (Mitsuba's). 4096 rays per
//! iteration from outside the cube through random points inside it, in the cube's
//! coordinates (the grid space the engine tracks in; the cube is one world unit wide there).

use criterion::{black_box, criterion_main, Criterion, Throughput};
use risotto::components::{Rgb, Vec3};
use risotto::loader::grid_file::read_grid;
use risotto::systems::bxdf::sample_uniform_sphere;
use risotto::systems::grid::{DensityGrid, MajorantGrid, MajorantSegment};
use risotto::systems::ray_marching::{ray_marching_transmittance, unbiased_ray_marching};
use risotto::systems::sampler::SplitMix64;
use risotto::systems::spectral_tracking::spectral_tracking;
use risotto::systems::tracking::{
    delta_tracking, delta_tracking_transmittance, ratio_tracking, residual_ratio_tracking,
};
use std::path::Path;

const N: usize = 4096;
/// `hetero_grid`'s density scale: `sigma_t = SCALE * density`.
const SCALE: f32 = 10.0;
/// The engine's default majorant resolution per axis.
const MAJORANT_RES: usize = 16;

/// Rays `(origin, unit direction)` from a sphere of radius 2 around the cube's centre
/// towards uniform points inside the cube.
fn rays(rng: &mut SplitMix64) -> Vec<(Vec3, Vec3)> {
    let centre = Vec3::splat(0.5);
    (0..N)
        .map(|_| {
            let o = centre + 2.0 * sample_uniform_sphere(rng.vec2());
            let target = Vec3::new(rng.f32(), rng.f32(), rng.f32());
            (o, (target - o).normalize())
        })
        .collect()
}

/// The extinction majorant segments of the ray `(o, d)` through `grid`.
fn segments(
    grid: &MajorantGrid,
    (o, d): (Vec3, Vec3),
) -> impl Iterator<Item = MajorantSegment> + '_ {
    grid.traverse(o, d, 0.0, f32::INFINITY)
        .map(|s| s.scaled(SCALE))
}

/// `sigma_t(t)` along the ray `(o, d)`.
fn extinction(density: &DensityGrid, (o, d): (Vec3, Vec3)) -> impl FnMut(f32) -> f32 + '_ {
    move |t| SCALE * density.lookup(o + d * t)
}

fn bench_heterogeneous(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let density: DensityGrid = read_grid(
        &root.join("scenes/mitsuba-suite/hetero_grid_density.vol"),
        None,
    )
    .unwrap();
    let fine = MajorantGrid::new(&density, [MAJORANT_RES; 3]);
    let global = MajorantGrid::global(&density);
    let mut rng = SplitMix64(0x4E7E_6E01);
    let rays = rays(&mut rng);
    // One random stream shared by all iterations: the work per ray does not depend on
    // which numbers it gets beyond their distribution.
    let mut rand = move || rng.f32();
    let sigma_t = |r| extinction(&density, r);
    // The default march step: one voxel.
    let step = 1.0 / density.dims()[0] as f32;

    let mut g = c.benchmark_group("heterogeneous");
    g.throughput(Throughput::Elements(N as u64));
    // One bench: `$per_ray` (an f32 or Rgb per ray) summed over the rays, so nothing is
    // optimised away. A macro, not a function: the estimators are generic over their
    // closures, and a `dyn` indirection per density lookup would be part of the timing.
    macro_rules! bench_rays {
        ($name:expr, |$r:ident| $per_ray:expr) => {
            g.bench_function($name, |b| {
                b.iter(|| {
                    let mut sum = Default::default();
                    for &$r in black_box(&rays) {
                        sum += $per_ray;
                    }
                    black_box::<f32>(sum)
                })
            });
        };
    }
    bench_rays!("majorant_dda_16", |r| segments(&fine, r)
        .map(|s| s.t1 - s.t0)
        .sum::<f32>());
    bench_rays!("delta_tracking_16", |r| {
        delta_tracking(segments(&fine, r), sigma_t(r), &mut rand).t
    });
    bench_rays!("delta_tracking_global", |r| {
        delta_tracking(segments(&global, r), sigma_t(r), &mut rand).t
    });
    bench_rays!("delta_transmittance_16", |r| {
        delta_tracking_transmittance(segments(&fine, r), sigma_t(r), &mut rand).value
    });
    bench_rays!("ratio_tracking_16", |r| {
        ratio_tracking(segments(&fine, r), sigma_t(r), &mut rand).value
    });
    bench_rays!("residual_ratio_tracking_16", |r| {
        residual_ratio_tracking(segments(&fine, r), sigma_t(r), &mut rand).value
    });
    // A chromatic medium: one grey majorant, the channels weighted by spectral MIS.
    let k = Rgb::new(1.0, 0.5, 0.25);
    bench_rays!("spectral_tracking_16", |r| {
        let f = spectral_tracking(segments(&fine, r), sigma_t(r), k, [1.0 / 3.0; 3], &mut rand);
        f.weight.r + f.weight.g + f.weight.b
    });
    bench_rays!("ray_marching_transmittance", |r| {
        ray_marching_transmittance(segments(&fine, r), sigma_t(r), &mut rand, step).value
    });
    bench_rays!("unbiased_ray_marching", |r| {
        unbiased_ray_marching(|| segments(&fine, r), sigma_t(r), &mut rand, step).value
    });
    g.finish();
}

// criterion_group! expands to an undocumented `pub fn`; a private module keeps it out of the
// `missing_docs` lint without an allow attribute.
mod group {
    criterion::criterion_group!(benches, super::bench_heterogeneous);
}
criterion_main!(group::benches);
