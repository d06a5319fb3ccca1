//! Light sampling (next-event estimation) and the light pdfs MIS needs.
//!
//! Lights: area lights (emissive primitives, one-sided: they emit on the side their geometric
//! normal points to), distant lights (irradiance `E` on a surface facing them), point lights
//! (intensity `I`, W/sr), spot lights (a point light whose intensity falls off away from an
//! axis, [`SpotFalloff`]) and an environment (constant radiance, optionally an equirectangular
//! map, importance sampled). One light is chosen per sample in proportion to an estimate of
//! its power; the returned pdf includes that choice. Pdfs are per unit solid angle at the
//! shading point, Dirac lights (distant, point, spot) report `delta = true` and pdf 1 x selection.
//!
//! The lights also emit: [`LightSet::sample_emission`] samples a ray leaving a light (the
//! start of a light subpath for light tracing, BDPT and VCM) with the same selection, and
//! [`LightSet::emission_pdf`] gives its densities (`lights/emission.rs`).

use crate::distribution::{Distribution1D, ONE_MINUS_EPSILON};
use crate::environment_map::EnvironmentMap;
use crate::geometry::{gamma, SceneGeometry, UNDERFLOW};
use crate::simd8::{Backend, Kernel8, Lanes8, Mask8, Row8, Simd};
use crate::volume_lights::VolumeEmitter;
use glam::{Vec2, Vec3};
use risotto_components::Rgb;
use std::f32::consts::PI;
use std::sync::Arc;

mod build;
mod column;
mod emission;
mod spot;

pub use emission::EmissionSample;
pub use spot::{SpotFalloff, SpotTexture};

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
    /// A spot light (Mitsuba 3's `spot`): a point light emitting `intensity * f(theta)`
    /// towards directions at angle `theta` from `direction` ([`SpotFalloff`]).
    Spot {
        /// Position.
        position: Vec3,
        /// Unit direction of the axis (where the light points).
        direction: Vec3,
        /// Radiant intensity on the axis (W/sr per channel).
        intensity: Rgb,
        /// The angular falloff.
        falloff: SpotFalloff,
        /// The projection texture, if any (multiplies the intensity).
        texture: Option<std::sync::Arc<SpotTexture>>,
    },
    /// Radiance arriving from every direction at infinity.
    Environment {
        /// Constant radiance (multiplies the map when there is one).
        radiance: Rgb,
        /// Optional equirectangular map.
        map: Option<Box<EnvironmentMap>>,
    },
    /// An emissive medium ([`crate::volume_lights`]): its samples are points inside it.
    Volume {
        /// The cells, their emission bounds and the emission field.
        emitter: Arc<VolumeEmitter>,
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
    /// Per light: what sampling a triangle area light needs, gathered in one record, for
    /// [`LightSet::sample_column`]; `None` for every other kind and for lights that are
    /// never selected.
    triangle_lights: Vec<Option<TriangleLight>>,
    /// With at most [`SMALL_SELECTION`] lights, the selection CDF's entries `1..n`: the
    /// selected light is the number of them `<= u` (as `Distribution1D::sample_discrete`).
    selection_cdf: Option<Vec<f32>>,
    /// With at most [`LANES8`] lights and a `selection_cdf`, the triangle lights indexed
    /// by light.
    lights8: Option<Box<Lights8>>,
}

/// Largest number of lights selected by counting CDF entries (one compare per light).
const SMALL_SELECTION: usize = 16;

/// Up to eight [`TriangleLight`]s as rows of [`crate::simd8`] lanes, one row per attribute
/// (zero where the light is not a triangle light): a lane's attribute is one
/// [`Simd::lookup`] by the lane's light index.
#[derive(Clone, Debug)]
struct Lights8 {
    /// Rows: `v[0].xyz`, `v[1].xyz`, `v[2].xyz`, `n.xyz`, `pmf_over_area`, `radiance.rgb`,
    /// and 1 where the light is a triangle light (0 elsewhere).
    attr: [Row8; 17],
}

impl Lights8 {
    /// `lights[j]` in column `j`.
    fn new(lights: [Option<&TriangleLight>; 8]) -> Self {
        let mut l8 = Lights8 {
            attr: [Row8([0.0; 8]); 17],
        };
        for (j, t) in lights.iter().enumerate() {
            let Some(t) = t else { continue };
            let [a, b, c] = t.v;
            let v = [a, b, c, t.n].map(|v| v.to_array());
            let [r, g, b] = t.radiance.to_array();
            let values = v.as_flattened().iter().copied();
            let values = values.chain([t.pmf_over_area, r, g, b, 1.0]);
            for (row, v) in l8.attr.iter_mut().zip(values) {
                row.0[j] = v;
            }
        }
        l8
    }
}

/// Largest number of lights in [`LightSet`]'s own [`Lights8`] table.
const LANES8: usize = 8;

/// An area light on a triangle, as [`LightSet::sample_column`] samples it.
#[derive(Clone, Copy, Debug)]
struct TriangleLight {
    /// The vertices (`SceneGeometry::triangle`).
    v: [Vec3; 3],
    /// Unit geometric normal (as `SceneGeometry::sample_prim` returns it).
    n: Vec3,
    /// Selection probability / area.
    pmf_over_area: f32,
    /// Emitted radiance.
    radiance: Rgb,
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
    /// How far short of the sampled point a shadow ray must stop, along the ray: the
    /// projection of the point's error bound (and of its rounding when the shadow ray
    /// rebuilds it as `p + distance * wi`) on the light's normal, over `|cos|` at the light
    /// ([`light_margin`]); 0 for point lights (no surface) and lights at infinity.
    pub margin: f32,
}

/// [`LightSample::margin`] of a point `q` on a light surface with unit normal `n` and
/// error bound `q_error`, sampled from a point `p` (`d = q - p` as computed, `cos_light =
/// |n . wi|`): the surface is within `dot(|n|, q_error)` of `q` along `n`, and the shadow
/// ray's rebuilt `p + distance * wi` within `gamma(5) (|d_i| + |q_i|)` of `q` per component
/// (the product `(d_i / distance) distance` errs by `gamma(3)` whatever `distance`'s error,
/// the subtraction and the sum by one rounding each); along the ray both are divided by the
/// cosine. The sum is raised by `1 + gamma(4)` for its own rounding. Written per component
/// so that [`LightSet::sample_column`]'s lanes repeat the same operations.
#[inline(always)]
pub fn light_margin(n: Vec3, q_error: Vec3, q: Vec3, d: Vec3, cos_light: f32) -> f32 {
    let g = gamma(5.0);
    let ex = q_error.x + g * (d.x.abs() + q.x.abs());
    let ey = q_error.y + g * (d.y.abs() + q.y.abs());
    let ez = q_error.z + g * (d.z.abs() + q.z.abs());
    let along_n = n.x.abs() * ex + n.y.abs() * ey + n.z.abs() * ez;
    along_n * (1.0 + gamma(4.0)) / cos_light
}

/// Output columns of [`LightSet::sample_column`], one row per point (all equally long). A
/// row whose `pdf` is 0 holds no sample: its `wi` is `Vec3::Z` (a valid direction to
/// evaluate a Bxdf for) and its other columns are unspecified. Elsewhere the row is the
/// [`LightSample`] of the same name's fields.
#[derive(Debug)]
pub struct LightSampleColumns<'a> {
    /// Unit direction from the shading point towards the light.
    pub wi: &'a mut [Vec3],
    /// Distance to the sampled point (infinity for lights at infinity).
    pub distance: &'a mut [f32],
    /// Radiance arriving along `-wi` (see [`LightSample::radiance`]).
    pub radiance: &'a mut [Rgb],
    /// Solid-angle pdf including the selection probability; 0: no sample.
    pub pdf: &'a mut [f32],
    /// True for Dirac lights (no MIS).
    pub delta: &'a mut [bool],
    /// Where the shadow ray stops short of the sampled point (see [`LightSample::margin`]).
    pub margin: &'a mut [f32],
}

impl LightSampleColumns<'_> {
    /// Number of rows (the length of `wi`).
    pub fn len(&self) -> usize {
        self.wi.len()
    }

    /// True when there are no rows.
    pub fn is_empty(&self) -> bool {
        self.wi.is_empty()
    }

    /// Row `i` as a sample (`None` where `pdf` is 0).
    pub fn get(&self, i: usize) -> Option<LightSample> {
        (self.pdf[i] != 0.0).then(|| LightSample {
            wi: self.wi[i],
            distance: self.distance[i],
            radiance: self.radiance[i],
            pdf: self.pdf[i],
            delta: self.delta[i],
            margin: self.margin[i],
        })
    }

    /// Writes `s` (`None`: no sample) as row `i`.
    #[inline]
    pub fn set(&mut self, i: usize, s: Option<LightSample>) {
        let s = s.unwrap_or(LightSample {
            wi: Vec3::Z,
            distance: 0.0,
            radiance: Rgb::BLACK,
            pdf: 0.0,
            delta: false,
            margin: 0.0,
        });
        self.wi[i] = s.wi;
        self.distance[i] = s.distance;
        self.radiance[i] = s.radiance;
        self.pdf[i] = s.pdf;
        self.delta[i] = s.delta;
        self.margin[i] = s.margin;
    }

    fn columns_equally_long(&self) -> bool {
        let n = self.len();
        self.distance.len() == n
            && self.radiance.len() == n
            && self.pdf.len() == n
            && self.delta.len() == n
            && self.margin.len() == n
    }
}

impl LightSet {
    /// The lights.
    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// True when there is no light at all.
    pub fn is_empty(&self) -> bool {
        self.lights.is_empty()
    }

    /// True when light sampling can produce a sample (some light is selectable).
    pub fn can_sample(&self) -> bool {
        self.selection.is_some()
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

    /// Whether the selection sample `u_select` selects a volume light (as [`Self::sample`]
    /// and [`Self::sample_column`] select).
    pub fn selects_volume(&self, u_select: f32) -> bool {
        self.selection.as_ref().is_some_and(|d| {
            let i = d.sample_discrete(u_select).0;
            matches!(self.lights.get(i), Some(Light::Volume { .. }))
        })
    }

    /// Volume-measure pdf (including selection) that light sampling picks the point `x` of
    /// the volume light `index` (0 for other lights): `P(light) p_V(x)`
    /// ([`crate::volume_lights`]).
    pub fn volume_pdf(&self, index: u32, x: Vec3) -> f32 {
        match self.lights.get(index as usize) {
            Some(Light::Volume { emitter }) => self.selection_pmf(index) * emitter.pdf(x),
            _ => 0.0,
        }
    }

    /// Samples a light from `p`. `u_select` chooses the light, `u` the point on it (a volume
    /// light's cell from `u_select` rescaled within the light's selection interval, its
    /// point in the cell from `u` and what is left of that rescaled value,
    /// [`VolumeEmitter::sample`]).
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
                let surf = geometry.sample_surface(*prim, u);
                let (q, n) = (surf.p, surf.ng);
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
                    margin: light_margin(n, surf.p_error, q, d, cos_light),
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
                margin: 0.0,
            }),
            Light::Point {
                position,
                intensity,
            } => point_light_sample(*position, *intensity, p, pmf),
            Light::Spot {
                position,
                direction,
                intensity,
                falloff,
                texture,
            } => {
                let s = point_light_sample(*position, *intensity, p, pmf)?;
                // The light emits towards -wi, at angle theta from its axis.
                let f = falloff.eval(-s.wi.dot(*direction));
                let radiance = match texture {
                    None => s.radiance * f,
                    Some(t) => s.radiance * t.eval(-s.wi, *direction) * f,
                };
                (f > 0.0).then_some(LightSample { radiance, ..s })
            }
            Light::Volume { emitter } => {
                let cdf = self.selection.as_ref()?.cdf();
                let (a, b) = (cdf[index], cdf[index + 1]);
                // The selection sample rescaled to [0, 1) within the light's interval picks
                // the cell (a uniform variable independent of the choice of light).
                let u_cell = if b > a {
                    ((u_select - a) / (b - a)).clamp(0.0, ONE_MINUS_EPSILON)
                } else {
                    0.0
                };
                let (x, pdf_v) = emitter.sample([u.x, u.y], u_cell)?;
                let d = x - p;
                let dist2 = d.length_squared();
                if dist2 <= 0.0 || !dist2.is_finite() {
                    return None;
                }
                let j = emitter.emission(x);
                if j.is_black() {
                    return None;
                }
                let dist = dist2.sqrt();
                // `radiance` and `pdf` both over the tracking bound: the power heuristic
                // of `pdf` against a Bxdf pdf is then the MIS weight against the collision
                // estimator (crate::volume_lights).
                let maj = emitter.mis_majorant(x);
                let pdf = pmf * pdf_v * dist2 / maj;
                (pdf > 0.0 && pdf.is_finite()).then_some(LightSample {
                    wi: d * (1.0 / dist),
                    distance: dist,
                    radiance: j * (1.0 / maj),
                    pdf,
                    delta: false,
                    margin: 0.0,
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
                    margin: 0.0,
                })
            }
        }
    }
}

/// The sample of an isotropic point light of `intensity` at `position` seen from `p`
/// (`I / d^2`, Dirac: pdf = the selection probability `pmf`); `None` at the light itself.
#[inline]
fn point_light_sample(position: Vec3, intensity: Rgb, p: Vec3, pmf: f32) -> Option<LightSample> {
    let d = position - p;
    let dist2 = d.length_squared();
    if dist2 <= 0.0 {
        return None;
    }
    let dist = dist2.sqrt();
    Some(LightSample {
        wi: d / dist,
        distance: dist,
        radiance: intensity / dist2,
        pdf: pmf,
        delta: true,
        margin: 0.0,
    })
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
    // 0 when a is 0, else 1 when a is not finite, else w when that is finite, else 1:
    // bit selects of always computed values, so that no branch depends on the (random)
    // pdfs (`if` on floats compiles to branches here).
    let w = a / (a + b);
    let w = select_bits(w.is_finite() & a.is_finite(), w, 1.0);
    select_bits(a != 0.0, w, 0.0)
}

/// `if c { x } else { y }` by bit masks: no branch.
#[inline]
fn select_bits(c: bool, x: f32, y: f32) -> f32 {
    let m = (c as u32).wrapping_neg();
    f32::from_bits((x.to_bits() & m) | (y.to_bits() & !m))
}

#[cfg(test)]
mod tests;
