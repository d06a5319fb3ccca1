//! Equal-area octahedral environment maps (`projection = "equal_area"`, pbrt-v4's image
//! infinite lights): a sky written as pbrt's square, in a light frame turned into the world
//! by `transform`, lights a diffuse ball as the same sky written as a latitude-longitude map
//! does (each texel computed from the sky's world direction by its own mapping; the
//! lat-long one by the scene format's documented formula, not risotto's code). Also the
//! errors of the new keys, and a pbrt file with an image infinite light renders.

mod common;
use common::images::block_z;
use common::scratch_dir;
use risotto::engine::render::RenderOutput;
use risotto::glam::{Mat3, Vec2, Vec3};
use risotto::loader::load::{load_scene_file, MaterialRegistry};
use risotto::systems::environment_map::equal_area::square_to_sphere;
use std::f32::consts::PI;
use std::path::Path;

/// The sky's radiance in world direction `d`: a warm lobe up and towards `+x`, a blue one
/// towards `-z`, a dim floor glow: every axis tells, so a turned or mirrored map shows.
fn sky(d: Vec3) -> [f32; 3] {
    let warm = d.dot(Vec3::new(0.6, 0.8, 0.0)).max(0.0).powi(3) * 4.0;
    let blue = d
        .dot(Vec3::new(0.0, 0.2, -1.0).normalize())
        .max(0.0)
        .powi(2)
        * 2.0;
    let floor = 0.05 + 0.05 * (-d.y).max(0.0);
    [
        warm + floor,
        0.6 * warm + 0.3 * blue + floor,
        0.2 * warm + blue + floor,
    ]
}

/// The light frame's rotation into the world: `+z` (the square's centre) to `+y` (up), then
/// turned about `y`, as [`TRANSFORM`] says (its steps apply in order).
fn to_world() -> Mat3 {
    Mat3::from_rotation_y(30f32.to_radians()) * Mat3::from_rotation_x(-90f32.to_radians())
}

const TRANSFORM: &str = "[{ rotate = { axis = [1, 0, 0], angle = -90 } }, \
                         { rotate = { axis = [0, 1, 0], angle = 30 } }]";

fn write_maps(dir: &Path) {
    let n = 128;
    exr::prelude::write_rgb_file(dir.join("square.exr"), n, n, |i, j| {
        let c = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
        let [r, g, b] = sky(to_world() * square_to_sphere(c));
        (r, g, b)
    })
    .unwrap();
    let (w, h) = (256, 128);
    exr::prelude::write_rgb_file(dir.join("latlong.exr"), w, h, |i, j| {
        // docs/scene-format.md: phi = 2 pi (u - 1/2), theta = pi v,
        // d = (sin theta sin phi, cos theta, -sin theta cos phi).
        let (u, v) = ((i as f32 + 0.5) / w as f32, (j as f32 + 0.5) / h as f32);
        let (phi, theta) = (2.0 * PI * (u - 0.5), PI * v);
        let d = Vec3::new(
            theta.sin() * phi.sin(),
            theta.cos(),
            -theta.sin() * phi.cos(),
        );
        let [r, g, b] = sky(d);
        (r, g, b)
    })
    .unwrap();
}

/// A white diffuse ball filling an orthographic view, lit by the environment `light`.
fn scene(light: &str, seed: u64) -> String {
    format!(
        r#"
[render]
width = 24
height = 24
spp = 64
seed = {seed}

[camera]
projection = "orthographic"
width = 1.3
from = [0.3, 0.4, 4]
to = [0, 0, 0]

[materials.white]
type = "diffuse"
reflectance = 0.8

[[shapes]]
type = "sphere"
material = "white"
center = [0, 0, 0]
radius = 1

[[lights]]
type = "environment"
{light}
"#
    )
}

fn render_text(dir: &Path, text: &str) -> RenderOutput {
    let out = common::render_scene_text(dir, text);
    assert_eq!(out.stats.counters.nan_dropped, 0);
    out
}

/// The largest |z| over 8 x 8-pixel blocks and channels of `a - b`
/// ([`common::images::block_z`]), and the image means' relative difference per channel.
fn compare(a: &RenderOutput, b: &RenderOutput) -> (f64, [f64; 3]) {
    let worst = block_z(a, b)
        .into_iter()
        .fold(0.0f64, |m, z| m.max(z.abs()));
    let mean = |o: &RenderOutput, c: usize| {
        o.beauty
            .pixels
            .iter()
            .map(|p| p.to_array()[c] as f64)
            .sum::<f64>()
    };
    let rel = [0, 1, 2].map(|c| mean(a, c) / mean(b, c) - 1.0);
    (worst, rel)
}

#[test]
fn an_equal_area_sky_lights_the_ball_as_its_latitude_longitude_twin() {
    let d = scratch_dir("equal-area", "twin");
    write_maps(&d);
    let latlong = render_text(&d, &scene(r#"map = "latlong.exr""#, 1));
    let square = render_text(
        &d,
        &scene(
            &format!(
                r#"map = "square.exr"
projection = "equal_area"
transform = {TRANSFORM}"#
            ),
            2,
        ),
    );
    let (z, rel) = compare(&square, &latlong);
    eprintln!("equal-area vs lat-long: max block |z| {z:.2}, means {rel:?}");
    // 9 blocks x 3 channels: |z| > 4.5 has probability ~2e-4 under pure noise; the two
    // maps' texels differ by their discretisations (about 1.4 and 0.7 degrees).
    assert!(z < 4.5, "max block |z| {z}");
    assert!(rel.iter().all(|r| r.abs() < 0.01), "{rel:?}");
    // The test can fail: the square read in the world frame (no transform) is far off.
    let unturned = render_text(
        &d,
        &scene(
            r#"map = "square.exr"
projection = "equal_area""#,
            3,
        ),
    );
    let (z, _) = compare(&unturned, &latlong);
    assert!(z > 10.0, "an unturned map is not told apart: max |z| {z}");
}

#[test]
fn bad_equal_area_keys_and_maps_are_located_errors() {
    let d = scratch_dir("equal-area", "errors");
    write_maps(&d);
    let cases: [(&str, &[&str]); 4] = [
        (
            "map = \"square.exr\"\nprojection = \"cube\"",
            &["projection", "\"latlong\" or \"equal_area\""],
        ),
        (
            "map = \"square.exr\"\nprojection = \"equal_area\"\nfilter = \"bilinear\"",
            &["filter", "nearest-texel"],
        ),
        (
            "map = \"square.exr\"\nprojection = \"equal_area\"\nconvention = \"mitsuba\"",
            &["convention", "latitude-longitude"],
        ),
        (
            "map = \"latlong.exr\"\nprojection = \"equal_area\"",
            &["latlong.exr", "square", "256 x 128"],
        ),
    ];
    for (light, needles) in cases {
        let path = d.join("scene.toml");
        std::fs::write(&path, scene(light, 1)).unwrap();
        let e = match load_scene_file(&path, &MaterialRegistry::with_builtins()) {
            Ok(_) => panic!("{light}: accepted"),
            Err(e) => e.to_string(),
        };
        for n in needles {
            assert!(e.contains(n), "{light}: {e:?} lacks {n:?}");
        }
        assert!(e.contains("scene.toml"), "{e}");
    }
}
