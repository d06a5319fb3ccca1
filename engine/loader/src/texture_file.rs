//! Reading image textures for the `image` pattern: PNG (8 or 16 bits, grey or RGB, with or
//! without alpha, palettes expanded; decoded from sRGB to linear), JPEG (8 bits, decoded
//! from sRGB; no alpha) and OpenEXR (linear RGB
//! through [`risotto_engine::output::read_exr_rgb`]); or, for an opacity mask, the alpha
//! channel alone ([`TextureChannels::Alpha`]: a PNG's alpha, linear by the PNG
//! specification, or an EXR's `A`), as grey. Sizes are checked against
//! [`MAX_TEXTURE_PIXELS`] from the header, before the pixels are allocated.

use risotto_components::Rgb;
use risotto_engine::output::read_exr_rgb_within;
use risotto_systems::pattern::Texture;
use std::path::Path;

mod jpeg;

/// The largest texture accepted, in pixels: 2^26 (8192 x 8192; 768 MiB of linear RGB).
pub const MAX_TEXTURE_PIXELS: u64 = 1 << 26;

/// Which channels of an image a texture reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TextureChannels {
    /// The colour (grey is spread to all three channels).
    #[default]
    Rgb,
    /// The alpha channel, as grey (an opacity mask); an image without one is an error.
    Alpha,
    /// The colour as stored, without decoding a PNG from sRGB (Mitsuba's `raw = true`:
    /// masks and other data written as 8- or 16-bit values); an EXR reads as [`Self::Rgb`].
    RawRgb,
}

/// Reads a texture by extension (`.png` or `.exr`, any case). Errors name the file and what
/// is wrong with it.
pub fn read_texture(path: &Path) -> Result<Texture, String> {
    read_texture_channels(path, TextureChannels::Rgb)
}

/// Reads `channels` of a texture by extension (`.png` or `.exr`, any case). Errors name the
/// file and what is wrong with it (an image without alpha asked for its alpha, too).
pub fn read_texture_channels(path: &Path, channels: TextureChannels) -> Result<Texture, String> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let (width, height, texels) = match ext.as_deref() {
        Some("png") => read_png(path, channels)?,
        Some("jpg" | "jpeg") => jpeg::read_jpeg(path, channels)?,
        Some("exr") if channels == TextureChannels::Alpha => read_exr_alpha(path)?,
        Some("exr") => {
            // The size is checked in the header, before the pixels are decoded.
            let image = read_exr_rgb_within(path, MAX_TEXTURE_PIXELS).map_err(|e| e.to_string())?;
            (image.width, image.height, image.pixels)
        }
        _ => {
            return Err(format!(
                "{}: an image texture must be a .png, .jpg (.jpeg) or .exr file",
                path.display()
            ))
        }
    };
    Texture::new(width, height, texels).map_err(|e| format!("{}: {e}", path.display()))
}

/// [`read_texture_channels`] with the rows in reverse order: the texture of an image whose
/// `v = 0` is its top row (Mitsuba's bitmaps) read by risotto's lookup, whose `v = 0` is the
/// bottom row.
pub fn read_texture_channels_top_down(
    path: &Path,
    channels: TextureChannels,
) -> Result<Texture, String> {
    let t = read_texture_channels(path, channels)?;
    let (width, height) = t.size();
    let texels: Vec<_> = (0..height)
        .rev()
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| t.texel(x, y))
        .collect();
    Texture::new(width, height, texels).map_err(|e| format!("{}: {e}", path.display()))
}

fn check_size(path: &Path, w: u64, h: u64) -> Result<(), String> {
    if w.saturating_mul(h) > MAX_TEXTURE_PIXELS {
        return Err(format!(
            "{}: {w} x {h} pixels is more than the {MAX_TEXTURE_PIXELS} a texture may have",
            path.display()
        ));
    }
    Ok(())
}

/// The sRGB transfer function's inverse (IEC 61966-2-1), code value in [0, 1] to linear.
fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The `A` channel of the first layer that has one, as grey texels.
fn read_exr_alpha(path: &Path) -> Result<(usize, usize, Vec<Rgb>), String> {
    let image = risotto_engine::output::read_exr_all_within(path, MAX_TEXTURE_PIXELS)
        .map_err(|e| e.to_string())?;
    let found = image.layer_data.iter().find_map(|layer| {
        let c = layer.channel_data.list.iter().find(|c| c.name.eq("A"))?;
        Some((layer.size.width(), layer.size.height(), c))
    });
    let Some((w, h, channel)) = found else {
        return Err(format!(
            "{}: asked for its alpha (`channel = \"a\"`), but no layer has an `A` channel",
            path.display()
        ));
    };
    check_size(path, w as u64, h as u64)?;
    let texels: Vec<Rgb> = channel
        .sample_data
        .values_as_f32()
        .map(Rgb::splat)
        .collect();
    if texels.len() != w * h {
        return Err(format!(
            "{}: a sub-sampled `A` channel is not supported",
            path.display()
        ));
    }
    Ok((w, h, texels))
}

fn read_png(path: &Path, wanted: TextureChannels) -> Result<(usize, usize, Vec<Rgb>), String> {
    let fail = |what: &dyn std::fmt::Display| format!("{}: {what}", path.display());
    let file = std::fs::File::open(path).map_err(|e| fail(&format!("cannot read: {e}")))?;
    // The decoder's own limit bounds its buffers; the pixel count is checked before the
    // frame buffer is allocated.
    let limits = png::Limits {
        bytes: (MAX_TEXTURE_PIXELS * 8) as usize,
    };
    let mut decoder = png::Decoder::new_with_limits(std::io::BufReader::new(file), limits);
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(|e| fail(&e))?;
    let (w, h) = (reader.info().width, reader.info().height);
    check_size(path, w.into(), h.into())?;
    let mut buf = vec![0u8; reader.output_buffer_size()];
    let frame = reader.next_frame(&mut buf).map_err(|e| fail(&e))?;
    let (colour, depth) = (frame.color_type, frame.bit_depth);
    let channels = match colour {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Indexed => return Err(fail(&"palette not expanded")),
    };
    let bytes = match depth {
        png::BitDepth::Eight => 1,
        png::BitDepth::Sixteen => 2,
        other => return Err(fail(&format!("unsupported bit depth {other:?}"))),
    };
    if wanted == TextureChannels::Alpha && channels % 2 == 1 {
        return Err(fail(&format!(
            "asked for its alpha (`channel = \"a\"`), but the image is {colour:?}, without \
             alpha"
        )));
    }
    let (w, h) = (w as usize, h as usize);
    let line = frame.line_size;
    let sample = |row: &[u8], k: usize| -> f32 {
        if bytes == 1 {
            f32::from(row[k]) / 255.0
        } else {
            f32::from(u16::from_be_bytes([row[2 * k], row[2 * k + 1]])) / 65535.0
        }
    };
    // sRGB decoding of 8-bit values through a table (256 entries, each exact).
    let table: Vec<f32> = (0..256).map(|i| srgb_to_linear(i as f32 / 255.0)).collect();
    let linear = |row: &[u8], k: usize| -> f32 {
        if wanted == TextureChannels::RawRgb {
            sample(row, k)
        } else if bytes == 1 {
            table[row[k] as usize]
        } else {
            srgb_to_linear(sample(row, k))
        }
    };
    let mut texels = Vec::with_capacity(w * h);
    for y in 0..h {
        let row = buf
            .get(y * line..(y + 1) * line)
            .ok_or_else(|| fail(&"truncated frame"))?;
        for x in 0..w {
            let k = x * channels;
            texels.push(if wanted == TextureChannels::Alpha {
                // Alpha is linear (PNG specification, sec. 12.4): not decoded from sRGB.
                Rgb::splat(sample(row, k + channels - 1))
            } else if channels < 3 {
                Rgb::splat(linear(row, k))
            } else {
                Rgb::new(linear(row, k), linear(row, k + 1), linear(row, k + 2))
            });
        }
    }
    Ok((w, h, texels))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write_png(path: &Path, w: u32, h: u32, colour: png::ColorType, data: &[u8]) {
        let file = std::fs::File::create(path).unwrap();
        let mut e = png::Encoder::new(file, w, h);
        e.set_color(colour);
        e.set_depth(png::BitDepth::Eight);
        e.write_header().unwrap().write_image_data(data).unwrap();
    }

    #[test]
    fn png_texels_are_decoded_from_srgb_row_by_row_from_the_top() {
        let dir = std::env::temp_dir().join(format!("risotto-texture-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let rgb = dir.join("rgb.png");
        // 2 x 2: top row red, green; bottom row blue, white.
        let data = [255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255];
        write_png(&rgb, 2, 2, png::ColorType::Rgb, &data);
        let t = read_texture(&rgb).unwrap();
        assert_eq!(t.size(), (2, 2));
        assert_eq!(t.texel(1, 0), Rgb::new(0.0, 1.0, 0.0));
        assert_eq!(t.texel(0, 1), Rgb::new(0.0, 0.0, 1.0));
        // Grey with alpha; sRGB 188 is linear 0.5 (to 3 digits).
        let grey = dir.join("grey.png");
        write_png(&grey, 1, 1, png::ColorType::GrayscaleAlpha, &[188, 7]);
        let g = read_texture(&grey).unwrap().texel(0, 0);
        assert!((g.r - 0.5029).abs() < 1e-3 && g.r == g.b, "{g:?}");
        // Errors name the file.
        let e = read_texture(&dir.join("missing.png")).unwrap_err();
        assert!(e.contains("missing.png"), "{e}");
        let bad = dir.join("bad.png");
        std::fs::write(&bad, b"not a png").unwrap();
        assert!(read_texture(&bad).unwrap_err().contains("bad.png"));
        assert!(read_texture(&dir.join("x.gif"))
            .unwrap_err()
            .contains(".png, .jpg (.jpeg) or .exr"));
        std::fs::remove_dir_all(&dir).ok();
    }

    /// A top-down texture (Mitsuba's bitmap convention) is the file with its rows reversed,
    /// so that risotto's lookup (v = 0 at the bottom row) reads the file's top row at v = 0.
    #[test]
    fn top_down_texture_reverses_the_rows() {
        let dir = std::env::temp_dir().join(format!("risotto-topdown-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let png = dir.join("rows.png");
        // 2 x 3 raw RGB, rows from the top: red-ish, green-ish, blue-ish.
        #[rustfmt::skip]
        let rows = [200, 0, 0, 201, 0, 0,  0, 200, 0, 0, 201, 0,  0, 0, 200, 0, 0, 201];
        write_png(&png, 2, 3, png::ColorType::Rgb, &rows);
        let plain = read_texture_channels(&png, TextureChannels::RawRgb).unwrap();
        let flipped = read_texture_channels_top_down(&png, TextureChannels::RawRgb).unwrap();
        assert_eq!(flipped.size(), (2, 3));
        for y in 0..3 {
            for x in 0..2 {
                assert_eq!(flipped.texel(x, y), plain.texel(x, 2 - y));
            }
        }
        // At v = 1/6 (the bottom row's centre in risotto's lookup) the flipped texture reads
        // the file's top row.
        assert_eq!(flipped.lookup(0.25, 1.0 / 6.0), plain.texel(0, 0));
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn raw_colour_is_read_as_stored() {
        let dir = std::env::temp_dir().join(format!("risotto-raw-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let rgb = dir.join("rgb.png");
        write_png(&rgb, 1, 1, png::ColorType::Rgb, &[128, 64, 255]);
        let raw = read_texture_channels(&rgb, TextureChannels::RawRgb).unwrap();
        assert_eq!(raw.texel(0, 0), Rgb::new(128.0 / 255.0, 64.0 / 255.0, 1.0));
        // Decoded from sRGB without raw: 128 is 0.2158.
        let decoded = read_texture(&rgb).unwrap().texel(0, 0);
        assert!((decoded.r - 0.2158).abs() < 1e-3, "{decoded:?}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn the_alpha_channel_is_read_linear_as_grey_and_its_absence_is_an_error() {
        let dir = std::env::temp_dir().join(format!("risotto-alpha-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // 2 x 1 RGBA: alpha 128 and 255 (colour values that differ from them).
        let rgba = dir.join("rgba.png");
        let data = [10, 20, 30, 128, 200, 100, 50, 255];
        write_png(&rgba, 2, 1, png::ColorType::Rgba, &data);
        let t = read_texture_channels(&rgba, TextureChannels::Alpha).unwrap();
        // Linear: 128 / 255, not sRGB-decoded (0.2158).
        assert_eq!(t.texel(0, 0), Rgb::splat(128.0 / 255.0));
        assert_eq!(t.texel(1, 0), Rgb::splat(1.0));
        // The colour of the same file is unaffected.
        let c = read_texture(&rgba).unwrap().texel(1, 0);
        assert!((c.r - srgb_to_linear(200.0 / 255.0)).abs() < 1e-6, "{c:?}");
        // Grey with alpha: the second sample.
        let ga = dir.join("ga.png");
        write_png(&ga, 1, 1, png::ColorType::GrayscaleAlpha, &[7, 51]);
        let a = read_texture_channels(&ga, TextureChannels::Alpha).unwrap();
        assert_eq!(a.texel(0, 0), Rgb::splat(0.2));
        // No alpha: an error naming the file.
        let grey = dir.join("grey.png");
        write_png(&grey, 1, 1, png::ColorType::Grayscale, &[7]);
        let e = read_texture_channels(&grey, TextureChannels::Alpha).unwrap_err();
        assert!(e.contains("grey.png") && e.contains("without alpha"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
