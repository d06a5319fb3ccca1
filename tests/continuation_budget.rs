//! The continuation budget of the volume contract (issue 3): crossing an index-matched or a
//! false boundary is a *pass*, not a scattering bounce. Passes do not consume `max_depth`; a
//! separate, generous limit (`RenderSettings::max_passes`) stops runaway paths and counts them
//! as `pass_limit` in the stats; thin interfaces leave no dark shells.
//!
//! Thin layers are also checked with absorbing interiors: each interval inside a volume must be
//! measured from the boundary it starts on (Beer-Lambert to float precision), for camera rays
//! and for shadow rays, near the origin and 1e4 away from it.
//!
//! Every check is deterministic: orthographic cameras (parallel rays), index-matched or false
//! boundaries (no random choice anywhere), emitters seen on the first segment (`max_depth` 1,
//! Mitsuba's convention: a path of one segment sees emitters and nothing else) or a Dirac
//! distant light. So images are compared with the closed form to float precision, and the
//! stats' item counts are compared with the exact number of surfaces each ray must cross.

mod common;
use common::*;
use glam::Vec3;
use risotto::builtins::builtin::{beer, Interior, Surface};
use risotto::engine::render::RenderOutput;
use risotto::engine::scene::{Scene, ShapeGeometry};
use risotto::engine::stats::{System, Termination};
use risotto::systems::geometry::Sphere;
use risotto_components::Rgb;

/// Radiance of the emitter behind everything.
const L: Rgb = Rgb::new(2.0, 3.0, 5.0);

/// Image size (pixel edges fall on multiples of `view / RES`).
const RES: u32 = 16;

/// Samples per pixel.
const SPP: u32 = 4;

/// Renders `scene` and checks, for every pixel `expected` gives a value for, each channel to
/// relative error `tol`. Also checks that no sample was dropped as non-finite.
fn render_and_check(
    scene: Scene,
    tol: f32,
    expected: impl Fn(u32, u32) -> Option<Rgb>,
) -> RenderOutput {
    let out = render_default(&scene.compile().unwrap());
    assert_eq!(
        out.stats.counters.nan_dropped, 0,
        "non-finite samples dropped"
    );
    let (w, h) = (out.beauty.width as u32, out.beauty.height as u32);
    let mut checked = 0;
    for y in 0..h {
        for x in 0..w {
            let Some(e) = expected(x, y) else { continue };
            let v = out.beauty.get(x as usize, y as usize);
            for (c, (v, e)) in v.to_array().iter().zip(e.to_array()).enumerate() {
                let err = (v - e).abs() / e.abs().max(1e-30);
                let ok = if e == 0.0 { *v == 0.0 } else { err < tol };
                assert!(
                    ok,
                    "pixel ({x}, {y}) channel {c}: got {v}, expected {e} (rel. error {err})"
                );
            }
            checked += 1;
        }
    }
    assert!(checked > 0, "no pixel checked");
    out
}

fn terminated(out: &RenderOutput, reason: Termination) -> u64 {
    out.stats.counters.terminated[reason as usize]
}

fn items(out: &RenderOutput, sys: System) -> u64 {
    out.stats.counters.system(sys).items
}

/// A black-diffuse 10 x 10 emitter of radiance `L` in the plane `z = origin.z + z`, centred on
/// `origin`, facing +z (towards the cameras).
fn emitter(scene: &mut Scene, origin: Vec3, z: f32) {
    let black = scene.add_material(
        "emitter",
        0,
        mat(Surface::Diffuse {
            reflectance: Rgb::BLACK,
        }),
    );
    scene.add_shape(
        "emitter",
        ShapeGeometry::Triangles(quad_tris(
            origin + Vec3::new(-5.0, -5.0, z),
            Vec3::X * 10.0,
            Vec3::Y * 10.0,
        )),
        black,
        Some(L),
    );
}

/// An orthographic camera on +z above `origin`, looking down -z, `view` units wide, with
/// `max_depth` 1 and the given pass budget.
fn ortho_scene(origin: Vec3, view: f32, res: u32, max_passes: u32) -> Scene {
    let mut s = settings(res, res, SPP, 1);
    s.max_passes = max_passes;
    Scene::new(
        ortho_camera(origin + Vec3::Z * 5.0, origin, Vec3::Y, view, res, res),
        s,
    )
}

/// The box `[lo, hi]` with inward-facing normals (reversed winding): subtracted from an
/// outer box in the same shape it makes a closed shell (the shell's outside is its front).
fn inverted_box_tris(lo: Vec3, hi: Vec3) -> Vec<[Vec3; 3]> {
    box_tris(lo, hi)
        .into_iter()
        .map(|[a, b, c]| [a, c, b])
        .collect()
}

// ---------------------------------------------------------------------------------------
// Stacks of thin index-matched layers.

/// Number of thin boxes in the layer stacks (24 boundaries).
const LAYERS: usize = 12;

/// `LAYERS` closed boxes with index-matched surfaces and the given interior, each `gap` thick
/// and `gap` apart, so their 24 faces (normal to z) lie `gap` apart from `z = origin.z + 1` down.
/// They span `x in [origin.x - 3, origin.x + x_max]`, `y in origin.y +- 3`; the emitter is at
/// `origin.z - 3`. Camera rays covered by the layers cross exactly `2 * LAYERS` boundaries.
fn layer_scene(origin: Vec3, gap: f32, x_max: f32, max_passes: u32, interior: Interior) -> Scene {
    let mut scene = ortho_scene(origin, 2.0, RES, max_passes);
    let m = scene.add_material("layer", 0, mat_in(Surface::Interface, interior));
    for k in 0..LAYERS {
        let top = 1.0 - 2.0 * k as f32 * gap;
        add_box(
            &mut scene,
            &format!("layer{k}"),
            origin + Vec3::new(-3.0, -3.0, top - gap),
            origin + Vec3::new(x_max, 3.0, top),
            m,
        );
    }
    emitter(&mut scene, origin, -3.0);
    scene
}

/// Renders a layer stack covering the whole view and checks that no pass consumed depth and
/// no pixel was darkened: with `max_depth` 1 only the camera segment may see the emitter, so
/// the image is exactly `L` only if all 24 crossings were free. When `exact_crossings`, the
/// stats must also show every boundary crossed exactly once (no surface skipped by the spawn
/// offset, none hit twice by self-intersection).
fn check_layers(origin: Vec3, gap: f32, exact_crossings: bool) {
    let out = render_and_check(
        layer_scene(origin, gap, 3.0, 1024, Interior::Null),
        1e-6,
        |_, _| Some(L),
    );
    let paths = (RES * RES * SPP) as u64;
    let c = &out.stats.counters;
    assert_eq!(terminated(&out, Termination::PassLimit), 0);
    assert_eq!(terminated(&out, Termination::Absorbed), 0);
    assert_eq!(
        terminated(&out, Termination::MaxDepth),
        paths,
        "every path ends on the emitter: {:?}",
        c.terminated
    );
    // Only the emitter points are shaded: the boundaries are passed, never scattered.
    assert_eq!(items(&out, System::Bxdf), paths);
    if exact_crossings {
        // Each path traces one ray per boundary plus the one that reaches the emitter.
        assert_eq!(
            items(&out, System::Intersect),
            paths * (2 * LAYERS as u64 + 1),
            "boundaries skipped or hit twice"
        );
        assert!(
            out.stats.warnings.is_empty(),
            "inconsistent volume stacks: {:?}",
            out.stats.warnings
        );
    }
}

#[test]
fn thin_layers_near_the_origin_cost_no_depth() {
    // 1e-4 apart: ~800 ulps of the coordinates, 25x the spawn offset there.
    check_layers(Vec3::ZERO, 1e-4, true);
}

#[test]
fn layers_a_few_ulps_apart_are_each_crossed_once() {
    // 2e-6 apart near z = 1 is ~17 ulps of the coordinates: above the spawn offset (about
    // 4 ulps of the largest coordinate), so every boundary must still be crossed exactly
    // once and every interval inside the absorbers measured.
    check_layers(Vec3::ZERO, 2e-6, true);
    check_absorbing_layers(Vec3::ZERO, 2e-6);
}

#[test]
fn thin_layers_far_from_the_origin_cost_no_depth() {
    // At 1e4 the float spacing is ~1e-3, so an absolute spawn epsilon would put the next
    // origin back on the surface just left. 0.1 apart (~100 ulps there) is resolvable: every
    // boundary must still be crossed exactly once.
    check_layers(Vec3::splat(1e4), 0.1, true);
    // 1e-4 apart at 1e4 is below the float spacing (faces coincide or are a few ulps apart):
    // crossings may merge, but no ray may get stuck on them or lose depth to them.
    check_layers(Vec3::splat(1e4), 1e-4, false);
}

#[test]
fn pass_limit_stops_paths_and_counts_them() {
    // The layers cover the left half of the view (pixel columns 0..8); the right half sees the
    // emitter directly. Crossing the 24 boundaries takes 24 passes.
    let left = |x: u32| x < RES / 2;
    let per_half = (RES / 2 * RES * SPP) as u64;

    // One pass short: every path through the layers is stopped (black) and counted.
    let out = render_and_check(
        layer_scene(Vec3::ZERO, 1e-4, 0.0, 2 * LAYERS as u32 - 1, Interior::Null),
        1e-6,
        |x, _| Some(if left(x) { Rgb::BLACK } else { L }),
    );
    assert_eq!(terminated(&out, Termination::PassLimit), per_half);
    assert_eq!(terminated(&out, Termination::MaxDepth), per_half);
    assert_eq!(terminated(&out, Termination::Absorbed), 0);
    let json: serde_json::Value = serde_json::from_str(&out.stats.to_json()).unwrap();
    assert_eq!(json["terminated"]["pass_limit"], per_half, "{json}");

    // Exactly enough passes: everything reaches the emitter.
    let out = render_and_check(
        layer_scene(Vec3::ZERO, 1e-4, 0.0, 2 * LAYERS as u32, Interior::Null),
        1e-6,
        |_, _| Some(L),
    );
    assert_eq!(terminated(&out, Termination::PassLimit), 0);
    assert_eq!(terminated(&out, Termination::MaxDepth), 2 * per_half);
    let json: serde_json::Value = serde_json::from_str(&out.stats.to_json()).unwrap();
    assert!(json["terminated"].get("pass_limit").is_none(), "{json}");
}

#[test]
fn thin_spherical_shell_leaves_no_dark_ring() {
    // Two concentric index-matched spheres 1e-5 apart (2.5x the spawn offset at radius 1):
    // rays crossing the thin shell, including the grazing ones at the silhouettes, must all
    // reach the emitter on the camera segment.
    let res = 64;
    let r = 1.0f32;
    let mut scene = ortho_scene(Vec3::ZERO, 2.2 * r, res, 1024);
    let m = scene.add_material("shell", 0, mat_in(Surface::Interface, Interior::Null));
    for (name, radius) in [("inner", r), ("outer", r * (1.0 + 1e-5))] {
        scene.add_shape(
            name,
            ShapeGeometry::Sphere(Sphere {
                center: Vec3::ZERO,
                radius,
            }),
            m,
            None,
        );
    }
    emitter(&mut scene, Vec3::ZERO, -3.0);
    let out = render_and_check(scene, 1e-6, |_, _| Some(L));
    let paths = (res * res * SPP) as u64;
    assert_eq!(terminated(&out, Termination::MaxDepth), paths);
    assert_eq!(terminated(&out, Termination::PassLimit), 0);
    assert_eq!(items(&out, System::Bxdf), paths);
    // Most rays cross all four boundaries (the view is 2.2 r wide, the disc covers ~65%).
    assert!(
        items(&out, System::Intersect) > paths + 4 * paths / 2,
        "{:?}",
        out.stats.counters.system(System::Intersect)
    );
    assert!(out.stats.warnings.is_empty(), "{:?}", out.stats.warnings);
}

// ---------------------------------------------------------------------------------------
// Thin absorbing layers: Beer-Lambert through many close boundaries.

/// Tolerance on an absorbing length measured through `LAYERS` boxes whose coordinates are at
/// most `extent` in magnitude: every one of the `2 * LAYERS` boundary positions is known to
/// an ulp (`<= extent * EPSILON`), so allow two ulps per boundary.
fn length_tolerance(extent: f32) -> f32 {
    2.0 * (2 * LAYERS) as f32 * extent * f32::EPSILON
}

/// Checks the absorbing length `-ln(T) / sigma` seen in every pixel of `out`, where
/// `T = value / unlit` per channel, against `expected` to within `tol`.
fn check_absorbing_length(out: &RenderOutput, unlit: Rgb, sigma: f32, expected: f32, tol: f32) {
    assert_eq!(out.stats.counters.nan_dropped, 0);
    for y in 0..out.beauty.height {
        for x in 0..out.beauty.width {
            let v = out.beauty.get(x, y).to_array();
            for (c, (v, l)) in v.iter().zip(unlit.to_array()).enumerate() {
                let length = -(v / l).ln() / sigma;
                assert!(
                    (length - expected).abs() <= tol,
                    "pixel ({x}, {y}) channel {c}: absorbing length {length}, expected \
                     {expected} +- {tol} (transmittance {} instead of {})",
                    v / l,
                    (-sigma * expected).exp()
                );
            }
        }
    }
}

/// Camera rays through `LAYERS` index-matched Beer boxes `gap` thick: the image is
/// `L exp(-sigma LAYERS gap)`, sigma chosen so that the transmittance is about 0.55.
fn check_absorbing_layers(origin: Vec3, gap: f32) {
    let length = LAYERS as f32 * gap;
    let sigma = 0.6 / length;
    let scene = layer_scene(
        origin,
        gap,
        3.0,
        1024,
        Interior::Beer {
            sigma_a: Rgb::splat(sigma),
        },
    );
    let out = render_default(&scene.compile().unwrap());
    let extent = origin.abs().max_element() + 1.0;
    check_absorbing_length(&out, L, sigma, length, length_tolerance(extent));
}

#[test]
fn thin_absorbing_layers_follow_beer_lambert() {
    // The layers of the depth tests, now absorbing: each of the 12 intervals inside a volume
    // must be measured from the boundary it starts on, not from wherever the continuation
    // ray was re-spawned.
    check_absorbing_layers(Vec3::ZERO, 1e-4);
    check_absorbing_layers(Vec3::splat(1e4), 0.1);
}

#[test]
fn shadow_rays_through_thin_absorbing_layers_follow_beer_lambert() {
    // A diffuse floor lit by a distant light at 30 degrees through LAYERS Beer boxes, 0.1
    // thick and 0.1 apart, 1e4 from the origin; the camera, below the layers, sees the floor.
    // Only shadow rays cross the layers, on chords gap / cos(theta).
    let origin = Vec3::splat(1e4);
    let (gap, theta) = (0.1f32, 30f32.to_radians());
    let length = LAYERS as f32 * gap / theta.cos();
    let sigma = 0.6 / length;
    let mut scene = Scene::new(
        ortho_camera(origin + Vec3::Y * 0.3, origin, Vec3::Z, 1.0, RES, RES),
        settings(RES, RES, SPP, 2),
    );
    let albedo = Rgb::new(0.8, 0.6, 0.4);
    add_floor(&mut scene, origin, albedo);
    let m = scene.add_material(
        "layer",
        0,
        mat_in(
            Surface::Interface,
            Interior::Beer {
                sigma_a: Rgb::splat(sigma),
            },
        ),
    );
    for k in 0..LAYERS {
        let bottom = 0.5 + 2.0 * k as f32 * gap;
        add_box(
            &mut scene,
            &format!("layer{k}"),
            origin + Vec3::new(-20.0, bottom, -20.0),
            origin + Vec3::new(20.0, bottom + gap, 20.0),
            m,
        );
    }
    let e = Rgb::new(3.0, 2.0, 1.5);
    add_sun(&mut scene, theta, e);
    let out = render_default(&scene.compile().unwrap());
    let unlit = albedo * e * (theta.cos() / std::f32::consts::PI);
    let extent = origin.abs().max_element() + 20.0;
    check_absorbing_length(
        &out,
        unlit,
        sigma,
        length,
        length_tolerance(extent) / theta.cos(),
    );
}

// ---------------------------------------------------------------------------------------
// False boundaries (priorities): liquid in a glass.

/// Absorption of the glass (priority 2, index-matched so that the check is deterministic).
const SIGMA_GLASS: Rgb = Rgb::new(0.3, 0.6, 0.9);
/// Absorption of the liquid (priority 1, a real dielectric: IOR 1.33, no cheap shadows).
const SIGMA_LIQUID: Rgb = Rgb::new(1.5, 0.4, 2.5);

/// Glass material (priority 2) and liquid material (priority 1).
fn glass_and_liquid(scene: &mut Scene) -> (u32, u32) {
    let glass = scene.add_material(
        "glass",
        2,
        mat_in(
            Surface::Interface,
            Interior::Beer {
                sigma_a: SIGMA_GLASS,
            },
        ),
    );
    let liquid = scene.add_material(
        "liquid",
        1,
        mat_in(
            Surface::Dielectric {
                ior: 1.33,
                tint: Rgb::WHITE,
                cheap_shadows: false,
            },
            Interior::Beer {
                sigma_a: SIGMA_LIQUID,
            },
        ),
    );
    (glass, liquid)
}

#[test]
fn false_boundaries_neither_refract_nor_shade_nor_cost_depth() {
    // A glass tumbler seen from above, as one closed shell: the outer box [-1.5, 1.5]^2 x
    // [-1, 1] minus the cavity [-0.5, 0.5]^3. The liquid is a box [-0.75, 0.75]^2 x
    // [-0.7, 0.8], wider and taller than the cavity, so all its faces lie inside the glass
    // wall (the scenes/liquid-in-glass.toml modelling) where they are false boundaries.
    //
    // A camera ray through the cavity (pixels 4..12 in x and y) meets: glass top (z = 1),
    // liquid top (0.8, false), cavity top (0.5), cavity bottom (-0.5), liquid bottom (-0.7,
    // false), glass bottom (-1). Where it is inside both volumes the glass, of higher
    // priority, is the innermost: 1 of glass and 1 of liquid in all. Outside the cavity it
    // crosses 2 of glass (through the liquid's footprint or not). If the liquid's faces were
    // real boundaries the ray would refract (and, at max_depth 1, never count the emitter).
    let view = 2.0;
    let mut scene = ortho_scene(Vec3::ZERO, view, RES, 1024);
    let (glass, liquid) = glass_and_liquid(&mut scene);
    let mut shell = box_tris(Vec3::new(-1.5, -1.5, -1.0), Vec3::new(1.5, 1.5, 1.0));
    shell.extend(inverted_box_tris(Vec3::splat(-0.5), Vec3::splat(0.5)));
    scene.add_shape("glass", ShapeGeometry::Triangles(shell), glass, None);
    add_box(
        &mut scene,
        "liquid",
        Vec3::new(-0.75, -0.75, -0.7),
        Vec3::new(0.75, 0.75, 0.8),
        liquid,
    );
    emitter(&mut scene, Vec3::ZERO, -3.0);

    let in_cavity = |i: u32| (4..12).contains(&i);
    let in_liquid = |i: u32| (2..14).contains(&i);
    let through_cavity = L * beer(SIGMA_GLASS, 1.0) * beer(SIGMA_LIQUID, 1.0);
    let through_wall = L * beer(SIGMA_GLASS, 2.0);
    let out = render_and_check(scene, 1e-4, |x, y| {
        Some(if in_cavity(x) && in_cavity(y) {
            through_cavity
        } else {
            through_wall
        })
    });
    // Boundaries crossed per path: 6 through the cavity, 4 through the liquid's footprint
    // only, 2 through the glass only; plus the ray that reaches the emitter.
    let mut expected_rays = 0u64;
    for y in 0..RES {
        for x in 0..RES {
            let crossings = if in_cavity(x) && in_cavity(y) {
                6
            } else if in_liquid(x) && in_liquid(y) {
                4
            } else {
                2
            };
            expected_rays += SPP as u64 * (crossings + 1);
        }
    }
    let paths = (RES * RES * SPP) as u64;
    assert_eq!(items(&out, System::Intersect), expected_rays);
    // Nothing but the emitter was shaded, and every path ended there.
    assert_eq!(items(&out, System::Bxdf), paths);
    assert_eq!(terminated(&out, Termination::MaxDepth), paths);
    assert!(out.stats.warnings.is_empty(), "{:?}", out.stats.warnings);
}

#[test]
fn shadow_rays_pass_false_boundaries_unchanged() {
    // A diffuse floor y = 0 lit by a distant light at theta through a glass slab y in
    // [0.5, 2.5] (priority 2) holding a liquid slab y in [1, 2] (priority 1, a dielectric
    // that blocks shadow rays when its boundary is real). Inside the glass the liquid's faces
    // are false boundaries: the shadow ray passes them unattenuated and the glass stays the
    // innermost volume, so T = exp(-sigma_glass * 2 / cos(theta)). The camera (below the
    // slabs, looking down) sees the floor only.
    let theta = 40f32.to_radians();
    let mut scene = Scene::new(
        ortho_camera(Vec3::new(0.0, 0.3, 0.0), Vec3::ZERO, Vec3::Z, 1.0, RES, RES),
        settings(RES, RES, SPP, 2),
    );
    let albedo = Rgb::new(0.8, 0.6, 0.4);
    add_floor(&mut scene, Vec3::ZERO, albedo);
    let (glass, liquid) = glass_and_liquid(&mut scene);
    add_box(
        &mut scene,
        "glass",
        Vec3::new(-20.0, 0.5, -20.0),
        Vec3::new(20.0, 2.5, 20.0),
        glass,
    );
    add_box(
        &mut scene,
        "liquid",
        Vec3::new(-15.0, 1.0, -15.0),
        Vec3::new(15.0, 2.0, 15.0),
        liquid,
    );
    let e = Rgb::new(3.0, 2.0, 1.5);
    add_sun(&mut scene, theta, e);
    // Lambert: albedo / pi * E * cos(theta), times the glass's transmittance.
    let expected =
        albedo * e * (theta.cos() / std::f32::consts::PI) * beer(SIGMA_GLASS, 2.0 / theta.cos());
    render_and_check(scene, 1e-4, |_, _| Some(expected));
}

#[test]
fn a_path_that_cannot_leave_ends_at_the_vertex_limit() {
    // The camera and a point light inside a closed room of reflectance-1 walls (six quads
    // facing in): a path's throughput stays 1, so Russian roulette never ends it, and only a
    // numerical leak at an edge lets it out. With an unbounded max_depth every path must end,
    // at MAX_PATH_VERTICES (before the depth column wraps) or through a leak, be counted and
    // warned about, and leave a finite image.
    use risotto::engine::scene::LightComponent;
    use risotto::systems::path::MAX_PATH_VERTICES;
    let cam = perspective(Vec3::ZERO, Vec3::new(0.3, -0.2, -1.0), 60.0, 4, 4);
    let mut scene = Scene::new(cam, settings(4, 4, 1, u32::MAX));
    let white = add_diffuse(&mut scene, "white", 1.0);
    let (x, y, z) = (Vec3::X * 2.0, Vec3::Y * 2.0, Vec3::Z * 2.0);
    let c = Vec3::splat(-1.0);
    let walls = [
        (c, z, x),
        (c + y, x, z),
        (c, x, y),
        (c + z, y, x),
        (c, y, z),
        (c + x, z, y),
    ];
    for (k, (corner, e1, e2)) in walls.into_iter().enumerate() {
        scene.add_shape(&format!("wall{k}"), quad(corner, e1, e2), white, None);
    }
    let bulb = LightComponent::Point {
        position: Vec3::new(0.0, 0.5, 0.0),
        intensity: Rgb::WHITE,
    };
    scene.add_light("bulb", bulb);
    let out = render_default(&scene.compile().unwrap());
    let limited = terminated(&out, Termination::DepthLimit);
    assert!(limited >= 1, "{}", out.stats);
    assert_eq!(
        limited + terminated(&out, Termination::Escaped),
        16,
        "{}",
        out.stats
    );
    // No path took more than MAX_PATH_VERTICES vertices: one ray from each but the last,
    // plus the camera ray.
    assert!(out.stats.counters.rays <= 16 * MAX_PATH_VERTICES as u64);
    assert_eq!(out.stats.counters.nan_dropped, 0);
    assert_finite("closed white room", &out);
    let json: serde_json::Value = serde_json::from_str(&out.stats.to_json()).unwrap();
    assert_eq!(json["terminated"]["depth_limit"], limited, "{json}");
    let summary = out.stats.to_string();
    let warning = format!("warning: {limited} paths reached {MAX_PATH_VERTICES}");
    assert!(summary.contains(&warning), "{summary}");
}

#[test]
fn a_walk_frozen_in_a_medium_too_dense_for_its_coordinates_ends_at_once() {
    // An albedo-1 medium of mean free path 1e-30 in a unit ball: every free flight is far
    // below the float spacing of the coordinates, so a walk's point can never move and its
    // throughput stays 1. Each path must end at its first event inside (counted as frozen,
    // warned about), not walk on in place to the vertex limit, by bounces or by the
    // integrator's own walk.
    use risotto::builtins::media::{HomogeneousMedium, Scattering};
    for scattering in [Scattering::Bounce, Scattering::Walk] {
        let cam = ortho_camera(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, Vec3::Y, 0.5, 2, 2);
        let mut scene = Scene::new(cam, settings(2, 2, 2, u32::MAX));
        let frozen = Interior::Homogeneous(HomogeneousMedium {
            sigma_t: Rgb::splat(1e30),
            sigma_s: Rgb::splat(1e30),
            phase: risotto::systems::phase::PhaseFunction::Isotropic,
            scattering,
            emission: Rgb::BLACK,
            albedo_pattern: None,
            g_pattern: None,
        });
        let m = scene.add_material("frozen", 1, mat_in(Surface::Interface, frozen));
        let ball = Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        };
        scene.add_shape("ball", ShapeGeometry::Sphere(ball), m, None);
        environment(&mut scene, Rgb::WHITE);
        let out = render_default(&scene.compile().unwrap());
        let what = format!("{scattering:?}");
        let c = &out.stats.counters;
        assert_eq!(
            terminated(&out, Termination::DepthLimit),
            0,
            "{what}: {}",
            out.stats
        );
        assert_eq!(
            c.volume_events[risotto::engine::stats::VolumeEvent::Frozen as usize],
            8,
            "{what}: {}",
            out.stats
        );
        assert_eq!(
            terminated(&out, Termination::Absorbed),
            8,
            "{what}: {}",
            out.stats
        );
        assert_eq!(c.nan_dropped, 0);
        assert_finite(&what, &out);
        assert!(
            out.stats
                .to_string()
                .contains("warning: 8 paths ended frozen"),
            "{what}: {}",
            out.stats
        );
    }
}
