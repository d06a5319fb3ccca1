//! The splat film: an image-wide accumulator every worker thread adds light-traced
//! contributions to, at whatever pixel they land.
//!
//! Camera samples land in their own pixel, so the tile [`Film`](super::Film)s need no
//! sharing; light-subpath vertices connected to the camera (light tracing, BDPT, VCM)
//! land anywhere. Floating-point sums shared by threads would depend on the order of the
//! additions (f32 and f64 addition is not associative), and the renderer promises images
//! that do not depend on the thread count. So each pixel and channel is an [`AtomicI64`]
//! in fixed point: a value `v` is added as `round(v * 2^32)` ([`SplatFilm::SCALE`]), and
//! integer addition is associative, so the sums are the same bits in every order.
//!
//! Range: the resolution is `2^-32`, so a contribution of `2^-24` is 256 units (rounded to
//! 1/512 of itself at worst); a sum reaches at most `(2^63 - 1) / 2^32`, just under `2^31`,
//! so sums up to `2^30` per pixel and channel have a factor of two to spare. A sum that
//! would pass the range saturates at it (the extreme `i64`) instead of wrapping, and every
//! saturated addition is counted; for contributions of one sign (radiance) saturation is
//! still independent of the order. Non-finite contributions are never added: they are
//! dropped and counted, all three channels together.

use crate::pixel_filter::{splat_weights, PixelFilter};
use glam::Vec2;
use risotto_components::Rgb;
use smallvec::SmallVec;
use std::sync::atomic::{AtomicI64, AtomicU64, Ordering};

/// An image of fixed-point sums shared by all threads (the module's conventions).
#[derive(Debug)]
pub struct SplatFilm {
    width: u32,
    height: u32,
    /// `round(sum * SCALE)`, three channels per pixel, row-major pixels.
    sums: Vec<AtomicI64>,
    /// The sums of the contributions' squares, in the same fixed point: the variance of the
    /// light-traced image ([`Self::sum_of_squares`]).
    squares: Vec<AtomicI64>,
    /// Contributions dropped because a channel was not finite.
    non_finite: AtomicU64,
    /// Channel additions that hit the range and saturated.
    saturated: AtomicU64,
    /// Square additions that saturated (only the variance is then too low).
    saturated_squares: AtomicU64,
}

impl SplatFilm {
    /// Fixed-point units per unit of radiance: `2^32`.
    pub const SCALE: f64 = 4_294_967_296.0;

    /// An empty film of `width x height` pixels; `None` for more than
    /// [`MAX_PIXELS`](super::MAX_PIXELS) pixels (48 bytes each: sums and sums of squares).
    pub fn new(width: u32, height: u32) -> Option<SplatFilm> {
        let pixels = u64::from(width) * u64::from(height);
        if pixels > super::MAX_PIXELS {
            return None;
        }
        Some(SplatFilm {
            width,
            height,
            sums: (0..3 * pixels).map(|_| AtomicI64::new(0)).collect(),
            squares: (0..3 * pixels).map(|_| AtomicI64::new(0)).collect(),
            non_finite: AtomicU64::new(0),
            saturated: AtomicU64::new(0),
            saturated_squares: AtomicU64::new(0),
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Adds `value` to pixel `pixel` (row-major index, below `width * height`; panics
    /// otherwise, like a slice index). A value with a non-finite channel is dropped and
    /// counted.
    #[inline]
    pub fn add(&self, pixel: u32, value: Rgb) {
        if !finite(value) {
            self.non_finite.fetch_add(1, Ordering::Relaxed);
            return;
        }
        let base = 3 * pixel as usize;
        let channels = &self.sums[base..base + 3];
        let squares = &self.squares[base..base + 3];
        for ((sum, square), v) in channels
            .iter()
            .zip(squares)
            .zip([value.r, value.g, value.b])
        {
            add_fixed(sum, v, &self.saturated);
            // f32 squares overflow only past 1.8e19 radiance: saturated as any sum that
            // passes the range, and counted apart.
            add_fixed(square, (v * v).min(f32::MAX), &self.saturated_squares);
        }
    }

    /// Adds `value` at film position `film` (pixels, (0,0) the image's top-left corner)
    /// to every pixel the filter's footprint covers, times its weight
    /// ([`splat_weights`]: `f(x - centre) / int f`). A non-finite value is dropped and
    /// counted once; a position no pixel covers adds nothing.
    pub fn add_filtered(&self, filter: &PixelFilter, film: Vec2, value: Rgb) {
        if !finite(value) {
            self.non_finite.fetch_add(1, Ordering::Relaxed);
            return;
        }
        if filter.is_pixel_box() {
            // The default filter: the one pixel whose half-open square holds the position,
            // weight 1 (what `splat_weights` gives it), without building the footprint.
            let (x, y) = (film.x.floor(), film.y.floor());
            let (w, h) = (self.width as f32, self.height as f32);
            if x >= 0.0 && y >= 0.0 && x < w && y < h {
                self.add(y as u32 * self.width + x as u32, value);
            }
            return;
        }
        self.add_weighted(filter, film, value);
    }

    /// [`Self::add_filtered`] through the general footprint of any filter.
    fn add_weighted(&self, filter: &PixelFilter, film: Vec2, value: Rgb) {
        let mut weights = SmallVec::new();
        splat_weights(filter, film, self.width, self.height, &mut weights);
        for (pixel, w) in weights {
            self.add(pixel, value * w);
        }
    }

    /// The sum of pixel `pixel` (r, g, b), to within `2^-33` per addition.
    pub fn sum(&self, pixel: u32) -> [f64; 3] {
        let base = 3 * pixel as usize;
        [0, 1, 2].map(|c| self.sums[base + c].load(Ordering::Relaxed) as f64 / Self::SCALE)
    }

    /// The sum of the squares of the contributions added to pixel `pixel` (r, g, b; a
    /// filtered splat's weighted share counts as one contribution), to within `2^-33` per
    /// addition: squares below `2^-33` are lost, which leaves out of the variance only
    /// contributions under about `1e-5`.
    pub fn sum_of_squares(&self, pixel: u32) -> [f64; 3] {
        let base = 3 * pixel as usize;
        [0, 1, 2].map(|c| self.squares[base + c].load(Ordering::Relaxed) as f64 / Self::SCALE)
    }

    /// Pixel `pixel`'s value after `light_paths` light subpaths were traced and splatted
    /// with [`crate::camera::CameraConnection::importance`]: the sum times `width * height
    /// / light_paths` (the normalisation of `camera/importance.rs`), the pixel's
    /// filter-weighted mean radiance. Black for no paths.
    pub fn pixel_value(&self, pixel: u32, light_paths: u64) -> [f64; 3] {
        if light_paths == 0 {
            return [0.0; 3];
        }
        let scale = f64::from(self.width) * f64::from(self.height) / light_paths as f64;
        self.sum(pixel).map(|s| s * scale)
    }

    /// The raw fixed-point sums of pixel `pixel` (`sum * SCALE`): what order independence
    /// is stated of.
    pub fn sum_fixed(&self, pixel: u32) -> [i64; 3] {
        let base = 3 * pixel as usize;
        [0, 1, 2].map(|c| self.sums[base + c].load(Ordering::Relaxed))
    }

    /// Contributions dropped because a channel was not finite.
    pub fn non_finite_dropped(&self) -> u64 {
        self.non_finite.load(Ordering::Relaxed)
    }

    /// Channel additions that saturated at the range.
    pub fn saturations(&self) -> u64 {
        self.saturated.load(Ordering::Relaxed)
    }

    /// Additions to the sums of squares that saturated at the range.
    pub fn square_saturations(&self) -> u64 {
        self.saturated_squares.load(Ordering::Relaxed)
    }

    /// Zeroes every sum and the counters (between iterations; not concurrently with
    /// additions).
    pub fn clear(&self) {
        for s in self.sums.iter().chain(&self.squares) {
            s.store(0, Ordering::Relaxed);
        }
        self.non_finite.store(0, Ordering::Relaxed);
        self.saturated.store(0, Ordering::Relaxed);
        self.saturated_squares.store(0, Ordering::Relaxed);
    }
}

/// Adds the finite `v` to one channel's sum, saturating, and counts a saturation in
/// `saturated`.
#[inline(always)]
fn add_fixed(sum: &AtomicI64, v: f32, saturated: &AtomicU64) {
    // `v 2^32` is exact (a power-of-two scale of an f32: 24 significant bits), so adding
    // 1/2 towards its sign is exact below 2^52 and leaves the integers above it alone,
    // and truncation then rounds half away from zero as `f64::round` does, without
    // its libm call. `as` saturates at the i64 range: a value beyond it saturates the
    // sum by itself.
    let scaled = f64::from(v) * SplatFilm::SCALE;
    let q = (scaled + 0.5f64.copysign(scaled)) as i64;
    if q == 0 {
        return;
    }
    let too_large = scaled.abs() >= I64_RANGE;
    // A compare-and-swap loop rather than `fetch_add`: a wrapped sum could not be
    // repaired afterwards without a race.
    let mut old = sum.load(Ordering::Relaxed);
    loop {
        let (new, wrapped) = match old.checked_add(q) {
            Some(new) => (new, false),
            None => (old.saturating_add(q), true),
        };
        match sum.compare_exchange_weak(old, new, Ordering::Relaxed, Ordering::Relaxed) {
            Ok(_) => {
                if too_large || wrapped {
                    saturated.fetch_add(1, Ordering::Relaxed);
                }
                return;
            }
            Err(current) => old = current,
        }
    }
}

/// `2^63`, the first f64 beyond the `i64` range.
const I64_RANGE: f64 = 9_223_372_036_854_775_808.0;

/// Whether all three channels are finite.
#[inline(always)]
fn finite(value: Rgb) -> bool {
    // x - x is 0 exactly for finite x and NaN otherwise (the test of `film::splat`).
    #[allow(clippy::eq_op, reason = "x - x is the finiteness test")]
    let zero = (value.r - value.r) + (value.g - value.g) + (value.b - value.b);
    zero == 0.0
}

#[cfg(test)]
mod tests;
