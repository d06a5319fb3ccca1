//! The work count of the bidirectional integrators (issue 34): the stats split their rays by
//! the strategy that traced them, and the split adds up to the ray counts the trace and
//! occlusion systems report (cornell has no transmissive surface: one occlusion query per
//! shadow ray).

use risotto::engine::integrator::GlobalIntegrator;
use risotto::engine::render::{render, RenderOptions, RenderOutput};
use risotto::engine::stats::{BidirRays, System};
use risotto::loader::load::{scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::load_scene;
use std::path::Path;

fn cornell(integrator: GlobalIntegrator) -> RenderOutput {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/mitsuba-suite/cornell.toml");
    let mut desc = load_scene(&path).unwrap();
    desc.render.width = 16;
    desc.render.height = 16;
    desc.render.spp = 4;
    let scene = scene_from_desc(desc, &MaterialRegistry::with_builtins())
        .unwrap()
        .compile()
        .unwrap();
    let options = RenderOptions {
        integrator: Some(integrator),
        threads: Some(1),
        ..RenderOptions::default()
    };
    render(&scene, &options, &|_| {}).unwrap()
}

#[test]
fn bidirectional_rays_by_kind_add_up_to_the_traced_rays() {
    let samples = 16 * 16 * 4;
    for integrator in [GlobalIntegrator::Bdpt, GlobalIntegrator::Light] {
        let out = cornell(integrator);
        let c = &out.stats.counters;
        let k = c.bidir_rays;
        let name = integrator.name();
        assert_eq!(k.camera + k.light, c.rays, "{name}: {k:?}");
        let shadow = k.light_samples + k.connections + k.camera_connections;
        let occlusion = c.systems[System::Occlusion as usize].items;
        assert_eq!(shadow, occlusion, "{name}: {k:?}");
        // One camera ray and at most one emitted ray per sample, and more of each kind
        // (paths go on) where the strategy traces them.
        assert!(
            k.camera >= samples && k.light > samples / 2,
            "{name}: {k:?}"
        );
        assert!(k.camera_connections > 0, "{name}: {k:?}");
        let connects = integrator == GlobalIntegrator::Bdpt;
        assert_eq!(k.connections > 0, connects, "{name}: {k:?}");
        assert_eq!(k.light_samples > 0, connects, "{name}: {k:?}");
    }
    let path = cornell(GlobalIntegrator::Path);
    assert_eq!(path.stats.counters.bidir_rays, BidirRays::default());
}
