//! Partial renders and their exact merge: what lets a render run as independent farm tasks.
//!
//! A render may cover a window of the image (`--crop`) and a range of each pixel's sample
//! indices (`--samples`); pixel seeds and sample indices are those of the whole render, so a
//! cropped render's pixels are the bits of the same pixels of the whole render. Such a piece
//! is written as a **partial EXR** ([`write_partial`]) and [`merge`] puts pieces back together.
//!
//! The file format is in [`partial_exr`]; this module says what a piece is ([`Partial`]) and
//! merges pieces.
//!
//! # Merging and its summation order
//! Parts must agree on resolution, seed, spp and scene hash; parts whose windows share a
//! pixel must have disjoint sample ranges; every pixel must end up with all `0..spp`
//! samples. The sums of a pixel are added in increasing order of the parts' first sample
//! index, starting from 0: a pixel covered by one part gets that part's sums bit for bit (so
//! a tile merge is exact), a pixel covered by sample ranges `a..b`, `b..c` gets
//! `(0 + S(a..b)) + S(b..c)` where a one-process render has the sequential sum `S(a..c)`. In
//! f64 the two differ by a few ulps (relative error below 1e-15 per addition), so after the
//! conversion to f32 beauty and variance are equal or one f32 ulp apart; counts are exact.
//! The variance of the mean is recomputed from the merged sums.
//!
//! # AOVs
//! A piece rendered with `--aovs` also carries the f64 sums of first-hit albedo, normal and
//! depth ([`AovFilm`]); they are merged in the same order as the film's sums, so tiles give
//! the one-process AOV layers bit for bit and sample ranges give them up to the same f64
//! summation order: each mean is equal or one f32 ulp apart, except where a component's
//! samples cancel to nearly zero (a normal component at a silhouette): there the bound is
//! absolute, the f64 rounding of the two sums, at most about `2e-16 * spp` times the mean
//! magnitude of the pixel's samples. (The f64 sum of a few f32 values of similar size is
//! exact in any order, so in practice most pixels agree bit for bit.) Either all parts
//! carry AOVs or none does: a mix is refused.

use std::path::{Path, PathBuf};

use risotto_systems::film::{AovFilm, Film};
use serde_json::Value;

use risotto_engine::output::{Image, OutputError};
use risotto_engine::render::{aov_means, RenderOutput, SampleRange, Window};

pub mod partial_exr;
pub use partial_exr::{parse_sample_range, read_partial, write_partial};

/// Name of the EXR part with the merge data.
pub const MERGE_PART: &str = "merge";

/// What a partial render is a piece of, and which piece.
#[derive(Clone, Debug, PartialEq)]
pub struct PartialHeader {
    /// Full image size.
    pub resolution: (u32, u32),
    /// The piece's window of the full image.
    pub window: Window,
    /// The sample indices of each pixel of the window the piece holds.
    pub samples: SampleRange,
    /// Samples per pixel of the whole render.
    pub spp: u32,
    /// Sampler seed.
    pub seed: u64,
    /// [`scene_hash`] of the scene and the options that change the image.
    pub scene_hash: String,
    /// Render statistics of the piece (the JSON of `RenderStats`).
    pub stats: Value,
}

/// A partial render: its header, its film (sums and counts over the window) and, when it
/// was rendered with AOVs, their sums.
#[derive(Clone, Debug)]
pub struct Partial {
    /// What it is a piece of.
    pub header: PartialHeader,
    /// Sums and counts, `window.width() x window.height()`.
    pub film: Film,
    /// Sums of first-hit albedo, normal and depth over the same pixels and samples (their
    /// means divide by `film.count`), when the piece carries AOVs.
    pub aovs: Option<AovFilm>,
}

/// Errors of reading, checking and merging partial renders.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// A file could not be read or written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// A file is not a partial render.
    #[error("{path}: not a risotto partial render: {reason}")]
    NotPartial {
        /// The file.
        path: PathBuf,
        /// What is missing or malformed.
        reason: String,
    },
    /// The parts do not fit together.
    #[error("cannot merge: {0}")]
    Refused(String),
}

/// The scene hash of partial renders: 64-bit FNV-1a over `pieces` (each followed by a
/// 0xff separator byte, which UTF-8 text never contains), as 16 hex digits. The driver
/// hashes the scene file's bytes, the effective settings and techniques that change
/// the image (the seed and spp are checked on their own), and the path and bytes of every
/// file the scene reads ([`CompiledScene::files`](risotto_engine::scene::CompiledScene::files):
/// meshes, grids, environment maps).
pub fn scene_hash(pieces: &[&[u8]]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for piece in pieces {
        for &b in piece.iter().chain(&[0xff]) {
            h ^= b as u64;
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    format!("{h:016x}")
}

impl Partial {
    /// The partial of a render's output: `resolution`, `spp`, `seed` and `scene_hash` say
    /// what it is a piece of; with `aovs` it carries the output's AOV sums (when the render
    /// kept them: `RenderOptions::aovs`).
    pub fn of_render(
        out: &RenderOutput,
        resolution: (u32, u32),
        spp: u32,
        seed: u64,
        scene_hash: String,
        aovs: bool,
    ) -> Self {
        Partial {
            header: PartialHeader {
                resolution,
                window: out.window,
                samples: out.samples,
                spp,
                seed,
                scene_hash,
                stats: serde_json::from_str(&out.stats.to_json()).unwrap_or(Value::Null),
            },
            film: out.film.clone(),
            aovs: (aovs && out.aovs.holds_sums()).then(|| out.aovs.clone()),
        }
    }

    /// The AOV layers a render writes (mean albedo, mean normal, mean depth: see
    /// [`aov_means`]), when the piece carries AOVs.
    pub fn aov_layers(&self) -> Option<(Image, Image, Vec<f32>)> {
        self.aovs.as_ref().map(|a| aov_means(a, &self.film.count))
    }

    /// Mean radiance per pixel of the window.
    pub fn beauty(&self) -> Image {
        let f = &self.film;
        let n = f.count.len();
        Image::from_pixels(
            f.width as usize,
            f.height as usize,
            (0..n).map(|i| f.mean(i)).collect(),
        )
    }
}

/// Adds stats JSON `b` into `a`: numbers add, objects merge key by key, arrays gain the
/// items they lack (features, warnings), anything else keeps `a`'s value.
fn add_stats(a: &mut Value, b: &Value) {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let sum = match (x.as_u64(), y.as_u64()) {
                (Some(p), Some(q)) => Value::from(p.saturating_add(q)),
                _ => Value::from(x.as_f64().unwrap_or(0.0) + y.as_f64().unwrap_or(0.0)),
            };
            *x = match sum {
                Value::Number(n) => n,
                _ => x.clone(),
            };
        }
        (Value::Object(x), Value::Object(y)) => {
            for (k, v) in y {
                match x.get_mut(k) {
                    Some(mine) => add_stats(mine, v),
                    None => {
                        x.insert(k.clone(), v.clone());
                    }
                }
            }
        }
        (Value::Array(x), Value::Array(y)) => {
            for v in y {
                if !x.contains(v) {
                    x.push(v.clone());
                }
            }
        }
        (a @ Value::Null, b) => *a = b.clone(),
        _ => {}
    }
}

/// The parts' non-finite cases (their arrays concatenated) cut to what one render keeps: one
/// per camera sample (the shallowest, then the earliest stage), the
/// [`MAX_NON_FINITE_CASES`](risotto_engine::stats::MAX_NON_FINITE_CASES) smallest (pixel, sample)
/// first.
fn keep_first_cases(cases: &mut Vec<Value>) {
    let num = |c: &Value, k: &str| c.get(k).and_then(Value::as_u64).unwrap_or(u64::MAX);
    let stage = |c: &Value| {
        let name = c.get("stage").and_then(Value::as_str).unwrap_or("");
        risotto_engine::stats::Stage::ALL
            .iter()
            .position(|s| s.name() == name)
            .unwrap_or(usize::MAX)
    };
    let key = |c: &Value| (num(c, "y"), num(c, "x"), num(c, "sample"));
    let rank = |c: &Value| (num(c, "depth"), stage(c));
    cases.sort_by(|a, b| key(a).cmp(&key(b)).then(rank(a).cmp(&rank(b))));
    cases.dedup_by(|later, first| key(later) == key(first));
    cases.truncate(risotto_engine::stats::MAX_NON_FINITE_CASES);
}

/// Merges partial renders (each with the file it came from, for messages) into the whole
/// render: checks that they fit (module docs; all carry AOVs or none does), places tiles
/// and adds sample passes (and their AOV sums) in the stated order. The result is a
/// partial covering the whole image and `0..spp`; its stats are the parts' summed
/// (`wall_seconds` is then the total task time) with `"parts"`, the number of parts.
pub fn merge(parts: &[(PathBuf, Partial)]) -> Result<Partial, MergeError> {
    let refuse = |m: String| Err(MergeError::Refused(m));
    let Some((first_path, first)) = parts.first() else {
        return refuse("no parts given".into());
    };
    let f = &first.header;
    let name = |p: &Path| p.display().to_string();
    for (path, part) in &parts[1..] {
        let h = &part.header;
        let (a, b) = (name(first_path), name(path));
        if h.resolution != f.resolution {
            return refuse(format!(
                "{b} is a piece of a {}x{} image, {a} of a {}x{} image",
                h.resolution.0, h.resolution.1, f.resolution.0, f.resolution.1
            ));
        }
        if h.seed != f.seed {
            return refuse(format!(
                "{b} was rendered with seed {}, {a} with seed {}",
                h.seed, f.seed
            ));
        }
        if h.spp != f.spp {
            return refuse(format!(
                "{b} is a piece of a {} spp render, {a} of a {} spp render",
                h.spp, f.spp
            ));
        }
        if h.scene_hash != f.scene_hash {
            return refuse(format!(
                "{b} has scene hash {}, {a} has {}: they were rendered from different scenes \
                 or with different options",
                h.scene_hash, f.scene_hash
            ));
        }
    }
    let (with, without): (Vec<_>, Vec<_>) = parts.iter().partition(|(_, p)| p.aovs.is_some());
    if !with.is_empty() && !without.is_empty() {
        let list = |v: &[&(PathBuf, Partial)]| {
            let mut names: Vec<String> = v.iter().take(4).map(|(p, _)| name(p)).collect();
            if v.len() > 4 {
                names.push(format!("and {} more", v.len() - 4));
            }
            names.join(", ")
        };
        let verb = |n: usize| if n == 1 { "does" } else { "do" };
        return refuse(format!(
            "some parts carry AOVs and some do not: {} {} (rendered with --aovs), {} {} not; \
             render every part with --aovs, or none",
            list(&with),
            if with.len() == 1 {
                "carries them"
            } else {
                "carry them"
            },
            list(&without),
            verb(without.len())
        ));
    }
    for (i, (pa, a)) in parts.iter().enumerate() {
        for (pb, b) in &parts[i + 1..] {
            let (ha, hb) = (&a.header, &b.header);
            let Some(common) = ha.window.intersection(&hb.window) else {
                continue;
            };
            if ha.samples.overlaps(&hb.samples) {
                let what = if ha.samples == hb.samples {
                    format!("overlapping tiles: both hold pixels {common}")
                } else {
                    format!(
                        "overlapping sample ranges: {} and {} share samples on pixels {common}",
                        ha.samples, hb.samples
                    )
                };
                return refuse(format!("{} and {}: {what}", name(pa), name(pb)));
            }
        }
    }
    let (w, h) = f.resolution;
    let full = Window::full(w, h);
    // Coverage: samples per pixel the parts hold (disjoint, as checked above).
    let mut covered = vec![0u64; full.pixels()];
    for (_, p) in parts {
        let win = p.header.window;
        for y in win.y0..win.y1 {
            for x in win.x0..win.x1 {
                covered[(y * w + x) as usize] += p.header.samples.len() as u64;
            }
        }
    }
    let mut missing: Option<(Window, (u32, u32))> = None;
    for y in 0..h {
        for x in 0..w {
            if covered[(y * w + x) as usize] != f.spp as u64 {
                missing = Some(match missing {
                    None => (
                        Window {
                            x0: x,
                            y0: y,
                            x1: x + 1,
                            y1: y + 1,
                        },
                        (x, y),
                    ),
                    Some((b, first)) => (
                        Window {
                            x0: b.x0.min(x),
                            y0: b.y0.min(y),
                            x1: b.x1.max(x + 1),
                            y1: b.y1.max(y + 1),
                        },
                        first,
                    ),
                });
            }
        }
    }
    if let Some((bounds, (x, y))) = missing {
        let have: Vec<String> = parts
            .iter()
            .filter(|(_, p)| {
                let win = p.header.window;
                (win.x0..win.x1).contains(&x) && (win.y0..win.y1).contains(&y)
            })
            .map(|(path, p)| format!("{} from {}", p.header.samples, name(path)))
            .collect();
        let have = if have.is_empty() {
            "no part".to_string()
        } else {
            have.join(", ")
        };
        return refuse(format!(
            "missing coverage: pixels {bounds} do not have all samples 0..{} (pixel ({x}, {y}) \
             has {have}); a tile or a sample range is missing",
            f.spp
        ));
    }
    // Summation order: by first sample index, then window (top to bottom, left to right).
    let mut order: Vec<&Partial> = parts.iter().map(|(_, p)| p).collect();
    order.sort_by_key(|p| {
        (
            p.header.samples.start,
            p.header.window.y0,
            p.header.window.x0,
        )
    });
    let mut film = Film::new(w, h);
    let mut aovs = first.aovs.is_some().then(|| AovFilm::new(w, h));
    let mut stats = Value::Null;
    for p in &order {
        let (x0, y0) = (p.header.window.x0, p.header.window.y0);
        film.add_tile(&p.film, x0, y0);
        if let (Some(sum), Some(part)) = (&mut aovs, &p.aovs) {
            sum.add_tile(part, x0, y0);
        }
        add_stats(&mut stats, &p.header.stats);
    }
    if let Value::Object(m) = &mut stats {
        m.insert("parts".into(), Value::from(parts.len()));
        if let Some(Value::Array(cases)) = m.get_mut("non_finite_cases") {
            keep_first_cases(cases);
        }
    }
    Ok(Partial {
        header: PartialHeader {
            resolution: f.resolution,
            window: full,
            samples: SampleRange {
                start: 0,
                end: f.spp,
            },
            spp: f.spp,
            seed: f.seed,
            scene_hash: f.scene_hash.clone(),
            stats,
        },
        film,
        aovs,
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A piece with made-up sums: `value` in the red sums, tiny and zero others.
    pub(crate) fn part(window: Window, samples: SampleRange, value: f64) -> Partial {
        let mut film = Film::new(window.width(), window.height());
        for (i, s) in film.sum.iter_mut().enumerate() {
            *s = [value + i as f64 / 3.0, 0.1, 1e-300];
        }
        for s in film.sum_sq.iter_mut() {
            *s = [value * value, 0.01, 0.0];
        }
        film.count.fill(samples.len());
        Partial {
            header: PartialHeader {
                resolution: (4, 2),
                window,
                samples,
                spp: 8,
                seed: 3,
                scene_hash: scene_hash(&[b"scene"]),
                stats: serde_json::json!({"samples": 1, "wall_seconds": 0.5, "features": ["a"]}),
            },
            film,
            aovs: None,
        }
    }

    /// [`part`] with made-up AOV sums: `value` in every albedo sum, bit patterns that an
    /// f32 would not keep in the normal and depth sums.
    pub(crate) fn part_with_aovs(window: Window, samples: SampleRange, value: f64) -> Partial {
        let mut p = part(window, samples, value);
        let mut a = AovFilm::new(window.width(), window.height());
        for (i, s) in a.albedo.iter_mut().enumerate() {
            *s = [value, 0.25 * i as f64, 0.0];
        }
        for (i, s) in a.normal.iter_mut().enumerate() {
            *s = [1.0 / 3.0, -(i as f64) / 7.0, -0.0];
        }
        for (i, d) in a.depth.iter_mut().enumerate() {
            *d = value * 1e10 + i as f64 / 9.0;
        }
        p.aovs = Some(a);
        p
    }

    #[test]
    fn stats_add_up() {
        let mut a = serde_json::json!({"n": 1, "t": 0.5, "f": ["x"], "o": {"k": 2}});
        add_stats(
            &mut a,
            &serde_json::json!({"n": 2, "t": 0.25, "f": ["x", "y"], "o": {"k": 3, "j": 1}}),
        );
        assert_eq!(
            a,
            serde_json::json!({"n": 3, "t": 0.75, "f": ["x", "y"], "o": {"k": 5, "j": 1}})
        );
    }

    #[test]
    fn merged_non_finite_cases_are_those_one_render_keeps() {
        let case = |x: u32, y: u32, sample: u32, depth: u32, stage: &str| serde_json::json!({"x": x, "y": y, "sample": sample, "depth": depth, "stage": stage});
        let mut cases = vec![case(3, 1, 0, 2, "transmission"), case(3, 1, 0, 2, "bxdf")];
        cases.extend((0..10).map(|i| case(9 - i, 0, 1, 0, "volume")));
        keep_first_cases(&mut cases);
        assert_eq!(cases.len(), risotto_engine::stats::MAX_NON_FINITE_CASES);
        assert_eq!(cases[0], case(0, 0, 1, 0, "volume"));
        // Row 1 comes after every pixel of row 0 kept; one case per camera sample.
        assert!(cases.iter().all(|c| c["y"] == 0));
        let mut two = vec![case(3, 1, 0, 2, "transmission"), case(3, 1, 0, 2, "bxdf")];
        keep_first_cases(&mut two);
        assert_eq!(two, vec![case(3, 1, 0, 2, "bxdf")]);
    }

    #[test]
    fn merge_adds_in_sample_order_whatever_the_argument_order() {
        let full = Window::full(4, 2);
        let a = part(full, SampleRange { start: 0, end: 3 }, 0.1);
        let b = part(full, SampleRange { start: 3, end: 8 }, 1e17);
        let ab = merge(&[("a".into(), a.clone()), ("b".into(), b.clone())]).unwrap();
        let ba = merge(&[("b".into(), b.clone()), ("a".into(), a.clone())]).unwrap();
        assert_eq!(ab.film.sum, ba.film.sum);
        assert_eq!(
            ab.film.sum[0][0],
            (0.0 + a.film.sum[0][0]) + b.film.sum[0][0]
        );
        assert_eq!(ab.film.count, vec![8; 8]);
        assert_eq!(ab.header.stats["samples"], 2);
        assert_eq!(ab.header.stats["parts"], 2);
    }

    #[test]
    fn aov_sums_merge_in_sample_order_and_mixed_parts_are_refused() {
        let full = Window::full(4, 2);
        let a = part_with_aovs(full, SampleRange { start: 0, end: 3 }, 0.1);
        let b = part_with_aovs(full, SampleRange { start: 3, end: 8 }, 1e7);
        let ba = merge(&[("b".into(), b.clone()), ("a".into(), a.clone())]).unwrap();
        let (sa, sb, m) = (
            a.aovs.as_ref().unwrap(),
            b.aovs.as_ref().unwrap(),
            ba.aovs.as_ref().unwrap(),
        );
        for i in 0..8 {
            assert_eq!(m.depth[i], (0.0 + sa.depth[i]) + sb.depth[i]);
            for c in 0..3 {
                assert_eq!(m.albedo[i][c], (0.0 + sa.albedo[i][c]) + sb.albedo[i][c]);
                assert_eq!(m.normal[i][c], (0.0 + sa.normal[i][c]) + sb.normal[i][c]);
            }
        }
        let (albedo, _, depth) = ba.aov_layers().unwrap();
        assert_eq!(albedo.get(0, 0).r, ((0.1 + 1e7) / 8.0) as f32);
        assert_eq!(depth[0], (m.depth[0] / 8.0) as f32);
        // Half of a render with AOVs and half without do not make a render with AOVs.
        let plain = part(full, SampleRange { start: 3, end: 8 }, 1e7);
        let err = merge(&[("with.exr".into(), a), ("plain.exr".into(), plain)]).unwrap_err();
        let msg = err.to_string();
        for needle in ["with.exr carries them", "plain.exr does not", "--aovs"] {
            assert!(msg.contains(needle), "{msg}");
        }
    }
}
