//! Helpers shared by the integration tests: small scenes built in code.
#![allow(dead_code, reason = "each test binary uses a different subset")]

use glam::Vec3;
use risotto::engine::builtin::{BuiltinMaterial, Interior, Surface};
use risotto::engine::render::{render, RenderOptions, RenderOutput};
use risotto::engine::scene::{CompiledScene, LightComponent, RenderSettings, Scene};
use risotto::systems::camera::{Camera, Projection};
use risotto_components::Rgb;

/// A camera looking down -z from `z = dist` with a horizontal fov.
pub fn camera(fov: f32, dist: f32, w: u32, h: u32) -> Camera {
    Camera::look_at(
        Projection::Perspective { fov_deg: fov },
        Vec3::new(0.0, 0.0, dist),
        Vec3::ZERO,
        Vec3::Y,
        w,
        h,
    )
    .unwrap()
}

/// Settings with the given resolution and spp.
pub fn settings(w: u32, h: u32, spp: u32, max_depth: u32) -> RenderSettings {
    RenderSettings {
        width: w,
        height: h,
        spp,
        max_depth,
        ..Default::default()
    }
}

/// A built-in material.
pub fn mat(surface: Surface) -> Box<BuiltinMaterial> {
    Box::new(BuiltinMaterial {
        surface,
        interior: Interior::None,
    })
}

/// A built-in material with an interior.
pub fn mat_in(surface: Surface, interior: Interior) -> Box<BuiltinMaterial> {
    Box::new(BuiltinMaterial { surface, interior })
}

/// A constant environment.
pub fn environment(scene: &mut Scene, radiance: Rgb) {
    scene.add_light(
        "env",
        LightComponent::Environment {
            radiance,
            map: None,
        },
    );
}

/// Renders with default options.
pub fn render_default(scene: &CompiledScene) -> RenderOutput {
    render(scene, &RenderOptions::default(), &|_| {}).unwrap()
}

/// Mean and standard error of the image mean (per channel), from the film's per-pixel
/// variances.
pub fn image_mean(out: &RenderOutput) -> (Rgb, Rgb) {
    let n = out.beauty.pixels.len() as f32;
    let mut mean = Rgb::BLACK;
    let mut var = Rgb::BLACK;
    for (p, v) in out.beauty.pixels.iter().zip(&out.variance.pixels) {
        mean += *p;
        var += *v;
    }
    (mean / n, (var / (n * n)).map(f32::sqrt))
}

/// A parallelogram `corner, corner + e1, corner + e1 + e2, corner + e2` as two triangles
/// whose geometric normal is `normalize(e1 x e2)`.
pub fn quad(corner: Vec3, e1: Vec3, e2: Vec3) -> Vec<[Vec3; 3]> {
    vec![
        [corner, corner + e1, corner + e1 + e2],
        [corner, corner + e1 + e2, corner + e2],
    ]
}

/// The axis-aligned box `[lo, hi]` as 12 triangles with outward normals.
pub fn box_tris(lo: Vec3, hi: Vec3) -> Vec<[Vec3; 3]> {
    let s = hi - lo;
    let (x, y, z) = (Vec3::X * s.x, Vec3::Y * s.y, Vec3::Z * s.z);
    let mut t = Vec::with_capacity(12);
    // Each face: corner and two edges ordered so that e1 x e2 points out of the box.
    t.extend(quad(lo, z, y)); // x = lo.x, normal -x (z x y = -x)
    t.extend(quad(lo + x, y, z)); // x = hi.x, normal +x
    t.extend(quad(lo, x, z)); // y = lo.y, normal -y (x x z = -y)
    t.extend(quad(lo + y, z, x)); // y = hi.y, normal +y
    t.extend(quad(lo, y, x)); // z = lo.z, normal -z (y x x = -z)
    t.extend(quad(lo + z, x, y)); // z = hi.z, normal +z
    t
}
