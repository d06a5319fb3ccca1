//! A deterministic mutation fuzzer over the shipped `scenes/*.toml` (issue 14), end to end:
//! each mutated file either fails with an error that names the file, or loads, compiles and
//! renders (shrunk to 6 x 6 pixels, 1 spp, depth <= 6) to a finite image with nothing dropped.
//! Never a panic. The parser-only fuzzer with more cases is
//! `engine/loader/src/scene_file/tests.rs::mutated_scenes_never_panic`. Both run longer, or on
//! other streams, with `RISOTTO_FUZZ_CASES` and `RISOTTO_FUZZ_SEED` (README, "Testing").

use risotto::engine::render::{render, RenderOptions};
use risotto::loader::load::{compile_scene, scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::parse_scene;
use std::path::{Path, PathBuf};

/// Deterministic choices: the SipHash (fixed keys) of a counter.
struct Rng(u64);
impl Rng {
    fn below(&mut self, n: usize) -> usize {
        use std::hash::{Hash, Hasher};
        let mut h = std::hash::DefaultHasher::new();
        self.0.hash(&mut h);
        self.0 += 1;
        (h.finish() % n.max(1) as u64) as usize
    }
}

/// Values that are valid TOML in a value position and hard for a renderer: zero, negative,
/// tiny, huge, and the limits of the types.
const VALUES: &[&str] = &[
    "0",
    "-1",
    "1e-30",
    "1e30",
    "3e38",
    "-3e38",
    "1e-45",
    "0.999999",
    "-0.999999",
    "65536",
    "4294967295",
    "[0, 0, 0]",
    "[1e30, 0, 0]",
    "[1e-30, 1e-30, 1e-30]",
    "true",
    "\"x\"",
];

/// Replaces the value of a random `key = value` line of `text` by one of [`VALUES`].
fn mutate(text: &str, rng: &mut Rng) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let assignments: Vec<usize> = (0..lines.len())
        .filter(|&i| {
            let l = lines[i].trim_start();
            !l.starts_with('#') && l.contains(" = ")
        })
        .collect();
    let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    for _ in 0..1 + rng.below(2) {
        let i = assignments[rng.below(assignments.len())];
        let (key, value) = out[i].split_once(" = ").unwrap_or((&out[i], ""));
        let (key, value) = (key.to_string(), value.to_string());
        out[i] = if rng.below(3) == 0 {
            format!("{key} = {}", VALUES[rng.below(VALUES.len())])
        } else {
            format!("{key} = {}", rescale_a_number(&value, rng))
        };
    }
    out.join("\n") + "\n"
}

/// Factors a number is multiplied by: far from 1 either way, negative, zero.
const FACTORS: &[f64] = &[1e-4, 1e-2, 0.5, 2.0, 1e2, 1e4, -1.0, 0.0];

/// `value` with one of its numbers (tokens between `[ ] { } ,` and spaces that parse as a
/// float) multiplied by one of [`FACTORS`], written as a float.
fn rescale_a_number(value: &str, rng: &mut Rng) -> String {
    let is_sep = |c: char| "[]{}, ".contains(c);
    let mut spans = Vec::new();
    let mut start = None;
    for (i, c) in value.char_indices().chain([(value.len(), ' ')]) {
        match (start, is_sep(c)) {
            (None, false) => start = Some(i),
            (Some(s), true) => {
                if value[s..i].parse::<f64>().is_ok() {
                    spans.push(s..i);
                }
                start = None;
            }
            _ => {}
        }
    }
    if spans.is_empty() {
        return value.to_string();
    }
    let span = spans[rng.below(spans.len())].clone();
    let x: f64 = value[span.clone()].parse().unwrap();
    let y = x * FACTORS[rng.below(FACTORS.len())];
    format!("{}{y:?}{}", &value[..span.start], &value[span.end..])
}

fn shipped_scenes() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 5, "{files:?}");
    files
}

/// The fuzzer's budget: `RISOTTO_FUZZ_CASES` cases (default `default`) from stream
/// `RISOTTO_FUZZ_SEED` (default 0), so anyone can run it longer or elsewhere:
/// `RISOTTO_FUZZ_CASES=100000 RISOTTO_FUZZ_SEED=7 cargo test --release ...`.
fn fuzz_budget(default: usize) -> (usize, u64) {
    let read = |name: &str| {
        std::env::var(name).ok().map(|v| {
            v.trim()
                .parse::<u64>()
                .unwrap_or_else(|_| panic!("{name}={v:?} is not a whole number"))
        })
    };
    (
        read("RISOTTO_FUZZ_CASES").map_or(default, |n| n as usize),
        read("RISOTTO_FUZZ_SEED").unwrap_or(0),
    )
}

#[test]
fn mutated_shipped_scenes_fail_located_or_render_finite() {
    let registry = MaterialRegistry::with_builtins();
    let (cases, seed) = fuzz_budget(40);
    let mut rng = Rng(0xD1B5_4A32_D192_ED03 ^ seed.wrapping_mul(0x9E37_79B9_7F4A_7C15));
    let (mut rendered, mut rejected) = (0, 0);
    for file in shipped_scenes() {
        let text = std::fs::read_to_string(&file).unwrap();
        // Parsed under the real path, so meshes and maps resolve as for the original.
        let shown = file.display().to_string();
        for case in 0..cases {
            let mutated = mutate(&text, &mut rng);
            let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                let desc = parse_scene(&mutated, &file).map_err(|e| e.to_string())?;
                let mut scene = scene_from_desc(desc, &registry).map_err(|e| e.to_string())?;
                scene.camera.width = 6;
                scene.camera.height = 6;
                scene.settings.width = 6;
                scene.settings.height = 6;
                scene.settings.spp = 1;
                scene.settings.max_depth = scene.settings.max_depth.min(6);
                let compiled = compile_scene(scene).map_err(|e| e.to_string())?;
                let options = RenderOptions {
                    threads: Some(1),
                    ..RenderOptions::default()
                };
                render(&compiled, &options, &|_| {}).map_err(|e| e.to_string())
            }));
            let what = format!("{shown} case {case}:\n{mutated}");
            match outcome {
                Err(_) => panic!("panicked on {what}"),
                Ok(Err(msg)) => {
                    rejected += 1;
                    assert!(msg.contains(&shown), "unlocated error `{msg}` for {what}");
                }
                Ok(Ok(out)) => {
                    rendered += 1;
                    assert_eq!(out.stats.counters.nan_dropped, 0, "{}\n{what}", out.stats);
                    assert!(
                        out.beauty.pixels.iter().all(|p| p.is_finite()),
                        "non-finite pixel for {what}"
                    );
                }
            }
        }
    }
    // Both outcomes must occur, or the mutator tests nothing (at the default budget, more
    // than 20 of each).
    let enough = (rendered + rejected) / 30;
    assert!(
        rendered > enough && rejected > enough,
        "rendered {rendered}, rejected {rejected}"
    );
}
