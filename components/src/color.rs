//! Linear RGB colour.

use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Sub};

/// A linear Rec.709 RGB triple (radiance, reflectance, throughput or transmittance,
/// depending on the column it lives in).
///
/// `repr(C)`: three f32 in the order r, g, b, so that SIMD kernels can store columns of it
/// as flat floats (as glam's `Vec3`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct Rgb {
    /// Red channel.
    pub r: f32,
    /// Green channel.
    pub g: f32,
    /// Blue channel.
    pub b: f32,
}

impl Rgb {
    /// Black (all channels 0).
    pub const BLACK: Rgb = Rgb::splat(0.0);
    /// White (all channels 1).
    pub const WHITE: Rgb = Rgb::splat(1.0);

    /// A colour from its three channels.
    pub const fn new(r: f32, g: f32, b: f32) -> Self {
        Rgb { r, g, b }
    }
    /// The same value in every channel.
    pub const fn splat(v: f32) -> Self {
        Rgb { r: v, g: v, b: v }
    }
    /// A colour from an array `[r, g, b]`.
    pub const fn from_array(a: [f32; 3]) -> Self {
        Rgb {
            r: a[0],
            g: a[1],
            b: a[2],
        }
    }
    /// The channels as an array `[r, g, b]`.
    pub const fn to_array(self) -> [f32; 3] {
        [self.r, self.g, self.b]
    }
    /// Largest channel.
    pub fn max_channel(self) -> f32 {
        self.r.max(self.g).max(self.b)
    }
    /// Mean of the channels.
    pub fn average(self) -> f32 {
        (self.r + self.g + self.b) * (1.0 / 3.0)
    }
    /// Rec.709 luminance.
    pub fn luminance(self) -> f32 {
        0.2126 * self.r + 0.7152 * self.g + 0.0722 * self.b
    }
    /// True when every channel is exactly zero.
    pub fn is_black(self) -> bool {
        self.r == 0.0 && self.g == 0.0 && self.b == 0.0
    }
    /// True when every channel is finite (no NaN, no infinity).
    pub fn is_finite(self) -> bool {
        self.r.is_finite() && self.g.is_finite() && self.b.is_finite()
    }
    /// Per-channel `exp`.
    pub fn exp(self) -> Self {
        Rgb::new(self.r.exp(), self.g.exp(), self.b.exp())
    }
    /// Per-channel map.
    pub fn map(self, f: impl Fn(f32) -> f32) -> Self {
        Rgb::new(f(self.r), f(self.g), f(self.b))
    }
    /// Per-channel minimum of two colours.
    pub fn min(self, o: Rgb) -> Self {
        Rgb::new(self.r.min(o.r), self.g.min(o.g), self.b.min(o.b))
    }
    /// Smallest channel.
    pub fn min_channel(self) -> f32 {
        self.r.min(self.g).min(self.b)
    }
}

impl Add for Rgb {
    type Output = Rgb;
    fn add(self, o: Rgb) -> Rgb {
        Rgb::new(self.r + o.r, self.g + o.g, self.b + o.b)
    }
}
impl AddAssign for Rgb {
    fn add_assign(&mut self, o: Rgb) {
        *self = *self + o;
    }
}
impl Sub for Rgb {
    type Output = Rgb;
    fn sub(self, o: Rgb) -> Rgb {
        Rgb::new(self.r - o.r, self.g - o.g, self.b - o.b)
    }
}
impl Mul for Rgb {
    type Output = Rgb;
    fn mul(self, o: Rgb) -> Rgb {
        Rgb::new(self.r * o.r, self.g * o.g, self.b * o.b)
    }
}
impl MulAssign for Rgb {
    fn mul_assign(&mut self, o: Rgb) {
        *self = *self * o;
    }
}
impl Mul<f32> for Rgb {
    type Output = Rgb;
    fn mul(self, s: f32) -> Rgb {
        Rgb::new(self.r * s, self.g * s, self.b * s)
    }
}
impl MulAssign<f32> for Rgb {
    fn mul_assign(&mut self, s: f32) {
        *self = *self * s;
    }
}
impl Div<f32> for Rgb {
    type Output = Rgb;
    fn div(self, s: f32) -> Rgb {
        let inv = 1.0 / s;
        self * inv
    }
}
