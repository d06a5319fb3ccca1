//! Image metrics against a reference, computed the way the Mitsuba harness's `rmse.py`
//! (`../shared/refs/mitsuba/rmse.py`) computes them, so numbers from either tool can be
//! compared directly.
//!
//! With `t` the test value and `r` the reference value of one channel of one pixel, and
//! only the entries where both are finite counted (`n` of them per channel):
//! - `rmse   = sqrt(sum (t - r)^2 / n)`
//! - `relmse = sum ((t - r)^2 / (r^2 + eps)) / n` (`eps` = 0.01 by default)
//! - `mae    = sum |t - r| / n`, `maxabs = max |t - r|`
//! - `mean_test`, `mean_ref`: means over the same entries; `mean_reldiff =
//!   (mean_test - mean_ref) / mean_ref` (NaN when `mean_ref` is 0).
//!
//! The overall numbers pool all three channels (`n` = all finite entries). Sums run in `f64`.

use std::fmt;

use risotto_engine::output::Image;

/// The `eps` of the relative MSE denominator `r^2 + eps`, as in `rmse.py`.
pub const DEFAULT_RELMSE_EPS: f64 = 0.01;

/// Metrics of one channel (or of all channels pooled, where the means are not defined).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct ChannelMetrics {
    /// Root mean squared error.
    pub rmse: f64,
    /// Mean of `(t - r)^2 / (r^2 + eps)`.
    pub relmse: f64,
    /// Mean absolute error.
    pub mae: f64,
    /// Largest absolute difference.
    pub maxabs: f64,
    /// Mean of the test image (finite entries only).
    pub mean_test: f64,
    /// Mean of the reference image (finite entries only).
    pub mean_ref: f64,
    /// `(mean_test - mean_ref) / mean_ref`; NaN when `mean_ref` is zero.
    pub mean_reldiff: f64,
}

/// The result of [`compare`].
#[derive(Clone, Debug, PartialEq)]
pub struct Metrics {
    /// Image size `(width, height)`.
    pub size: (usize, usize),
    /// Per-channel metrics, `[R, G, B]`.
    pub per_channel: [ChannelMetrics; 3],
    /// All channels pooled (its `mean_*` fields are the means over all channels).
    pub all: ChannelMetrics,
    /// NaN values (channel entries) in the test image.
    pub test_nan: usize,
    /// Infinite values in the test image.
    pub test_inf: usize,
    /// NaN values in the reference.
    pub ref_nan: usize,
    /// Infinite values in the reference.
    pub ref_inf: usize,
    /// The relMSE epsilon used.
    pub eps: f64,
}

/// The images cannot be compared.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum CompareError {
    /// Different dimensions.
    #[error("size mismatch: test is {test_w}x{test_h}, reference is {ref_w}x{ref_h}")]
    SizeMismatch {
        /// Test width.
        test_w: usize,
        /// Test height.
        test_h: usize,
        /// Reference width.
        ref_w: usize,
        /// Reference height.
        ref_h: usize,
    },
    /// An image's pixel vector does not match its dimensions.
    #[error("{which} image has {len} pixels for {w}x{h}")]
    Malformed {
        /// "test" or "reference".
        which: &'static str,
        /// Pixel count found.
        len: usize,
        /// Declared width.
        w: usize,
        /// Declared height.
        h: usize,
    },
}

/// Compares `test` against `reference` with the default relMSE epsilon (0.01).
pub fn compare(test: &Image, reference: &Image) -> Result<Metrics, CompareError> {
    compare_with_eps(test, reference, DEFAULT_RELMSE_EPS)
}

/// Compares `test` against `reference`; `eps` is the relMSE denominator's epsilon.
pub fn compare_with_eps(
    test: &Image,
    reference: &Image,
    eps: f64,
) -> Result<Metrics, CompareError> {
    if (test.width, test.height) != (reference.width, reference.height) {
        return Err(CompareError::SizeMismatch {
            test_w: test.width,
            test_h: test.height,
            ref_w: reference.width,
            ref_h: reference.height,
        });
    }
    for (which, img) in [("test", test), ("reference", reference)] {
        if img.pixels.len() != img.width * img.height {
            return Err(CompareError::Malformed {
                which,
                len: img.pixels.len(),
                w: img.width,
                h: img.height,
            });
        }
    }

    #[derive(Default, Clone, Copy)]
    struct Acc {
        n: u64,
        sq: f64,
        rel: f64,
        abs: f64,
        max: f64,
        sum_t: f64,
        sum_r: f64,
    }
    let mut acc = [Acc::default(); 3];
    let (mut test_nan, mut test_inf, mut ref_nan, mut ref_inf) = (0, 0, 0, 0);
    for (pt, pr) in test.pixels.iter().zip(&reference.pixels) {
        for (c, (t, r)) in pt.to_array().into_iter().zip(pr.to_array()).enumerate() {
            test_nan += usize::from(t.is_nan());
            test_inf += usize::from(t.is_infinite());
            ref_nan += usize::from(r.is_nan());
            ref_inf += usize::from(r.is_infinite());
            if !(t.is_finite() && r.is_finite()) {
                continue;
            }
            let (t, r) = (f64::from(t), f64::from(r));
            let d = t - r;
            let a = &mut acc[c];
            a.n += 1;
            a.sq += d * d;
            a.rel += d * d / (r * r + eps);
            a.abs += d.abs();
            a.max = a.max.max(d.abs());
            a.sum_t += t;
            a.sum_r += r;
        }
    }

    // Like rmse.py, an empty set divides by 1 (giving zeros), not by 0.
    let finish = |a: &Acc| {
        let n = a.n.max(1) as f64;
        let (mt, mr) = (a.sum_t / n, a.sum_r / n);
        ChannelMetrics {
            rmse: (a.sq / n).sqrt(),
            relmse: a.rel / n,
            mae: a.abs / n,
            maxabs: a.max,
            mean_test: mt,
            mean_ref: mr,
            mean_reldiff: if mr != 0.0 { (mt - mr) / mr } else { f64::NAN },
        }
    };
    let per_channel = [finish(&acc[0]), finish(&acc[1]), finish(&acc[2])];
    let pooled = acc.iter().fold(Acc::default(), |p, a| Acc {
        n: p.n + a.n,
        sq: p.sq + a.sq,
        rel: p.rel + a.rel,
        abs: p.abs + a.abs,
        max: p.max.max(a.max),
        sum_t: p.sum_t + a.sum_t,
        sum_r: p.sum_r + a.sum_r,
    });
    Ok(Metrics {
        size: (test.width, test.height),
        per_channel,
        all: finish(&pooled),
        test_nan,
        test_inf,
        ref_nan,
        ref_inf,
        eps,
    })
}

impl Metrics {
    /// The metrics as JSON shaped like `rmse.py --json` output (`shape` is `[h, w, 3]`,
    /// `per_channel` keyed `R`, `G`, `B`; a NaN `mean_reldiff` becomes `null`).
    pub fn to_json(&self) -> serde_json::Value {
        let per: serde_json::Map<String, serde_json::Value> = ["R", "G", "B"]
            .iter()
            .zip(&self.per_channel)
            .map(|(name, m)| {
                (
                    name.to_string(),
                    serde_json::to_value(m).unwrap_or_default(),
                )
            })
            .collect();
        serde_json::json!({
            "shape": [self.size.1, self.size.0, 3],
            "test_nan": self.test_nan,
            "test_inf": self.test_inf,
            "ref_nan": self.ref_nan,
            "ref_inf": self.ref_inf,
            "per_channel": per,
            "rmse": self.all.rmse,
            "relmse": self.all.relmse,
            "mae": self.all.mae,
            "maxabs": self.all.maxabs,
            "eps": self.eps,
        })
    }
}

/// A table in the layout `rmse.py` prints.
impl fmt::Display for Metrics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "size: {}x{}", self.size.0, self.size.1)?;
        writeln!(
            f,
            "NaN/Inf  test: {}/{}  ref: {}/{}",
            self.test_nan, self.test_inf, self.ref_nan, self.ref_inf
        )?;
        writeln!(
            f,
            "{:4}{:>12}{:>12}{:>12}{:>12}{:>12}{:>12}{:>10}",
            "", "rmse", "relMSE", "mae", "maxabs", "mean test", "mean ref", "rel.diff"
        )?;
        for (name, m) in ["R", "G", "B"].iter().zip(&self.per_channel) {
            writeln!(
                f,
                "{name:4}{:>12.6e}{:>12.6e}{:>12.6e}{:>12.6e}{:>12.6}{:>12.6}{:>9.3}%",
                m.rmse,
                m.relmse,
                m.mae,
                m.maxabs,
                m.mean_test,
                m.mean_ref,
                100.0 * m.mean_reldiff
            )?;
        }
        write!(
            f,
            "{:4}{:>12.6e}{:>12.6e}{:>12.6e}{:>12.6e}",
            "all", self.all.rmse, self.all.relmse, self.all.mae, self.all.maxabs
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use risotto_components::Rgb;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * (1.0 + b.abs())
    }

    #[test]
    fn identical_images_have_zero_error() {
        let img = Image::from_pixels(2, 1, vec![Rgb::new(0.1, 0.2, 0.3), Rgb::new(1.0, 2.0, 4.0)]);
        let m = compare(&img, &img).unwrap();
        assert_eq!(m.all.rmse, 0.0);
        assert_eq!(m.all.relmse, 0.0);
        assert_eq!(m.all.maxabs, 0.0);
        assert!(m.per_channel.iter().all(|c| c.mean_reldiff == 0.0));
        assert!(close(
            m.per_channel[2].mean_ref,
            (f64::from(0.3f32) + 4.0) / 2.0
        ));
    }

    /// Hand-computed values for a 2x1 image.
    #[test]
    fn synthetic_known_answers() {
        // test - ref per pixel: R: (+1, -3), G: (0, 0), B: (+2, +2)
        let reference =
            Image::from_pixels(2, 1, vec![Rgb::new(1.0, 0.5, 0.0), Rgb::new(4.0, 0.5, 1.0)]);
        let test = Image::from_pixels(2, 1, vec![Rgb::new(2.0, 0.5, 2.0), Rgb::new(1.0, 0.5, 3.0)]);
        let m = compare(&test, &reference).unwrap();
        let [r, g, b] = m.per_channel;
        // R: squares 1, 9 -> mse 5
        assert!(close(r.rmse, 5f64.sqrt()));
        assert!(close(r.relmse, (1.0 / 1.01 + 9.0 / 16.01) / 2.0));
        assert!(close(r.mae, 2.0));
        assert!(close(r.maxabs, 3.0));
        assert!(close(r.mean_test, 1.5));
        assert!(close(r.mean_ref, 2.5));
        assert!(close(r.mean_reldiff, -0.4));
        assert_eq!(g.rmse, 0.0);
        // B: squares 4, 4; ref 0 and 1
        assert!(close(b.rmse, 2.0));
        assert!(close(b.relmse, (4.0 / 0.01 + 4.0 / 1.01) / 2.0));
        assert!(close(b.mean_reldiff, (2.5 - 0.5) / 0.5));
        // pooled: squares 1 + 9 + 0 + 0 + 4 + 4 = 18 over 6
        assert!(close(m.all.rmse, 3f64.sqrt()));
        assert!(close(m.all.mae, 8.0 / 6.0));
        assert!(close(m.all.maxabs, 3.0));
        assert!(close(
            m.all.relmse,
            (1.0 / 1.01 + 9.0 / 16.01 + 4.0 / 0.01 + 4.0 / 1.01) / 6.0
        ));
        // a different eps changes only relmse
        let m2 = compare_with_eps(&test, &reference, 1.0).unwrap();
        assert!(close(
            m2.per_channel[2].relmse,
            (4.0 / 1.0 + 4.0 / 2.0) / 2.0
        ));
        assert_eq!(m2.all.rmse, m.all.rmse);
    }

    #[test]
    fn non_finite_entries_are_counted_and_excluded() {
        let reference = Image::from_pixels(
            3,
            1,
            vec![
                Rgb::splat(1.0),
                Rgb::new(1.0, f32::INFINITY, 1.0),
                Rgb::splat(1.0),
            ],
        );
        let test = Image::from_pixels(
            3,
            1,
            vec![
                Rgb::new(f32::NAN, 2.0, 2.0),
                Rgb::splat(3.0),
                Rgb::splat(1.0),
            ],
        );
        let m = compare(&test, &reference).unwrap();
        assert_eq!((m.test_nan, m.test_inf, m.ref_nan, m.ref_inf), (1, 0, 0, 1));
        // R: only pixels 1, 2 count: diffs 2, 0
        assert!(close(m.per_channel[0].rmse, 2f64.sqrt()));
        assert!(close(m.per_channel[0].mean_test, 2.0));
        // G: pixels 0, 2: diffs 1, 0
        assert!(close(m.per_channel[1].mae, 0.5));
        // B: all three: diffs 1, 2, 0
        assert!(close(m.per_channel[2].mae, 1.0));
        // pooled over the 7 finite pairs: |d| = 2,0 + 1,0 + 1,2,0 = 6
        assert!(close(m.all.mae, 6.0 / 7.0));
        assert!(m.all.rmse.is_finite() && m.all.relmse.is_finite());
    }

    #[test]
    fn zero_reference_mean_gives_nan_reldiff_and_null_json() {
        let z = Image::filled(2, 2, Rgb::BLACK);
        let t = Image::filled(2, 2, Rgb::splat(0.1));
        let m = compare(&t, &z).unwrap();
        assert!(m.per_channel[0].mean_reldiff.is_nan());
        let j = m.to_json();
        assert!(j["per_channel"]["R"]["mean_reldiff"].is_null());
        assert_eq!(j["shape"], serde_json::json!([2, 2, 3]));
        assert!((j["rmse"].as_f64().unwrap() - 0.1).abs() < 1e-7);
        assert!(m.to_string().contains("all"));
    }

    #[test]
    fn size_mismatch_is_an_error() {
        let a = Image::filled(2, 3, Rgb::BLACK);
        let b = Image::filled(3, 2, Rgb::BLACK);
        let err = compare(&a, &b).unwrap_err();
        assert_eq!(
            err,
            CompareError::SizeMismatch {
                test_w: 2,
                test_h: 3,
                ref_w: 3,
                ref_h: 2
            }
        );
        assert!(err.to_string().contains("2x3"));
        let mut bad = Image::filled(2, 3, Rgb::BLACK);
        bad.pixels.pop();
        assert!(matches!(
            compare(&bad, &a),
            Err(CompareError::Malformed { which: "test", .. })
        ));
    }

    /// Small Mitsuba 3 renders committed for the tests (PIZ-compressed float32, as Mitsuba
    /// writes them): `render.py cornell|glass_beer -D res=32 --spp 16` of the reference
    /// harness in `../shared/refs/mitsuba`, which the tests do not need.
    fn mitsuba_test_image(name: &str) -> std::path::PathBuf {
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../tests/data")
            .join(format!("{name}-mitsuba-32-piz.exr"))
    }

    /// A Mitsuba image against itself through an EXR round trip: zero error and the means
    /// `rmse.py` reports for it.
    #[test]
    fn reference_round_trip_compares_equal() {
        let path = &mitsuba_test_image("cornell");
        let img = risotto_engine::output::read_exr_rgb(path).unwrap();
        let tmp = std::env::temp_dir().join(format!("risotto-compare-{}.exr", std::process::id()));
        let var = Image::filled(img.width, img.height, Rgb::BLACK);
        let counts = vec![1.0; img.width * img.height];
        risotto_engine::output::write_exr(
            &tmp,
            &risotto_engine::output::FilmOutput {
                beauty: &img,
                variance: &var,
                sample_count: &counts,
                albedo: None,
                normal: None,
                depth: None,
            },
        )
        .unwrap();
        let back = risotto_engine::output::read_exr_rgb(&tmp).unwrap();
        let _ = std::fs::remove_file(&tmp);
        let m = compare(&back, &img).unwrap();
        assert_eq!(m.all.maxabs, 0.0);
        assert!((m.per_channel[0].mean_ref - 0.2593422340775078).abs() < 1e-6);
        // A uniformly brighter copy: rel.diff of the means is exactly the gain.
        let brighter = Image::from_pixels(
            img.width,
            img.height,
            img.pixels.iter().map(|p| *p * 1.5).collect(),
        );
        let m = compare(&brighter, &img).unwrap();
        for c in &m.per_channel {
            assert!((c.mean_reldiff - 0.5).abs() < 1e-6, "{}", c.mean_reldiff);
        }
    }
    /// Two Mitsuba images compared by `rmse.py` itself (numbers recorded from `rmse.py
    /// glass_beer-mitsuba-32-piz.exr cornell-mitsuba-32-piz.exr --json`): same metrics to ~1e-9.
    #[test]
    fn matches_rmse_py_on_reference_images() {
        let test = risotto_engine::output::read_exr_rgb(&mitsuba_test_image("glass_beer")).unwrap();
        let reference =
            risotto_engine::output::read_exr_rgb(&mitsuba_test_image("cornell")).unwrap();
        let m = compare(&test, &reference).unwrap();
        let near = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs();
        // [rmse, relmse, mae, maxabs, mean_test, mean_ref, mean_reldiff] per channel
        let want = [
            [
                1.30957227738226,
                9.50976551733374,
                0.46208043080912375,
                16.5,
                0.46135709239024436,
                0.2593422340775078,
                0.7789508678804773,
            ],
            [
                0.9532842936972242,
                12.210942943034489,
                0.429006406018015,
                11.5,
                0.39966810332771274,
                0.16793098262569472,
                1.379954532979434,
            ],
            [
                0.4910256294513583,
                16.918316473851686,
                0.38922713451077495,
                3.5,
                0.3829737777396076,
                0.04796077020861933,
                6.985146528584751,
            ],
        ];
        for (c, w) in m.per_channel.iter().zip(&want) {
            let got = [
                c.rmse,
                c.relmse,
                c.mae,
                c.maxabs,
                c.mean_test,
                c.mean_ref,
                c.mean_reldiff,
            ];
            for (g, w) in got.iter().zip(w) {
                assert!(near(*g, *w), "{g} vs rmse.py {w}");
            }
        }
        assert!(near(m.all.rmse, 0.977213157074081));
        assert!(near(m.all.relmse, 12.879674978073306));
        assert!(near(m.all.mae, 0.42677132377930455));
        assert!(near(m.all.maxabs, 16.5));
    }
}
