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
        let pmf_over_area: Vec<f32> = lights
            .iter()
            .zip(&pmf)
            .map(|(l, &pmf)| match l {
                Light::Area { prim, .. } => pmf / geometry.prim_area(*prim),
                _ => 0.0,
            })
            .collect();
        let triangle_lights = lights
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
        LightSet {
            lights,
            selection,
            light_of_prim,
            environment,
            pmf,
            pmf_over_area,
            triangle_lights,
            selection_cdf,
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

impl LightSet {
    /// [`Self::sample`] for a column of points: `out[i]` is the light sample from `p[i]`
    /// with position sample `(u[i][0], u[i][1])` and selection sample `u[i][2]` (a vertex's
    /// four-dimension set; `u[i][3]` is not used) where `active[i]`, `None` elsewhere.
    /// `geometry` must be the geometry the set was built with.
    ///
    /// Bit for bit `sample`'s results (tested). Groups of four points whose selected lights
    /// are all triangle area lights (the common case) are evaluated in SSE lanes: the point
    /// on the triangle, direction, distance and solid-angle pdf of four samples share one
    /// square root and two divisions. Other groups go through `sample` point by point.
    ///
    /// # Panics
    /// When the columns differ in length.
    pub fn sample_column(
        &self,
        geometry: &SceneGeometry,
        p: &[Vec3],
        u: &[[f32; 4]],
        active: &[bool],
        out: &mut [Option<LightSample>],
    ) {
        let len = p.len();
        assert!(
            u.len() == len && active.len() == len && out.len() == len,
            "sample_column: column lengths"
        );
        let Some(selection) = self.selection.as_ref() else {
            out.fill(None);
            return;
        };
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx2") {
            // SAFETY: this CPU has AVX2 (checked on the line above).
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
        out: &mut [Option<LightSample>],
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
        out: &mut [Option<LightSample>],
    ) {
        let (p4, p_rest) = p.as_chunks::<4>();
        let (u4, u_rest) = u.as_chunks::<4>();
        let (a4, a_rest) = active.as_chunks::<4>();
        let (out4, out_rest) = out.as_chunks_mut::<4>();
        for (((p, u), a), out) in p4.iter().zip(u4).zip(a4).zip(out4) {
            self.sample_four(geometry, selection, p, u, a, out);
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
            out_rest.copy_from_slice(&o[..r]);
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
            let mut out = vec![None; len];
            set.sample_column(geometry, &p, &u, &active, &mut out);
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
        let mut out = vec![None; n];
        set.sample_column(&geometry, &p, &u, &vec![true; n], &mut out);
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
