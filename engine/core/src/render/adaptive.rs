//! Adaptive sampling's decisions between passes ([`RenderOptions::noise_target`]): each
//! pixel's estimated relative error from the tiles' films, which pixels stop, how many
//! samples each of the others takes in the next pass, and the summary the stats report.
//!
//! Under [`StoppingRule::Unbiased`](super::StoppingRule::Unbiased) the decisions read a
//! pilot (tiles of `min_spp` samples of every pixel from an independent scramble,
//! [`PILOT_SEED_SALT`], rendered before the image and never part of it) and the image's
//! pixels before each pixel in raster order, never the pixel's own samples; the floor of
//! dark pixels is the pilot's too. So a pixel's sample count is a function of samples
//! independent of its own, and its mean is unbiased (the pass lengths of an interruptible
//! render follow the wall time, which a pixel's samples move by microseconds: not a
//! dependence worth the name).

use super::{NoiseTarget, RenderOutput, Tile, Window, NOISE_FLOOR_FRACTION};
use crate::integrator::TileFilm;
use crate::stats::SystemStats;
use risotto_systems::adaptive::AdaptiveSummary;

/// XORed into the scene's seed for the pilot's pixel seeds
/// ([`crate::integrator::TileFilm::seed_salt`]): an independent Owen scramble of the same
/// sequence (independent streams under the independent sampler).
pub(super) const PILOT_SEED_SALT: u64 = 0x5851_f42d_4c95_7f2d;

/// The pilot's tiles of an unbiased adaptive render, one beside each of `tiles`, empty.
pub(super) fn pilot_tiles(tiles: &[Tile]) -> Vec<Tile> {
    tiles
        .iter()
        .map(|(t, _)| {
            let mut pilot = TileFilm::without_aovs(t.x0, t.y0, t.film.width, t.film.height);
            pilot.seed_salt = PILOT_SEED_SALT;
            (pilot, SystemStats::default())
        })
        .collect()
}

/// The means, variances of the means and sample counts of the window's pixels, gathered
/// from `tiles`.
struct Estimates {
    value: Vec<[f32; 3]>,
    variance: Vec<[f32; 3]>,
    count: Vec<u32>,
}

impl Estimates {
    /// Estimates of `window`'s pixels, all 0.
    fn new(window: Window) -> Estimates {
        let n = window.pixels();
        Estimates {
            value: vec![[0.0; 3]; n],
            variance: vec![[0.0; 3]; n],
            count: vec![0; n],
        }
    }
}

/// The estimates of `window`'s pixels, gathered from `tiles` (the pilot's, once a render).
fn window_estimates(tiles: &[Tile], window: Window) -> Estimates {
    let mut estimates = Estimates::new(window);
    gather_estimates(tiles, window, &mut estimates);
    estimates
}

/// Gathers the estimates of `window`'s pixels from `tiles` into `into`.
fn gather_estimates(tiles: &[Tile], window: Window, into: &mut Estimates) {
    use rayon::prelude::*;
    let w = window.width() as usize;
    let Estimates {
        value,
        variance,
        count,
    } = into;
    // The tiles are a grid (`render_passes` and `pilot_tiles` make them row by row, left to
    // right, every tile but the last of a row or column as wide and high as the first): so
    // image row `y` is in tile row `y / tile height`, and rows fill in parallel.
    let per_row = tiles.iter().take_while(|(t, _)| t.y0 == window.y0).count();
    let tile_height = tiles.first().map_or(1, |(t, _)| t.film.height.max(1)) as usize;
    (value.par_chunks_mut(w))
        .zip(variance.par_chunks_mut(w))
        .zip(count.par_chunks_mut(w))
        .enumerate()
        .for_each(|(y, ((value, variance), count))| {
            let row = (y / tile_height) * per_row;
            for (tile, _) in &tiles[row..row + per_row] {
                let film = &tile.film;
                let ty = (window.y0 as usize + y) - tile.y0 as usize;
                debug_assert!(ty < film.height as usize);
                let x0 = (tile.x0 - window.x0) as usize;
                for tx in 0..film.width as usize {
                    let src = ty * film.width as usize + tx;
                    value[x0 + tx] = film.mean(src).to_array();
                    variance[x0 + tx] = film.variance_of_mean(src).to_array();
                    count[x0 + tx] = film.count[src];
                }
            }
        });
}

/// The estimated relative error of each pixel of the window ([`NoiseTarget`]).
fn window_errors(value: &[[f32; 3]], variance: &[[f32; 3]], window: Window) -> Vec<f32> {
    let mut error = vec![0.0; window.pixels()];
    window_errors_into(value, variance, window, &mut error);
    error
}

/// [`window_errors`] into `error`.
fn window_errors_into(
    value: &[[f32; 3]],
    variance: &[[f32; 3]],
    window: Window,
    error: &mut [f32],
) {
    let (w, h) = (window.width() as usize, window.height() as usize);
    let floor = risotto_systems::adaptive::error_floor(value, NOISE_FLOOR_FRACTION);
    risotto_systems::adaptive::windowed_relative_error(w, h, value, variance, floor, error);
}

/// How far [`StoppingRule::Unbiased`](super::StoppingRule::Unbiased)'s pilot estimate
/// pools: the 9 x 9 pilot pixels around a pixel, 81 x `min_spp` samples (1296 at the
/// default 16).
const PILOT_POOL_RADIUS: usize = 4;

/// How far its estimate from the image's preceding pixels pools: the 8 rows above a pixel
/// (17 pixels each) and the 8 pixels to its left, 144 pixels of the image's samples.
const PRECEDING_POOL_RADIUS: usize = 8;

/// What [`StoppingRule::Unbiased`](super::StoppingRule::Unbiased) keeps of its pilot for
/// the rest of the render, made once the pilot is rendered: its tiles' films are then
/// dropped.
pub(super) struct PilotErrors {
    /// Each pixel's per-sample relative error, pooled over the pilot's 9 x 9 pixels around
    /// it ([`risotto_systems::adaptive::pooled_relative_error`]).
    per_sample_error: Vec<f32>,
    /// The floor of dark pixels, from the pilot's means.
    floor: [f32; 3],
    /// The pilot's samples a pixel.
    pub(super) spp: u32,
}

impl PilotErrors {
    /// The pooled errors of the pilot's `tiles`, which cover `window`.
    pub(super) fn of(tiles: &[Tile], window: Window) -> PilotErrors {
        PilotErrors::from_estimates(&window_estimates(tiles, window), window)
    }

    /// The pooled errors of the pilot's estimates of `window`'s pixels.
    fn from_estimates(pilot: &Estimates, window: Window) -> PilotErrors {
        use risotto_systems::adaptive::{error_floor, pooled_relative_error, Neighbourhood};
        let (w, h) = (window.width() as usize, window.height() as usize);
        let floor = error_floor(&pilot.value, NOISE_FLOOR_FRACTION);
        let mut per_sample_error = vec![0.0; w * h];
        pooled_relative_error(
            w,
            h,
            &pilot.value,
            &pilot.per_sample_variance(),
            Neighbourhood::Square(PILOT_POOL_RADIUS),
            floor,
            &mut per_sample_error,
        );
        PilotErrors {
            per_sample_error,
            floor,
            spp: pilot.count.first().copied().unwrap_or(0),
        }
    }
}

impl Estimates {
    /// The variances of one sample: the variances of the means times the counts.
    fn per_sample_variance(&self) -> Vec<[f32; 3]> {
        let mut out = Vec::new();
        self.per_sample_variance_into(&mut out);
        out
    }

    /// [`Estimates::per_sample_variance`] into `out`.
    fn per_sample_variance_into(&self, out: &mut Vec<[f32; 3]>) {
        out.clear();
        out.extend((self.variance.iter().zip(&self.count)).map(|(v, &n)| v.map(|v| v * n as f32)));
    }
}

/// The error [`StoppingRule::Unbiased`](super::StoppingRule::Unbiased) estimates for each
/// pixel of the window: the worst of two per-sample relative errors, each pooled over a
/// neighbourhood ([`risotto_systems::adaptive::pooled_relative_error`]), over the square
/// root of the pixel's count in `image`: the pilot's around the pixel, and the image's
/// pixels before it in raster order; both against the pilot's floor.
///
/// Pooled, not the worst of each pixel's own estimate: where a pixel's variance is rare
/// bright paths, its own few samples mostly miss them; pooled over a neighbourhood they
/// are seen at their rate. Both estimates are needed: the pilot sees the pixel's own
/// region (the first rows of a noisy region have only smooth pixels before them), the
/// preceding pixels hold many more samples than the pilot.
#[cfg(test)]
fn unbiased_errors(image: &Estimates, pilot: &PilotErrors, window: Window) -> Vec<f32> {
    let mut error = vec![0.0; window.pixels()];
    unbiased_errors_into(image, pilot, window, &mut Vec::new(), &mut error);
    error
}

/// [`unbiased_errors`] into `error`, with `per_sample_variance` as scratch.
fn unbiased_errors_into(
    image: &Estimates,
    pilot: &PilotErrors,
    window: Window,
    per_sample_variance: &mut Vec<[f32; 3]>,
    error: &mut [f32],
) {
    use risotto_systems::adaptive::{pooled_relative_error, Neighbourhood};
    let (w, h) = (window.width() as usize, window.height() as usize);
    image.per_sample_variance_into(per_sample_variance);
    pooled_relative_error(
        w,
        h,
        &image.value,
        per_sample_variance,
        Neighbourhood::Preceding(PRECEDING_POOL_RADIUS),
        pilot.floor,
        error,
    );
    for ((e, pilot_error), &n) in (error.iter_mut())
        .zip(&pilot.per_sample_error)
        .zip(&image.count)
    {
        *e = e.max(*pilot_error) / (n.max(1) as f32).sqrt();
    }
}

/// What [`plan_next_pass`] works in, made once a render and reused at every pass end: made
/// on the render's calling thread, not on its pool's, where made and freed pass after pass
/// the allocator's per-thread arenas kept freed copies (4 bytes a pixel more peak under
/// the unbiased rule, `tests/film_memory.rs`).
pub(super) struct PlanBuffers {
    image: Estimates,
    per_sample_variance: Vec<[f32; 3]>,
    error: Vec<f32>,
}

impl PlanBuffers {
    /// Buffers for `window`'s pixels.
    pub(super) fn new(window: Window) -> PlanBuffers {
        PlanBuffers {
            image: Estimates::new(window),
            per_sample_variance: Vec::with_capacity(window.pixels()),
            error: vec![0.0; window.pixels()],
        }
    }
}

/// Plans the next pass of an adaptive render from the error each pixel's estimate gives
/// at its count: a pixel at its target stops for good, the others get the sample indices
/// that should bring them to it ([`risotto_systems::adaptive::next_sample_count`]; at
/// least `2 min_spp` samples before any stops, at most `samples.end`). Sets each tile's
/// [`TileFilm::sample_ranges`] and returns how many pixels still take samples, working in
/// `buffers`. The error
/// is [`StoppingRule::Unbiased`](super::StoppingRule::Unbiased)'s with a `pilot` (which
/// only that rule renders), [`StoppingRule::Window`](super::StoppingRule::Window)'s
/// without.
pub(super) fn plan_next_pass(
    tiles: &mut [Tile],
    pilot: Option<&PilotErrors>,
    window: Window,
    target: NoiseTarget,
    samples: std::ops::Range<u32>,
    buffers: &mut PlanBuffers,
) -> usize {
    use risotto_systems::adaptive::next_sample_count;
    let PlanBuffers {
        image,
        per_sample_variance,
        error,
    } = buffers;
    gather_estimates(tiles, window, image);
    match pilot {
        None => window_errors_into(&image.value, &image.variance, window, error),
        Some(pilot) => unbiased_errors_into(image, pilot, window, per_sample_variance, error),
    }
    let error = &*error;
    let w = window.width() as usize;
    let cap = samples.end - samples.start;
    let min_stop = target.min_spp.max(1).saturating_mul(2);
    let plan_tile = |tile: &mut TileFilm| {
        let (tw, th) = (tile.film.width as usize, tile.film.height as usize);
        // Before the first plan every pixel took the first pass.
        let first = tile.sample_ranges.is_empty();
        if first {
            tile.sample_ranges = vec![samples.start..samples.start; tw * th];
        }
        let mut active = 0;
        for ty in 0..th {
            for tx in 0..tw {
                let local = ty * tw + tx;
                let x = (tile.x0 - window.x0) as usize + tx;
                let y = (tile.y0 - window.y0) as usize + ty;
                let range = &mut tile.sample_ranges[local];
                // A pixel that took nothing in the pass just done had stopped.
                let stopped = !first && range.start >= range.end;
                let count = tile.film.count[local];
                let next = match stopped {
                    true => None,
                    false => next_sample_count(
                        count,
                        error[y * w + x],
                        target.relative_error,
                        min_stop,
                        cap,
                    ),
                };
                let begin = samples.start + count;
                *range = match next {
                    Some(next) => begin..samples.start + next,
                    None => begin..begin,
                };
                active += usize::from(range.start < range.end);
            }
        }
        active
    };
    use rayon::prelude::*;
    tiles.par_iter_mut().map(|(tile, _)| plan_tile(tile)).sum()
}

/// The stats of an adaptive render: its sample counts and final error estimates.
pub(super) fn adaptive_summary(
    out: &RenderOutput,
    target: NoiseTarget,
    pilot: Option<&PilotErrors>,
) -> AdaptiveSummary {
    let value: Vec<[f32; 3]> = out.beauty.pixels.iter().map(|p| p.to_array()).collect();
    let variance: Vec<[f32; 3]> = out.variance.pixels.iter().map(|p| p.to_array()).collect();
    let error = window_errors(&value, &variance, out.window);
    AdaptiveSummary {
        pilot_spp: pilot.map_or(0, |p| p.spp),
        ..AdaptiveSummary::new(target.relative_error, &out.film.count, &error)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4 x 3 window's estimates: every pixel `value` 1 with variance of the mean `var`
    /// and `count` samples.
    fn uniform(var: f32, count: u32) -> Estimates {
        Estimates {
            value: vec![[1.0; 3]; 12],
            variance: vec![[var; 3]; 12],
            count: vec![count; 12],
        }
    }

    #[test]
    fn the_unbiased_rule_never_reads_a_pixels_own_samples() {
        let window = Window::full(4, 3);
        let pilot = PilotErrors::from_estimates(&uniform(0.0004, 16), window);
        let image = uniform(0.0001, 64);
        let error = unbiased_errors(&image, &pilot, window);
        // The pilot's per-sample relative error is sqrt(0.0004 x 16) = 0.08, at 64 samples
        // 0.01; the image's preceding pixels say sqrt(0.0001 x 64) / 8 = 0.01 too.
        assert!(error.iter().all(|e| (e - 0.01).abs() < 1e-6), "{error:?}");
        // Whatever a pixel's own samples say (its mean, its variance), its error stays.
        let i = 5;
        let mut own = uniform(0.0001, 64);
        own.value[i] = [0.01; 3];
        own.variance[i] = [9.0; 3];
        assert_eq!(unbiased_errors(&own, &pilot, window)[i], error[i]);
        // A noisier pixel before it raises it: pixel 5's preceding pixels are the first
        // row's four and pixel 4, one of them now of per-sample variance 0.0025 x 64.
        let mut before = uniform(0.0001, 64);
        before.variance[i - 1] = [0.0025; 3];
        let pooled = ((4.0 * 0.0064 + 0.16) / 5.0f32).sqrt() / 8.0;
        assert!((unbiased_errors(&before, &pilot, window)[i] - pooled).abs() < 1e-6);
        // So does a noisier pilot pixel anywhere in its 9 x 9 window (here the whole
        // film): one of twelve at per-sample variance 0.0016 x 16.
        let mut noisy_pilot = uniform(0.0004, 16);
        noisy_pilot.variance[i + 1] = [0.0016; 3];
        let noisy_pilot = PilotErrors::from_estimates(&noisy_pilot, window);
        let pooled = ((11.0 * 0.0064 + 0.0256) / 12.0f32).sqrt() / 8.0;
        assert!((unbiased_errors(&image, &noisy_pilot, window)[i] - pooled).abs() < 1e-6);
        // The error falls with the pixel's own count: it is the image's error at that
        // count.
        let mut more = uniform(0.0001, 64);
        more.count[i] = 256;
        assert!((unbiased_errors(&more, &pilot, window)[i] - 0.005).abs() < 1e-6);
    }
}
