//! Hard cases (issue 14): valid scenes at awkward scales and positions whose images have an
//! exact or invariant expectation. Every test checks the expectation within 3 standard errors
//! (from the film's variance layer) plus a small allowance for float rounding.

mod common;
use common::*;
use glam::Vec3;
use risotto::builtins::builtin::{Interior, Surface};
use risotto::engine::render::RenderOutput;
use risotto::engine::scene::{Scene, ShapeGeometry};
use risotto::systems::geometry::Sphere;
use risotto_components::Rgb;

/// Asserts `got` (mean, standard error) equals `want` within 3 sigma and `rel` relative.
fn assert_matches(what: &str, got: (Rgb, Rgb), want: f64, rel: f64) {
    let (mean, se) = got;
    for (c, (m, s)) in mean.to_array().into_iter().zip(se.to_array()).enumerate() {
        let tol = 3.0 * s as f64 + rel * want.abs() + 1e-7;
        assert!(
            (m as f64 - want).abs() <= tol,
            "{what}, channel {c}: {m} +- {s} vs {want} (tolerance {tol})"
        );
    }
}

/// A diffuse sphere of albedo `rho` and radius `r` whose top touches the origin, lit by a
/// sun of irradiance pi straight down, seen by an orthographic camera from above across
/// `view` units: each visible point has radiance `rho cos(theta)` (direct lighting only).
fn sphere_top(r: f32, view: f32, rho: f32) -> (Scene, f64) {
    let n = 16;
    let cam = ortho_camera(Vec3::Y * 3.0, Vec3::ZERO, Vec3::Z, view, n, n);
    let mut scene = Scene::new(cam, settings(n, n, 8, 2));
    let m = scene.add_material(
        "ball",
        0,
        mat(Surface::Diffuse {
            reflectance: Rgb::splat(rho),
        }),
    );
    scene.add_shape(
        "ball",
        ShapeGeometry::Sphere(Sphere {
            center: Vec3::new(0.0, -r, 0.0),
            radius: r,
        }),
        m,
        None,
    );
    add_sun(&mut scene, 0.0, Rgb::splat(std::f32::consts::PI));
    // The image mean: rho times the mean of cos(theta) = sqrt(1 - (x^2 + z^2) / r^2) over
    // the square of side `view` (midpoint rule, converged far below the tolerance).
    let (k, h) = (400, view as f64 / 2.0);
    let mut sum = 0.0;
    for i in 0..k {
        for j in 0..k {
            let x = -h + (i as f64 + 0.5) * view as f64 / k as f64;
            let z = -h + (j as f64 + 0.5) * view as f64 / k as f64;
            sum += (1.0 - (x * x + z * z) / (r as f64 * r as f64)).sqrt();
        }
    }
    (scene, rho as f64 * sum / (k * k) as f64)
}

/// Item 3: shadow rays leaving the top of a sphere centred at (0, -r, 0) were spawned below
/// its surface (the hit point `centre + n r` in f32 erred by ulps of r, the offset was
/// relative to the point, near zero): 0.379 instead of 0.5 at r = 1, 0.190 at r = 100.
#[test]
fn sphere_top_lit_from_above_has_no_acne() {
    for r in [1.0f32, 100.0, 1e4] {
        let (scene, want) = sphere_top(r, 0.2 * r, 0.5);
        let out = render_default(&scene.compile().unwrap());
        assert_finite("sphere top", &out);
        assert_matches(&format!("r = {r}"), image_mean(&out), want, 1e-4);
    }
}

/// A unit box on a ground of the given geometry, under a sun straight down (irradiance pi)
/// and a dim sky; an orthographic camera from above sees the ground beside the box.
fn box_on_ground(ground: ShapeGeometry) -> RenderOutput {
    let n = 16;
    let cam = ortho_camera(
        Vec3::new(2.0, 5.0, 0.0),
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::Z,
        2.0,
        n,
        n,
    );
    let mut scene = Scene::new(cam, settings(n, n, 16, 3));
    let m = add_diffuse(&mut scene, "grey", 0.5);
    scene.add_shape("ground", ground, m, None);
    add_box(
        &mut scene,
        "box",
        Vec3::new(-0.5, 0.0, -0.5),
        Vec3::new(0.5, 1.0, 0.5),
        m,
    );
    add_sun(&mut scene, 0.0, Rgb::splat(std::f32::consts::PI));
    environment(&mut scene, Rgb::splat(0.1));
    render_default(&scene.compile().unwrap())
}

/// Item 3: the ground beside a box on a radius-100 sphere was 36% darker than on a plane.
/// The sphere's ground lies at most 0.045 below the plane here and tilts by at most 0.03
/// rad: the two agree to well under 1%.
#[test]
fn box_on_a_sphere_ground_matches_a_plane_ground() {
    let r = 100.0;
    let sphere = box_on_ground(ShapeGeometry::Sphere(Sphere {
        center: Vec3::new(0.0, -r, 0.0),
        radius: r,
    }));
    let plane = box_on_ground(quad(
        Vec3::new(-50.0, 0.0, -50.0),
        Vec3::Z * 100.0,
        Vec3::X * 100.0,
    ));
    assert_finite("sphere ground", &sphere);
    let (ms, ss) = image_mean(&sphere);
    let (mp, sp) = image_mean(&plane);
    let se = (ss * ss + sp * sp).map(f32::sqrt);
    assert_matches(
        "sphere - plane + 1",
        (ms - mp + Rgb::splat(1.0), se),
        1.0,
        0.01,
    );
}

/// Item 3: a camera 1.7 units above a sphere of radius 1e4 looking at the horizon saw a
/// black band of ground just below it. Every ground pixel is lit by the sun (30 degrees
/// from the zenith; the ground's normal tilts by under 0.02 rad up to the horizon), so
/// none is below half of `rho E cos(31 deg) / pi`.
#[test]
fn huge_sphere_ground_has_no_black_horizon_band() {
    let r = 1e4f32;
    let (w, h) = (32u32, 32u32);
    let fov = 20.0f32;
    let eye = Vec3::new(0.0, 1.7, 0.0);
    let cam = perspective(eye, eye + Vec3::new(0.0, 0.0, -1.0), fov, w, h);
    let mut scene = Scene::new(cam, settings(w, h, 4, 2));
    let m = add_diffuse(&mut scene, "ground", 0.5);
    scene.add_shape(
        "ground",
        ShapeGeometry::Sphere(Sphere {
            center: Vec3::new(0.0, -r, 0.0),
            radius: r,
        }),
        m,
        None,
    );
    add_sun(
        &mut scene,
        30f32.to_radians(),
        Rgb::splat(std::f32::consts::PI),
    );
    let out = render_default(&scene.compile().unwrap());
    assert_finite("horizon", &out);
    // The horizon dips acos(r / (r + 1.7)) = 0.0184 rad below the view axis; rows whose
    // whole pixel lies 0.025 rad below it see ground only.
    let half = (fov.to_radians() / 2.0).tan();
    let lowest_pixel_angle =
        |y: u32| ((y as f32 - h as f32 / 2.0) / (w as f32 / 2.0) * half).atan();
    let want = 0.5 * 0.5 * 31f32.to_radians().cos();
    let mut checked = 0;
    for y in 0..h {
        if lowest_pixel_angle(y) < 0.025 {
            continue;
        }
        for x in 0..w {
            let p = out.beauty.get(x as usize, y as usize);
            assert!(
                p.to_array().iter().all(|&c| c > 0.5 * want),
                "pixel ({x}, {y}): {p:?}"
            );
            checked += 1;
        }
    }
    assert!(checked >= 8 * w, "{checked} pixels checked");
}

/// A scene of `n x n` pixels, `spp` samples, direct lighting only: a grey (0.5) diffuse
/// floor, the 10 x 10 square of `y = 0` (normal +y, z x x) around `offset`, seen straight
/// from above by an orthographic camera 2 units across.
fn grey_floor_from_above(offset: Vec3, n: u32, spp: u32) -> Scene {
    let cam = ortho_camera(offset + Vec3::Y * 3.0, offset, Vec3::Z, 2.0, n, n);
    let mut scene = Scene::new(cam, settings(n, n, spp, 2));
    let grey = add_diffuse(&mut scene, "grey", 0.5);
    scene.add_shape(
        "floor",
        quad(
            offset + Vec3::new(-5.0, 0.0, -5.0),
            Vec3::Z * 10.0,
            Vec3::X * 10.0,
        ),
        grey,
        None,
    );
    scene
}

/// A 1 x 1 lamp (radiance 1, facing down) 1 unit over a diffuse floor, both moved by
/// `offset`; an orthographic camera from above (through the one-sided lamp's back) sees the
/// floor under it.
fn lamp_over_floor(offset: Vec3) -> RenderOutput {
    let mut scene = grey_floor_from_above(offset, 16, 16);
    let black = add_diffuse(&mut scene, "lamp", 0.0);
    // Lamp normal -y (x x z).
    scene.add_shape(
        "lamp",
        quad(offset + Vec3::new(-0.5, 1.0, -0.5), Vec3::X, Vec3::Z),
        black,
        Some(Rgb::splat(1.0)),
    );
    render_default(&scene.compile().unwrap())
}

/// Item 2: area-light shadow rays failed about 1e4 units from the origin (0.0259 against
/// 0.0692). The same scene at the origin and moved by (2e3, 0, 2e3), 1e4 or 1e5 gives the
/// same image within noise (0.0091 against 0.0398 at 2e3 before the fix).
#[test]
fn area_light_far_from_the_origin_matches_the_origin() {
    let at_origin = image_mean(&lamp_over_floor(Vec3::ZERO));
    for far in [2e3f32, 1e4, 1e5] {
        let moved = lamp_over_floor(Vec3::new(far, 0.0, far));
        assert_finite("moved lamp", &moved);
        let (m, s) = image_mean(&moved);
        let se = (s * s + at_origin.1 * at_origin.1).map(f32::sqrt);
        assert_matches(
            &format!("moved by {far}: difference + 1"),
            (m - at_origin.0 + Rgb::splat(1.0), se),
            1.0,
            0.0,
        );
    }
}

/// The grey floor ([`grey_floor_from_above`]) under a slab of absorbing medium `1e-4` thick
/// (an index-matched box `y in [1e-4, 2e-4]`, Beer `sigma_a = 5000`) and a sun straight down
/// (irradiance pi), all moved by `offset`: the camera ray and the shadow ray each cross the
/// slab once, normally, so every pixel is `0.5 exp(-sigma_a d)^2 = 0.5 / e`.
fn floor_under_thin_slab(offset: Vec3) -> RenderOutput {
    let mut scene = grey_floor_from_above(offset, 8, 4);
    let absorber = scene.add_material(
        "absorber",
        0,
        mat_in(
            Surface::Interface,
            Interior::Beer {
                sigma_a: Rgb::splat(5000.0),
            },
        ),
    );
    add_box(
        &mut scene,
        "slab",
        offset + Vec3::new(-4.0, 1e-4, -4.0),
        offset + Vec3::new(4.0, 2e-4, 4.0),
        absorber,
    );
    add_sun(&mut scene, 0.0, Rgb::splat(std::f32::consts::PI));
    render_default(&scene.compile().unwrap())
}

/// Thin shells far from the origin: the spawn offset was `5e-7` of the largest coordinate
/// (`5e-3` at `1e4`), so rays restarting on a face of a slab `1e-4` thick skipped the other
/// face, and shadow rays from the floor started above the slab. With offsets from the
/// points' own error bounds (zero along `y` here: every face has exact `y` coordinates) the
/// camera ray and the shadow ray both cross it, at every offset: `0.5 exp(-1) = 0.18394`.
#[test]
fn thin_absorbing_slab_far_from_the_origin_attenuates_by_beer() {
    let want = 0.5 * (-1.0f64).exp();
    for far in [0.0f32, 1e2, 1e4, 1e5] {
        let out = floor_under_thin_slab(Vec3::new(far, 0.0, far));
        assert_finite("thin slab", &out);
        // Slab faces are 1e-4 apart in f32: `2e-4 - 1e-4` is exact to 1e-11, but the
        // thickness itself is f32's 1e-4, 2.5e-9 relative from the decimal; allow 1e-4.
        assert_matches(&format!("offset {far}"), image_mean(&out), want, 1e-4);
    }
}

/// A diffuse floor under a point light 2 units up and a constant sky, everything scaled by
/// `s` (the light's intensity by `s^2`, so the irradiance stays the same), seen from above
/// around the light's foot.
fn point_lit_floor(s: f32) -> RenderOutput {
    let n = 8;
    let cam = ortho_camera(Vec3::Y * 5.0 * s, Vec3::ZERO, Vec3::Z, 0.5 * s, n, n);
    let mut scene = Scene::new(cam, settings(n, n, 64, 2));
    let grey = add_diffuse(&mut scene, "grey", 0.5);
    scene.add_shape(
        "floor",
        quad(
            Vec3::new(-20.0, 0.0, -20.0) * s,
            Vec3::Z * 40.0 * s,
            Vec3::X * 40.0 * s,
        ),
        grey,
        None,
    );
    scene.add_light(
        "bulb",
        risotto::engine::scene::LightComponent::Point {
            position: Vec3::Y * 2.0 * s,
            intensity: Rgb::splat(4.0 * s * s),
        },
    );
    environment(&mut scene, Rgb::splat(0.2));
    render_default(&scene.compile().unwrap())
}

/// Item 8: scaled by 1e-6, the scene's light-selection radius was clamped to 1e-3, which
/// inflated the sky's power by 1e6 against the bulb's: the bulb was almost never selected
/// and the floor came out 11% dark. The same scene at scale 1e-6 and 1 agrees.
#[test]
fn tiny_scene_does_not_starve_its_point_light() {
    let unit = image_mean(&point_lit_floor(1.0));
    let tiny = point_lit_floor(1e-6);
    assert_finite("tiny scene", &tiny);
    let (m, s) = image_mean(&tiny);
    let se = (s * s + unit.1 * unit.1).map(f32::sqrt);
    assert_matches(
        "scale 1e-6 - scale 1 + 1",
        (m - unit.0 + Rgb::splat(1.0), se),
        1.0,
        0.0,
    );
}

/// A camera `height` above a large diffuse floor (the 40 x 40 square around the origin,
/// albedo 0.5) looking 45 degrees down, lit by a sun straight down (irradiance pi): every
/// pixel sees the floor at radiance 0.5 exactly (nothing else is in the scene).
fn camera_just_above_floor(height: f32) -> RenderOutput {
    let (w, h) = (16, 16);
    let eye = Vec3::new(0.0, height, 0.0);
    let cam = perspective(eye, eye + Vec3::new(0.0, -1.0, -1.0), 40.0, w, h);
    let mut scene = Scene::new(cam, settings(w, h, 2, 2));
    let m = add_diffuse(&mut scene, "floor", 0.5);
    scene.add_shape(
        "floor",
        quad(Vec3::new(-20.0, 0.0, -20.0), Vec3::Z * 40.0, Vec3::X * 40.0),
        m,
        None,
    );
    add_sun(&mut scene, 0.0, Rgb::splat(std::f32::consts::PI));
    render_default(&scene.compile().unwrap())
}

/// Item 4: a camera 1e-6 above a plane looking 45 degrees down saw through it (the upper
/// half of the image exactly 0): rays whose dominant axis is horizontal shear the far
/// vertices (20 units off) into the triangle test, whose conservative t bound (about
/// 1e-6 there) rejected the true hit at t = 1.4e-6. Every pixel must see the floor.
#[test]
fn camera_just_above_a_plane_sees_the_plane() {
    for height in [1e-3f32, 1e-6, 1e-8, 1e-12] {
        let out = camera_just_above_floor(height);
        assert_finite("camera above floor", &out);
        for (i, p) in out.beauty.pixels.iter().enumerate() {
            assert!(
                (p.r - 0.5).abs() < 1e-4,
                "height {height}: pixel ({}, {}) is {p:?}, want 0.5",
                i % 16,
                i / 16
            );
        }
    }
}

/// A slab `y in [-1, 0]` (40 x 40) of `surface` with a Beer interior (sigma_a 1) under a
/// constant sky of radiance 1, seen by a camera at `eye` looking along `dir`.
fn camera_in_slab(surface: Surface, eye: Vec3, dir: Vec3) -> RenderOutput {
    let (w, h) = (8, 8);
    let cam = perspective(eye, eye + dir, 30.0, w, h);
    let mut scene = Scene::new(cam, settings(w, h, 64, 8));
    let m = scene.add_material(
        "glass",
        0,
        mat_in(
            surface,
            risotto::builtins::builtin::Interior::Beer {
                sigma_a: Rgb::splat(1.0),
            },
        ),
    );
    add_box(
        &mut scene,
        "slab",
        Vec3::new(-20.0, -1.0, -20.0),
        Vec3::new(20.0, 0.0, 20.0),
        m,
    );
    environment(&mut scene, Rgb::splat(1.0));
    render_default(&scene.compile().unwrap())
}

/// Item 4: a camera exactly on a glass surface showed no absorption at all. A camera on
/// the surface of a slab, looking into it, sees what a camera 1e-4 inside sees (the
/// absorption along the path to the slab's floor): for an index-matched interface that is
/// about exp(-sqrt 2) = 0.24, and for glass the same image as just inside.
#[test]
fn camera_on_a_glass_surface_is_inside_the_glass() {
    for surface in [
        Surface::Interface,
        Surface::Dielectric {
            ior: 1.5,
            tint: Rgb::splat(1.0),
            cheap_shadows: false,
        },
    ] {
        // On the top face looking down, on the bottom face looking up, on the side face
        // x = 20 looking in and down (the probe for the camera's volumes used to come from
        // one fixed direction, so only the first case worked).
        for (on, inside, dir) in [
            (
                Vec3::ZERO,
                Vec3::new(0.0, -1e-4, 0.0),
                Vec3::new(0.0, -1.0, -1.0),
            ),
            (
                Vec3::new(0.0, -1.0, 0.0),
                Vec3::new(0.0, -1.0 + 1e-4, 0.0),
                Vec3::new(0.0, 1.0, -1.0),
            ),
            (
                Vec3::new(20.0, -0.5, 0.0),
                Vec3::new(20.0 - 1e-4, -0.5, 0.0),
                Vec3::new(-1.0, -1.0, 0.0),
            ),
        ] {
            let what = format!("{surface:?} at {on}");
            let on = camera_in_slab(surface.clone(), on, dir);
            let inside = camera_in_slab(surface.clone(), inside, dir);
            assert_finite("camera on glass", &on);
            let (m, s) = image_mean(&on);
            let (mi, si) = image_mean(&inside);
            assert!(mi.r < 0.5, "{what}: just inside gives {mi:?}");
            let se = (s * s + si * si).map(f32::sqrt);
            assert_matches(
                &format!("{what}: on the surface - just inside + 1"),
                (m - mi + Rgb::splat(1.0), se),
                1.0,
                2e-3,
            );
        }
    }
}

/// Item 7: emission 1e38 seen directly gave infinite beauty pixels (16 samples summed past
/// f32's 3.4e38). A lamp of radiance 1e38 facing the camera renders as 1e38, every layer
/// finite.
#[test]
fn emission_of_1e38_renders_finite() {
    let n = 8;
    let cam = ortho_camera(Vec3::Y * 3.0, Vec3::ZERO, Vec3::Z, 1.0, n, n);
    let mut scene = Scene::new(cam, settings(n, n, 16, 2));
    let black = add_diffuse(&mut scene, "lamp", 0.0);
    // Normal +y (z x x), towards the camera.
    scene.add_shape(
        "lamp",
        quad(Vec3::new(-1.0, 0.0, -1.0), Vec3::Z * 2.0, Vec3::X * 2.0),
        black,
        Some(Rgb::splat(1e38)),
    );
    let out = render_default(&scene.compile().unwrap());
    assert_finite("lamp of 1e38", &out);
    for p in &out.beauty.pixels {
        assert!((p.r / 1e38 - 1.0).abs() < 1e-5, "{p:?}");
    }
}

/// A floor, a sun, a sky and one ball per entry of `balls` (material index, shape name), all
/// the same sphere of radius 1 on the floor, seen from above at an angle.
fn balls_scene(materials: &[(&str, i32, Surface, Interior)], balls: &[(usize, &str)]) -> Scene {
    let (w, h) = (24, 16);
    let cam = perspective(
        Vec3::new(0.0, 2.0, 5.0),
        Vec3::new(0.0, 0.8, 0.0),
        35.0,
        w,
        h,
    );
    let mut scene = Scene::new(cam, settings(w, h, 16, 12));
    add_floor(&mut scene, Vec3::ZERO, Rgb::splat(0.5));
    let ids: Vec<u32> = materials
        .iter()
        .map(|(name, priority, surface, interior)| {
            scene.add_material(name, *priority, mat_in(surface.clone(), interior.clone()))
        })
        .collect();
    for &(m, name) in balls {
        let ball = Sphere {
            center: Vec3::Y,
            radius: 1.0,
        };
        scene.add_shape(name, ShapeGeometry::Sphere(ball), ids[m], None);
    }
    add_sun(&mut scene, 0.6, Rgb::new(3.0, 2.9, 2.7));
    environment(&mut scene, Rgb::new(0.2, 0.25, 0.35));
    scene
}

/// Item 10: two glass balls with the same centre and radius rendered unlike one (the spawn
/// offset past one surface skipped the other's crossing, and rays left balls they were
/// never recorded inside). Of coincident shapes only the one of highest priority is built
/// (ties: the first, when they share a material), so the image is bit for bit the image of
/// that one ball alone; equal priorities with different materials are an error.
#[test]
fn coincident_glass_balls_render_as_one() {
    let glass = || Surface::Dielectric {
        ior: 1.5,
        tint: Rgb::splat(1.0),
        cheap_shadows: false,
    };
    let water = Surface::Dielectric {
        ior: 1.33,
        tint: Rgb::splat(1.0),
        cheap_shadows: false,
    };
    let ink = Interior::Beer {
        sigma_a: Rgb::new(0.3, 1.2, 3.0),
    };
    let render_of = |scene: Scene| {
        let out = render_default(&scene.compile().unwrap());
        assert_finite("coincident balls", &out);
        out
    };
    // (materials, the coincident balls, the one ball they must render as)
    type Case<'a> = (
        Vec<(&'a str, i32, Surface, Interior)>,
        Vec<(usize, &'a str)>,
        (usize, &'a str),
    );
    let cases: [Case; 3] = [
        // Two balls of one glass.
        (
            vec![("glass", 0, glass(), Interior::None)],
            vec![(0, "ball"), (0, "ball2")],
            (0, "ball"),
        ),
        // Three, of glass with ink inside.
        (
            vec![("inked", 0, glass(), ink.clone())],
            vec![(0, "ball"), (0, "ball2"), (0, "ball3")],
            (0, "ball"),
        ),
        // Water of priority 1 and glass of priority 0: the water fills the ball.
        (
            vec![
                ("water", 1, water.clone(), ink.clone()),
                ("glass", 0, glass(), Interior::None),
            ],
            vec![(0, "drop"), (1, "ball")],
            (0, "drop"),
        ),
    ];
    for (materials, balls, one) in cases {
        let what = format!("{balls:?}");
        let many = render_of(balls_scene(&materials, &balls));
        let single = render_of(balls_scene(&materials, &[one]));
        assert!(
            many.beauty.pixels == single.beauty.pixels,
            "{what}: mean {:?} against one ball's {:?}",
            many.beauty.mean(),
            single.beauty.mean()
        );
        // Every ball but the one is named as left out, and no ray crossed a boundary
        // wrongly (the boundary validator's warnings).
        assert_eq!(
            many.stats.warnings.len(),
            balls.len() - 1,
            "{what}: {:?}",
            many.stats.warnings
        );
        for w in &many.stats.warnings {
            assert!(w.contains("left out"), "{what}: {w}");
        }
    }
    // Triangles: a glass crate listed twice (the same 12 triangles) renders as one.
    let crates = |n: usize| {
        let mut scene = balls_scene(&[("glass", 0, glass(), ink.clone())], &[]);
        for i in 0..n {
            let (lo, hi) = (Vec3::new(-0.7, 0.0, -0.7), Vec3::new(0.7, 1.4, 0.7));
            // Material 0 is the floor's; 1 is the glass.
            add_box(&mut scene, &format!("crate{i}"), lo, hi, 1);
        }
        render_of(scene)
    };
    let (two, one) = (crates(2), crates(1));
    assert!(
        two.beauty.pixels == one.beauty.pixels,
        "two crates: mean {:?} against one crate's {:?}",
        two.beauty.mean(),
        one.beauty.mean()
    );
    assert_eq!(two.stats.warnings.len(), 1, "{:?}", two.stats.warnings);
    // Water and glass of the same priority: which fills the ball is undefined.
    let e = balls_scene(
        &[
            ("water", 0, water, Interior::None),
            ("glass", 0, glass(), Interior::None),
        ],
        &[(0, "drop"), (1, "ball")],
    )
    .compile()
    .err()
    .expect("equal priorities, different materials accepted");
    let msg = e.to_string();
    for needle in ["\"ball\"", "\"drop\"", "\"water\"", "\"glass\"", "priority"] {
        assert!(msg.contains(needle), "{msg} lacks {needle}");
    }
}

/// A light value above the documented maximum (1e30, `MAX_RADIANCE`) is an error at its
/// line, for every kind of light: the fuzzer found `emission = 3e38` behind a subsurface
/// walk overflowing f32 on its way to the film (two samples dropped as infinite).
#[test]
fn light_values_above_the_documented_maximum_are_located_errors() {
    use risotto::loader::scene_file::parse_scene;
    let base = |extra: &str| {
        format!(
            "[camera]\nfov = 40\nfrom = [0, 0, 4]\nto = [0, 0, 0]\n\n[materials.m]\ntype = \"diffuse\"\n\n{extra}\n"
        )
    };
    let cases = [
        "[[shapes]]\ntype = \"sphere\"\nmaterial = \"m\"\nradius = 1\nemission = 3e38",
        "[[lights]]\ntype = \"environment\"\nradiance = [1, 2e30, 1]",
        "[[lights]]\ntype = \"point\"\nposition = [0, 2, 0]\nintensity = 1e31",
        "[[lights]]\ntype = \"distant\"\ndirection = [0, -1, 0]\nirradiance = 1e35",
    ];
    let path = std::path::Path::new("max.toml");
    for case in cases {
        let text = base(case);
        let e = parse_scene(&text, path).expect_err(case).to_string();
        let line = text.lines().count();
        assert!(
            e.contains("max.toml") && e.contains("1e30") && e.contains(&format!(":{line}:")),
            "{case}: {e}"
        );
    }
    // At the maximum: accepted.
    assert!(parse_scene(
        &base("[[lights]]\ntype = \"environment\"\nradiance = 1e30"),
        path
    )
    .is_ok());
}
