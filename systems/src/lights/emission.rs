//! Emission sampling: the first segment of a light subpath, for light tracing, BDPT and
//! vertex connection and merging (Georgiev et al. 2012, "Light Transport Simulation with
//! Vertex Connection and Merging"; the quantities are SmallVCM's `emissionPdfW`,
//! `directPdfA`, `cosAtLight`, `isDelta` and `isFinite`, `light.hxx`).
//!
//! A light is chosen with the same selection distribution and the same `u_select` as
//! next-event estimation ([`LightSet::sample`]), then a ray leaving it: a position `p` with
//! density `pdf_position` (area measure on surfaces and on the disk of lights at infinity,
//! volume measure in emissive media, the selection probability alone for point and spot
//! lights) and a direction with solid-angle density `pdf_direction` given `p` (pbrt-v4
//! `Light::SampleLe` / `PDF_Le`, `lights.cpp`; PBR 3rd ed. sec. 16.1.5). The emitted power
//! is then estimated without bias by `radiance * cos_at_light / (pdf_position *
//! pdf_direction)`, the starting throughput of the light subpath.
//!
//! Lights at infinity (distant, environment) start their rays on a disk of the scene's
//! bounding-sphere radius `R` perpendicular to the direction, centred `R` behind the
//! sphere's centre, so every ray crosses the whole scene (PBR 3rd ed. sec. 16.1.5,
//! "Infinite area lights"); the disk's area density is `1 / (pi R^2)`.

use super::*;
use crate::warp::{
    sample_concentric_disk, sample_cosine_hemisphere, sample_uniform_cone, sample_uniform_sphere,
    uniform_cone_pdf, Frame, INV_4PI,
};
use std::f32::consts::FRAC_1_PI;

/// A ray leaving a light (the first segment of a light subpath).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissionSample {
    /// Index into [`LightSet::lights`].
    pub light: u32,
    /// Ray origin: on the light; for lights at infinity a point on a disk of the scene's
    /// bounding-sphere radius, outside the scene, facing `direction`.
    pub p: Vec3,
    /// Error bound of `p` (area lights: the surface sample's; else 0).
    pub p_error: Vec3,
    /// Unit surface normal at `p` for area lights; `direction` for lights at infinity;
    /// `Vec3::ZERO` for point, spot and volume lights (no surface).
    pub n: Vec3,
    /// Unit direction the light travels.
    pub direction: Vec3,
    /// `Le`: area and environment lights their radiance, point and spot lights their
    /// intensity (falloff and texture included), distant lights their irradiance, volume
    /// lights the emission coefficient `j(p)`.
    pub radiance: Rgb,
    /// Density of `p` including the light selection probability: area measure (area
    /// lights, the disk of lights at infinity), volume measure (volume lights); the
    /// selection probability alone for point and spot lights (a Dirac position).
    pub pdf_position: f32,
    /// Solid-angle density of `direction` given `p` (distant lights: 1, a Dirac direction).
    pub pdf_direction: f32,
    /// `|n . direction|` for area lights, 1 elsewhere.
    pub cos_at_light: f32,
    /// Point and spot lights (the position is a Dirac delta).
    pub delta_position: bool,
    /// Distant lights (the direction is a Dirac delta).
    pub delta_direction: bool,
    /// Distant and environment lights.
    pub at_infinity: bool,
}

/// The bounding sphere `(centre, radius)` of the box `scene_bounds`, as the scene compiler
/// computes the radius it prices lights at infinity with (an empty box, `lo > hi`, is the
/// unit sphere at the origin; the radius is kept positive so that `1 / (pi R^2)` stays
/// finite).
#[inline]
fn bounding_sphere((lo, hi): (Vec3, Vec3)) -> (Vec3, f32) {
    if lo.cmple(hi).all() {
        ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-18))
    } else {
        (Vec3::ZERO, 1.0)
    }
}

/// The origin of a ray of a light at infinity travelling `direction`: the concentric-disk
/// point of `u` on the disk of radius `radius` perpendicular to `direction`, centred
/// `radius` behind `center` (PBR 3rd ed. sec. 16.1.5).
#[inline]
fn disk_origin(center: Vec3, radius: f32, direction: Vec3, u: Vec2) -> Vec3 {
    let frame = Frame::from_normal(direction);
    let d = sample_concentric_disk(u);
    center + radius * (frame.s * d.x + frame.t * d.y - direction)
}

impl LightSet {
    /// The light [`sample`](Self::sample)`(.., u_select, ..)` selects (`None` when nothing
    /// can be sampled or the selected light has probability 0).
    pub fn selected_light(&self, u_select: f32) -> Option<u32> {
        let (index, _) = self.selection.as_ref()?.sample_discrete(u_select);
        (self.pmf[index] > 0.0).then_some(index as u32)
    }

    /// The index of the environment light, if any (also when it is left out of selection,
    /// [`LightSet::with_environment_sampling`]).
    pub fn environment_light(&self) -> Option<u32> {
        self.environment
    }

    /// Samples a light in proportion to the selection distribution [`sample`](Self::sample)
    /// uses (the same light for the same `u_select`) and a ray leaving it: `u_position`
    /// places the origin (on the surface, the disk of lights at infinity, or in the
    /// medium's cell), `u_direction` the direction. A volume light's cell comes from
    /// `u_select` rescaled within the light's selection interval, as in `sample`.
    /// `scene_bounds` gives the bounding sphere of lights at infinity. `None` when no ray
    /// can leave (nothing selectable, a zero density, or no emission along the sample).
    pub fn sample_emission(
        &self,
        geometry: &SceneGeometry,
        scene_bounds: (Vec3, Vec3),
        u_select: f32,
        u_position: Vec2,
        u_direction: Vec2,
    ) -> Option<EmissionSample> {
        let index = self.selected_light(u_select)?;
        let pmf = self.pmf[index as usize];
        // The fields every kind sets; the rest are overridden per kind below.
        let ray = |p: Vec3, p_error: Vec3, n: Vec3, direction: Vec3, cos: f32| EmissionSample {
            light: index,
            p,
            p_error,
            n,
            direction,
            radiance: Rgb::BLACK,
            pdf_position: pmf,
            pdf_direction: 0.0,
            cos_at_light: cos,
            delta_position: false,
            delta_direction: false,
            at_infinity: false,
        };
        let sample = match &self.lights[index as usize] {
            Light::Area { prim, radiance } => {
                let surf = geometry.sample_surface(*prim, u_position);
                let n = surf.ng;
                // A degenerate triangle has a zero normal: no direction to emit in.
                if n == Vec3::ZERO {
                    return None;
                }
                // One-sided: cosine-weighted about the normal, density cos / pi (Malley).
                let local = sample_cosine_hemisphere(u_direction);
                let direction = Frame::from_normal(n).to_world(local).normalize();
                let cos = n.dot(direction);
                EmissionSample {
                    radiance: *radiance,
                    pdf_position: self.pmf_over_area[index as usize],
                    pdf_direction: cos.max(0.0) * FRAC_1_PI,
                    ..ray(surf.p, surf.p_error, n, direction, cos.abs())
                }
            }
            Light::Point {
                position,
                intensity,
            } => EmissionSample {
                radiance: *intensity,
                pdf_direction: INV_4PI,
                delta_position: true,
                ..ray(
                    *position,
                    Vec3::ZERO,
                    Vec3::ZERO,
                    sample_uniform_sphere(u_direction),
                    1.0,
                )
            },
            Light::Spot {
                position,
                direction: axis,
                intensity,
                falloff,
                texture,
            } => {
                // Uniform in the cone the falloff is non-zero in (pbrt-v4 `SpotLight::SampleLe`
                // samples the same cone, `cosFalloffEnd`).
                let cos_max = falloff.cos_cutoff();
                let local = sample_uniform_cone(u_direction, cos_max);
                let direction = Frame::from_normal(*axis).to_world(local).normalize();
                let f = falloff.eval(direction.dot(*axis));
                let radiance = match texture {
                    None => *intensity * f,
                    Some(t) => *intensity * t.eval(direction, *axis) * f,
                };
                EmissionSample {
                    radiance,
                    pdf_direction: uniform_cone_pdf(cos_max),
                    delta_position: true,
                    ..ray(*position, Vec3::ZERO, Vec3::ZERO, direction, 1.0)
                }
            }
            Light::Distant {
                direction,
                irradiance,
            } => {
                let (center, radius) = bounding_sphere(scene_bounds);
                let p = disk_origin(center, radius, *direction, u_position);
                EmissionSample {
                    radiance: *irradiance,
                    pdf_position: pmf / (PI * radius * radius),
                    pdf_direction: 1.0,
                    delta_direction: true,
                    at_infinity: true,
                    ..ray(p, Vec3::ZERO, *direction, *direction, 1.0)
                }
            }
            Light::Environment { radiance, map } => {
                // The map samples the direction towards the environment; light travels
                // the opposite way.
                let (towards, le, pdf_direction) = match map {
                    Some(m) => {
                        let (dir, value, pdf) = m.sample(u_direction);
                        (dir, *radiance * value, pdf)
                    }
                    None => (sample_uniform_sphere(u_direction), *radiance, INV_4PI),
                };
                let direction = -towards;
                let (center, radius) = bounding_sphere(scene_bounds);
                let p = disk_origin(center, radius, direction, u_position);
                EmissionSample {
                    radiance: le,
                    pdf_position: pmf / (PI * radius * radius),
                    pdf_direction,
                    at_infinity: true,
                    ..ray(p, Vec3::ZERO, direction, direction, 1.0)
                }
            }
            Light::Volume { emitter } => {
                let u_cell = self.volume_cell_sample(index as usize, u_select)?;
                let (x, pdf_v) = emitter.sample([u_position.x, u_position.y], u_cell)?;
                EmissionSample {
                    radiance: emitter.emission(x),
                    pdf_position: pmf * pdf_v,
                    pdf_direction: INV_4PI,
                    ..ray(
                        x,
                        Vec3::ZERO,
                        Vec3::ZERO,
                        sample_uniform_sphere(u_direction),
                        1.0,
                    )
                }
            }
        };
        let valid = sample.pdf_position > 0.0
            && sample.pdf_position.is_finite()
            && sample.pdf_direction > 0.0
            && sample.pdf_direction.is_finite()
            && !sample.radiance.is_black();
        valid.then_some(sample)
    }

    /// The densities [`sample_emission`](Self::sample_emission) would have had for a ray
    /// leaving light `light` at `p` (normal `n` for area lights) in `direction`:
    /// `(pdf_position, pdf_direction)` with the conventions of [`EmissionSample`]'s fields
    /// (selection included). For lights at infinity `p` is ignored and `direction` is the
    /// direction light travels (`pdf_position` is the disk's `1 / (pi R^2)` times the
    /// selection probability); a distant light's `pdf_direction` is 1 whatever `direction`
    /// (its Dirac delta, as SmallVCM's `DirectionalLight`). `(0, 0)` for an unknown light.
    pub fn emission_pdf(
        &self,
        light: u32,
        p: Vec3,
        n: Vec3,
        direction: Vec3,
        scene_bounds: (Vec3, Vec3),
    ) -> (f32, f32) {
        let Some(kind) = self.lights.get(light as usize) else {
            return (0.0, 0.0);
        };
        let pmf = self.pmf[light as usize];
        let disk = || {
            let (_, radius) = bounding_sphere(scene_bounds);
            pmf / (PI * radius * radius)
        };
        match kind {
            Light::Area { .. } => (
                self.pmf_over_area[light as usize],
                n.dot(direction).max(0.0) * FRAC_1_PI,
            ),
            Light::Point { .. } => (pmf, INV_4PI),
            Light::Spot {
                direction: axis,
                falloff,
                ..
            } => {
                let cos_max = falloff.cos_cutoff();
                let inside = direction.dot(*axis) >= cos_max;
                (
                    pmf,
                    if inside {
                        uniform_cone_pdf(cos_max)
                    } else {
                        0.0
                    },
                )
            }
            Light::Distant { .. } => (disk(), 1.0),
            Light::Environment { map, .. } => {
                let pdf = map.as_ref().map_or(INV_4PI, |m| m.pdf(-direction));
                (disk(), pdf)
            }
            Light::Volume { emitter } => (pmf * emitter.pdf(p), INV_4PI),
        }
    }

    /// For the volume light `index` selected by `u_select`, `u_select` rescaled to `[0, 1)`
    /// within the light's selection interval (a uniform variable independent of the choice
    /// of light), as [`sample`](Self::sample) computes it to pick the cell.
    fn volume_cell_sample(&self, index: usize, u_select: f32) -> Option<f32> {
        let cdf = self.selection.as_ref()?.cdf();
        let (a, b) = (cdf[index], cdf[index + 1]);
        Some(if b > a {
            ((u_select - a) / (b - a)).clamp(0.0, ONE_MINUS_EPSILON)
        } else {
            0.0
        })
    }
}

#[cfg(test)]
#[path = "emission_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "emission_direction_tests.rs"]
mod direction_tests;
