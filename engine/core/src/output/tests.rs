//! Tests of `output.rs`.

use super::*;

/// A scratch directory for one test (removed when dropped) and the file `name` in it.
fn scratch(name: &str) -> (crate::scratch_dir::ScratchDir, PathBuf) {
    let dir = crate::scratch_dir::ScratchDir::new(&format!("output-{name}"));
    let path = dir.join(name);
    (dir, path)
}

/// Pseudo-random but reproducible floats covering tiny, huge, negative and special-ish
/// values, so a lossy path (half floats, lossy compression) would show.
fn test_image(w: usize, h: usize, seed: u32) -> Image {
    let mut s = seed.wrapping_mul(747_796_405).wrapping_add(1);
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        // Random bit patterns of finite floats: mantissa and exponent both vary.
        let f = f32::from_bits(s & 0xBFFF_FFFF);
        if f.is_finite() {
            f
        } else {
            1.0
        }
    };
    let pixels = (0..w * h)
        .map(|_| Rgb::new(next(), next(), next()))
        .collect();
    Image::from_pixels(w, h, pixels)
}

#[test]
fn exr_round_trip_is_bit_exact() {
    let (w, h) = (37, 23);
    let beauty = test_image(w, h, 1);
    let variance = test_image(w, h, 2);
    let albedo = test_image(w, h, 3);
    let normal = test_image(w, h, 4);
    let counts: Vec<f32> = (0..w * h).map(|i| i as f32).collect();
    let depth: Vec<f32> = (0..w * h).map(|i| 0.5 * i as f32).collect();
    let (_dir, path) = scratch("roundtrip.exr");
    write_exr(
        &path,
        &FilmOutput {
            beauty: &beauty,
            variance: &variance,
            sample_count: &counts,
            albedo: Some(&albedo),
            normal: Some(&normal),
            depth: Some(&depth),
        },
    )
    .unwrap();
    let back = read_exr_rgb(&path).unwrap();
    assert_eq!((back.width, back.height), (w, h));
    for (a, b) in beauty.pixels.iter().zip(&back.pixels) {
        assert_eq!(
            a.to_array().map(f32::to_bits),
            b.to_array().map(f32::to_bits)
        );
    }
    // Two parts: `beauty` with exactly R, G, B; `aovs` with the documented names, all
    // float32, ZIP.
    let img = x::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(&path)
        .unwrap();
    assert_eq!(img.layer_data.len(), 2);
    let names = |l: &x::Layer<x::AnyChannels<x::FlatSamples>>| -> Vec<String> {
        l.channel_data
            .list
            .iter()
            .map(|c| c.name.to_string())
            .collect()
    };
    let part0 = &img.layer_data[0];
    assert_eq!(
        part0.attributes.layer_name,
        Some(x::Text::from(BEAUTY_PART))
    );
    assert_eq!(names(part0), ["B", "G", "R"]);
    let layer = &img.layer_data[1];
    assert_eq!(layer.attributes.layer_name, Some(x::Text::from(AOV_PART)));
    let mut got = names(layer);
    got.sort();
    let mut want = [
        "variance.R",
        "variance.G",
        "variance.B",
        "sampleCount",
        "albedo.R",
        "albedo.G",
        "albedo.B",
        "normal.X",
        "normal.Y",
        "normal.Z",
        "depth.Z",
    ];
    want.sort_unstable();
    assert_eq!(got, want);
    for l in &img.layer_data {
        assert_eq!(l.encoding.compression, x::Compression::ZIP16);
        assert!(l
            .channel_data
            .list
            .iter()
            .all(|c| matches!(c.sample_data, x::FlatSamples::F32(_))));
    }
    let get = |name: &str| -> &x::FlatSamples {
        &layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.eq(name))
            .unwrap()
            .sample_data
    };
    let x::FlatSamples::F32(v) = get("variance.G") else {
        panic!("variance.G is not float32");
    };
    assert!(v
        .iter()
        .zip(&variance.pixels)
        .all(|(a, p)| a.to_bits() == p.g.to_bits()));
    let x::FlatSamples::F32(d) = get("depth.Z") else {
        panic!("depth.Z is not float32");
    };
    assert_eq!(d, &depth);
    let x::FlatSamples::F32(nz) = get("normal.Z") else {
        panic!("normal.Z is not float32");
    };
    assert!(nz
        .iter()
        .zip(&normal.pixels)
        .all(|(a, p)| a.to_bits() == p.b.to_bits()));
    let x::FlatSamples::F32(sc) = get("sampleCount") else {
        panic!("sampleCount is not float32");
    };
    assert_eq!(sc, &counts);
}

#[test]
fn exr_without_optional_planes_and_top_left_origin() {
    let (w, h) = (4, 3);
    let mut beauty = Image::filled(w, h, Rgb::BLACK);
    beauty.set(0, 0, Rgb::new(1.0, 2.0, 3.0));
    beauty.set(3, 2, Rgb::new(-4.0, 5.5, 1e30));
    let variance = Image::filled(w, h, Rgb::splat(0.25));
    let counts = vec![8.0; w * h];
    let (_dir, path) = scratch("minimal.exr");
    let out = FilmOutput {
        beauty: &beauty,
        variance: &variance,
        sample_count: &counts,
        albedo: None,
        normal: None,
        depth: None,
    };
    write_exr(&path, &out).unwrap();
    let back = read_exr_rgb(&path).unwrap();
    assert_eq!(back, beauty);
    // First scan line in the file is the top row: check via the exr crate's pixel API.
    let img = x::read_first_rgba_layer_from_file(
        &path,
        |res, _| vec![[0.0f32; 3]; res.width() * res.height()],
        |buf: &mut Vec<[f32; 3]>, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            buf[pos.y() * 4 + pos.x()] = [r, g, b];
        },
    )
    .unwrap();
    assert_eq!(img.layer_data.channel_data.pixels[0], [1.0, 2.0, 3.0]);
    assert_eq!(img.layer_data.channel_data.pixels[11], [-4.0, 5.5, 1e30]);
}

#[test]
fn exr_rejects_mismatched_planes() {
    let beauty = Image::filled(4, 4, Rgb::WHITE);
    let small = Image::filled(2, 4, Rgb::WHITE);
    let counts = vec![1.0; 16];
    let (_dir, path) = scratch("bad.exr");
    let err = write_exr(
        &path,
        &FilmOutput {
            beauty: &beauty,
            variance: &small,
            sample_count: &counts,
            albedo: None,
            normal: None,
            depth: None,
        },
    )
    .unwrap_err();
    assert!(matches!(err, OutputError::Invalid { .. }));
    assert!(err.to_string().contains("variance"), "{err}");
    assert!(err.to_string().contains("bad.exr"), "{err}");
    let err = write_exr(
        &path,
        &FilmOutput {
            beauty: &beauty,
            variance: &beauty,
            sample_count: &counts[..15],
            albedo: None,
            normal: None,
            depth: None,
        },
    )
    .unwrap_err();
    assert!(err.to_string().contains("sampleCount"), "{err}");
}

#[test]
fn read_missing_file_names_the_path() {
    let err = read_exr_rgb(Path::new("/nonexistent/dir/nothing.exr")).unwrap_err();
    assert!(matches!(err, OutputError::Io { .. }), "{err:?}");
    assert!(err.to_string().contains("/nonexistent/dir/nothing.exr"));
}

/// A Mitsuba 3 render (PIZ-compressed float32; `tests/data/cornell-mitsuba-32-piz.exr`,
/// made with the reference harness in `../shared/refs/mitsuba`) loads with the channel
/// means that harness's `rmse.py` computes for it.
#[test]
fn reads_mitsuba_piz() {
    let path =
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/cornell-mitsuba-32-piz.exr");
    let img = read_exr_rgb(path).unwrap();
    assert_eq!((img.width, img.height), (32, 32));
    let m = img.mean();
    let want = [0.2593422340775078, 0.16793098262569472, 0.04796077020861933];
    for c in 0..3 {
        assert!(
            (m[c] - want[c]).abs() < 1e-6,
            "channel {c}: {} vs {}",
            m[c],
            want[c]
        );
    }
}

#[test]
fn srgb_curve_known_values() {
    assert_eq!(srgb_encode_u8(0.0), 0);
    assert_eq!(srgb_encode_u8(1.0), 255);
    assert_eq!(srgb_encode_u8(2.0), 255);
    assert_eq!(srgb_encode_u8(-1.0), 0);
    assert_eq!(srgb_encode_u8(f32::NAN), 0);
    assert_eq!(srgb_encode_u8(f32::INFINITY), 0);
    // 1.055 * 0.5^(1/2.4) - 0.055 = 0.735357 -> 187.52
    assert_eq!(srgb_encode_u8(0.5), 188);
    // 0.18 -> 0.461356 -> 117.65
    assert_eq!(srgb_encode_u8(0.18), 118);
    // Both pieces meet at the breakpoint: 12.92 * 0.0031308 = 0.0404499.
    let lo = srgb_oetf(0.003_130_8);
    let hi = 1.055 * 0.003_130_8f32.powf(1.0 / 2.4) - 0.055;
    assert!((lo - 0.040_449_9).abs() < 1e-6 && (lo - hi).abs() < 1e-6);
    assert_eq!(srgb_encode_u8(0.003_130_8), 10);
    // Linear segment: 0.001 -> 0.01292 -> 3.29
    assert_eq!(srgb_encode_u8(0.001), 3);
}

#[test]
fn png_known_bytes() {
    let mut img = Image::filled(3, 2, Rgb::BLACK);
    img.set(0, 0, Rgb::new(0.5, 0.0, 1.0));
    img.set(1, 0, Rgb::new(f32::NAN, 0.003_130_8, 7.0));
    img.set(2, 0, Rgb::new(0.25, 0.09, -3.0));
    img.set(0, 1, Rgb::new(f32::INFINITY, f32::NEG_INFINITY, 0.001));
    let (_dir, path) = scratch("known.png");
    write_png(&path, &img, 0.0).unwrap();
    let data = decode_png(&path);
    assert_eq!(
        data,
        vec![
            188, 0, 255, 0, 10, 255, 137, 85, 0, //
            0, 0, 3, 0, 0, 0, 0, 0, 0
        ]
    );
    // +1 stop: 0.25 -> 0.5 -> 188; 0.5 -> 1.0 -> 255.
    write_png(&path, &img, 1.0).unwrap();
    let data = decode_png(&path);
    assert_eq!(&data[0..3], &[255, 0, 255]);
    assert_eq!(data[6], 188);
}

/// The largest exposure still scales a lit pixel to white; beyond it, and for NaN, the
/// scale would overflow to infinity (`0 x inf` = NaN, written black): an error, no file.
#[test]
fn png_exposure_is_bounded() {
    let img = Image::filled(2, 1, Rgb::new(1e-10, 0.0, 0.5));
    let (_dir, path) = scratch("exposure.png");
    write_png(&path, &img, MAX_EXPOSURE_STOPS).unwrap();
    assert_eq!(decode_png(&path), vec![255, 0, 255, 255, 0, 255]);
    std::fs::remove_file(&path).unwrap();
    for e in [MAX_EXPOSURE_STOPS + 1.0, -1e30, f32::NAN, f32::INFINITY] {
        let err = write_png(&path, &img, e).unwrap_err().to_string();
        assert!(err.contains("exposure") && err.contains("64"), "{e}: {err}");
        assert!(!path.exists(), "{e}: a file was written");
    }
}

fn decode_png(path: &Path) -> Vec<u8> {
    let decoder = png::Decoder::new(File::open(path).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    buf.truncate(info.buffer_size());
    buf
}

/// An output is replaced whole or not at all: a write that fails halfway leaves the old file
/// as it was and no temporary behind; one that succeeds replaces it.
#[test]
fn outputs_are_written_atomically() {
    let (_dir, path) = scratch("atomic");
    std::fs::write(&path, b"old").unwrap();
    let failed = write_atomically(&path, |tmp| {
        std::fs::write(tmp, b"half of the ne").unwrap();
        Err(invalid(tmp, "the disk filled up"))
    });
    assert!(failed.is_err());
    assert_eq!(std::fs::read(&path).unwrap(), b"old");
    let names = || -> Vec<String> {
        std::fs::read_dir(path.parent().unwrap())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect()
    };
    assert_eq!(names().len(), 1, "{:?}", names());
    write_file_atomically(&path, b"new").unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), b"new");
    assert_eq!(names().len(), 1, "{:?}", names());
}

/// A reader's own pixel bound (a texture's, an environment map's) is checked in the header:
/// the same file reads under a bound it fits and is refused, naming the claim, under one it
/// does not; and a film EXR's many channels (beauty, variance, count: 7 samples a pixel) are
/// counted against four channels' worth of the bound.
#[test]
fn reader_bounds_are_checked_from_the_header() {
    let (w, h) = (8, 4);
    let beauty = test_image(w, h, 3);
    let variance = test_image(w, h, 4);
    let counts = vec![1.0; w * h];
    let (_dir, path) = scratch("bounded.exr");
    let out = FilmOutput {
        beauty: &beauty,
        variance: &variance,
        sample_count: &counts,
        albedo: None,
        normal: None,
        depth: None,
    };
    write_exr(&path, &out).unwrap();
    // 32 pixels, 7 channels = 224 samples: fits a bound of 56 pixels (224 samples).
    assert_eq!(read_exr_rgb_within(&path, 56).unwrap(), beauty);
    let e = read_exr_rgb_within(&path, 31).unwrap_err().to_string();
    assert!(e.contains("8 x 4 pixels, more than the 31"), "{e}");
    let e = read_exr_rgb_within(&path, 55).unwrap_err().to_string();
    assert!(
        e.contains("224 samples") && e.contains("more than the 220"),
        "{e}"
    );
}

/// A FIFO or a directory given as an EXR (a texture, an environment map, a part to merge)
/// is refused before it is opened: opening a FIFO would block until a writer came.
#[cfg(unix)]
#[test]
fn special_files_are_refused_before_opening() {
    let dir = crate::scratch_dir::ScratchDir::new("exr-special");
    let fifo = dir.join("pipe.exr");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if made.is_ok_and(|s| s.success()) {
        let e = exr_part_names(&fifo).unwrap_err().to_string();
        assert!(
            e.contains("pipe.exr") && e.contains("not a regular file"),
            "{e}"
        );
        let e = read_exr_rgb(&fifo).unwrap_err().to_string();
        assert!(
            e.contains("pipe.exr") && e.contains("not a regular file"),
            "{e}"
        );
    }
    let e = read_exr_rgb(&dir.join(".")).unwrap_err().to_string();
    assert!(e.contains("not a regular file"), "{e}");
}
