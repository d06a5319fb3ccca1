//! The `risotto` driver end to end: a valid scene renders and writes its outputs; every kind
//! of bad input exits non-zero with a message that names the file and the problem (and never
//! a panic); the stats show that stages a scene does not need did not run.

use std::path::{Path, PathBuf};
use std::process::Output;

mod common;
use common::cli::{assert_fails, assert_fails_once, line_of, risotto, SCENE};
use common::scratch_dir;

/// `SCENE` with each `(from, to)` replacement applied once (each `from` must occur).
fn scene_with(edits: &[(&str, &str)]) -> String {
    let mut s = SCENE.to_string();
    for (from, to) in edits {
        assert!(s.contains(from), "test bug: {from:?} not in the scene");
        s = s.replacen(from, to, 1);
    }
    s
}

fn render(dir: &Path, name: &str, text: &str, extra: &[&str]) -> (Output, PathBuf) {
    let scene = dir.join(name);
    std::fs::write(&scene, text).unwrap();
    let out = dir.join(Path::new(name).with_extension("exr"));
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    args.extend_from_slice(extra);
    (risotto(&args), out)
}

fn stats_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Calls of a system in the stats (systems that never ran are left out of the JSON).
fn calls(stats: &serde_json::Value, system: &str) -> u64 {
    stats["systems"]
        .get(system)
        .map_or(0, |s| s["calls"].as_u64().unwrap())
}

#[test]
fn valid_scene_renders_exr_png_and_stats() {
    let dir = scratch_dir("cli", "valid");
    let stats = dir.join("stats.json");
    let (out, exr) = render(
        &dir,
        "ok.toml",
        SCENE,
        &["--stats", stats.to_str().unwrap(), "--threads", "2"],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = risotto::engine::output::read_exr_rgb(&exr).unwrap();
    assert_eq!((img.width, img.height), (16, 12));
    assert!(img.pixels.iter().all(|p| p.is_finite()));
    assert!(img.mean()[0] > 0.0, "black render");
    let png = std::fs::read(exr.with_extension("png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");

    let s = stats_json(&stats);
    for key in [
        "systems",
        "rays",
        "samples",
        "terminated",
        "nan_dropped",
        "wall_seconds",
        "features",
    ] {
        assert!(s.get(key).is_some(), "stats lack {key}: {s}");
    }
    assert_eq!(s["samples"].as_u64(), Some(16 * 12 * 4));
    assert!(s["rays"].as_u64().unwrap() >= 16 * 12 * 4);
    assert!(calls(&s, "intersect") > 0 && calls(&s, "shade") > 0);
    let features: Vec<&str> = s["features"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap())
        .collect();
    assert!(features.contains(&"area_lights") && features.contains(&"environment"));
    // Only needed stages ran: no transmissive surface, no volume.
    assert_eq!(calls(&s, "partition"), 0, "{s}");
    assert_eq!(calls(&s, "volume"), 0, "{s}");
    assert!(!features.contains(&"volumes"));
}

#[test]
fn volume_stages_run_only_when_a_scene_has_a_volume() {
    let dir = scratch_dir("cli", "volume");
    let stats = dir.join("stats.json");
    // An index-matched box of absorbing fog in front of the camera.
    let text = format!(
        "{SCENE}\n[materials.fog]\ntype = \"interface\"\n\
         interior = {{ type = \"beer\", sigma_a = [1, 1, 1] }}\n\n\
         [[shapes]]\nname = \"fog\"\ntype = \"box\"\nmaterial = \"fog\"\n\
         min = [-1, 0, -1]\nmax = [1, 1, 1]\n"
    );
    let (out, _) = render(
        &dir,
        "fog.toml",
        &text,
        &["--stats", stats.to_str().unwrap()],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s = stats_json(&stats);
    assert!(calls(&s, "partition") > 0, "{s}");
    assert!(calls(&s, "volume") > 0, "{s}");
    let features = s["features"].to_string();
    assert!(features.contains("volumes") && features.contains("transmissive_surfaces"));
}

#[test]
fn malformed_toml_reports_line_and_column() {
    let dir = scratch_dir("cli", "malformed");
    // Line 4, column 7 is the second `=`.
    let (out, _) = render(
        &dir,
        "broken.toml",
        &scene_with(&[("spp = 4", "spp = = 4")]),
        &[],
    );
    assert_fails("malformed TOML", &out, &["broken.toml:4:7"]);
}

/// A message stays printable: a terminal escape sequence in a file name is shown escaped,
/// not obeyed, and a hostile file's 100 000-character line is quoted as a window around the
/// error, not in full.
#[test]
fn messages_escape_control_characters_and_cut_long_lines() {
    let dir = scratch_dir("cli", "printable");
    let (out, _) = render(&dir, "a\u{1b}[31mred.toml", "x", &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        !stderr.contains('\u{1b}') && stderr.contains("a\\u{1b}[31mred.toml"),
        "{stderr:?}"
    );
    let deep = format!("x = {}\n", "[".repeat(100_000));
    let (out, _) = render(&dir, "deep.toml", &deep, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_fails("deep nesting", &out, &["deep.toml:1:", "^"]);
    assert!(
        stderr.len() < 2000 && stderr.lines().all(|l| l.chars().count() <= 1100),
        "{} bytes: {}",
        stderr.len(),
        &stderr[..stderr.len().min(300)]
    );
}

#[test]
fn missing_obj_names_the_path_tried() {
    let dir = scratch_dir("cli", "missing_obj");
    let text = scene_with(&[(
        "type = \"quad\"\nmaterial = \"floor\"\ncorner = [-5, 0, -5]\nedge1 = [0, 0, 10]\nedge2 = [10, 0, 0]",
        "type = \"mesh\"\nmaterial = \"floor\"\npath = \"meshes/nowhere.obj\"",
    )]);
    let (out, _) = render(&dir, "mesh.toml", &text, &[]);
    let tried = dir.join("meshes/nowhere.obj");
    assert_fails(
        "missing OBJ",
        &out,
        &["mesh.toml", "\"floor\"", "path", tried.to_str().unwrap()],
    );
}

#[test]
fn invalid_values_are_reported_with_file_entity_and_field() {
    let dir = scratch_dir("cli", "invalid");
    // (file name, edits of SCENE, what stderr must say)
    type Case<'a> = (&'a str, Vec<(&'a str, &'a str)>, &'a [&'a str]);
    let cases: [Case; 5] = [
        (
            "negative_emission.toml",
            vec![("emission = 5", "emission = [1, -2, 1]")],
            &["\"lamp\"", "emission", ">= 0", "-2"],
        ),
        (
            "zero_ior.toml",
            vec![(
                "[materials.emitter]",
                "[materials.glass]\ntype = \"dielectric\"\nior = 0\n\n[materials.emitter]",
            )],
            &["materials.glass", "ior", "> 0"],
        ),
        (
            "zero_direction.toml",
            vec![(
                "[[lights]]",
                "[[lights]]\nname = \"sun\"\ntype = \"distant\"\ndirection = [0, 0, 0]\n\
                 irradiance = 1\n\n[[lights]]",
            )],
            &["\"sun\"", "direction", "non-zero"],
        ),
        (
            "fov180.toml",
            vec![("fov = 40", "fov = 180")],
            &["camera", "fov", "180"],
        ),
        (
            "unknown_type.toml",
            vec![("type = \"diffuse\"\nreflectance = 0.5", "type = \"velvet\"")],
            &["materials.floor", "unknown material type", "velvet"],
        ),
    ];
    for (name, edits, needles) in cases {
        let (out, _) = render(&dir, name, &scene_with(&edits), &[]);
        let mut all = vec![name];
        all.extend_from_slice(needles);
        assert_fails(name, &out, &all);
    }
    // Value errors point at the offending line: `fov = 180` is on line 8, column 7.
    let (out, _) = render(
        &dir,
        "fov.toml",
        &scene_with(&[("fov = 40", "fov = 180")]),
        &[],
    );
    assert_fails("fov 180", &out, &["fov.toml:8:7"]);
}

#[test]
fn nonexistent_scene_is_reported() {
    let dir = scratch_dir("cli", "nonexistent");
    let missing = dir.join("no_such_scene.toml");
    let out = risotto(&["render", missing.to_str().unwrap(), "--quiet"]);
    assert_fails(
        "missing scene",
        &out,
        &["no_such_scene.toml", "cannot read"],
    );
}

#[test]
fn bad_options_are_rejected_before_rendering() {
    let dir = scratch_dir("cli", "options");
    // Issue 14 item 6: `--batch-size 1099511627776` panicked.
    for (flag, value) in [
        ("--spp", "0"),
        ("--spp", "65537"),
        ("--threads", "0"),
        // 100000 aborted the process (no stack for so many threads).
        ("--threads", "100000"),
        ("--batch-size", "1099511627776"),
    ] {
        let (out, exr) = render(&dir, "ok.toml", SCENE, &[flag, value]);
        assert_fails(flag, &out, &[&format!("{flag} {value}")]);
        assert!(!exr.exists(), "{flag} {value}: an image was written");
    }
    // `--exposure 1e30` (2^1e30 = inf) wrote an all-black preview of a lit image, NaN one
    // too: refused before rendering.
    for value in ["1e30", "-200", "nan", "inf"] {
        let (out, exr) = render(&dir, "ok.toml", SCENE, &["--exposure", value]);
        assert_fails(value, &out, &["--exposure", "between -64 and 64 stops"]);
        assert!(!exr.exists(), "--exposure {value}: an image was written");
    }
}

/// Outputs are checked before the render (issue 14 item 9): `--out` must be an EXR, the
/// stats file must differ from the EXR, its PNG preview and the scene, and a location that
/// cannot be written is an error before any sample is taken. Nothing the user named is
/// overwritten by another output.
#[test]
fn outputs_that_would_clobber_each_other_are_rejected_before_rendering() {
    let dir = scratch_dir("cli", "outputs");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let s = scene.to_str().unwrap();
    let exr = dir.join("x.exr");
    let (e, png) = (exr.to_str().unwrap(), dir.join("x.png"));
    let p = png.to_str().unwrap();

    // --out x.png: the EXR would be written there and then overwritten by the preview.
    let out = risotto(&["render", s, "--out", p, "--quiet"]);
    assert_fails("--out x.png", &out, &[p, ".exr"]);
    assert!(!png.exists(), "{p} was written");

    for (what, stats) in [("the EXR", e), ("the PNG preview", p), ("the scene", s)] {
        let out = risotto(&["render", s, "--out", e, "--stats", stats, "--quiet"]);
        assert_fails(&format!("--stats = {what}"), &out, &["--stats", stats]);
        assert!(!exr.exists() && !png.exists(), "--stats = {what}: rendered");
        assert_eq!(std::fs::read_to_string(&scene).unwrap(), SCENE, "{what}");
    }
    // The same file spelled differently is still the same file.
    let dotted = dir.join(".").join("x.exr");
    let out = risotto(&[
        "render",
        s,
        "--out",
        e,
        "--stats",
        dotted.to_str().unwrap(),
        "--quiet",
    ]);
    assert_fails("--stats = ./x.exr", &out, &["--stats"]);
}

/// Spawns `risotto ARGS` and waits at most `secs` seconds for it (killing it then).
fn run_with_timeout(args: &[&str], secs: u64) -> Option<Output> {
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_risotto"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while start.elapsed().as_secs() < secs {
        if child.try_wait().unwrap().is_some() {
            return Some(child.wait_with_output().unwrap());
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let _ = child.kill();
    let _ = child.wait();
    None
}

#[test]
fn an_unwritable_output_is_an_error_before_the_render() {
    let dir = scratch_dir("cli", "unwritable");
    // A render that would take hours: only a check before it can answer in time.
    let slow = scene_with(&[
        ("width = 16", "width = 2048"),
        ("height = 12", "height = 2048"),
        ("spp = 4", "spp = 65536"),
    ]);
    let scene = dir.join("slow.toml");
    std::fs::write(&scene, slow).unwrap();
    let s = scene.to_str().unwrap();
    let missing = dir.join("no/such/dir/x.exr");
    let m = missing.to_str().unwrap();
    let fine = dir.join("fine.exr");
    let sub = dir.join("a_directory");
    std::fs::create_dir_all(&sub).unwrap();
    let cases: [(&str, Vec<&str>, &str); 3] = [
        ("missing --out directory", vec!["--out", m], m),
        (
            "missing --stats directory",
            vec!["--out", fine.to_str().unwrap(), "--stats", m],
            m,
        ),
        (
            "--out is a directory",
            vec!["--out", sub.to_str().unwrap()],
            sub.to_str().unwrap(),
        ),
    ];
    for (what, extra, needle) in cases {
        let mut args = vec!["render", s, "--quiet"];
        args.extend(extra);
        let out = run_with_timeout(&args, 30)
            .unwrap_or_else(|| panic!("{what}: still rendering after 30 s"));
        assert_fails(what, &out, &[needle]);
    }
}

/// Bad scattering-media values are located errors: the file, the interior's entity, the key
/// and the value.
#[test]
fn bad_media_values_are_located_errors() {
    let dir = scratch_dir("cli", "media");
    let with_interior = |interior: &str| {
        scene_with(&[(
            "[materials.emitter]",
            &format!(
                "[materials.smoke]\ntype = \"interface\"\ninterior = {interior}\n\n\
                 [materials.emitter]"
            ),
        )])
    };
    let cases: [(&str, &str, &[&str]); 8] = [
        (
            "albedo.toml",
            r#"{ type = "homogeneous", sigma_t = 2, albedo = 1.5 }"#,
            &["materials.smoke.interior", "albedo", "[0, 1]", "1.5"],
        ),
        (
            "negative.toml",
            r#"{ type = "homogeneous", sigma_t = [1, -2, 1] }"#,
            &["materials.smoke.interior", "sigma_t", "-2"],
        ),
        (
            "g.toml",
            r#"{ type = "homogeneous", sigma_t = 2, phase = { type = "hg", g = 1.0 } }"#,
            &["materials.smoke.interior.phase", "g", "1"],
        ),
        (
            "blend.toml",
            r#"{ type = "homogeneous", sigma_t = 2, phase = { type = "double_hg", g1 = 0.5, g2 = -0.5, blend = 2 } }"#,
            &["phase", "blend", "2"],
        ),
        (
            "phase.toml",
            r#"{ type = "homogeneous", sigma_t = 2, phase = { type = "rayleigh" } }"#,
            &["phase", "unknown phase function", "rayleigh"],
        ),
        (
            "both.toml",
            r#"{ type = "homogeneous", sigma_t = 2, sigma_s = 1 }"#,
            &["materials.smoke.interior", "sigma_s", "not both"],
        ),
        (
            "none.toml",
            r#"{ type = "homogeneous", albedo = 0.5 }"#,
            &["materials.smoke.interior", "sigma_t"],
        ),
        (
            "mode.toml",
            r#"{ type = "homogeneous", sigma_t = 2, scattering = "double" }"#,
            &["scattering", "double", "multiple, walk, bounce, single"],
        ),
    ];
    for (name, interior, needles) in cases {
        let (out, _) = render(&dir, name, &with_interior(interior), &[]);
        let mut all = vec![name];
        all.extend_from_slice(needles);
        assert_fails(name, &out, &all);
    }
    // And a valid medium renders.
    let (out, exr) = render(
        &dir,
        "ok.toml",
        &with_interior(r#"{ type = "homogeneous", sigma_t = 2, albedo = 0.5 }"#),
        &[],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(exr.exists());
}

/// Errors found after parsing (the material registry, an environment map's contents, the
/// camera's volumes) are located like the parser's own, `file:line:col`, and each message
/// is printed once: errors whose message already holds their cause used to expose it as
/// `source()` too, so the driver's cause-chain printing repeated it (an unreadable
/// environment map printed its EXR error three times).
#[test]
fn late_errors_are_located_and_printed_once() {
    let dir = scratch_dir("cli", "late_errors");
    std::fs::write(dir.join("garbage.exr"), b"not an EXR file").unwrap();
    let glass_ball = "[[shapes]]\nname = \"ball\"\ntype = \"sphere\"\nmaterial = \"glass\"\n\
                      center = [0, 0.5, 0]\nradius = 0.5\n\n[[lights]]";
    // (file name, edits of SCENE, the edited value whose line:col must be named, the
    // message that must appear exactly once)
    let opaque_ball = glass_ball.replace("\"glass\"", "\"floor\"");
    type Case<'a> = (&'a str, Vec<(&'a str, &'a str)>, &'a str, &'a str);
    let cases: [Case; 6] = [
        (
            "material_type.toml",
            vec![("type = \"diffuse\"\nreflectance = 0.5", "type = \"difuse\"")],
            "\"difuse\"",
            "unknown material type \"difuse\"",
        ),
        (
            "interior_type.toml",
            vec![(
                "reflectance = 0.5",
                "reflectance = 0.5\ninterior = { type = \"bear\", sigma_a = 1 }",
            )],
            "\"bear\"",
            "unknown interior type \"bear\"",
        ),
        (
            "env_map.toml",
            vec![("radiance = 0.1", "map = \"garbage.exr\"")],
            "\"garbage.exr\"",
            "file identifier missing",
        ),
        (
            "missing_env_map.toml",
            vec![("radiance = 0.1", "map = \"nowhere.exr\"")],
            "\"nowhere.exr\"",
            "does not exist",
        ),
        (
            "camera_inside.toml",
            vec![
                ("to = [0, 0.5, 0]", "to = [0, 0.5, 0]\ninside = [\"ball\"]"),
                (
                    "[materials.emitter]",
                    "[materials.glass]\ntype = \"dielectric\"\n\n[materials.emitter]",
                ),
                ("[[lights]]", glass_ball),
            ],
            "[\"ball\"]",
            "is inside []",
        ),
        (
            "camera_inside_opaque.toml",
            vec![
                ("to = [0, 0.5, 0]", "to = [0, 0.5, 0]\ninside = [\"ball\"]"),
                ("[[lights]]", &opaque_ball),
            ],
            "[\"ball\"]",
            "shape \"ball\" has no interior",
        ),
    ];
    for (name, edits, value, message) in cases {
        let text = scene_with(&edits);
        let (out, _) = render(&dir, name, &text, &[]);
        let line = line_of(&text, value);
        let line_start = text[..text.find(value).unwrap()]
            .rfind('\n')
            .map_or(0, |i| i + 1);
        let col = text[line_start..text.find(value).unwrap()].chars().count() + 1;
        assert_fails(name, &out, &[&format!("{name}:{line}:{col}:")]);
        assert_fails_once(name, &out, message);
    }
    // The reference of `converge` is read by the driver: its EXR error names the file once.
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let garbage = dir.join("garbage.exr");
    let out = risotto(&[
        "converge",
        scene.to_str().unwrap(),
        "--reference",
        garbage.to_str().unwrap(),
        "--spp",
        "1",
        "--out",
        dir.join("converge").to_str().unwrap(),
    ]);
    assert_fails_once("converge --reference", &out, garbage.to_str().unwrap());
    assert_fails_once("converge --reference", &out, "file identifier missing");
}

/// Bad `subsurface` material values are located errors: the file, the material, the key and
/// the value; a valid one (all defaults but the colour) renders.
#[test]
fn bad_subsurface_values_are_located_errors() {
    let dir = scratch_dir("cli", "subsurface");
    let with_material = |body: &str| {
        scene_with(&[(
            "[materials.emitter]",
            &format!("[materials.skin]\ntype = \"subsurface\"\n{body}\n\n[materials.emitter]"),
        )])
    };
    let cases: [(&str, &str, &[&str]); 7] = [
        (
            "albedo.toml",
            "albedo = [0.5, 1.2, 0.5]",
            &["materials.skin", "albedo", "[0, 1]", "1.2"],
        ),
        (
            "mfp.toml",
            "mean_free_path = [1, 0, 1]",
            &["materials.skin", "mean_free_path", "> 0"],
        ),
        (
            "unit.toml",
            "unit_length = -0.01",
            &["materials.skin", "unit_length", "-0.01"],
        ),
        (
            "tiny.toml",
            "mean_free_path = 1e-30\nunit_length = 1e-20",
            &["materials.skin", "mean_free_path", "overflows"],
        ),
        ("g.toml", "g = 1.0", &["materials.skin", "g", "(-1, 1)"]),
        (
            "mode.toml",
            "mode = \"photon\"",
            &["materials.skin", "mode", "photon", "random_walk"],
        ),
        (
            "key.toml",
            "interior = { type = \"null\" }",
            &["materials.skin", "interior"],
        ),
    ];
    for (name, body, needles) in cases {
        let (out, _) = render(&dir, name, &with_material(body), &[]);
        let mut all = vec![name];
        all.extend_from_slice(needles);
        assert_fails(name, &out, &all);
    }
    let (out, exr) = render(
        &dir,
        "ok.toml",
        &with_material("albedo = [0.8, 0.5, 0.4]\nmean_free_path = 0.05"),
        &[],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(exr.exists());
}
