//! An RGB texture read by `(u, v)`: bilinear between texel centres (or the nearest texel),
//! repeating, mirrored or clamped outside `[0, 1]^2`, through an optional affine map of
//! `(u, v)` ([`ImageLookup`]).

use super::PatternError;
use risotto_components::Rgb;

/// A `width x height` RGB texture (linear values), row 0 at the top.
///
/// Texel `(x, y)` (x to the right, y down from the top row) is centred at
/// `u = (x + 0.5) / width`, `v = 1 - (y + 0.5) / height`: `v` grows upwards, as on a surface
/// parameterised like pbrt's image textures. Between centres the texture is bilinear; outside
/// `[0, 1]^2` it repeats (the wrap applies to the texel indices, so the seam interpolates
/// between the last and the first column).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    width: usize,
    height: usize,
    texels: Vec<Rgb>,
    min: Rgb,
    max: Rgb,
    /// Every texel has equal channels (a grey PNG, or a mask): the texture can be one
    /// number per point (a roughness).
    grey: bool,
}

impl Texture {
    /// A texture from `width * height` texels, row after row from the top; every channel
    /// finite and >= 0, both sizes >= 1.
    pub fn new(width: usize, height: usize, texels: Vec<Rgb>) -> Result<Texture, PatternError> {
        if width == 0 || height == 0 || width.checked_mul(height) != Some(texels.len()) {
            return Err(PatternError::Parameter(format!(
                "image: {width} x {height} texels do not match the {} given",
                texels.len()
            )));
        }
        if let Some(i) = texels
            .iter()
            .position(|t| !(t.is_finite() && t.min_channel() >= 0.0))
        {
            return Err(PatternError::Parameter(format!(
                "image: texel ({}, {}) is {:?}: channels must be finite and >= 0",
                i % width,
                i / width,
                texels[i]
            )));
        }
        let fold = |f: fn(f32, f32) -> f32, init: f32| {
            texels.iter().fold(Rgb::splat(init), |m, t| {
                Rgb::new(f(m.r, t.r), f(m.g, t.g), f(m.b, t.b))
            })
        };
        let (min, max) = (fold(f32::min, f32::INFINITY), fold(f32::max, 0.0));
        let grey = texels.iter().all(|t| t.r == t.g && t.g == t.b);
        Ok(Texture {
            width,
            height,
            texels,
            min,
            max,
            grey,
        })
    }

    /// True when every texel has equal channels (so does every lookup).
    pub fn is_grey(&self) -> bool {
        self.grey
    }

    /// `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// Texel `(x, y)` (y from the top).
    pub fn texel(&self, x: usize, y: usize) -> Rgb {
        self.texels[x + self.width * y]
    }

    /// Per-channel minimum and maximum texel: the range of [`Texture::lookup`] (bilinear
    /// weights are convex, and the lookup clamps rounding into it).
    pub fn range(&self) -> (Rgb, Rgb) {
        (self.min, self.max)
    }

    /// The lookup at `(u, v)` that `how` describes (non-finite coordinates read as 0): the
    /// texture coordinates mapped by `how.uv_transform`, then [`Texture::lookup`] for a
    /// bilinear, repeating lookup, or the same with the filter and wrap `how` names. The
    /// indices wrap independently, as Mitsuba 3's `bitmap` wraps them (`wrap_mode`,
    /// `filter_type`): a bilinear lookup near a clamped edge blends the edge texel with
    /// itself, near a mirrored one with its mirror image.
    #[inline]
    pub fn lookup_with(&self, u: f32, v: f32, how: &ImageLookup) -> Rgb {
        let (u, v) = match &how.uv_transform {
            None => (u, v),
            Some(m) => {
                let q = m.transform_point2(glam::Vec2::new(u, v));
                (q.x, q.y)
            }
        };
        match (how.filter, how.wrap) {
            (TextureFilter::Bilinear, Wrap::Repeat) => self.lookup(u, v),
            (TextureFilter::Bilinear, wrap) => {
                let (x0, x1, fx) = bilinear_axis(u, self.width, wrap);
                let (y0, y1, fy) = bilinear_axis(1.0 - v, self.height, wrap);
                self.blend(x0, x1, fx, y0, y1, fy)
            }
            (TextureFilter::Nearest, wrap) => {
                let x = nearest_axis(u, self.width, wrap);
                let y = nearest_axis(1.0 - v, self.height, wrap);
                self.texel(x, y)
            }
        }
    }

    /// The bilinear, repeating lookup at `(u, v)` (non-finite coordinates read as 0).
    #[inline]
    pub fn lookup(&self, u: f32, v: f32) -> Rgb {
        let (x0, x1, fx) = wrap_axis(u, self.width);
        let (y0, y1, fy) = wrap_axis(1.0 - v, self.height);
        self.blend(x0, x1, fx, y0, y1, fy)
    }

    /// The bilinear blend of texels `x0, x1` (weight `fx` on `x1`) of rows `y0, y1` (weight
    /// `fy` on `y1`).
    #[inline(always)]
    fn blend(&self, x0: usize, x1: usize, fx: f32, y0: usize, y1: usize, fy: f32) -> Rgb {
        let lerp = |a: Rgb, b: Rgb, t: f32| a + (b - a) * t;
        let top = lerp(self.texel(x0, y0), self.texel(x1, y0), fx);
        let bottom = lerp(self.texel(x0, y1), self.texel(x1, y1), fx);
        // The weights are convex, so the value lies in the texels' range; the clamp keeps
        // rounding from leaving it (the pattern bounds rely on it).
        let (lo, hi) = (self.min, self.max);
        let c = lerp(top, bottom, fy);
        Rgb::new(
            c.r.max(lo.r).min(hi.r),
            c.g.max(lo.g).min(hi.g),
            c.b.max(lo.b).min(hi.b),
        )
    }
}

/// `(index, next index, fraction)` of coordinate `t` on an axis of `n` texels with centres at
/// `(i + 0.5) / n`, wrapping.
#[inline]
fn wrap_axis(t: f32, n: usize) -> (usize, usize, f32) {
    let t = if t.is_finite() { t } else { 0.0 };
    let g = t * n as f32 - 0.5;
    let g0 = g.floor();
    let f = (g - g0).clamp(0.0, 1.0);
    let n = n as i64;
    // Saturating cast for huge coordinates, then wrap.
    let i = (g0 as i64).rem_euclid(n);
    (i as usize, ((i + 1) % n) as usize, f)
}

/// What lies outside `[0, 1]` on each texture axis (Mitsuba 3's `wrap_mode`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    /// The texture tiles the plane.
    #[default]
    Repeat,
    /// The texture tiles the plane mirrored every other tile (period 2).
    Mirror,
    /// The edge texels extend outwards.
    Clamp,
}

/// How a lookup between texel centres is made (Mitsuba 3's `filter_type`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TextureFilter {
    /// Bilinear between the four nearest texel centres.
    #[default]
    Bilinear,
    /// The texel the point lies in.
    Nearest,
}

/// How an `image` pattern reads its texture: an affine map of `(u, v)` first (Mitsuba's
/// `to_uv`: `(u, v) -> M (u, v) + t`), then the filter and wrap. The default is the plain
/// [`Texture::lookup`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImageLookup {
    /// Maps the surface's `(u, v)` to the texture's; `None` = identity.
    pub uv_transform: Option<glam::Affine2>,
    /// What lies outside `[0, 1]`.
    pub wrap: Wrap,
    /// Bilinear or nearest.
    pub filter: TextureFilter,
}

/// The texel index `i` of an axis of `n` texels under `wrap` (`i` any integer; `n >= 1`).
#[inline]
fn wrap_index(i: i64, n: i64, wrap: Wrap) -> usize {
    (match wrap {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::Clamp => i.clamp(0, n - 1),
        Wrap::Mirror => {
            let j = i.rem_euclid(2 * n);
            if j >= n {
                2 * n - 1 - j
            } else {
                j
            }
        }
    }) as usize
}

/// `(index, next index, fraction)` of coordinate `t` on an axis of `n` texels with centres at
/// `(i + 0.5) / n`, each index wrapped by `wrap`.
#[inline]
fn bilinear_axis(t: f32, n: usize, wrap: Wrap) -> (usize, usize, f32) {
    let t = if t.is_finite() { t } else { 0.0 };
    let g = t * n as f32 - 0.5;
    let g0 = g.floor();
    let f = (g - g0).clamp(0.0, 1.0);
    // Saturating cast for huge coordinates; the sum cannot overflow after the clamp to a
    // range far inside i64.
    let i = (g0 as i64).clamp(-(1 << 40), 1 << 40);
    let n = n as i64;
    (wrap_index(i, n, wrap), wrap_index(i + 1, n, wrap), f)
}

/// The index of the texel coordinate `t` lies in, on an axis of `n` texels, wrapped by
/// `wrap`.
#[inline]
fn nearest_axis(t: f32, n: usize, wrap: Wrap) -> usize {
    let t = if t.is_finite() { t } else { 0.0 };
    let i = ((t * n as f32).floor() as i64).clamp(-(1 << 40), 1 << 40);
    wrap_index(i, n as i64, wrap)
}
