//! Every shipped scene (`scenes/**/*.toml`) builds, compiles and renders at a tiny size
//! without NaNs, to a finite image that is not black. The hard cases of `scenes/hard/`
//! (some exactly black, some 1e-30) are checked against their own stated expectations by
//! `tests/hard_scenes.rs`.

use risotto::engine::render::{render, RenderOptions};
use risotto::loader::load::{compile_scene, load_scene_file, MaterialRegistry};
use std::path::{Path, PathBuf};

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

fn toml_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("scenes dir") {
        let path = entry.expect("dir entry").path();
        if path.is_dir() {
            if path.file_name().is_some_and(|n| n == "hard") {
                continue;
            }
            toml_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "toml") {
            out.push(path);
        }
    }
}

#[test]
fn every_scene_renders_finite_and_not_black() {
    let mut files = Vec::new();
    toml_files(&scenes_dir(), &mut files);
    files.sort();
    let registry = MaterialRegistry::with_builtins();
    for required in [
        "mitsuba-suite/glass_beer.toml",
        "liquid-in-glass.toml",
        "overlapping-absorbers.toml",
        "camera-in-volume.toml",
        "fire.toml",
    ] {
        assert!(
            files.contains(&scenes_dir().join(required)),
            "{required} missing"
        );
    }
    for file in files {
        let mut scene = load_scene_file(&file, &registry).unwrap_or_else(|e| panic!("{e}"));
        // Tiny: 24 pixels wide, the scene's aspect ratio, 4 samples.
        let s = &mut scene.settings;
        let h = ((24 * s.height) / s.width).max(1);
        s.width = 24;
        s.height = h;
        s.spp = 4;
        scene.camera.width = 24;
        scene.camera.height = h;
        let compiled = compile_scene(scene).unwrap_or_else(|e| panic!("{e}"));
        let out = render(&compiled, &RenderOptions::default(), &|_| {}).unwrap();
        let what = file.display();
        assert_eq!(out.stats.counters.nan_dropped, 0, "{what}: NaN samples");
        assert!(
            out.beauty.pixels.iter().all(|p| p.is_finite()),
            "{what}: non-finite pixels"
        );
        let m = out.beauty.mean();
        assert!(m.iter().all(|c| *c > 1e-3), "{what}: mean {m:?}");
    }
}

#[test]
fn camera_in_volume_scene_states_what_probing_finds() {
    let file = scenes_dir().join("camera-in-volume.toml");
    let registry = MaterialRegistry::with_builtins();
    let explicit = load_scene_file(&file, &registry).unwrap();
    assert_eq!(explicit.camera_volume, Some(vec!["haze".to_string()]));
    let explicit = compile_scene(explicit).unwrap();
    let mut probed = load_scene_file(&file, &registry).unwrap();
    probed.camera_volume = None;
    let probed = compile_scene(probed).unwrap();
    assert_eq!(probed.camera_stack.len(), 1);
    assert_eq!(probed.camera_stack, explicit.camera_stack);
}
