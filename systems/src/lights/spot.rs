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
