//! Spectra to linear Rec.709 RGB, as Mitsuba 3's RGB variants convert them.
//!
//! Scene formats written for spectral renderers give colours as sampled spectra
//! (`<spectrum value="400:0.1, 500:0.5, 700:0.9"/>` in Mitsuba XML, `"spectrum Kd" [...]`
//! in pbrt) or blackbody temperatures. risotto renders in RGB, so an importer converts
//! each spectrum once, here, the way Mitsuba 3's RGB variants do when they load one
//! (`spectrum_list_to_srgb` in Mitsuba 3's `src/core/spectrum.cpp`, checked against
//! Mitsuba 3.9.1 itself: see the tests):
//!
//! - the spectrum is linear between its samples and zero outside them;
//! - XYZ is its integral against the CIE 1931 2° colour-matching functions over 360–830 nm,
//!   by a 1000-point Riemann sum, divided by ∫ȳ (so a unit spectrum has luminance 1);
//! - a **reflectance** (anything not emitted: albedos, reflectances, and in Mitsuba also
//!   media coefficients) is weighted by the D65 illuminant (normalised to unit luminance)
//!   before integrating, so a flat spectrum of value `v` gives RGB `(v, v, v)`; the result
//!   is clamped to [0, 1];
//! - an **emission** is integrated as given (equal-energy white is then slightly pink in
//!   Rec.709: a flat spectrum of 1 gives ≈ (1.205, 0.948, 0.909)); negative channels are
//!   clamped to 0;
//! - **unbounded** (not a Mitsuba case; for formats whose non-emitted coefficients may
//!   exceed 1, pbrt's `sigma_a`) is weighted like a reflectance and clamped at 0 only.
//!
//! XYZ to RGB is the Rec.709 / sRGB primaries with a D65 white point (IEC 61966-2-1; the
//! matrix Mitsuba's `xyz_to_srgb` uses).

/// What a spectrum describes, which decides how it becomes RGB (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpectrumUse {
    /// A reflectance or albedo: D65-weighted, clamped to [0, 1].
    Reflectance,
    /// Emitted radiance, intensity or irradiance: unweighted, clamped at 0.
    Emission,
    /// A non-emitted coefficient that may exceed 1: D65-weighted, clamped at 0.
    Unbounded,
}

/// First wavelength of the CIE tables, nm.
const CIE_MIN: f64 = 360.0;
/// Last wavelength of the CIE tables, nm.
const CIE_MAX: f64 = 830.0;
/// Samples in the CIE tables (every 5 nm from [`CIE_MIN`] to [`CIE_MAX`]).
const CIE_SAMPLES: usize = 95;
/// Points of the Riemann sum over [`CIE_MIN`, `CIE_MAX`] (Mitsuba's choice, kept so the
/// conversion agrees with it to float precision).
const STEPS: usize = 1000;
/// ∫ȳ(λ) dλ as Mitsuba normalises it (`MI_CIE_Y_NORMALIZATION`), nm.
const CIE_Y_INTEGRAL: f64 = 106.750_259_399_414_06;
/// ∫ D65(λ) ȳ(λ) dλ / ∫ ȳ(λ) dλ with D65 as tabulated below (relative power 100 at
/// 560 nm): dividing D65 by it gives a unit-luminance illuminant (`MI_CIE_D65_NORMALIZATION`).
const D65_LUMINANCE: f64 = 98.997_417_518_762_55;
/// The largest number of samples a spectrum may have (bounds work on hostile input).
pub const MAX_SPECTRUM_SAMPLES: usize = 100_000;

/// The CIE 1931 2° standard observer colour-matching functions x̄, ȳ, z̄ at 5 nm from 360 to
/// 830 nm: CIE 015:2004 "Colorimetry", table T.4 (also CVRL, cvrl.ioo.ucl.ac.uk, "CIE 1931
/// 2-deg, XYZ CMFs"), at single precision as Mitsuba 3 stores them.
const CIE_1931_XYZ: [[f64; 3]; CIE_SAMPLES] = [
    [0.0001299, 3.917e-6, 0.0006061],    // 360 nm
    [0.0002321, 6.965e-6, 0.001086],     // 365 nm
    [0.0004149, 1.239e-5, 0.001946],     // 370 nm
    [0.0007416, 2.202e-5, 0.003486],     // 375 nm
    [0.001368, 3.9e-5, 0.006450001],     // 380 nm
    [0.002236, 6.4e-5, 0.01054999],      // 385 nm
    [0.004243, 0.00012, 0.02005001],     // 390 nm
    [0.00765, 0.000217, 0.03621],        // 395 nm
    [0.01431, 0.000396, 0.06785001],     // 400 nm
    [0.02319, 0.00064, 0.1102],          // 405 nm
    [0.04351, 0.00121, 0.2074],          // 410 nm
    [0.07763, 0.00218, 0.3713],          // 415 nm
    [0.13438, 0.004, 0.6456],            // 420 nm
    [0.21477, 0.0073, 1.0390501],        // 425 nm
    [0.2839, 0.0116, 1.3856],            // 430 nm
    [0.3285, 0.01684, 1.62296],          // 435 nm
    [0.34828, 0.023, 1.74706],           // 440 nm
    [0.34806, 0.0298, 1.7826],           // 445 nm
    [0.3362, 0.038, 1.77211],            // 450 nm
    [0.3187, 0.048, 1.7441],             // 455 nm
    [0.2908, 0.06, 1.6692],              // 460 nm
    [0.2511, 0.0739, 1.5281],            // 465 nm
    [0.19536, 0.09098, 1.28764],         // 470 nm
    [0.1421, 0.1126, 1.0419],            // 475 nm
    [0.09564, 0.13902, 0.8129501],       // 480 nm
    [0.05795001, 0.1693, 0.6162],        // 485 nm
    [0.03201, 0.20802, 0.46518],         // 490 nm
    [0.0147, 0.2586, 0.3533],            // 495 nm
    [0.0049, 0.323, 0.272],              // 500 nm
    [0.0024, 0.4073, 0.2123],            // 505 nm
    [0.0093, 0.503, 0.1582],             // 510 nm
    [0.0291, 0.6082, 0.1117],            // 515 nm
    [0.06327, 0.71, 0.07824999],         // 520 nm
    [0.1096, 0.7932, 0.05725001],        // 525 nm
    [0.1655, 0.862, 0.04216],            // 530 nm
    [0.2257499, 0.9148501, 0.02984],     // 535 nm
    [0.2904, 0.954, 0.0203],             // 540 nm
    [0.3597, 0.9803, 0.0134],            // 545 nm
    [0.4334499, 0.9949501, 0.008749999], // 550 nm
    [0.5120501, 1.0, 0.005749999],       // 555 nm
    [0.5945, 0.995, 0.0039],             // 560 nm
    [0.6784, 0.9786, 0.002749999],       // 565 nm
    [0.7621, 0.952, 0.0021],             // 570 nm
    [0.8425, 0.9154, 0.0018],            // 575 nm
    [0.9163, 0.87, 0.001650001],         // 580 nm
    [0.9786, 0.8163, 0.0014],            // 585 nm
    [1.0263, 0.757, 0.0011],             // 590 nm
    [1.0567, 0.6949, 0.001],             // 595 nm
    [1.0622, 0.631, 0.0008],             // 600 nm
    [1.0456, 0.5668, 0.0006],            // 605 nm
    [1.0026, 0.503, 0.00034],            // 610 nm
    [0.9384, 0.4412, 0.00024],           // 615 nm
    [0.8544499, 0.381, 0.00019],         // 620 nm
    [0.7514, 0.321, 1e-4],               // 625 nm
    [0.6424, 0.265, 4.999999e-5],        // 630 nm
    [0.5419, 0.217, 3e-5],               // 635 nm
    [0.4479, 0.175, 2e-5],               // 640 nm
    [0.3608, 0.1382, 1e-5],              // 645 nm
    [0.2835, 0.107, 0.0],                // 650 nm
    [0.2187, 0.0816, 0.0],               // 655 nm
    [0.1649, 0.061, 0.0],                // 660 nm
    [0.1212, 0.04458, 0.0],              // 665 nm
    [0.0874, 0.032, 0.0],                // 670 nm
    [0.0636, 0.0232, 0.0],               // 675 nm
    [0.04677, 0.017, 0.0],               // 680 nm
    [0.0329, 0.01192, 0.0],              // 685 nm
    [0.0227, 0.00821, 0.0],              // 690 nm
    [0.01584, 0.005723, 0.0],            // 695 nm
    [0.01135916, 0.004102, 0.0],         // 700 nm
    [0.008110916, 0.002929, 0.0],        // 705 nm
    [0.005790346, 0.002091, 0.0],        // 710 nm
    [0.004109457, 0.001484, 0.0],        // 715 nm
    [0.002899327, 0.001047, 0.0],        // 720 nm
    [0.00204919, 0.00074, 0.0],          // 725 nm
    [0.001439971, 0.00052, 0.0],         // 730 nm
    [0.0009999493, 0.0003611, 0.0],      // 735 nm
    [0.0006900786, 0.0002492, 0.0],      // 740 nm
    [0.0004760213, 0.0001719, 0.0],      // 745 nm
    [0.0003323011, 0.00012, 0.0],        // 750 nm
    [0.0002348261, 8.48e-5, 0.0],        // 755 nm
    [0.0001661505, 6e-5, 0.0],           // 760 nm
    [0.000117413, 4.24e-5, 0.0],         // 765 nm
    [8.307527e-5, 3e-5, 0.0],            // 770 nm
    [5.870652e-5, 2.12e-5, 0.0],         // 775 nm
    [4.150994e-5, 1.499e-5, 0.0],        // 780 nm
    [2.935326e-5, 1.06e-5, 0.0],         // 785 nm
    [2.067383e-5, 7.4657e-6, 0.0],       // 790 nm
    [1.455977e-5, 5.2578e-6, 0.0],       // 795 nm
    [1.025398e-5, 3.7029e-6, 0.0],       // 800 nm
    [7.221456e-6, 2.6078e-6, 0.0],       // 805 nm
    [5.085868e-6, 1.8366e-6, 0.0],       // 810 nm
    [3.581652e-6, 1.2934e-6, 0.0],       // 815 nm
    [2.522525e-6, 9.1093e-7, 0.0],       // 820 nm
    [1.776509e-6, 6.4153e-7, 0.0],       // 825 nm
    [1.251141e-6, 4.5181e-7, 0.0],       // 830 nm
];
/// CIE standard illuminant D65, relative spectral power (100 at 560 nm) at 5 nm from 360
/// to 830 nm: CIE 015:2004, table T.1 (ISO 11664-2).
const D65: [f64; CIE_SAMPLES] = [
    46.6383, 49.3637, 52.0891, 51.0323, 49.9755, 52.3118, 54.6482, 68.7015, // 360 nm ..
    82.7549, 87.1204, 91.486, 92.4589, 93.4318, 90.057, 86.6823, 95.7736, // 400 nm ..
    104.865, 110.936, 117.008, 117.41, 117.812, 116.336, 114.861, 115.392, // 440 nm ..
    115.923, 112.367, 108.811, 109.082, 109.354, 108.578, 107.802, 106.296, // 480 nm ..
    104.79, 106.239, 107.689, 106.047, 104.405, 104.225, 104.046, 102.023, // 520 nm ..
    100.0, 98.1671, 96.3342, 96.0611, 95.788, 92.2368, 88.6856, 89.3459, // 560 nm ..
    90.0062, 89.8026, 89.5991, 88.6489, 87.6987, 85.4936, 83.2886, 83.4939, // 600 nm ..
    83.6992, 81.863, 80.0268, 80.1207, 80.2146, 81.2462, 82.2778, 80.281, // 640 nm ..
    78.2842, 74.0027, 69.7213, 70.6652, 71.6091, 72.979, 74.349, 67.9765, // 680 nm ..
    61.604, 65.7448, 69.8856, 72.4863, 75.087, 69.3398, 63.5927, 55.0054, // 720 nm ..
    46.4182, 56.6118, 66.8054, 65.0941, 63.3828, 63.8434, 64.304, 61.8779, // 760 nm ..
    59.4519, 55.7054, 51.959, 54.6998, 57.4406, 58.8765, 60.3125, // 800 nm .. 830 nm
];
/// The CIE 1931 colour-matching functions (x̄, ȳ, z̄) at `lambda_nm`, linear between the
/// 5 nm samples, zero outside 360–830 nm.
pub fn cie_xyz(lambda_nm: f64) -> [f64; 3] {
    match table_position(lambda_nm) {
        Some((i, t)) => {
            let (a, b) = (CIE_1931_XYZ[i], CIE_1931_XYZ[i + 1]);
            [0, 1, 2].map(|c| a[c] + t * (b[c] - a[c]))
        }
        None => [0.0; 3],
    }
}

/// D65's relative power at `lambda_nm` divided by its luminance (so it integrates to
/// luminance 1), linear between samples, zero outside 360–830 nm.
fn d65_normalised(lambda_nm: f64) -> f64 {
    match table_position(lambda_nm) {
        Some((i, t)) => (D65[i] + t * (D65[i + 1] - D65[i])) / D65_LUMINANCE,
        None => 0.0,
    }
}

/// The table interval holding `lambda_nm` and the position in it, `None` outside the
/// tables (or for NaN).
fn table_position(lambda_nm: f64) -> Option<(usize, f64)> {
    if !(CIE_MIN..=CIE_MAX).contains(&lambda_nm) {
        return None;
    }
    let t = (lambda_nm - CIE_MIN) * ((CIE_SAMPLES - 1) as f64 / (CIE_MAX - CIE_MIN));
    // In range, so t is in [0, 94]; the last interval also takes t = 94 exactly.
    let i = (t as usize).min(CIE_SAMPLES - 2);
    Some((i, t - i as f64))
}

/// CIE XYZ to linear Rec.709 (sRGB primaries, D65 white; IEC 61966-2-1, the matrix
/// Mitsuba 3's `xyz_to_srgb` uses).
pub fn xyz_to_linear_srgb(xyz: [f64; 3]) -> [f64; 3] {
    const M: [[f64; 3]; 3] = [
        [3.240479, -1.537150, -0.498535],
        [-0.969256, 1.875991, 0.041556],
        [0.055648, -0.204043, 1.057311],
    ];
    M.map(|row| row[0] * xyz[0] + row[1] * xyz[1] + row[2] * xyz[2])
}

/// A sampled spectrum — `(wavelength in nm, value)` pairs in increasing wavelength — as
/// linear Rec.709 RGB for `use_` (see the module docs). A single pair is a constant
/// spectrum over its one wavelength only (Mitsuba's rule), so callers give a uniform value
/// as RGB directly. Errors: no samples, too many, a non-finite number, wavelengths not
/// strictly increasing.
pub fn sampled_to_rgb(samples: &[(f64, f64)], use_: SpectrumUse) -> Result<[f64; 3], String> {
    if samples.is_empty() {
        return Err("a spectrum needs at least one wavelength:value pair".into());
    }
    if samples.len() > MAX_SPECTRUM_SAMPLES {
        return Err(format!(
            "a spectrum of {} samples is more than the {MAX_SPECTRUM_SAMPLES} allowed",
            samples.len()
        ));
    }
    if let Some((l, v)) = samples
        .iter()
        .find(|(l, v)| !l.is_finite() || !v.is_finite())
    {
        return Err(format!("spectrum sample {l}:{v} is not a finite number"));
    }
    if let Some(w) = samples.windows(2).find(|w| w[1].0 <= w[0].0) {
        return Err(format!(
            "spectrum wavelengths must increase: {} nm is followed by {} nm",
            w[0].0, w[1].0
        ));
    }
    let (first, last) = (samples[0].0, samples[samples.len() - 1].0);
    let mut xyz = [0.0; 3];
    for k in 0..STEPS {
        let lambda = CIE_MIN + (k as f64 / (STEPS - 1) as f64) * (CIE_MAX - CIE_MIN);
        if lambda < first || lambda > last {
            continue;
        }
        // The interval [i, i + 1] holding lambda (the last one for lambda == last).
        let i = samples
            .partition_point(|s| s.0 <= lambda)
            .saturating_sub(1)
            .min(samples.len().saturating_sub(2));
        let value = if samples.len() == 1 {
            samples[0].1
        } else {
            let ((l0, v0), (l1, v1)) = (samples[i], samples[i + 1]);
            v0 + (lambda - l0) / (l1 - l0) * (v1 - v0)
        };
        let weight = match use_ {
            SpectrumUse::Emission => value,
            SpectrumUse::Reflectance | SpectrumUse::Unbounded => value * d65_normalised(lambda),
        };
        let cmf = cie_xyz(lambda);
        for c in 0..3 {
            xyz[c] += cmf[c] * weight;
        }
    }
    let scale = (CIE_MAX - CIE_MIN) / STEPS as f64 / CIE_Y_INTEGRAL;
    let rgb = xyz_to_linear_srgb(xyz.map(|x| x * scale));
    Ok(match use_ {
        SpectrumUse::Reflectance => rgb.map(|c| c.clamp(0.0, 1.0)),
        SpectrumUse::Emission | SpectrumUse::Unbounded => rgb.map(|c| c.max(0.0)),
    })
}

/// A blackbody at `kelvin` as linear Rec.709 RGB for `use_`: Planck's spectral radiance in
/// W m⁻² sr⁻¹ nm⁻¹ (Mitsuba 3's `blackbody` spectrum, whose spectral variants emit exactly
/// this; its RGB variants refuse a blackbody, so the conversion is what a spectral render
/// shows in RGB), converted as [`sampled_to_rgb`] converts a spectrum. A 5000 K blackbody is
/// ≈ 1.27·10⁴ at 550 nm: emitters using one usually scale it down. Errors: a temperature
/// that is not a positive finite number.
pub fn blackbody_rgb(kelvin: f64, use_: SpectrumUse) -> Result<[f64; 3], String> {
    if !(kelvin.is_finite() && kelvin > 0.0) {
        return Err(format!(
            "blackbody temperature {kelvin} K is not a positive number"
        ));
    }
    // Sampled at 1 nm over the CIE range: the linear interpolation between samples then
    // differs from Planck's curve by far less than float precision in the result.
    let samples: Vec<(f64, f64)> = (0..=(CIE_MAX - CIE_MIN) as usize)
        .map(|k| {
            let lambda = CIE_MIN + k as f64;
            (lambda, planck(lambda, kelvin))
        })
        .collect();
    sampled_to_rgb(&samples, use_)
}

/// Planck's law: the spectral radiance of a blackbody at `kelvin`, W m⁻² sr⁻¹ nm⁻¹,
/// B(λ, T) = 2hc² / λ⁵ / (exp(hc / (λ k T)) − 1) (λ in metres, then per nm).
fn planck(lambda_nm: f64, kelvin: f64) -> f64 {
    // CODATA 2018 exact values.
    const C: f64 = 2.997_924_58e8;
    const H: f64 = 6.626_070_15e-34;
    const K: f64 = 1.380_649e-23;
    let lambda = lambda_nm * 1e-9;
    let per_metre = 2.0 * H * C * C / lambda.powi(5) / (H * C / (lambda * K * kelvin)).exp_m1();
    per_metre * 1e-9
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
        a.iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() <= tol * y.abs().max(1e-3))
    }

    /// Values printed by Mitsuba 3.9.1 (`scalar_rgb`): `mi.load_string` of a diffuse
    /// `reflectance`, an area `radiance` and a point `intensity` given as each spectrum,
    /// then `mi.traverse(...)[...value]` (script in the commit message of this file).
    #[test]
    fn sampled_spectra_convert_as_mitsuba_3_does() {
        // (spectrum, Mitsuba's reflectance RGB, Mitsuba's emission RGB)
        type Case<'a> = (&'a [(f64, f64)], [f64; 3], [f64; 3]);
        let cases: &[Case] = &[
            (
                &[(400.0, 0.1), (500.0, 0.5), (700.0, 0.9)],
                [0.775405, 0.593508, 0.277033],
                [0.917922, 0.565488, 0.241605],
            ),
            (
                &[(400.0, 0.1), (500.0, 0.8), (600.0, 0.2), (700.0, 0.9)],
                [0.181677, 0.57158, 0.475121],
                [0.270751, 0.53672, 0.422007],
            ),
            (
                &[(360.0, 1.0), (830.0, 1.0)],
                [0.998985, 0.998874, 0.998802],
                [1.20488, 0.948228, 0.909267],
            ),
            // Out of gamut: Mitsuba clamps (reflectance to [0, 1], emission at 0).
            (
                &[(450.0, 1.0), (550.0, 1.0), (650.0, 1.0)],
                [0.841254, 1.0, 0.500249],
                [1.02256, 1.02191, 0.412319],
            ),
            (
                &[(550.0, 1.0), (560.0, 1.0)],
                [0.0124793, 0.137198, 0.0],
                [0.0122891, 0.133081, 0.0],
            ),
            (
                &[(300.0, 2.0), (900.0, 2.0)],
                [1.0, 1.0, 1.0],
                [2.40977, 1.89646, 1.81853],
            ),
        ];
        for (samples, reflectance, emission) in cases {
            let r = sampled_to_rgb(samples, SpectrumUse::Reflectance).unwrap();
            let e = sampled_to_rgb(samples, SpectrumUse::Emission).unwrap();
            assert!(
                close(r, *reflectance, 2e-5),
                "{samples:?}: {r:?} vs {reflectance:?}"
            );
            assert!(
                close(e, *emission, 2e-5),
                "{samples:?}: {e:?} vs {emission:?}"
            );
        }
        // Unbounded: the reflectance weighting without the clamp at 1.
        let u = sampled_to_rgb(&[(300.0, 2.0), (900.0, 2.0)], SpectrumUse::Unbounded).unwrap();
        assert!(close(u, [1.99797, 1.99775, 1.9976], 2e-5), "{u:?}");
    }

    /// `mi.cie1931_xyz` of Mitsuba 3.9.1 at and between table samples, and zero outside.
    #[test]
    fn colour_matching_functions_are_the_cie_1931_tables() {
        assert_eq!(cie_xyz(600.0), [1.0622, 0.631, 0.0008]);
        assert!(close(
            cie_xyz(362.5),
            [0.000181, 5.441e-6, 0.00084605],
            1e-6
        ));
        assert_eq!(cie_xyz(830.0), [1.251141e-6, 4.5181e-7, 0.0]);
        assert_eq!(cie_xyz(359.0), [0.0; 3]);
        assert_eq!(cie_xyz(f64::NAN), [0.0; 3]);
        // ∫ȳ by the trapezoid rule on the 5 nm table is the luminance normalisation.
        let y: f64 = (0..CIE_SAMPLES - 1)
            .map(|i| 2.5 * (CIE_1931_XYZ[i][1] + CIE_1931_XYZ[i + 1][1]))
            .sum();
        assert!((y - CIE_Y_INTEGRAL).abs() < 0.2, "{y}");
    }

    /// The matrix maps D65's white point (x, y) = (0.3127, 0.3290) to equal RGB.
    #[test]
    fn d65_white_is_rgb_white() {
        let (x, y) = (0.3127, 0.3290);
        let rgb = xyz_to_linear_srgb([x / y, 1.0, (1.0 - x - y) / y]);
        assert!(close(rgb, [1.0, 1.0, 1.0], 1e-3), "{rgb:?}");
    }

    /// Planck at 5000 K against Mitsuba 3.9.1's `blackbody` (`scalar_spectral`,
    /// `eval` at 400, 500, 550, 700 nm: 8743.57, 12107.2, 12713, 11812), and the RGB of a
    /// hot blackbody is bluer than that of a cool one.
    #[test]
    fn blackbody_follows_planck_as_mitsuba_does() {
        for (l, v) in [
            (400.0, 8743.57),
            (500.0, 12107.2),
            (550.0, 12713.0),
            (700.0, 11812.0),
        ] {
            let p = planck(l, 5000.0);
            assert!((p - v).abs() / v < 1e-4, "{l}: {p} vs {v}");
        }
        let cool = blackbody_rgb(2000.0, SpectrumUse::Emission).unwrap();
        let hot = blackbody_rgb(10000.0, SpectrumUse::Emission).unwrap();
        assert!(
            cool[0] / cool[2] > 5.0 && hot[2] / hot[0] > 1.0,
            "{cool:?} {hot:?}"
        );
        // The luminance of the RGB is the luminance of the spectrum (Y = ∫ B ȳ / ∫ ȳ),
        // computed independently here by the trapezoid rule at 1 nm.
        let rgb = blackbody_rgb(5000.0, SpectrumUse::Emission).unwrap();
        let lum = 0.212671 * rgb[0] + 0.715160 * rgb[1] + 0.072169 * rgb[2];
        let y: f64 = (360..830)
            .map(|l| {
                let f = |l: f64| planck(l, 5000.0) * cie_xyz(l)[1];
                0.5 * (f(l as f64) + f(l as f64 + 1.0))
            })
            .sum::<f64>()
            / CIE_Y_INTEGRAL;
        assert!((lum - y).abs() / y < 5e-3, "{lum} vs {y}");
    }

    #[test]
    fn bad_spectra_are_errors_naming_the_value() {
        let r = SpectrumUse::Reflectance;
        assert!(sampled_to_rgb(&[], r).unwrap_err().contains("at least one"));
        let e = sampled_to_rgb(&[(500.0, 1.0), (400.0, 1.0)], r).unwrap_err();
        assert!(e.contains("500 nm is followed by 400 nm"), "{e}");
        let e = sampled_to_rgb(&[(500.0, f64::NAN)], r).unwrap_err();
        assert!(e.contains("500:NaN"), "{e}");
        let e = blackbody_rgb(-5.0, r).unwrap_err();
        assert!(e.contains("-5 K"), "{e}");
    }
}
