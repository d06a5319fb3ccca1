//! Image output and input: multi-channel OpenEXR for renders, sRGB PNG previews, and reading
//! the RGB of reference EXRs.
//!
//! # EXR layout written by [`write_exr`]
//! One two-part, scan-line OpenEXR 2 file; every channel `FLOAT` (32-bit), ZIP compression
//! (lossless, 16 scan lines per block).
//!
//! | part (`name`) | channels | content |
//! |---|---|---|
//! | 0 `beauty` | `R`, `G`, `B` | the rendered image (linear Rec.709 radiance) |
//! | 1 `aovs` | `variance.R`, `variance.G`, `variance.B` | per-pixel variance of the mean estimate |
//! | | `sampleCount` | samples that contributed to the pixel |
//! | | `albedo.R`, `albedo.G`, `albedo.B` | optional first-hit albedo |
//! | | `normal.X`, `normal.Y`, `normal.Z` | optional first-hit shading normal (world space) |
//! | | `depth.Z` | optional first-hit distance |
//!
//! Why two parts: single-part readers (OpenEXR's `InputFile`/RGBA interface, and therefore
//! Mitsuba's `Bitmap`) open part 0 only, and there they find exactly `R`, `G`, `B`, so the
//! file loads as a plain RGB image (`rmse.py`'s `convert(RGB)` works; with the auxiliary
//! channels in the same part Mitsuba would load a 14-channel bitmap that `convert(RGB)`
//! rejects). Multi-part-aware tools (`exrheader`, OpenImageIO, Nuke, Blender, the exr crate)
//! see both parts. Auxiliary channel names carry a `layer.` prefix (OpenEXR "Technical
//! Introduction", "Layers") so they stay unique even for tools that flatten parts.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use exr::prelude as x;
use exr::prelude::{ReadChannels as _, ReadLayers as _, WritableImage as _};
use risotto_components::Rgb;
use smallvec::SmallVec;

/// Name of the EXR part holding the beauty `R`, `G`, `B` (part 0).
pub const BEAUTY_PART: &str = "beauty";
/// Name of the EXR part holding the auxiliary channels (part 1).
pub const AOV_PART: &str = "aovs";

/// A linear RGB image, row-major, pixel `(0, 0)` at the top left.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `width * height` pixels, row after row from the top.
    pub pixels: Vec<Rgb>,
}

impl Image {
    /// A `width` x `height` image with every pixel set to `value`.
    pub fn filled(width: usize, height: usize, value: Rgb) -> Self {
        Image {
            width,
            height,
            pixels: vec![value; width * height],
        }
    }

    /// An image from its pixels (row-major, top row first).
    ///
    /// # Panics
    /// When `pixels.len() != width * height`.
    pub fn from_pixels(width: usize, height: usize, pixels: Vec<Rgb>) -> Self {
        assert_eq!(
            pixels.len(),
            width * height,
            "Image::from_pixels: {} pixels for a {width}x{height} image",
            pixels.len()
        );
        Image {
            width,
            height,
            pixels,
        }
    }

    /// The pixel in column `x`, row `y` (row 0 is the top).
    pub fn get(&self, x: usize, y: usize) -> Rgb {
        self.pixels[y * self.width + x]
    }

    /// Overwrites the pixel in column `x`, row `y`.
    pub fn set(&mut self, x: usize, y: usize, value: Rgb) {
        self.pixels[y * self.width + x] = value;
    }

    /// Per-channel mean over all pixels, accumulated in `f64` (non-finite values included,
    /// so a NaN anywhere makes the mean NaN).
    pub fn mean(&self) -> [f64; 3] {
        let mut s = [0.0f64; 3];
        for p in &self.pixels {
            s[0] += f64::from(p.r);
            s[1] += f64::from(p.g);
            s[2] += f64::from(p.b);
        }
        let n = self.pixels.len().max(1) as f64;
        s.map(|v| v / n)
    }

    /// True when `pixels.len()` matches the dimensions.
    fn is_consistent(&self) -> bool {
        self.pixels.len() == self.width * self.height
    }
}

/// Everything a render writes into its EXR. All images must share the beauty's size; the
/// scalar planes (`sample_count`, `depth`) hold `width * height` values in the same order.
#[derive(Clone, Copy, Debug)]
pub struct FilmOutput<'a> {
    /// The rendered image (mean estimate per pixel).
    pub beauty: &'a Image,
    /// Per-pixel, per-channel variance of the mean estimate (not of single samples).
    pub variance: &'a Image,
    /// Number of samples per pixel.
    pub sample_count: &'a [f32],
    /// Optional first-hit albedo.
    pub albedo: Option<&'a Image>,
    /// Optional first-hit normal, stored as `(x, y, z)` in the `r, g, b` fields.
    pub normal: Option<&'a Image>,
    /// Optional first-hit distance along the camera ray.
    pub depth: Option<&'a [f32]>,
}

/// An image could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// Creating or writing the file failed at the OS level.
    #[error("{path}: {cause}")]
    Io {
        /// The file involved.
        path: PathBuf,
        /// The underlying error (part of this error's message, so not also its
        /// `source()`: a printer of the cause chain would repeat it).
        cause: std::io::Error,
    },
    /// The EXR library rejected the file or the data.
    #[error("{path}: EXR error: {cause}")]
    Exr {
        /// The file involved.
        path: PathBuf,
        /// The underlying error (part of this error's message, so not also its
        /// `source()`: a printer of the cause chain would repeat it).
        cause: exr::error::Error,
    },
    /// The PNG library failed to encode.
    #[error("{path}: PNG error: {cause}")]
    Png {
        /// The file involved.
        path: PathBuf,
        /// The underlying error (part of this error's message, so not also its
        /// `source()`: a printer of the cause chain would repeat it).
        cause: png::EncodingError,
    },
    /// The data handed in (or found in the file) is not a usable image.
    #[error("{path}: {reason}")]
    Invalid {
        /// The file involved.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
}

fn invalid(path: &Path, reason: impl Into<String>) -> OutputError {
    OutputError::Invalid {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// Writes a render as one float32, ZIP-compressed, two-part EXR (layout in the module
/// docs). Every plane must match the beauty's size.
pub fn write_exr(path: &Path, out: &FilmOutput) -> Result<(), OutputError> {
    write_exr_placed(path, out, None, None)
}

/// Where the pixels of a [`FilmOutput`] sit in the full image: the EXR display window is
/// `(0, 0)` to `full`, the data window starts at `origin` (a crop of the full image).
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    /// Full image size (the display window).
    pub full: (usize, usize),
    /// Top-left pixel of the data window in the full image.
    pub origin: (usize, usize),
}

/// A third EXR part after `beauty` and `aovs`: its name, channels and text attributes.
pub struct ExtraPart {
    /// The part's name.
    pub name: &'static str,
    /// Its channels (each the data window's size).
    pub channels: Vec<x::AnyChannel<x::FlatSamples>>,
    /// Text attributes of its header.
    pub attributes: Vec<(&'static str, String)>,
}

/// An [`ExtraPart`] named `name` holding `img` as channels `R`, `G`, `B` (a denoised image,
/// say), with the header text `attributes`.
pub fn rgb_part(
    name: &'static str,
    img: &Image,
    attributes: Vec<(&'static str, String)>,
) -> ExtraPart {
    let mut channels = SmallVec::new();
    push_rgb(&mut channels, "", ["R", "G", "B"], img);
    ExtraPart {
        name,
        channels: channels.into_vec(),
        attributes,
    }
}

/// [`write_exr`] with the data window placed in a larger display window and an optional
/// extra part.
pub fn write_exr_placed(
    path: &Path,
    out: &FilmOutput,
    placement: Option<Placement>,
    extra: Option<ExtraPart>,
) -> Result<(), OutputError> {
    write_atomically(path, |tmp| exr_to(tmp, path, out, placement, extra))
}

/// [`write_exr_placed`] into the file `tmp`, errors naming `path`.
fn exr_to(
    tmp: &Path,
    path: &Path,
    out: &FilmOutput,
    placement: Option<Placement>,
    extra: Option<ExtraPart>,
) -> Result<(), OutputError> {
    let (w, h) = (out.beauty.width, out.beauty.height);
    if w == 0 || h == 0 {
        return Err(invalid(
            path,
            format!("cannot write an empty {w}x{h} image"),
        ));
    }
    let n = w * h;
    let check_image = |name: &str, img: &Image| {
        if img.width != w || img.height != h || !img.is_consistent() {
            Err(invalid(
                path,
                format!(
                    "{name} is {}x{} with {} pixels, expected {w}x{h}",
                    img.width,
                    img.height,
                    img.pixels.len()
                ),
            ))
        } else {
            Ok(())
        }
    };
    let check_plane = |name: &str, plane: &[f32]| {
        if plane.len() != n {
            Err(invalid(
                path,
                format!("{name} has {} values, expected {n}", plane.len()),
            ))
        } else {
            Ok(())
        }
    };
    check_image("beauty", out.beauty)?;
    check_image("variance", out.variance)?;
    check_plane("sampleCount", out.sample_count)?;

    let mut aovs: SmallVec<[x::AnyChannel<x::FlatSamples>; 4]> = SmallVec::new();
    push_rgb(&mut aovs, "variance.", ["R", "G", "B"], out.variance);
    if let Some(albedo) = out.albedo {
        check_image("albedo", albedo)?;
        push_rgb(&mut aovs, "albedo.", ["R", "G", "B"], albedo);
    }
    if let Some(normal) = out.normal {
        check_image("normal", normal)?;
        push_rgb(&mut aovs, "normal.", ["X", "Y", "Z"], normal);
    }
    aovs.push(x::AnyChannel::new(
        "sampleCount",
        x::FlatSamples::F32(out.sample_count.to_vec()),
    ));
    if let Some(depth) = out.depth {
        check_plane("depth", depth)?;
        aovs.push(x::AnyChannel::new(
            "depth.Z",
            x::FlatSamples::F32(depth.to_vec()),
        ));
    }
    let mut beauty = SmallVec::new();
    push_rgb(&mut beauty, "", ["R", "G", "B"], out.beauty);

    // ZIP16 scan lines: lossless for float32 and supported by every OpenEXR reader.
    let placement = placement.unwrap_or(Placement {
        full: (w, h),
        origin: (0, 0),
    });
    let (Ok(ox), Ok(oy)) = (
        i32::try_from(placement.origin.0),
        i32::try_from(placement.origin.1),
    ) else {
        return Err(invalid(path, "data window origin beyond EXR's range"));
    };
    let part = |name: &str, channels| {
        let mut attributes = x::LayerAttributes::named(name);
        attributes.layer_position = x::Vec2(ox, oy);
        x::Layer::new(
            (w, h),
            attributes,
            x::Encoding::SMALL_LOSSLESS,
            x::AnyChannels::sort(channels),
        )
    };
    let mut layers = vec![part(BEAUTY_PART, beauty), part(AOV_PART, aovs)];
    if let Some(extra) = extra {
        let mut layer = part(extra.name, extra.channels.into_iter().collect());
        for (key, value) in extra.attributes {
            let text = x::Text::new_or_none(&value)
                .ok_or_else(|| invalid(path, format!("attribute {key}: not Latin-1 text")))?;
            layer
                .attributes
                .other
                .insert(x::Text::from(key), x::AttributeValue::Text(text));
        }
        layers.push(layer);
    }
    let attributes = x::ImageAttributes::new(x::IntegerBounds::from_dimensions(placement.full));
    x::Image::from_layers(attributes, layers)
        .write()
        .to_file(tmp)
        .map_err(|source| exr_error(path, source))
}

/// Appends three float32 channels `prefix + names[c]` holding channel `c` of `img`.
fn push_rgb(
    channels: &mut SmallVec<[x::AnyChannel<x::FlatSamples>; 4]>,
    prefix: &str,
    names: [&str; 3],
    img: &Image,
) {
    for (c, suffix) in names.iter().enumerate() {
        let values: Vec<f32> = img.pixels.iter().map(|p| p.to_array()[c]).collect();
        channels.push(x::AnyChannel::new(
            format!("{prefix}{suffix}").as_str(),
            x::FlatSamples::F32(values),
        ));
    }
}

/// Every part and channel of a flat EXR, with all attributes (largest resolution level).
pub fn read_exr_all(
    path: &Path,
) -> Result<x::Image<x::Layers<x::AnyChannels<x::FlatSamples>>>, OutputError> {
    read_exr_all_within(path, MAX_IMAGE_PIXELS)
}

/// [`read_exr_all`] with a bound on each part's pixels (at most [`MAX_IMAGE_PIXELS`]) and on
/// all the samples of all parts together (four channels' worth of `max_pixels`), both checked
/// in the headers before the reader allocates anything: a small compressed file that claims
/// a huge image, or dozens of channels, is an error naming the claim.
pub fn read_exr_all_within(
    path: &Path,
    max_pixels: u64,
) -> Result<x::Image<x::Layers<x::AnyChannels<x::FlatSamples>>>, OutputError> {
    // The header's claimed size is checked before the reader allocates for it.
    check_exr_header(path, max_pixels.min(MAX_IMAGE_PIXELS))?;
    x::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .map_err(|source| exr_error(path, source))
}

/// Maps the exr crate's error, keeping OS errors as [`OutputError::Io`].
fn exr_error(path: &Path, source: exr::error::Error) -> OutputError {
    match source {
        exr::error::Error::Io(e) => OutputError::Io {
            path: path.to_path_buf(),
            cause: e,
        },
        other => OutputError::Exr {
            path: path.to_path_buf(),
            cause: other,
        },
    }
}

/// The largest image [`read_exr_rgb`] accepts, in pixels per part: 2^28 (16384 x 16384, a
/// 3 GB RGB float image). Larger headers are rejected before their pixels are allocated.
pub const MAX_IMAGE_PIXELS: u64 = 1 << 28;

/// Bytes the file needs at least per chunk: its 8-byte offset-table entry and the chunk's
/// own header (an `i32` coordinate and an `i32` byte count for scan-line chunks; more for
/// tiles and multi-part files).
const MIN_BYTES_PER_CHUNK: u64 = 16;

/// Opens `path` for reading if it is a regular file (after symbolic links): opening a FIFO
/// blocks until a writer comes, and a device such as `/dev/zero` reads forever.
fn open_regular(path: &Path) -> Result<File, OutputError> {
    let io = |cause| OutputError::Io {
        path: path.to_path_buf(),
        cause,
    };
    if !std::fs::metadata(path).map_err(io)?.is_file() {
        return Err(invalid(
            path,
            "not a regular file (a directory, device, FIFO or socket)".to_string(),
        ));
    }
    File::open(path).map_err(io)
}

/// The names of the parts (layers) of the EXR at `path`, from its headers alone: no pixel is
/// read, so a caller can refuse a file without the part it needs before decoding it.
pub fn exr_part_names(path: &Path) -> Result<Vec<String>, OutputError> {
    let file = open_regular(path)?;
    let meta = exr::meta::MetaData::read_from_unbuffered(file, false)
        .map_err(|source| exr_error(path, source))?;
    Ok(meta
        .headers
        .iter()
        .map(|h| {
            h.own_attributes
                .layer_name
                .as_ref()
                .map_or_else(String::new, |n| n.to_string())
        })
        .collect())
}

/// Reads only the headers of `path` and checks the claimed sizes (see [`read_exr_rgb`] and
/// [`read_exr_all_within`]).
fn check_exr_header(path: &Path, max_pixels: u64) -> Result<(), OutputError> {
    let file = open_regular(path)?;
    let file_len = file
        .metadata()
        .map_err(|cause| OutputError::Io {
            path: path.to_path_buf(),
            cause,
        })?
        .len();
    let meta = exr::meta::MetaData::read_from_unbuffered(file, false)
        .map_err(|source| exr_error(path, source))?;
    let mut chunks = 0u64;
    let mut samples = 0u64;
    for (i, header) in meta.headers.iter().enumerate() {
        let (w, h) = (header.layer_size.width(), header.layer_size.height());
        let pixels = (w as u64).saturating_mul(h as u64);
        if pixels > max_pixels {
            return Err(invalid(
                path,
                format!(
                    "part {i}: the header claims {w} x {h} pixels, more than the {max_pixels} \
                     pixels this image may have"
                ),
            ));
        }
        samples = samples.saturating_add(pixels.saturating_mul(header.channels.list.len() as u64));
        chunks = chunks.saturating_add(header.chunk_count as u64);
    }
    let max_samples = max_pixels.saturating_mul(4);
    if samples > max_samples {
        return Err(invalid(
            path,
            format!(
                "the headers claim {samples} samples in all channels of all parts, more than \
                 the {max_samples} (four channels of {max_pixels} pixels) this image may have"
            ),
        ));
    }
    let needed = chunks.saturating_mul(MIN_BYTES_PER_CHUNK);
    if needed > file_len {
        let sizes: Vec<String> = meta
            .headers
            .iter()
            .map(|h| format!("{} x {}", h.layer_size.width(), h.layer_size.height()))
            .collect();
        return Err(invalid(
            path,
            format!(
                "the header claims {} pixels in {chunks} chunks, which need at least {needed} \
                 bytes, but the file has {file_len} bytes (truncated or corrupt)",
                sizes.join(", ")
            ),
        ));
    }
    Ok(())
}

/// Reads the `R`, `G`, `B` channels of an EXR (any compression the exr crate decodes,
/// including PIZ; half, float and uint samples are converted to `f32`).
///
/// The "main" image is the first layer (part) that has un-prefixed `R`, `G`, `B` channels;
/// failing that, the first layer with a `prefix.R/G/B` triple; failing that, a luminance-only
/// `Y` channel is replicated into all three channels.
///
/// Before any pixel memory is allocated, every part's size (the header's `dataWindow`) is
/// checked against [`MAX_IMAGE_PIXELS`], and the file must be long enough to hold the chunks
/// the headers imply (an offset-table entry and a chunk header for each), so a small file
/// whose header claims a huge image is an error naming the file and the claimed size.
pub fn read_exr_rgb(path: &Path) -> Result<Image, OutputError> {
    read_exr_rgb_within(path, MAX_IMAGE_PIXELS)
}

/// [`read_exr_rgb`] with a smaller bound on the pixels of a part (a texture's, an
/// environment map's), checked in the headers before any pixel is decoded.
pub fn read_exr_rgb_within(path: &Path, max_pixels: u64) -> Result<Image, OutputError> {
    let image = read_exr_all_within(path, max_pixels)?;

    type Layer = x::Layer<x::AnyChannels<x::FlatSamples>>;
    let find = |layer: &Layer, name: &str| -> Option<usize> {
        layer.channel_data.list.iter().position(|c| c.name.eq(name))
    };
    // Un-prefixed RGB in any layer first, then any `prefix.R/G/B`, then `Y`.
    let mut chosen: Option<(&Layer, [usize; 3])> = None;
    for layer in &image.layer_data {
        if let (Some(r), Some(g), Some(b)) = (find(layer, "R"), find(layer, "G"), find(layer, "B"))
        {
            chosen = Some((layer, [r, g, b]));
            break;
        }
    }
    if chosen.is_none() {
        'layers: for layer in &image.layer_data {
            for c in &layer.channel_data.list {
                let name = c.name.to_string();
                if let Some(prefix) = name.strip_suffix(".R") {
                    if let (Some(r), Some(g), Some(b)) = (
                        find(layer, &name),
                        find(layer, &format!("{prefix}.G")),
                        find(layer, &format!("{prefix}.B")),
                    ) {
                        chosen = Some((layer, [r, g, b]));
                        break 'layers;
                    }
                }
            }
        }
    }
    if chosen.is_none() {
        for layer in &image.layer_data {
            if let Some(y) = find(layer, "Y") {
                chosen = Some((layer, [y, y, y]));
                break;
            }
        }
    }
    let Some((layer, idx)) = chosen else {
        return Err(invalid(path, "no R,G,B (or Y) channels in any layer"));
    };

    let (w, h) = (layer.size.width(), layer.size.height());
    let planes: Vec<Vec<f32>> = idx
        .iter()
        .map(|&i| {
            layer.channel_data.list[i]
                .sample_data
                .values_as_f32()
                .collect()
        })
        .collect();
    if planes.iter().any(|p| p.len() != w * h) {
        return Err(invalid(path, "sub-sampled RGB channels are not supported"));
    }
    let pixels = (0..w * h)
        .map(|i| Rgb::new(planes[0][i], planes[1][i], planes[2][i]))
        .collect();
    Ok(Image::from_pixels(w, h, pixels))
}

/// The sRGB opto-electronic transfer function (IEC 61966-2-1), exact piecewise form: linear
/// segment `12.92 v` up to `v = 0.0031308`, then `1.055 v^(1/2.4) - 0.055`. Input is clamped
/// to `[0, 1]` first; non-finite input maps to 0.
pub fn srgb_oetf(v: f32) -> f32 {
    if !v.is_finite() {
        return 0.0;
    }
    let v = v.clamp(0.0, 1.0);
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Linear value to an 8-bit sRGB code: `round(255 * oetf(v))`.
pub fn srgb_encode_u8(v: f32) -> u8 {
    // oetf is in [0, 1], so the rounded product fits u8.
    (srgb_oetf(v) * 255.0).round() as u8
}

/// The largest exposure, in stops either way, [`write_png`] takes: `2^64` already turns
/// every lit pixel white; beyond about 128 the scale overflows to infinity, and `0 x inf`
/// would write black where the image is white.
pub const MAX_EXPOSURE_STOPS: f32 = 64.0;

/// Whether [`write_png`] takes the exposure `stops`: `Err` says why not (NaN, or beyond
/// [`MAX_EXPOSURE_STOPS`]); a caller checks with it before the work whose preview it is.
pub fn check_exposure(stops: f32) -> Result<(), String> {
    if stops.is_nan() || stops.abs() > MAX_EXPOSURE_STOPS {
        return Err(format!(
            "must be between -{MAX_EXPOSURE_STOPS} and {MAX_EXPOSURE_STOPS} stops"
        ));
    }
    Ok(())
}

/// Writes an 8-bit sRGB PNG preview: each channel is scaled by `2^exposure_stops`, clamped
/// to `[0, 1]` and encoded with the exact sRGB curve ([`srgb_oetf`]). Non-finite values are
/// written as 0. The file carries an `sRGB` chunk (perceptual intent). An exposure that is
/// not finite or beyond [`MAX_EXPOSURE_STOPS`] is an error.
pub fn write_png(path: &Path, img: &Image, exposure_stops: f32) -> Result<(), OutputError> {
    check_exposure(exposure_stops)
        .map_err(|why| invalid(path, format!("exposure {exposure_stops}: {why}")))?;
    if !img.is_consistent() {
        return Err(invalid(
            path,
            format!(
                "{} pixels for a {}x{} image",
                img.pixels.len(),
                img.width,
                img.height
            ),
        ));
    }
    let (Ok(w), Ok(h)) = (u32::try_from(img.width), u32::try_from(img.height)) else {
        return Err(invalid(path, "image too large for PNG"));
    };
    if w == 0 || h == 0 {
        return Err(invalid(
            path,
            format!("cannot write an empty {w}x{h} image"),
        ));
    }
    let scale = exposure_stops.exp2();
    let mut bytes = Vec::with_capacity(img.pixels.len() * 3);
    for p in &img.pixels {
        for c in p.to_array() {
            bytes.push(srgb_encode_u8(c * scale));
        }
    }
    write_atomically(path, |tmp| {
        let file = File::create(tmp).map_err(|cause| OutputError::Io {
            path: path.to_path_buf(),
            cause,
        })?;
        let png_err = |cause| OutputError::Png {
            path: path.to_path_buf(),
            cause,
        };
        let mut encoder = png::Encoder::new(BufWriter::new(file), w, h);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut writer = encoder.write_header().map_err(png_err)?;
        writer.write_image_data(&bytes).map_err(png_err)?;
        writer.finish().map_err(png_err)
    })
}

mod atomic_write;
pub use atomic_write::{remove_temporaries_for_exit, write_atomically, write_file_atomically};

#[cfg(test)]
mod tests;
