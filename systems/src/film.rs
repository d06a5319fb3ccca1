//! The film and the splat system; light-traced contributions, which land at any pixel,
//! go to the thread-shared fixed-point [`SplatFilm`].
//!
//! Per pixel the film keeps the sum of sample radiance, the sum of squares and the sample
//! count, so the mean and the variance of the mean can be reported. Non-finite samples (NaN,
//! infinity) are never splatted: they are counted and dropped (the sample still counts as
//! taken, with zero radiance, so the estimator stays unbiased for the finite ones).
//!
//! The sums are kept in f64, so no finite f32 radiance can overflow them (`2^32` samples
//! of `f32::MAX` squared is 1.5e86, far below f64's 1.8e308); in f32, 16 samples of 1e38
//! summed to infinity and a radiance of 1e20 squared to infinity in the sum of squares
//! (issue 14 item 7). The reported layers are f32: the mean of finite f32 samples is
//! finite, and the variance of the mean saturates at `f32::MAX` (reached for radiance
//! varying by more than about 1e19), the film's documented maximum.

/// Largest `width * height` of a film: 2^26 pixels (8192 x 8192), whose render takes about
/// 15 GB (the engine's measured `FILM_BYTES_PER_PIXEL`, 224 bytes a pixel). What asks for
/// more (a scene, a partial render) is refused with the value rather than aborting an
/// allocation; the engine also refuses a film larger than the machine's memory.
pub const MAX_PIXELS: u64 = 1 << 26;

use risotto_components::Rgb;

mod splat;
pub use splat::SplatFilm;

/// Accumulated samples for a rectangle of pixels (a whole image or one tile).
#[derive(Clone, Debug)]
pub struct Film {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Sum of sample radiance per pixel (r, g, b), in f64.
    pub sum: Vec<[f64; 3]>,
    /// Sum of squared sample radiance per pixel (per channel), in f64.
    pub sum_sq: Vec<[f64; 3]>,
    /// Number of samples per pixel.
    pub count: Vec<u32>,
    /// Samples dropped because they were not finite.
    pub nan_dropped: u64,
}

impl Film {
    /// An empty film.
    pub fn new(width: u32, height: u32) -> Self {
        let n = (width as usize) * (height as usize);
        Film {
            width,
            height,
            sum: vec![[0.0; 3]; n],
            sum_sq: vec![[0.0; 3]; n],
            count: vec![0; n],
            nan_dropped: 0,
        }
    }

    /// Mean radiance of pixel `i` (finite: a mean of finite f32 samples).
    pub fn mean(&self, i: usize) -> Rgb {
        if self.count[i] == 0 {
            Rgb::BLACK
        } else {
            let n = self.count[i] as f64;
            let [r, g, b] = self.sum[i].map(|s| (s / n) as f32);
            Rgb::new(r, g, b)
        }
    }

    /// Variance of the mean estimate of pixel `i` (sample variance / n), per channel.
    pub fn variance_of_mean(&self, i: usize) -> Rgb {
        let n = self.count[i] as f64;
        if n < 2.0 {
            return Rgb::BLACK;
        }
        let var = |c: usize| -> f32 {
            let (s, s2) = (self.sum[i][c], self.sum_sq[i][c]);
            let v = (s2 - s * s / n) / (n - 1.0);
            // Saturates at the largest f32 rather than rounding to infinity.
            (v.max(0.0) / n).min(f32::MAX as f64) as f32
        };
        Rgb::new(var(0), var(1), var(2))
    }

    /// Adds another film of the same size (used to gather tiles).
    pub fn add_tile(&mut self, tile: &Film, x0: u32, y0: u32) {
        for ty in 0..tile.height {
            for tx in 0..tile.width {
                let src = (ty * tile.width + tx) as usize;
                let dst = ((y0 + ty) * self.width + (x0 + tx)) as usize;
                for c in 0..3 {
                    self.sum[dst][c] += tile.sum[src][c];
                    self.sum_sq[dst][c] += tile.sum_sq[src][c];
                }
                self.count[dst] += tile.count[src];
            }
        }
        self.nan_dropped += tile.nan_dropped;
    }
}

/// Per-pixel sums of first-hit AOVs for a rectangle of pixels (a whole image or one tile),
/// in f64 like [`Film`]'s sums. Each camera sample adds its first hit's albedo, shading
/// normal and distance along the camera ray; a sample whose camera ray hit nothing adds
/// zeros (and an infinite distance adds zero). The means divide by the [`Film::count`] of
/// the same pixel: every sample taken, including those whose radiance was dropped as
/// non-finite.
#[derive(Clone, Debug, PartialEq)]
pub struct AovFilm {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Sum of first-hit albedo per pixel (r, g, b).
    pub albedo: Vec<[f64; 3]>,
    /// Sum of first-hit shading normals per pixel (x, y, z; world space).
    pub normal: Vec<[f64; 3]>,
    /// Sum of first-hit distances per pixel.
    pub depth: Vec<f64>,
}

impl AovFilm {
    /// Empty sums.
    pub fn new(width: u32, height: u32) -> Self {
        let n = (width as usize) * (height as usize);
        AovFilm {
            width,
            height,
            albedo: vec![[0.0; 3]; n],
            normal: vec![[0.0; 3]; n],
            depth: vec![0.0; n],
        }
    }

    /// A film of `width x height` pixels that holds no sums, for a render whose AOVs nobody
    /// reads (an adaptive render's pilot): [`Self::holds_sums`] is false, the splat skips it
    /// and adding it to another film adds nothing.
    pub fn without_sums(width: u32, height: u32) -> Self {
        AovFilm {
            width,
            height,
            albedo: Vec::new(),
            normal: Vec::new(),
            depth: Vec::new(),
        }
    }

    /// Whether the film holds its pixels' sums (not one made by [`Self::without_sums`]; a
    /// film of no pixels holds none).
    pub fn holds_sums(&self) -> bool {
        !self.depth.is_empty()
    }

    /// Mean albedo of pixel `i` over `count` samples (black for none).
    pub fn albedo_mean(&self, i: usize, count: u32) -> Rgb {
        let [r, g, b] = self.albedo[i].map(|s| mean(s, count));
        Rgb::new(r, g, b)
    }

    /// Mean shading normal of pixel `i` over `count` samples (not renormalised; zero for
    /// none).
    pub fn normal_mean(&self, i: usize, count: u32) -> [f32; 3] {
        self.normal[i].map(|s| mean(s, count))
    }

    /// Mean first-hit distance of pixel `i` over `count` samples (0 for none).
    pub fn depth_mean(&self, i: usize, count: u32) -> f32 {
        mean(self.depth[i], count)
    }

    /// Adds the sums of `tile` (a rectangle at `(x0, y0)` of this one), as
    /// [`Film::add_tile`] does.
    pub fn add_tile(&mut self, tile: &AovFilm, x0: u32, y0: u32) {
        if !tile.holds_sums() || !self.holds_sums() {
            return;
        }
        for ty in 0..tile.height {
            for tx in 0..tile.width {
                let src = (ty * tile.width + tx) as usize;
                let dst = ((y0 + ty) * self.width + (x0 + tx)) as usize;
                for c in 0..3 {
                    self.albedo[dst][c] += tile.albedo[src][c];
                    self.normal[dst][c] += tile.normal[src][c];
                }
                self.depth[dst] += tile.depth[src];
            }
        }
    }
}

/// `sum / count` as f32, 0 for no samples.
fn mean(sum: f64, count: u32) -> f32 {
    if count == 0 {
        0.0
    } else {
        (sum / count as f64) as f32
    }
}

/// Splats finished samples: `pixel[i]` (an index into `film`) receives `radiance[i]`.
/// Returns how many samples were dropped as non-finite.
pub fn splat(film: &mut Film, pixel: &[u32], radiance: &[Rgb]) -> u64 {
    // The three per-pixel columns cut to one length, so one bounds check covers all three.
    let n = film.count.len();
    let (sum, sum_sq, count) = (&mut film.sum[..n], &mut film.sum_sq[..n], &mut film.count);
    let mut dropped = 0;
    // Samples come in runs of one pixel (a batch holds each pixel's samples together): the
    // pixel's sums stay in registers during a run and are stored when the pixel changes.
    // Adding to memory per sample chained every sum through a store and a reload; the
    // additions happen in the same order, so the sums are the same bits.
    let Some(&first) = pixel.first() else {
        return 0;
    };
    let mut p = first as usize;
    let (mut s, mut sq, mut c) = (sum[p], sum_sq[p], count[p]);
    for (&q, &l) in pixel.iter().zip(radiance) {
        let q = q as usize;
        if q != p {
            (sum[p], sum_sq[p], count[p]) = (s, sq, c);
            p = q;
            (s, sq, c) = (sum[p], sum_sq[p], count[p]);
        }
        c += 1;
        // x - x is 0 for every finite x and NaN for infinities and NaN, so the sum is 0
        // exactly when all three channels are finite (fewer instructions than three
        // is_finite tests).
        #[allow(clippy::eq_op, reason = "x - x is the finiteness test")]
        let finite = (l.r - l.r) + (l.g - l.g) + (l.b - l.b) == 0.0;
        if finite {
            let l = [l.r as f64, l.g as f64, l.b as f64];
            for c in 0..3 {
                s[c] += l[c];
                sq[c] += l[c] * l[c];
            }
        } else {
            dropped += 1;
        }
    }
    (sum[p], sum_sq[p], count[p]) = (s, sq, c);
    film.nan_dropped += dropped;
    dropped
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_and_variance_match_direct_computation() {
        let mut f = Film::new(2, 1);
        let vals = [1.0f32, 2.0, 4.0, 7.0];
        let rad: Vec<Rgb> = vals.iter().map(|&v| Rgb::splat(v)).collect();
        splat(&mut f, &[1, 1, 1, 1], &rad);
        assert_eq!(f.mean(1), Rgb::splat(3.5));
        // sample variance of {1,2,4,7} = 7, variance of the mean = 7/4.
        assert!((f.variance_of_mean(1).r - 1.75).abs() < 1e-6);
        assert_eq!(f.count[0], 0);
    }

    #[test]
    fn splat_in_any_pixel_order_equals_per_sample_sums() {
        // Runs, revisits and single samples, in two calls (sums carry over): every sum must
        // be the in-order sum of its pixel's samples, bit for bit.
        let mut f = Film::new(3, 1);
        let pixel = [2u32, 2, 0, 0, 0, 2, 1, 2, 2, 0];
        let rad: Vec<Rgb> = (0..pixel.len())
            .map(|i| {
                Rgb::new(
                    0.1 * i as f32 + 0.3,
                    1.0 / (i as f32 + 3.0),
                    7.77 * i as f32,
                )
            })
            .collect();
        splat(&mut f, &pixel[..6], &rad[..6]);
        splat(&mut f, &pixel[6..], &rad[6..]);
        let (mut sum, mut sq, mut count) = ([[0.0f64; 3]; 3], [[0.0f64; 3]; 3], [0u32; 3]);
        for (&p, &l) in pixel.iter().zip(&rad) {
            for (c, x) in l.to_array().into_iter().enumerate() {
                sum[p as usize][c] += x as f64;
                sq[p as usize][c] += x as f64 * x as f64;
            }
            count[p as usize] += 1;
        }
        assert_eq!(f.sum, sum.to_vec());
        assert_eq!(f.sum_sq, sq.to_vec());
        assert_eq!(f.count, count.to_vec());
        assert_eq!(splat(&mut f, &[], &[]), 0, "empty input");
    }

    #[test]
    fn non_finite_samples_are_counted_not_splatted() {
        let mut f = Film::new(1, 1);
        let d = splat(
            &mut f,
            &[0, 0, 0],
            &[
                Rgb::splat(1.0),
                Rgb::new(f32::NAN, 0.0, 0.0),
                Rgb::splat(f32::INFINITY),
            ],
        );
        assert_eq!(d, 2);
        assert_eq!(f.nan_dropped, 2);
        assert_eq!(f.sum[0], [1.0; 3]);
        assert_eq!(f.count[0], 3);
    }

    /// Issue 14 item 7: in f32 sums, 16 samples of 1e38 gave an infinite mean and samples
    /// of 1e20 an infinite variance. The mean stays exact, the variance finite (saturating
    /// at `f32::MAX` where the true value exceeds it).
    #[test]
    fn huge_finite_radiance_does_not_overflow() {
        let mut f = Film::new(2, 1);
        let huge: Vec<Rgb> = (0..16).map(|_| Rgb::splat(1e38)).collect();
        splat(&mut f, &[0; 16], &huge);
        assert_eq!(f.mean(0), Rgb::splat(1e38));
        assert!(f.variance_of_mean(0).is_finite());
        let bright: Vec<Rgb> = (0..16)
            .map(|i| Rgb::new(1e20 * (i % 2) as f32, 1e20, f32::MAX * (i % 2) as f32))
            .collect();
        splat(&mut f, &[1; 16], &bright);
        let (m, v) = (f.mean(1), f.variance_of_mean(1));
        assert!((m.r / 5e19 - 1.0).abs() < 1e-6, "{m:?}");
        // Sample variance of eight 0s and eight 1e20s: 16/15 * 0.25e40; over 16 samples.
        assert!((v.r as f64 / (0.25e40 / 15.0) - 1.0).abs() < 1e-5, "{v:?}");
        assert!(v.g < 1e-3 * v.r, "{v:?}");
        assert_eq!(v.b, f32::MAX);
        assert_eq!(f.nan_dropped, 0);
    }

    #[test]
    fn aov_tiles_add_in_place_and_means_divide_by_the_count() {
        let mut tile = AovFilm::new(1, 2);
        tile.albedo[1] = [1.5, 0.0, 3.0];
        tile.normal[1] = [0.0, -2.0, 0.0];
        tile.depth[1] = 7.0;
        let mut whole = AovFilm::new(3, 2);
        whole.add_tile(&tile, 2, 0);
        whole.add_tile(&tile, 2, 0);
        // Pixel (2, 1): twice the tile's pixel 1.
        assert_eq!(whole.albedo[5], [3.0, 0.0, 6.0]);
        assert_eq!(whole.depth[5], 14.0);
        assert_eq!(whole.albedo_mean(5, 4), Rgb::new(0.75, 0.0, 1.5));
        assert_eq!(whole.normal_mean(5, 4), [0.0, -1.0, 0.0]);
        assert_eq!(whole.depth_mean(5, 4), 3.5);
        // No samples: zero, not NaN.
        assert_eq!(whole.depth_mean(0, 0), 0.0);
        assert_eq!(whole.albedo_mean(5, 0), Rgb::BLACK);
    }

    /// A film without sums holds nothing and adds nothing; a film with sums holds them.
    #[test]
    fn a_film_without_sums_holds_and_adds_nothing() {
        let none = AovFilm::without_sums(1, 2);
        assert!(!none.holds_sums() && none.albedo.is_empty() && none.depth.is_empty());
        assert!(AovFilm::new(1, 2).holds_sums());
        let mut whole = AovFilm::new(3, 2);
        whole.depth[5] = 2.0;
        whole.add_tile(&none, 2, 0);
        assert_eq!(whole, {
            let mut w = AovFilm::new(3, 2);
            w.depth[5] = 2.0;
            w
        });
    }
}
