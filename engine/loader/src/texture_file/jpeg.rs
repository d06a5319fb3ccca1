//! JPEG textures (8-bit, baseline or progressive, grey or colour), decoded by `zune-jpeg`
//! (the decoder the `image` crate uses): Mitsuba's test scenes and many asset libraries
//! ship their colour textures as JPEG.

use std::path::Path;

use risotto_components::Rgb;
use zune_jpeg::zune_core::colorspace::ColorSpace;
use zune_jpeg::zune_core::options::DecoderOptions;
use zune_jpeg::JpegDecoder;

use super::{check_size, srgb_to_linear, TextureChannels, MAX_TEXTURE_PIXELS};

/// The texels of the JPEG at `path`, row after row from the top: decoded from sRGB to
/// linear (`Rgb`) or as stored (`RawRgb`); a JPEG has no alpha (`Alpha` is an error). The
/// size is checked from the header before the pixels are decoded.
pub(super) fn read_jpeg(
    path: &Path,
    wanted: TextureChannels,
) -> Result<(usize, usize, Vec<Rgb>), String> {
    let fail = |what: &dyn std::fmt::Display| format!("{}: {what}", path.display());
    if wanted == TextureChannels::Alpha {
        return Err(fail(
            &"asked for its alpha (`channel = \"a\"`), but a JPEG has no alpha",
        ));
    }
    let bytes = std::fs::read(path).map_err(|e| fail(&format!("cannot read: {e}")))?;
    let side = (MAX_TEXTURE_PIXELS as f64).sqrt() as usize;
    let options = DecoderOptions::default()
        .jpeg_set_out_colorspace(ColorSpace::RGB)
        .set_max_width(side.max(1) * 4)
        .set_max_height(side.max(1) * 4);
    let mut decoder = JpegDecoder::new_with_options(&bytes[..], options);
    decoder.decode_headers().map_err(|e| fail(&e))?;
    let (w, h) = decoder
        .dimensions()
        .ok_or_else(|| fail(&"no image size in the header"))?;
    check_size(path, w as u64, h as u64)?;
    let pixels = decoder.decode().map_err(|e| fail(&e))?;
    let (w, h) = (w, h);
    if pixels.len() < w * h * 3 {
        return Err(fail(&"truncated image"));
    }
    // sRGB decoding of 8-bit values through a table (256 entries, each exact).
    let table: Vec<f32> = (0..256).map(|i| srgb_to_linear(i as f32 / 255.0)).collect();
    let value = |b: u8| {
        if wanted == TextureChannels::RawRgb {
            f32::from(b) / 255.0
        } else {
            table[b as usize]
        }
    };
    Ok((
        w,
        h,
        pixels
            .chunks_exact(3)
            .take(w * h)
            .map(|p| Rgb::new(value(p[0]), value(p[1]), value(p[2])))
            .collect(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mitsuba's own `wood.jpg` (mitsuba-data, in the repository's test data) decodes to the
    /// bytes Mitsuba 3.9.1's libjpeg reader gives at four texels (within one step: IDCTs may
    /// round differently), row 0 at the top; `RawRgb` keeps the bytes, `Rgb` decodes sRGB.
    #[test]
    fn wood_jpg_decodes_as_mitsuba_reads_it() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../tests/data/mitsuba-data/common/textures/wood.jpg");
        let (w, h, raw) = read_jpeg(&path, TextureChannels::RawRgb).unwrap();
        assert_eq!((w, h), (2048, 1571));
        for ((x, y), want) in [
            ((0, 0), [97, 79, 77]),
            ((100, 37), [138, 121, 113]),
            ((511, 900), [146, 131, 126]),
            ((2047, 1570), [119, 104, 97]),
        ] {
            let t = raw[y * w + x];
            for (got, want) in [t.r, t.g, t.b].into_iter().zip(want) {
                assert!(
                    (got * 255.0 - want as f32).abs() <= 1.01,
                    "texel ({x}, {y}): {t:?} vs Mitsuba's {want}"
                );
            }
        }
        let (_, _, linear) = read_jpeg(&path, TextureChannels::Rgb).unwrap();
        assert_eq!(linear[0].r, srgb_to_linear(raw[0].r));
        let e = read_jpeg(&path, TextureChannels::Alpha).unwrap_err();
        assert!(e.contains("no alpha") && e.contains("wood.jpg"), "{e}");
        let dir = std::env::temp_dir().join(format!("risotto-jpeg-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bad = dir.join("bad.jpg");
        std::fs::write(&bad, b"\xff\xd8 not a jpeg").unwrap();
        assert!(read_jpeg(&bad, TextureChannels::Rgb)
            .unwrap_err()
            .contains("bad.jpg"));
        std::fs::remove_dir_all(&dir).ok();
    }
}
