//! White furnace tests: energy conservation of diffuse and dielectric surfaces.

mod common;
use common::*;
use glam::Vec3;
use risotto::builtins::builtin::Surface;
use risotto::engine::scene::{Scene, ShapeGeometry};
use risotto::systems::geometry::Sphere;
use risotto_components::Rgb;

fn furnace(surface: Surface) -> (Rgb, Rgb) {
    let mut scene = Scene::new(camera(40.0, 4.0, 32, 32), settings(32, 32, 64, 64));
    scene.settings.rr_depth = 64;
    let m = scene.add_material("m", 0, mat(surface));
    scene.add_shape(
        "sphere",
        ShapeGeometry::Sphere(Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        }),
        m,
        None,
    );
    environment(&mut scene, Rgb::WHITE);
    let out = render_default(&scene.compile().unwrap());
    image_mean(&out)
}

#[test]
fn diffuse_albedo_one_sphere_disappears_in_a_furnace() {
    let (mean, se) = furnace(Surface::Diffuse {
        reflectance: Rgb::WHITE,
    });
    for (m, s) in mean.to_array().iter().zip(se.to_array()) {
        assert!((m - 1.0).abs() <= 3.0 * s + 1e-3, "mean {m} se {s}");
    }
}

#[test]
fn glass_sphere_conserves_energy_in_a_furnace() {
    let (mean, se) = furnace(Surface::Dielectric {
        ior: 1.5,
        tint: Rgb::WHITE,
        cheap_shadows: false,
    });
    for (m, s) in mean.to_array().iter().zip(se.to_array()) {
        assert!((m - 1.0).abs() <= 3.0 * s + 1e-3, "mean {m} se {s}");
    }
}
