//! Files a scene names must be regular files within the documented size (issue 37): a
//! device (`/dev/zero`, read forever), a FIFO (blocks forever) or a directory is refused with a
//! located error naming the key and the path, before anything is read. The render is run as a
//! process with a deadline, so a regression hangs no test.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod common;
use common::cli::SCENE;

fn dir(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("side-{test}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Renders `scene` and returns its stderr; fails if it succeeds, panics or outlives 30 s.
fn refused(scene: &Path) -> String {
    let mut child = Command::new(env!("CARGO_BIN_EXE_risotto"))
        .args([
            "render",
            scene.to_str().unwrap(),
            "--quiet",
            "--no-preview",
            "-o",
        ])
        .arg(scene.with_extension("exr"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(30) {
            let _ = child.kill();
            panic!("{}: still running after 30 s", scene.display());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "{}: accepted", scene.display());
    assert!(!stderr.contains("panicked"), "{stderr}");
    stderr
}

#[test]
fn devices_fifos_and_directories_are_refused_before_reading() {
    let d = dir("special");
    let fifo = d.join("pipe.obj");
    let made = Command::new("mkfifo").arg(&fifo).status();
    let mut cases: Vec<(&str, String, &str)> = vec![
        (
            "mesh from /dev/zero",
            "[[shapes]]\ntype = \"mesh\"\nmaterial = \"floor\"\npath = \"/dev/zero\"\n".into(),
            "not a regular file",
        ),
        (
            "environment map that is a directory",
            "[[lights]]\ntype = \"environment\"\nmap = \".\"\n".into(),
            "is a directory",
        ),
        (
            "texture from /dev/zero",
            "[materials.tex]\ntype = \"diffuse\"\nreflectance = { pattern = \"image\", path = \"/dev/zero\" }\n".into(),
            "not a regular file",
        ),
    ];
    if made.is_ok_and(|s| s.success()) {
        cases.push((
            "mesh from a FIFO",
            "[[shapes]]\ntype = \"mesh\"\nmaterial = \"floor\"\npath = \"pipe.obj\"\n".into(),
            "not a regular file",
        ));
    }
    for (i, (what, extra, needle)) in cases.iter().enumerate() {
        // The sky light of SCENE is replaced for the environment case (one environment).
        let base = if extra.contains("environment") {
            SCENE.replace(
                "type = \"environment\"\nradiance = 0.1",
                "type = \"point\"\nposition = [0, 3, 0]\nintensity = 1",
            )
        } else {
            SCENE.to_string()
        };
        let scene = d.join(format!("case{i}.toml"));
        std::fs::write(&scene, format!("{base}\n{extra}")).unwrap();
        let m = refused(&scene);
        assert!(m.contains(needle), "{what}: {m}");
        assert!(
            m.contains(&format!("case{i}.toml:")),
            "{what}: names the scene line: {m}"
        );
    }
}

/// An OBJ's points and lines are not surfaces: skipped, and said so in the compiled scene's
/// warnings (which every render's stats repeat), counted.
#[test]
fn obj_points_and_lines_are_skipped_with_a_warning() {
    use risotto::loader::load::{compile_scene, load_scene_file, MaterialRegistry};
    let d = dir("obj-pl");
    let obj = "v 0 0 0\nv 1 0 0\nv 0 0 1\nv 1 1 1\np 4\nl 1 4\n  l 2 4\nf 1 3 2\n";
    std::fs::write(d.join("pl.obj"), obj).unwrap();
    let scene = d.join("pl.toml");
    let mesh = "[[shapes]]\ntype = \"mesh\"\nmaterial = \"floor\"\npath = \"pl.obj\"\n";
    std::fs::write(&scene, format!("{SCENE}\n{mesh}")).unwrap();
    let loaded = load_scene_file(&scene, &MaterialRegistry::with_builtins()).unwrap();
    let compiled = compile_scene(loaded).unwrap();
    let w: Vec<&String> = compiled
        .warnings
        .iter()
        .filter(|w| w.contains("pl.obj"))
        .collect();
    assert_eq!(w.len(), 1, "{:?}", compiled.warnings);
    assert!(
        w[0].contains("1 point and 2 line statements skipped"),
        "{}",
        w[0]
    );
    // Two quads (the scene's) and the one face.
    assert_eq!(compiled.geometry.num_triangles(), 5);
}
