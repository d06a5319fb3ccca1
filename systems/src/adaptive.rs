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
//! A stopping rule that reads the samples it stops on can bias the mean (Kirk and Arvo 1991,
//! "Unbiased sampling techniques for image synthesis"); with the window, a minimum number of
//! samples before any pixel stops, and decisions only at pass ends (doubling passes), the
//! bias is well below the noise at the target. The renderer's test measures it.

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
    let n = width * height;
    assert!(value.len() == n && variance.len() == n && error.len() == n);
    // Each pixel's own relative error, worst channel.
    let own: Vec<f32> = (0..n)
        .map(|i| {
            let mut worst = 0.0f32;
            for c in 0..3 {
                let denominator = value[i][c].max(floor[c]);
                let numerator = variance[i][c].max(0.0).sqrt();
                if denominator > 0.0 {
                    worst = worst.max(numerator / denominator);
                } else if numerator > 0.0 {
                    worst = f32::INFINITY;
                }
            }
            worst
        })
        .collect();
    // The worst over the window.
    for y in 0..height {
        for x in 0..width {
            let mut worst = 0.0f32;
            for wy in y.saturating_sub(1)..(y + 2).min(height) {
                for wx in x.saturating_sub(1)..(x + 2).min(width) {
                    worst = worst.max(own[wy * width + wx]);
                }
            }
            error[y * width + x] = worst;
        }
    }
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
}
