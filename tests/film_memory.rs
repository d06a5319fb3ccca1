//! The film's memory per pixel (issue 37): the figure the renderer checks a film against the
//! machine's memory with ([`FILM_BYTES_PER_PIXEL`]) is the one a render takes. Two renders of
//! a trivial scene (one sphere, sky, 1 spp) at 512^2 and 1024^2 pixels report their peak
//! resident memory (`--stats`, Linux `VmHWM`); the difference over the 786,432 extra pixels
//! is the film's cost per pixel, everything else (code, scene, threads) being the same.

use risotto::engine::render::FILM_BYTES_PER_PIXEL;
use std::path::Path;

mod common;
use common::cli::{ok, risotto};

const SCENE: &str = r#"[render]
width = SIZE
height = SIZE
spp = 1
[camera]
from = [0, 0, 5]
to = [0, 0, 0]
fov = 40
[materials.white]
type = "diffuse"
reflectance = [0.5, 0.5, 0.5]
[[shapes]]
type = "sphere"
material = "white"
center = [0, 0, 0]
radius = 1
[[lights]]
type = "environment"
radiance = [1, 1, 1]
"#;

/// Peak resident bytes of a render of the scene at `size`^2 (with the PNG preview, as a user
/// runs it), or `None` where the platform does not report it.
fn peak_resident(dir: &Path, size: u32) -> Option<u64> {
    let scene = dir.join(format!("s{size}.toml"));
    std::fs::write(&scene, SCENE.replace("SIZE", &size.to_string())).unwrap();
    let (out, stats) = (
        dir.join(format!("s{size}.exr")),
        dir.join(format!("s{size}.json")),
    );
    let args = [
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--stats",
        stats.to_str().unwrap(),
        "--quiet",
        "-t",
        "1",
    ];
    ok("render", risotto(&args));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    json["run"]["peak_resident_bytes"].as_u64()
}

#[test]
fn a_renders_film_costs_the_documented_bytes_per_pixel() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("film-memory");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let (Some(small), Some(large)) = (peak_resident(&dir, 512), peak_resident(&dir, 1024)) else {
        eprintln!("no peak memory on this platform: nothing to measure");
        return;
    };
    let per_pixel = large.saturating_sub(small) as f64 / (1024.0 * 1024.0 - 512.0 * 512.0);
    eprintln!("film: {per_pixel:.0} bytes a pixel (documented {FILM_BYTES_PER_PIXEL})");
    let documented = FILM_BYTES_PER_PIXEL as f64;
    assert!(
        (0.8 * documented..=1.2 * documented).contains(&per_pixel),
        "a render's film takes {per_pixel:.0} bytes a pixel; FILM_BYTES_PER_PIXEL says \
         {FILM_BYTES_PER_PIXEL}: update it (and docs/scene-format.md) or the film"
    );
}
