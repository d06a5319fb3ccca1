//! The partial EXR: how a [`Partial`] is written to and read from a file, bit-exactly.
//!
//! # Layout
//! The two parts of [`write_exr`](risotto_engine::output::write_exr) (`beauty`, `aovs`: beauty,
//! variance and sample count of the piece, and its albedo, normal and depth layers when it
//! carries AOVs, so it can be viewed as it is) plus a third part, `merge`, with what merging
//! needs:
//!
//! - **windows**: the display window is the full image (`0,0` to `width-1,height-1`), the data
//!   window of every part is the piece's window in it;
//! - **channels** (all `UINT`, ZIP, lossless): `sum.R.hi`, `sum.R.lo`, ... `sumSq.B.lo`: the
//!   film's per-pixel f64 sums of sample radiance and of its square, each f64 stored
//!   bit-exactly as its upper (`.hi`) and lower (`.lo`) 32 bits, because EXR has no 64-bit
//!   float and an f32 sum would lose the bits that make the merge exact; `count`: samples
//!   per pixel; and, for a piece rendered with `--aovs` (an [`AovFilm`]), the f64 sums of
//!   first-hit albedo, normal and depth the same way: `albedoSum.R.hi` ... `albedoSum.B.lo`, `normalSum.X.hi` ...
//!   `normalSum.Z.lo`, `depthSum.Z.hi`, `depthSum.Z.lo` (all of them or none; their means
//!   divide by `count`);
//! - **text attributes**: `risotto.samples` (`START..END`), `risotto.spp`, `risotto.seed`,
//!   `risotto.sceneHash` ([`scene_hash`](super::scene_hash)), `risotto.stats` (the piece's
//!   stats JSON) and `risotto.encoding` (the channel encoding above, in words).

use std::path::Path;

use exr::prelude as x;
use risotto_systems::film::{AovFilm, Film};
use serde_json::Value;

use super::{MergeError, Partial, PartialHeader, MERGE_PART};
use risotto_engine::output::{
    exr_part_names, read_exr_all, write_exr_placed, ExtraPart, FilmOutput, Image, Placement,
};
use risotto_engine::render::{SampleRange, Window, MAX_FILM_PIXELS};

const SAMPLES: &str = "risotto.samples";
const SPP: &str = "risotto.spp";
const SEED: &str = "risotto.seed";
const SCENE_HASH: &str = "risotto.sceneHash";
const STATS: &str = "risotto.stats";
const ENCODING: &str = "risotto.encoding";
const ENCODING_TEXT: &str = "sum.C, sumSq.C (C = R, G, B): per-pixel f64 sums of sample \
    radiance and of its square, each f64's bits split into two UINT channels (.hi = upper 32 \
    bits, .lo = lower 32 bits); count: samples per pixel; albedoSum.C (C = R, G, B), \
    normalSum.C (C = X, Y, Z), depthSum.Z, present only with AOVs: per-pixel f64 sums of \
    first-hit albedo, shading normal and distance, split the same way, whose means divide \
    by count";
const CHANNELS: [char; 3] = ['R', 'G', 'B'];
/// The AOV sums' channel prefixes and per-component suffixes in the `merge` part.
const ALBEDO_SUM: (&str, [char; 3]) = ("albedoSum", ['R', 'G', 'B']);
const NORMAL_SUM: (&str, [char; 3]) = ("normalSum", ['X', 'Y', 'Z']);
const DEPTH_SUM: &str = "depthSum.Z";

/// Appends the two UINT channels `NAME.hi`, `NAME.lo` holding the bits of `values`.
fn push_f64(
    channels: &mut Vec<x::AnyChannel<x::FlatSamples>>,
    name: &str,
    values: impl Iterator<Item = f64>,
) {
    let bits: Vec<u64> = values.map(f64::to_bits).collect();
    for (half, shift) in [("hi", 32), ("lo", 0)] {
        let words = bits.iter().map(|b| (b >> shift) as u32).collect();
        channels.push(x::AnyChannel::new(
            format!("{name}.{half}").as_str(),
            x::FlatSamples::U32(words),
        ));
    }
}
/// JSON text with every non-ASCII character escaped (`\uXXXX`), as EXR text attributes
/// hold Latin-1 only.
fn ascii_json(v: &Value) -> String {
    let s = v.to_string();
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        if c.is_ascii() {
            out.push(c);
        } else {
            let mut buf = [0u16; 2];
            for u in c.encode_utf16(&mut buf) {
                out.push_str(&format!("\\u{u:04x}"));
            }
        }
    }
    out
}

/// Writes `partial` as a partial EXR (layout in the module docs), atomically: into a
/// temporary file beside `path`, then renamed over it, so a reader (or a render killed
/// mid-write) never sees half a file.
pub fn write_partial(path: &Path, partial: &Partial) -> Result<(), MergeError> {
    let f = &partial.film;
    let h = &partial.header;
    let (w, ht) = (f.width as usize, f.height as usize);
    let n = f.count.len();
    let beauty = partial.beauty();
    let variance = Image::from_pixels(w, ht, (0..n).map(|i| f.variance_of_mean(i)).collect());
    let counts: Vec<f32> = f.count.iter().map(|&c| c as f32).collect();
    let mut channels = Vec::new();
    for (name, sums) in [("sum", &f.sum), ("sumSq", &f.sum_sq)] {
        for (c, letter) in CHANNELS.iter().enumerate() {
            push_f64(
                &mut channels,
                &format!("{name}.{letter}"),
                sums.iter().map(|s| s[c]),
            );
        }
    }
    let layers = partial.aov_layers();
    if let Some(a) = &partial.aovs {
        for ((name, letters), sums) in [(ALBEDO_SUM, &a.albedo), (NORMAL_SUM, &a.normal)] {
            for (c, letter) in letters.iter().enumerate() {
                push_f64(
                    &mut channels,
                    &format!("{name}.{letter}"),
                    sums.iter().map(|s| s[c]),
                );
            }
        }
        push_f64(&mut channels, DEPTH_SUM, a.depth.iter().copied());
    }
    channels.push(x::AnyChannel::new(
        "count",
        x::FlatSamples::U32(f.count.clone()),
    ));
    let extra = ExtraPart {
        name: MERGE_PART,
        channels,
        attributes: vec![
            (SAMPLES, h.samples.to_string()),
            (SPP, h.spp.to_string()),
            (SEED, h.seed.to_string()),
            (SCENE_HASH, h.scene_hash.clone()),
            (STATS, ascii_json(&h.stats)),
            (ENCODING, ENCODING_TEXT.to_string()),
        ],
    };
    let film = FilmOutput {
        beauty: &beauty,
        variance: &variance,
        sample_count: &counts,
        albedo: layers.as_ref().map(|l| &l.0),
        normal: layers.as_ref().map(|l| &l.1),
        depth: layers.as_ref().map(|l| l.2.as_slice()),
    };
    let placement = Placement {
        full: (h.resolution.0 as usize, h.resolution.1 as usize),
        origin: (h.window.x0 as usize, h.window.y0 as usize),
    };
    // Atomic (a temporary beside it, fsynced, renamed): a checkpoint killed mid-write
    // leaves the previous one.
    Ok(write_exr_placed(path, &film, Some(placement), Some(extra))?)
}

/// Reads a partial EXR written by [`write_partial`] (or by `risotto merge`).
pub fn read_partial(path: &Path) -> Result<Partial, MergeError> {
    let not = |reason: String| MergeError::NotPartial {
        path: path.to_path_buf(),
        reason,
    };
    // Whether the file is a partial at all is read from its headers: a large image that is
    // not one is refused without decoding its pixels.
    if !exr_part_names(path)?.iter().any(|n| n == MERGE_PART) {
        return Err(not(format!(
            "no \"{MERGE_PART}\" part (render with --crop, --samples, --checkpoint or \
             --partial to write one)"
        )));
    }
    let image = read_exr_all(path)?;
    let layer = image
        .layer_data
        .iter()
        .find(|l| l.attributes.layer_name == Some(x::Text::from(MERGE_PART)))
        .ok_or_else(|| {
            not(format!(
                "no \"{MERGE_PART}\" part (render with --crop, --samples, --checkpoint or \
                 --partial to write one)"
            ))
        })?;
    let text = |key: &str| -> Result<String, MergeError> {
        match layer.attributes.other.get(&x::Text::from(key)) {
            Some(x::AttributeValue::Text(t)) => Ok(t.to_string()),
            Some(_) => Err(not(format!("attribute {key} is not text"))),
            None => Err(not(format!("no attribute {key}"))),
        }
    };
    let number = |key: &str| -> Result<u64, MergeError> {
        let t = text(key)?;
        t.parse()
            .map_err(|_| not(format!("attribute {key} = \"{t}\" is not a whole number")))
    };
    let samples_text = text(SAMPLES)?;
    let samples =
        parse_sample_range(&samples_text).map_err(|e| not(format!("attribute {SAMPLES}: {e}")))?;
    let spp = u32::try_from(number(SPP)?).map_err(|_| not(format!("{SPP} too large")))?;
    let seed = number(SEED)?;
    let scene_hash = text(SCENE_HASH)?;
    let stats =
        serde_json::from_str(&text(STATS)?).map_err(|e| not(format!("attribute {STATS}: {e}")))?;

    let display = image.attributes.display_window;
    let (pos, size) = (layer.attributes.layer_position, layer.size);
    // A part's header is not trusted with the merged image's size: the display window is
    // checked against the renderer's own limit before anything is allocated for it.
    let (dw, dh) = (display.size.width() as u64, display.size.height() as u64);
    if dw.saturating_mul(dh) > MAX_FILM_PIXELS || dw > u32::MAX as u64 || dh > u32::MAX as u64 {
        return Err(not(format!(
            "display window {dw}x{dh} is more than the {MAX_FILM_PIXELS} pixels a render may have"
        )));
    }
    let resolution = (dw as u32, dh as u32);
    let inside = display.position.x() == 0
        && display.position.y() == 0
        && pos.x() >= 0
        && pos.y() >= 0
        && pos.x() as usize + size.width() <= resolution.0 as usize
        && pos.y() as usize + size.height() <= resolution.1 as usize;
    if !inside {
        return Err(not(format!(
            "data window at ({}, {}) of {}x{} is not inside the display window {}x{} at \
             ({}, {})",
            pos.x(),
            pos.y(),
            size.width(),
            size.height(),
            resolution.0,
            resolution.1,
            display.position.x(),
            display.position.y()
        )));
    }
    let window = Window {
        x0: pos.x() as u32,
        y0: pos.y() as u32,
        x1: pos.x() as u32 + size.width() as u32,
        y1: pos.y() as u32 + size.height() as u32,
    };
    let n = window.pixels();
    let channel = |name: &str| -> Result<&[u32], MergeError> {
        let c = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.eq(name))
            .ok_or_else(|| not(format!("no channel {name}")))?;
        match &c.sample_data {
            x::FlatSamples::U32(v) if v.len() == n => Ok(v.as_slice()),
            x::FlatSamples::U32(v) => Err(not(format!(
                "channel {name} has {} values for {n} pixels",
                v.len()
            ))),
            _ => Err(not(format!("channel {name} is not UINT"))),
        }
    };
    // One f64 plane from the channels `NAME.hi` and `NAME.lo`.
    let plane = |name: &str| -> Result<Vec<f64>, MergeError> {
        let hi = channel(&format!("{name}.hi"))?;
        let lo = channel(&format!("{name}.lo"))?;
        Ok(hi
            .iter()
            .zip(lo)
            .map(|(&h, &l)| f64::from_bits(((h as u64) << 32) | l as u64))
            .collect())
    };
    let (w, h) = (window.width(), window.height());
    let mut film = Film::new(w, h);
    for (name, sums) in [("sum", &mut film.sum), ("sumSq", &mut film.sum_sq)] {
        for (c, letter) in CHANNELS.iter().enumerate() {
            for (s, v) in sums.iter_mut().zip(plane(&format!("{name}.{letter}"))?) {
                s[c] = v;
            }
        }
    }
    film.count = channel("count")?.to_vec();
    // Every pixel of a part holds every sample of its range (a sample whose radiance was not
    // finite is counted and dropped from the sums): a part whose counts disagree with its
    // declared range was relabelled or damaged, and merging it would make a wrong image.
    let per_pixel = u64::from(samples.end - samples.start);
    if let Some(i) = film.count.iter().position(|&c| u64::from(c) != per_pixel) {
        let (x, y) = (
            window.x0 as usize + i % w as usize,
            window.y0 as usize + i / w as usize,
        );
        return Err(not(format!(
            "pixel ({x}, {y}) holds {} samples, but the part declares {SAMPLES} = {samples}              ({per_pixel} per pixel)",
            film.count[i]
        )));
    }
    // AOV sums: any of their channels means all of them must be there.
    let has_aovs = layer.channel_data.list.iter().any(|c| {
        let name = c.name.to_string();
        ["albedoSum.", "normalSum.", "depthSum."]
            .iter()
            .any(|p| name.starts_with(p))
    });
    let aovs = if has_aovs {
        let mut a = AovFilm::new(w, h);
        for ((name, letters), sums) in [(ALBEDO_SUM, &mut a.albedo), (NORMAL_SUM, &mut a.normal)] {
            for (c, letter) in letters.iter().enumerate() {
                for (s, v) in sums.iter_mut().zip(plane(&format!("{name}.{letter}"))?) {
                    s[c] = v;
                }
            }
        }
        a.depth = plane(DEPTH_SUM)?;
        Some(a)
    } else {
        None
    };
    Ok(Partial {
        header: PartialHeader {
            resolution,
            window,
            samples,
            spp,
            seed,
            scene_hash,
            stats,
        },
        film,
        aovs,
    })
}

/// Parses `START..END` (whole numbers; not checked for START < END).
pub fn parse_sample_range(s: &str) -> Result<SampleRange, String> {
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| format!("\"{s}\" is not START..END"))?;
    let num = |t: &str| {
        t.trim()
            .parse::<u32>()
            .map_err(|_| format!("\"{s}\": \"{t}\" is not a whole number"))
    };
    Ok(SampleRange {
        start: num(a)?,
        end: num(b)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::merge::tests::{part, part_with_aovs};

    /// An EXR that is not a partial render is refused from its headers, before its pixels
    /// are decoded (`risotto info` on a large render decoded gigabytes to say so): here a
    /// plain image whose pixel data is cut off, which decoding would fail on first.
    #[test]
    fn a_plain_image_is_refused_from_its_headers() {
        let dir = risotto_engine::scratch_dir::ScratchDir::new("merge-plain");
        let path = dir.join("plain.exr");
        x::write_rgb_file(&path, 64, 64, |_, _| (0.5f32, 0.25f32, 0.125f32)).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..1000]).unwrap();
        let e = read_partial(&path).unwrap_err().to_string();
        assert!(
            e.contains("plain.exr") && e.contains("no \"merge\" part"),
            "{e}"
        );
    }

    /// A part whose header was edited is refused before its lie is used: relabelled sample
    /// ranges (the counts give it away), and a display window past the renderer's limit
    /// (which `merge` would allocate).
    #[test]
    fn a_part_with_a_lying_header_is_refused() {
        let dir = risotto_engine::scratch_dir::ScratchDir::new("merge-lies");
        let window = Window::full(4, 2);
        // Counts of samples 0..4, declared as 2..4.
        let mut relabelled = part(window, SampleRange { start: 0, end: 4 }, 0.5);
        relabelled.header.samples = SampleRange { start: 2, end: 4 };
        let path = dir.join("relabelled.exr");
        write_partial(&path, &relabelled).unwrap();
        let e = read_partial(&path).unwrap_err().to_string();
        assert!(
            e.contains("relabelled.exr")
                && e.contains("pixel (0, 0) holds 4 samples")
                && e.contains("risotto.samples = 2..4"),
            "{e}"
        );
        // The same part honestly labelled reads.
        relabelled.header.samples = SampleRange { start: 0, end: 4 };
        write_partial(&path, &relabelled).unwrap();
        assert!(read_partial(&path).is_ok());
        // A 4x2 piece of a 65536 x 65536 image.
        let mut huge = part(window, SampleRange { start: 0, end: 2 }, 0.5);
        huge.header.resolution = (65536, 65536);
        let path = dir.join("huge.exr");
        write_partial(&path, &huge).unwrap();
        let e = read_partial(&path).unwrap_err().to_string();
        assert!(
            e.contains("huge.exr") && e.contains("display window 65536x65536"),
            "{e}"
        );
    }

    #[test]
    fn partial_round_trip_is_bit_exact() {
        let dir = risotto_engine::scratch_dir::ScratchDir::new("merge-p");
        let path = dir.join("p.exr");
        let p = part(
            Window {
                x0: 1,
                y0: 0,
                x1: 3,
                y1: 2,
            },
            SampleRange { start: 2, end: 6 },
            0.7,
        );
        write_partial(&path, &p).unwrap();
        let back = read_partial(&path).unwrap();
        assert_eq!(back.header, p.header);
        assert_eq!(back.film.sum, p.film.sum);
        assert_eq!(back.film.sum_sq, p.film.sum_sq);
        assert_eq!(back.film.count, p.film.count);
        // The beauty part is a plain viewable crop.
        let rgb = risotto_engine::output::read_exr_rgb(&path).unwrap();
        assert_eq!(rgb, p.beauty());
    }

    #[test]
    fn aov_sums_round_trip_bit_exactly_with_viewable_layers() {
        let dir = risotto_engine::scratch_dir::ScratchDir::new("merge-aovs");
        let path = dir.join("aovs.exr");
        let window = Window {
            x0: 0,
            y0: 1,
            x1: 4,
            y1: 2,
        };
        let p = part_with_aovs(window, SampleRange { start: 0, end: 8 }, 0.3);
        write_partial(&path, &p).unwrap();
        let back = read_partial(&path).unwrap();
        assert_eq!(back.aovs, p.aovs);
        assert_eq!(back.film.sum, p.film.sum);
        // The `aovs` part holds the mean layers a render writes, recomputed from the sums.
        let image = read_exr_all(&path).unwrap();
        let layer = image
            .layer_data
            .iter()
            .find(|l| {
                l.attributes.layer_name == Some(x::Text::from(risotto_engine::output::AOV_PART))
            })
            .unwrap();
        let plane = |name: &str| -> Vec<f32> {
            let c = layer.channel_data.list.iter().find(|c| c.name.eq(name));
            c.unwrap_or_else(|| panic!("no {name}"))
                .sample_data
                .values_as_f32()
                .collect()
        };
        let (albedo, normal, depth) = p.aov_layers().unwrap();
        assert_eq!(plane("depth.Z"), depth);
        let g: Vec<f32> = albedo.pixels.iter().map(|c| c.g).collect();
        assert_eq!(plane("albedo.G"), g);
        let y: Vec<f32> = normal.pixels.iter().map(|c| c.g).collect();
        assert_eq!(plane("normal.Y"), y);
        // Without AOVs there are neither sums nor layers.
        let plain = part(window, SampleRange { start: 0, end: 8 }, 0.3);
        write_partial(&path, &plain).unwrap();
        assert!(read_partial(&path).unwrap().aovs.is_none());
        let names: Vec<String> = read_exr_all(&path)
            .unwrap()
            .layer_data
            .iter()
            .flat_map(|l| l.channel_data.list.iter().map(|c| c.name.to_string()))
            .collect();
        assert!(!names
            .iter()
            .any(|n| n.contains("albedo") || n.contains("depth")));
    }

    #[test]
    fn a_partial_with_some_aov_sums_missing_is_refused_by_name() {
        use exr::prelude::WritableImage as _;
        let dir = risotto_engine::scratch_dir::ScratchDir::new("merge-half-aovs");
        let path = dir.join("half-aovs.exr");
        let p = part_with_aovs(Window::full(4, 2), SampleRange { start: 0, end: 8 }, 0.3);
        write_partial(&path, &p).unwrap();
        let mut image = read_exr_all(&path).unwrap();
        let merge_part = image
            .layer_data
            .iter_mut()
            .find(|l| l.attributes.layer_name == Some(x::Text::from(MERGE_PART)))
            .unwrap();
        merge_part
            .channel_data
            .list
            .retain(|c| !c.name.eq("normalSum.Y.lo"));
        image.write().to_file(&path).unwrap();
        let err = read_partial(&path).unwrap_err().to_string();
        assert!(err.contains("half-aovs.exr"), "{err}");
        assert!(err.contains("no channel normalSum.Y.lo"), "{err}");
    }
}
