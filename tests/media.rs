//! Scattering media against results that are not the renderer itself: white furnaces,
//! Chandrasekhar's single-scattering formula for a slab and his H-function for a
//! semi-infinite isotropic half-space, and single scattering against multiple scattering
//! restricted to one volume event.

mod common;
use common::*;
use glam::Vec3;
use risotto::builtins::builtin::{Interior, Surface};
use risotto::builtins::media::{HomogeneousMedium, Scattering};
use risotto::engine::integrator::LightingTechnique;
use risotto::engine::render::RenderOutput;
use risotto::engine::scene::{Scene, ShapeGeometry};
use risotto::systems::phase::PhaseFunction;
use risotto_components::Rgb;
use std::f64::consts::PI;

fn medium(sigma_t: f32, albedo: f32, phase: PhaseFunction, scattering: Scattering) -> Interior {
    Interior::Homogeneous(HomogeneousMedium {
        sigma_t: Rgb::splat(sigma_t),
        sigma_s: Rgb::splat(sigma_t * albedo),
        phase,
        scattering,
        emission: Rgb::BLACK,
        albedo_pattern: None,
        g_pattern: None,
    })
}

/// A white furnace: an albedo-1 medium in an index-matched unit sphere under a constant
/// environment of radiance 1, seen whole by a 12 x 12 camera.
fn furnace(interior: Interior, spp: u32, technique: LightingTechnique) -> RenderOutput {
    let mut scene = Scene::new(camera(40.0, 4.0, 12, 12), settings(12, 12, spp, u32::MAX));
    let m = scene.add_material("medium", 0, mat_in(Surface::Interface, interior));
    scene.add_shape(
        "ball",
        ShapeGeometry::Sphere(risotto::systems::geometry::Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        }),
        m,
        None,
    );
    environment(&mut scene, Rgb::WHITE);
    render_with(&scene.compile().unwrap(), technique, None)
}

/// Under MIS (where the constant environment is left to phase sampling) every path of an
/// albedo-1 medium carries exactly 1: every pixel is 1 to float precision, for isotropic,
/// forward and backward scattering, dense and thin. Under light sampling alone (shadow rays
/// through the medium, MIS weight 1, environment hits after scattering not counted) the
/// estimate is noisy but its image mean is still 1 within 3 standard errors (isotropic;
/// with g = +-0.9 in a dense medium light sampling alone is too heavy-tailed for a
/// standard-error test at this size).
#[test]
fn albedo_one_media_are_white_furnaces() {
    let phases = [
        PhaseFunction::Isotropic,
        PhaseFunction::henyey_greenstein(0.9).unwrap(),
        PhaseFunction::henyey_greenstein(-0.9).unwrap(),
    ];
    for phase in phases {
        for sigma_t in [0.2f32, 20.0] {
            let out = furnace(
                medium(sigma_t, 1.0, phase, Scattering::Multiple),
                16,
                LightingTechnique::Mis,
            );
            let what = format!("{phase:?} sigma_t {sigma_t}");
            for p in &out.beauty.pixels {
                for c in [p.r, p.g, p.b] {
                    assert!((c - 1.0).abs() <= 1e-4, "{what}: pixel {c}");
                }
            }
            assert_eq!(out.stats.counters.nan_dropped, 0, "{what}");
            assert!(
                out.stats.counters.volume_events
                    [risotto::engine::stats::VolumeEvent::Scatter as usize]
                    > 0,
                "{what}: the medium scattered"
            );
        }
    }
    for sigma_t in [0.2f32, 20.0] {
        let interior = medium(sigma_t, 1.0, PhaseFunction::Isotropic, Scattering::Multiple);
        let out = furnace(interior, 64, LightingTechnique::NeeOnly);
        let (mean, se) = image_mean(&out);
        let what = format!("light sampling, sigma_t {sigma_t}: {mean:?} +- {se:?}");
        assert!(se.g > 0.0, "{what}: light sampling alone is noisy");
        assert!((mean.g - 1.0).abs() <= 3.0 * se.g, "{what}");
        assert_eq!(out.stats.counters.nan_dropped, 0, "{what}");
    }
}

/// A wide slab `y in [-d, 0]` of the medium (index-matched boundary), seen from straight
/// above by an orthographic camera over its centre, lit by a sun at `theta0` from the
/// vertical; black below and around.
fn slab(interior: Interior, d: f32, theta0: f64, spp: u32, max_depth: u32) -> RenderOutput {
    let cam = ortho_camera(Vec3::new(0.0, 5.0, 0.0), Vec3::ZERO, Vec3::Z, 0.5, 8, 8);
    let mut scene = Scene::new(cam, settings(8, 8, spp, max_depth));
    let m = scene.add_material("medium", 0, mat_in(Surface::Interface, interior));
    let half = 40.0;
    add_box(
        &mut scene,
        "slab",
        Vec3::new(-half, -d, -half),
        Vec3::new(half, 0.0, half),
        m,
    );
    add_sun(&mut scene, theta0 as f32, Rgb::splat(1.0));
    render_with(&scene.compile().unwrap(), LightingTechnique::Mis, None)
}

/// Single-scattered radiance leaving a slab of optical thickness `tau` towards the zenith
/// (mu = 1), lit by a collimated beam of irradiance `e` (perpendicular to the beam) at
/// `mu0 = cos theta0` from the same side: Chandrasekhar, *Radiative Transfer* (1960), ch. I
/// sec. 11 (single scattering in a plane-parallel atmosphere, eq. (44) with the source
/// function of the first order):
/// `L = e * albedo * p(Theta) * mu0 / (mu0 + mu) * (1 - exp(-tau (1/mu0 + 1/mu)))`,
/// with `Theta` the scattering angle between the beam and the viewing ray's reverse.
fn single_scattering_slab(e: f64, albedo: f64, p: f64, tau: f64, mu0: f64) -> f64 {
    let mu = 1.0;
    e * albedo * p * mu0 / (mu0 + mu) * (1.0 - (-tau * (1.0 / mu0 + 1.0 / mu)).exp())
}

/// Single scattering two ways, against the closed form: the homogeneous interior in
/// `single` mode (the lighting delegate lights one point per technique on the camera ray;
/// unbounded depth, nothing else scatters) and in `multiple` mode restricted to paths with
/// exactly one volume event (`max_depth = 2`: the camera segment and the light segment).
/// Isotropic and forward-scattering (g = 0.6, which makes the scattering angle matter).
#[test]
fn single_scattering_in_a_slab_matches_chandrasekhar() {
    let (d, sigma_t, albedo, theta0) = (0.5f32, 2.0f32, 0.7f32, 50f64.to_radians());
    let mu0 = theta0.cos();
    for g in [0.0f32, 0.6] {
        let phase = if g == 0.0 {
            PhaseFunction::Isotropic
        } else {
            PhaseFunction::henyey_greenstein(g).unwrap()
        };
        // Light arrives travelling (sin t0, -cos t0, 0) and leaves towards +y: the cosine
        // between propagation directions is -cos t0 = -mu0. HG with the propagation
        // convention: p = (1 - g^2) / (4 pi (1 + g^2 - 2 g cos)^1.5).
        let cos = -mu0;
        let g64 = g as f64;
        let p = (1.0 - g64 * g64) / (4.0 * PI * (1.0 + g64 * g64 - 2.0 * g64 * cos).powf(1.5));
        let want = single_scattering_slab(1.0, albedo as f64, p, (sigma_t * d) as f64, mu0);
        for (mode, max_depth) in [(Scattering::Single, u32::MAX), (Scattering::Multiple, 2)] {
            let out = slab(
                medium(sigma_t, albedo, phase, mode),
                d,
                theta0,
                1024,
                max_depth,
            );
            let (mean, se) = image_mean(&out);
            let what = format!("g {g} {mode:?}: {mean:?} +- {se:?}, want {want}");
            let (m, s) = (mean.g as f64, se.g as f64);
            assert!(s < 0.01 * want, "{what}: not converged enough to test");
            assert!((m - want).abs() <= 3.0 * s + 1e-3 * want, "{what}");
            assert_eq!(out.stats.counters.nan_dropped, 0, "{what}");
        }
    }
}

/// Multiple scattering in a semi-infinite isotropic half-space (a slab 200 mean free paths
/// deep) under a collimated beam, against Chandrasekhar's exact diffuse reflection
/// (1960, ch. IV sec. 27, eq. (46) with the H-function of ch. V): the radiance reflected
/// towards `mu` from a beam of irradiance `e` at `mu0` is
/// `L = e * (w / (4 pi)) * mu0 / (mu + mu0) * H(mu) H(mu0)`. All orders of scattering.
#[test]
fn half_space_reflection_matches_the_h_function() {
    let (w, theta0) = (0.9f64, 60f64.to_radians());
    let mu0 = theta0.cos();
    let want =
        (w / (4.0 * PI)) * mu0 / (1.0 + mu0) * chandrasekhar_h(w, 1.0) * chandrasekhar_h(w, mu0);
    // The H-function against Chandrasekhar's table for conservative scattering (w = 1:
    // H(1) = 2.90781, where the iteration converges slowest).
    let h1 = chandrasekhar_h(1.0, 1.0);
    assert!((h1 - 2.90781).abs() < 3e-3, "H(1) = {h1}");
    let sigma_t = 10.0f32;
    let out = slab(
        medium(
            sigma_t,
            w as f32,
            PhaseFunction::Isotropic,
            Scattering::Multiple,
        ),
        20.0,
        theta0,
        2048,
        u32::MAX,
    );
    let (mean, se) = image_mean(&out);
    let (m, s) = (mean.g as f64, se.g as f64);
    let what = format!("{mean:?} +- {se:?}, want {want}");
    assert!(s < 0.01 * want, "{what}: not converged enough to test");
    assert!((m - want).abs() <= 3.0 * s + 2e-3 * want, "{what}");
    assert_eq!(out.stats.counters.nan_dropped, 0);
}

/// Without a lighting delegate (`--lighting bxdf`: the path tracer offers none, as an
/// integrator like PxrVCM never does) single scattering falls back to multiple scattering
/// and still renders the furnace white: the medium is not silently black.
#[test]
fn single_scattering_without_a_delegate_falls_back_to_multiple() {
    let interior = medium(2.0, 1.0, PhaseFunction::Isotropic, Scattering::Single);
    let out = furnace(interior, 16, LightingTechnique::BxdfOnly);
    let (mean, se) = image_mean(&out);
    assert!(
        (mean.g - 1.0).abs() <= 3.0 * se.g + 1e-4,
        "{mean:?} +- {se:?}"
    );
    assert!(
        out.stats.counters.volume_events[risotto::engine::stats::VolumeEvent::Scatter as usize] > 0,
        "the medium scattered"
    );
}

/// The `scattering` technique overrides what the medium says: a multiple-scattering furnace
/// rendered with `scattering = single` loses the higher orders (darker than 1), and with
/// `scattering = multiple` it is white again.
#[test]
fn the_scattering_technique_overrides_the_medium() {
    use risotto::engine::render::{render, RenderOptions};
    use risotto::engine::technique::PluginTechniques;
    let mut scene = Scene::new(camera(40.0, 4.0, 12, 12), settings(12, 12, 16, u32::MAX));
    let interior = medium(2.0, 1.0, PhaseFunction::Isotropic, Scattering::Multiple);
    let m = scene.add_material("medium", 0, mat_in(Surface::Interface, interior));
    scene.add_shape(
        "ball",
        ShapeGeometry::Sphere(risotto::systems::geometry::Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        }),
        m,
        None,
    );
    environment(&mut scene, Rgb::WHITE);
    let compiled = scene.compile().unwrap();
    let mean = |scattering| {
        let options = RenderOptions {
            plugin_techniques: match scattering {
                Some(s) => PluginTechniques::default()
                    .with("scattering", Scattering::name(s))
                    .unwrap(),
                None => PluginTechniques::default(),
            },
            ..RenderOptions::default()
        };
        image_mean(&render(&compiled, &options, &|_| {}).unwrap())
            .0
            .g
    };
    let (scene_says, single, multiple) = (
        mean(None),
        mean(Some(Scattering::Single)),
        mean(Some(Scattering::Multiple)),
    );
    assert!((scene_says - 1.0).abs() < 1e-4, "{scene_says}");
    assert!((multiple - 1.0).abs() < 1e-4, "{multiple}");
    assert!(
        single < 0.95,
        "single scattering alone must lose light: {single}"
    );
}
