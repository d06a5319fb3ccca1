//! End-to-end bench: `scenes/mitsuba-suite/cornell.toml` at 64x64, 16 spp (65536 camera
//! samples per iteration), throughput in samples, with each global integrator (`path`, `light`,
//! `bdpt`, `vcm`: their cost per sample side by side). The full-size comparison with Mitsuba 3
//! (256x256, 64 spp) is a driver run; see benches/README.md.

use criterion::{criterion_main, Criterion, Throughput};
use risotto::engine::integrator::GlobalIntegrator;
use risotto::engine::render::{render, RenderOptions};
use risotto::loader::load::{scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::load_scene;
use std::path::Path;

fn cornell(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut desc = load_scene(&root.join("scenes/mitsuba-suite/cornell.toml")).unwrap();
    desc.render.width = 64;
    desc.render.height = 64;
    desc.render.spp = 16;
    let scene = scene_from_desc(desc, &MaterialRegistry::with_builtins())
        .unwrap()
        .compile()
        .unwrap();
    let mut g = c.benchmark_group("end_to_end");
    g.sample_size(10);
    g.throughput(Throughput::Elements(64 * 64 * 16));
    g.bench_function("cornell_64x64_16spp", |b| {
        b.iter(|| render(&scene, &RenderOptions::default(), &|_| {}).unwrap())
    });
    for integrator in [
        GlobalIntegrator::Light,
        GlobalIntegrator::Bdpt,
        GlobalIntegrator::Vcm,
    ] {
        let options = RenderOptions {
            integrator: Some(integrator),
            ..RenderOptions::default()
        };
        let name = format!("cornell_64x64_16spp_{}", integrator.name());
        g.bench_function(name, |b| {
            b.iter(|| render(&scene, &options, &|_| {}).unwrap())
        });
    }
    g.finish();
}

// criterion_group! expands to an undocumented `pub fn`; a private module keeps it out of the
// `missing_docs` lint without an allow attribute.
mod group {
    criterion::criterion_group!(benches, super::cornell);
}
criterion_main!(group::benches);
