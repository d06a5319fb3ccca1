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

/// One `.vol` named by 3,000 media (and a PNG by 3,000 patterns, an OBJ by 300 shapes) is
/// decoded once per scene load and shared (issue 37: the grid was read 3,000 times, 3.1 GB),
/// and the scene renders as the one naming it once does: bit for bit.
#[test]
fn a_file_named_by_thousands_of_entities_is_read_once() {
    use risotto::engine::render::{render, RenderOptions};
    use risotto::loader::load::{compile_scene, scene_from_desc, MaterialRegistry};
    use risotto::loader::scene_file::load_scene;
    let d = dir("read-once");
    // A 16^3 .vol (16 KiB of density).
    let n = 16i32;
    let mut vol = b"VOL\x03".to_vec();
    for v in [1, n, n, n, 1] {
        vol.extend(v.to_le_bytes());
    }
    for v in [0f32, 0., 0., 1., 1., 1.] {
        vol.extend(v.to_le_bytes());
    }
    for i in 0..n * n * n {
        vol.extend((0.5 + (i % 7) as f32 * 0.25).to_le_bytes());
    }
    std::fs::write(d.join("g.vol"), &vol).unwrap();
    let png = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/textures/beachball.png");
    std::fs::copy(&png, d.join("ball.png")).unwrap();
    let obj = "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 3 2\n";
    std::fs::write(d.join("tri.obj"), obj).unwrap();
    let fog =
        |i: usize| {
            format!(
            "[materials.fog{i}]\ntype = \"interface\"\ninterior = {{ type = \"heterogeneous\", \
             density = {{ grid = \"{}\" }}, scale = 3 }}\n\
             [materials.tex{i}]\ntype = \"diffuse\"\n\
             reflectance = {{ pattern = \"image\", path = \"ball.png\" }}\n",
            // Another spelling of the same file for half of them.
            if i.is_multiple_of(2) { "g.vol" } else { "./g.vol" }
        )
        };
    let shapes = "[[shapes]]\nname = \"fog\"\ntype = \"box\"\nmaterial = \"fog0\"\n\
                  min = [-0.5, 0.2, -0.5]\nmax = [0.5, 1.2, 0.5]\n";
    let tris = |k: usize| -> String {
        (0..k)
            .map(|i| {
                format!("[[shapes]]\ntype = \"mesh\"\nmaterial = \"tex0\"\npath = \"tri.obj\"\ntransform = [{{ translate = [{}, 0, -3] }}]\n", i as f32 * 1e-3)
            })
            .collect()
    };
    let many: String = (0..3000).map(fog).collect();
    let big = d.join("many.toml");
    std::fs::write(&big, format!("{SCENE}\n{many}\n{shapes}\n{}", tris(300))).unwrap();
    let one = d.join("one.toml");
    std::fs::write(
        &one,
        format!("{SCENE}\n{}\n{shapes}\n{}", fog(0), tris(300)),
    )
    .unwrap();
    let registry = MaterialRegistry::with_builtins();
    let image = |path: &Path| {
        let desc = load_scene(path).unwrap();
        let params = desc.materials[0].params.clone();
        let scene = scene_from_desc(desc, &registry).unwrap();
        // One grid, one texture, one mesh: three decodes, whatever the count of names.
        assert_eq!(params.side_files().decodes(), 3, "{}", path.display());
        let compiled = compile_scene(scene).unwrap();
        let options = RenderOptions {
            threads: Some(1),
            ..RenderOptions::default()
        };
        render(&compiled, &options, &|_| {}).unwrap().beauty.pixels
    };
    let start = std::time::Instant::now();
    let many_pixels = image(&big);
    let seconds = start.elapsed().as_secs_f64();
    assert_eq!(
        many_pixels,
        image(&one),
        "the shared grid renders as the single one"
    );
    assert!(seconds < 30.0, "3,000 media took {seconds} s");
}
