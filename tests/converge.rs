//! `risotto techniques`, `risotto converge` and `risotto render --technique` end to end, on
//! small versions of the Mitsuba cornell box: the sweep's four files and their consistency,
//! the errors that real estimator properties imply (MSE falls with spp; Sobol beats the
//! independent sampler on a diffuse scene), zero error against the render itself, and bad
//! input rejected with a message naming it.

use std::collections::BTreeMap;
use std::path::Path;

mod common;
use common::cli::{assert_fails, risotto};
use common::converge::{assert_ok, converge, cornell, csv_rows, num, CORNELL_ALL};
use common::scratch_dir;

/// The MSE of `technique` at `spp` in the sweep in `dir`.
fn mse(rows: &[BTreeMap<String, String>], technique: &str, spp: u32) -> f64 {
    let row = rows
        .iter()
        .find(|r| r["technique"] == technique && r["spp"] == spp.to_string())
        .unwrap_or_else(|| panic!("no row {technique} {spp}"));
    num(row, "mse")
}

#[test]
fn sweep_writes_csv_json_png_and_svg_that_agree() {
    let dir = scratch_dir("converge", "files");
    let scene = cornell(&dir, 16);
    let out_dir = dir.join("out");
    let out = converge(
        &scene,
        &out_dir,
        &["--spp", "1,2,4", "--reference-spp", "64", "--repeats", "2"],
    );
    assert_ok("converge", &out);
    let table = String::from_utf8_lossy(&out.stdout);

    let (header, rows) = csv_rows(&out_dir);
    assert_eq!(header, risotto::tools::converge::CSV_COLUMNS);
    // `all` on cornell, each at spp 1, 2, 4 in that order (no adaptive=on: with at most 4
    // spp no pixel could stop early).
    let labels = CORNELL_ALL;
    assert_eq!(rows.len(), 3 * labels.len());
    for (i, row) in rows.iter().enumerate() {
        assert_eq!(row["technique"], labels[i / 3]);
        assert_eq!(row["spp"], ["1", "2", "4"][i % 3]);
        assert_eq!(row["repeats"], "2");
        let (t, t_mean, t_max) = (
            num(row, "seconds"),
            num(row, "seconds_mean"),
            num(row, "seconds_max"),
        );
        assert!(0.0 < t && t <= t_mean && t_mean <= t_max, "{row:?}");
        let (m, m0, m1) = (num(row, "mse"), num(row, "mse_min"), num(row, "mse_max"));
        assert!(0.0 < m0 && m0 <= m && m <= m1, "{row:?}");
        // Different seeds per repeat: the two renders differ.
        assert!(m0 < m1, "repeats gave the same error: {row:?}");
        let r = num(row, "relmse");
        assert!(num(row, "relmse_min") <= r && r <= num(row, "relmse_max"));
        assert!((num(row, "rmse") - m.sqrt()).abs() <= 1e-12 * m.sqrt().max(1.0));
        let eff = num(row, "efficiency");
        assert!((eff * m * t - 1.0).abs() < 1e-9, "{row:?}");
        for c in ["bias_r", "bias_g", "bias_b"] {
            assert!(num(row, c).abs() < m1.sqrt(), "{c}: {row:?}");
        }
    }

    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("converge.json")).unwrap())
            .unwrap();
    let curves = json["curves"].as_array().unwrap();
    assert_eq!(curves.len(), labels.len());
    for (c, label) in curves.iter().zip(labels) {
        assert_eq!(c["label"], label);
        assert_eq!(c["points"].as_array().unwrap().len(), 3);
        assert!(table.contains(label), "table lacks {label}: {table}");
    }
    assert_eq!(json["reference"]["source"], "rendered");
    assert_eq!(json["reference"]["spp"], 64);
    assert!(json["reference"]["noise_mse"].as_f64().unwrap() > 0.0);
    assert_eq!(
        json["comparison"]["rows"].as_array().unwrap().len(),
        labels.len()
    );

    // The plots: a PNG that decodes to the plot size, not blank, and an SVG of that size.
    let decoder = png::Decoder::new(std::fs::File::open(out_dir.join("converge.png")).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    use risotto::tools::converge::plot::{PLOT_HEIGHT, PLOT_WIDTH};
    assert_eq!((info.width, info.height), (PLOT_WIDTH, PLOT_HEIGHT));
    let coloured = buf[..info.buffer_size()]
        .chunks(3)
        .filter(|p| p[0] != p[1] || p[1] != p[2])
        .count();
    assert!(coloured > 1000, "the PNG has no coloured curves");
    let svg = std::fs::read_to_string(out_dir.join("converge.svg")).unwrap();
    assert!(svg.starts_with("<svg"), "{}", &svg[..svg.len().min(100)]);
    assert!(svg.contains(&format!("width=\"{PLOT_WIDTH}\"")));
    assert!(svg.contains(&format!("height=\"{PLOT_HEIGHT}\"")));
    for label in labels {
        assert!(svg.contains(label), "SVG legend lacks {label}");
    }
}

/// `--metric relmse` compares the techniques by the relMSE: the efficiency column is
/// `1 / (relMSE x seconds)`, the table and the JSON say which metric, and both errors are in
/// the CSV still. A wrong name is an error naming it.
#[test]
fn the_relmse_metric_is_what_the_sweep_compares_by() {
    let dir = scratch_dir("converge", "relmse");
    let scene = cornell(&dir, 16);
    let out_dir = dir.join("out");
    let args = [
        "--spp",
        "1,2",
        "--reference-spp",
        "16",
        "--techniques",
        "lighting=mis",
        "--metric",
        "relmse",
    ];
    let out = converge(&scene, &out_dir, &args);
    assert_ok("converge", &out);
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(table.contains("1/(relMSE*s)"), "{table}");
    assert!(table.contains("equal error: relMSE"), "{table}");
    let (_, rows) = csv_rows(&out_dir);
    assert_eq!(rows.len(), 2);
    for row in &rows {
        let (r, m, t) = (num(row, "relmse"), num(row, "mse"), num(row, "seconds"));
        assert!(r > 0.0 && m > 0.0 && (r / m - 1.0).abs() > 0.01, "{row:?}");
        let eff = num(row, "efficiency");
        assert!((eff * r * t - 1.0).abs() < 1e-9, "{row:?}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("converge.json")).unwrap())
            .unwrap();
    assert_eq!(json["metric"], "relmse");
    let bad = converge(
        &scene,
        &dir.join("bad"),
        &["--spp", "1", "--metric", "rmse"],
    );
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("\"rmse\" is not mse or relmse"), "{err}");
}

#[test]
fn mse_falls_with_spp_and_sobol_beats_the_independent_sampler() {
    // MIS at 1 and 16 spp: Monte Carlo divides the MSE by about 16 (Sobol by more), so
    // a factor 4 is a robust bound. The independent sampler's RMSE falls as spp^-1/2.
    // At 16 spp on the diffuse cornell box, stratification must show: independent's MSE
    // is well above Sobol's (about 5x at 256x256).
    let dir = scratch_dir("converge", "falls");
    let scene = cornell(&dir, 24);
    let out_dir = dir.join("out");
    let out = converge(
        &scene,
        &out_dir,
        &[
            "--techniques",
            "lighting=mis,sampler=independent",
            "--spp",
            "1,4,16",
            "--reference-spp",
            "4096",
            "--repeats",
            "2",
        ],
    );
    assert_ok("converge", &out);
    let (_, rows) = csv_rows(&out_dir);
    let mis = "lighting=mis+sampler=sobol";
    let (m1, m16) = (mse(&rows, mis, 1), mse(&rows, mis, 16));
    assert!(m16 < m1 / 4.0, "MIS: MSE {m1} at 1 spp, {m16} at 16 spp");
    let ind = "sampler=independent";
    let (i16, s16) = (mse(&rows, ind, 16), mse(&rows, mis, 16));
    assert!(
        i16 > 1.5 * s16,
        "16 spp: independent MSE {i16}, Sobol {s16}"
    );
}

#[test]
fn independent_sampler_rmse_falls_as_the_inverse_square_root_of_spp() {
    // Monte Carlo: RMSE ~ spp^-1/2. The camera looks down so that the light is out of view:
    // at low spp a visible emitter's edge pixels are hit or missed as a whole (errors of
    // 17 in a pixel), a heavy tail that makes a few repeats' MSE erratic.
    let dir = scratch_dir("converge", "slope");
    let scene = cornell(&dir, 24);
    let text = std::fs::read_to_string(&scene).unwrap();
    assert!(
        text.contains("to = [0, 0, 0]"),
        "test bug: cornell's camera target"
    );
    std::fs::write(
        &scene,
        text.replacen("to = [0, 0, 0]", "to = [0, -0.6, 0]", 1),
    )
    .unwrap();
    let out_dir = dir.join("out");
    let out = converge(
        &scene,
        &out_dir,
        &[
            "--techniques",
            "sampler=independent",
            "--spp",
            "1,4,16,64",
            "--reference-spp",
            "4096",
            "--repeats",
            "2",
        ],
    );
    assert_ok("converge", &out);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("converge.json")).unwrap())
            .unwrap();
    let slope = json["curves"][0]["rmse_spp_slope"].as_f64().unwrap();
    assert!(
        (-0.65..=-0.35).contains(&slope),
        "independent sampler: RMSE ~ spp^{slope}, expected -0.5"
    );
}

#[test]
fn error_against_the_render_itself_is_zero() {
    // The sweep's first repeat uses the scene's seed, as `render` does, so a reference that
    // is `render`'s output at the same spp gives exactly zero error (and the independent
    // sampler, a different image, does not).
    let dir = scratch_dir("converge", "itself");
    let scene = cornell(&dir, 16);
    let exr = dir.join("ref.exr");
    let out = risotto(&[
        "render",
        scene.to_str().unwrap(),
        "--spp",
        "4",
        "--out",
        exr.to_str().unwrap(),
        "--quiet",
    ]);
    assert_ok("render", &out);
    let out_dir = dir.join("out");
    let out = converge(
        &scene,
        &out_dir,
        &[
            "--reference",
            exr.to_str().unwrap(),
            "--spp",
            "4",
            "--techniques",
            "lighting=mis,sampler=independent",
        ],
    );
    assert_ok("converge", &out);
    let (_, rows) = csv_rows(&out_dir);
    assert_eq!(rows.len(), 2);
    for col in ["mse", "relmse", "bias_r", "bias_g", "bias_b"] {
        assert_eq!(num(&rows[0], col), 0.0, "{col}: {:?}", rows[0]);
    }
    assert!(num(&rows[1], "relmse") > 0.0, "{:?}", rows[1]);
}

/// The technique names `risotto techniques` lists (its unindented lines).
fn listed(scene: &Path) -> Vec<String> {
    let out = risotto(&["techniques", scene.to_str().unwrap()]);
    assert_ok("techniques", &out);
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| !l.starts_with(' '))
        .map(|l| l.split(':').next().unwrap().to_string())
        .collect()
}

#[test]
fn techniques_lists_only_what_applies() {
    let dir = scratch_dir("converge", "listing");
    let scene = cornell(&dir, 16);
    // Cornell has no volumes: the integrator, lighting, sampler and visible emitters
    // (its light is two triangles), nothing else, and converge's adaptive sampling (the
    // path tracer renders it).
    assert_eq!(
        listed(&scene),
        [
            "integrator",
            "lighting",
            "sampler",
            "visible_emitters",
            "adaptive"
        ]
    );
    let out = risotto(&["techniques", scene.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    for v in [
        "lighting=mis",
        "lighting=nee",
        "lighting=bxdf",
        "sampler=sobol",
        "sampler=independent",
        "integrator=path",
        "integrator=bdpt",
        "integrator=vcm",
        "adaptive=off",
        "adaptive=on",
        "visible_emitters=supersampled",
        "visible_emitters=paths",
    ] {
        assert!(text.contains(v), "listing lacks {v}: {text}");
    }
    // Without any light the lighting technique changes nothing and is not listed.
    let text = std::fs::read_to_string(&scene).unwrap();
    let name = text.find("name = \"light\"").expect("cornell's light");
    let start = text[..name].rfind("[[shapes]]").unwrap();
    let end = start + text[start..].find("\n\n").unwrap_or(text.len() - start);
    let dark = dir.join("dark.toml");
    std::fs::write(&dark, format!("{}{}", &text[..start], &text[end..])).unwrap();
    assert_eq!(listed(&dark), ["sampler", "adaptive"]);
    let out = risotto(&[
        "render",
        dark.to_str().unwrap(),
        "--technique",
        "lighting=nee",
        "--quiet",
        "--out",
        dir.join("dark.exr").to_str().unwrap(),
    ]);
    assert_fails(
        "lighting in the dark",
        &out,
        &["lighting=nee", "does not apply"],
    );
}

#[test]
fn technique_flag_selects_and_lighting_stays_its_alias() {
    let dir = scratch_dir("converge", "flag");
    let scene = cornell(&dir, 16);
    let render = |name: &str, extra: &[&str]| {
        let exr = dir.join(name);
        let mut args = vec![
            "render",
            scene.to_str().unwrap(),
            "--spp",
            "4",
            "--quiet",
            "--out",
            exr.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        assert_ok(name, &risotto(&args));
        std::fs::read(exr).unwrap()
    };
    let default = render("default.exr", &[]);
    let alias = render("alias.exr", &["--lighting", "nee"]);
    let flag = render("flag.exr", &["--technique", "lighting=nee"]);
    assert_eq!(
        alias, flag,
        "--lighting nee differs from --technique lighting=nee"
    );
    assert_ne!(alias, default);
    let independent = render("ind.exr", &["--technique", "sampler=independent"]);
    assert_ne!(independent, default);
    let explicit = render("sobol.exr", &["--technique", "sampler=sobol"]);
    assert_eq!(explicit, default);
}

#[test]
fn bad_techniques_and_references_are_named_in_the_error() {
    let dir = scratch_dir("converge", "bad");
    let scene = cornell(&dir, 16);
    let s = scene.to_str().unwrap();
    let out_dir = dir.join("out");
    let o = out_dir.to_str().unwrap();
    let exr = dir.join("x.exr");
    let e = exr.to_str().unwrap();
    assert_fails(
        "unknown technique",
        &risotto(&["render", s, "--technique", "shading=fast", "--out", e]),
        &[
            "shading",
            "known in this scene: integrator, lighting, sampler",
        ],
    );
    assert_fails(
        "bad value",
        &risotto(&["render", s, "--technique", "sampler=halton", "--out", e]),
        &["halton", "sobol, independent"],
    );
    assert_fails(
        "bad --lighting",
        &risotto(&["render", s, "--lighting", "path", "--out", e]),
        &["path", "mis, nee, bxdf"],
    );
    assert_fails(
        "conflict",
        &risotto(&[
            "render",
            s,
            "--lighting",
            "nee",
            "--technique",
            "lighting=mis",
            "--out",
            e,
        ]),
        &["lighting=mis", "already set to nee"],
    );
    assert_fails(
        "malformed",
        &risotto(&["converge", s, "--techniques", "lighting", "--out", o]),
        &["\"lighting\"", "NAME=VALUE"],
    );
    assert_fails(
        "converge bad value",
        &risotto(&[
            "converge",
            s,
            "--techniques",
            "lighting=nee,sampler=grid",
            "--out",
            o,
        ]),
        &["grid", "sampler"],
    );
    assert_fails(
        "bad spp",
        &risotto(&["converge", s, "--spp", "1,x", "--out", o]),
        &["--spp 1,x", "\"x\""],
    );
    // A reference of the wrong size: render one at 8x8.
    let small = cornell(&dir, 8);
    assert_ok(
        "small render",
        &risotto(&[
            "render",
            small.to_str().unwrap(),
            "--spp",
            "1",
            "--quiet",
            "--out",
            e,
        ]),
    );
    assert_fails(
        "reference size",
        &risotto(&[
            "converge",
            s,
            "--reference",
            e,
            "--spp",
            "1",
            "--out",
            o,
            "--quiet",
        ]),
        &[e, "8x8", "16x16"],
    );
    assert_fails(
        "missing reference",
        &risotto(&["converge", s, "--reference", "/nonexistent.exr", "--out", o]),
        &["/nonexistent.exr"],
    );
    // Every render's image is kept until the sweep ends: 4294967295 repeats would grow
    // memory without bound (before, the sweep started and never ended). Refused before
    // anything is rendered, naming the numbers.
    assert_fails(
        "memory of the kept images",
        &risotto(&[
            "converge",
            s,
            "--repeats",
            "4294967295",
            "--spp",
            "1,2",
            "--out",
            o,
            "--quiet",
        ]),
        &["--repeats 4294967295", "2 spp counts", "16x16", "GiB"],
    );
    assert!(
        !out_dir.join("converge.csv").exists(),
        "the refused sweep wrote a CSV"
    );
}

#[test]
fn a_time_budget_doubles_spp_until_a_render_takes_that_long() {
    let dir = scratch_dir("converge", "budget");
    let scene = cornell(&dir, 16);
    let out_dir = dir.join("out");
    let budget = 0.004;
    let out = converge(
        &scene,
        &out_dir,
        &[
            "--budget",
            &budget.to_string(),
            "--techniques",
            "lighting=mis,lighting=bxdf",
            "--reference-spp",
            "256",
        ],
    );
    assert_ok("converge --budget", &out);
    let (_, rows) = csv_rows(&out_dir);
    for label in ["lighting=mis+sampler=sobol", "lighting=bxdf"] {
        let curve: Vec<_> = rows.iter().filter(|r| r["technique"] == label).collect();
        assert!(!curve.is_empty(), "{label}: no rows");
        for (i, r) in curve.iter().enumerate() {
            assert_eq!(num(r, "spp"), (1u64 << i) as f64, "{label}: {r:?}");
            let last = i + 1 == curve.len();
            assert_eq!(num(r, "seconds") >= budget, last, "{label} row {i}: {r:?}");
        }
    }
}

#[test]
fn a_rendered_reference_uses_the_most_efficient_converging_technique() {
    // Neither swept variant is the default (mis + sobol), and Bxdf sampling alone is an
    // order of magnitude less efficient than light sampling on the cornell box's small
    // light: judged from two seeds, without a reference, the reference must be rendered
    // with `lighting=nee`. One repeat, so the second image is the extra render.
    let dir = scratch_dir("converge", "reference-choice");
    let scene = cornell(&dir, 24);
    let out = converge(
        &scene,
        &dir,
        &[
            "--reference-spp",
            "64",
            "--spp",
            "4,16",
            "--techniques",
            "lighting=bxdf,lighting=nee",
        ],
    );
    assert_ok("converge", &out);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("converge.json")).unwrap()).unwrap();
    assert_eq!(json["reference"]["techniques"], "lighting=nee", "{json:#}");
    // An approximation is never chosen, however fast: single scattering only.
    let smoke = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/mitsuba-suite/smoke_homog.toml");
    let text = std::fs::read_to_string(&smoke)
        .unwrap()
        .replacen("width = 256", "width = 12", 1)
        .replacen("height = 256", "height = 12", 1);
    let small = dir.join("smoke-12.toml");
    std::fs::write(&small, text).unwrap();
    let out_dir = dir.join("smoke");
    let out = converge(
        &small,
        &out_dir,
        &[
            "--reference-spp",
            "16",
            "--spp",
            "2,8",
            "--techniques",
            "scattering=single,lighting=bxdf",
        ],
    );
    assert_ok("converge smoke", &out);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("converge.json")).unwrap())
            .unwrap();
    assert_eq!(json["reference"]["techniques"], "lighting=bxdf", "{json:#}");
}
