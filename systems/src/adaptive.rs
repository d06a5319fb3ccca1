//! Adaptive sampling's stopping rule: which pixels of a film still need samples to reach a
//! requested relative error (`risotto render --noise-target X`).
//!
//! The error of a pixel is estimated from the film itself: the standard error of its mean,
//! `sqrt(variance of the mean)`, relative to the mean, per channel, the largest channel
//! counting. Two guards keep the estimate from stopping a pixel too early:
//! - **A 3 x 3 window.** A pixel's error is the worst of its own and its eight neighbours':
//!   a pixel whose few samples all missed a rare bright path (a caustic, a small light seen
//!   through glass) has a variance estimate of about 0, but its neighbours rarely all have;
//!   the window makes it sample on. Cycles' adaptive sampler guards the same way (its
//!   convergence test looks at a window of neighbouring pixels).
//! - **A floor on the denominator**, `floor` per channel (the renderer takes 1 % of the
//!   image's mean): below it the error is measured against the floor, so a nearly black
//!   pixel does not demand thousands of samples for a relative error no one sees.
//!
//! A stopping rule that reads the samples it stops on biases the mean where light arrives
//! by rare paths (Kirk and Arvo 1991, "Unbiased sampling techniques for image synthesis"):
//! a pixel that has not drawn one yet shows a low mean and a low variance together, and
//! stops low. The window, a minimum number of samples and decisions only at pass ends
//! bound it; they do not remove it (`tests/adaptive.rs` measures 1.1 % on its scene).
//! [`preceding_relative_error`] reads no pixel's own samples: the renderer's unbiased rule
//! is built on it.

/// The relative error of each pixel of a `width` x `height` film, the worst over its 3 x 3
/// window (clipped at the border) of each pixel's own `max_c sqrt(var_c) / max(value_c,
/// floor_c)`.
/// `value` holds the means, `variance` the variances of the means, row after row;
/// `error` receives one value per pixel (0 for a window without light and variance).
pub fn windowed_relative_error(
    width: usize,
    height: usize,
    value: &[[f32; 3]],
    variance: &[[f32; 3]],
    floor: [f32; 3],
    error: &mut [f32],
) {
    let own = own_relative_errors(width * height, value, variance, floor, error);
    worst_over_neighbourhoods(
        width,
        height,
        &own,
        error,
        |y| y.saturating_sub(1)..(y + 2).min(height),
        |x, _, _| x.saturating_sub(1)..(x + 2).min(width),
    );
}

/// Each pixel's `error`: the worst of `own` over its neighbourhood, the rows `rows(y)` and
/// in each row `wy` the columns `columns(x, y, wy)`.
fn worst_over_neighbourhoods(
    width: usize,
    height: usize,
    own: &[f32],
    error: &mut [f32],
    rows: impl Fn(usize) -> std::ops::Range<usize>,
    columns: impl Fn(usize, usize, usize) -> std::ops::Range<usize>,
) {
    for y in 0..height {
        for x in 0..width {
            let mut worst = 0.0f32;
            for wy in rows(y) {
                for wx in columns(x, y, wy) {
                    worst = worst.max(own[wy * width + wx]);
                }
            }
            error[y * width + x] = worst;
        }
    }
}

/// Each of the `n` pixels' own relative error, `max_c sqrt(var_c) / max(value_c, floor_c)`
/// (infinite where a channel has variance but neither value nor floor), after checking that
/// every column (`error`, the caller's output, too) has `n`.
fn own_relative_errors(
    n: usize,
    value: &[[f32; 3]],
    variance: &[[f32; 3]],
    floor: [f32; 3],
    error: &[f32],
) -> Vec<f32> {
    assert!(value.len() == n && variance.len() == n && error.len() == n);
    value
        .iter()
        .zip(variance)
        .map(|(value, variance)| {
            let mut worst = 0.0f32;
            for c in 0..3 {
                let denominator = value[c].max(floor[c]);
                let numerator = variance[c].max(0.0).sqrt();
                if denominator > 0.0 {
                    worst = worst.max(numerator / denominator);
                } else if numerator > 0.0 {
                    worst = f32::INFINITY;
                }
            }
            worst
        })
        .collect()
}

/// The relative error of each pixel as its **preceding** pixels estimate it: the worst of
/// the own errors (as in [`windowed_relative_error`]) of the pixels of its 5 x 5 window
/// that come before it in raster order, the two rows above it (five pixels each) and the
/// two pixels to its left; 0 for the first pixel, which has none.
///
/// Why: no pixel's error reads its own samples or those of any pixel after it, so the
/// stopping decisions of a film form a directed acyclic graph, and a pixel's sample count
/// is independent of its samples. Its mean is then unbiased whatever the rule (Kirk and
/// Arvo 1991: a stopping rule biases the mean only through the samples it reads and keeps).
/// The renderer's unbiased rule takes the worst of this and a discarded pilot's estimate,
/// which sees the pixel's own region (a pixel at the top edge of a noisy region has only
/// smooth pixels before it).
pub fn preceding_relative_error(
    width: usize,
    height: usize,
    value: &[[f32; 3]],
    variance: &[[f32; 3]],
    floor: [f32; 3],
    error: &mut [f32],
) {
    let own = own_relative_errors(width * height, value, variance, floor, error);
    worst_over_neighbourhoods(
        width,
        height,
        &own,
        error,
        |y| y.saturating_sub(2)..y + 1,
        // The rows above: x - 2 ..= x + 2; the pixel's own row: x - 2 .. x.
        |x, y, wy| x.saturating_sub(2)..if wy == y { x } else { (x + 3).min(width) },
    );
}

/// Per-channel floors for [`windowed_relative_error`]: `fraction` of the image's mean value
/// per channel (means of all pixels).
pub fn error_floor(value: &[[f32; 3]], fraction: f32) -> [f32; 3] {
    let mut sum = [0.0f64; 3];
    for v in value {
        for c in 0..3 {
            sum[c] += v[c].max(0.0) as f64;
        }
    }
    let n = value.len().max(1) as f64;
    sum.map(|s| (s / n) as f32 * fraction)
}

/// Summary of where an adaptive render's samples went and the error it estimates at the
/// end (the renderer's stats).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AdaptiveSummary {
    /// The requested relative error.
    pub target: f32,
    /// Samples per pixel: least, mean, most.
    pub spp_min: u32,
    /// Mean samples per pixel.
    pub spp_mean: f64,
    /// Most samples per pixel.
    pub spp_max: u32,
    /// Fraction of pixels whose estimated error is at or below the target.
    pub converged_fraction: f64,
    /// Median of the pixels' estimated errors.
    pub error_median: f32,
    /// 95th percentile of the pixels' estimated errors.
    pub error_p95: f32,
    /// Samples a pixel of the unbiased stopping rule's pilot, rendered and discarded (not
    /// in the spp above); 0 under the window rule.
    pub pilot_spp: u32,
}

impl AdaptiveSummary {
    /// Summarises the sample counts and estimated errors of a film's pixels.
    pub fn new(target: f32, counts: &[u32], error: &[f32]) -> AdaptiveSummary {
        let n = counts.len().max(1);
        let mut sorted: Vec<f32> = error
            .iter()
            .map(|e| if e.is_nan() { f32::INFINITY } else { *e })
            .collect();
        sorted.sort_by(f32::total_cmp);
        let at = |q: f64| -> f32 {
            if sorted.is_empty() {
                0.0
            } else {
                sorted[((sorted.len() - 1) as f64 * q).round() as usize]
            }
        };
        AdaptiveSummary {
            target,
            spp_min: counts.iter().copied().min().unwrap_or(0),
            spp_mean: counts.iter().map(|&c| c as f64).sum::<f64>() / n as f64,
            spp_max: counts.iter().copied().max().unwrap_or(0),
            converged_fraction: error.iter().filter(|&&e| e <= target).count() as f64
                / error.len().max(1) as f64,
            error_median: at(0.5),
            error_p95: at(0.95),
            pilot_spp: 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_window_keeps_a_lucky_pixel_sampling() {
        // 3 x 1: the middle pixel's samples happened to agree (variance 0), its neighbours'
        // did not: alone it would stop, in its window it goes on.
        let value = [[1.0; 3], [1.0; 3], [1.0; 3]];
        let variance = [[0.04; 3], [0.0; 3], [0.04; 3]];
        let mut error = [0.0; 3];
        windowed_relative_error(3, 1, &value, &variance, [0.0; 3], &mut error);
        // Every pixel: the worst of its window, sqrt(0.04) / 1.
        assert_eq!(error, [0.2; 3]);
        // Alone it would have stopped.
        windowed_relative_error(
            1,
            1,
            &value[1..2],
            &variance[1..2],
            [0.0; 3],
            &mut error[..1],
        );
        assert_eq!(error[0], 0.0);
    }

    #[test]
    fn the_worst_channel_counts_and_the_floor_bounds_dark_pixels() {
        let value = [[1.0, 0.001, 1.0]];
        let variance = [[0.0001, 0.0001, 0.0]];
        let mut error = [0.0];
        // Without a floor the dark green channel's relative error (0.01 / 0.001) dominates.
        windowed_relative_error(1, 1, &value, &variance, [0.0; 3], &mut error);
        assert!((error[0] - 10.0).abs() < 1e-4, "{error:?}");
        // A floor of 0.1 on green: 0.01 / 0.1.
        windowed_relative_error(1, 1, &value, &variance, [0.0, 0.1, 0.0], &mut error);
        assert!((error[0] - 0.1).abs() < 1e-6, "{error:?}");
        // Black without variance: 0; black with variance and no floor: infinite.
        windowed_relative_error(1, 1, &[[0.0; 3]], &[[0.0; 3]], [0.0; 3], &mut error);
        assert_eq!(error[0], 0.0);
        windowed_relative_error(1, 1, &[[0.0; 3]], &[[1.0; 3]], [0.0; 3], &mut error);
        assert_eq!(error[0], f32::INFINITY);
    }

    #[test]
    fn the_summary_counts_samples_and_errors() {
        let s = AdaptiveSummary::new(0.1, &[16, 32, 64, 16], &[0.05, 0.1, 0.2, f32::NAN]);
        assert_eq!((s.spp_min, s.spp_max), (16, 64));
        assert_eq!(s.spp_mean, 32.0);
        assert_eq!(s.converged_fraction, 0.5);
        assert_eq!(s.error_p95, f32::INFINITY);
        assert_eq!(
            error_floor(&[[1.0, 2.0, 0.0], [3.0, 2.0, 0.0]], 0.5),
            [1.0, 1.0, 0.0]
        );
    }

    #[test]
    fn a_pixel_preceded_by_noise_reads_it_and_nothing_of_its_own_or_later() {
        // 5 x 4, every pixel certain (variance 0) but one noisy pixel at (2, 1).
        let (w, h) = (5, 4);
        let value = vec![[1.0; 3]; w * h];
        let mut variance = vec![[0.0; 3]; w * h];
        variance[w + 2] = [0.01; 3];
        let mut error = vec![0.0; w * h];
        preceding_relative_error(w, h, &value, &variance, [0.0; 3], &mut error);
        // The pixels after (2, 1) within two columns and two rows read its 0.1; the noisy
        // pixel itself, everything before it and everything farther do not.
        for y in 0..h {
            for x in 0..w {
                let after = (y == 1 && (3..=4).contains(&x)) || ((2..=3).contains(&y) && x <= 4);
                let expected = if after { 0.1 } else { 0.0 };
                assert!(
                    (error[y * w + x] - expected).abs() < 1e-6,
                    "({x}, {y}): {}",
                    error[y * w + x]
                );
            }
        }
        // Changing a pixel's own samples never changes its own error.
        let mut moved = variance.clone();
        moved[2 * w + 1] = [4.0; 3];
        let mut error2 = vec![0.0; w * h];
        preceding_relative_error(w, h, &value, &moved, [0.0; 3], &mut error2);
        assert_eq!(error2[2 * w + 1], error[2 * w + 1]);
    }
}
