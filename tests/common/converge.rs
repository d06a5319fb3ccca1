//! Helpers of the tests that run `risotto converge`: small scenes, the command, and its CSV.

use super::cli::risotto;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Output;

/// The uniform curves of `converge --techniques all` on [`cornell`], in order: the
/// defaults, the light tracer, bdpt and vcm, lighting nee and bxdf, the independent
/// sampler (`all` adds `adaptive=on` after them where the spp list lets pixels stop early).
pub const CORNELL_ALL: [&str; 8] = [
    "lighting=mis+sampler=sobol",
    "integrator=light",
    "integrator=bdpt",
    "integrator=vcm",
    "lighting=nee",
    "lighting=bxdf",
    "sampler=independent",
    "visible_emitters=paths",
];

/// The cornell box of the Mitsuba suite at `size` x `size` pixels.
pub fn cornell(dir: &Path, size: u32) -> PathBuf {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/mitsuba-suite/cornell.toml"),
    )
    .unwrap();
    for key in ["width = 256", "height = 256"] {
        assert!(text.contains(key), "test bug: {key} not in cornell.toml");
    }
    let text = text
        .replacen("width = 256", &format!("width = {size}"), 1)
        .replacen("height = 256", &format!("height = {size}"), 1);
    let path = dir.join(format!("cornell-{size}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// Fails with the command's stderr unless it succeeded.
pub fn assert_ok(what: &str, out: &Output) {
    assert!(
        out.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Runs `risotto converge SCENE --out DIR --quiet ARGS`.
pub fn converge(scene: &Path, dir: &Path, args: &[&str]) -> Output {
    let mut all = vec![
        "converge",
        scene.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--quiet",
    ];
    all.extend_from_slice(args);
    risotto(&all)
}

/// The rows of `converge.csv` as column name -> text maps.
pub fn csv_rows(dir: &Path) -> (Vec<String>, Vec<BTreeMap<String, String>>) {
    let text = std::fs::read_to_string(dir.join("converge.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            assert_eq!(cells.len(), header.len(), "row {l}");
            header
                .iter()
                .cloned()
                .zip(cells.iter().map(|c| c.to_string()))
                .collect()
        })
        .collect();
    (header, rows)
}

pub fn num(row: &BTreeMap<String, String>, col: &str) -> f64 {
    row[col]
        .parse()
        .unwrap_or_else(|_| panic!("{col}: {}", row[col]))
}
