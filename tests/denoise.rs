//! `render --denoise` (issue 35): Intel Open Image Denoise, guided by the albedo and normal
//! layers. Built only with the `denoise` feature (README, "Denoising"; `.ci/run` installs
//! the library and runs this file).
#![cfg(feature = "denoise")]

use risotto::components::Rgb;
use risotto::engine::output::{read_exr_rgb, Image};
use std::path::{Path, PathBuf};

mod common;
use common::cli::{ok, risotto};

fn dir() -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join("denoise");
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Channel `R`, `G`, `B` of part `part` of the EXR `path`.
fn part(path: &Path, part: &str) -> Vec<[f32; 3]> {
    let image = exr::prelude::read_all_flat_layers_from_file(path).unwrap();
    let layer = image
        .layer_data
        .iter()
        .find(|l| l.attributes.layer_name.as_ref().is_some_and(|n| n.eq(part)))
        .unwrap_or_else(|| panic!("no {part} part"));
    let channel = |name: &str| -> Vec<f32> {
        let c = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.eq(name))
            .unwrap();
        c.sample_data.values_as_f32().collect()
    };
    let (r, g, b) = (channel("R"), channel("G"), channel("B"));
    (0..r.len()).map(|i| [r[i], g[i], b[i]]).collect()
}

/// Mean squared error of `a` against `reference`, each channel's error divided by
/// `reference^2 + 0.01` when `relative` (relMSE, the error measure of denoising work, e.g.
/// Rousselle et al. 2011: plain MSE of an HDR image is the error of its brightest pixels), or
/// of both images clamped to `[0, 1]` (the error of the displayed image) when not.
fn error(a: &[[f32; 3]], reference: &Image, relative: bool) -> f64 {
    assert_eq!(a.len(), reference.pixels.len());
    let sum: f64 = a
        .iter()
        .zip(&reference.pixels)
        .flat_map(|(p, q)| {
            let q = q.to_array();
            (0..3).map(move |c| {
                let (x, y) = (p[c] as f64, q[c] as f64);
                if relative {
                    (x - y).powi(2) / (y * y + 0.01)
                } else {
                    (x.min(1.0) - y.min(1.0)).powi(2)
                }
            })
        })
        .sum();
    sum / (3 * a.len()) as f64
}

/// At 4 spp on cornell the denoised image is far closer to Mitsuba's converged reference
/// than the noisy one (the check), and the EXR's beauty is the noisy image itself,
/// bit for bit the render without `--denoise`.
#[test]
fn cornell_at_4_spp_denoises_far_closer_to_the_reference() {
    let d = dir();
    let render = |name: &str, extra: &[&str]| {
        let out = d.join(name);
        let mut args = vec![
            "render",
            "scenes/mitsuba-suite/cornell.toml",
            "--size",
            "64x64",
            "--spp",
            "4",
            "-t",
            "2",
            "--quiet",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        ok("render", risotto(&args));
        out
    };
    let denoised_exr = render("cornell-denoised.exr", &["--denoise"]);
    let plain_exr = render("cornell-plain.exr", &[]);
    let reference = read_exr_rgb(Path::new("tests/data/cornell-mitsuba-64.exr")).unwrap();
    let noisy = part(&denoised_exr, "beauty");
    assert_eq!(
        noisy,
        part(&plain_exr, "beauty"),
        "--denoise changed the beauty"
    );
    let denoised = part(&denoised_exr, "denoised");
    // Measured (64x64, 4 spp): relMSE 4.8e-2 noisy, 6.5e-3 denoised; display MSE 1.5e-3 and
    // 2.5e-4. Plain linear MSE is *not* lower (9.2e-3 noisy, 2.0e-2 denoised): it is the
    // error of the light's edge pixels (radiance ~17 times a coverage of 0 to 4 samples),
    // which any filter trades against its neighbours'.
    for relative in [true, false] {
        let (noisy_error, denoised_error) = (
            error(&noisy, &reference, relative),
            error(&denoised, &reference, relative),
        );
        let name = if relative { "relMSE" } else { "display MSE" };
        assert!(
            denoised_error < noisy_error / 4.0,
            "denoised {name} {denoised_error:.3e} is not far below the noisy {noisy_error:.3e}"
        );
    }
    // The PNG preview is the denoised image: it differs from the plain render's.
    let png = |p: &Path| std::fs::read(p.with_extension("png")).unwrap();
    assert_ne!(png(&denoised_exr), png(&plain_exr));
}

/// The library call takes white noise off a flat grey wall (a denoiser that invented
/// structure or shifted the level would fail), keeps the image's size and refuses guide
/// layers of another size.
#[test]
fn noise_on_a_flat_image_is_removed_and_mismatched_layers_are_refused() {
    let (w, h) = (128, 128);
    let flat = |v: f32| Image::from_pixels(w, h, vec![Rgb::new(v, v, v); w * h]);
    // 0.5 +- up to 0.25, independent per pixel and channel (a fixed xorshift stream).
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut noise = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
    };
    let noisy = Image::from_pixels(
        w,
        h,
        (0..w * h)
            .map(|_| {
                Rgb::new(
                    0.5 + 0.5 * noise(),
                    0.5 + 0.5 * noise(),
                    0.5 + 0.5 * noise(),
                )
            })
            .collect(),
    );
    let albedo = flat(0.8);
    let normal = Image::from_pixels(w, h, vec![Rgb::new(0.0, 0.0, 1.0); w * h]);
    let out = risotto::denoise::denoise(&noisy, &albedo, &normal).unwrap();
    assert_eq!((out.width, out.height, out.pixels.len()), (w, h, w * h));
    let squared_error = |img: &Image| -> f64 {
        let sum: f64 = img
            .pixels
            .iter()
            .flat_map(|p| p.to_array())
            .map(|c| (c as f64 - 0.5).powi(2))
            .sum();
        sum / (3 * w * h) as f64
    };
    let mean = out
        .pixels
        .iter()
        .map(|p| p.to_array().iter().sum::<f32>() as f64)
        .sum::<f64>()
        / (3 * w * h) as f64;
    let (before, after) = (squared_error(&noisy), squared_error(&out));
    assert!(
        after < before / 20.0,
        "squared error {before:.3e} -> {after:.3e}"
    );
    assert!((mean - 0.5).abs() < 0.01, "mean {mean}");
    let small = Image::from_pixels(2, 2, vec![Rgb::new(0.5, 0.5, 0.5); 4]);
    let err = risotto::denoise::denoise(&noisy, &small, &normal).unwrap_err();
    assert!(err.to_string().contains("albedo layer is 2x2"), "{err}");
}
