//! The light-traced image of a bidirectional integrator
//! ([`Integrator::splats`](crate::integrator::Integrator::splats)) added to a gathered film.

use super::Window;
use risotto_systems::film::{Film, SplatFilm};

/// Adds the light-traced image `splat` (sums over the whole image, times `scale`) to the
/// window's film: each pixel's sum grows by its splat value times its sample count, so
/// that its mean is the camera paths' mean plus the splats'. The sums of squares are the
/// camera paths' alone: the variance layer does not include the splats' noise.
pub(super) fn add_splats(film: &mut Film, window: Window, splat: &SplatFilm, scale: f64) {
    let w = window.width();
    for y in window.y0..window.y1 {
        for x in window.x0..window.x1 {
            let j = ((y - window.y0) * w + (x - window.x0)) as usize;
            let s = splat.sum(y * splat.width() + x);
            let count = f64::from(film.count[j]);
            for c in 0..3 {
                film.sum[j][c] += s[c] * scale * count;
            }
        }
    }
}
