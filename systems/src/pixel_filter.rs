//! Pixel reconstruction filters by filter importance sampling.
//!
//! A pixel's value is the filter-weighted mean of the image function around the pixel
//! centre, `I_p = int f(x - c_p) L(x) dx / int f`. Instead of splatting each sample into
//! every pixel its filter covers (Mitsuba 3's `ImageBlock::put`, which then divides each
//! pixel by its sum of weights), the camera draws each sample's film position from the
//! filter's own density around the centre of the sample's pixel, so every sample has
//! weight 1 and lands in its pixel only: Ernst, Stamminger and Greiner, "Filter Importance
//! Sampling", IEEE Symposium on Interactive Ray Tracing 2006; pbrt-v4 (Pharr, Jakob,
//! Humphreys, *Physically Based Rendering*, 4th ed.), sec. 8.8.3 and `FilterSampler`. For a
//! filter that is never negative both estimate the same pixel value; filters with negative
//! lobes (Mitchell, Lanczos) would need signed weights and are not offered.
//!
//! Every filter here is separable, `f(x, y) = f1(x) f1(y)`, so each axis is sampled alone by
//! the exact inverse of the 1-D CDF: closed forms for the box and the tent, and for the
//! Gaussian a tabulated inverse CDF (solved exactly at construction) refined by a Newton
//! step on the integral of the density itself (so the samples follow the truncated
//! Gaussian to f32 resolution, not a piecewise approximation of it, and weight 1 is exact).
//!
//! The default, a box of radius 1/2, is the uniform jitter over the pixel square: the
//! camera then does not call [`warp_pixel_jitter`] at all and its rays are those of a
//! renderer without filters, bit for bit.

use glam::Vec2;

mod splat;
pub use splat::{film_coverage, splat_weights};

/// A pixel reconstruction filter, separable, non-negative, centred on the pixel centre;
/// distances in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
#[expect(
    clippy::large_enum_variant,
    reason = "one filter per camera; the Gaussian's tables inline keep the camera Copy"
)]
pub enum PixelFilter {
    /// `f(x) = 1` for `|x| <= radius` (Mitsuba's `box`, pbrt-v4's `box`). Radius 1/2 is the
    /// pixel square.
    Box {
        /// Half-width in pixels, finite and > 0.
        radius: f32,
    },
    /// `f(x) = max(0, 1 - |x| / radius)` (Mitsuba's `tent`, pbrt-v4's `triangle`).
    Tent {
        /// Half-width in pixels, finite and > 0.
        radius: f32,
    },
    /// The Gaussian of standard deviation `stddev` truncated at `radius` and lowered by its
    /// value there so that it reaches 0 continuously: `f(x) = max(0, exp(-x^2 / (2 s^2)) -
    /// exp(-r^2 / (2 s^2)))`, as Mitsuba 3 (`src/rfilters/gaussian.cpp`) and pbrt-v4
    /// (`GaussianFilter`) define it.
    Gaussian(GaussianFilter),
}

impl Default for PixelFilter {
    /// The box over the pixel square ([`PixelFilter::PIXEL_BOX`]).
    fn default() -> Self {
        PixelFilter::PIXEL_BOX
    }
}

impl PixelFilter {
    /// The box of radius 1/2: uniform sampling over each pixel's square.
    pub const PIXEL_BOX: PixelFilter = PixelFilter::Box { radius: 0.5 };

    /// Whether this is [`PixelFilter::PIXEL_BOX`], which needs no warp of the pixel jitter.
    #[inline]
    pub fn is_pixel_box(&self) -> bool {
        *self == PixelFilter::PIXEL_BOX
    }

    /// The radius of the filter's support in pixels (per axis).
    pub fn radius(&self) -> f32 {
        match *self {
            PixelFilter::Box { radius } | PixelFilter::Tent { radius } => radius,
            PixelFilter::Gaussian(g) => g.radius,
        }
    }

    /// The 1-D filter `f1(x)` (unnormalised; the 2-D filter is `f1(x) f1(y)`).
    pub fn eval_1d(&self, x: f32) -> f32 {
        let x = x.abs();
        match *self {
            PixelFilter::Box { radius } => {
                if x <= radius {
                    1.0
                } else {
                    0.0
                }
            }
            PixelFilter::Tent { radius } => (1.0 - x / radius).max(0.0),
            PixelFilter::Gaussian(g) => g.eval(f64::from(x)) as f32,
        }
    }

    /// The integral of [`Self::eval_1d`] over the line.
    pub fn integral_1d(&self) -> f32 {
        match *self {
            PixelFilter::Box { radius } => 2.0 * radius,
            PixelFilter::Tent { radius } => radius,
            PixelFilter::Gaussian(g) => (2.0 * g.half_integral) as f32,
        }
    }

    /// The offset from the pixel centre, in pixels, of the uniform sample `u` in [0, 1):
    /// the inverse of the 1-D filter's CDF at `u` (monotonic in `u`, so stratified samples
    /// stay stratified).
    #[inline]
    pub fn sample_1d(&self, u: f32) -> f32 {
        match *self {
            PixelFilter::Box { radius } => (2.0 * u - 1.0) * radius,
            PixelFilter::Tent { radius } => sample_tent(u, radius),
            PixelFilter::Gaussian(g) => g.sample(u),
        }
    }
}

/// Inverse CDF of the tent `1 - |x| / r` on [-r, r]: the CDF is `(x + r)^2 / (2 r^2)` left
/// of 0 and `1 - (r - x)^2 / (2 r^2)` right of it (pbrt-v4's `SampleTent`, written with the
/// same split of `u`).
#[inline]
fn sample_tent(u: f32, r: f32) -> f32 {
    if u < 0.5 {
        r * ((2.0 * u).sqrt() - 1.0)
    } else {
        r * (1.0 - (2.0 * (1.0 - u)).max(0.0).sqrt())
    }
}

/// Number of intervals of a [`GaussianFilter`]'s CDF table over [0, radius].
const GAUSSIAN_TABLE: usize = 16;

/// The truncated, lowered Gaussian of [`PixelFilter::Gaussian`] with its CDF over
/// `[0, radius]` and the inverse of it tabulated at construction.
#[derive(Clone, Copy, PartialEq)]
pub struct GaussianFilter {
    /// Standard deviation in pixels, finite and > 0.
    pub stddev: f32,
    /// Truncation radius in pixels, finite and > 0.
    pub radius: f32,
    /// `exp(-r^2 / (2 s^2))`, subtracted so the filter is 0 at the radius.
    bias: f64,
    /// `int_0^r f`.
    half_integral: f64,
    /// `int_0^{x_i} f` at `x_i = i r / GAUSSIAN_TABLE`.
    cdf: [f64; GAUSSIAN_TABLE + 1],
    /// The inverse of the half CDF at `v = k / INVERSE_TABLE`, solved to f64 precision at
    /// construction: the sampler's start and the lower end of its integral.
    inverse: [f64; INVERSE_TABLE + 1],
}

/// Entries of a [`GaussianFilter`]'s inverse-CDF table. Interpolating it linearly misses the
/// inverse by about 1e-5 pixels; one Newton step on the exact integral squares that.
const INVERSE_TABLE: usize = 256;

impl std::fmt::Debug for GaussianFilter {
    /// The parameters (the table follows from them).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GaussianFilter")
            .field("stddev", &self.stddev)
            .field("radius", &self.radius)
            .finish()
    }
}

impl GaussianFilter {
    /// The filter of standard deviation `stddev` truncated at `radius` (both in pixels);
    /// `None` unless both are finite and > 0. Mitsuba 3's default is `stddev = 0.5`,
    /// `radius = 2` (4 standard deviations); pbrt-v4's `sigma = 0.5`, `radius = 1.5`.
    pub fn new(stddev: f32, radius: f32) -> Option<GaussianFilter> {
        if !(stddev.is_finite() && stddev > 0.0 && radius.is_finite() && radius > 0.0) {
            return None;
        }
        let (s, r) = (f64::from(stddev), f64::from(radius));
        let bias = (-r * r / (2.0 * s * s)).exp();
        let mut g = GaussianFilter {
            stddev,
            radius,
            bias,
            half_integral: 0.0,
            cdf: [0.0; GAUSSIAN_TABLE + 1],
            inverse: [0.0; INVERSE_TABLE + 1],
        };
        let h = r / GAUSSIAN_TABLE as f64;
        for i in 0..GAUSSIAN_TABLE {
            let a = i as f64 * h;
            g.cdf[i + 1] = g.cdf[i] + g.integral(a, a + h);
        }
        g.half_integral = g.cdf[GAUSSIAN_TABLE];
        if g.half_integral <= 0.0 {
            return None;
        }
        for k in 0..=INVERSE_TABLE {
            g.inverse[k] = g.invert_half(k as f64 / INVERSE_TABLE as f64);
        }
        Some(g)
    }

    /// `f(x)` for `x >= 0`.
    #[inline]
    fn eval(&self, x: f64) -> f64 {
        let s = f64::from(self.stddev);
        if x > f64::from(self.radius) {
            return 0.0;
        }
        ((-x * x / (2.0 * s * s)).exp() - self.bias).max(0.0)
    }

    /// `int_a^b f` (`a <= b`) by composite 5-point Gauss-Legendre quadrature (Abramowitz and
    /// Stegun 25.4.29, exact for polynomials of degree 9) on pieces no wider than a quarter
    /// of the standard deviation, where the Gaussian is so close to a polynomial that the
    /// error is at f64 rounding (the test compares with the closed form through `erf`).
    /// Within one table interval of the defaults (`radius / 16 = 1/8` pixel) that is one
    /// piece.
    #[inline]
    fn integral(&self, a: f64, b: f64) -> f64 {
        let width = 0.25 * f64::from(self.stddev);
        // At most radius / (stddev / 4) pieces: the loader bounds radius / stddev.
        let pieces = ((b - a) / width).ceil().max(1.0) as usize;
        let step = (b - a) / pieces as f64;
        (0..pieces)
            .map(|k| self.gauss_legendre(a + k as f64 * step, a + (k + 1) as f64 * step))
            .sum()
    }

    /// `int_a^b f` by one 5-point Gauss-Legendre rule.
    #[inline]
    fn gauss_legendre(&self, a: f64, b: f64) -> f64 {
        const NODES: [f64; 5] = [
            0.0,
            -0.538_469_310_105_683_1,
            0.538_469_310_105_683_1,
            -0.906_179_845_938_664,
            0.906_179_845_938_664,
        ];
        const WEIGHTS: [f64; 5] = [
            0.568_888_888_888_888_9,
            0.478_628_670_499_366_5,
            0.478_628_670_499_366_5,
            0.236_926_885_056_189_1,
            0.236_926_885_056_189_1,
        ];
        let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
        half * NODES
            .iter()
            .zip(WEIGHTS)
            .map(|(&t, w)| w * self.eval(mid + half * t))
            .sum::<f64>()
    }

    /// The offset `x` in [-radius, radius] whose CDF is `u`: the sign from the half of
    /// [0, 1) `u` lies in (keeping the map monotonic), the magnitude by inverting
    /// `int_0^x f = t` on [0, radius].
    fn sample(&self, u: f32) -> f32 {
        let u = f64::from(u);
        let (sign, v) = if u < 0.5 {
            (-1.0, 1.0 - 2.0 * u)
        } else {
            (1.0, 2.0 * u - 1.0)
        };
        (sign * self.sample_half(v.clamp(0.0, 1.0))) as f32
    }

    /// `x` in [0, radius] with `int_0^x f = v int_0^r f`, fast: the inverse table's linear
    /// interpolation, then one Newton step `x -= (int_{x_k}^x f - (v - v_k) Z) / f(x)` on the
    /// exact integral from the table entry `x_k` (whose CDF `v_k` is exact), kept inside the
    /// entry's interval. The error after the step is about the square of the
    /// interpolation's (the test checks the CDF of the result against the closed form);
    /// where the step is not small against the interval, the full solver answers.
    #[inline]
    fn sample_half(&self, v: f64) -> f64 {
        let t = v * INVERSE_TABLE as f64;
        let k = (t as usize).min(INVERSE_TABLE - 1);
        let (a, b) = (self.inverse[k], self.inverse[k + 1]);
        let x = a + (b - a) * (t - k as f64);
        let d = self.eval(x);
        let rest = (t - k as f64) / INVERSE_TABLE as f64 * self.half_integral;
        let step = (self.integral(a, x) - rest) / d;
        // Near the radius, where f vanishes and the inverse is steep, one step is not
        // enough: those few intervals (of probability 1 / INVERSE_TABLE each) take the full
        // solver.
        if d > 0.0 && step.abs() <= 0.05 * (b - a) {
            (x - step).clamp(a, b)
        } else {
            self.invert_half(v)
        }
    }

    /// `x` in [0, radius] with `int_0^x f = v int_0^r f`, to f64 precision (the inverse
    /// table's entries): the CDF table's interval, then Newton
    /// steps `x -= (F(x) - t) / f(x)` on the exact integral, kept inside a shrinking bracket
    /// (bisection whenever a step leaves it, as where `f` vanishes at the radius).
    fn invert_half(&self, v: f64) -> f64 {
        let target = v * self.half_integral;
        // The last table entry with cdf <= target.
        let i = self.cdf[1..GAUSSIAN_TABLE]
            .partition_point(|&c| c <= target)
            .min(GAUSSIAN_TABLE - 1);
        let h = f64::from(self.radius) / GAUSSIAN_TABLE as f64;
        let (mut lo, mut hi) = (i as f64 * h, (i + 1) as f64 * h);
        let (base, span) = (self.cdf[i], self.cdf[i + 1] - self.cdf[i]);
        let rest = target - base;
        // Linear start inside the interval.
        let mut x = if span > 0.0 {
            lo + h * (rest / span).clamp(0.0, 1.0)
        } else {
            lo
        };
        let x0 = lo;
        // Far below f32 resolution of the offset (6e-8 relative).
        let tolerance = 1e-9 * f64::from(self.radius);
        for _ in 0..40 {
            let g = self.integral(x0, x) - rest;
            if g > 0.0 {
                hi = x;
            } else {
                lo = x;
            }
            let d = self.eval(x);
            let step = if d > 0.0 { g / d } else { f64::INFINITY };
            // Converged: accept before the bracket test (x itself is now a bracket end, and a
            // step of rounding size could point out of it).
            if step.abs() <= tolerance {
                x -= step;
                break;
            }
            let next = x - step;
            x = if next > lo && next < hi {
                next
            } else {
                0.5 * (lo + hi)
            };
            if hi - lo <= tolerance {
                break;
            }
        }
        x.clamp(0.0, f64::from(self.radius))
    }
}

/// Turns pixel jitter in [0, 1)^2 (uniform over the pixel square, measured from its corner)
/// into film offsets from the pixel corner distributed as `filter` around the pixel centre:
/// `jitter <- 1/2 + (sample_1d(jitter.x), sample_1d(jitter.y))`, in place. Each axis is a
/// monotonic map of its own sample dimension, so the sampler's stratification carries over.
/// Offsets may leave the pixel (and the image, at its border) by up to the filter radius.
pub fn warp_pixel_jitter(filter: &PixelFilter, jitter: &mut [Vec2]) {
    match *filter {
        PixelFilter::Box { radius } => {
            for j in jitter {
                *j = Vec2::splat(0.5) + (*j * 2.0 - Vec2::ONE) * radius;
            }
        }
        PixelFilter::Tent { radius } => {
            for j in jitter {
                *j = Vec2::new(
                    0.5 + sample_tent(j.x, radius),
                    0.5 + sample_tent(j.y, radius),
                );
            }
        }
        PixelFilter::Gaussian(g) => {
            for j in jitter {
                *j = Vec2::new(0.5 + g.sample(j.x), 0.5 + g.sample(j.y));
            }
        }
    }
}

#[cfg(test)]
mod tests;
