//! Light sampling (next-event estimation) and the light pdfs MIS needs.
//!
//! Lights: area lights (emissive primitives, one-sided: they emit on the side their geometric
//! normal points to), distant lights (irradiance `E` on a surface facing them), point lights
//! (intensity `I`, W/sr) and an environment (constant radiance, optionally an equirectangular
//! map, importance sampled). One light is chosen per sample in proportion to an estimate of
//! its power; the returned pdf includes that choice. Pdfs are per unit solid angle at the
//! shading point, Dirac lights (distant, point) report `delta = true` and pdf 1 x selection.

use crate::distribution::{Distribution1D, EnvironmentMap, ONE_MINUS_EPSILON};
use crate::geometry::SceneGeometry;
use glam::{Vec2, Vec3, Vec4};
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
    /// Per light: what sampling a triangle area light needs, gathered in one record, for
    /// [`LightSet::sample_column`]; `None` for every other kind and for lights that are
    /// never selected.
    triangle_lights: Vec<Option<TriangleLight>>,
    /// With at most [`SMALL_SELECTION`] lights, the selection CDF's entries `1..n`: the
    /// selected light is the number of them `<= u` (as `Distribution1D::sample_discrete`).
    selection_cdf: Option<Vec<f32>>,
    /// With at most [`LANES8`] lights (and a `selection_cdf`), the triangle lights'
    /// attributes as columns indexed by light, for the eight-lane AVX2 sampler.
    lights8: Option<Box<Lights8>>,
}

/// Largest number of lights the eight-lane sampler handles: one light per lane of a 256-bit
/// register, so that a lane's light attribute is one `vpermps` by the lane's light index.
const LANES8: usize = 8;

/// The [`TriangleLight`]s of a set of at most [`LANES8`] lights, one row per attribute and
/// one column per light (zero for lights that are not triangle lights).
#[derive(Clone, Debug)]
struct Lights8 {
    /// Rows: `v[0].xyz`, `v[1].xyz`, `v[2].xyz`, `n.xyz`, `pmf_over_area`, `radiance.rgb`.
    attr: [[f32; LANES8]; 16],
    /// -1 (all bits) where the light is a triangle light, 0 elsewhere.
    triangle: [i32; LANES8],
}

impl Lights8 {
    fn new(triangle_lights: &[Option<TriangleLight>]) -> Self {
        let mut l8 = Lights8 {
            attr: [[0.0; LANES8]; 16],
            triangle: [0; LANES8],
        };
        for (i, t) in triangle_lights.iter().enumerate() {
            let Some(t) = t else { continue };
            let values = [
                t.v[0].x,
                t.v[0].y,
                t.v[0].z,
                t.v[1].x,
                t.v[1].y,
                t.v[1].z,
                t.v[2].x,
                t.v[2].y,
                t.v[2].z,
                t.n.x,
                t.n.y,
                t.n.z,
                t.pmf_over_area,
                t.radiance.r,
                t.radiance.g,
                t.radiance.b,
            ];
            for (row, v) in l8.attr.iter_mut().zip(values) {
                row[i] = v;
            }
            l8.triangle[i] = -1;
        }
        l8
    }
}

/// Number of chunks (a helper that keeps the chunk count readable where it is used).
#[inline]
fn len_of<T>(chunks: &[T]) -> usize {
    chunks.len()
}

/// Largest number of lights selected by counting CDF entries (one compare per light).
const SMALL_SELECTION: usize = 16;

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
        });
        self.wi[i] = s.wi;
        self.distance[i] = s.distance;
        self.radiance[i] = s.radiance;
        self.pdf[i] = s.pdf;
        self.delta[i] = s.delta;
    }

    fn columns_equally_long(&self) -> bool {
        let n = self.len();
        self.distance.len() == n
            && self.radiance.len() == n
            && self.pdf.len() == n
            && self.delta.len() == n
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
        let lights8 = (selection_cdf.is_some() && lights.len() <= LANES8)
            .then(|| Box::new(Lights8::new(&triangle_lights)));
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

impl LightSet {
    /// [`Self::sample`] for a column of points: row `i` of `out` is the light sample from
    /// `p[i]` with position sample `(u[i][0], u[i][1])` and selection sample `u[i][2]` (a
    /// vertex's four-dimension set; `u[i][3]` is not used) where `active[i]`, no sample
    /// elsewhere. `geometry` must be the geometry the set was built with.
    ///
    /// Bit for bit `sample`'s results (tested). Groups of points whose selected lights are
    /// all triangle area lights (the common case) are evaluated in SIMD lanes: the point on
    /// the triangle, direction, distance and solid-angle pdf of four (SSE) or eight (AVX2,
    /// at most eight lights) samples share one square root and two divisions. Other points
    /// go through `sample` one by one. The columns (rather than `Option<LightSample>`
    /// rows) let the eight-lane path store whole vectors and the caller hand `out.wi`
    /// straight to the Bxdf.
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
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx2") {
            if let (Some(l8), Some(cdf)) = (self.lights8.as_deref(), self.selection_cdf.as_deref())
            {
                // SAFETY: this CPU has AVX2 (checked above).
                #[allow(unsafe_code, reason = "AVX2 dispatch after run-time detection")]
                unsafe {
                    avx2::sample_column(self, l8, cdf, geometry, p, u, active, out)
                };
                return;
            }
            // SAFETY: this CPU has AVX2 (checked above).
            #[allow(unsafe_code, reason = "AVX2 dispatch after run-time detection")]
            unsafe {
                self.sample_column_avx2(geometry, selection, p, u, active, out)
            };
            return;
        }
        self.sample_column_lanes(geometry, selection, p, u, active, out);
    }

    /// [`Self::sample_column_lanes`] compiled for AVX2: the same four-lane operations in
    /// VEX encoding (three operands, `blendv` selects). No FMA is enabled, so every product
    /// and sum rounds as in the SSE build: the same bits.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn sample_column_avx2(
        &self,
        geometry: &SceneGeometry,
        selection: &Distribution1D,
        p: &[Vec3],
        u: &[[f32; 4]],
        active: &[bool],
        out: &mut LightSampleColumns<'_>,
    ) {
        self.sample_column_lanes(geometry, selection, p, u, active, out);
    }

    /// The body of [`Self::sample_column`] (columns of equal length, a selection exists).
    #[inline(always)]
    fn sample_column_lanes(
        &self,
        geometry: &SceneGeometry,
        selection: &Distribution1D,
        p: &[Vec3],
        u: &[[f32; 4]],
        active: &[bool],
        out: &mut LightSampleColumns<'_>,
    ) {
        let (p4, p_rest) = p.as_chunks::<4>();
        let (u4, u_rest) = u.as_chunks::<4>();
        let (a4, a_rest) = active.as_chunks::<4>();
        for (g, ((p, u), a)) in p4.iter().zip(u4).zip(a4).enumerate() {
            let mut o = [None; 4];
            self.sample_four(geometry, selection, p, u, a, &mut o);
            for (j, o) in o.into_iter().enumerate() {
                out.set(4 * g + j, o);
            }
        }
        if !p_rest.is_empty() {
            // The last partial group, padded with inactive copies of its first point.
            let r = p_rest.len();
            let (mut p, mut u, mut a) = ([p_rest[0]; 4], [u_rest[0]; 4], [false; 4]);
            p[..r].copy_from_slice(p_rest);
            u[..r].copy_from_slice(u_rest);
            a[..r].copy_from_slice(a_rest);
            let mut o = [None; 4];
            self.sample_four(geometry, selection, &p, &u, &a, &mut o);
            let start = len_of(p4) * 4;
            for (j, o) in o.into_iter().take(r).enumerate() {
                out.set(start + j, o);
            }
        }
    }

    /// Four points of [`Self::sample_column`].
    #[inline(always)]
    fn sample_four(
        &self,
        geometry: &SceneGeometry,
        selection: &Distribution1D,
        p: &[Vec3; 4],
        u: &[[f32; 4]; 4],
        active: &[bool; 4],
        out: &mut [Option<LightSample>; 4],
    ) {
        let index = self.select_four(selection, Vec4::new(u[0][2], u[1][2], u[2][2], u[3][2]));
        let pick = |j: usize| self.triangle_lights[index[j]].as_ref();
        if let (Some(t0), Some(t1), Some(t2), Some(t3)) = (pick(0), pick(1), pick(2), pick(3)) {
            sample_triangles_four([t0, t1, t2, t3], p, u, active, out);
        } else {
            for j in 0..4 {
                out[j] = if active[j] {
                    self.sample(geometry, p[j], u[j][2], Vec2::new(u[j][0], u[j][1]))
                } else {
                    None
                };
            }
        }
    }

    /// The lights `selection.sample_discrete(u)` chooses for four lanes of `u`. With few
    /// lights, the same count of CDF entries `<= u` (after the same clamp into `[0, 1)`),
    /// four lanes per compare.
    #[inline(always)]
    fn select_four(&self, selection: &Distribution1D, u: Vec4) -> [usize; 4] {
        match &self.selection_cdf {
            Some(cdf) => {
                // clamp_unit: NaN and negatives to 0 (the compare is false for NaN).
                let u = Vec4::select(
                    u.cmpge(Vec4::ZERO),
                    u.min(Vec4::splat(ONE_MINUS_EPSILON)),
                    Vec4::ZERO,
                );
                // Per-lane counts in the bytes of one integer: multiplying the 4-bit compare
                // mask by 0x0020_4081 moves bit j to bit 8j (the shifted copies do not
                // overlap), and at most 16 entries keep every byte below 256.
                let mut count = 0u32;
                for &c in cdf {
                    let mask = Vec4::splat(c).cmple(u).bitmask();
                    count += mask.wrapping_mul(0x0020_4081) & 0x0101_0101;
                }
                [0, 1, 2, 3].map(|j| ((count >> (8 * j)) & 0xff) as usize)
            }
            None => u.to_array().map(|u| selection.sample_discrete(u).0),
        }
    }
}

/// The `Light::Area` branch of [`LightSet::sample`] with `SceneGeometry::sample_prim`'s
/// triangle branch, for four (light, point, sample) triples in SSE lanes, operation for
/// operation the same float arithmetic (so bit for bit the same values); `None` where
/// `sample` returns `None` and in inactive lanes.
#[inline(always)]
fn sample_triangles_four(
    t: [&TriangleLight; 4],
    p: &[Vec3; 4],
    u: &[[f32; 4]; 4],
    active: &[bool; 4],
    out: &mut [Option<LightSample>; 4],
) {
    let lanes = |f: &dyn Fn(usize) -> f32| Vec4::new(f(0), f(1), f(2), f(3));
    let (ux, uy) = (lanes(&|j| u[j][0]), lanes(&|j| u[j][1]));
    // Heitz 2019 (see SceneGeometry::sample_prim): fold the square onto the triangle.
    let below = ux.cmplt(uy);
    let (hx, hy) = (ux * 0.5, uy * 0.5);
    let b0 = Vec4::select(below, hx, ux - hy);
    let b1 = Vec4::select(below, uy - hx, hy);
    let b2 = Vec4::ONE - b0 - b1;
    let q = |c: usize| {
        lanes(&|j| t[j].v[0][c]) * b0
            + lanes(&|j| t[j].v[1][c]) * b1
            + lanes(&|j| t[j].v[2][c]) * b2
    };
    let dx = q(0) - lanes(&|j| p[j].x);
    let dy = q(1) - lanes(&|j| p[j].y);
    let dz = q(2) - lanes(&|j| p[j].z);
    let dist2 = dx * dx + dy * dy + dz * dz;
    // dist2 > 0 and finite (false for NaN), like sample's early return.
    let mut ok = dist2.cmpgt(Vec4::ZERO) & dist2.cmplt(Vec4::INFINITY);
    let dist = dist2.sqrt();
    let inv = Vec4::ONE / dist;
    let (wx, wy, wz) = (dx * inv, dy * inv, dz * inv);
    let cos_light =
        -(lanes(&|j| t[j].n.x) * wx + lanes(&|j| t[j].n.y) * wy + lanes(&|j| t[j].n.z) * wz);
    ok &= cos_light.cmpgt(Vec4::ZERO);
    let pdf = lanes(&|j| t[j].pmf_over_area) * dist2 / cos_light;
    ok &= pdf.cmpgt(Vec4::ZERO) & pdf.cmplt(Vec4::INFINITY);
    let ok = ok.bitmask();
    let (wx, wy, wz) = (wx.to_array(), wy.to_array(), wz.to_array());
    let (dist, pdf) = (dist.to_array(), pdf.to_array());
    for j in 0..4 {
        out[j] = (active[j] && ok & (1 << j) != 0).then(|| LightSample {
            wi: Vec3::new(wx[j], wy[j], wz[j]),
            distance: dist[j],
            radiance: t[j].radiance,
            pdf: pdf[j],
            delta: false,
        });
    }
}

/// [`LightSet::sample_column`] eight points at a time for sets of at most [`LANES8`] lights
/// selected by counting CDF entries: the selected light's index, a vector of eight, picks
/// each triangle attribute with one `vpermps` from a register holding it for every light,
/// where the four-lane path gathers four scalars per attribute; and one square root and two
/// divisions serve eight samples. The float operations are [`sample_triangles_four`]'s
/// (no FMA), lane by lane, so the bits are `LightSet::sample`'s. Lanes whose light is not a
/// triangle light go through `LightSet::sample`.
#[cfg(target_arch = "x86_64")]
#[allow(
    unsafe_code,
    reason = "AVX2 intrinsics: unaligned loads of references' memory, and the calls into \
              `#[target_feature]` functions, reached only after run-time detection"
)]
mod avx2 {
    use super::{LightSampleColumns, LightSet, Lights8, LANES8};
    use crate::distribution::ONE_MINUS_EPSILON;
    use crate::geometry::SceneGeometry;
    use glam::{Vec2, Vec3};
    use risotto_components::Rgb;
    use std::arch::x86_64::*;

    /// Points per kernel call.
    const N: usize = LANES8;

    /// The body of `LightSet::sample_column` (columns of equal length checked by the
    /// caller).
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[target_feature(enable = "avx2")]
    #[allow(
        clippy::too_many_arguments,
        reason = "the set, its columns and the output"
    )]
    pub(super) unsafe fn sample_column(
        set: &LightSet,
        l8: &Lights8,
        cdf: &[f32],
        geometry: &SceneGeometry,
        p: &[Vec3],
        u: &[[f32; 4]],
        active: &[bool],
        out: &mut LightSampleColumns<'_>,
    ) {
        let (p8, p_rest) = p.as_chunks::<N>();
        let (u8, u_rest) = u.as_chunks::<N>();
        let (a8, a_rest) = active.as_chunks::<N>();
        let (wi8, wi_rest) = out.wi.as_chunks_mut::<N>();
        let (distance8, distance_rest) = out.distance.as_chunks_mut::<N>();
        let (radiance8, radiance_rest) = out.radiance.as_chunks_mut::<N>();
        let (pdf8, pdf_rest) = out.pdf.as_chunks_mut::<N>();
        let (delta8, delta_rest) = out.delta.as_chunks_mut::<N>();
        let outs = wi8
            .iter_mut()
            .zip(distance8)
            .zip(radiance8)
            .zip(pdf8)
            .zip(delta8);
        for (((p, u), a), o) in p8.iter().zip(u8).zip(a8).zip(outs) {
            let ((((wi, distance), radiance), pdf), delta) = o;
            let o = Out8 {
                wi,
                distance,
                radiance,
                pdf,
                delta,
            };
            eight(set, l8, cdf, geometry, p, u, a, o);
        }
        if !p_rest.is_empty() {
            // The last partial group, padded with inactive copies of its first point.
            // Element loops rather than `copy_from_slice`: a `memcpy` call of a varying
            // small length mispredicts inside.
            let (mut p, mut u, mut a) = ([p_rest[0]; N], [u_rest[0]; N], [false; N]);
            for (j, ((&pr, &ur), &ar)) in p_rest.iter().zip(u_rest).zip(a_rest).enumerate() {
                (p[j], u[j], a[j]) = (pr, ur, ar);
            }
            let (mut wi, mut distance, mut radiance) = ([Vec3::Z; N], [0.0; N], [Rgb::BLACK; N]);
            let (mut pdf, mut delta) = ([0.0; N], [false; N]);
            let o = Out8 {
                wi: &mut wi,
                distance: &mut distance,
                radiance: &mut radiance,
                pdf: &mut pdf,
                delta: &mut delta,
            };
            eight(set, l8, cdf, geometry, &p, &u, &a, o);
            let rest = wi_rest
                .iter_mut()
                .zip(distance_rest)
                .zip(radiance_rest)
                .zip(pdf_rest)
                .zip(delta_rest);
            for (j, ((((w, d), r), p), de)) in rest.enumerate() {
                (*w, *d, *r, *p, *de) = (wi[j], distance[j], radiance[j], pdf[j], delta[j]);
            }
        }
    }

    /// Eight rows of the output columns.
    struct Out8<'a> {
        wi: &'a mut [Vec3; N],
        distance: &'a mut [f32; N],
        radiance: &'a mut [Rgb; N],
        pdf: &'a mut [f32; N],
        delta: &'a mut [bool; N],
    }

    /// Stores the components `x`, `y`, `z` of eight vectors as eight `repr(C)` triples
    /// (`Vec3`, `Rgb`) at `dst`: output vector `V`, lane `i` is float `8 V + i`, component
    /// `(8 V + i) % 3` of triple `(8 V + i) / 3`.
    ///
    /// # Safety
    /// `dst` must be 96 writable bytes.
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn store3(x: __m256, y: __m256, z: __m256, dst: *mut f32) {
        let part = |triple: __m256i| {
            (
                _mm256_permutevar8x32_ps(x, triple),
                _mm256_permutevar8x32_ps(y, triple),
                _mm256_permutevar8x32_ps(z, triple),
            )
        };
        let (x0, y0, z0) = part(_mm256_setr_epi32(0, 0, 0, 1, 1, 1, 2, 2));
        let v0 = _mm256_blend_ps::<0b0010_0100>(_mm256_blend_ps::<0b1001_0010>(x0, y0), z0);
        let (x1, y1, z1) = part(_mm256_setr_epi32(2, 3, 3, 3, 4, 4, 4, 5));
        let v1 = _mm256_blend_ps::<0b0100_1001>(_mm256_blend_ps::<0b0010_0100>(x1, y1), z1);
        let (x2, y2, z2) = part(_mm256_setr_epi32(5, 5, 6, 6, 6, 7, 7, 7));
        let v2 = _mm256_blend_ps::<0b1001_0010>(_mm256_blend_ps::<0b0100_1001>(x2, y2), z2);
        // SAFETY: the caller's 96 bytes.
        unsafe {
            _mm256_storeu_ps(dst, v0);
            _mm256_storeu_ps(dst.add(8), v1);
            _mm256_storeu_ps(dst.add(16), v2);
        }
    }

    /// All lanes `x`.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn splat(x: f32) -> __m256 {
        _mm256_set1_ps(x)
    }

    /// Component `K` (0 x, 1 y, 2 z) of eight `Vec3` (`repr(C)`, three f32 each) held in
    /// three vectors: lane `i` is float number `3 i + K`, in vector `(3 i + K) / 8` at
    /// position `(3 i + K) % 8`.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn component<const K: i32>(v: [__m256; 3]) -> __m256 {
        let idx = _mm256_setr_epi32(
            K,
            (3 + K) % 8,
            (6 + K) % 8,
            (9 + K) % 8,
            (12 + K) % 8,
            (15 + K) % 8,
            (18 + K) % 8,
            (21 + K) % 8,
        );
        let p = v.map(|v| _mm256_permutevar8x32_ps(v, idx));
        match K {
            0 => _mm256_blend_ps::<0b1100_0000>(_mm256_blend_ps::<0b0011_1000>(p[0], p[1]), p[2]),
            1 => _mm256_blend_ps::<0b1110_0000>(_mm256_blend_ps::<0b0001_1000>(p[0], p[1]), p[2]),
            _ => _mm256_blend_ps::<0b1110_0000>(_mm256_blend_ps::<0b0001_1100>(p[0], p[1]), p[2]),
        }
    }

    /// Eight points of `sample_column`.
    #[target_feature(enable = "avx2")]
    #[inline]
    #[allow(
        clippy::too_many_arguments,
        reason = "the set, its columns and the output"
    )]
    fn eight(
        set: &LightSet,
        l8: &Lights8,
        cdf: &[f32],
        geometry: &SceneGeometry,
        p: &[Vec3; N],
        u: &[[f32; 4]; N],
        active: &[bool; N],
        out: Out8<'_>,
    ) {
        // SAFETY: eight `Vec3` are 96 readable bytes, eight `[f32; 4]` 128.
        let (pv, uv) = unsafe {
            let pf = p.as_ptr().cast::<f32>();
            let uf = u.as_ptr().cast::<f32>();
            (
                [
                    _mm256_loadu_ps(pf),
                    _mm256_loadu_ps(pf.add(8)),
                    _mm256_loadu_ps(pf.add(16)),
                ],
                [
                    _mm256_loadu_ps(uf),
                    _mm256_loadu_ps(uf.add(8)),
                    _mm256_loadu_ps(uf.add(16)),
                    _mm256_loadu_ps(uf.add(24)),
                ],
            )
        };
        let (px, py, pz) = (component::<0>(pv), component::<1>(pv), component::<2>(pv));
        // Transpose the rows (two per vector) into columns 0, 1, 2, whose lanes come out in
        // point order 0 2 4 6 1 3 5 7; one permute puts them back in order.
        let (t0, t1) = (
            _mm256_unpacklo_ps(uv[0], uv[1]),
            _mm256_unpackhi_ps(uv[0], uv[1]),
        );
        let (t2, t3) = (
            _mm256_unpacklo_ps(uv[2], uv[3]),
            _mm256_unpackhi_ps(uv[2], uv[3]),
        );
        let order = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
        let column = |v: __m256d| _mm256_permutevar8x32_ps(_mm256_castpd_ps(v), order);
        let (t0, t1, t2, t3) = (
            _mm256_castps_pd(t0),
            _mm256_castps_pd(t1),
            _mm256_castps_pd(t2),
            _mm256_castps_pd(t3),
        );
        let ux = column(_mm256_unpacklo_pd(t0, t2));
        let uy = column(_mm256_unpackhi_pd(t0, t2));
        let us = column(_mm256_unpacklo_pd(t1, t3));

        // Light selection as `LightSet::select_four`: clamp into [0, 1) (NaN and negatives
        // to 0), then count the CDF entries <= u (a true compare is -1).
        let zero = _mm256_setzero_ps();
        let us = _mm256_blendv_ps(
            zero,
            _mm256_min_ps(us, splat(ONE_MINUS_EPSILON)),
            _mm256_cmp_ps::<_CMP_GE_OQ>(us, zero),
        );
        let mut index = _mm256_setzero_si256();
        for &c in cdf {
            let le = _mm256_cmp_ps::<_CMP_LE_OQ>(splat(c), us);
            index = _mm256_sub_epi32(index, _mm256_castps_si256(le));
        }
        // SAFETY: every row of `l8` is 32 readable bytes.
        let attr = |a: usize| unsafe {
            _mm256_permutevar8x32_ps(_mm256_loadu_ps(l8.attr[a].as_ptr()), index)
        };
        // SAFETY: as above.
        let triangle = unsafe {
            _mm256_permutevar8x32_epi32(_mm256_loadu_si256(l8.triangle.as_ptr().cast()), index)
        };
        let triangle = _mm256_movemask_ps(_mm256_castsi256_ps(triangle)) as u32;

        // `sample_triangles_four`, eight lanes.
        let below = _mm256_cmp_ps::<_CMP_LT_OQ>(ux, uy);
        let (hx, hy) = (_mm256_mul_ps(ux, splat(0.5)), _mm256_mul_ps(uy, splat(0.5)));
        let b0 = _mm256_blendv_ps(_mm256_sub_ps(ux, hy), hx, below);
        let b1 = _mm256_blendv_ps(hy, _mm256_sub_ps(uy, hx), below);
        let b2 = _mm256_sub_ps(_mm256_sub_ps(splat(1.0), b0), b1);
        let q = |c: usize| {
            _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(attr(c), b0), _mm256_mul_ps(attr(3 + c), b1)),
                _mm256_mul_ps(attr(6 + c), b2),
            )
        };
        let dx = _mm256_sub_ps(q(0), px);
        let dy = _mm256_sub_ps(q(1), py);
        let dz = _mm256_sub_ps(q(2), pz);
        let dist2 = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
            _mm256_mul_ps(dz, dz),
        );
        let mut ok = _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GT_OQ>(dist2, zero),
            _mm256_cmp_ps::<_CMP_LT_OQ>(dist2, splat(f32::INFINITY)),
        );
        let dist = _mm256_sqrt_ps(dist2);
        let inv = _mm256_div_ps(splat(1.0), dist);
        let (wx, wy, wz) = (
            _mm256_mul_ps(dx, inv),
            _mm256_mul_ps(dy, inv),
            _mm256_mul_ps(dz, inv),
        );
        let cos_light = _mm256_xor_ps(
            _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(attr(9), wx), _mm256_mul_ps(attr(10), wy)),
                _mm256_mul_ps(attr(11), wz),
            ),
            splat(-0.0),
        );
        ok = _mm256_and_ps(ok, _mm256_cmp_ps::<_CMP_GT_OQ>(cos_light, zero));
        let pdf = _mm256_div_ps(_mm256_mul_ps(attr(12), dist2), cos_light);
        ok = _mm256_and_ps(
            ok,
            _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GT_OQ>(pdf, zero),
                _mm256_cmp_ps::<_CMP_LT_OQ>(pdf, splat(f32::INFINITY)),
            ),
        );
        // Active lanes: the eight bools widened to 32-bit lanes, compared with 0.
        // SAFETY: eight bools are 8 readable bytes.
        let act = unsafe { _mm_loadl_epi64(active.as_ptr().cast()) };
        let act = _mm256_cmpeq_epi32(_mm256_cvtepu8_epi32(act), _mm256_setzero_si256());
        let ok = _mm256_andnot_ps(_mm256_castsi256_ps(act), ok);
        // Rows without a sample: pdf 0 and wi +z.
        let wx = _mm256_and_ps(wx, ok);
        let wy = _mm256_and_ps(wy, ok);
        let wz = _mm256_blendv_ps(splat(1.0), wz, ok);
        let pdf = _mm256_and_ps(pdf, ok);
        // SAFETY: each output row block is eight `Vec3`/`Rgb` (96 bytes) or eight f32 (32);
        // the delta block is eight bools (8 bytes), written as one u64 of zeros (false).
        unsafe {
            store3(wx, wy, wz, out.wi.as_mut_ptr().cast());
            store3(
                attr(13),
                attr(14),
                attr(15),
                out.radiance.as_mut_ptr().cast(),
            );
            _mm256_storeu_ps(out.distance.as_mut_ptr(), dist);
            _mm256_storeu_ps(out.pdf.as_mut_ptr(), pdf);
        }
        *out.delta = [false; N];
        if triangle != 0xff {
            other_lanes(set, geometry, triangle, p, u, active, out);
        }
    }

    /// The lanes of [`eight`] whose light is not a triangle light (bit clear in
    /// `triangle`), through `LightSet::sample`.
    #[cold]
    #[inline(never)]
    fn other_lanes(
        set: &LightSet,
        geometry: &SceneGeometry,
        triangle: u32,
        p: &[Vec3; N],
        u: &[[f32; 4]; N],
        active: &[bool; N],
        out: Out8<'_>,
    ) {
        let mut cols = LightSampleColumns {
            wi: out.wi,
            distance: out.distance,
            radiance: out.radiance,
            pdf: out.pdf,
            delta: out.delta,
        };
        for j in (0..N).filter(|&j| triangle & (1 << j) == 0) {
            let s = active[j]
                .then(|| set.sample(geometry, p[j], u[j][2], Vec2::new(u[j][0], u[j][1])))
                .flatten();
            cols.set(j, s);
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
        set: &LightSet,
        geometry: &SceneGeometry,
        p: &[Vec3],
        u: &[[f32; 4]],
        active: &[bool],
    ) -> Vec<Option<LightSample>> {
        let n = p.len();
        let (mut wi, mut distance, mut radiance) =
            (vec![Vec3::NAN; n], vec![-1.0; n], vec![Rgb::splat(-1.0); n]);
        let (mut pdf, mut delta) = (vec![-1.0; n], vec![true; n]);
        let mut cols = LightSampleColumns {
            wi: &mut wi,
            distance: &mut distance,
            radiance: &mut radiance,
            pdf: &mut pdf,
            delta: &mut delta,
        };
        set.sample_column(geometry, p, u, active, &mut cols);
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
            let out = sample_column_rows(set, geometry, &p, &u, &active);
            for i in 0..len {
                let want = active[i]
                    .then(|| set.sample(geometry, p[i], u[i][2], Vec2::new(u[i][0], u[i][1])))
                    .flatten();
                let bits = |s: Option<LightSample>| {
                    s.map(|s| {
                        (
                            s.wi.to_array().map(f32::to_bits),
                            s.distance.to_bits(),
                            s.radiance.to_array().map(f32::to_bits),
                            s.pdf.to_bits(),
                            s.delta,
                        )
                    })
                };
                assert_eq!(bits(out[i]), bits(want), "len {len}, point {i}");
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
        let out = sample_column_rows(&set, &geometry, &p, &u, &vec![true; n]);
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
