//! Light sampling (next-event estimation) and the light pdfs MIS needs.
//!
//! Lights: area lights (emissive primitives, one-sided: they emit on the side their geometric
//! normal points to), distant lights (irradiance `E` on a surface facing them), point lights
//! (intensity `I`, W/sr) and an environment (constant radiance, optionally an equirectangular
//! map, importance sampled). One light is chosen per sample in proportion to an estimate of
//! its power; the returned pdf includes that choice. Pdfs are per unit solid angle at the
//! shading point, Dirac lights (distant, point) report `delta = true` and pdf 1 x selection.

use crate::distribution::{Distribution1D, EnvironmentMap};
use crate::geometry::SceneGeometry;
use glam::{Vec2, Vec3};
use risotto_components::Rgb;
use std::f32::consts::PI;

/// One light.
#[derive(Clone, Debug)]
pub enum Light {
    /// An emissive primitive with constant radiance on its front side.
    Area {
        /// Primitive index in the scene geometry.
        prim: u32,
        /// Emitted radiance.
        radiance: Rgb,
    },
    /// A light at infinity in one direction.
    Distant {
        /// Direction the light travels (unit).
        direction: Vec3,
        /// Irradiance on a surface perpendicular to `direction`.
        irradiance: Rgb,
    },
    /// An isotropic point light.
    Point {
        /// Position.
        position: Vec3,
        /// Radiant intensity (W/sr per channel).
        intensity: Rgb,
    },
    /// Radiance arriving from every direction at infinity.
    Environment {
        /// Constant radiance (multiplies the map when there is one).
        radiance: Rgb,
        /// Optional equirectangular map.
        map: Option<Box<EnvironmentMap>>,
    },
}

/// All lights of a scene, with the selection distribution and a per-primitive lookup.
#[derive(Clone, Debug)]
pub struct LightSet {
    lights: Vec<Light>,
    selection: Option<Distribution1D>,
    /// For every primitive, the index of its area light or `u32::MAX`.
    light_of_prim: Vec<u32>,
    environment: Option<u32>,
    /// Per light: selection probability, and for area lights selection probability / area
    /// (the area-measure pdf of a sample), precomputed so sampling does not divide by them.
    pmf: Vec<f32>,
    pmf_over_area: Vec<f32>,
}

/// One light sample, as seen from a shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit direction from the shading point towards the light.
    pub wi: Vec3,
    /// Distance to the sampled point (infinity for lights at infinity).
    pub distance: f32,
    /// Radiance (or for Dirac lights, the irradiance-equivalent `Li`) arriving along `-wi`.
    pub radiance: Rgb,
    /// Solid-angle pdf including the light selection probability (Dirac lights: selection
    /// probability only).
    pub pdf: f32,
    /// True for Dirac lights (no MIS).
    pub delta: bool,
}

impl LightSet {
    /// Builds the set. `scene_radius` bounds the scene (for the power of lights at infinity).
    pub fn new(lights: Vec<Light>, geometry: &SceneGeometry, scene_radius: f32) -> Self {
        let mut light_of_prim = vec![u32::MAX; geometry.num_prims()];
        let mut environment = None;
        let r2 = scene_radius * scene_radius;
        let power: Vec<f32> = lights
            .iter()
            .enumerate()
            .map(|(i, l)| match l {
                Light::Area { prim, radiance } => {
                    light_of_prim[*prim as usize] = i as u32;
                    radiance.average() * PI * geometry.prim_area(*prim)
                }
                Light::Distant { irradiance, .. } => irradiance.average() * PI * r2,
                Light::Point { intensity, .. } => 4.0 * PI * intensity.average(),
                Light::Environment { radiance, map } => {
                    environment = Some(i as u32);
                    // Integral of the map's radiance over the sphere (4 pi for a constant 1).
                    let sphere = map.as_ref().map_or(4.0 * PI, |m| m.integral().average());
                    radiance.average() * sphere * PI * r2
                }
            })
            .map(|p| if p.is_finite() { p.max(0.0) } else { 0.0 })
            .collect();
        let selection = (!lights.is_empty()).then(|| Distribution1D::new(&power));
        let pmf: Vec<f32> = (0..lights.len())
            .map(|i| selection.as_ref().map_or(0.0, |d| d.pmf(i)))
            .collect();
        let pmf_over_area = lights
            .iter()
            .zip(&pmf)
            .map(|(l, &pmf)| match l {
                Light::Area { prim, .. } => pmf / geometry.prim_area(*prim),
                _ => 0.0,
            })
            .collect();
        LightSet {
            lights,
            selection,
            light_of_prim,
            environment,
            pmf,
            pmf_over_area,
        }
    }

    /// The lights.
    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// True when there is no light at all.
    pub fn is_empty(&self) -> bool {
        self.lights.is_empty()
    }

    /// Index of the area light on `prim`, if any.
    pub fn area_light(&self, prim: u32) -> Option<u32> {
        self.light_of_prim
            .get(prim as usize)
            .copied()
            .filter(|&l| l != u32::MAX)
    }

    /// Probability of selecting light `index`.
    pub fn selection_pmf(&self, index: u32) -> f32 {
        self.pmf.get(index as usize).copied().unwrap_or(0.0)
    }

    /// Radiance of the environment towards direction `dir` (seen along a ray going `dir`).
    pub fn environment_radiance(&self, dir: Vec3) -> Rgb {
        match self.environment.map(|i| &self.lights[i as usize]) {
            Some(Light::Environment { radiance, map }) => match map {
                Some(m) => *radiance * m.eval(dir),
                None => *radiance,
            },
            _ => Rgb::BLACK,
        }
    }

    /// Solid-angle pdf (including selection) that light sampling picks direction `dir` on the
    /// environment.
    pub fn environment_pdf(&self, dir: Vec3) -> f32 {
        match self.environment {
            Some(i) => {
                let sel = self.selection_pmf(i);
                match &self.lights[i as usize] {
                    Light::Environment { map: Some(m), .. } => sel * m.pdf(dir),
                    _ => sel / (4.0 * PI),
                }
            }
            None => 0.0,
        }
    }

    /// Solid-angle pdf (including selection) that light sampling from `from` picks the point
    /// `p` (normal `n`) on the area light of `prim`.
    pub fn area_pdf(&self, prim: u32, from: Vec3, p: Vec3, n: Vec3) -> f32 {
        let Some(l) = self.area_light(prim) else {
            return 0.0;
        };
        let d = p - from;
        let dist2 = d.length_squared();
        let cos = (n.dot(d) / dist2.sqrt()).abs();
        if cos <= 0.0 || dist2 <= 0.0 {
            return 0.0;
        }
        self.pmf_over_area[l as usize] * dist2 / cos
    }

    /// Samples a light from `p`. `u_select` chooses the light, `u` the point on it.
    pub fn sample(
        &self,
        geometry: &SceneGeometry,
        p: Vec3,
        u_select: f32,
        u: Vec2,
    ) -> Option<LightSample> {
        let (index, _) = self.selection.as_ref()?.sample_discrete(u_select);
        let pmf = self.pmf[index];
        if pmf <= 0.0 {
            return None;
        }
        match &self.lights[index] {
            Light::Area { prim, radiance } => {
                let (q, n) = geometry.sample_prim(*prim, u);
                let d = q - p;
                let dist2 = d.length_squared();
                if dist2 <= 0.0 || !dist2.is_finite() {
                    return None;
                }
                let dist = dist2.sqrt();
                // One division for the direction (glam's Vec3 / f32 divides per component).
                let wi = d * (1.0 / dist);
                // One-sided emitter: it shines towards where its normal points.
                let cos_light = -n.dot(wi);
                if cos_light <= 0.0 {
                    return None;
                }
                // Area pdf (pmf / area) to solid angle: * dist^2 / cos (PBR 4th ed. eq. 4.9).
                let pdf = self.pmf_over_area[index] * dist2 / cos_light;
                (pdf.is_finite() && pdf > 0.0).then_some(LightSample {
                    wi,
                    distance: dist,
                    radiance: *radiance,
                    pdf,
                    delta: false,
                })
            }
            Light::Distant {
                direction,
                irradiance,
            } => Some(LightSample {
                wi: -*direction,
                distance: f32::INFINITY,
                radiance: *irradiance,
                pdf: pmf,
                delta: true,
            }),
            Light::Point {
                position,
                intensity,
            } => {
                let d = *position - p;
                let dist2 = d.length_squared();
                if dist2 <= 0.0 {
                    return None;
                }
                let dist = dist2.sqrt();
                Some(LightSample {
                    wi: d / dist,
                    distance: dist,
                    radiance: *intensity / dist2,
                    pdf: pmf,
                    delta: true,
                })
            }
            Light::Environment { radiance, map } => {
                let (wi, le, pdf) = match map {
                    Some(m) => {
                        let (dir, value, pdf) = m.sample(u);
                        (dir, *radiance * value, pdf)
                    }
                    None => (
                        crate::bxdf::sample_uniform_sphere(u),
                        *radiance,
                        1.0 / (4.0 * PI),
                    ),
                };
                let pdf = pdf * pmf;
                (pdf > 0.0 && pdf.is_finite()).then_some(LightSample {
                    wi,
                    distance: f32::INFINITY,
                    radiance: le,
                    pdf,
                    delta: false,
                })
            }
        }
    }
}

/// The light-sampling system: one light sample per point.
///
/// Inputs: `p` (shading positions), `u_select`, `u` (sample columns). Outputs: `out[i]`, `None`
/// where no light could be sampled.
pub fn sample_lights(
    lights: &LightSet,
    geometry: &SceneGeometry,
    p: &[Vec3],
    u_select: &[f32],
    u: &[Vec2],
    out: &mut [Option<LightSample>],
) {
    for i in 0..p.len() {
        out[i] = lights.sample(geometry, p[i], u_select[i], u[i]);
    }
}

/// Power heuristic with exponent 2 (Veach 1997, eq. 9.13) for one sample of each strategy.
#[inline]
pub fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let a = pdf_a * pdf_a;
    let b = pdf_b * pdf_b;
    if a == 0.0 {
        return 0.0;
    }
    if !a.is_finite() {
        return 1.0;
    }
    let w = a / (a + b);
    if w.is_finite() {
        w
    } else {
        1.0
    }
}
