//! Shapes given as meshes (`ShapeGeometry::Mesh`: shared vertices and three indices a
//! triangle, as mesh files hold them; issue 36) are the surfaces of the soups of their
//! triangles: the same image bit for bit, and coincident with them.

mod common;
use common::*;
use glam::Vec3;
use risotto::builtins::builtin::{Interior, Surface};
use risotto::engine::scene::{Scene, ShapeGeometry, TriangleMesh, VertexAttributes};
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

/// A `w x h` view from `from` (field of view `fov`) of a floor under a sun and a sky,
/// rendered at `spp` and `max_depth`.
fn lit_floor(w: u32, h: u32, from: Vec3, fov: f32, spp: u32, max_depth: u32) -> Scene {
    let cam = perspective(from, Vec3::new(0.0, 0.5, 0.0), fov, w, h);
    let mut scene = Scene::new(cam, settings(w, h, spp, max_depth));
    add_floor(&mut scene, Vec3::ZERO, Rgb::splat(0.5));
    add_sun(&mut scene, 0.6, Rgb::new(3.0, 2.9, 2.7));
    environment(&mut scene, Rgb::new(0.2, 0.25, 0.35));
    scene
}

/// A floor, a sun and a sky, and the glass boxes `boxes` (true: a mesh) in one material.
fn scene(boxes: &[bool]) -> Scene {
    let mut scene = lit_floor(24, 16, Vec3::new(0.5, 2.5, 5.0), 35.0, 16, 12);
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

/// Two smooth-shaded boxes (vertex normals pointing away from each box's centre), as meshes
/// or as soups with the same attributes. A mesh whose attributes' corners are its own
/// triangles lends them to the build and gets them back after it (the second box's from
/// its own first vertex on); the image is the soups' bit for bit.
#[test]
fn meshes_with_vertex_normals_render_as_their_soups() {
    let render = |as_mesh: bool| {
        let mut scene = lit_floor(32, 24, Vec3::new(0.5, 2.5, 6.0), 40.0, 8, 6);
        let m = add_diffuse(&mut scene, "white", 0.7);
        for (k, x) in [-1.2f32, 1.1].into_iter().enumerate() {
            let (lo, hi) = (Vec3::new(x - 0.5, 0.0, -0.5), Vec3::new(x + 0.5, 1.0, 0.5));
            let soup = box_tris(lo, hi);
            let mesh = TriangleMesh::from_soup(&soup);
            let centre = (lo + hi) * 0.5;
            let normals = mesh
                .positions
                .iter()
                .map(|&p| (p - centre).normalize())
                .collect();
            let attributes = VertexAttributes {
                normals,
                uvs: Vec::new(),
                corners: mesh.triangles.clone(),
                shadow_terminator_offset: false,
            };
            let geometry = if as_mesh {
                ShapeGeometry::Mesh(mesh)
            } else {
                ShapeGeometry::Triangles(soup)
            };
            let e = scene.add_shape(&format!("box{k}"), geometry, m, None);
            scene.set_vertex_attributes(e, attributes);
        }
        render_default(&scene.compile().unwrap())
    };
    let (mesh, soup) = (render(true), render(false));
    assert_finite("smooth boxes", &mesh);
    assert_eq!(mesh.beauty.pixels, soup.beauty.pixels);
    assert_eq!(mesh.normal.pixels, soup.normal.pixels);
}
