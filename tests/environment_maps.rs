//! Environment maps are validated before they light anything (issue 14 item 5): a NaN,
//! infinite or negative texel is an error naming the scene, the light, the map, the pixel and
//! the value; an EXR whose header claims more pixels than `MAX_IMAGE_PIXELS` (or more chunks
//! than the file can hold) is a located error before anything is allocated for its pixels.

mod common;
use common::scratch_dir;
use risotto::engine::output::{read_exr_rgb, MAX_IMAGE_PIXELS};
use risotto::loader::load::{load_scene_file, MaterialRegistry};
use std::path::{Path, PathBuf};

/// Writes `dir/scene.toml` lit only by the environment map `dir/sky.exr`.
fn scene_with_map(dir: &Path) -> PathBuf {
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        r#"
[render]
width = 8
height = 8
spp = 1

[camera]
fov = 40
from = [0, 0, 4]
to = [0, 0, 0]

[materials.white]
type = "diffuse"

[[shapes]]
type = "sphere"
material = "white"
center = [0, 0, 0]
radius = 1

[[lights]]
name = "sky"
type = "environment"
map = "sky.exr"
"#,
    )
    .unwrap();
    scene
}

/// An 8 x 4 uncompressed RGB float map, 0.5 everywhere except `bad` at pixel (5, 2).
fn write_map(path: &Path, bad: (f32, f32, f32)) {
    exr::prelude::write_rgb_file(path, 8, 4, |x, y| {
        if (x, y) == (5, 2) {
            bad
        } else {
            (0.5f32, 0.5f32, 0.5f32)
        }
    })
    .unwrap();
}

/// Loads `dir/scene.toml` (lit by `dir/sky.exr`), which must fail, and asserts the error
/// names the scene, the light, the map and each of `parts`.
fn assert_load_error(dir: &Path, parts: &[&str]) {
    let scene = scene_with_map(dir);
    let msg = match load_scene_file(&scene, &MaterialRegistry::with_builtins()) {
        Ok(_) => panic!("{} loaded", scene.display()),
        Err(e) => e.to_string(),
    };
    let located = [
        scene.display().to_string(),
        "\"sky\"".to_string(),
        dir.join("sky.exr").display().to_string(),
    ];
    let located: Vec<&str> = located.iter().map(String::as_str).collect();
    assert_names(&msg, &located);
    assert_names(&msg, parts);
}

fn assert_names(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "`{p}` missing from: {msg}");
    }
}

#[test]
fn a_valid_map_loads() {
    let dir = scratch_dir("envmap", "valid");
    write_map(&dir.join("sky.exr"), (2.0, 0.0, 1e30));
    load_scene_file(&scene_with_map(&dir), &MaterialRegistry::with_builtins()).unwrap();
}

#[test]
fn non_finite_and_negative_texels_are_located_errors() {
    let cases = [
        ("nan", (0.5, f32::NAN, 0.5), "G", "NaN"),
        ("inf", (0.5, 0.5, f32::INFINITY), "B", "inf"),
        ("negative", (-0.25, 0.5, 0.5), "R", "-0.25"),
    ];
    for (name, bad, channel, value) in cases {
        let dir = scratch_dir("envmap", name);
        let map = dir.join("sky.exr");
        write_map(&map, bad);
        assert_load_error(&dir, &["(5, 2)", channel, value]);
    }
}

/// Writes a 4 x 4 RGB float EXR in ZIP16 scan lines (16 lines a chunk) and returns its bytes.
fn small_scanline_exr(path: &Path) -> Vec<u8> {
    use exr::prelude::*;
    let layer = Layer::new(
        (4, 4),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        SpecificChannels::rgb(|_: Vec2<usize>| (0.5f32, 0.5f32, 0.5f32)),
    );
    Image::from_layer(layer).write().to_file(path).unwrap();
    let bytes = std::fs::read(path).unwrap();
    assert!(bytes.len() < 2048, "{} bytes", bytes.len());
    bytes
}

/// The offset of the value of the attribute `name` of type `kind` (after its size field,
/// which must be `size`).
fn attribute_value(bytes: &[u8], name: &str, kind: &str, size: i32) -> usize {
    let key = format!("{name}\0{kind}\0");
    let at = bytes
        .windows(key.len())
        .position(|w| w == key.as_bytes())
        .unwrap_or_else(|| panic!("no {name} attribute"))
        + key.len();
    assert_eq!(&bytes[at..at + 4], &size.to_le_bytes(), "{name} size");
    at + 4
}

/// Makes the header claim a `(max + 1)^2` image: the dataWindow's `xMax, yMax` become `max`
/// and the chunkCount attribute the matching number of 16-line chunks, so the header is
/// consistent in itself and only the file's length gives it away.
fn patch_data_window(bytes: &mut [u8], max: i32) {
    let corners = attribute_value(bytes, "dataWindow", "box2i", 16);
    for k in [2, 3] {
        let o = corners + 4 * k;
        bytes[o..o + 4].copy_from_slice(&max.to_le_bytes());
    }
    let chunks = attribute_value(bytes, "chunkCount", "int", 4);
    let count = (max + 1 + 15) / 16;
    bytes[chunks..chunks + 4].copy_from_slice(&count.to_le_bytes());
}

/// `dir/sky.exr`: a small file whose header claims a `(max + 1)^2` image (see
/// [`patch_data_window`]); returns its path and `read_exr_rgb`'s error.
fn lying_map(dir: &Path, max: i32) -> (PathBuf, String) {
    let map = dir.join("sky.exr");
    let mut bytes = small_scanline_exr(&map);
    patch_data_window(&mut bytes, max);
    std::fs::write(&map, &bytes).unwrap();
    let err = read_exr_rgb(&map).unwrap_err().to_string();
    (map, err)
}

#[test]
fn a_header_claiming_a_huge_image_is_an_error_before_allocating() {
    let dir = scratch_dir("envmap", "huge");
    let (map, err) = lying_map(&dir, 99_999);
    assert_names(
        &err,
        &[
            &map.display().to_string(),
            "100000 x 100000",
            &MAX_IMAGE_PIXELS.to_string(),
        ],
    );
    assert_load_error(&dir, &["100000 x 100000"]);
}

#[test]
fn a_header_claiming_more_chunks_than_the_file_holds_is_an_error() {
    // 4000 x 4000 is under the pixel limit, but its 250 chunks need a 2 KB offset table and
    // 250 chunk headers that a ~1 KB file cannot contain.
    let (map, err) = lying_map(&scratch_dir("envmap", "chunks"), 3_999);
    assert_names(&err, &[&map.display().to_string(), "4000 x 4000", "bytes"]);
}
