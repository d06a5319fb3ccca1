//! Mitsuba 3's render z-test (`src/render/tests/test_render.py` of mitsuba3, `z_test` and the
//! acceptance rule of `test_render`), so that a risotto render of one of Mitsuba's own test
//! scenes is judged exactly as Mitsuba judges its own renders.
//!
//! The reference is a mean image `r` and a per-sample variance image `v` (Mitsuba's `moment`
//! integrator: second moment minus squared mean), both stored as RGB. Mitsuba compares in
//! CIE XYZ: the test image, the reference and the variance image are each taken to XYZ with
//! the linear sRGB matrix (for the variance this undoes the XYZ -> RGB conversion its
//! reference script applied when it wrote the file). Then, per pixel and channel,
//!
//! - `z = |t - r| * sqrt(spp / max(v, 1e-4))` with `spp` the test render's samples per pixel,
//! - `p = 2 (1 - Phi(z)) = erfc(z / sqrt(2))`,
//!
//! and an entry passes when `p > alpha`, where `alpha = 1 - (1 - 0.01)^(1 / pixels)` is the
//! Sidak-corrected significance level over the image's pixels. The render is accepted when at
//! least 99.75 % of the pixels pass, counted as passing entries over three. Mitsuba's test
//! renders `2e6 / pixels` samples per pixel ([`mitsuba_test_spp`]).
//!
//! The test assumes the renders' per-sample variance is the reference's; a renderer whose
//! estimator is noisier than Mitsuba's fails it even when unbiased, one that converges faster
//! (risotto's low-discrepancy sampler) passes more easily.

use risotto_components::Rgb;
use risotto_engine::output::Image;

/// Mitsuba's significance level before the Sidak correction.
pub const MITSUBA_SIGNIFICANCE: f64 = 0.01;
/// The fraction of pixels that must pass for the render to be accepted.
pub const MITSUBA_PASS_FRACTION: f64 = 0.9975;
/// Mitsuba's floor on the reference variance ("sanitize the variance images").
pub const MITSUBA_VARIANCE_FLOOR: f64 = 1e-4;
/// Mitsuba's sample budget per test render, spread evenly over the pixels.
pub const MITSUBA_SAMPLE_BUDGET: u64 = 2_000_000;

/// Samples per pixel of Mitsuba's test render of a `width` x `height` image: the sample
/// budget divided by the pixel count (integer division, as Mitsuba's `sample_budget //
/// pixel_count`), at least 1.
pub fn mitsuba_test_spp(width: usize, height: usize) -> u32 {
    let pixels = (width as u64 * height as u64).max(1);
    (MITSUBA_SAMPLE_BUDGET / pixels).clamp(1, u32::MAX as u64) as u32
}

/// The outcome of [`mitsuba_z_test`].
#[derive(Clone, Debug, PartialEq)]
pub struct ZTestOutcome {
    /// Pixels of the image.
    pub pixels: usize,
    /// Pixel-channel entries whose p-value exceeds `alpha`.
    pub passing_entries: usize,
    /// `passing_entries / 3 / pixels`: compared with [`MITSUBA_PASS_FRACTION`].
    pub passing_fraction: f64,
    /// The Sidak-corrected significance level per entry.
    pub alpha: f64,
    /// The smallest p-value, with its pixel `(x, y)` and XYZ channel (0, 1, 2).
    pub min_p_value: (f64, usize, usize, usize),
    /// Whether Mitsuba would accept the render.
    pub accepted: bool,
}

impl std::fmt::Display for ZTestOutcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (p, x, y, c) = self.min_p_value;
        write!(
            f,
            "{} the null hypothesis: {:.3} % of {} pixels pass (need {:.2} %), alpha {:.3e}, \
             min p-value {:.3e} at pixel ({x}, {y}) channel {}",
            if self.accepted {
                "accepted"
            } else {
                "rejected"
            },
            100.0 * self.passing_fraction,
            self.pixels,
            100.0 * MITSUBA_PASS_FRACTION,
            self.alpha,
            p,
            ["X", "Y", "Z"][c]
        )
    }
}

/// Linear sRGB (Rec. 709 primaries, D65) to CIE XYZ, the matrix of Mitsuba's
/// `srgb_to_xyz` (and of IEC 61966-2-1).
fn rgb_to_xyz(c: Rgb) -> [f64; 3] {
    let (r, g, b) = (c.r as f64, c.g as f64, c.b as f64);
    [
        0.412453 * r + 0.357580 * g + 0.180423 * b,
        0.212671 * r + 0.715160 * g + 0.072169 * b,
        0.019334 * r + 0.119193 * g + 0.950227 * b,
    ]
}

/// The complementary error function with a relative error below `1.2e-7` everywhere
/// (Press et al., *Numerical Recipes*, 2nd ed., sec. 6.2, the Chebyshev fit `erfcc`): the
/// z-test's p-values are tiny (the Sidak level of a 48 x 48 image is 4.4e-6), so an
/// approximation with an *absolute* error bound would not do.
pub fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * poly.exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// Mitsuba's z-test of `image` (rendered with `spp` samples per pixel) against `reference`
/// and its per-sample variance `reference_variance` (module docs). Errors when the sizes
/// differ or an image is empty.
pub fn mitsuba_z_test(
    image: &Image,
    spp: u32,
    reference: &Image,
    reference_variance: &Image,
) -> Result<ZTestOutcome, String> {
    for (what, other) in [("reference", reference), ("variance", reference_variance)] {
        if (other.width, other.height) != (image.width, image.height) {
            return Err(format!(
                "z-test: the image is {}x{} but the {what} is {}x{}",
                image.width, image.height, other.width, other.height
            ));
        }
    }
    let pixels = image.width * image.height;
    if pixels == 0 {
        return Err("z-test: the image is empty".to_string());
    }
    // Sidak: 1 - (1 - s)^(1/n), written with ln_1p / expm1 to keep its digits for large n.
    let alpha = -((-MITSUBA_SIGNIFICANCE).ln_1p() / pixels as f64).exp_m1();
    let mut passing_entries = 0;
    let mut min_p_value = (f64::INFINITY, 0, 0, 0);
    for (i, ((t, r), v)) in image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .zip(&reference_variance.pixels)
        .enumerate()
    {
        let (t, r, v) = (rgb_to_xyz(*t), rgb_to_xyz(*r), rgb_to_xyz(*v));
        for c in 0..3 {
            let z = (t[c] - r[c]).abs() * (spp as f64 / v[c].max(MITSUBA_VARIANCE_FLOOR)).sqrt();
            // A NaN in the test image has no p-value and fails, as in numpy's `p > alpha`.
            let p = erfc(z / std::f64::consts::SQRT_2);
            if p > alpha {
                passing_entries += 1;
            }
            if p.is_nan() || (!min_p_value.0.is_nan() && p < min_p_value.0) {
                min_p_value = (p, i % image.width, i / image.width, c);
            }
        }
    }
    let passing_fraction = passing_entries as f64 / 3.0 / pixels as f64;
    Ok(ZTestOutcome {
        pixels,
        passing_entries,
        passing_fraction,
        alpha,
        min_p_value,
        accepted: passing_fraction >= MITSUBA_PASS_FRACTION,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erfc_matches_tabulated_values() {
        // Abramowitz and Stegun table 7.1 / high-precision values.
        for (x, want) in [
            (0.0, 1.0),
            (0.5, 0.479_500_122_186_953_5),
            (1.0, 0.157_299_207_050_285_1),
            (2.0, 4.677_734_981_047_266e-3),
            (3.0, 2.209_049_699_858_544e-5),
            (4.0, 1.541_725_790_028_002e-8),
            (5.0, 1.537_459_794_428_035e-12),
            (-1.0, 1.842_700_792_949_715),
        ] {
            let got = erfc(x);
            assert!(
                ((got - want) / want).abs() < 1.2e-7,
                "erfc({x}) = {got}, want {want}"
            );
        }
    }

    fn flat(w: usize, h: usize, v: f32) -> Image {
        Image::filled(w, h, Rgb::new(v, v, v))
    }

    #[test]
    fn sidak_level_and_spp_are_mitsubas() {
        assert_eq!(mitsuba_test_spp(48, 48), 868);
        assert_eq!(mitsuba_test_spp(200, 120), 83);
        let o = mitsuba_z_test(
            &flat(48, 48, 0.5),
            868,
            &flat(48, 48, 0.5),
            &flat(48, 48, 1.0),
        )
        .unwrap();
        // 1 - 0.99^(1/2304), by the binomial series to first order: 0.01005 / 2304.
        assert!((o.alpha - 4.362_1e-6).abs() < 1e-9, "{}", o.alpha);
        assert!(o.accepted && o.passing_entries == 3 * 48 * 48);
    }

    #[test]
    fn a_shifted_image_is_rejected_and_noise_is_not() {
        let (w, h, spp) = (48, 48, 868);
        let reference = flat(w, h, 0.5);
        let variance = flat(w, h, 0.25);
        // Unbiased noise of the predicted size (sigma = sqrt(0.25 / spp)) passes: a
        // deterministic pseudo-normal sequence (sum of 12 uniforms) keeps the test repeatable.
        let sigma = (0.25f64 / spp as f64).sqrt();
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let pixels = (0..w * h)
            .map(|_| {
                let n: f64 = (0..12).map(|_| uniform()).sum::<f64>() - 6.0;
                let v = (0.5 + sigma * n) as f32;
                Rgb::new(v, v, v)
            })
            .collect();
        let noisy = Image::from_pixels(w, h, pixels);
        let o = mitsuba_z_test(&noisy, spp, &reference, &variance).unwrap();
        assert!(o.accepted, "{o}");
        // A bias of 5 sigma on every pixel fails nearly every entry.
        let shifted = flat(w, h, (0.5 + 5.0 * sigma) as f32);
        let o = mitsuba_z_test(&shifted, spp, &reference, &variance).unwrap();
        assert!(!o.accepted, "{o}");
        // So does a bias on 1 % of the pixels only (the 0.25 % allowance is exceeded).
        let mut spots = noisy.clone();
        for i in (0..w * h).step_by(97) {
            spots.pixels[i] = Rgb::new(0.7, 0.7, 0.7);
        }
        let o = mitsuba_z_test(&spots, spp, &reference, &variance).unwrap();
        assert!(!o.accepted, "{o}");
        // A NaN pixel fails its entries.
        let mut nan = flat(w, h, 0.5);
        nan.pixels[5] = Rgb::new(f32::NAN, 0.5, 0.5);
        let o = mitsuba_z_test(&nan, spp, &reference, &variance).unwrap();
        assert!(o.passing_entries < 3 * w * h && o.min_p_value.0.is_nan());
    }

    #[test]
    fn sizes_must_agree() {
        let e = mitsuba_z_test(&flat(4, 4, 1.0), 1, &flat(4, 5, 1.0), &flat(4, 4, 1.0));
        assert!(e.unwrap_err().contains("4x5"));
    }
}
