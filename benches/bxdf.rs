//! Throughput of the per-sample scattering math: 4096 samples per iteration over columns of
//! `wo` and `u`, the shape the engine's batch Bxdf closures will feed them in.

use criterion::{black_box, criterion_main, Criterion, Throughput};
use risotto::components::{Rgb, Vec2, Vec3};
use risotto::systems::bxdf::{
    dielectric_sample, diffuse_sample, diffuse_sample_world, hg_sample, sample_cosine_hemisphere,
    sample_uniform_sphere, BxdfSample,
};
use risotto::systems::microfacet::Ggx;
use risotto::systems::rough_conductor::RoughConductor;
use risotto::systems::rough_dielectric::RoughDielectric;

const N: usize = 4096;

/// Deterministic low-discrepancy-ish columns (R2 sequence, Roberts 2018) so the bench does
/// not depend on a random crate.
fn u_column(offset: f32) -> Vec<Vec2> {
    const A1: f32 = 0.754_877_7;
    const A2: f32 = 0.569_840_3;
    (0..N)
        .map(|i| {
            let i = i as f32 + offset;
            Vec2::new((0.5 + A1 * i).fract(), (0.5 + A2 * i).fract())
        })
        .collect()
}

fn bench_bxdf(c: &mut Criterion) {
    let u = u_column(0.0);
    // Surface wo columns: upper hemisphere for diffuse; both sides for the dielectric.
    let wo_up: Vec<Vec3> = u_column(7.0)
        .into_iter()
        .map(sample_cosine_hemisphere)
        .collect();
    let wo_any: Vec<Vec3> = u_column(13.0)
        .into_iter()
        .map(sample_uniform_sphere)
        .collect();
    let mut out: Vec<Option<BxdfSample>> = vec![None; N];
    let mut out_hg: Vec<(Vec3, f32)> = vec![(Vec3::ZERO, 0.0); N];

    let mut group = c.benchmark_group("bxdf");
    group.throughput(Throughput::Elements(N as u64));
    group.bench_function("diffuse_sample", |b| {
        let albedo = Rgb::new(0.8, 0.5, 0.2);
        b.iter(|| {
            for ((o, wo), u) in out.iter_mut().zip(black_box(&wo_up)).zip(black_box(&u)) {
                *o = diffuse_sample(albedo, *wo, *u);
            }
            black_box(&out);
        })
    });
    // The column kernel the renderer's Lambertian runs (world-space normals and directions,
    // eight lanes at a time); `diffuse_sample` above is its per-point local-frame form.
    let normal: Vec<Vec3> = u_column(3.0)
        .into_iter()
        .map(sample_uniform_sphere)
        .collect();
    let vn: Vec<Vec3> = normal
        .iter()
        .zip(&wo_up)
        .map(|(n, wo)| risotto::systems::bxdf::Frame::from_normal(*n).to_world(*wo))
        .collect();
    let (mut wi, mut pdf) = (vec![Vec3::ZERO; N], vec![0.0f32; N]);
    group.bench_function("diffuse_sample_world", |b| {
        b.iter(|| {
            diffuse_sample_world(
                black_box(&normal),
                black_box(&vn),
                black_box(&u),
                &mut wi,
                &mut pdf,
            );
            black_box(&wi);
        })
    });
    group.bench_function("dielectric_sample", |b| {
        b.iter(|| {
            for ((o, wo), u) in out.iter_mut().zip(black_box(&wo_any)).zip(black_box(&u)) {
                *o = dielectric_sample(black_box(1.5), Rgb::WHITE, *wo, *u);
            }
            black_box(&out);
        })
    });
    // The GGX lobes (alpha 0.3, energy compensation on, Au): visible-normal sampling plus
    // the evaluation each sample's weight and pdf come from, and the evaluation alone (what
    // light sampling runs).
    let au = risotto::systems::conductor::metal("Au").expect("a preset");
    let gold = RoughConductor::new(
        Ggx::isotropic(0.3),
        Rgb::from_array(au.eta),
        Rgb::from_array(au.k),
        Rgb::WHITE,
        true,
    );
    let lobe_u = u_column(21.0);
    group.bench_function("rough_conductor_sample", |b| {
        b.iter(|| {
            let samples = out.iter_mut().zip(black_box(&wo_up)).zip(black_box(&u));
            for (((o, wo), u), ul) in samples.zip(&lobe_u) {
                *o = gold.sample(*wo, *u, ul.x);
            }
            black_box(&out);
        })
    });
    let wi_up: Vec<Vec3> = lobe_u
        .iter()
        .map(|&u| sample_cosine_hemisphere(u))
        .collect();
    let mut evals = vec![(Rgb::BLACK, 0.0f32); N];
    group.bench_function("rough_conductor_eval", |b| {
        b.iter(|| {
            for ((e, wo), wi) in evals.iter_mut().zip(black_box(&wo_up)).zip(&wi_up) {
                *e = gold.eval(*wo, *wi);
            }
            black_box(&evals);
        })
    });
    let glass = RoughDielectric::new(Ggx::isotropic(0.3), 1.5, Rgb::WHITE, true);
    group.bench_function("rough_dielectric_sample", |b| {
        b.iter(|| {
            let samples = out.iter_mut().zip(black_box(&wo_any)).zip(black_box(&u));
            for (((o, wo), u), ul) in samples.zip(&lobe_u) {
                *o = glass.sample(*wo, *u, ul.x);
            }
            black_box(&out);
        })
    });
    group.bench_function("hg_sample_g0.7", |b| {
        b.iter(|| {
            for ((o, wo), u) in out_hg.iter_mut().zip(black_box(&wo_any)).zip(black_box(&u)) {
                *o = hg_sample(black_box(0.7), *wo, *u);
            }
            black_box(&out_hg);
        })
    });
    group.finish();
}

// criterion_group! expands to an undocumented `pub fn`; a private module keeps it out of the
// `missing_docs` lint without an allow attribute.
mod group {
    criterion::criterion_group!(benches, super::bench_bxdf);
}
criterion_main!(group::benches);
