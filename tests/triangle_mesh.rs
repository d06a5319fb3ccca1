//! Shapes given as meshes (`ShapeGeometry::Mesh`: shared vertices and three indices a
//! triangle, as mesh files hold them; issue 36) are the surfaces of the soups of their
//! triangles: the same image bit for bit, and coincident with them.

mod common;
use common::*;
use glam::Vec3;
use risotto::builtins::builtin::{Interior, Surface};
use risotto::engine::scene::{Scene, ShapeGeometry, TriangleMesh};
use risotto_components::Rgb;

/// A box of glass with ink inside, as a mesh of its 8 corners (listed in an order of their
/// own) or as the soup of the same triangles.
fn glass_box(as_mesh: bool) -> ShapeGeometry {
    let soup = box_tris(Vec3::new(-0.8, 0.0, -0.6), Vec3::new(0.7, 1.2, 0.9));
    let mesh = TriangleMesh::from_soup(&soup);
    assert_eq!(mesh.positions.len(), 8);
    // The vertices reversed: a mesh's order is its file's, not the weld's.
    let n = mesh.positions.len() as u32;
    let reversed = TriangleMesh {
        positions: mesh.positions.iter().rev().copied().collect(),
        triangles: mesh
            .triangles
            .iter()
            .map(|t| t.map(|k| n - 1 - k))
            .collect(),
    };
    assert!((0..reversed.len()).all(|i| reversed.triangle(i) == soup[i]));
    if as_mesh {
        ShapeGeometry::Mesh(reversed)
    } else {
        ShapeGeometry::Triangles(soup)
    }
}

/// A floor, a sun and a sky, and the glass boxes `boxes` (true: a mesh) in one material.
fn scene(boxes: &[bool]) -> Scene {
    let (w, h) = (24, 16);
    let cam = perspective(
        Vec3::new(0.5, 2.5, 5.0),
        Vec3::new(0.0, 0.5, 0.0),
        35.0,
        w,
        h,
    );
    let mut scene = Scene::new(cam, settings(w, h, 16, 12));
    add_floor(&mut scene, Vec3::ZERO, Rgb::splat(0.5));
    let glass = Surface::Dielectric {
        ior: 1.5,
        tint: Rgb::splat(1.0),
        cheap_shadows: false,
    };
    let ink = Interior::Beer {
        sigma_a: Rgb::new(0.3, 1.2, 3.0),
    };
    let m = scene.add_material("inked", 0, mat_in(glass, ink));
    for (i, &as_mesh) in boxes.iter().enumerate() {
        scene.add_shape(&format!("box{i}"), glass_box(as_mesh), m, None);
    }
    add_sun(&mut scene, 0.6, Rgb::new(3.0, 2.9, 2.7));
    environment(&mut scene, Rgb::new(0.2, 0.25, 0.35));
    scene
}

#[test]
fn a_mesh_renders_as_the_soup_of_its_triangles() {
    let soup = render_default(&scene(&[false]).compile().unwrap());
    let mesh = render_default(&scene(&[true]).compile().unwrap());
    assert_finite("glass box", &mesh);
    let bits = |o: &risotto::engine::render::RenderOutput| {
        o.beauty
            .pixels
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&soup), bits(&mesh));
    // Something of the box shows: not two empty images.
    let lit = mesh
        .beauty
        .pixels
        .iter()
        .filter(|p| p.to_array().iter().any(|&c| c > 0.0));
    assert!(lit.count() > 100);
}

/// A mesh and a soup of the same triangles are coincident shapes: only the first is built
/// (a warning says so), and the image is that of one box.
#[test]
fn a_mesh_and_its_soup_are_coincident() {
    let compiled = scene(&[true, false]).compile().unwrap();
    assert!(
        compiled.warnings.iter().any(|w| w.contains("box1")),
        "{:?}",
        compiled.warnings
    );
    let both = render_default(&compiled);
    let one = render_default(&scene(&[true]).compile().unwrap());
    assert_eq!(both.beauty.pixels, one.beauty.pixels);
}
