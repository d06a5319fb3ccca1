//! The light-traced image of a bidirectional integrator
//! ([`Integrator::splats`](crate::integrator::Integrator::splats)) added to a gathered film.

use super::Window;
use risotto_systems::film::{Film, SplatFilm};

/// Adds the light-traced image `splat` (sums over the whole image, times `scale`, which is
/// `width * height / N` for `N` light subpaths) to the window's film, mean and variance.
///
/// A pixel's `n` camera samples `x_i` (sums `S = sum x_i`, `Q = sum x_i^2`) become
/// `x_i + m` for the splats' mean `m`: `S += n m` and `Q += 2 m S + n m^2`, so that the
/// camera samples' variance is unchanged (adding `n m` to `S` alone would shrink it, to
/// nothing where the splats outweigh the camera paths). The splats' own variance of the
/// mean is then added: `m = scale sum_j c_j` over the light subpaths' contributions `c_j`
/// to the pixel, independent of the camera samples, so `Var(m) = scale^2 N Var(c) =
/// scale^2 (sum c_j^2 - (sum c_j)^2 / N)` (the squares are per splat: two vertices of one
/// light subpath in the same pixel count as two, a small underestimate), which enters the
/// film's variance of the mean `(Q - S^2 / n) / ((n - 1) n)` as `Q += n (n - 1) Var(m)`.
pub(super) fn add_splats(film: &mut Film, window: Window, splat: &SplatFilm, scale: f64) {
    let w = window.width();
    let light_paths = f64::from(splat.width()) * f64::from(splat.height()) / scale;
    for y in window.y0..window.y1 {
        for x in window.x0..window.x1 {
            let j = ((y - window.y0) * w + (x - window.x0)) as usize;
            let pixel = y * splat.width() + x;
            let (s, q) = (splat.sum(pixel), splat.sum_of_squares(pixel));
            let n = f64::from(film.count[j]);
            for c in 0..3 {
                let m = s[c] * scale;
                let var_of_mean = (scale * scale * (q[c] - s[c] * s[c] / light_paths)).max(0.0);
                let sum = film.sum[j][c];
                film.sum_sq[j][c] += 2.0 * m * sum + n * m * m + n * (n - 1.0) * var_of_mean;
                film.sum[j][c] = sum + n * m;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use risotto_components::Rgb;

    /// The camera samples' variance survives the splats' mean, and the splats' variance of
    /// the mean is added to it: against sums written out by hand.
    #[test]
    fn splats_add_their_mean_and_their_variance() {
        let window = Window {
            x0: 0,
            y0: 0,
            x1: 1,
            y1: 1,
        };
        let mut film = Film::new(1, 1);
        // Camera samples 1, 2, 3, 6: mean 3, sample variance 14 / 3.
        for x in [1.0f64, 2.0, 3.0, 6.0] {
            for c in 0..3 {
                film.sum[0][c] += x;
                film.sum_sq[0][c] += x * x;
            }
            film.count[0] += 1;
        }
        let camera_var_of_mean = 14.0 / 3.0 / 4.0;
        // Light subpaths: 4 traced, two of them splat 0.5 and 1.5 here; scale 1 / 4 (one
        // pixel): the splats' mean is (0.5 + 1.5) / 4 = 0.5 and its variance
        // (1 / 16) (0.25 + 2.25 - 4 / 4) = 0.09375.
        let splat = SplatFilm::new(1, 1).unwrap();
        splat.add(0, Rgb::splat(0.5));
        splat.add(0, Rgb::splat(1.5));
        add_splats(&mut film, window, &splat, 0.25);
        let mean = film.mean(0);
        assert!((mean.g - 3.5).abs() < 1e-6, "{mean:?}");
        let v = film.variance_of_mean(0).g as f64;
        let expected = camera_var_of_mean + 0.09375;
        assert!((v - expected).abs() < 1e-6 * expected, "{v} vs {expected}");
    }
}
