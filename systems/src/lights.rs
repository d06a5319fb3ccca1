//! Light sampling (next-event estimation) and the light pdfs MIS needs.
//!
//! Lights: area lights (emissive primitives, one-sided: they emit on the side their geometric
//! normal points to), distant lights (irradiance `E` on a surface facing them), point lights
//! (intensity `I`, W/sr) and an environment (constant radiance, optionally an equirectangular
//! map, importance sampled). One light is chosen per sample in proportion to an estimate of
//! its power; the returned pdf includes that choice. Pdfs are per unit solid angle at the
//! shading point, Dirac lights (distant, point) report `delta = true` and pdf 1 x selection.

use crate::distribution::{Distribution1D, EnvironmentMap, ONE_MINUS_EPSILON};
use crate::geometry::{gamma, SceneGeometry, UNDERFLOW};
use crate::simd8::{Backend, Kernel8, Lanes8, Mask8, Row8, Simd};
use crate::volume_lights::VolumeEmitter;
use glam::{Vec2, Vec3};
use risotto_components::Rgb;
use std::f32::consts::PI;
use std::sync::Arc;

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
    /// Builds the set. `scene_radius` bounds the scene (for the power of lights at infinity).
    pub fn new(lights: Vec<Light>, geometry: &SceneGeometry, scene_radius: f32) -> Self {
        Self::with_environment_sampling(lights, geometry, scene_radius, true)
    }

    /// [`LightSet::new`], where `sample_constant_environment = false` leaves a constant
    /// environment (one without a map) out of light selection: it is never sampled and its
    /// [`environment_pdf`](Self::environment_pdf) is 0, while its radiance stays. For a
    /// caller whose every non-Dirac vertex also samples its Bxdf (and counts the
    /// environment where those rays escape, with MIS weight 1 then), that is unbiased and
    /// better: Bxdf sampling of a constant environment is importance sampling of the whole
    /// integrand but visibility, and the other lights get the light samples (pbrt-v4's
    /// `allowIncompletePDF` for `UniformInfiniteLight`). A set with nothing left to sample
    /// samples nothing ([`can_sample`](Self::can_sample)).
    pub fn with_environment_sampling(
        lights: Vec<Light>,
        geometry: &SceneGeometry,
        scene_radius: f32,
        sample_constant_environment: bool,
    ) -> Self {
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
                // As an area light's `L pi A`: radiance per length times volume, times pi.
                Light::Volume { emitter } => emitter.power() * PI,
                Light::Environment {
                    radiance,
                    map: None,
                } if !sample_constant_environment => {
                    environment = Some(i as u32);
                    let _ = radiance;
                    0.0
                }
                Light::Environment { radiance, map } => {
                    environment = Some(i as u32);
                    // Integral of the map's radiance over the sphere (4 pi for a constant 1).
                    let sphere = map.as_ref().map_or(4.0 * PI, |m| m.integral().average());
                    radiance.average() * sphere * PI * r2
                }
            })
            .map(|p| if p.is_finite() { p.max(0.0) } else { 0.0 })
            .collect();
        let power = cap_volume_power(&lights, power);
        // Without constant-environment sampling, a set whose lights all have zero power
        // selects nothing (rather than falling back to a uniform choice that would pick
        // the environment).
        let selectable = if sample_constant_environment {
            !lights.is_empty()
        } else {
            power.iter().any(|&p| p > 0.0)
        };
        let selection = selectable.then(|| Distribution1D::new(&power));
        let pmf: Vec<f32> = (0..lights.len())
            .map(|i| selection.as_ref().map_or(0.0, |d| d.pmf(i)))
            .collect();
        let pmf_over_area: Vec<f32> = lights
            .iter()
            .zip(&pmf)
            .map(|(l, &pmf)| match l {
                Light::Area { prim, .. } => pmf / geometry.prim_area(*prim),
                _ => 0.0,
            })
            .collect();
        let triangle_lights: Vec<Option<TriangleLight>> = lights
            .iter()
            .zip(&pmf_over_area)
            .zip(&pmf)
            .map(|((l, &pmf_over_area), &pmf)| match *l {
                Light::Area { prim, radiance }
                    if (prim as usize) < geometry.num_triangles() && pmf > 0.0 =>
                {
                    Some(TriangleLight {
                        v: geometry.triangle(prim as usize),
                        n: geometry.sample_prim(prim, Vec2::ZERO).1,
                        pmf_over_area,
                        radiance,
                    })
                }
                _ => None,
            })
            .collect();
        let selection_cdf = selection
            .as_ref()
            .filter(|d| d.len() <= SMALL_SELECTION)
            .map(|d| d.cdf()[1..d.len()].to_vec());
        let lights8 = (selection_cdf.is_some() && lights.len() <= LANES8).then(|| {
            let light = |j: usize| triangle_lights.get(j).and_then(Option::as_ref);
            Box::new(Lights8::new(std::array::from_fn(light)))
        });
        LightSet {
            lights,
            selection,
            light_of_prim,
            environment,
            pmf,
            pmf_over_area,
            triangle_lights,
            selection_cdf,
            lights8,
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
                    margin: 0.0,
                })
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

impl LightSet {
    /// [`Self::sample`] for a column of points: row `i` of `out` is the light sample from
    /// `p[i]` with position sample `(u[i][0], u[i][1])` and selection sample `u[i][2]` (a
    /// vertex's four-dimension set; `u[i][3]` is not used) where `active[i]`, no sample
    /// elsewhere. `geometry` must be the geometry the set was built with.
    ///
    /// Bit for bit `sample`'s results (tested). Points are taken eight at a time
    /// (`simd8` lanes): the selection, and for lanes whose selected light is a
    /// triangle area light (the common case) the point on the triangle, direction, distance
    /// and solid-angle pdf, with one square root and two divisions for the eight. Lanes of
    /// other lights go through `sample` one by one. The columns (rather than
    /// `Option<LightSample>` rows) let the caller hand `out.wi` straight to the Bxdf.
    ///
    /// # Panics
    /// When the columns differ in length.
    pub fn sample_column(
        &self,
        geometry: &SceneGeometry,
        p: &[Vec3],
        u: &[[f32; 4]],
        active: &[bool],
        out: &mut LightSampleColumns<'_>,
    ) {
        self.sample_column_on(Backend::best(), geometry, p, u, active, out);
    }

    /// [`Self::sample_column`] on the lanes of `backend`.
    fn sample_column_on(
        &self,
        backend: Backend,
        geometry: &SceneGeometry,
        p: &[Vec3],
        u: &[[f32; 4]],
        active: &[bool],
        out: &mut LightSampleColumns<'_>,
    ) {
        let len = p.len();
        assert!(
            u.len() == len && active.len() == len && out.len() == len,
            "sample_column: column lengths"
        );
        assert!(out.columns_equally_long(), "sample_column: column lengths");
        let Some(selection) = self.selection.as_ref() else {
            for i in 0..len {
                out.set(i, None);
            }
            return;
        };
        backend.run(LightColumns {
            set: self,
            selection,
            geometry,
            p,
            u,
            active,
            out,
        });
    }

    /// The lights `selection.sample_discrete(u)` chooses for eight lanes of `u`, as lanes
    /// of whole numbers. With few lights, the same count of CDF entries `<= u` (after the
    /// same clamp into `[0, 1)`), eight lanes per compare.
    #[inline(always)]
    fn select_eight<S: Simd>(&self, s: S, selection: &Distribution1D, u: S::F) -> S::F {
        match &self.selection_cdf {
            Some(cdf) => {
                // clamp_unit: NaN and negatives to 0 (the compare is false for NaN).
                let zero = s.splat(0.0);
                let u = S::F::select(zero.le(u), u.min(s.splat(ONE_MINUS_EPSILON)), zero);
                let (mut count, one) = (zero, s.splat(1.0));
                for &c in cdf {
                    count = count + S::F::select(s.splat(c).le(u), one, zero);
                }
                count
            }
            None => {
                let index = u.to_array().map(|u| selection.sample_discrete(u).0 as f32);
                s.load(&Row8(index))
            }
        }
    }

    /// Eight points of [`Self::sample_column`]: `LightSet::sample`'s `Light::Area` branch with
    /// `SceneGeometry::sample_prim`'s triangle branch on the lanes of `s`, operation for
    /// operation the same float arithmetic (no fused multiply-add), so the same bits; lanes
    /// whose light is not a triangle light through `LightSet::sample`.
    #[inline(always)]
    fn sample_eight<S: Simd>(
        &self,
        s: S,
        selection: &Distribution1D,
        geometry: &SceneGeometry,
        (p, u, active): (&[Vec3; 8], &[[f32; 4]; 8], &[bool; 8]),
        out: Out8<'_>,
    ) {
        let [px, py, pz] = s.load_xyz(p);
        // No closures over lane operations here: a closure's body is compiled without the
        // kernel's target features.
        let ux = s.load(&Row8(u.map(|u| u[0])));
        let uy = s.load(&Row8(u.map(|u| u[1])));
        let index = self.select_eight(s, selection, s.load(&Row8(u.map(|u| u[2]))));
        // The attribute table and each lane's column in it: the set's own, by light, or
        // the lanes' lights gathered, by lane.
        let gathered;
        let (l8, column) = match self.lights8.as_deref() {
            Some(l8) => (l8, index),
            None => {
                let index = index
                    .to_array()
                    .map(|i| self.triangle_lights[i as usize].as_ref());
                gathered = Lights8::new(index);
                let lane = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0];
                (&gathered, s.load(&Row8(lane)))
            }
        };
        let (zero, one, inf) = (s.splat(0.0), s.splat(1.0), s.splat(f32::INFINITY));
        // Heitz 2019 (see SceneGeometry::sample_prim): fold the square onto the triangle.
        let below = ux.lt(uy);
        let half = s.splat(0.5);
        let (hx, hy) = (ux * half, uy * half);
        let b0 = S::F::select(below, hx, ux - hy);
        let b1 = S::F::select(below, uy - hx, hy);
        let b2 = one - b0 - b1;
        let [x0, y0, z0, x1, y1, z1, x2, y2, z2, nx, ny, nz, pmf_over_area, r, g, b, triangle] =
            &l8.attr;
        let triangle = s.lookup(triangle, column).gt(zero).bits();
        let (x0, y0, z0) = (
            s.lookup(x0, column),
            s.lookup(y0, column),
            s.lookup(z0, column),
        );
        let (x1, y1, z1) = (
            s.lookup(x1, column),
            s.lookup(y1, column),
            s.lookup(z1, column),
        );
        let (x2, y2, z2) = (
            s.lookup(x2, column),
            s.lookup(y2, column),
            s.lookup(z2, column),
        );
        let qx = x0 * b0 + x1 * b1 + x2 * b2;
        let qy = y0 * b0 + y1 * b1 + y2 * b2;
        let qz = z0 * b0 + z1 * b1 + z2 * b2;
        let (dx, dy, dz) = (qx - px, qy - py, qz - pz);
        let dist2 = dx * dx + dy * dy + dz * dz;
        // dist2 > 0 and finite (false for NaN), like sample's early return.
        let ok = dist2.gt(zero) & dist2.lt(inf);
        let dist = dist2.sqrt();
        let inv = one / dist;
        let (wx, wy, wz) = (dx * inv, dy * inv, dz * inv);
        // One-sided emitter: cos_light = -n . wi > 0.
        let (nx, ny, nz) = (
            s.lookup(nx, column),
            s.lookup(ny, column),
            s.lookup(nz, column),
        );
        let cos_light = (nx * wx + ny * wy + nz * wz).neg();
        // `light_margin` of `sample_surface`'s bound, `triangle_point_error([v2, v1, v0],
        // b2, b1, b0)`, operation for operation.
        let (ab0, ab1, ab2) = (b0.abs(), b1.abs(), b2.abs());
        let (g3, g4, g5) = (
            s.splat(gamma(3.0)),
            s.splat(gamma(4.0)),
            s.splat(gamma(5.0)),
        );
        let tiny = s.splat(UNDERFLOW);
        let lever = g3 * ((one + ab1) + ab0);
        let ex = (x2.abs() * ab2 + x1.abs() * ab1 + x0.abs() * ab0) * g4 + x2.abs() * lever + tiny;
        let ey = (y2.abs() * ab2 + y1.abs() * ab1 + y0.abs() * ab0) * g4 + y2.abs() * lever + tiny;
        let ez = (z2.abs() * ab2 + z1.abs() * ab1 + z0.abs() * ab0) * g4 + z2.abs() * lever + tiny;
        let ex = ex + g5 * (dx.abs() + qx.abs());
        let ey = ey + g5 * (dy.abs() + qy.abs());
        let ez = ez + g5 * (dz.abs() + qz.abs());
        let along_n = nx.abs() * ex + ny.abs() * ey + nz.abs() * ez;
        let margin = along_n * s.splat(1.0 + gamma(4.0)) / cos_light;
        let pdf = s.lookup(pmf_over_area, column) * dist2 / cos_light;
        let act = s.load(&Row8(active.map(|a| if a { 1.0 } else { 0.0 })));
        let ok = ok & cos_light.gt(zero) & pdf.gt(zero) & pdf.lt(inf) & act.gt(zero);
        // Rows without a sample: pdf 0 and wi +z.
        let wx = S::F::select(ok, wx, zero).to_array();
        let wy = S::F::select(ok, wy, zero).to_array();
        let wz = S::F::select(ok, wz, one).to_array();
        let (r, g, b) = (
            s.lookup(r, column).to_array(),
            s.lookup(g, column).to_array(),
            s.lookup(b, column).to_array(),
        );
        for j in 0..8 {
            out.wi[j] = Vec3::new(wx[j], wy[j], wz[j]);
            out.radiance[j] = Rgb::new(r[j], g[j], b[j]);
        }
        *out.distance = dist.to_array();
        *out.pdf = S::F::select(ok, pdf, zero).to_array();
        *out.delta = [false; 8];
        *out.margin = S::F::select(ok, margin, zero).to_array();
        if triangle != 0xff {
            self.other_lanes(geometry, triangle, p, u, active, out);
        }
    }

    /// The lanes of [`Self::sample_eight`] whose light is not a triangle light (bit clear
    /// in `triangle`), through `LightSet::sample`.
    #[cold]
    #[inline(never)]
    fn other_lanes(
        &self,
        geometry: &SceneGeometry,
        triangle: u32,
        p: &[Vec3; 8],
        u: &[[f32; 4]; 8],
        active: &[bool; 8],
        out: Out8<'_>,
    ) {
        let mut cols = LightSampleColumns {
            wi: out.wi,
            distance: out.distance,
            radiance: out.radiance,
            pdf: out.pdf,
            delta: out.delta,
            margin: out.margin,
        };
        for j in (0..8).filter(|&j| triangle & (1 << j) == 0) {
            let s = active[j]
                .then(|| self.sample(geometry, p[j], u[j][2], Vec2::new(u[j][0], u[j][1])))
                .flatten();
            cols.set(j, s);
        }
    }
}

/// The scalar reference of [`LightSet::sample_column`], point by point.
#[cfg(test)]
fn sample_column_scalar(
    set: &LightSet,
    geometry: &SceneGeometry,
    p: &[Vec3],
    u: &[[f32; 4]],
    active: &[bool],
) -> Vec<Option<LightSample>> {
    (0..p.len())
        .map(|i| {
            active[i]
                .then(|| set.sample(geometry, p[i], u[i][2], Vec2::new(u[i][0], u[i][1])))
                .flatten()
        })
        .collect()
}

/// Eight rows of the output columns.
struct Out8<'a> {
    wi: &'a mut [Vec3; 8],
    distance: &'a mut [f32; 8],
    radiance: &'a mut [Rgb; 8],
    pdf: &'a mut [f32; 8],
    delta: &'a mut [bool; 8],
    margin: &'a mut [f32; 8],
}

/// The arguments of [`LightSet::sample_column`] (columns of equal length, a selection
/// exists), as a [`Kernel8`].
struct LightColumns<'a, 'o> {
    set: &'a LightSet,
    selection: &'a Distribution1D,
    geometry: &'a SceneGeometry,
    p: &'a [Vec3],
    u: &'a [[f32; 4]],
    active: &'a [bool],
    out: &'a mut LightSampleColumns<'o>,
}

impl Kernel8 for LightColumns<'_, '_> {
    type Output = ();
    #[inline(always)]
    fn run<S: Simd>(self, s: S) {
        let (set, selection, geometry) = (self.set, self.selection, self.geometry);
        let (p8, p_rest) = self.p.as_chunks::<8>();
        let (u8, u_rest) = self.u.as_chunks::<8>();
        let (a8, a_rest) = self.active.as_chunks::<8>();
        let out = &mut *self.out;
        let (wi8, wi_rest) = out.wi.as_chunks_mut::<8>();
        let (distance8, distance_rest) = out.distance.as_chunks_mut::<8>();
        let (radiance8, radiance_rest) = out.radiance.as_chunks_mut::<8>();
        let (pdf8, pdf_rest) = out.pdf.as_chunks_mut::<8>();
        let (delta8, delta_rest) = out.delta.as_chunks_mut::<8>();
        let (margin8, margin_rest) = out.margin.as_chunks_mut::<8>();
        let outs = wi8
            .iter_mut()
            .zip(distance8)
            .zip(radiance8)
            .zip(pdf8)
            .zip(delta8)
            .zip(margin8);
        for (((p, u), a), o) in p8.iter().zip(u8).zip(a8).zip(outs) {
            let (((((wi, distance), radiance), pdf), delta), margin) = o;
            let o = Out8 {
                wi,
                distance,
                radiance,
                pdf,
                delta,
                margin,
            };
            set.sample_eight(s, selection, geometry, (p, u, a), o);
        }
        if !p_rest.is_empty() {
            // The last partial block, padded with inactive copies of its first point.
            // Element loops rather than `copy_from_slice`: a `memcpy` call of a varying
            // small length mispredicts inside.
            let (mut p, mut u, mut a) = ([p_rest[0]; 8], [u_rest[0]; 8], [false; 8]);
            for (j, ((&pr, &ur), &ar)) in p_rest.iter().zip(u_rest).zip(a_rest).enumerate() {
                (p[j], u[j], a[j]) = (pr, ur, ar);
            }
            let (mut wi, mut distance, mut radiance) = ([Vec3::Z; 8], [0.0; 8], [Rgb::BLACK; 8]);
            let (mut pdf, mut delta, mut margin) = ([0.0; 8], [false; 8], [0.0; 8]);
            let o = Out8 {
                wi: &mut wi,
                distance: &mut distance,
                radiance: &mut radiance,
                pdf: &mut pdf,
                delta: &mut delta,
                margin: &mut margin,
            };
            set.sample_eight(s, selection, geometry, (&p, &u, &a), o);
            let rest = wi_rest
                .iter_mut()
                .zip(distance_rest)
                .zip(radiance_rest)
                .zip(pdf_rest)
                .zip(delta_rest)
                .zip(margin_rest);
            for (j, (((((w, d), r), p), de), mg)) in rest.enumerate() {
                (*w, *d, *r, *p, *de) = (wi[j], distance[j], radiance[j], pdf[j], delta[j]);
                *mg = margin[j];
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

/// The selection powers with the volume lights' share capped at one half when other lights
/// have power: a volume emitter's `j_max V` overstates what reaches a vertex (much of it is
/// absorbed inside the medium, and the cells of a large emitter far from the vertex light it
/// little), and at full weight a wide emissive slab took all but `1e-5` of the light
/// samples from a point light beside it. Sets without volume lights are unchanged.
fn cap_volume_power(lights: &[Light], mut power: Vec<f32>) -> Vec<f32> {
    let is_volume = |i: usize| matches!(lights[i], Light::Volume { .. });
    let (mut volume, mut other) = (0.0f64, 0.0f64);
    for (i, &p) in power.iter().enumerate() {
        if is_volume(i) {
            volume += p as f64;
        } else {
            other += p as f64;
        }
    }
    if volume > other && other > 0.0 {
        let k = (other / volume) as f32;
        for (i, p) in power.iter_mut().enumerate() {
            if is_volume(i) {
                *p *= k;
            }
        }
    }
    power
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
mod tests {
    use super::*;
    use crate::geometry::Sphere;
    use crate::sampler::SplitMix64 as Rng;

    /// A scene of `n_tri` small triangles (area lights of varied power, some facing away
    /// from the origin region) plus one sphere; returns the geometry and the triangle lights.
    fn triangle_scene(n_tri: usize, rng: &mut Rng) -> (SceneGeometry, Vec<Light>) {
        let mut tris = Vec::new();
        let mut lights = Vec::new();
        for i in 0..n_tri {
            let c = Vec3::new(
                rng.f32() * 4.0 - 2.0,
                1.0 + rng.f32(),
                rng.f32() * 4.0 - 2.0,
            );
            let e1 = Vec3::new(rng.f32(), 0.1 * rng.f32(), rng.f32() - 0.5);
            let e2 = Vec3::new(rng.f32() - 0.5, 0.1 * rng.f32(), rng.f32());
            tris.push(if i % 2 == 0 {
                [c, c + e1, c + e2]
            } else {
                [c, c + e2, c + e1]
            });
            lights.push(Light::Area {
                prim: i as u32,
                radiance: Rgb::new(1.0 + i as f32, 2.0, 0.5 * rng.f32()),
            });
        }
        let sphere = Sphere {
            center: Vec3::new(0.0, 3.0, 0.0),
            radius: 0.5,
        };
        (SceneGeometry::build(tris, vec![sphere]), lights)
    }

    /// `set.sample_column` into fresh columns (filled with junk first, so that rows the
    /// sampler fails to write show), read back as rows.
    fn sample_column_rows(
        backend: Backend,
        set: &LightSet,
        geometry: &SceneGeometry,
        p: &[Vec3],
        u: &[[f32; 4]],
        active: &[bool],
    ) -> Vec<Option<LightSample>> {
        let n = p.len();
        let (mut wi, mut distance, mut radiance) =
            (vec![Vec3::NAN; n], vec![-1.0; n], vec![Rgb::splat(-1.0); n]);
        let (mut pdf, mut delta, mut margin) = (vec![-1.0; n], vec![true; n], vec![-1.0; n]);
        let mut cols = LightSampleColumns {
            wi: &mut wi,
            distance: &mut distance,
            radiance: &mut radiance,
            pdf: &mut pdf,
            delta: &mut delta,
            margin: &mut margin,
        };
        set.sample_column_on(backend, geometry, p, u, active, &mut cols);
        for i in 0..n {
            if cols.pdf[i] == 0.0 {
                assert_eq!(cols.wi[i], Vec3::Z, "rows without a sample have wi = +z");
            }
        }
        (0..n).map(|i| cols.get(i)).collect()
    }

    /// `sample_column` must return exactly `sample`'s results point by point.
    fn check_column(set: &LightSet, geometry: &SceneGeometry, rng: &mut Rng) {
        for len in [0usize, 1, 3, 4, 5, 8, 11, 64] {
            let p: Vec<Vec3> = (0..len)
                .map(|i| match i % 7 {
                    // A point on a light's plane corner and far away points: degenerate
                    // and grazing samples.
                    0 => geometry.triangle(0)[0],
                    1 => Vec3::splat(1e30),
                    _ => Vec3::new(
                        rng.f32() * 2.0 - 1.0,
                        rng.f32() - 1.0,
                        rng.f32() * 2.0 - 1.0,
                    ),
                })
                .collect();
            let u: Vec<[f32; 4]> = (0..len)
                .map(|i| match i % 5 {
                    0 => [0.0, 0.0, 0.0, 0.5],
                    1 => [0.5, 0.5, 1.0 - f32::EPSILON / 2.0, 0.5],
                    _ => [rng.f32(), rng.f32(), rng.f32(), rng.f32()],
                })
                .collect();
            let active: Vec<bool> = (0..len).map(|i| i % 6 != 3).collect();
            let want = sample_column_scalar(set, geometry, &p, &u, &active);
            for backend in Backend::all() {
                let out = sample_column_rows(backend, set, geometry, &p, &u, &active);
                check_rows(&out, &want, &format!("{backend:?}, len {len}"));
            }
        }
    }

    /// Rows `got` and `want` hold the same bits.
    fn check_rows(got: &[Option<LightSample>], want: &[Option<LightSample>], what: &str) {
        for i in 0..want.len() {
            {
                let bits = |s: Option<LightSample>| {
                    s.map(|s| {
                        (
                            s.wi.to_array().map(f32::to_bits),
                            s.distance.to_bits(),
                            s.radiance.to_array().map(f32::to_bits),
                            s.pdf.to_bits(),
                            s.delta,
                            s.margin.to_bits(),
                        )
                    })
                };
                assert_eq!(bits(got[i]), bits(want[i]), "{what}, point {i}");
            }
        }
    }

    #[test]
    fn power_heuristic_weights_and_edge_cases() {
        // Veach's w = a^2 / (a^2 + b^2), and the conventions for degenerate pdfs.
        assert_eq!(power_heuristic(1.0, 1.0), 0.5);
        assert_eq!(power_heuristic(3.0, 4.0), 9.0 / 25.0);
        assert_eq!(power_heuristic(0.0, 2.0), 0.0, "a = 0");
        assert_eq!(power_heuristic(0.0, 0.0), 0.0, "a = b = 0");
        assert_eq!(power_heuristic(f32::INFINITY, 1.0), 1.0, "a infinite");
        assert_eq!(power_heuristic(1e20, 1.0), 1.0, "a^2 overflows");
        assert_eq!(power_heuristic(f32::NAN, 1.0), 1.0, "a NaN");
        assert_eq!(power_heuristic(1.0, f32::INFINITY), 0.0, "b infinite");
        assert_eq!(power_heuristic(1.0, f32::NAN), 1.0, "w NaN");
        assert_eq!(power_heuristic(1e19, 1e19), 0.5, "a^2 + b^2 finite");
    }

    #[test]
    fn column_sampling_equals_per_point_sampling() {
        let mut rng = Rng(5);
        // Triangle lights only (every group takes the four-lane path), with few lights
        // (selection by counting) and many (binary search in the distribution).
        for n in [1usize, 2, 5, 16, 40] {
            let (geometry, lights) = triangle_scene(n, &mut rng);
            let set = LightSet::new(lights, &geometry, 10.0);
            check_column(&set, &geometry, &mut rng);
        }
        // Mixed kinds: groups that select a sphere, point, distant or environment light
        // fall back to per-point sampling; a zero-power triangle light is never selected.
        let (geometry, mut lights) = triangle_scene(4, &mut rng);
        lights.push(Light::Area {
            prim: 4,
            radiance: Rgb::splat(3.0),
        });
        lights.push(Light::Point {
            position: Vec3::new(0.0, 2.0, 0.0),
            intensity: Rgb::splat(5.0),
        });
        lights.push(Light::Distant {
            direction: -Vec3::Y,
            irradiance: Rgb::splat(0.5),
        });
        lights.push(Light::Environment {
            radiance: Rgb::splat(0.1),
            map: None,
        });
        lights.push(Light::Area {
            prim: 3,
            radiance: Rgb::BLACK,
        });
        let set = LightSet::new(lights, &geometry, 10.0);
        check_column(&set, &geometry, &mut rng);
        // At most eight lights of mixed kinds (the eight-lane path, whose lanes of other
        // kinds go through `sample`).
        let (geometry, mut lights) = triangle_scene(3, &mut rng);
        lights.push(Light::Area {
            prim: 3,
            radiance: Rgb::splat(3.0),
        });
        lights.push(Light::Point {
            position: Vec3::new(0.0, 2.0, 0.0),
            intensity: Rgb::splat(5.0),
        });
        lights.push(Light::Area {
            prim: 2,
            radiance: Rgb::BLACK,
        });
        let set = LightSet::new(lights, &geometry, 10.0);
        check_column(&set, &geometry, &mut rng);
        // No lights at all.
        let set = LightSet::new(Vec::new(), &geometry, 10.0);
        check_column(&set, &geometry, &mut rng);
    }

    #[test]
    fn triangle_light_samples_match_area_pdf_and_emitter() {
        // Independent of the sampling code path: every sample's pdf is the solid-angle pdf
        // area_pdf computes from the hit point, and the point lies on the sampled emitter's
        // plane at the reported distance.
        let mut rng = Rng(9);
        let (geometry, lights) = triangle_scene(6, &mut rng);
        let set = LightSet::new(lights, &geometry, 10.0);
        let n = 4096;
        let p: Vec<Vec3> = (0..n)
            .map(|_| Vec3::new(rng.f32(), -1.0, rng.f32()))
            .collect();
        let u: Vec<[f32; 4]> = (0..n)
            .map(|_| [rng.f32(), rng.f32(), rng.f32(), 0.0])
            .collect();
        let out = sample_column_rows(Backend::best(), &set, &geometry, &p, &u, &vec![true; n]);
        let mut found = 0;
        for (i, s) in out.iter().enumerate() {
            let Some(s) = s else { continue };
            found += 1;
            let q = p[i] + s.wi * s.distance;
            let prim = (0..6)
                .find(|&t| {
                    let [a, b, c] = geometry.triangle(t);
                    let nrm = (b - a).cross(c - a).normalize();
                    (q - a).dot(nrm).abs() < 1e-4
                })
                .expect("sample lies on some emitter") as u32;
            let ng = geometry.sample_prim(prim, Vec2::ZERO).1;
            let want = set.area_pdf(prim, p[i], q, ng);
            assert!((s.pdf - want).abs() <= 1e-3 * want, "{} vs {want}", s.pdf);
        }
        assert!(found > n / 4, "only {found} samples");
    }
}
