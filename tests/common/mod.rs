//! Helpers shared by the integration tests: small scenes built in code.
#![allow(dead_code, reason = "each test binary uses a different subset")]

pub mod cli;
pub mod converge;
pub mod images;

use glam::Vec3;
use risotto::builtins::builtin::{BuiltinMaterial, Interior, Surface};
use risotto::engine::integrator::LightingTechnique;
use risotto::engine::render::{render, RenderOptions, RenderOutput};
use risotto::engine::scene::{CompiledScene, LightComponent, RenderSettings, Scene, ShapeGeometry};
use risotto::systems::camera::{Camera, Projection};
use risotto_components::Rgb;
use std::f64::consts::PI;

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

/// The parallelogram `corner`, `corner + e1`, `corner + e1 + e2`, `corner + e2` as two
/// triangles whose geometric normal is along `e1 x e2` (the engine's winding convention).
pub fn quad(corner: Vec3, e1: Vec3, e2: Vec3) -> ShapeGeometry {
    let (a, b, c, d) = (corner, corner + e1, corner + e1 + e2, corner + e2);
    ShapeGeometry::Triangles(vec![[a, b, c], [a, c, d]])
}

/// An orthographic camera at `from` looking at `to`, showing `view_width` world units across.
pub fn ortho_camera(from: Vec3, to: Vec3, up: Vec3, view_width: f32, w: u32, h: u32) -> Camera {
    Camera::look_at(
        Projection::Orthographic { width: view_width },
        from,
        to,
        up,
        w,
        h,
    )
    .unwrap()
}

/// A perspective camera at `from` looking at `to` (up = +y) with a full horizontal fov.
pub fn perspective(from: Vec3, to: Vec3, fov: f32, w: u32, h: u32) -> Camera {
    Camera::look_at(
        Projection::Perspective { fov_deg: fov },
        from,
        to,
        Vec3::Y,
        w,
        h,
    )
    .unwrap()
}

/// Renders with the given lighting technique and thread count (other options default).
pub fn render_with(
    scene: &CompiledScene,
    technique: LightingTechnique,
    threads: Option<usize>,
) -> RenderOutput {
    let options = RenderOptions {
        technique,
        threads,
        ..RenderOptions::default()
    };
    render(scene, &options, &|_| {}).unwrap()
}

/// Mean and standard error (per channel) of the mean over the pixels `(x, y)` with
/// `x in xs`, `y in ys`, from the film's per-pixel variances of the mean (pixels are
/// independent estimates, so the variances of their average add with weight 1/n^2).
pub fn crop_mean(
    out: &RenderOutput,
    xs: std::ops::Range<usize>,
    ys: std::ops::Range<usize>,
) -> (Rgb, Rgb) {
    let mut mean = Rgb::BLACK;
    let mut var = Rgb::BLACK;
    let mut n = 0.0f32;
    for y in ys {
        for x in xs.clone() {
            mean += out.beauty.get(x, y);
            var += out.variance.get(x, y);
            n += 1.0;
        }
    }
    (mean / n, (var / (n * n)).map(f32::sqrt))
}

/// A parallelogram `corner, corner + e1, corner + e1 + e2, corner + e2` as two triangles
/// whose geometric normal is `normalize(e1 x e2)`.
pub fn quad_tris(corner: Vec3, e1: Vec3, e2: Vec3) -> Vec<[Vec3; 3]> {
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
    t.extend(quad_tris(lo, z, y)); // x = lo.x, normal -x (z x y = -x)
    t.extend(quad_tris(lo + x, y, z)); // x = hi.x, normal +x
    t.extend(quad_tris(lo, x, z)); // y = lo.y, normal -y (x x z = -y)
    t.extend(quad_tris(lo + y, z, x)); // y = hi.y, normal +y
    t.extend(quad_tris(lo, y, x)); // z = lo.z, normal -z (y x x = -z)
    t.extend(quad_tris(lo + z, x, y)); // z = hi.z, normal +z
    t
}

/// Adds the axis-aligned box `[lo, hi]` ([`box_tris`]) as shape `name` of `material`,
/// without emission.
pub fn add_box(scene: &mut Scene, name: &str, lo: Vec3, hi: Vec3, material: u32) {
    scene.add_shape(
        name,
        ShapeGeometry::Triangles(box_tris(lo, hi)),
        material,
        None,
    );
}

/// Adds a distant light "sun" of irradiance `e` travelling down (-y), tilted by `theta`
/// radians towards +x.
pub fn add_sun(scene: &mut Scene, theta: f32, e: Rgb) {
    scene.add_light(
        "sun",
        LightComponent::Distant {
            direction: Vec3::new(theta.sin(), -theta.cos(), 0.0),
            irradiance: e,
        },
    );
}

/// A diffuse floor: the 40 x 40 square of the plane `y = center.y` around `center`, facing
/// up, with its own material `floor` of the given albedo.
pub fn add_floor(scene: &mut Scene, center: Vec3, albedo: Rgb) {
    let floor = scene.add_material(
        "floor",
        0,
        mat(Surface::Diffuse {
            reflectance: albedo,
        }),
    );
    scene.add_shape(
        "floor",
        ShapeGeometry::Triangles(quad_tris(
            center + Vec3::new(-20.0, 0.0, -20.0),
            Vec3::Z * 40.0,
            Vec3::X * 40.0,
        )),
        floor,
        None,
    );
}

/// Adds a built-in diffuse material `name` of the given grey albedo; returns its index.
pub fn add_diffuse(scene: &mut Scene, name: &str, albedo: f32) -> u32 {
    scene.add_material(
        name,
        0,
        mat(Surface::Diffuse {
            reflectance: Rgb::splat(albedo),
        }),
    )
}

/// Asserts that no beauty or variance pixel is non-finite.
pub fn assert_finite(what: &str, out: &RenderOutput) {
    for (i, (p, v)) in out
        .beauty
        .pixels
        .iter()
        .zip(&out.variance.pixels)
        .enumerate()
    {
        assert!(
            p.to_array()
                .iter()
                .chain(&v.to_array())
                .all(|x| x.is_finite()),
            "{what}: pixel {i} is {p:?} (variance {v:?})"
        );
    }
}

/// Chandrasekhar's H-function for isotropic scattering with albedo `w`, the solution of
/// `1 / H(mu) = 1 - (w / 2) mu int_0^1 H(mu') / (mu + mu') dmu'`
/// (Chandrasekhar 1960, ch. V eq. (6)), by fixed-point iteration on 48 Gauss-Legendre
/// nodes, evaluated at `mu` by the same equation.
pub fn chandrasekhar_h(w: f64, mu: f64) -> f64 {
    let table = chandrasekhar_h_table(w);
    h_from_table(&table, w, mu)
}

/// `H` at the 48 Gauss-Legendre nodes on [0, 1], as (node, weight, H(node)), the converged
/// fixed point of [`chandrasekhar_h`]'s iteration (for moments of `H`).
pub fn chandrasekhar_h_table(w: f64) -> Vec<(f64, f64, f64)> {
    let nodes = gauss_legendre_01(48);
    let mut table: Vec<(f64, f64, f64)> = nodes.iter().map(|&(x, wx)| (x, wx, 1.0)).collect();
    for _ in 0..3000 {
        let h: Vec<f64> = nodes
            .iter()
            .map(|&(x, _)| h_from_table(&table, w, x))
            .collect();
        for (row, h) in table.iter_mut().zip(h) {
            row.2 = h;
        }
    }
    table
}

/// The right-hand side of the H-equation at `mu` with `H` given on the quadrature nodes.
fn h_from_table(table: &[(f64, f64, f64)], w: f64, mu: f64) -> f64 {
    let integral: f64 = table.iter().map(|&(x, wx, hx)| wx * hx / (mu + x)).sum();
    1.0 / (1.0 - w / 2.0 * mu * integral)
}

/// The `n`-point Gauss-Legendre rule on [0, 1] as (node, weight) pairs: Newton iteration on
/// the Legendre polynomial P_n.
pub fn gauss_legendre_01(n: usize) -> Vec<(f64, f64)> {
    let legendre = |x: f64| {
        let (mut p0, mut p1) = (1.0, x);
        for k in 2..=n {
            let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
            p0 = p1;
            p1 = p2;
        }
        // P_n(x) and its derivative.
        (p1, n as f64 * (x * p1 - p0) / (x * x - 1.0))
    };
    let nodes: Vec<(f64, f64)> = (0..n)
        .map(|i| {
            let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            for _ in 0..100 {
                let (p, dp) = legendre(x);
                x -= p / dp;
            }
            let (_, dp) = legendre(x);
            ((x + 1.0) / 2.0, 1.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect();
    let weight_sum: f64 = nodes.iter().map(|n| n.1).sum();
    assert!(
        (weight_sum - 1.0).abs() < 1e-12,
        "quadrature weights sum to {weight_sum}"
    );
    nodes
}

/// Writes a Mitsuba `.vol` of `dims` voxels, all `value`.
pub fn constant_vol(path: &std::path::Path, dims: [i32; 3], value: f32) {
    let mut b = b"VOL\x03".to_vec();
    for v in [1, dims[0], dims[1], dims[2], 1] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for _ in 0..dims.iter().product::<i32>() {
        b.extend_from_slice(&value.to_le_bytes());
    }
    std::fs::write(path, b).unwrap();
}

/// A scene file's text: a unit sphere of medium (index-matched boundary) at the origin seen
/// whole by an `n x n` camera, lit by a sun of irradiance `sun` (shadow rays cross the
/// medium) and an environment of 0.5; `interior` is the interior table's text.
pub fn medium_ball_scene(interior: &str, n: u32, spp: u32, seed: u64, sun: f32) -> String {
    format!(
        r#"
[render]
width = {n}
height = {n}
spp = {spp}
max_depth = -1
seed = {seed}

[camera]
fov = 40
from = [0, 0, 4]
to = [0, 0, 0]

[materials.medium]
type = "interface"
interior = {interior}

[[shapes]]
name = "ball"
type = "sphere"
material = "medium"
center = [0, 0, 0]
radius = 1

[[lights]]
type = "environment"
radiance = 0.5

[[lights]]
type = "distant"
direction = [1, -1, -0.5]
irradiance = {sun}
"#
    )
}

/// Loads and compiles the scene file text `text` as if it were `dir/scene.toml` (relative
/// paths from `dir`).
pub fn load_scene_text(
    dir: &std::path::Path,
    text: &str,
) -> Result<CompiledScene, risotto::loader::load::LoadError> {
    use risotto::loader::load::{scene_from_desc, MaterialRegistry};
    let desc = risotto::loader::scene_file::parse_scene(text, &dir.join("scene.toml"))?;
    Ok(scene_from_desc(desc, &MaterialRegistry::with_builtins())?
        .compile()
        .expect("the scene compiles"))
}

/// Renders the scene file text `text` ([`load_scene_text`]) with the default options.
pub fn render_scene_text(dir: &std::path::Path, text: &str) -> RenderOutput {
    render_default(&load_scene_text(dir, text).expect("the scene loads"))
}

/// A fresh, empty directory for the files of test `test` of the binary `binary`, under
/// Cargo's scratch directory for integration tests (`target/tmp`): the same path on every
/// run, so a run replaces what the last one left there (kept for inspection after a
/// failure) instead of piling directories up in the system's temporary directory.
pub fn scratch_dir(binary: &str, test: &str) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("{binary}-{test}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A unit sphere of material `body` (the lines of a `[materials.ball]` table) at the
/// origin, seen from `z = 5` with field of view `fov` degrees on a `size x size` image,
/// `spp` samples, paths of at most `max_depth` bounces, lit by `lights` (`[[lights]]`
/// tables).
pub fn sphere_scene(
    body: &str,
    size: u32,
    fov: f32,
    spp: u32,
    max_depth: u32,
    lights: &str,
) -> String {
    format!(
        r#"[render]
width = {size}
height = {size}
spp = {spp}
max_depth = {max_depth}
rr_depth = 50

[camera]
fov = {fov}
from = [0, 0, 5]
to = [0, 0, 0]
up = [0, 1, 0]

[materials.ball]
{body}

[[shapes]]
name = "ball"
type = "sphere"
material = "ball"
center = [0, 0, 0]
radius = 1

{lights}
"#
    )
}

/// [`sphere_scene`] filling a 16x16 view under a white environment of radiance 1, paths up
/// to 200 bounces: a white furnace, whose image mean is the material's energy balance.
pub fn sphere_furnace_scene(body: &str, spp: u32) -> String {
    let sky = "[[lights]]\ntype = \"environment\"\nradiance = 1";
    sphere_scene(body, 16, 10.0, spp, 200, sky)
}

/// Each material `body` of `cases` fails to load in a [`sphere_furnace_scene`] (under
/// `dir`) with an error naming the file, the material `materials.ball` and every one of
/// its needles.
pub fn assert_located_errors(dir: &std::path::Path, cases: &[(&str, &[&str])]) {
    for (body, needles) in cases {
        let err = match load_scene_text(dir, &sphere_furnace_scene(body, 1)) {
            Ok(_) => panic!("{body}: loaded"),
            Err(e) => e.to_string(),
        };
        assert!(err.contains("scene.toml:"), "{body}: no file in {err}");
        assert!(
            err.contains("materials.ball"),
            "{body}: no material in {err}"
        );
        for n in needles.iter() {
            assert!(err.contains(n), "{body}: `{n}` missing from: {err}");
        }
    }
}
