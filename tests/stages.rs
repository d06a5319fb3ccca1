//! The scheduler runs only the stages a scene's contents need, and the stats prove it
//! (issue 3: "a scene whose factories report no interior never runs this system (the stats
//! show zero calls)").
//!
//! The same small room (diffuse floor and block, an area light, a distant light) is rendered
//! with one extra object that changes the compiled [`Features`]; each render's stats must list
//! exactly those features, show the systems they call for and no others:
//!
//! * `partition` and `volume` run only when some material computes an interior;
//! * shadow rays take the any-hit fast path (`occlusion`) only when every surface is opaque
//!   and there is no volume; otherwise they walk through surfaces with closest-hit queries
//!   (counted under `intersect`) and `occlusion` never runs.
//!
//! [`Features`]: risotto::engine::scene::Features

mod common;
use common::*;
use glam::Vec3;
use risotto::builtins::builtin::{Interior, Surface};
use risotto::engine::render::RenderOutput;
use risotto::engine::scene::{LightComponent, Scene, ShapeGeometry};
use risotto::engine::stats::{System, Termination};
use risotto_components::Rgb;

/// A diffuse floor and block under a small area light and a distant light, seen from the
/// front, plus whatever `extra` adds.
fn render_room(extra: impl FnOnce(&mut Scene)) -> RenderOutput {
    let mut scene = Scene::new(
        perspective(
            Vec3::new(0.0, 1.5, 4.0),
            Vec3::new(0.0, 0.5, 0.0),
            50.0,
            16,
            16,
        ),
        settings(16, 16, 4, 4),
    );
    let grey = scene.add_material(
        "grey",
        0,
        mat(Surface::Diffuse {
            reflectance: Rgb::splat(0.5),
        }),
    );
    scene.add_shape(
        "floor",
        ShapeGeometry::Triangles(quad_tris(
            Vec3::new(-5.0, 0.0, -5.0),
            Vec3::Z * 10.0,
            Vec3::X * 10.0,
        )),
        grey,
        None,
    );
    add_box(
        &mut scene,
        "block",
        Vec3::new(0.6, 0.0, -0.5),
        Vec3::new(1.4, 0.8, 0.3),
        grey,
    );
    // A 1 x 1 lamp at y = 3 facing down (e1 x e2 = x x z = -y).
    scene.add_shape(
        "lamp",
        ShapeGeometry::Triangles(quad_tris(Vec3::new(-0.5, 3.0, -0.5), Vec3::X, Vec3::Z)),
        grey,
        Some(Rgb::splat(10.0)),
    );
    scene.add_light(
        "sun",
        LightComponent::Distant {
            direction: Vec3::new(0.3, -1.0, -0.2).normalize(),
            irradiance: Rgb::splat(2.0),
        },
    );
    extra(&mut scene);
    let out = render_default(&scene.compile().unwrap());
    assert_eq!(out.stats.counters.nan_dropped, 0);
    assert_eq!(
        out.stats.counters.terminated[Termination::PassLimit as usize],
        0
    );
    assert!(
        out.beauty.mean().iter().all(|&c| c > 0.0),
        "black render: the checks below need shadow rays"
    );
    out
}

/// An object in front of the block (left of centre) with the given material.
fn add_object(scene: &mut Scene, material: Box<risotto::builtins::builtin::BuiltinMaterial>) {
    let m = scene.add_material("object", 0, material);
    add_box(
        scene,
        "object",
        Vec3::new(-1.2, 0.0, -0.2),
        Vec3::new(-0.2, 1.0, 0.8),
        m,
    );
}

/// The stats' JSON `systems` object and `features` list.
fn json(out: &RenderOutput) -> (serde_json::Value, Vec<String>) {
    let v: serde_json::Value = serde_json::from_str(&out.stats.to_json()).unwrap();
    let features = v["features"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap().to_string())
        .collect();
    (v["systems"].clone(), features)
}

fn calls(out: &RenderOutput, sys: System) -> u64 {
    out.stats.counters.system(sys).calls
}

/// Shadow rays were answered by the any-hit fast path, every one of them.
fn assert_fast_shadows(out: &RenderOutput) {
    let (t, o) = (
        out.stats.counters.system(System::Transmission),
        out.stats.counters.system(System::Occlusion),
    );
    assert!(t.calls > 0 && t.items > 0, "no shadow rays: {t:?}");
    assert_eq!((o.calls, o.items), (t.calls, t.items), "{o:?} vs {t:?}");
}

/// Shadow rays walked through surfaces (the fast path never ran).
fn assert_walked_shadows(out: &RenderOutput) {
    let t = out.stats.counters.system(System::Transmission);
    assert!(t.calls > 0 && t.items > 0, "no shadow rays: {t:?}");
    assert_eq!(calls(out, System::Occlusion), 0);
    let (systems, _) = json(out);
    assert!(systems.get("occlusion").is_none(), "{systems}");
}

#[test]
fn opaque_scene_runs_no_volume_stages_and_fast_shadows() {
    let out = render_room(|s| {
        add_object(
            s,
            mat(Surface::Diffuse {
                reflectance: Rgb::new(0.7, 0.2, 0.2),
            }),
        )
    });
    let (systems, features) = json(&out);
    assert_eq!(features, ["area_lights", "distant_lights"]);
    assert_eq!(calls(&out, System::Partition), 0);
    assert_eq!(calls(&out, System::Volume), 0);
    for absent in ["partition", "volume"] {
        assert!(systems.get(absent).is_none(), "{absent} ran: {systems}");
    }
    assert_fast_shadows(&out);
    assert!(
        systems["occlusion"]["calls"].as_u64().unwrap() > 0,
        "{systems}"
    );
}

#[test]
fn absorbing_interior_runs_partition_and_volume() {
    let out = render_room(|s| {
        add_object(
            s,
            mat_in(
                Surface::Interface,
                Interior::Beer {
                    sigma_a: Rgb::new(0.5, 1.0, 2.0),
                },
            ),
        )
    });
    let (systems, features) = json(&out);
    assert_eq!(
        features,
        [
            "volumes",
            "transmissive_surfaces",
            "transmission_shadows",
            "area_lights",
            "distant_lights"
        ]
    );
    assert!(calls(&out, System::Partition) > 0);
    assert!(calls(&out, System::Volume) > 0);
    for present in ["partition", "volume"] {
        assert!(systems[present]["calls"].as_u64().unwrap() > 0, "{systems}");
    }
    // Shadow rays must cross the index-matched boundary and be attenuated inside.
    assert_walked_shadows(&out);
}

/// An absorbing interior never shades points inside a volume: no `phase` system, no volume
/// events; a scattering one does, and its stats say how many flights scattered or passed.
#[test]
fn only_scattering_media_run_the_volume_scatter_stage() {
    let beer = render_room(|s| {
        add_object(
            s,
            mat_in(
                Surface::Interface,
                Interior::Beer {
                    sigma_a: Rgb::new(0.5, 1.0, 2.0),
                },
            ),
        )
    });
    let (systems, features) = json(&beer);
    assert!(
        !features.iter().any(|f| f == "scattering_media"),
        "{features:?}"
    );
    assert_eq!(calls(&beer, System::Phase), 0);
    assert!(systems.get("phase").is_none(), "{systems}");
    assert!(beer.stats.counters.volume_events.iter().all(|&n| n == 0));

    let smoke = render_room(|s| {
        add_object(
            s,
            mat_in(
                Surface::Interface,
                Interior::Homogeneous(risotto::builtins::media::HomogeneousMedium {
                    sigma_t: Rgb::splat(2.0),
                    sigma_s: Rgb::splat(1.6),
                    phase: risotto::systems::phase::PhaseFunction::Isotropic,
                    scattering: risotto::builtins::media::Scattering::Multiple,
                    emission: Rgb::BLACK,
                    albedo_pattern: None,
                    g_pattern: None,
                }),
            ),
        )
    });
    let (systems, features) = json(&smoke);
    assert!(
        features.iter().any(|f| f == "scattering_media"),
        "{features:?}"
    );
    assert!(calls(&smoke, System::Phase) > 0);
    assert!(systems["phase"]["calls"].as_u64().unwrap() > 0, "{systems}");
    let events = &smoke.stats.counters.volume_events;
    use risotto::engine::stats::VolumeEvent;
    assert!(events[VolumeEvent::Scatter as usize] > 0 && events[VolumeEvent::Pass as usize] > 0);
    let v: serde_json::Value = serde_json::from_str(&smoke.stats.to_json()).unwrap();
    assert!(v["volume_events"]["scatter"].as_u64().unwrap() > 0, "{v}");
    assert_walked_shadows(&smoke);
}

#[test]
fn dielectric_without_interior_runs_no_volume_stages() {
    // Transmissive (refraction, priorities) but no volume: no partitioning, no volume
    // integrators. Shadow rays walk, because a transmissive boundary may be a false boundary
    // (priorities) that shadow rays must pass; the fast path is for opaque scenes only.
    let out = render_room(|s| {
        add_object(
            s,
            mat(Surface::Dielectric {
                ior: 1.5,
                tint: Rgb::WHITE,
                cheap_shadows: false,
            }),
        )
    });
    let (systems, features) = json(&out);
    assert_eq!(
        features,
        ["transmissive_surfaces", "area_lights", "distant_lights"]
    );
    assert_eq!(calls(&out, System::Partition), 0);
    assert_eq!(calls(&out, System::Volume), 0);
    for absent in ["partition", "volume"] {
        assert!(systems.get(absent).is_none(), "{absent} ran: {systems}");
    }
    assert_walked_shadows(&out);
}
