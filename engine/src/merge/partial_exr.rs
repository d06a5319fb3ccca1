//! The partial EXR: how a [`Partial`] is written to and read from a file, bit-exactly.
//!
//! # Layout
//! The two parts of [`write_exr`](crate::output::write_exr) (`beauty`, `aovs`: beauty,
//! variance and sample count of the piece, so it can be viewed as it is) plus a third part,
//! `merge`, with what merging needs:
//!
//! - **windows**: the display window is the full image (`0,0` to `width-1,height-1`), the data
//!   window of every part is the piece's window in it;
//! - **channels** (all `UINT`, ZIP, lossless): `sum.R.hi`, `sum.R.lo`, ... `sumSq.B.lo`: the
//!   film's per-pixel f64 sums of sample radiance and of its square, each f64 stored
//!   bit-exactly as its upper (`.hi`) and lower (`.lo`) 32 bits, because EXR has no 64-bit
//!   float and an f32 sum would lose the bits that make the merge exact; `count`: samples
//!   per pixel;
//! - **text attributes**: `risotto.samples` (`START..END`), `risotto.spp`, `risotto.seed`,
//!   `risotto.sceneHash` ([`scene_hash`](super::scene_hash)), `risotto.stats` (the piece's
//!   stats JSON) and `risotto.encoding` (the channel encoding above, in words).

use std::path::Path;

use exr::prelude as x;
use risotto_systems::film::Film;
use serde_json::Value;

use super::{MergeError, Partial, PartialHeader, MERGE_PART};
use crate::output::{
    read_exr_all, write_exr_placed, ExtraPart, FilmOutput, Image, OutputError, Placement,
};
use crate::render::{SampleRange, Window};

const SAMPLES: &str = "risotto.samples";
const SPP: &str = "risotto.spp";
const SEED: &str = "risotto.seed";
const SCENE_HASH: &str = "risotto.sceneHash";
const STATS: &str = "risotto.stats";
const ENCODING: &str = "risotto.encoding";
const ENCODING_TEXT: &str = "sum.C, sumSq.C (C = R, G, B): per-pixel f64 sums of sample \
    radiance and of its square, each f64's bits split into two UINT channels (.hi = upper 32 \
    bits, .lo = lower 32 bits); count: samples per pixel";
const CHANNELS: [char; 3] = ['R', 'G', 'B'];
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
            let bits: Vec<u64> = sums.iter().map(|s| s[c].to_bits()).collect();
            for (half, shift) in [("hi", 32), ("lo", 0)] {
                let values = bits.iter().map(|b| (b >> shift) as u32).collect();
                channels.push(x::AnyChannel::new(
                    format!("{name}.{letter}.{half}").as_str(),
                    x::FlatSamples::U32(values),
                ));
            }
        }
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
        albedo: None,
        normal: None,
        depth: None,
    };
    let placement = Placement {
        full: (h.resolution.0 as usize, h.resolution.1 as usize),
        origin: (h.window.x0 as usize, h.window.y0 as usize),
    };
    let name = path.file_name().map_or_else(
        || "partial.exr".into(),
        |n| n.to_string_lossy().into_owned(),
    );
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    write_exr_placed(&tmp, &film, Some(placement), Some(extra))?;
    std::fs::rename(&tmp, path).map_err(|cause| {
        let _ = std::fs::remove_file(&tmp);
        OutputError::Io {
            path: path.to_path_buf(),
            cause,
        }
    })?;
    Ok(())
}

/// Reads a partial EXR written by [`write_partial`] (or by `risotto merge`).
pub fn read_partial(path: &Path) -> Result<Partial, MergeError> {
    let not = |reason: String| MergeError::NotPartial {
        path: path.to_path_buf(),
        reason,
    };
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
    let resolution = (display.size.width() as u32, display.size.height() as u32);
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
    let mut film = Film::new(window.width(), window.height());
    for (name, sums) in [("sum", &mut film.sum), ("sumSq", &mut film.sum_sq)] {
        for (c, letter) in CHANNELS.iter().enumerate() {
            let hi = channel(&format!("{name}.{letter}.hi"))?;
            let lo = channel(&format!("{name}.{letter}.lo"))?;
            for (i, s) in sums.iter_mut().enumerate() {
                s[c] = f64::from_bits(((hi[i] as u64) << 32) | lo[i] as u64);
            }
        }
    }
    film.count = channel("count")?.to_vec();
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
    use crate::merge::tests::part;

    #[test]
    fn partial_round_trip_is_bit_exact() {
        let dir = std::env::temp_dir().join(format!("risotto-merge-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
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
        let rgb = crate::output::read_exr_rgb(&path).unwrap();
        assert_eq!(rgb, p.beauty());
    }
}
