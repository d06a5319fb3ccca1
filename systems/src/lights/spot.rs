//! The spot light's angular falloff, as Mitsuba 3's `spot` emitter defines it
//! (`src/emitters/spot.cpp`, `SpotLight::falloff_curve`): full intensity within
//! `beam_width` of the axis, a ramp *linear in the angle* from 1 at `beam_width` to 0 at
//! `cutoff_angle`, and nothing beyond:
//!
//! ```text
//! f(theta) = 1                                              cos theta >= cos beam_width
//!          = (cutoff_angle - theta) / (cutoff_angle - beam_width)   in between
//!          = 0                                              cos theta <= cos cutoff_angle
//! ```

/// A spot light's falloff profile (angles in radians, precomputed as Mitsuba does).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotFalloff {
    /// Half-angle of the cone beyond which nothing is emitted (radians).
    pub cutoff: f32,
    /// Half-angle of the fully lit central beam (radians, `<= cutoff`).
    pub beam: f32,
    cos_cutoff: f32,
    cos_beam: f32,
    /// `1 / (cutoff - beam)` (infinite when they are equal: the ramp is then empty).
    inv_transition: f32,
}

impl SpotFalloff {
    /// The falloff of a spot with `cutoff_angle` and `beam_width` in degrees (Mitsuba's
    /// parameters). Callers check `0 < beam_width <= cutoff_angle <= 90`.
    pub fn from_degrees(cutoff_angle: f32, beam_width: f32) -> Self {
        let cutoff = cutoff_angle.to_radians();
        let beam = beam_width.to_radians();
        SpotFalloff {
            cutoff,
            beam,
            cos_cutoff: cutoff.cos(),
            cos_beam: beam.cos(),
            inv_transition: 1.0 / (cutoff - beam),
        }
    }

    /// `cos(cutoff)`: directions with a larger cosine to the axis are inside the cone the
    /// falloff is non-zero in.
    #[inline]
    pub fn cos_cutoff(&self) -> f32 {
        self.cos_cutoff
    }

    /// The falloff factor in `[0, 1]` for a direction at `cos_theta` from the axis.
    #[inline]
    pub fn eval(&self, cos_theta: f32) -> f32 {
        if cos_theta <= self.cos_cutoff {
            0.0
        } else if cos_theta >= self.cos_beam {
            1.0
        } else {
            ((self.cutoff - cos_theta.clamp(-1.0, 1.0).acos()) * self.inv_transition)
                .clamp(0.0, 1.0)
        }
    }

    /// The falloff integrated over the sphere, `2 pi int_0^cutoff f(theta) sin theta
    /// dtheta` (steradians): the spot's power is this times its intensity. In closed
    /// form (integrating the ramp by parts) `2 pi (1 - (sin c - sin b) / (c - b))` for
    /// cutoff `c` and beam `b`, `2 pi (1 - cos c)` when `b = c` (the limit).
    pub fn solid_angle(&self) -> f32 {
        let (c, b) = (self.cutoff as f64, self.beam as f64);
        let w = c - b;
        let ramp = if w > 1e-4 {
            (c.sin() - b.sin()) / w
        } else {
            // (sin c - sin b) / (c - b) = cos(m) sinc(w / 2) for the midpoint m, series
            // in w (the division above loses precision as w -> 0).
            let m = 0.5 * (c + b);
            m.cos() * (1.0 - w * w / 24.0)
        };
        (2.0 * std::f64::consts::PI * (1.0 - ramp)) as f32
    }
}

/// A spot light's projection texture (Mitsuba 3's `spot` `texture`): the intensity is
/// multiplied by the texture, projected through the spot's frame with the cutoff cone as the
/// field of view. For a direction `d` leaving the light with local coordinates
/// `(x, y, z) = (d . s, d . t, d . axis)`, the texture is read at Mitsuba's
/// `(0.5 + 0.5 x / (z tan cutoff), 0.5 + 0.5 y / (z tan cutoff))`, `s` and `t` being the
/// frame of Mitsuba's `lookat` (`s = normalize(up x axis)`, `t = axis x s`), and the image's
/// top row at Mitsuba's `v = 0` (our [`Texture`](crate::pattern::Texture) has `v` growing upwards, so `1 - v`).
#[derive(Clone, Debug, PartialEq)]
pub struct SpotTexture {
    /// The image (linear RGB).
    pub texture: crate::pattern::Texture,
    /// The frame's first axis (the texture's `u` direction).
    pub s: glam::Vec3,
    /// The frame's second axis (the texture's `v` direction).
    pub t: glam::Vec3,
    /// `tan(cutoff)`: the cone's half-width at unit distance along the axis.
    pub tan_cutoff: f32,
    /// The mean texel, per channel: the texture's share of the light's power (for light
    /// selection only, which needs no more than a positive estimate).
    pub mean: risotto_components::Rgb,
}

impl SpotTexture {
    /// The projection of `texture` by a spot at `axis` (unit) with `up` (not parallel to it)
    /// and `cutoff` (radians). `None` when `up` is parallel to the axis.
    pub fn new(
        texture: crate::pattern::Texture,
        axis: glam::Vec3,
        up: glam::Vec3,
        cutoff: f32,
    ) -> Option<SpotTexture> {
        let s = up.cross(axis).try_normalize()?;
        let t = axis.cross(s);
        let (w, h) = texture.size();
        let mut sum = risotto_components::Rgb::BLACK;
        for y in 0..h {
            for x in 0..w {
                sum += texture.texel(x, y);
            }
        }
        let mean = sum * (1.0 / (w * h) as f32);
        Some(SpotTexture {
            texture,
            s,
            t,
            tan_cutoff: cutoff.tan(),
            mean,
        })
    }

    /// The texture's factor for the unit direction `d` leaving the light (`axis` its axis);
    /// black behind the light.
    #[inline]
    pub fn eval(&self, d: glam::Vec3, axis: glam::Vec3) -> risotto_components::Rgb {
        let z = d.dot(axis);
        // Behind the light (or NaN): nothing.
        if z.is_nan() || z <= 0.0 {
            return risotto_components::Rgb::BLACK;
        }
        let scale = 0.5 / (z * self.tan_cutoff);
        let u = 0.5 + d.dot(self.s) * scale;
        let v = 0.5 + d.dot(self.t) * scale;
        self.texture.lookup(u, 1.0 - v)
    }
}
