//! Hard cases for scattering media (issue 14): very thin and very dense, albedo 0 and 1,
//! Henyey-Greenstein g = +-0.999 and double HG with extreme lobes, chromatic extinction with a
//! zero and a huge channel, scenes scaled by 1e-4 and 1e4, grazing camera rays on a medium's
//! boundary, nested and coincident boundaries. Every render must be finite (no pixel NaN or
//! infinite, nothing dropped at the film, no stage producing a non-finite value) and match a
//! known limit: a white furnace, an exact transmittance, a transparent background, or the
//! same image at another scale.

mod common;
use common::*;
use glam::Vec3;
use risotto::builtins::builtin::{Interior, Surface};
use risotto::builtins::media::{HomogeneousMedium, Scattering};
use risotto::engine::integrator::LightingTechnique;
use risotto::engine::render::RenderOutput;
use risotto::engine::scene::{Scene, ShapeGeometry};
use risotto::engine::stats::Termination;
use risotto::systems::camera::Camera;
use risotto::systems::geometry::Sphere;
use risotto::systems::phase::PhaseFunction;
use risotto_components::Rgb;

/// A multiple-scattering homogeneous medium of extinction `sigma_t` and albedo `albedo`.
fn medium(sigma_t: Rgb, albedo: f32, phase: PhaseFunction) -> Interior {
    Interior::Homogeneous(HomogeneousMedium {
        sigma_t,
        sigma_s: sigma_t * albedo,
        phase,
        scattering: Scattering::Multiple,
        emission: Rgb::BLACK,
        albedo_pattern: None,
        g_pattern: None,
    })
}

fn hg(g: f32) -> PhaseFunction {
    PhaseFunction::henyey_greenstein(g).unwrap()
}

/// Asserts the render is finite everywhere and that nothing was dropped or flagged.
fn assert_clean(what: &str, out: &RenderOutput) {
    let c = &out.stats.counters;
    assert_eq!(c.nan_dropped, 0, "{what}: {}", out.stats);
    assert!(
        c.non_finite.iter().all(|&n| n == 0),
        "{what}: {}",
        out.stats
    );
    assert_finite(what, out);
    for (i, p) in out.beauty.pixels.iter().enumerate() {
        assert!(p.min_channel() >= 0.0, "{what}: pixel {i} is {p:?}");
    }
}

/// A sphere of radius `r` at the origin, its surface `surface` and its interior `interior`,
/// under a constant environment of radiance 1, seen by `cam` (`n x n` pixels, `spp`).
fn ball(cam: Camera, n: u32, spp: u32, r: f32, surface: Surface, interior: Interior) -> Scene {
    let mut scene = Scene::new(cam, settings(n, n, spp, u32::MAX));
    let m = scene.add_material("ball", 1, mat_in(surface, interior));
    scene.add_shape(
        "ball",
        ShapeGeometry::Sphere(Sphere {
            center: Vec3::ZERO,
            radius: r,
        }),
        m,
        None,
    );
    environment(&mut scene, Rgb::WHITE);
    scene
}

/// An orthographic camera on +z showing `width` across, looking at the origin.
fn ortho(width: f32, n: u32) -> Camera {
    ortho_camera(
        Vec3::new(0.0, 0.0, 10.0 * width),
        Vec3::ZERO,
        Vec3::Y,
        width,
        n,
        n,
    )
}

fn render_mis(scene: Scene) -> RenderOutput {
    render_with(&scene.compile().unwrap(), LightingTechnique::Mis, None)
}

/// Asserts every channel of every pixel is within `tol` of `want`.
fn assert_every_pixel(what: &str, out: &RenderOutput, want: f32, tol: f32) {
    for (i, p) in out.beauty.pixels.iter().enumerate() {
        for c in p.to_array() {
            assert!((c - want).abs() <= tol, "{what}: pixel {i} is {p:?}");
        }
    }
}

#[test]
fn albedo_one_media_with_extreme_phase_functions_are_white_furnaces() {
    // Under MIS a constant environment is left to phase sampling, so every path of an
    // albedo-1 medium behind an index-matched boundary carries exactly 1.
    let phases = [
        hg(0.999),
        hg(-0.999),
        PhaseFunction::double_henyey_greenstein(0.999, -0.999, 0.5).unwrap(),
        PhaseFunction::double_henyey_greenstein(0.999, -0.999, 0.999).unwrap(),
    ];
    for phase in phases {
        for sigma_t in [1e-4f32, 2.0] {
            let what = format!("{phase:?}, sigma_t {sigma_t}");
            let interior = medium(Rgb::splat(sigma_t), 1.0, phase);
            let out = render_mis(ball(ortho(2.4, 8), 8, 8, 1.0, Surface::Interface, interior));
            assert_clean(&what, &out);
            assert_every_pixel(&what, &out, 1.0, 1e-4);
        }
    }
}

#[test]
fn a_dense_albedo_one_medium_is_a_white_furnace() {
    // sigma_t 1e4 in a ball of radius 1e-3: optical radius 10, about a hundred scattering
    // events a path, HG g = 0.7.
    let interior = medium(Rgb::splat(1e4), 1.0, hg(0.7));
    let out = render_mis(ball(
        ortho(2.4e-3, 8),
        8,
        4,
        1e-3,
        Surface::Interface,
        interior,
    ));
    assert_clean("dense white", &out);
    assert_every_pixel("dense white", &out, 1.0, 1e-4);
}

#[test]
fn a_thin_medium_is_transparent() {
    // sigma_t 1e-4, albedo 0.8 in a unit ball: at most 1 - exp(-2e-4 * 0.2) = 4e-5 of the
    // background is absorbed along any chord (scattering in a uniform environment changes
    // nothing).
    let interior = medium(Rgb::splat(1e-4), 0.8, hg(0.7));
    let out = render_mis(ball(ortho(2.4, 8), 8, 8, 1.0, Surface::Interface, interior));
    assert_clean("thin", &out);
    assert_every_pixel("thin", &out, 1.0, 1e-4);
}

#[test]
fn a_dense_black_medium_is_black_and_its_background_is_untouched() {
    // sigma_t 1e4, albedo 0: inside the silhouette nothing gets through (optical depth
    // >= 2e4 * sqrt(1 - 0.8^2) along every chord the inner pixels see), with a sun above too.
    let n = 10;
    let interior = medium(Rgb::splat(1e4), 0.0, hg(0.7));
    let mut scene = ball(ortho(4.0, n), n, 4, 1.0, Surface::Interface, interior);
    add_sun(&mut scene, 0.3, Rgb::splat(3.0));
    let out = render_mis(scene);
    assert_clean("dense black", &out);
    let pixel = 4.0 / n as f32;
    for y in 0..n as usize {
        for x in 0..n as usize {
            let centre = |i: usize| -2.0 + (i as f32 + 0.5) * pixel;
            let (cx, cy) = (centre(x), -centre(y));
            let far = (cx.abs() + pixel / 2.0).hypot(cy.abs() + pixel / 2.0);
            let near = (cx.abs() - pixel / 2.0)
                .max(0.0)
                .hypot((cy.abs() - pixel / 2.0).max(0.0));
            let p = out.beauty.get(x, y);
            if far <= 0.8 {
                assert!(p.max_channel() == 0.0, "inside ({x}, {y}): {p:?}");
            } else if near >= 1.0 {
                assert!(
                    p.to_array().iter().all(|&c| c == 1.0),
                    "background ({x}, {y}): {p:?}"
                );
            }
        }
    }
}

#[test]
fn a_dense_grey_medium_stays_between_black_and_white() {
    // sigma_t 1e4, albedo 0.5 in a unit ball: paths scatter near the surface and die; under a
    // uniform environment of 1 the ball is darker than 1 and brighter than 0.
    let interior = medium(Rgb::splat(1e4), 0.5, hg(-0.5));
    let out = render_mis(ball(ortho(1.2, 8), 8, 8, 1.0, Surface::Interface, interior));
    assert_clean("dense grey", &out);
    let (mean, se) = image_mean(&out);
    assert!(
        mean.g > 0.05 && mean.g + 3.0 * se.g < 1.0,
        "{mean:?} +- {se:?}"
    );
}

/// Mean over the square `[-h, h]^2` of `exp(-sigma 2 sqrt(1 - x^2 - y^2))` inside the unit
/// disc and 1 outside: the transmittance of a unit ball of an absorbing medium seen by an
/// orthographic camera (midpoint rule, converged far below the tolerances).
fn ball_transmittance(sigma: f64, h: f64) -> f64 {
    let k = 600;
    let mut sum = 0.0;
    for i in 0..k {
        for j in 0..k {
            let x = -h + (i as f64 + 0.5) * 2.0 * h / k as f64;
            let y = -h + (j as f64 + 0.5) * 2.0 * h / k as f64;
            let r2 = x * x + y * y;
            sum += if r2 < 1.0 {
                (-sigma * 2.0 * (1.0 - r2).sqrt()).exp()
            } else {
                1.0
            };
        }
    }
    sum / (k * k) as f64
}

#[test]
fn chromatic_extinction_with_a_zero_and_a_huge_channel() {
    // sigma_t = (0, 1, 1e3), albedo 0: red passes untouched, green is Beer-Lambert along
    // each chord, blue is black inside the silhouette except at its rim.
    let h = 1.2f32;
    let chromatic = |albedo: f32| {
        let interior = medium(Rgb::new(0.0, 1.0, 1e3), albedo, hg(0.7));
        let cam = ortho(2.0 * h, 16);
        let out = render_mis(ball(cam, 16, 16, 1.0, Surface::Interface, interior));
        assert_clean(&format!("chromatic, albedo {albedo}"), &out);
        out
    };
    let out = chromatic(0.0);
    let (mean, se) = image_mean(&out);
    let tol = |c: usize, want: f64| 3.0 * se.to_array()[c] as f64 + 2e-3 * want + 1e-6;
    let want = [
        1.0,
        ball_transmittance(1.0, h as f64),
        ball_transmittance(1e3, h as f64),
    ];
    for (c, (&m, &w)) in mean.to_array().iter().zip(&want).enumerate() {
        assert!(
            (m as f64 - w).abs() <= tol(c, w),
            "channel {c}: {m} +- {} vs {w}",
            se.to_array()[c]
        );
    }
    // With albedo 0.8 the paths scatter (sampled by the other channels' extinction), and
    // the clear channel's estimate is noisy but still the background on average; the others
    // lose energy.
    let out = chromatic(0.8);
    let (mean, se) = image_mean(&out);
    assert!(
        (mean.r - 1.0).abs() <= 3.0 * se.r + 1e-4,
        "{mean:?} +- {se:?}"
    );
    assert!(mean.g < 1.0 && mean.b < 1.0, "{mean:?} +- {se:?}");
}

/// A medium ball of radius `s` (sigma_t `2 / s`, albedo 0.8, HG 0.7) on nothing, lit by a
/// sun and a dim environment, seen by a perspective camera at distance `4 s`.
fn scaled_ball(s: f32) -> RenderOutput {
    let n = 12;
    let cam = perspective(Vec3::new(0.0, 0.0, 4.0 * s), Vec3::ZERO, 40.0, n, n);
    let mut scene = Scene::new(cam, settings(n, n, 16, u32::MAX));
    let interior = medium(Rgb::splat(2.0 / s), 0.8, hg(0.7));
    let m = scene.add_material("ball", 1, mat_in(Surface::Interface, interior));
    scene.add_shape(
        "ball",
        ShapeGeometry::Sphere(Sphere {
            center: Vec3::ZERO,
            radius: s,
        }),
        m,
        None,
    );
    add_sun(&mut scene, 0.6, Rgb::splat(2.0));
    environment(&mut scene, Rgb::splat(0.1));
    render_with(&scene.compile().unwrap(), LightingTechnique::Mis, None)
}

#[test]
fn a_medium_scene_is_scale_invariant() {
    let reference = scaled_ball(1.0);
    assert_clean("scale 1", &reference);
    let (m1, se1) = image_mean(&reference);
    assert!(m1.g > 0.1, "the ball is lit: {m1:?}");
    for s in [1e-4f32, 1e4] {
        let out = scaled_ball(s);
        let what = format!("scale {s}");
        assert_clean(&what, &out);
        let (m, se) = image_mean(&out);
        for c in 0..3 {
            let (a, b) = (m.to_array()[c], m1.to_array()[c]);
            let tol = 3.0 * se.to_array()[c].hypot(se1.to_array()[c]) + 1e-3 * b;
            assert!(
                (a - b).abs() <= tol,
                "{what}, channel {c}: {a} vs {b} (tol {tol})"
            );
        }
    }
}

#[test]
fn grazing_camera_rays_along_a_medium_boundary() {
    // An absorbing slab y in [-1, 0] (z in [-1, 1]) seen edge-on by an orthographic camera
    // on +z whose rays run parallel to its top face; rows straddle y = 0. Rows above see the
    // background (exactly 1), rows below the slab's transmittance exp(-sigma 2) = 1/2, and the
    // rows that graze the face something in between.
    let sigma = std::f32::consts::LN_2 / 2.0;
    let n = 9;
    // Pixel rows 0.1 high, the middle row's centre on y = 0.
    let cam = ortho_camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 0.9, n, n);
    let mut scene = Scene::new(cam, settings(n, n, 64, u32::MAX));
    let interior = medium(Rgb::splat(sigma), 0.0, hg(0.7));
    let m = scene.add_material("slab", 1, mat_in(Surface::Interface, interior));
    add_box(
        &mut scene,
        "slab",
        Vec3::new(-5.0, -1.0, -1.0),
        Vec3::new(5.0, 0.0, 1.0),
        m,
    );
    environment(&mut scene, Rgb::WHITE);
    let out = render_mis(scene);
    assert_clean("grazing", &out);
    let (n, mid) = (n as usize, n as usize / 2);
    for y in 0..=mid {
        for x in 0..n {
            let p = out.beauty.get(x, y);
            for c in p.to_array() {
                if y < mid {
                    assert_eq!(c, 1.0, "above ({x}, {y}): {p:?}");
                } else {
                    assert!((0.0..=1.0).contains(&c), "grazing ({x}, {y}): {p:?}");
                }
            }
        }
    }
    // The transmittance estimate is a coin flip per path (pass or absorbed): test the mean of
    // the rows below, not single pixels.
    let (mean, se) = crop_mean(&out, 0..n, mid + 1..n);
    for (m, s) in mean.to_array().into_iter().zip(se.to_array()) {
        assert!((m - 0.5).abs() <= 3.0 * s + 1e-4, "below: {m} +- {s}");
    }
    let (grazing, _) = crop_mean(&out, 0..n, mid..mid + 1);
    assert!(
        grazing.g > mean.g,
        "grazing row {grazing:?} vs below {mean:?}"
    );
}

#[test]
fn a_medium_inside_glass_sharing_its_surface_is_a_white_furnace() {
    // The glass's own interior is the medium: one surface, a refracting boundary and a
    // volume boundary at once. Albedo 1 under a uniform environment: every pixel 1 (the
    // radiance scalings of entering and leaving cancel).
    let glass = Surface::Dielectric {
        ior: 1.5,
        tint: Rgb::WHITE,
        cheap_shadows: false,
    };
    for phase in [hg(0.7), hg(-0.999)] {
        let what = format!("glass with {phase:?} inside");
        let interior = medium(Rgb::splat(2.0), 1.0, phase);
        let out = render_mis(ball(ortho(2.4, 8), 8, 8, 1.0, glass.clone(), interior));
        assert_clean(&what, &out);
        assert_every_pixel(&what, &out, 1.0, 1e-3);
    }
}

#[test]
fn a_medium_ball_nested_in_glass_and_a_coincident_medium_are_white_furnaces() {
    let glass = |interior| {
        mat_in(
            Surface::Dielectric {
                ior: 1.5,
                tint: Rgb::WHITE,
                cheap_shadows: false,
            },
            interior,
        )
    };
    for (what, inner_radius) in [("nested", 0.5f32), ("coincident", 1.0)] {
        let mut scene = Scene::new(ortho(2.4, 8), settings(8, 8, 8, u32::MAX));
        let outer = scene.add_material("glass", 1, glass(Interior::Null));
        let interior = medium(Rgb::splat(2.0), 1.0, hg(0.7));
        let inner = scene.add_material("medium", 2, mat_in(Surface::Interface, interior));
        for (name, r, m) in [("glass", 1.0, outer), ("medium", inner_radius, inner)] {
            scene.add_shape(
                name,
                ShapeGeometry::Sphere(Sphere {
                    center: Vec3::ZERO,
                    radius: r,
                }),
                m,
                None,
            );
        }
        environment(&mut scene, Rgb::WHITE);
        let out = render_mis(scene);
        assert_clean(what, &out);
        assert_every_pixel(what, &out, 1.0, 1e-3);
    }
}

#[test]
fn free_flights_shorter_than_the_spawn_offset_stay_inside_the_boundary() {
    // A mean free path of 1e-7 in a unit ball, below the spawn offset (~5e-7 at unit
    // coordinates): nearly every scattering point of a ray that has just crossed the
    // boundary lies within rounding of it. Points on the wrong side send the next ray across
    // the boundary a second time (the stack counts an entry into a ball it is already in,
    // or an exit from one it never entered), and an albedo-1 path so trapped outside never
    // ends: the furnace run of 8c744e1 grew its arena until it ran out of memory. Paths end
    // at max_depth here (deep inside, nothing is lit); the counters must stay at zero.
    let interior = medium(Rgb::splat(1e7), 1.0, PhaseFunction::Isotropic);
    assert_flights_stay_inside("spawn-offset flights", interior);
}

/// Renders `interior` in the unit ball under a white environment (paths end at max_depth 24)
/// and checks that no ray crossed its boundary the wrong way or left while inside, and that
/// the flights scattered.
fn assert_flights_stay_inside(what: &str, interior: Interior) {
    let mut scene = ball(ortho(2.4, 12), 12, 4, 1.0, Surface::Interface, interior);
    scene.settings.max_depth = 24;
    let out = render_mis(scene);
    assert_clean(what, &out);
    let c = &out.stats.counters;
    let crossings = |v: &[u64]| v.iter().sum::<u64>();
    assert_eq!(crossings(&c.entered_twice), 0, "{what}: {}", out.stats);
    assert_eq!(crossings(&c.unmatched_exits), 0, "{what}: {}", out.stats);
    assert_eq!(crossings(&c.escaped_inside), 0, "{what}: {}", out.stats);
    assert!(
        c.volume_events[risotto::engine::stats::VolumeEvent::Scatter as usize] > 1000,
        "{what}: the flights scatter: {}",
        out.stats
    );
}

#[test]
fn heterogeneous_free_flights_shorter_than_the_spawn_offset_stay_inside_the_boundary() {
    // The same ball as above as a heterogeneous medium (a constant grid, scale 1e7, the
    // default majorant grid): delta tracking's collisions within rounding of the boundary
    // must stay inside it too.
    use risotto::builtins::heterogeneous::{HeterogeneousMedium, Tracking};
    use risotto::systems::grid::DensityGrid;
    let m = HeterogeneousMedium::new(
        DensityGrid::constant([4, 4, 4], 1.0).unwrap(),
        4,
        1e7,
        Rgb::WHITE,
        PhaseFunction::Isotropic,
        Tracking::Ratio,
    );
    let interior = Interior::Heterogeneous(std::sync::Arc::new(m));
    assert_flights_stay_inside("heterogeneous spawn-offset flights", interior);
}

#[test]
fn a_grazing_entry_whose_chord_is_shorter_than_the_offset_escapes() {
    // Camera rays grazing a unit ball's top: those that enter at cos < 2.5e-4 have a chord
    // (2 cos) shorter than the spawn offset along the ray (offset / cos, cos clamped at
    // 1e-3), so the continued ray skips the exit and sees nothing ahead. It has left; a free
    // flight on its unbounded segment scattered it in empty space instead, and in this
    // albedo-1 furnace (Russian roulette never culls throughput 1) such a path walked until
    // the depth limit (without one, until memory ran out: furnace at 256 spp, pixel
    // (77, 52), sample 189). About 140 of these 16384 rays skip their exit.
    let interior = medium(Rgb::splat(2.0), 1.0, PhaseFunction::Isotropic);
    // A perspective camera at the top's tangent (directions vary continuously, where an
    // orthographic camera's rays would sit at f32 heights), 3.5e-6 across at the ball.
    let cam = perspective(
        Vec3::new(0.0, 1.0, 10.0),
        Vec3::new(0.0, 1.0, 0.0),
        2e-5,
        32,
        32,
    );
    let mut scene = ball(cam, 32, 16, 1.0, Surface::Interface, interior);
    scene.settings.max_depth = 2000;
    let out = render_mis(scene);
    assert_clean("grazing entry", &out);
    let c = &out.stats.counters;
    assert_eq!(
        c.terminated[Termination::MaxDepth as usize],
        0,
        "paths trapped outside the ball: {}",
        out.stats
    );
    assert_every_pixel("grazing entry", &out, 1.0, 1e-3);
}

#[test]
fn a_majorant_below_the_density_is_reported_not_hidden() {
    // A heterogeneous ball whose majorant grid bounds half its real density: every estimator
    // samples extinctions above the bound. The stats count them and the summary warns; with
    // the right bounds (what the loader always builds) the count is 0 and shown as 0.
    use risotto::builtins::heterogeneous::{HeterogeneousMedium, Tracking};
    use risotto::systems::grid::{DensityGrid, MajorantGrid};
    use std::sync::Arc;
    let grid = |v: f32| DensityGrid::constant([4, 4, 4], v).unwrap();
    let right = HeterogeneousMedium::new(
        grid(1.0),
        4,
        2.0,
        Rgb::splat(0.8),
        PhaseFunction::Isotropic,
        Tracking::Ratio,
    );
    let wrong = HeterogeneousMedium {
        majorants: Arc::new(MajorantGrid::new(&grid(0.5), [4, 4, 4])),
        ..right.clone()
    };
    let render = |m: HeterogeneousMedium| {
        let scene = ball(
            ortho(2.5, 8),
            8,
            4,
            1.0,
            Surface::Interface,
            Interior::Heterogeneous(Arc::new(m)),
        );
        render_default(&scene.compile().unwrap())
    };
    let ok = render(right);
    assert_eq!(ok.stats.counters.majorant_violations, 0);
    let json = serde_json::to_value(&ok.stats).unwrap();
    assert_eq!(json["majorant_violations"], 0, "{json}");
    let bad = render(wrong);
    let v = bad.stats.counters.majorant_violations;
    assert!(v > 100, "{v}");
    let json = serde_json::to_value(&bad.stats).unwrap();
    assert_eq!(json["majorant_violations"], v, "{json}");
    let summary = bad.stats.to_string();
    assert!(summary.contains("above their majorant"), "{summary}");
    assert_eq!(bad.stats.counters.nan_dropped, 0);
}
