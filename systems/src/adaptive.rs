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
//! [`pooled_relative_error`] over [`Neighbourhood::Preceding`] reads no pixel's own
//! samples: the renderer's unbiased rule is built on it.

use rayon::prelude::*;

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
    if own.is_empty() {
        return;
    }
    // Rows in parallel (the calling thread's rayon pool): each reads `own` alone.
    error
        .par_chunks_mut(width)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, e) in row.iter_mut().enumerate() {
                let mut worst = 0.0f32;
                for wy in y.saturating_sub(1)..(y + 2).min(height) {
                    for wx in x.saturating_sub(1)..(x + 2).min(width) {
                        worst = worst.max(own[wy * width + wx]);
                    }
                }
                *e = worst;
            }
        });
}

/// Each of the `n` pixels' own relative error ([`relative_error`] of the pixel alone),
/// after checking that every column (`error`, the caller's output, too) has `n`.
fn own_relative_errors(
    n: usize,
    value: &[[f32; 3]],
    variance: &[[f32; 3]],
    floor: [f32; 3],
    error: &[f32],
) -> Vec<f32> {
    assert!(value.len() == n && variance.len() == n && error.len() == n);
    value
        .par_iter()
        .zip(variance)
        .map(|(v, s)| relative_error(entry(*v, *s), 1, floor))
        .collect()
}

/// The pixels [`pooled_relative_error`] pools for a pixel, of radius `r`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Neighbourhood {
    /// `Square(r)`: the `(2r + 1) x (2r + 1)` square centred on the pixel, clipped at the
    /// film's border.
    Square(usize),
    /// `Preceding(r)`: the pixels of that square that come **before** the pixel in raster
    /// order: the `r` rows above it (`2r + 1` pixels each) and the `r` pixels to its left.
    /// Neither the pixel itself nor any pixel after it.
    Preceding(usize),
}

impl Neighbourhood {
    fn radius(self) -> usize {
        match self {
            Neighbourhood::Square(r) | Neighbourhood::Preceding(r) => r,
        }
    }
}

/// The **per-sample** relative error of each pixel as its neighbourhood estimates it,
/// pooled: `max_c sqrt(mean var_c) / max(mean value_c, floor_c)`, the means taken over the
/// pixels of its `neighbourhood` (infinite where a channel has variance
/// but neither value nor floor, 0 where the neighbourhood is empty: the first pixel under
/// [`Neighbourhood::Preceding`]). A pixel's relative error at `n` samples is this over
/// `sqrt(n)`.
///
/// `value` holds the means, `per_sample_variance` the variances of one sample (a film's
/// variance of the mean times its count), row after row; `error` receives one value per
/// pixel.
///
/// Why pooled, where [`windowed_relative_error`] takes the worst: where light arrives by
/// rare bright paths (a caustic on a wall seen through glass), a pixel's variance is
/// mostly those paths, and its own few dozen samples usually hold none of them, so its own
/// estimate is low. A mean over a neighbourhood's hundreds of pixels pools enough samples
/// to see them at their rate: on `tests/adaptive.rs`'s scene it took the unbiased stopping
/// rule's MSE at equal samples from 2.6x and 1.9x uniform sampling's (targets 0.2 and 0.1,
/// ten seeds) to 1.28x and 1.00x (README, "Renders that stop at a requested accuracy").
///
/// The sums are plain sums, never running sums that subtract what leaves the window: a
/// firefly's variance (10^6 and more) subtracted back out of a running sum leaves rounding
/// errors as large as a dim pixel's whole variance. Rows are summed once (`2r + 1`
/// pixels), then `2r + 1` row sums a pixel: about `(4r + 2) x 6` additions a pixel, bands
/// of rows on the calling thread's rayon pool.
pub fn pooled_relative_error(
    width: usize,
    height: usize,
    value: &[[f32; 3]],
    per_sample_variance: &[[f32; 3]],
    neighbourhood: Neighbourhood,
    floor: [f32; 3],
    error: &mut [f32],
) {
    // A radius past the film's size pools what the film's size does (and keeps the
    // arithmetic below from overflowing).
    let radius = neighbourhood.radius().min(width.max(height));
    let preceding = matches!(neighbourhood, Neighbourhood::Preceding(_));
    let n = width * height;
    assert!(value.len() == n && per_sample_variance.len() == n && error.len() == n);
    if n == 0 {
        return;
    }
    let add = |sum: &mut [f64; 6], e: [f64; 6]| {
        for k in 0..6 {
            sum[k] += e[k];
        }
    };
    // The sum of row `y`'s pixels `from..to`.
    let row_sum = |y: usize, from: usize, to: usize| {
        let mut sum = [0.0f64; 6];
        for x in from..to {
            let i = y * width + x;
            add(&mut sum, entry(value[i], per_sample_variance[i]));
        }
        sum
    };
    let columns = |x: usize| x.saturating_sub(radius)..(x + radius + 1).min(width);
    // The rows pooled whole for row `y` (for `Preceding`, the pixel's own row adds its
    // pixels to the left); both ends rise with `y`, and no more than `ring` rows at once.
    let rows = |y: usize| {
        if preceding {
            y.saturating_sub(radius)..y
        } else {
            y.saturating_sub(radius)..(y + radius + 1).min(height)
        }
    };
    let ring = (2 * radius + 1).min(height);
    // Bands of rows run in parallel, each summing the rows it pools itself (a few more
    // than it holds): every pixel's sums are the same additions in the same order, so the
    // result does not depend on the bands or the threads.
    let band_rows = (4 * ring).max(BAND_ROWS);
    error
        .par_chunks_mut(band_rows * width)
        .enumerate()
        .for_each(|(band, band_error)| {
            let first_row = band * band_rows;
            // Row `r`'s sums over each pixel's columns, at `r % ring`.
            let mut row_sums = vec![[0.0f64; 6]; ring * width];
            let mut summed_to = rows(first_row).start;
            for (y, row_error) in (first_row..).zip(band_error.chunks_mut(width)) {
                let pooled_rows = rows(y);
                while summed_to < pooled_rows.end {
                    let at = (summed_to % ring) * width;
                    for x in 0..width {
                        let c = columns(x);
                        row_sums[at + x] = row_sum(summed_to, c.start, c.end);
                    }
                    summed_to += 1;
                }
                for (x, e) in row_error.iter_mut().enumerate() {
                    let c = columns(x);
                    let mut sum = [0.0f64; 6];
                    for r in pooled_rows.clone() {
                        add(&mut sum, row_sums[(r % ring) * width + x]);
                    }
                    let mut count = pooled_rows.len() * c.len();
                    if preceding {
                        add(&mut sum, row_sum(y, c.start, x));
                        count += x - c.start;
                    }
                    *e = relative_error(sum, count, floor);
                }
            }
        });
}

/// Rows a band of [`pooled_relative_error`] holds at least: enough that the rows it sums
/// beyond its own are a small part of its work.
const BAND_ROWS: usize = 32;

/// A pixel's variance then value, per channel, in f64: what [`relative_error`] sums.
fn entry(value: [f32; 3], variance: [f32; 3]) -> [f64; 6] {
    let (s, v) = (variance, value);
    [s[0], s[1], s[2], v[0], v[1], v[2]].map(|x| x as f64)
}

/// `max_c sqrt(variance_c / count) / max(value_c / count, floor_c)` of the sums
/// `[variance; 3, value; 3]` of `count` pixels (infinite where a channel has variance but
/// neither value nor floor; 0 for no pixels).
fn relative_error(sum: [f64; 6], count: usize, floor: [f32; 3]) -> f32 {
    let mut worst = 0.0f64;
    if count > 0 {
        let count = count as f64;
        for c in 0..3 {
            let denominator = (sum[3 + c] / count).max(floor[c] as f64);
            let numerator = (sum[c] / count).max(0.0).sqrt();
            if denominator > 0.0 {
                worst = worst.max(numerator / denominator);
            } else if numerator > 0.0 {
                worst = f64::INFINITY;
            }
        }
    }
    worst as f32
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

/// How far past its estimated need a pixel's next pass aims ([`next_sample_count`]): 10 %
/// more samples, so the look at its end finds the error about 5 % below the target and
/// passes the stop more often than not.
pub const NEED_MARGIN: f64 = 1.1;

/// The least a pixel's next pass grows its samples by when it has not stopped
/// ([`next_sample_count`]): a quarter, so a pixel just above its target does not creep up on
/// it a few samples a pass (every pass costs a look at the whole image).
pub const MIN_GROWTH: f64 = 0.25;

/// Where a pixel's samples should reach by the end of the next pass, or `None` when it
/// stops: it has `count` samples, and its estimated relative error at that count is `error`
/// (a standard error over a value, as the stopping rule estimates it) against `target`.
///
/// A pixel stops once the error is at most the target, if it has at least `min_stop`
/// samples (the renderer's guard: twice the first pass's, so no pixel stops on the estimate
/// of its first few samples alone), or when it has `cap`. Otherwise the next pass sizes its
/// samples from the estimate: the error of a mean falls as `1/sqrt(n)`, so the count that
/// meets the target is `count (error / target)^2` ([`NEED_MARGIN`] on top). That count is
/// taken within `[count (1 + MIN_GROWTH), 2 count]`: no more than doubling, because an
/// early estimate from few samples is the least trustworthy (it overshoots where a sample
/// was a firefly and undershoots where a rare path was missed), and the next look corrects
/// it. A non-finite error (no floor and a black pixel, or a non-finite estimate) doubles.
///
/// Sized passes land a pixel near its target: passes that doubled until two looks in a row
/// were at the target stopped pixels at 2 to 4 times the samples they needed (0.5 to 0.7
/// times the target's error).
pub fn next_sample_count(
    count: u32,
    error: f32,
    target: f32,
    min_stop: u32,
    cap: u32,
) -> Option<u32> {
    if count >= cap || (error <= target && count >= min_stop) {
        return None;
    }
    let n = count.max(1) as f64;
    let need = if error.is_finite() {
        n * (error as f64 / target as f64).powi(2) * NEED_MARGIN
    } else {
        f64::INFINITY
    };
    let next = need.clamp(n * (1.0 + MIN_GROWTH), 2.0 * n).ceil();
    // In f64 the clamp is exact for any u32 count, and its floor, `ceil(1.25 max(count,
    // 1))`, is above `count`; the cast saturates.
    let next = (next as u32).max(min_stop);
    Some(next.min(cap))
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
    /// Passes rendered, the first (every pixel's `min_spp`) included; the pilot is not one.
    pub passes: u32,
    /// Wall time spent between passes estimating every pixel's error and planning the next
    /// pass's samples: what deciding cost.
    pub plan_seconds: f64,
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
            passes: 0,
            plan_seconds: 0.0,
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

    /// `pooled_relative_error` of one pixel by its definition: the neighbourhood listed
    /// pixel by pixel.
    fn pooled_by_definition(
        film: &TestFilm,
        neighbourhood: Neighbourhood,
        floor: [f32; 3],
        (x, y): (usize, usize),
    ) -> f32 {
        let (width, height) = (film.width, film.height);
        let (value, variance) = (&film.value, &film.variance);
        let radius = neighbourhood.radius().min(1000);
        let (mut sum, mut count) = ([0.0f64; 6], 0usize);
        for wy in y.saturating_sub(radius)..(y + radius + 1).min(height) {
            for wx in x.saturating_sub(radius)..(x + radius + 1).min(width) {
                let before = (wy, wx) < (y, x);
                if matches!(neighbourhood, Neighbourhood::Preceding(_)) && !before {
                    continue;
                }
                let i = wy * width + wx;
                for c in 0..3 {
                    sum[c] += variance[i][c] as f64;
                    sum[3 + c] += value[i][c] as f64;
                }
                count += 1;
            }
        }
        if count == 0 {
            return 0.0;
        }
        (0..3)
            .map(|c| {
                let d = (sum[3 + c] / count as f64).max(floor[c] as f64);
                (sum[c] / count as f64).sqrt() / d
            })
            .fold(0.0f64, f64::max) as f32
    }

    /// A film's means and per-sample variances, row after row.
    struct TestFilm {
        width: usize,
        height: usize,
        value: Vec<[f32; 3]>,
        variance: Vec<[f32; 3]>,
    }

    /// A film of `width` x `height` pixels of pseudo-random values and variances, a few of
    /// them fireflies (variance 10^4) and some black.
    fn film(width: usize, height: usize, seed: u64) -> TestFilm {
        let mut state = seed;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut value = Vec::new();
        let mut variance = Vec::new();
        for _ in 0..width * height {
            let kind = next();
            let scale: f32 = if kind < 0.05 {
                1e4
            } else if kind < 0.15 {
                0.0
            } else {
                1.0
            };
            value.push([next(), next(), next()].map(|v| v * scale.min(10.0)));
            variance.push([next(), next(), next()].map(|v| v * scale));
        }
        TestFilm {
            width,
            height,
            value,
            variance,
        }
    }

    #[test]
    fn pooled_errors_are_the_neighbourhoods_means() {
        for (width, height) in [(1, 1), (5, 1), (1, 6), (7, 4), (23, 17), (5, 100), (3, 70)] {
            let test_film = film(width, height, (width * 31 + height) as u64);
            let (value, variance) = (&test_film.value, &test_film.variance);
            for radius in [0, 1, 3, 40, usize::MAX] {
                for neighbourhood in [
                    Neighbourhood::Square(radius),
                    Neighbourhood::Preceding(radius),
                ] {
                    for floor in [[0.0; 3], [0.05, 0.1, 0.2]] {
                        let mut error = vec![-1.0; width * height];
                        pooled_relative_error(
                            width,
                            height,
                            value,
                            variance,
                            neighbourhood,
                            floor,
                            &mut error,
                        );
                        for y in 0..height {
                            for x in 0..width {
                                let expected =
                                    pooled_by_definition(&test_film, neighbourhood, floor, (x, y));
                                let got = error[y * width + x];
                                assert!(
                                    (got - expected).abs() <= 1e-5 * expected.abs().max(1e-3),
                                    "{width}x{height} {neighbourhood:?} {floor:?} \
                                     ({x}, {y}): {got} against {expected}"
                                );
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn windowed_errors_are_the_worst_of_each_three_by_three() {
        let film = film(23, 17, 3);
        let (w, h) = (film.width, film.height);
        let mut error = vec![-1.0; w * h];
        windowed_relative_error(w, h, &film.value, &film.variance, [0.01; 3], &mut error);
        for y in 0..h {
            for x in 0..w {
                let mut worst = 0.0f32;
                for wy in y.saturating_sub(1)..(y + 2).min(h) {
                    for wx in x.saturating_sub(1)..(x + 2).min(w) {
                        worst = worst.max(own_error(&film, wy * w + wx));
                    }
                }
                assert_eq!(error[y * w + x], worst, "({x}, {y})");
            }
        }
    }

    /// Pixel `i`'s own relative error in `film`, floor 0.01: a 1 x 1 film of it alone.
    fn own_error(film: &TestFilm, i: usize) -> f32 {
        let mut e = [0.0];
        windowed_relative_error(
            1,
            1,
            &film.value[i..=i],
            &film.variance[i..=i],
            [0.01; 3],
            &mut e,
        );
        e[0]
    }

    #[test]
    fn a_preceding_estimate_reads_nothing_of_the_pixel_or_after_it() {
        let (w, h, r) = (9, 7, 2);
        let TestFilm {
            value, variance, ..
        } = film(w, h, 7);
        let pooled = |value: &[[f32; 3]], variance: &[[f32; 3]]| {
            let mut error = vec![0.0; w * h];
            let floor = [0.01; 3];
            pooled_relative_error(
                w,
                h,
                value,
                variance,
                Neighbourhood::Preceding(r),
                floor,
                &mut error,
            );
            error
        };
        let error = pooled(&value, &variance);
        for i in 0..w * h {
            // Every pixel from `i` on replaced (a firefly, a black pixel): `i`'s estimate
            // stays.
            let (mut v, mut s) = (value.clone(), variance.clone());
            for j in i..w * h {
                v[j] = if j % 2 == 0 { [50.0; 3] } else { [0.0; 3] };
                s[j] = if j % 2 == 0 { [1e6; 3] } else { [0.0; 3] };
            }
            assert_eq!(pooled(&v, &s)[i], error[i], "pixel {i}");
        }
        // A firefly just before a pixel raises its estimate; the first pixel has none.
        let (x, y) = (4, 3);
        let mut s = variance.clone();
        s[y * w + x - 1] = [1e6; 3];
        assert!(pooled(&value, &s)[y * w + x] > 10.0 * error[y * w + x]);
        assert_eq!(error[0], 0.0);
    }

    #[test]
    fn a_firefly_leaves_nothing_in_later_pixels_sums() {
        // One row: a firefly, then black pixels. Once the firefly is out of a pixel's
        // neighbourhood, what the sliding sums leave of it must not read as error.
        // Dim pixels (value 0.01, per-sample relative error 0.1) after a firefly: once the
        // firefly is out of a pixel's neighbourhood, nothing of it may remain in the sums
        // (a running sum that subtracted it would leave 1e-8 of it: 1 % of their variance).
        let (w, h) = (12, 3);
        let mut value = vec![[0.01; 3]; w * h];
        let mut variance = vec![[1e-6; 3]; w * h];
        value[0] = [1e3; 3];
        variance[0] = [1e8; 3];
        for neighbourhood in [Neighbourhood::Square(2), Neighbourhood::Preceding(2)] {
            let mut error = vec![0.0; w * h];
            let floor = [1e-3; 3];
            pooled_relative_error(w, h, &value, &variance, neighbourhood, floor, &mut error);
            for (i, &e) in error.iter().enumerate() {
                if i % w >= 3 || i / w >= 3 {
                    assert!((e - 0.1).abs() < 1e-6, "{neighbourhood:?} pixel {i}: {e}");
                }
            }
            assert!(error[1] > 1.0, "{error:?}");
        }
    }

    #[test]
    fn a_pass_takes_the_estimated_need_within_a_quarter_and_double() {
        let (t, min_stop, cap) = (0.1, 32, 4096);
        // At the target: stops, but not before `min_stop`, and never past the cap.
        assert_eq!(next_sample_count(100, 0.1, t, min_stop, cap), None);
        assert_eq!(next_sample_count(16, 0.05, t, min_stop, cap), Some(32));
        assert_eq!(next_sample_count(4096, 1.0, t, min_stop, cap), None);
        assert_eq!(next_sample_count(3000, 1.0, t, min_stop, cap), Some(4096));
        // Above it: the need, 10 % over, within [1.25, 2] times the count.
        assert_eq!(next_sample_count(100, 0.12, t, min_stop, cap), Some(159));
        assert_eq!(next_sample_count(100, 0.101, t, min_stop, cap), Some(125));
        assert_eq!(next_sample_count(100, 0.2, t, min_stop, cap), Some(200));
        // No estimate to size from: doubles.
        for e in [f32::NAN, f32::INFINITY] {
            assert_eq!(next_sample_count(100, e, t, min_stop, cap), Some(200));
        }
        // Every count, error and cap: more samples than now, at most the cap, at most
        // doubling (or the earliest stop).
        for count in (1..3000).step_by(7) {
            for e in [0.0, 0.05, 0.0999, 0.1, 0.1001, 0.15, 0.3, 10.0, 1e30] {
                for cap in [count, count + 1, 2 * count, 5000] {
                    if let Some(next) = next_sample_count(count, e, t, min_stop, cap) {
                        assert!(count < next && next <= cap, "{count} {e} {cap}: {next}");
                        assert!(next <= (2 * count).max(min_stop), "{count} {e}: {next}");
                    } else {
                        assert!(count >= cap || (e <= t && count >= min_stop));
                    }
                }
            }
        }
    }

    /// With exact estimates (a pixel of per-sample relative error `s`, so `s / sqrt(n)` at
    /// `n` samples), a pixel stops at between its need and 1.25 times it: its error between
    /// 0.89 and 1.0 times the target. Passes that doubled until two looks in a row were at
    /// the target stopped it at 2 to 4 times its need.
    #[test]
    fn exact_estimates_stop_a_pixel_within_a_quarter_past_its_need() {
        let (t, min_spp) = (0.05f32, 16u32);
        for s in (1..250).map(|k| 0.25 * 1.03f32.powi(k)) {
            let error = |n: u32| s / (n as f32).sqrt();
            let mut n = min_spp;
            while let Some(next) = next_sample_count(n, error(n), t, 2 * min_spp, u32::MAX) {
                n = next;
            }
            let need = (s / t).powi(2).max(2.0 * min_spp as f32);
            assert!(error(n) <= t, "{s}: {n} samples, error {}", error(n));
            assert!(
                n as f32 <= (1.25 * need).max(2.0 * min_spp as f32) + 1.0,
                "{s}: {n} samples for a need of {need}"
            );
        }
    }
}
