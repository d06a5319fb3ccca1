//! The driver's conventions from Mitsuba and pbrt (issue 35): `-D KEY.PATH=VALUE` overrides,
//! short flags, `--size`, `--no-preview`, a scene from standard input, and `--crop` errors
//! that show the expected order. Each override is checked against the flag or file edit it
//! stands for: the images must be the same bits.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

mod common;
use common::cli::{assert_fails, ok, risotto, SCENE};
use risotto::engine::output::read_exr_rgb;

fn setup(test: &str) -> (PathBuf, PathBuf) {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("cli-{test}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, SCENE).unwrap();
    (dir, scene)
}

/// The beauty's pixels as bits, and the size.
fn bits(path: &Path) -> (usize, usize, Vec<[u32; 3]>) {
    let img = read_exr_rgb(path).unwrap();
    let mut v = Vec::new();
    for y in 0..img.height {
        for x in 0..img.width {
            v.push(img.get(x, y).to_array().map(f32::to_bits));
        }
    }
    (img.width, img.height, v)
}

fn render(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(&["--quiet", "-t", "1"]);
    args.extend_from_slice(extra);
    risotto(&args)
}

#[test]
fn an_override_renders_as_the_edited_file_does() {
    let (dir, scene) = setup("define");
    let edited = dir.join("edited.toml");
    std::fs::write(
        &edited,
        SCENE
            .replace("spp = 4", "spp = 2")
            .replace("emission = 5", "emission = 2")
            .replace("reflectance = 0.5", "reflectance = 0.25"),
    )
    .unwrap();
    let (a, b, c) = (dir.join("a.exr"), dir.join("b.exr"), dir.join("c.exr"));
    ok("edited", render(&edited, &a, &[]));
    ok(
        "-D",
        render(
            &scene,
            &b,
            &[
                "-D",
                "render.spp=2",
                "--define",
                "shapes.1.emission=2",
                "-D",
                "materials.floor.reflectance=0.25",
            ],
        ),
    );
    ok("plain", render(&scene, &c, &[]));
    assert_eq!(bits(&a), bits(&b), "the overrides are the edits");
    assert_ne!(bits(&a), bits(&c), "the overrides change the image");
    // The later override wins.
    let d = dir.join("d.exr");
    ok(
        "twice",
        render(
            &scene,
            &d,
            &[
                "-D",
                "render.spp=7",
                "-D",
                "render.spp=2",
                "-D",
                "shapes.1.emission=2",
                "-D",
                "materials.floor.reflectance=0.25",
            ],
        ),
    );
    assert_eq!(bits(&a), bits(&d));
}

#[test]
fn size_and_no_preview() {
    let (dir, scene) = setup("size");
    let out = dir.join("small.exr");
    ok(
        "--size",
        render(&scene, &out, &["--size", "8x5", "--no-preview"]),
    );
    let (w, h, _) = bits(&out);
    assert_eq!((w, h), (8, 5));
    assert!(!dir.join("small.png").exists(), "--no-preview wrote a PNG");
    let with = dir.join("with.exr");
    ok("preview", render(&scene, &with, &[]));
    assert!(dir.join("with.png").exists());
    // --size is -D render.width/height.
    let d = dir.join("d.exr");
    ok(
        "-D size",
        render(
            &scene,
            &d,
            &["-D", "render.width=8", "-D", "render.height=5"],
        ),
    );
    assert_eq!(bits(&out), bits(&d));
    for bad in ["8", "0x5", "8x70000"] {
        assert_fails(
            bad,
            &render(&scene, &out, &["--size", bad]),
            &["--size", bad],
        );
    }
}

/// `risotto render - -o OUT` with `text` on standard input.
fn render_stdin(text: &str, out: &Path) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_risotto"))
        .args([
            "render",
            "-",
            "-o",
            out.to_str().unwrap(),
            "--quiet",
            "-t",
            "1",
        ])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(text.as_bytes())
        .unwrap();
    child.wait_with_output().unwrap()
}

#[test]
fn a_scene_from_standard_input_is_the_file() {
    let (dir, scene) = setup("stdin");
    let file_out = dir.join("file.exr");
    ok("file", render(&scene, &file_out, &[]));
    let stdin_out = dir.join("stdin.exr");
    ok("stdin", render_stdin(SCENE, &stdin_out));
    assert_eq!(bits(&file_out), bits(&stdin_out));
    // Errors in a scene from standard input name it so.
    let out = render_stdin(&SCENE.replace("spp = 4", "spp = -4"), &stdin_out);
    assert_fails("stdin error", &out, &["<stdin>:4:", "spp"]);
}

#[test]
fn bad_overrides_and_crops_say_what_is_expected() {
    let (dir, scene) = setup("errors");
    let out = dir.join("x.exr");
    let cases: [(&[&str], &[&str]); 5] = [
        (&["-D", "render.spp=0"], &["`-D render.spp=0`", "spp"]),
        (
            &["-D", "render.spp"],
            &["`-D render.spp`", "KEY.PATH=VALUE"],
        ),
        (
            &["-D", "shapes.9.radius=1"],
            &["`-D shapes.9.radius=1`", "from 0 to 1"],
        ),
        (
            &["--crop", "2,10,12,3"],
            &["--crop 2,10,12,3", "X0,Y0,X1,Y1", "not pbrt's x0,x1,y0,y1"],
        ),
        (&["--crop", "0,0,17,12"], &["--crop 0,0,17,12", "16x12"]),
    ];
    for (args, needles) in cases {
        assert_fails(&format!("{args:?}"), &render(&scene, &out, args), needles);
    }
    // `techniques` takes overrides too.
    let t = ok(
        "techniques -D",
        risotto(&["techniques", scene.to_str().unwrap(), "-D", "render.spp=2"]),
    );
    assert!(String::from_utf8_lossy(&t.stdout).contains("lighting"));
}

#[test]
fn stats_say_which_build_image_threads_and_where_the_time_went() {
    let (dir, scene) = setup("stats");
    let (out, stats) = (dir.join("s.exr"), dir.join("s.json"));
    ok(
        "--stats",
        render(
            &scene,
            &out,
            &[
                "--stats",
                stats.to_str().unwrap(),
                "--crop",
                "2,1,10,7",
                "--samples",
                "1..3",
            ],
        ),
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    let run = &v["run"];
    assert_eq!(run["version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(run["resolution"], serde_json::json!([16, 12]));
    assert_eq!(run["window"], serde_json::json!([2, 1, 10, 7]));
    assert_eq!(
        (run["spp"].as_u64(), run["threads"].as_u64()),
        (Some(4), Some(1))
    );
    assert_eq!(run["samples"], serde_json::json!([1, 3]));
    for key in [
        "load_seconds",
        "build_seconds",
        "render_seconds",
        "output_seconds",
    ] {
        let t = run[key].as_f64().unwrap_or(-1.0);
        assert!((0.0..60.0).contains(&t), "{key}: {t}");
    }
    assert_eq!(run["render_seconds"], v["wall_seconds"]);
    if cfg!(target_os = "linux") {
        assert!(run["peak_resident_bytes"].as_u64().unwrap() > 1 << 20);
    }
    if let Some(c) = run["commit"].as_str() {
        assert!(
            c.len() == 40 && c.chars().all(|c| c.is_ascii_hexdigit()),
            "{c}"
        );
    }
}

/// `--threads 1` holds for the whole run, loading and compiling too (they run on rayon's
/// global pool, which `--threads` sizes before the scene is read): on a mesh large enough
/// for the parallel BVH build (a 20,000-triangle grid), `render` reports one thread, and
/// `converge`, which compiles the scene before it reads its other options, starts (sizing
/// the pool after the build had started it failed).
#[test]
fn threads_bound_loading_and_compiling() {
    let (dir, scene) = setup("threads");
    let n = 100;
    let mut obj = String::new();
    for j in 0..=n {
        for i in 0..=n {
            obj += &format!(
                "v {} 0 {}\n",
                i as f32 / n as f32 - 0.5,
                j as f32 / n as f32 - 0.5
            );
        }
    }
    let v = |i: usize, j: usize| j * (n + 1) + i + 1;
    for j in 0..n {
        for i in 0..n {
            obj += &format!("f {} {} {}\n", v(i, j), v(i, j + 1), v(i + 1, j));
            obj += &format!("f {} {} {}\n", v(i + 1, j), v(i, j + 1), v(i + 1, j + 1));
        }
    }
    std::fs::write(dir.join("grid.obj"), obj).unwrap();
    let mut text = std::fs::read_to_string(&scene).unwrap();
    text += "\n[[shapes]]\nname = \"grid\"\ntype = \"mesh\"\npath = \"grid.obj\"\n\
             material = \"floor\"\ntransform = [{ translate = [0, 0.5, 0] }]\n";
    std::fs::write(&scene, text).unwrap();
    let (out, stats) = (dir.join("t.exr"), dir.join("t.json"));
    ok(
        "render -t 1",
        render(&scene, &out, &["--stats", stats.to_str().unwrap()]),
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert_eq!(v["run"]["threads"].as_u64(), Some(1));
    let converge_dir = dir.join("converge");
    let args = [
        "converge",
        scene.to_str().unwrap(),
        "--techniques",
        "lighting=mis",
        "--spp",
        "1",
        "--reference-spp",
        "2",
        "--threads",
        "1",
        "--out",
        converge_dir.to_str().unwrap(),
    ];
    ok("converge --threads 1", risotto(&args));
}

/// `convert` refuses what it cannot convert, with the reason: a TOML scene (nothing to
/// convert) and an output that would overwrite its input.
#[test]
fn convert_refuses_toml_input_and_overwriting_the_scene() {
    let (dir, scene) = setup("convert-refusals");
    let out = dir.join("out.toml");
    let o = risotto(&["convert", scene.to_str().unwrap(), out.to_str().unwrap()]);
    assert_fails("convert toml", &o, &["already a risotto TOML scene"]);
    assert!(!out.exists());
    let xml = dir.join("scene.xml");
    std::fs::write(&xml, "<scene version=\"3.0.0\"/>").unwrap();
    let o = risotto(&["convert", xml.to_str().unwrap(), xml.to_str().unwrap()]);
    assert_fails(
        "convert onto itself",
        &o,
        &["would overwrite the scene being converted"],
    );
    assert_eq!(
        std::fs::read_to_string(&xml).unwrap(),
        "<scene version=\"3.0.0\"/>"
    );
}

/// `--denoise` with a partial-render flag is a usage error naming both; in a build without
/// the `denoise` feature it is refused before anything renders, naming the feature and the
/// README section that says how to build it (with the feature: `tests/denoise.rs`).
#[test]
fn denoise_is_refused_with_partial_renders_and_without_its_feature() {
    let (dir, scene) = setup("denoise");
    let out = dir.join("d.exr");
    let crop = render(&scene, &out, &["--denoise", "--crop", "0,0,4,4"]);
    assert_fails("--denoise --crop", &crop, &["--denoise", "--crop"]);
    if !cfg!(feature = "denoise") {
        let refused = render(&scene, &out, &["--denoise"]);
        assert_fails(
            "--denoise without the feature",
            &refused,
            &["--denoise", "`denoise` feature", "\"Denoising\""],
        );
        assert!(!out.exists(), "a refused --denoise wrote {}", out.display());
    }
}
