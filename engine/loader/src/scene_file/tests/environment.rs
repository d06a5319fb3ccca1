//! The environment light's map options: `filter`, `transform` (rotations only) and
//! `convention`, and their errors.

use super::*;
use glam::Mat3;
use risotto_engine::scratch_dir::ScratchDir;
use risotto_systems::environment_map::EnvFilter;

/// `BASE` with its environment light given a map (an existing file; only its existence is
/// checked at parse time) and the extra keys `keys`; returns the text and the scratch
/// directory holding `scene.toml`'s map (removed when dropped).
fn with_map(keys: &str) -> (String, ScratchDir) {
    // One directory per call: tests run in parallel and each scratch directory starts empty.
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let k = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = ScratchDir::new(&format!("env-map-options-{k}"));
    std::fs::write(dir.join("sky.exr"), b"only its existence matters here").unwrap();
    let text = base_with(
        "radiance = [0.1, 0.2, 0.3]",
        &format!("map = \"sky.exr\"\n{keys}"),
    );
    (text, dir)
}

fn environment(text: &str, dir: &Path) -> (EnvFilter, Mat3) {
    let s = parse_scene(text, &dir.join("scene.toml")).unwrap();
    match &s.lights[2] {
        LightDesc::Environment {
            filter, to_world, ..
        } => (*filter, *to_world),
        other => panic!("{other:?}"),
    }
}

#[test]
fn environment_map_defaults_to_bilinear_and_unrotated() {
    let (text, dir) = with_map("");
    assert_eq!(
        environment(&text, &dir),
        (EnvFilter::Bilinear, Mat3::IDENTITY)
    );
    let (text, dir) = with_map("filter = \"nearest\"");
    assert_eq!(environment(&text, &dir).0, EnvFilter::Nearest);
}

#[test]
fn environment_transform_is_a_rotation_and_convention_turns_it_half_about_y() {
    // Translation is ignored (the environment is at infinity); steps chain as for shapes.
    let (text, dir) = with_map(
        "transform = [{ rotate = { axis = [0, 1, 0], angle = 90 } }, { translate = [5, 0, 0] }]",
    );
    let (_, m) = environment(&text, &dir);
    // A quarter turn about +y takes +x to -z.
    assert!((m * Vec3::X - Vec3::NEG_Z).length() < 1e-6, "{m}");
    assert!((m * Vec3::Y - Vec3::Y).length() < 1e-6, "{m}");
    let (text, dir) = with_map(
        "transform = [{ rotate = { axis = [0, 1, 0], angle = 90 } }]\nconvention = \"mitsuba\"",
    );
    let (_, m) = environment(&text, &dir);
    // Mitsuba's u = 0 (its -z) is our u = 0.5's direction turned half: to_world = R Ry(π),
    // so the map's +x goes first to -x, then to +z.
    assert!((m * Vec3::X - Vec3::Z).length() < 1e-6, "{m}");
    let (text, dir) = with_map("convention = \"risotto\"");
    assert_eq!(environment(&text, &dir).1, Mat3::IDENTITY);
}

#[test]
fn environment_scale_shear_bad_names_and_keys_without_a_map_are_located_errors() {
    let cases = [
        (
            "transform = [{ scale = 2 }]",
            &["rotation", "[2.0000, 0.0000, 0.0000]"][..],
        ),
        (
            "transform = [{ matrix = [[1, 0.5, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]] }]",
            &["rotation", "0.5000"],
        ),
        (
            "filter = \"trilinear\"",
            &["`filter`", "\"bilinear\" or \"nearest\"", "trilinear"],
        ),
        (
            "convention = \"pbrt\"",
            &["`convention`", "\"mitsuba\"", "pbrt"],
        ),
    ];
    for (keys, fragments) in cases {
        let (text, dir) = with_map(keys);
        let e = parse_scene(&text, &dir.join("scene.toml")).unwrap_err();
        let msg = e.to_string();
        assert_eq!(e.line(), Some(line_of(&text, keys)), "{msg}");
        assert!(msg.contains("lights[2]"), "{msg}");
        for f in fragments {
            assert!(msg.contains(f), "`{f}` not in: {msg}");
        }
    }
    // Without a map the options mean nothing: an error at the key, not a silent no-op.
    for key in [
        "filter = \"nearest\"",
        "convention = \"mitsuba\"",
        "transform = []",
    ] {
        let text = base_with(
            "radiance = [0.1, 0.2, 0.3]",
            &format!("radiance = 1\n{key}"),
        );
        let e = parse_err(&text);
        assert_message(
            &e,
            line_of(&text, key),
            &["only applies to an environment `map`"],
        );
    }
}
