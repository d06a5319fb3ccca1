//! Adaptive sampling's decisions between passes ([`RenderOptions::noise_target`]): each
//! pixel's estimated relative error from the tiles' films, which pixels stop, and the
//! summary the stats report.

use super::{NoiseTarget, RenderOutput, Tile, Window, NOISE_FLOOR_FRACTION};
use risotto_systems::adaptive::AdaptiveSummary;

/// The means and variances of the means of the window's pixels, gathered from `tiles`.
fn window_estimates(tiles: &[Tile], window: Window) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
    let (w, h) = (window.width() as usize, window.height() as usize);
    let mut value = vec![[0.0f32; 3]; w * h];
    let mut variance = vec![[0.0f32; 3]; w * h];
    for (tile, _) in tiles {
        let film = &tile.film;
        for ty in 0..film.height {
            for tx in 0..film.width {
                let src = (ty * film.width + tx) as usize;
                let x = (tile.x0 - window.x0 + tx) as usize;
                let y = (tile.y0 - window.y0 + ty) as usize;
                value[y * w + x] = film.mean(src).to_array();
                variance[y * w + x] = film.variance_of_mean(src).to_array();
            }
        }
    }
    (value, variance)
}

/// The estimated relative error of each pixel of the window ([`NoiseTarget`]).
fn window_errors(value: &[[f32; 3]], variance: &[[f32; 3]], window: Window) -> Vec<f32> {
    let (w, h) = (window.width() as usize, window.height() as usize);
    let floor = risotto_systems::adaptive::error_floor(value, NOISE_FLOOR_FRACTION);
    let mut error = vec![0.0; w * h];
    risotto_systems::adaptive::windowed_relative_error(w, h, value, variance, floor, &mut error);
    error
}

/// Stops, for good, the pixels whose estimated error has been at or below the target at two
/// consecutive pass ends (the guard against stopping on an unluckily low estimate: the
/// second look has twice the samples); returns how many still take samples.
pub(super) fn stop_converged_pixels(
    tiles: &mut [Tile],
    window: Window,
    target: NoiseTarget,
) -> usize {
    let (value, variance) = window_estimates(tiles, window);
    let error = window_errors(&value, &variance, window);
    let w = window.width() as usize;
    let mut active = 0;
    for (tile, _) in tiles.iter_mut() {
        let (tw, th) = (tile.film.width as usize, tile.film.height as usize);
        if tile.active.is_empty() {
            tile.active = vec![true; tw * th];
            tile.converged_passes = vec![0; tw * th];
        }
        for ty in 0..th {
            for tx in 0..tw {
                let local = ty * tw + tx;
                let x = (tile.x0 - window.x0) as usize + tx;
                let y = (tile.y0 - window.y0) as usize + ty;
                if tile.active[local] {
                    let passes = &mut tile.converged_passes[local];
                    *passes = if error[y * w + x] <= target.relative_error {
                        *passes + 1
                    } else {
                        0
                    };
                    tile.active[local] = *passes < 2;
                }
                active += usize::from(tile.active[local]);
            }
        }
    }
    active
}

/// The stats of an adaptive render: its sample counts and final error estimates.
pub(super) fn adaptive_summary(out: &RenderOutput, target: NoiseTarget) -> AdaptiveSummary {
    let value: Vec<[f32; 3]> = out.beauty.pixels.iter().map(|p| p.to_array()).collect();
    let variance: Vec<[f32; 3]> = out.variance.pixels.iter().map(|p| p.to_array()).collect();
    let error = window_errors(&value, &variance, out.window);
    AdaptiveSummary::new(target.relative_error, &out.film.count, &error)
}
