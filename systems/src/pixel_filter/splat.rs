//! Splatting a film position into the pixels whose filters cover it: the light-tracing
//! side of the [`PixelFilter`].
//!
//! The camera estimates pixel `j` as `I_j = int f(x - c_j) L(x) dx / int f` by drawing film
//! positions from the filter around the pixel centre `c_j` (filter importance sampling,
//! [`super::warp_pixel_jitter`]). A light-traced contribution arrives at one film position
//! `x` instead, and estimates the same integrals when it is added to every pixel `j` with
//! weight `f(x - c_j) / int f` (Veach's thesis, sec. 10.3.3.3, the light-tracing
//! measurement; pbrt-v4's `RGBFilm::AddSplat`, which weighs by the filter value alone and
//! normalises by its integral through the film's scale). The weights are *not* renormalised
//! to sum to 1: they sum to `sum_j f(x - c_j) / int f`, which is exactly 1 for a box whose
//! width is a whole number of pixels or a tent of radius 1, within about 1.5 % for the
//! Gaussian of standard deviation 1/2 (its lattice sum, by Poisson summation), and less
//! than 1 near the image border, where part of the footprint falls outside the image. That
//! is what the camera's filter-sampled rays estimate too, so the two images agree pixel
//! for pixel in expectation.
//!
//! Film positions are in pixels, `(0, 0)` the top-left corner of the image; the centre of
//! pixel `(i, j)` is `(i + 1/2, j + 1/2)`.

use super::PixelFilter;
use glam::Vec2;
use smallvec::SmallVec;

/// The 1-D weight of a pixel whose centre is `d` pixels from the film position. The box
/// covers the half-open interval `[-radius, radius)`, so a position on the border of two
/// pixel-box footprints lands in one pixel, not both (the other filters vanish at their
/// radius).
#[inline]
fn weight_1d(filter: &PixelFilter, d: f32) -> f32 {
    match *filter {
        PixelFilter::Box { radius } => {
            if d >= -radius && d < radius {
                1.0
            } else {
                0.0
            }
        }
        _ => filter.eval_1d(d),
    }
}

/// The pixel indices along one axis of `n` pixels whose filter footprint (centre
/// `k + 1/2`, `radius`) may cover `x`: `k` in `[lo, hi)` with `lo = ceil(x - 1/2 - radius)`
/// and `hi = floor(x - 1/2 + radius) + 1`, clamped to the image. Empty for a non-finite
/// `x`.
#[inline]
fn axis_range(x: f32, radius: f32, n: u32) -> (u32, u32) {
    if !x.is_finite() {
        return (0, 0);
    }
    let clamp = |k: i64| k.clamp(0, i64::from(n)) as u32;
    (
        clamp(floor(-(x - 0.5 - radius)).saturating_neg()),
        clamp(floor(x - 0.5 + radius).saturating_add(1)),
    )
}

/// `floor(y)` as an integer (saturating far outside the i64 range) by truncation and a
/// correction for negative non-integers: `f32::floor` is a libm call on the baseline
/// x86-64 target, and a splat takes four.
#[inline(always)]
fn floor(y: f32) -> i64 {
    let t = y as i64;
    t.saturating_sub(i64::from((t as f32) > y))
}

/// The pixels (row-major index, weight) a contribution at film position `film` adds to, for
/// an image of `width x height` pixels with pixel filter `filter`: every pixel whose
/// footprint covers `film`, with weight `f(film - centre) / int f` (the module's
/// normalisation). `out` is cleared first; pixels of weight 0 are left out, and a
/// position no pixel's filter covers (outside the image by more than the filter reaches,
/// or not finite) leaves `out` empty.
pub fn splat_weights(
    filter: &PixelFilter,
    film: Vec2,
    width: u32,
    height: u32,
    out: &mut SmallVec<[(u32, f32); 16]>,
) {
    out.clear();
    let radius = filter.radius();
    let (x0, x1) = axis_range(film.x, radius, width);
    let (y0, y1) = axis_range(film.y, radius, height);
    if x0 >= x1 || y0 >= y1 {
        return;
    }
    // Separable: the x weights once, then one product per pixel.
    let norm = 1.0 / filter.integral_1d();
    let mut wx: SmallVec<[f32; 8]> = SmallVec::new();
    wx.extend((x0..x1).map(|i| weight_1d(filter, film.x - (i as f32 + 0.5)) * norm));
    for j in y0..y1 {
        let wy = weight_1d(filter, film.y - (j as f32 + 0.5)) * norm;
        if wy == 0.0 {
            continue;
        }
        for (i, &w) in (x0..x1).zip(&wx) {
            let weight = w * wy;
            if weight > 0.0 {
                out.push((j * width + i, weight));
            }
        }
    }
}

/// `sum_j f(film - c_j) / int f` over the pixels `j` of a `width x height` image: the sum of
/// [`splat_weights`], computed per axis. It is the density, relative to uniform, of the
/// film positions a camera draws when it takes the same number of samples in every pixel
/// and places them by [`super::warp_pixel_jitter`]: the film-position density is this over
/// `width * height` (per square pixel). 1 inside the image for the pixel box, 0 where no
/// pixel's filter reaches.
pub fn film_coverage(filter: &PixelFilter, film: Vec2, width: u32, height: u32) -> f32 {
    if filter.is_pixel_box() {
        // One pixel per axis covers a position in `[0, n)` (the box is half-open), with
        // weight 1 over an integral of 1: the sum below, without its floors and loops (the
        // default filter, and one coverage per light vertex connected to the camera).
        let inside = |x: f32, n: u32| (0.0..n as f32).contains(&x);
        return (inside(film.x, width) && inside(film.y, height)) as u32 as f32;
    }
    let axis = |x: f32, n: u32| -> f32 {
        let (lo, hi) = axis_range(x, filter.radius(), n);
        (lo..hi)
            .map(|k| weight_1d(filter, x - (k as f32 + 0.5)))
            .sum::<f32>()
            / filter.integral_1d()
    };
    axis(film.x, width) * axis(film.y, height)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pixel_filter::GaussianFilter;
    use crate::sampler::SplitMix64;
    use std::f32::consts::PI;

    fn filters() -> [PixelFilter; 5] {
        [
            PixelFilter::PIXEL_BOX,
            PixelFilter::Box { radius: 1.5 },
            PixelFilter::Tent { radius: 1.0 },
            PixelFilter::Tent { radius: 1.7 },
            PixelFilter::Gaussian(GaussianFilter::new(0.5, 2.0).unwrap()),
        ]
    }

    /// Inside the image (farther than the radius from the border) the weights sum to the
    /// filter's lattice sum over its integral: exactly 1 for a pixel box, a box of radius
    /// 3/2 and a tent of radius 1 (partitions of unity), and within the Poisson-summation
    /// bound for the others (`2 sum_k |F(k)| / F(0)` per axis, `F` the filter's Fourier
    /// transform: 1.45 % for the Gaussian of standard deviation 1/2, whose
    /// `|F(k)| / F(0) = exp(-2 pi^2 s^2 k^2)`; `sinc^2(k r)` for a tent of radius `r`).
    /// Each weight is the filter at the offset over its integral, and the weights equal
    /// [`film_coverage`]'s sum.
    #[test]
    fn splat_weights_sum_to_one_inside_the_image() {
        let (w, h) = (20u32, 15u32);
        let mut rng = SplitMix64(3);
        let mut out = SmallVec::new();
        for filter in filters() {
            // Per axis, 2 sum_k |F(k)| / F(0); the Gaussian's truncation and lowering
            // (by exp(-8)) move its transform by less than the 0.2 % of slack.
            let per_axis: f32 = match filter {
                PixelFilter::Gaussian(_) => 2.0 * (-2.0 * PI * PI * 0.25).exp() + 2e-3,
                PixelFilter::Tent { radius } if radius != 1.0 => (1..200)
                    .map(|k| {
                        let t = PI * radius * k as f32;
                        2.0 * (t.sin() / t).powi(2)
                    })
                    .sum(),
                _ => 0.0,
            };
            let bound = (1.0 + per_axis).powi(2) - 1.0;
            let mut worst: f32 = 0.0;
            for _ in 0..2000 {
                let film = Vec2::new(3.0, 3.0) + rng.vec2() * Vec2::new(14.0, 9.0);
                splat_weights(&filter, film, w, h, &mut out);
                let sum: f32 = out.iter().map(|p| p.1).sum();
                worst = worst.max((sum - 1.0).abs());
                assert!((sum - film_coverage(&filter, film, w, h)).abs() < 1e-5);
                for &(p, weight) in &out {
                    let c = Vec2::new((p % w) as f32 + 0.5, (p / w) as f32 + 0.5);
                    let want = filter.eval_1d(film.x - c.x) * filter.eval_1d(film.y - c.y)
                        / filter.integral_1d().powi(2);
                    assert!((weight - want).abs() < 1e-6, "{filter:?} {film} {p}");
                }
                // No pixel left out: every pixel of positive weight is in `out`.
                let listed: f32 = (0..w * h)
                    .map(|p| {
                        let c = Vec2::new((p % w) as f32 + 0.5, (p / w) as f32 + 0.5);
                        weight_1d(&filter, film.x - c.x) * weight_1d(&filter, film.y - c.y)
                    })
                    .sum::<f32>()
                    / filter.integral_1d().powi(2);
                assert!((listed - sum).abs() < 1e-5, "{filter:?} {film}");
            }
            assert!(worst <= bound + 1e-5, "{filter:?}: {worst} > {bound}");
            if bound == 0.0 {
                assert!(worst < 1e-5);
            } else {
                // The lattice sum does vary: a test of the bound, not of a constant.
                assert!(worst > 0.1 * bound, "{filter:?}: {worst}");
            }
        }
    }

    /// The integer floor equals `f32::floor` on integers, halves and their neighbours of
    /// both signs, and saturates instead of overflowing far out.
    #[test]
    fn integer_floor_is_floor() {
        for k in -300..300 {
            for y in [k as f32, k as f32 + 0.5, k as f32 - 1e-3, k as f32 * 1.37] {
                assert_eq!(floor(y), y.floor() as i64, "{y}");
            }
        }
        assert_eq!(floor(-1e30), i64::MIN);
        assert_eq!(floor(1e30), i64::MAX);
    }

    /// The pixel box puts a position in exactly the pixel whose square holds it (the
    /// half-open convention at shared borders), and nothing outside the image.
    #[test]
    fn pixel_box_splats_into_the_pixel_holding_the_position() {
        let mut out = SmallVec::new();
        let f = PixelFilter::PIXEL_BOX;
        for (film, want) in [
            (Vec2::new(0.0, 0.0), Some(0)),
            (Vec2::new(3.0, 2.0), Some(2 * 8 + 3)),
            (Vec2::new(7.999, 4.5), Some(4 * 8 + 7)),
            (Vec2::new(8.0, 1.0), None),
            (Vec2::new(-0.001, 1.0), None),
            (Vec2::new(f32::NAN, 1.0), None),
            (Vec2::new(1e30, -1e30), None),
        ] {
            splat_weights(&f, film, 8, 5, &mut out);
            assert_eq!(out.first().map(|p| p.0), want, "{film}");
            assert!(out.len() <= 1);
            assert!(out.iter().all(|p| p.1 == 1.0));
        }
    }

    /// Near the border a wide filter's footprint reaches out of the image: the weights
    /// cover only the pixels inside and sum to less than 1, and a position outside the
    /// image but within the radius still reaches the border pixels.
    #[test]
    fn footprints_are_clipped_at_the_border() {
        let mut out = SmallVec::new();
        let f = PixelFilter::Tent { radius: 1.5 };
        splat_weights(&f, Vec2::new(-0.4, 2.5), 6, 6, &mut out);
        assert!(!out.is_empty());
        assert!(out.iter().all(|&(p, _)| p % 6 == 0));
        let sum: f32 = out.iter().map(|p| p.1).sum();
        assert!(sum > 0.0 && sum < 0.5, "{sum}");
        splat_weights(&f, Vec2::new(-1.1, 2.5), 6, 6, &mut out);
        assert!(out.is_empty());
        assert_eq!(film_coverage(&f, Vec2::new(-1.1, 2.5), 6, 6), 0.0);
    }

    /// The pixel box's coverage (a shortcut) is the sum of its splat weights (the general
    /// path) everywhere: inside, on and just off every border, and at non-finite positions.
    #[test]
    fn pixel_box_coverage_is_the_sum_of_its_weights() {
        let (w, h) = (5u32, 3u32);
        let mut out = SmallVec::new();
        let xs = [
            -1.0,
            -1e-7,
            -0.0,
            0.0,
            0.5,
            2.5,
            4.999_999_5,
            5.0,
            5.000_001,
            7.0,
        ];
        let ys = [-0.0, 1e-7, 1.0, 2.999_999_8, 3.0, f32::NAN, f32::INFINITY];
        for &x in &xs {
            for &y in &ys {
                let film = Vec2::new(x, y);
                splat_weights(&PixelFilter::PIXEL_BOX, film, w, h, &mut out);
                let sum: f32 = out.iter().map(|p| p.1).sum();
                let c = film_coverage(&PixelFilter::PIXEL_BOX, film, w, h);
                // (An empty sum is -0: equal to the shortcut's 0, and refused alike.)
                assert_eq!(c, sum, "{film}");
            }
        }
    }
}
