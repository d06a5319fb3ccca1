//! MIS consistency: light sampling only, Bxdf sampling only and their power-heuristic
//! combination are three unbiased estimators of the same integral (Veach 1997, ch. 9), so
//! their image means must agree within their standard errors. A wrong light pdf, a wrong MIS
//! weight or a double-counted emitter shows up as a disagreement.

mod common;
use common::*;
use glam::Vec3;
use risotto::engine::builtin::Surface;
use risotto::engine::integrator::LightingTechnique;
use risotto::engine::render::RenderOutput;
use risotto::engine::scene::{CompiledScene, Scene, ShapeGeometry};
use risotto::systems::geometry::Sphere;
use risotto_components::Rgb;

const TECHNIQUES: [LightingTechnique; 3] = [
    LightingTechnique::Mis,
    LightingTechnique::NeeOnly,
    LightingTechnique::BxdfOnly,
];

/// Renders `build(seed)` with every technique (a different seed each) and checks that every
/// pair of image means agrees within 4 combined standard errors per channel. Returns the
/// renders.
fn assert_techniques_agree(
    build: impl Fn(u64) -> CompiledScene,
    techniques: &[LightingTechnique],
) -> Vec<RenderOutput> {
    let outs: Vec<(LightingTechnique, RenderOutput)> = techniques
        .iter()
        .enumerate()
        .map(|(i, &t)| (t, render_with(&build(i as u64 + 1), t, None)))
        .collect();
    let stats: Vec<(Rgb, Rgb)> = outs.iter().map(|(_, o)| image_mean(o)).collect();
    for a in 0..outs.len() {
        for b in a + 1..outs.len() {
            let ((ma, sa), (mb, sb)) = (stats[a], stats[b]);
            for c in 0..3 {
                let (ma, mb) = (ma.to_array()[c], mb.to_array()[c]);
                let (sa, sb) = (sa.to_array()[c], sb.to_array()[c]);
                let se = (sa * sa + sb * sb).sqrt();
                // The test is only meaningful if the estimates are reasonably precise.
                assert!(
                    se < 0.05 * ma.max(mb),
                    "too noisy: se {se}, means {ma} {mb}"
                );
                assert!(
                    (ma - mb).abs() <= 4.0 * se,
                    "{:?} vs {:?}, channel {c}: {ma} vs {mb} (combined se {se})",
                    outs[a].0,
                    outs[b].0
                );
            }
        }
    }
    outs.into_iter().map(|(_, o)| o).collect()
}

fn diffuse(scene: &mut Scene, name: &str, rho: Rgb) -> u32 {
    scene.add_material(name, 0, mat(Surface::Diffuse { reflectance: rho }))
}

/// An open box (floor, back, left and right walls; no ceiling and no front) with a diffuse
/// sphere, a moderate square area light under the missing ceiling and a sky environment seen
/// through the openings. Several bounces, so the techniques meet at every vertex.
fn open_box(seed: u64) -> CompiledScene {
    let (w, h) = (24, 24);
    let cam = perspective(
        Vec3::new(0.0, 1.0, 3.5),
        Vec3::new(0.0, 0.9, 0.0),
        45.0,
        w,
        h,
    );
    let mut scene = Scene::new(cam, settings(w, h, 1024, 5));
    scene.settings.seed = seed;
    let white = diffuse(&mut scene, "white", Rgb::splat(0.7));
    let red = diffuse(&mut scene, "red", Rgb::new(0.7, 0.1, 0.1));
    let green = diffuse(&mut scene, "green", Rgb::new(0.1, 0.7, 0.1));
    let black = diffuse(&mut scene, "emitter", Rgb::BLACK);
    // Normals: floor z x x = +y, back x x y = +z, left y x z = +x, right z x y = -x.
    let c = Vec3::new(-1.0, 0.0, -1.0);
    scene.add_shape("floor", quad(c, 2.0 * Vec3::Z, 2.0 * Vec3::X), white, None);
    scene.add_shape("back", quad(c, 2.0 * Vec3::X, 2.0 * Vec3::Y), white, None);
    scene.add_shape("left", quad(c, 2.0 * Vec3::Y, 2.0 * Vec3::Z), red, None);
    let c2 = Vec3::new(1.0, 0.0, -1.0);
    scene.add_shape("right", quad(c2, 2.0 * Vec3::Z, 2.0 * Vec3::Y), green, None);
    scene.add_shape(
        "ball",
        ShapeGeometry::Sphere(Sphere {
            center: Vec3::new(0.3, 0.35, -0.3),
            radius: 0.35,
        }),
        white,
        None,
    );
    // 0.6 x 0.6 at y = 1.9, x x z = -y: facing down into the box.
    scene.add_shape(
        "lamp",
        quad(Vec3::new(-0.3, 1.9, -0.5), 0.6 * Vec3::X, 0.6 * Vec3::Z),
        black,
        Some(Rgb::new(12.0, 10.0, 8.0)),
    );
    environment(&mut scene, Rgb::new(0.3, 0.4, 0.5));
    scene.compile().unwrap()
}

#[test]
fn nee_bxdf_and_mis_agree_on_diffuse_box_with_area_light_and_sky() {
    let outs = assert_techniques_agree(open_box, &TECHNIQUES);
    // Sanity: the lamp lights the box (mean well above the sky's contribution alone).
    let (m, _) = image_mean(&outs[0]);
    assert!(m.average() > 0.3, "{m:?}");
}

/// A mirror sphere on a diffuse floor under a square area light: the camera sees the light in
/// the sphere through a specular bounce, which every technique must count exactly once.
fn mirror_ball(seed: u64) -> CompiledScene {
    let (w, h) = (24, 24);
    let cam = perspective(
        Vec3::new(0.0, 1.0, 3.0),
        Vec3::new(0.0, 0.5, 0.0),
        40.0,
        w,
        h,
    );
    let mut scene = Scene::new(cam, settings(w, h, 1024, 4));
    scene.settings.seed = seed;
    let white = diffuse(&mut scene, "white", Rgb::splat(0.6));
    let black = diffuse(&mut scene, "emitter", Rgb::BLACK);
    let mirror = scene.add_material(
        "mirror",
        0,
        mat(Surface::Mirror {
            reflectance: Rgb::new(0.9, 0.8, 0.7),
        }),
    );
    let c = Vec3::new(-3.0, 0.0, -3.0);
    scene.add_shape("floor", quad(c, 6.0 * Vec3::Z, 6.0 * Vec3::X), white, None);
    scene.add_shape(
        "ball",
        ShapeGeometry::Sphere(Sphere {
            center: Vec3::new(0.0, 0.5, 0.0),
            radius: 0.5,
        }),
        mirror,
        None,
    );
    scene.add_shape(
        "lamp",
        quad(Vec3::new(-0.5, 2.0, 0.0), Vec3::X, Vec3::Z),
        black,
        Some(Rgb::splat(10.0)),
    );
    scene.compile().unwrap()
}

#[test]
fn mis_and_bxdf_only_agree_with_a_mirror_reflecting_the_light() {
    let outs = assert_techniques_agree(mirror_ball, &TECHNIQUES);
    // The lamp is above the field of view (about 31 degrees above its centre, half-height
    // 20 degrees). The brightest floor point, right under it, has E ~ 2.3 (form factor of a
    // 1 x 1 square at distance 2), L = 0.6 / pi * E ~ 0.44; a pixel above 3 can only be the
    // lamp (radiance 10) seen in the mirror (reflectance 0.7..0.9).
    let brightest = outs[0]
        .beauty
        .pixels
        .iter()
        .map(|p| p.max_channel())
        .fold(0.0f32, f32::max);
    assert!(
        brightest > 3.0,
        "no visible reflection of the light: {brightest}"
    );
}
