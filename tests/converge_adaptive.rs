//! `risotto converge` with `adaptive=on` (issue 36): an adaptive curve's points are renders
//! at decreasing noise targets, each recording its target and the mean spp its pixels took
//! (the same as the `sampleCount` layer of `render --noise-target` at that target); `all`
//! includes it where the path tracer renders, and a bidirectional integrator with it is
//! refused before any render. Small scenes; the figures of merit are in the README.

use std::path::{Path, PathBuf};

mod common;
use common::cli::{assert_fails, risotto};
use common::converge::{assert_ok, converge, cornell, csv_rows, num, CORNELL_ALL};
use common::scratch_dir;

/// The scene of `tests/adaptive.rs`: very uneven noise (a smoky glass ball beside lit walls).
fn smoke_ball() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/adaptive-smoke-ball.toml")
}

/// The mean of the `sampleCount` layer of an EXR.
fn sample_count_mean(exr: &Path) -> f64 {
    use exr::prelude as x;
    let image = risotto::engine::output::read_exr_all(exr).unwrap();
    let channel = image
        .layer_data
        .iter()
        .flat_map(|part| part.channel_data.list.iter())
        .find(|c| c.name.eq("sampleCount"))
        .expect("no sampleCount layer");
    let x::FlatSamples::F32(counts) = &channel.sample_data else {
        panic!("sampleCount is not float32");
    };
    counts.iter().map(|&c| c as f64).sum::<f64>() / counts.len() as f64
}

#[test]
fn an_adaptive_curve_lowers_its_target_and_takes_more_samples_and_time() {
    let dir = scratch_dir("converge-adaptive", "curve");
    let scene = smoke_ball();
    let out_dir = dir.join("out");
    let out = converge(
        &scene,
        &out_dir,
        &[
            "--techniques",
            "adaptive=on",
            "--spp",
            "1024",
            "--noise-targets",
            "0.2,0.8,0.05",
            "--min-spp",
            "4",
            "--repeats",
            "2",
            "-D",
            "render.seed=3",
            "--reference-spp",
            "64",
            "--reference-technique",
            "lighting=mis",
            "--threads",
            "2",
        ],
    );
    assert_ok("converge adaptive=on", &out);
    let (header, rows) = csv_rows(&out_dir);
    assert_eq!(header, risotto::tools::converge::CSV_COLUMNS);
    assert_eq!(rows.len(), 3, "{rows:?}");
    // The targets in descending order whatever order they were given in; each point at
    // most the sweep's largest spp, at least the two looks of 4 samples.
    let targets: Vec<f64> = rows.iter().map(|r| num(r, "noise_target")).collect();
    let expected = [0.8, 0.2, 0.05];
    assert_eq!(targets, expected);
    for r in &rows {
        assert_eq!(
            (r["technique"].as_str(), r["spp"].as_str()),
            ("adaptive=on", "1024")
        );
        let m = num(r, "spp_mean");
        assert!((8.0..1024.0).contains(&m), "{r:?}");
    }
    // Lower targets: more samples (each step about 16 x the samples of the pixels still
    // sampling), so more time. The time is compared across the curve only, about 10 x the
    // samples: one step's 2.4 x can drown in the load of the tests running beside this one.
    for w in rows.windows(2) {
        assert!(
            num(&w[1], "spp_mean") > 1.5 * num(&w[0], "spp_mean"),
            "{:?}",
            w
        );
    }
    assert!(num(&rows[2], "spp_mean") > 8.0 * num(&rows[0], "spp_mean"));
    assert!(
        num(&rows[2], "seconds") > num(&rows[0], "seconds"),
        "{rows:?}"
    );
    // The JSON has them too; the table lists the curve.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("converge.json")).unwrap())
            .unwrap();
    let points = json["curves"][0]["points"].as_array().unwrap();
    assert_eq!(points[1]["noise_target"], 0.2);
    // Within an ulp or two: serde_json's parser (without its `float_roundtrip` feature) may
    // read the shortest decimal of an f64 one ulp off (240.99739583333334 as ...337).
    let (json_mean, csv_mean) = (
        points[1]["spp_mean"].as_f64().unwrap(),
        num(&rows[1], "spp_mean"),
    );
    assert!(
        (json_mean - csv_mean).abs() <= 1e-12 * csv_mean,
        "{json_mean} vs {csv_mean}"
    );
    assert_eq!(json["curves"][0]["techniques"]["adaptive"], "on");
    assert!(String::from_utf8_lossy(&out.stdout).contains("adaptive=on"));

    // The mean spp is the renders': `render --noise-target 0.2` with the same minimum and
    // cap writes a sampleCount layer of that mean, averaged over the repeats' seeds 3, 4.
    let rendered: f64 = ["3", "4"]
        .iter()
        .map(|seed| {
            let exr = dir.join(format!("target-0.2-seed-{seed}.exr"));
            let render = risotto(&[
                "render",
                scene.to_str().unwrap(),
                "--noise-target",
                "0.2",
                "--min-spp",
                "4",
                "--spp",
                "1024",
                "--seed",
                seed,
                "--threads",
                "2",
                "--quiet",
                "--out",
                exr.to_str().unwrap(),
            ]);
            assert_ok("render --noise-target", &render);
            sample_count_mean(&exr) / 2.0
        })
        .sum();
    let swept = num(&rows[1], "spp_mean");
    assert!(
        (rendered - swept).abs() <= 1e-9 * rendered,
        "render {rendered} vs converge {swept}"
    );
}

/// `adaptive=unbiased` sweeps the unbiased stopping rule beside `adaptive=on`: its own
/// curve, labelled and recorded as such, its pilot not in its mean spp.
#[test]
fn the_unbiased_rule_is_a_curve_of_its_own() {
    let dir = scratch_dir("converge-adaptive", "unbiased");
    let out_dir = dir.join("out");
    let out = converge(
        &smoke_ball(),
        &out_dir,
        &[
            "--techniques",
            "adaptive=on,adaptive=unbiased",
            "--spp",
            "256",
            "--noise-targets",
            "0.2",
            "--min-spp",
            "4",
            "--repeats",
            "1",
            "--reference-spp",
            "16",
            "--reference-technique",
            "lighting=mis",
            "--threads",
            "2",
        ],
    );
    assert_ok("converge adaptive=unbiased", &out);
    let (_, rows) = csv_rows(&out_dir);
    let labels: Vec<&str> = rows.iter().map(|r| r["technique"].as_str()).collect();
    assert_eq!(labels, ["adaptive=on", "adaptive=unbiased"]);
    for r in &rows {
        let m = num(r, "spp_mean");
        assert!((8.0..256.0).contains(&m), "{r:?}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("converge.json")).unwrap())
            .unwrap();
    assert_eq!(json["curves"][1]["techniques"]["adaptive"], "unbiased");
}

#[test]
fn all_adds_adaptive_on_once_where_the_path_tracer_renders() {
    let dir = scratch_dir("converge-adaptive", "all");
    let scene = cornell(&dir, 8);
    let out_dir = dir.join("out");
    let out = converge(&scene, &out_dir, &["--spp", "64", "--min-spp", "8"]);
    assert_ok("converge all", &out);
    let (_, rows) = csv_rows(&out_dir);
    let mut labels: Vec<&str> = rows.iter().map(|r| r["technique"].as_str()).collect();
    labels.dedup();
    let n = CORNELL_ALL.len();
    assert_eq!(labels[..n], CORNELL_ALL);
    assert_eq!(labels[n..], ["adaptive=on"]);
    // Uniform rows leave the adaptive columns empty; the adaptive curve starts at the
    // default first target.
    for r in &rows[..n] {
        assert_eq!(
            (r["noise_target"].as_str(), r["spp_mean"].as_str()),
            ("", "")
        );
    }
    assert_eq!(rows[n]["noise_target"], "4e-1");
    assert_eq!(rows[n]["technique"], "adaptive=on");

    // Too small a cap for any pixel to stop early: `all` leaves it out and says so.
    let out = converge(&scene, &dir.join("small"), &["--spp", "4"]);
    assert_ok("converge all --spp 4", &out);
    assert!(String::from_utf8_lossy(&out.stderr).contains("adaptive=on left out"));
    let (_, rows) = csv_rows(&dir.join("small"));
    assert!(rows.iter().all(|r| r["technique"] != "adaptive=on"));

    // A scene the bidirectional integrator renders: neither listed nor swept.
    let bdpt = ["-D", "render.integrator=\"bdpt\""];
    let listing = risotto(&["techniques", scene.to_str().unwrap(), bdpt[0], bdpt[1]]);
    assert_ok("techniques", &listing);
    assert!(!String::from_utf8_lossy(&listing.stdout).contains("adaptive"));
    let out = converge(
        &scene,
        &dir.join("bdpt"),
        &["--spp", "64", "--techniques", "all", bdpt[0], bdpt[1]],
    );
    assert_ok("converge all on a bdpt scene", &out);
    let (_, rows) = csv_rows(&dir.join("bdpt"));
    assert!(rows.iter().all(|r| !r["technique"].contains("adaptive")));
}

#[test]
fn a_time_budget_halves_the_target_and_caps_at_the_uniform_curves_largest_spp() {
    let dir = scratch_dir("converge-adaptive", "budget");
    let out_dir = dir.join("out");
    let budget = 0.03;
    let out = converge(
        &smoke_ball(),
        &out_dir,
        &[
            "--budget",
            &budget.to_string(),
            "--techniques",
            "lighting=mis,adaptive=on",
            "--noise-targets",
            "0.8",
            "--min-spp",
            "4",
            "--reference-spp",
            "64",
            "--threads",
            "2",
        ],
    );
    assert_ok("converge --budget adaptive=on", &out);
    let (_, rows) = csv_rows(&out_dir);
    let curve =
        |label: &str| -> Vec<_> { rows.iter().filter(|r| r["technique"] == label).collect() };
    let uniform = curve("lighting=mis+sampler=sobol");
    let adaptive = curve("adaptive=on");
    assert!(!uniform.is_empty() && !adaptive.is_empty(), "{rows:?}");
    // The cap: the uniform curve's largest spp, at least 4 x --min-spp.
    let cap = num(uniform.last().unwrap(), "spp").max(16.0);
    for (i, r) in adaptive.iter().enumerate() {
        assert_eq!(num(r, "spp"), cap, "{r:?}");
        assert_eq!(num(r, "noise_target"), 0.8 * 0.5f64.powi(i as i32), "{r:?}");
        // Only the last point may reach the budget (or every pixel took the cap there).
        if i + 1 < adaptive.len() {
            assert!(num(r, "seconds_mean") < budget, "row {i}: {r:?}");
        }
    }
}

#[test]
fn adaptive_with_a_bidirectional_integrator_and_bad_plans_are_refused() {
    let dir = scratch_dir("converge-adaptive", "bad");
    let scene = cornell(&dir, 8);
    let out_dir = dir.join("out");
    let refused = |args: &[&str], needles: &[&str]| {
        let out = converge(&scene, &out_dir, args);
        assert_fails(&args.join(" "), &out, needles);
        assert!(
            !out_dir.join("converge.csv").exists(),
            "{args:?} wrote a CSV"
        );
    };
    for integrator in ["bdpt", "vcm", "light"] {
        let spec = format!("lighting=mis,integrator={integrator}+adaptive=on");
        refused(
            &["--techniques", &spec],
            &[
                &format!("integrator={integrator}+adaptive=on"),
                "needs the path tracer",
            ],
        );
    }
    refused(
        &["--techniques", "adaptive=maybe"],
        &["adaptive", "maybe", "off, on"],
    );
    refused(
        &["--techniques", "adaptive=on", "--spp", "1,2,32"],
        &["--min-spp 16", "raise --spp or lower --min-spp"],
    );
    refused(
        &["--techniques", "adaptive=on", "--noise-targets", "0.1,-1"],
        &["--noise-targets", "-1"],
    );
    refused(
        &["--techniques", "adaptive=on", "--min-spp", "0"],
        &["--min-spp 0"],
    );
    refused(
        &["--reference-technique", "lighting=nee+adaptive=on"],
        &["--reference-technique", "rendered uniformly", "biased"],
    );
}
