//! Scenes whose geometry made the BVH build quadratic (issue 37): one triangle listed
//! 100,000 times in an OBJ, a mesh listed 10,000 times in `[[shapes]]`, and one polygon of
//! 200,000 vertices (fan-triangulated into slivers sharing a vertex). Each must load and
//! render at 16x16, 1 spp, to the image of its plain counterpart: coincident copies of a
//! surface are the surface, and a 200,000-gon is the disc a 2,000-gon is at 16x16.
//! (Before the fix each took over 120 s to build; `systems/src/bvh2_build/tests.rs`
//! checks the builds' shape on the same input.)

mod common;
use std::fmt::Write;

use risotto::engine::render::RenderOutput;

/// A 16x16, 1 spp scene of `shapes` (the `[[shapes]]` tables' text, material `grey`) lit
/// by an environment and a sun.
fn scene(shapes: &str) -> String {
    format!(
        r#"
[render]
width = 16
height = 16
spp = 1
max_depth = 3

[camera]
fov = 40
from = [0.3, 0.2, 4]
to = [0, 0, 0]

[materials.grey]
type = "diffuse"
reflectance = 0.6

{shapes}

[[lights]]
type = "environment"
radiance = 0.5

[[lights]]
type = "distant"
direction = [1, -1, -2]
irradiance = 3
"#
    )
}

/// A `[[shapes]]` table of the mesh `path`.
fn mesh_shape(name: &str, path: &str) -> String {
    format!(
        "[[shapes]]\nname = \"{name}\"\ntype = \"mesh\"\npath = \"{path}\"\nmaterial = \"grey\"\n"
    )
}

/// The number of pixels whose colour differs between `a` and `b`, and the largest relative
/// difference of the two image means over the channels.
fn difference(a: &RenderOutput, b: &RenderOutput) -> (usize, f32) {
    let pixels = a
        .beauty
        .pixels
        .iter()
        .zip(&b.beauty.pixels)
        .filter(|(p, q)| p != q)
        .count();
    let (ma, mb) = (common::image_mean(a).0, common::image_mean(b).0);
    let rel = (ma - mb).map(f32::abs).max_channel() / ma.max_channel().max(1e-6);
    (pixels, rel)
}

/// An OBJ of `vertices` and the triangle `1 2 3` listed `copies` times.
fn triangle_obj(copies: usize) -> String {
    let mut obj = String::from("v -1 -1 0\nv 1 -1 0.5\nv 0 1 0\n");
    for _ in 0..copies {
        obj.push_str("f 1 2 3\n");
    }
    obj
}

#[test]
fn one_triangle_listed_100000_times_renders_as_one_triangle() {
    let dir = common::scratch_dir("degenerate_geometry", "repeated_triangle");
    std::fs::write(dir.join("once.obj"), triangle_obj(1)).unwrap();
    std::fs::write(dir.join("repeated.obj"), triangle_obj(100_000)).unwrap();
    let once = common::render_scene_text(&dir, &scene(&mesh_shape("t", "once.obj")));
    let repeated = common::render_scene_text(&dir, &scene(&mesh_shape("t", "repeated.obj")));
    let (pixels, rel) = difference(&once, &repeated);
    assert!(
        common::image_mean(&once).0.max_channel() > 0.05,
        "the triangle is lit"
    );
    assert_eq!(
        (pixels, rel),
        (0, 0.0),
        "copies of one triangle are that triangle"
    );
}

#[test]
fn a_mesh_listed_10000_times_renders_as_the_mesh() {
    let dir = common::scratch_dir("degenerate_geometry", "repeated_mesh");
    // A tetrahedron: four triangles, seen from the camera on two or three faces.
    std::fs::write(
        dir.join("tet.obj"),
        "v -1 -1 -1\nv 1 -1 -1\nv 0 1 -1\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n",
    )
    .unwrap();
    let once = common::render_scene_text(&dir, &scene(&mesh_shape("tet", "tet.obj")));
    let mut shapes = String::new();
    for k in 0..10_000 {
        writeln!(shapes, "{}", mesh_shape(&format!("tet{k}"), "tet.obj")).unwrap();
    }
    let repeated = common::render_scene_text(&dir, &scene(&shapes));
    let (pixels, rel) = difference(&once, &repeated);
    assert!(
        common::image_mean(&once).0.max_channel() > 0.05,
        "the mesh is lit"
    );
    assert_eq!((pixels, rel), (0, 0.0), "copies of one mesh are that mesh");
}

/// An OBJ of one polygon: `n` vertices on the unit circle, in one face.
fn disc_obj(n: usize) -> String {
    let mut obj = String::new();
    for k in 0..n {
        let a = k as f64 / n as f64 * std::f64::consts::TAU;
        writeln!(obj, "v {} {} 0", a.cos(), a.sin()).unwrap();
    }
    obj.push('f');
    for k in 1..=n {
        write!(obj, " {k}").unwrap();
    }
    obj.push('\n');
    obj
}

#[test]
fn a_polygon_of_200000_vertices_renders_as_a_disc() {
    let dir = common::scratch_dir("degenerate_geometry", "fan");
    std::fs::write(dir.join("fine.obj"), disc_obj(200_000)).unwrap();
    std::fs::write(dir.join("coarse.obj"), disc_obj(2_000)).unwrap();
    let fine = common::render_scene_text(&dir, &scene(&mesh_shape("disc", "fine.obj")));
    let coarse = common::render_scene_text(&dir, &scene(&mesh_shape("disc", "coarse.obj")));
    let (pixels, rel) = difference(&fine, &coarse);
    assert!(
        common::image_mean(&fine).0.max_channel() > 0.05,
        "the disc is lit"
    );
    // The two discs differ by at most 1.2e-6 in radius (1 - cos(pi / 2000)): a camera sample
    // lands between them with probability ~1e-5 a pixel. Hits on slivers differ from hits on
    // wider triangles by rounding, which may carry into a bounce: a few pixels, and means
    // equal within a hundredth.
    assert!(
        pixels <= 16 && rel < 0.01,
        "{pixels} pixels differ, means by {rel}"
    );
}
