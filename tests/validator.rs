//! The boundary validator: an open surface with an interior (a lone quad whose material has a
//! volume) produces unmatched exits, reported once by name; a closed sphere does not.

mod common;
use common::*;
use glam::Vec3;
use risotto::engine::builtin::{Interior, Surface};
use risotto::engine::scene::{Scene, ShapeGeometry};
use risotto::systems::geometry::Sphere;
use risotto_components::Rgb;

fn render_with(geometry: ShapeGeometry) -> Vec<String> {
    let mut scene = Scene::new(camera(40.0, 4.0, 16, 16), settings(16, 16, 4, 16));
    let m = scene.add_material(
        "glassy",
        0,
        mat_in(
            Surface::Interface,
            Interior::Beer {
                sigma_a: Rgb::splat(0.5),
            },
        ),
    );
    scene.add_shape("boundary", geometry, m, None);
    environment(&mut scene, Rgb::WHITE);
    render_default(&scene.compile().unwrap()).stats.warnings
}

#[test]
fn open_boundary_seen_from_behind_is_reported_once_by_name() {
    // A quad facing away from the camera (normal -z): camera rays hit its back face first.
    let quad = vec![
        [
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
        ],
        [
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
        ],
    ];
    let w = render_with(ShapeGeometry::Triangles(quad));
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].contains("\"boundary\""), "{}", w[0]);
}

#[test]
fn closed_sphere_gives_no_warning() {
    let w = render_with(ShapeGeometry::Sphere(Sphere {
        center: Vec3::ZERO,
        radius: 1.0,
    }));
    assert!(w.is_empty(), "{w:?}");
}
