//! A volume's `u, v, w` and its heterogeneous grid are measured in its shape's object space
//! and follow the shape's `transform` (issue 31, point 5b): a scene file's `transform` on a
//! `box` or `mesh` gives the compiled scene the object-space bounds; a shading context's
//! `u, v, w` at world points of a turned box are those of the object-space points; a
//! density ramp along object x in a box turned 90 degrees about y renders as a ramp along
//! world z, as the unturned box's image turned, and not along x as the world box would
//! place it.

mod common;
use common::{load_scene_text, render_scene_text, scratch_dir};

use glam::Vec3;
use risotto::engine::plugin::{Builtin, ShadingContext, ShadingMode};
use risotto::engine::render::RenderOutput;
use risotto_components::{ShadingPointRow, ShadingPoints};

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    a.abs_diff_eq(b, tol)
}

const CAMERA: &str = r#"
[camera]
fov = 40
from = [0, 0, 9]
to = [0, 0, 0]
"#;

#[test]
fn a_transform_on_a_box_or_mesh_gives_object_space_bounds() {
    let d = scratch_dir("object_space", "bounds");
    // A mesh written in [0, 1] x [0, 2] x [0, 3] (a tetrahedron-like solid with those
    // bounds; closed or not does not matter for its bounds).
    std::fs::write(
        d.join("solid.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 2 0\nv 0 0 3\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    )
    .unwrap();
    let text = format!(
        r#"{CAMERA}
[materials.m]
type = "diffuse"

[[shapes]]
name = "turned"
type = "box"
material = "m"
min = [0, 0, 0]
max = [2, 1, 1]
transform = [{{ rotate = {{ axis = [0, 1, 0], angle = 90 }} }}, {{ translate = [5, 0, 0] }}]

[[shapes]]
name = "mesh"
type = "mesh"
material = "m"
path = "solid.obj"
transform = [{{ scale = 2 }}, {{ rotate = {{ axis = [0, 0, 1], angle = 45 }} }}, {{ translate = [0, 1, -4] }}]

[[shapes]]
name = "plain"
type = "box"
material = "m"
min = [-3, -3, -3]
max = [-2, -2, -2]

[[shapes]]
name = "ball"
type = "sphere"
material = "m"
center = [3, 3, 3]
radius = 0.5
"#
    );
    let scene = load_scene_text(&d, &text).unwrap();
    let index = |n: &str| scene.shapes.iter().position(|s| s.name == n).unwrap();

    let turned = scene.shape_space[index("turned")];
    assert!(!turned.is_identity());
    let (lo, hi) = turned.bounds;
    assert!(
        close(lo, Vec3::ZERO, 1e-6) && close(hi, Vec3::new(2.0, 1.0, 1.0), 1e-6),
        "the box's object bounds are its min / max: {lo} {hi}"
    );
    // The world box is the turned one.
    let (wlo, whi) = scene.shape_bounds[index("turned")];
    assert!(close(wlo, Vec3::new(5.0, 0.0, -2.0), 1e-6), "{wlo}");
    assert!(close(whi, Vec3::new(6.0, 1.0, 0.0), 1e-6), "{whi}");
    assert_eq!(turned.world_bounds, (wlo, whi));
    assert!(close(
        turned
            .object_to_world
            .transform_point3(Vec3::new(2.0, 0.0, 0.0)),
        Vec3::new(5.0, 0.0, -2.0),
        1e-6
    ));

    let mesh = scene.shape_space[index("mesh")];
    let (lo, hi) = mesh.bounds;
    assert!(
        close(lo, Vec3::ZERO, 1e-5) && close(hi, Vec3::new(1.0, 2.0, 3.0), 1e-5),
        "the mesh's object bounds are its file's: {lo} {hi}"
    );
    assert!(
        !close(mesh.world_bounds.1, hi, 0.1),
        "the world box differs"
    );

    // Shapes written in world coordinates: the identity, object bounds = world bounds.
    for name in ["plain", "ball"] {
        let s = scene.shape_space[index(name)];
        assert!(s.is_identity(), "{name}");
        assert_eq!(s.bounds, scene.shape_bounds[index(name)], "{name}");
    }
}

#[test]
fn a_contexts_uvw_follow_the_turned_box() {
    let d = scratch_dir("object_space", "uvw");
    let text = format!(
        r#"{CAMERA}
[materials.fog]
type = "interface"
interior = {{ type = "homogeneous", sigma_t = 1, albedo = 0.5 }}

[[shapes]]
name = "fog"
type = "box"
material = "fog"
min = [0, 0, 0]
max = [2, 1, 1]
transform = [{{ rotate = {{ axis = [0, 1, 0], angle = 90 }} }}, {{ translate = [5, 0, 0] }}]
"#
    );
    let scene = load_scene_text(&d, &text).unwrap();
    let space = scene.shape_space[0];
    let mut table = ShadingPoints::default();
    for i in 0..4 {
        table.push(ShadingPointRow::in_volume(Vec3::ZERO, Vec3::X, i, 0));
    }
    let ctx =
        ShadingContext::new(&table, 0..4, ShadingMode::Interior, 0, &[]).with_volume_space(space);
    let mut v = ctx.begin_volume_sampling();
    // Object point o maps to world (5 + o.z, o.y, -o.x).
    let object = [
        Vec3::new(2.0, 0.5, 0.5),
        Vec3::ZERO,
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(0.5, 0.25, 0.75),
    ];
    let world: Vec<Vec3> = object
        .iter()
        .map(|o| Vec3::new(5.0 + o.z, o.y, -o.x))
        .collect();
    v.set_builtin(Builtin::P, &world);
    let c = v.context();
    for (i, o) in object.iter().enumerate() {
        let expected = *o / Vec3::new(2.0, 1.0, 1.0);
        let got = Vec3::new(c.u()[i], c.v()[i], c.w()[i]);
        assert!(
            close(got, expected, 1e-6),
            "world {}: u, v, w = {got}, expected {expected} (object {o})",
            world[i]
        );
    }
}

/// Writes a Mitsuba `.vol` of `n x 1 x 1` voxels whose density rises along x from 0 to 1.
fn ramp_vol(path: &std::path::Path, n: i32) {
    let mut b = b"VOL\x03".to_vec();
    for v in [1, n, 1, 1, 1] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for i in 0..n {
        b.extend_from_slice(&(i as f32 / (n - 1) as f32).to_le_bytes());
    }
    std::fs::write(path, b).unwrap();
}

/// An absorbing box of the ramp medium, `box_table` its shape keys besides type and
/// material, seen from above (+y) by an orthographic camera whose image up is world -z,
/// against an environment of 1: each pixel is the transmittance through the box along y.
fn ramp_image(dir: &std::path::Path, box_table: &str) -> (RenderOutput, usize) {
    absorber_image(dir, r#"{ grid = "ramp.vol" }"#, box_table)
}

/// [`ramp_image`] with the density table `density`.
fn absorber_image(dir: &std::path::Path, density: &str, box_table: &str) -> (RenderOutput, usize) {
    let n = 16;
    let text = format!(
        r#"
[render]
width = {n}
height = {n}
spp = 64
max_depth = -1
seed = 3

[camera]
projection = "orthographic"
width = 1.9
from = [0, 5, 0]
to = [0, 0, 0]
up = [0, 0, -1]

[materials.smoke]
type = "interface"
interior = {{ type = "heterogeneous", density = {density}, scale = 1.5, albedo = 0, tracking = "ratio", majorant_grid = 8 }}

[[shapes]]
name = "smoke"
type = "box"
material = "smoke"
{box_table}

[[lights]]
type = "environment"
radiance = 1
"#
    );
    (render_scene_text(dir, &text), n)
}

/// Means of the image's columns (left to right) and rows (top to bottom), green channel.
fn column_row_means(out: &RenderOutput, n: usize) -> (Vec<f64>, Vec<f64>) {
    let px = |x: usize, y: usize| out.beauty.pixels[y * n + x].g as f64;
    let cols = (0..n)
        .map(|x| (0..n).map(|y| px(x, y)).sum::<f64>() / n as f64)
        .collect();
    let rows = (0..n)
        .map(|y| (0..n).map(|x| px(x, y)).sum::<f64>() / n as f64)
        .collect();
    (cols, rows)
}

fn spread(v: &[f64]) -> f64 {
    let max = v.iter().cloned().fold(f64::MIN, f64::max);
    let min = v.iter().cloned().fold(f64::MAX, f64::min);
    max - min
}

#[test]
fn a_turned_boxs_grid_turns_with_it() {
    let d = scratch_dir("object_space", "ramp");
    ramp_vol(&d.join("ramp.vol"), 16);
    let cube = "min = [-1, -1, -1]\nmax = [1, 1, 1]";
    let (plain, n) = ramp_image(&d, cube);
    // Turned 90 degrees about y: object x is world -z, the image's up. The world box is the
    // same cube, so world-space bounds would place the ramp along x as before.
    let (turned, _) = ramp_image(
        &d,
        &format!("{cube}\ntransform = [{{ rotate = {{ axis = [0, 1, 0], angle = 90 }} }}]"),
    );
    // The same turned box, written twice as large and scaled by 1/2: the grid's placement
    // and the extinction per world unit are those of `turned` (rays mapped to object space
    // keep their parameter t, with a direction of length 2 there).
    let (scaled, _) = ramp_image(
        &d,
        "min = [-2, -2, -2]\nmax = [2, 2, 2]\ntransform = [{ scale = 0.5 }, { rotate = { axis = [0, 1, 0], angle = 90 } }]",
    );

    let (pc, pr) = column_row_means(&plain, n);
    assert!(
        spread(&pc) > 0.5 && spread(&pr) < 0.1,
        "unturned: the ramp runs across the columns (x): columns {pc:?}, rows {pr:?}"
    );
    let (tc, tr) = column_row_means(&turned, n);
    assert!(
        spread(&tr) > 0.5 && spread(&tc) < 0.1,
        "turned: the ramp runs along the rows (world z), not x: columns {tc:?}, rows {tr:?}"
    );
    // Density 1 at object x = 1, world z = -1, the top of the image: the top rows are the
    // darkest.
    assert!(
        tr[0] < 0.5 * tr[n - 1],
        "turned: dense at the top (world -z): rows {tr:?}"
    );
    // The turned image is the unturned one turned: its rows (top to bottom) are the
    // unturned columns from the dense end to the thin one.
    let dense_first: Vec<f64> = if pc[0] < pc[n - 1] {
        pc.clone()
    } else {
        pc.iter().rev().cloned().collect()
    };
    for (y, (t, p)) in tr.iter().zip(&dense_first).enumerate() {
        assert!(
            (t - p).abs() < 0.07,
            "row {y}: turned {t} against unturned column {p} (rows {tr:?}, columns {dense_first:?})"
        );
    }
    let (_, sr) = column_row_means(&scaled, n);
    for (y, (s, t)) in sr.iter().zip(&tr).enumerate() {
        assert!(
            (s - t).abs() < 0.07,
            "row {y}: scaled {s} against turned {t} (rows {sr:?} against {tr:?})"
        );
    }
}

#[test]
fn a_pattern_density_stays_in_world_space_in_a_turned_box() {
    // A pattern reads the world P, in a turned shape too: a gradient along world x stays
    // along x (the columns). Its majorant grid is laid over the turned box's object cells,
    // each bounding the pattern over the cell's world box: no sampled density exceeds it.
    let d = scratch_dir("object_space", "pattern");
    let density = r#"{ pattern = "gradient", axis = "x", from = -1, to = 1, a = 0, b = 1 }"#;
    let cube = "min = [-1, -1, -1]\nmax = [1, 1, 1]";
    for turn in [
        "",
        "transform = [{ rotate = { axis = [0, 1, 0], angle = 90 } }]",
    ] {
        let (out, n) = absorber_image(&d, density, &format!("{cube}\n{turn}"));
        let (c, r) = column_row_means(&out, n);
        assert!(
            spread(&c) > 0.5 && spread(&r) < 0.1,
            "{turn:?}: the gradient runs across the columns (world x): columns {c:?}, rows {r:?}"
        );
        assert_eq!(out.stats.counters.majorant_violations, 0, "{turn:?}");
    }
}
