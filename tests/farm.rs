//! Splitting a render into farm tasks and merging it back (issue 15): `--crop` pixels are the
//! bits of the whole render's, a 2x2 tile x 2 sample-range split merges to the one-process
//! render (tiles exactly; sample passes to the stated f64 summation order), every misfit is
//! refused with a message naming the files, bad `--crop` / `--samples` values are named, and
//! a checkpointed render that is killed resumes to the uninterrupted image; with `--aovs`
//! the parts carry the AOVs and the merge writes the one-process AOV layers.

use std::path::{Path, PathBuf};
use std::process::Output;

mod common;
use common::cli::{assert_fails, ok, risotto, SCENE};
use risotto::engine::output::read_exr_rgb;
use risotto::tools::merge::{read_partial, Partial};

/// A fresh directory for one test, with `SCENE` in it as `scene.toml`.
fn setup(test: &str) -> (PathBuf, PathBuf) {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("farm-{test}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.toml");
    // The shared CLI scene at 8 spp.
    std::fs::write(&scene, SCENE.replace("spp = 4", "spp = 8")).unwrap();
    (dir, scene)
}

/// `risotto render SCENE --out DIR/NAME --quiet EXTRA...`; returns the output path.
fn render(dir: &Path, scene: &Path, name: &str, extra: &[&str]) -> PathBuf {
    let out = dir.join(name);
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    args.extend_from_slice(extra);
    ok(&format!("render {name} {extra:?}"), risotto(&args));
    out
}

fn merge(dir: &Path, parts: &[&PathBuf], out: &str) -> (Output, PathBuf) {
    let out = dir.join(out);
    let mut args = vec!["merge".to_string()];
    args.extend(parts.iter().map(|p| p.to_str().unwrap().to_string()));
    args.extend(["--out".into(), out.to_str().unwrap().into()]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    (risotto(&args), out)
}

/// Bits of the beauty, variance and count of a partial, recomputed from its film.
fn layers(p: &Partial) -> (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<u32>) {
    let f = &p.film;
    let n = f.count.len();
    (
        (0..n).map(|i| f.mean(i).to_array()).collect(),
        (0..n).map(|i| f.variance_of_mean(i).to_array()).collect(),
        f.count.clone(),
    )
}

const TILES: [&str; 4] = ["0,0,8,6", "8,0,16,6", "0,6,8,12", "8,6,16,12"];

/// The AOV layers of an EXR's `aovs` part (`albedo.*`, `normal.*`, `depth.Z`), by name.
fn aov_layers(path: &Path) -> Vec<(String, Vec<f32>)> {
    let image = exr::prelude::read_all_flat_layers_from_file(path).unwrap();
    let part = image
        .layer_data
        .iter()
        .find(|l| {
            l.attributes
                .layer_name
                .as_ref()
                .is_some_and(|n| n.eq("aovs"))
        })
        .expect("an aovs part");
    let mut layers: Vec<(String, Vec<f32>)> = part
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .filter(|(name, _)| {
            ["albedo.", "normal.", "depth."]
                .iter()
                .any(|p| name.starts_with(p))
        })
        .collect();
    layers.sort_by(|a, b| a.0.cmp(&b.0));
    layers
}

/// f32 values at most `ulps` apart (as ordered bit patterns; +0 and -0 are equal).
fn within_ulps(a: f32, b: f32, ulps: i64) -> bool {
    let key = |x: f32| {
        let i = x.to_bits() as i32 as i64;
        if i < 0 {
            i64::from(i32::MIN) - i
        } else {
            i
        }
    };
    a == b || (key(a) - key(b)).abs() <= ulps
}

#[test]
fn crop_pixels_are_the_bits_of_the_whole_render() {
    let (dir, scene) = setup("crop");
    let full = read_exr_rgb(&render(&dir, &scene, "full.exr", &[])).unwrap();
    // An odd window that no tile grid lines up with.
    let crop = read_exr_rgb(&render(&dir, &scene, "crop.exr", &["--crop", "3,2,14,7"])).unwrap();
    assert_eq!((crop.width, crop.height), (11, 5));
    for y in 0..5 {
        for x in 0..11 {
            assert_eq!(
                crop.get(x, y).to_array().map(f32::to_bits),
                full.get(x + 3, y + 2).to_array().map(f32::to_bits),
                "pixel ({}, {})",
                x + 3,
                y + 2
            );
        }
    }
    // And the partial knows where it sits.
    let p = read_partial(&dir.join("crop.exr")).unwrap();
    assert_eq!(p.header.resolution, (16, 12));
    assert_eq!(p.header.window.to_string(), "3,2,14,7");
    assert_eq!(p.header.samples.to_string(), "0..8");
}

#[test]
fn tiles_times_sample_ranges_merge_to_the_one_process_render() {
    let (dir, scene) = setup("split");
    let whole = render(&dir, &scene, "whole.exr", &["--partial"]);
    let whole = read_partial(&whole).unwrap();
    let mut parts = Vec::new();
    for (t, tile) in TILES.iter().enumerate() {
        for range in ["0..3", "3..8"] {
            let name = format!("tile{t}-{range}.exr");
            parts.push(render(
                &dir,
                &scene,
                &name,
                &["--crop", tile, "--samples", range],
            ));
        }
    }
    let refs: Vec<&PathBuf> = parts.iter().collect();
    let (out, merged_path) = merge(&dir, &refs, "merged.exr");
    ok("merge", out);
    assert!(dir.join("merged.png").is_file());
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("merged.stats.json")).unwrap())
            .unwrap();
    assert_eq!(stats["parts"], 8);
    assert_eq!(stats["samples"], 16 * 12 * 8, "{stats}");
    let merged = read_partial(&merged_path).unwrap();
    assert_eq!(merged.film.count, whole.film.count);
    // Sums: the merged sum is (0 + S(0..3)) + S(3..8), the whole render's the sequential
    // S(0..8): equal to a few f64 ulps.
    for (i, (m, w)) in merged.film.sum.iter().zip(&whole.film.sum).enumerate() {
        for c in 0..3 {
            assert!(
                (m[c] - w[c]).abs() <= 1e-14 * w[c].abs(),
                "pixel {i}: sum {} vs {}",
                m[c],
                w[c]
            );
        }
    }
    // Beauty and variance: equal or one f32 ulp apart.
    let ((mb, mv, mc), (wb, wv, wc)) = (layers(&merged), layers(&whole));
    assert_eq!(mc, wc);
    for (what, a, b) in [("beauty", &mb, &wb), ("variance", &mv, &wv)] {
        for (i, (x, y)) in a.iter().zip(b).enumerate() {
            for c in 0..3 {
                let d = (x[c].to_bits() as i64 - y[c].to_bits() as i64).abs();
                assert!(d <= 1, "{what} pixel {i}: {} vs {}", x[c], y[c]);
            }
        }
    }
    // The file's own beauty part is what its sums say.
    let rgb = read_exr_rgb(&merged_path).unwrap();
    assert_eq!(
        rgb.pixels.iter().map(|p| p.to_array()).collect::<Vec<_>>(),
        mb
    );
    // The sample split is a real test: sample passes do not add to the same bits everywhere
    // by construction, but the tiles alone merge exactly.
    let tiles: Vec<PathBuf> = TILES
        .iter()
        .enumerate()
        .map(|(t, tile)| render(&dir, &scene, &format!("t{t}.exr"), &["--crop", tile]))
        .collect();
    let refs: Vec<&PathBuf> = tiles.iter().collect();
    let (out, tiled) = merge(&dir, &refs, "tiled.exr");
    ok("merge tiles", out);
    let tiled = read_partial(&tiled).unwrap();
    assert_eq!(tiled.film.sum, whole.film.sum, "tile merge must be exact");
    assert_eq!(tiled.film.sum_sq, whole.film.sum_sq);
}

#[test]
fn a_two_way_sample_split_merges_to_the_one_process_render() {
    let (dir, scene) = setup("samples");
    let whole = read_partial(&render(&dir, &scene, "whole.exr", &["--partial"])).unwrap();
    let a = render(&dir, &scene, "a.exr", &["--samples", "0..5"]);
    let b = render(&dir, &scene, "b.exr", &["--samples", "5..8"]);
    // Argument order does not matter: the sums are added by first sample index.
    let (out, ab) = merge(&dir, &[&a, &b], "ab.exr");
    ok("merge a b", out);
    let (out, ba) = merge(&dir, &[&b, &a], "ba.exr");
    ok("merge b a", out);
    let (ab, ba) = (read_partial(&ab).unwrap(), read_partial(&ba).unwrap());
    assert_eq!(ab.film.sum, ba.film.sum);
    let pa = read_partial(&a).unwrap();
    let pb = read_partial(&b).unwrap();
    for i in 0..ab.film.sum.len() {
        for c in 0..3 {
            assert_eq!(
                ab.film.sum[i][c],
                (0.0 + pa.film.sum[i][c]) + pb.film.sum[i][c]
            );
            let w = whole.film.sum[i][c];
            assert!((ab.film.sum[i][c] - w).abs() <= 1e-14 * w.abs());
        }
    }
    assert_eq!(ab.film.count, whole.film.count);
}

/// `--aovs` on farm tasks: a 2x2 grid x 2 sample chunks merges to the one-process `--aovs`
/// render's albedo, normal and depth layers (every value equal or one f32 ulp apart: the
/// f64 sums differ only in summation order, see `engine::merge`), the tiles alone merge to
/// them bit for bit, and carrying AOVs changes no bit of the beauty.
#[test]
fn aovs_of_tiles_times_sample_chunks_merge_to_the_one_process_aovs() {
    let (dir, scene) = setup("aovs");
    let one = aov_layers(&render(&dir, &scene, "one.exr", &["--aovs"]));
    let names: Vec<&str> = one.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        ["albedo.B", "albedo.G", "albedo.R", "depth.Z", "normal.X", "normal.Y", "normal.Z"]
    );
    assert!(
        one[3].1.iter().any(|&d| d > 0.0),
        "the camera sees something"
    );
    let whole_path = render(&dir, &scene, "whole.exr", &["--partial", "--aovs"]);
    let whole = read_partial(&whole_path).unwrap();
    let plain = read_partial(&render(&dir, &scene, "plain.exr", &["--partial"])).unwrap();
    assert!(plain.aovs.is_none());
    assert_eq!(whole.film.sum, plain.film.sum, "--aovs changed the beauty");
    assert_eq!(whole.film.sum_sq, plain.film.sum_sq);
    assert_eq!(
        aov_layers(&whole_path),
        one,
        "a partial writes the same layers"
    );
    let whole_aovs = whole.aovs.as_ref().expect("the partial carries AOV sums");

    let mut parts = Vec::new();
    for (col, row) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        for chunk in ["0", "1"] {
            let tile = format!("{col},{row}");
            let args = [
                "--grid", "2x2", "--tile", &tile, "--chunks", "2", "--chunk", chunk, "--aovs",
            ];
            parts.push(render(
                &dir,
                &scene,
                &format!("t{col}{row}-{chunk}.exr"),
                &args,
            ));
        }
    }
    let info = ok("info", risotto(&["info", parts[0].to_str().unwrap()]));
    let info: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
    assert_eq!(info["aovs"], true);
    let refs: Vec<&PathBuf> = parts.iter().collect();
    let (out, merged_path) = merge(&dir, &refs, "merged.exr");
    ok("merge", out);
    let merged = read_partial(&merged_path).unwrap();
    let sums = merged.aovs.as_ref().expect("the merge carries AOV sums");
    // Sums: (0 + S(0..4)) + S(4..8) against the sequential S(0..8), to f64 rounding.
    let close = |m: f64, w: f64| (m - w).abs() <= 1e-14 * w.abs().max(1.0);
    for i in 0..sums.depth.len() {
        assert!(close(sums.depth[i], whole_aovs.depth[i]), "depth sum {i}");
        for c in 0..3 {
            assert!(
                close(sums.albedo[i][c], whole_aovs.albedo[i][c]),
                "albedo {i}"
            );
            assert!(
                close(sums.normal[i][c], whole_aovs.normal[i][c]),
                "normal {i}"
            );
        }
    }
    // Layers: equal or one f32 ulp apart.
    let merged_layers = aov_layers(&merged_path);
    assert_eq!(merged_layers.len(), one.len());
    for ((name, m), (_, w)) in merged_layers.iter().zip(&one) {
        for (i, (a, b)) in m.iter().zip(w).enumerate() {
            assert!(within_ulps(*a, *b, 1), "{name} pixel {i}: {a} vs {b}");
        }
    }
    // Beauty: as without AOVs (within the same summation tolerance), counts exact.
    assert_eq!(merged.film.count, whole.film.count);
    let ((mb, _, _), (wb, _, _)) = (layers(&merged), layers(&whole));
    for (i, (x, y)) in mb.iter().zip(&wb).enumerate() {
        for c in 0..3 {
            assert!(within_ulps(x[c], y[c], 1), "beauty pixel {i}");
        }
    }

    // The tiles alone (every sample each) merge to the one-process layers bit for bit.
    let tiles: Vec<PathBuf> = TILES
        .iter()
        .enumerate()
        .map(|(t, tile)| {
            render(
                &dir,
                &scene,
                &format!("tile{t}.exr"),
                &["--crop", tile, "--aovs"],
            )
        })
        .collect();
    let refs: Vec<&PathBuf> = tiles.iter().collect();
    let (out, tiled_path) = merge(&dir, &refs, "tiled.exr");
    ok("merge tiles", out);
    let tiled = read_partial(&tiled_path).unwrap();
    assert_eq!(
        tiled.aovs.as_ref(),
        Some(whole_aovs),
        "tile merge must be exact"
    );
    assert_eq!(tiled.film.sum, whole.film.sum);
    let bits = |l: &[(String, Vec<f32>)]| -> Vec<Vec<u32>> {
        l.iter()
            .map(|(_, v)| v.iter().map(|x| x.to_bits()).collect())
            .collect()
    };
    assert_eq!(bits(&aov_layers(&tiled_path)), bits(&one));
}

#[test]
fn merge_refuses_parts_that_do_not_fit() {
    let (dir, scene) = setup("refuse");
    let tl = render(&dir, &scene, "tl.exr", &["--crop", "0,0,8,6"]);
    let tr = render(&dir, &scene, "tr.exr", &["--crop", "8,0,16,6"]);
    let bottom = render(&dir, &scene, "bottom.exr", &["--crop", "0,6,16,12"]);
    let (out, _) = merge(&dir, &[&tl, &tr, &bottom], "good.exr");
    ok("the fitting parts", out);
    // The top tiles and a bottom half rendered with one option changed.
    let fit_but_bottom = |name: &str, options: &[&str]| {
        let mut args = vec!["--crop", "0,6,16,12"];
        args.extend_from_slice(options);
        let bottom = render(&dir, &scene, name, &args);
        vec![tl.clone(), tr.clone(), bottom]
    };
    let cases: Vec<(&str, Vec<PathBuf>, Vec<&str>)> = vec![
        (
            "missing tile",
            vec![tl.clone(), bottom.clone()],
            vec!["missing coverage", "8,0,16,6"],
        ),
        (
            "overlapping tiles",
            vec![
                tl.clone(),
                tr.clone(),
                bottom.clone(),
                render(&dir, &scene, "mid.exr", &["--crop", "4,4,12,8"]),
            ],
            vec!["overlapping tiles", "mid.exr", "tl.exr", "4,4,8,6"],
        ),
        (
            "overlapping sample ranges",
            vec![
                render(&dir, &scene, "s05.exr", &["--samples", "0..5"]),
                render(&dir, &scene, "s38.exr", &["--samples", "3..8"]),
            ],
            vec!["overlapping sample ranges", "s05.exr", "s38.exr", "0..5"],
        ),
        (
            "missing sample range",
            vec![render(&dir, &scene, "s03.exr", &["--samples", "0..3"])],
            vec!["missing coverage", "0..3 from", "s03.exr"],
        ),
        (
            "different seed",
            fit_but_bottom("seed.exr", &["--seed", "9"]),
            vec!["seed.exr", "seed 9", "tl.exr", "seed 0"],
        ),
        (
            "different scene",
            fit_but_bottom("depth.exr", &["--max-depth", "2"]),
            vec!["depth.exr", "scene hash", "tl.exr"],
        ),
        (
            "different spp",
            fit_but_bottom("spp.exr", &["--spp", "4"]),
            vec!["spp.exr", "4 spp", "8 spp"],
        ),
        (
            "AOVs in some parts only",
            fit_but_bottom("aovs.exr", &["--aovs"]),
            vec![
                "aovs.exr carries them",
                "tl.exr, ",
                "tr.exr do not",
                "--aovs",
            ],
        ),
    ];
    for (what, parts, needles) in cases {
        let refs: Vec<&PathBuf> = parts.iter().collect();
        let (out, path) = merge(&dir, &refs, &format!("{}.exr", what.replace(' ', "-")));
        assert_fails(what, &out, &needles);
        assert!(!path.exists(), "{what}: wrote {}", path.display());
    }
    // A different resolution: the same scene at another size.
    let small = dir.join("small.toml");
    std::fs::write(
        &small,
        SCENE
            .replace("spp = 4", "spp = 8")
            .replace("width = 16", "width = 8"),
    )
    .unwrap();
    let other = render(&dir, &small, "small.exr", &["--crop", "0,6,8,12"]);
    let (out, _) = merge(&dir, &[&tl, &tr, &other], "res.exr");
    assert_fails(
        "resolution",
        &out,
        &["small.exr", "8x12", "16x12", "tl.exr"],
    );
    // Not a partial at all, and a missing file.
    let plain = render(&dir, &scene, "plain.exr", &[]);
    let (out, _) = merge(&dir, &[&plain], "plain-merged.exr");
    assert_fails(
        "plain render",
        &out,
        &["plain.exr", "not a risotto partial"],
    );
    let (out, _) = merge(&dir, &[&dir.join("nothing.exr")], "none.exr");
    assert_fails("missing file", &out, &["nothing.exr"]);
    // Outputs onto the parts: `--out tl.exr` merged and then overwrote the tile, and
    // `--stats` could overwrite another. Refused before reading, the part left as it was.
    let tl_bytes = std::fs::read(&tl).unwrap();
    let (out, _) = merge(&dir, &[&tl, &tr, &bottom], "tl.exr");
    let t = tl.to_str().unwrap();
    assert_fails("--out = a part", &out, &["--out", t, "the part"]);
    let o = dir.join("refused.exr");
    let merge_with = |extra: &[&str]| {
        let mut args = vec!["merge", t, tr.to_str().unwrap(), bottom.to_str().unwrap()];
        args.extend_from_slice(&["--out", o.to_str().unwrap()]);
        args.extend_from_slice(extra);
        risotto(&args)
    };
    let r = merge_with(&["--stats", t]);
    assert_fails("--stats = a part", &r, &["--stats", t, "the part"]);
    assert!(!o.exists(), "the refused merge wrote {}", o.display());
    assert_eq!(
        std::fs::read(&tl).unwrap(),
        tl_bytes,
        "the part was changed"
    );
    // A preview exposure that would write a black PNG for a white image.
    let r = merge_with(&["--exposure", "1e30"]);
    assert_fails("--exposure 1e30", &r, &["--exposure", "between -64 and 64"]);
    assert!(!o.exists(), "the refused merge wrote {}", o.display());
}

#[test]
fn bad_crop_and_sample_ranges_are_named() {
    let (dir, scene) = setup("bad-args");
    let s = scene.to_str().unwrap();
    let out = dir.join("x.exr");
    let o = out.to_str().unwrap();
    for (flag, value, needles) in [
        (
            "--crop",
            "0,0,17,5",
            vec!["--crop 0,0,17,5", "outside the 16x12"],
        ),
        ("--crop", "0,12,4,13", vec!["--crop 0,12,4,13", "outside"]),
        ("--crop", "5,5,5,6", vec!["--crop 5,5,5,6", "empty"]),
        ("--crop", "6,5,4,6", vec!["--crop 6,5,4,6", "empty"]),
        ("--crop", "1,2,3", vec!["--crop 1,2,3", "four"]),
        ("--crop", "1,2,x,4", vec!["--crop 1,2,x,4", "\"x\""]),
        ("--samples", "3..3", vec!["--samples 3..3", "empty"]),
        ("--samples", "5..2", vec!["--samples 5..2", "empty"]),
        (
            "--samples",
            "0..9",
            vec!["--samples 0..9", "8 samples per pixel"],
        ),
        ("--samples", "4", vec!["--samples", "START..END"]),
        ("--samples", "a..4", vec!["--samples", "\"a\""]),
        ("--checkpoint", "0", vec!["--checkpoint 0", "positive"]),
        (
            "--checkpoint",
            "1e300",
            vec!["--checkpoint 1e300", "too long"],
        ),
    ] {
        let r = risotto(&["render", s, "--out", o, "--quiet", flag, value]);
        assert_fails(&format!("{flag} {value}"), &r, &needles);
        assert!(!out.exists(), "{flag} {value} wrote a file");
    }
}

/// A render killed after its first checkpoint leaves a valid partial at --out; rendering
/// the missing samples and merging gives the uninterrupted render, AOVs included.
#[test]
fn a_killed_checkpointed_render_resumes_to_the_uninterrupted_one() {
    let (dir, scene) = setup("resume");
    // Enough samples that the render outlives its first checkpoints by far.
    let spp = "4096";
    let out = dir.join("job.exr");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_risotto"))
        .args([
            "render",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
            "--spp",
            spp,
            "--threads",
            "1",
            "--checkpoint",
            "0.2",
            "--aovs",
        ])
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while !out.exists() {
        assert!(
            start.elapsed().as_secs() < 60,
            "no checkpoint after a minute"
        );
        assert!(child.try_wait().unwrap().is_none(), "render ended early");
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    child.kill().unwrap();
    let status = child.wait().unwrap();
    assert!(
        !status.success(),
        "the render finished before it was killed"
    );
    let checkpoint = read_partial(&out).expect("the checkpoint is a valid partial");
    let done = checkpoint.header.samples;
    assert_eq!(done.start, 0);
    assert!(done.end > 0 && done.end < 4096, "{done}");
    assert!(checkpoint.film.count.iter().all(|&c| c == done.end));
    assert!(checkpoint.aovs.is_some(), "the checkpoint keeps the AOVs");
    // `risotto info` says what is done.
    let info = ok("info", risotto(&["info", out.to_str().unwrap()]));
    let info: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
    assert_eq!(info["samples"], serde_json::json!([0, done.end]));
    // Resume: the missing range, then merge.
    let rest = render(
        &dir,
        &scene,
        "rest.exr",
        &[
            "--spp",
            spp,
            "--samples",
            &format!("{}..{spp}", done.end),
            "--aovs",
        ],
    );
    let (o, merged) = merge(&dir, &[&out, &rest], "resumed.exr");
    ok("merge resumed", o);
    let merged = read_partial(&merged).unwrap();
    let whole = read_partial(&render(
        &dir,
        &scene,
        "whole.exr",
        &["--spp", spp, "--partial", "--aovs"],
    ))
    .unwrap();
    assert_eq!(merged.film.count, whole.film.count);
    for (m, w) in merged.film.sum.iter().zip(&whole.film.sum) {
        for c in 0..3 {
            assert!(
                (m[c] - w[c]).abs() <= 1e-13 * w[c].abs(),
                "{} vs {}",
                m[c],
                w[c]
            );
        }
    }
    let (m, w) = (merged.aovs.unwrap(), whole.aovs.unwrap());
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-13 * b.abs().max(1.0);
    for i in 0..w.depth.len() {
        assert!(close(m.depth[i], w.depth[i]), "depth sum {i}");
        for c in 0..3 {
            assert!(close(m.albedo[i][c], w.albedo[i][c]), "albedo sum {i}");
            assert!(close(m.normal[i][c], w.normal[i][c]), "normal sum {i}");
        }
    }
}

/// Checkpoints do not change the image: tiles keep their films across passes, so the sums
/// are added in the same order as without them.
#[test]
fn a_checkpointed_render_is_the_same_bits() {
    let (dir, scene) = setup("checkpoint-bits");
    let plain = read_partial(&render(&dir, &scene, "plain.exr", &["--partial", "--aovs"])).unwrap();
    let cp = read_partial(&render(
        &dir,
        &scene,
        "cp.exr",
        &["--checkpoint", "0.000001", "--aovs"],
    ))
    .unwrap();
    assert_eq!(cp.film.sum, plain.film.sum);
    assert_eq!(cp.film.sum_sq, plain.film.sum_sq);
    assert!(cp.aovs.is_some());
    assert_eq!(cp.aovs, plain.aovs);
    assert_eq!(cp.header.samples, plain.header.samples);
}

/// `--grid COLSxROWS --tile COL,ROW` and `--chunks N --chunk J` (the farm templates' task
/// indices) cut the image and the spp with no gap and no overlap, and merge.
#[test]
fn grid_tiles_and_sample_chunks_cover_the_render() {
    let (dir, scene) = setup("grid");
    let mut parts = Vec::new();
    // 3 columns of a 16-pixel row: 0..5, 5..10, 10..16; 3 chunks of 8: 0..2, 2..5, 5..8.
    for col in 0..3 {
        for chunk in 0..3 {
            let name = format!("c{col}-{chunk}.exr");
            let tile = format!("{col},0");
            let chunk = chunk.to_string();
            let args = [
                "--grid", "3x1", "--tile", &tile, "--chunks", "3", "--chunk", &chunk,
            ];
            parts.push(render(&dir, &scene, &name, &args));
        }
    }
    let header = |i: usize| read_partial(&parts[i]).unwrap().header;
    assert_eq!(header(0).window.to_string(), "0,0,5,12");
    assert_eq!(header(4).window.to_string(), "5,0,10,12");
    assert_eq!(header(8).window.to_string(), "10,0,16,12");
    assert_eq!(header(0).samples.to_string(), "0..2");
    assert_eq!(header(1).samples.to_string(), "2..5");
    assert_eq!(header(2).samples.to_string(), "5..8");
    let refs: Vec<&PathBuf> = parts.iter().collect();
    let (out, merged) = merge(&dir, &refs, "merged.exr");
    ok("merge grid", out);
    let merged = read_partial(&merged).unwrap();
    assert!(merged.film.count.iter().all(|&c| c == 8));
    let s = scene.to_str().unwrap();
    let o = dir.join("x.exr");
    let o = o.to_str().unwrap();
    for (args, needles) in [
        (
            vec!["--grid", "3x1", "--tile", "3,0"],
            vec!["--tile 3,0", "3x1"],
        ),
        (
            vec!["--grid", "17x1", "--tile", "0,0"],
            vec!["--grid 17x1", "16x12"],
        ),
        (vec!["--grid", "0x1", "--tile", "0,0"], vec!["--grid 0x1"]),
        (
            vec!["--grid", "2", "--tile", "0,0"],
            vec!["--grid 2", "AxB"],
        ),
        (
            vec!["--chunks", "9", "--chunk", "0"],
            vec!["--chunks 9", "8"],
        ),
        (
            vec!["--chunks", "2", "--chunk", "2"],
            vec!["--chunk 2", "below"],
        ),
    ] {
        let mut a = vec!["render", s, "--out", o, "--quiet"];
        a.extend_from_slice(&args);
        assert_fails(&format!("{args:?}"), &risotto(&a), &needles);
    }
}

#[test]
fn progress_json_prints_one_parseable_line_per_update_and_a_last_done_line() {
    // What a farm manager parses: every stdout line is a JSON object, the counts never
    // decrease, and the last line says done with every sample of the window counted.
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("farm-progress-json");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let out_exr = dir.join("out.exr");
    let out = risotto(&[
        "render",
        scene.to_str().unwrap(),
        "--spp",
        "8",
        "--crop",
        "2,3,10,9",
        "--progress",
        "json",
        "--out",
        out_exr.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<serde_json::Value> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l:?}: {e}")))
        .collect();
    let last = lines.last().expect("at least the done line");
    assert_eq!(last["event"], "done", "{stdout}");
    let total = 8 * 6 * 8; // the crop's 8 x 6 pixels at 8 spp
    assert_eq!(last["samples_total"], total);
    assert_eq!(last["samples_done"], total);
    assert_eq!(last["fraction"].as_f64(), Some(1.0));
    let done: Vec<u64> = lines
        .iter()
        .map(|v| v["samples_done"].as_u64().unwrap())
        .collect();
    assert!(done.windows(2).all(|w| w[0] <= w[1]), "{done:?}");
    // A mode that does not exist is a usage error naming it.
    let bad = risotto(&["render", scene.to_str().unwrap(), "--progress", "jsn"]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("jsn"));
}

#[test]
fn merge_refuses_parts_rendered_from_a_different_mesh_file() {
    // The scene text is the same; only the OBJ it reads changed between the tasks (a vertex
    // moved): the scene hash covers the files a scene reads, so merging is refused.
    let (dir, _) = setup("mesh-hash");
    let obj =
        |z: f32| format!("v -1 -1 {z}\nv 1 -1 {z}\nv 1 1 {z}\nv -1 1 {z}\nf 1 2 3\nf 1 3 4\n");
    let scene = dir.join("mesh.toml");
    std::fs::write(
        &scene,
        r#"
[render]
width = 8
height = 8
spp = 2

[camera]
fov = 40
from = [0, 0, 4]
to = [0, 0, 0]

[materials.white]
type = "diffuse"

[[shapes]]
type = "mesh"
path = "quad.obj"
material = "white"

[[lights]]
type = "environment"
radiance = 1
"#,
    )
    .unwrap();
    std::fs::write(dir.join("quad.obj"), obj(0.0)).unwrap();
    let top = render(&dir, &scene, "top.exr", &["--crop", "0,0,8,4"]);
    let bottom_same = render(&dir, &scene, "bottom-same.exr", &["--crop", "0,4,8,8"]);
    let (out, _) = merge(&dir, &[&top, &bottom_same], "same.exr");
    ok("the same mesh", out);
    std::fs::write(dir.join("quad.obj"), obj(0.5)).unwrap();
    let bottom = render(&dir, &scene, "bottom.exr", &["--crop", "0,4,8,8"]);
    let (out, path) = merge(&dir, &[&top, &bottom], "changed.exr");
    assert_fails(
        "a changed mesh",
        &out,
        &["bottom.exr", "scene hash", "top.exr"],
    );
    assert!(!path.exists());
}

/// A checkpoint that cannot be written costs only its protection: the render warns and goes
/// on to the end. Here the render's temporary file (`.job.exr.PID.tmp`, the name every
/// write of `job.exr` by that process goes through) is made a directory as soon as the
/// process exists, long before its first checkpoint: every checkpoint fails, whatever the
/// disk's speed (the test used to swap the first checkpoint for a directory, and a slow
/// first write could size the next pass to the rest of the render, leaving no later
/// checkpoint to fail); the render still finishes every sample and only then fails,
/// writing its final image.
#[test]
fn a_checkpoint_that_cannot_be_written_is_a_warning() {
    let (dir, scene) = setup("checkpoint_fails");
    let out = dir.join("job.exr");
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_risotto"))
        .args([
            "render",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
            "--spp",
            // About 3 s of rendering: many checkpoints.
            "65536",
            "--threads",
            "1",
            "--checkpoint",
            "0.05",
        ])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::fs::create_dir(dir.join(format!(".job.exr.{}.tmp", child.id()))).unwrap();
    let result = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(!result.status.success(), "{stderr}");
    assert!(
        stderr.contains("warning: checkpoint not written, rendering on")
            && stderr.contains("checkpoint(s) could not be written to"),
        "{stderr}"
    );
    // The render ran to its end: the failure is the final image's, not a checkpoint's.
    let last = stderr.lines().last().unwrap_or_default();
    assert!(
        last.starts_with("error:") && last.contains("job.exr"),
        "{stderr}"
    );
}
