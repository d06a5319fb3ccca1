//! Building a [`LightSet`]: each light's power, the selection distribution by power (the
//! volume lights' share capped), the per-light pmfs, and the triangle lights' data the
//! column kernel reads.

use super::*;

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
                // Intensity times the falloff's integral over the sphere (not 4 pi).
                Light::Spot {
                    intensity,
                    falloff,
                    texture,
                    ..
                } => {
                    let tint = texture.as_ref().map_or(1.0, |t| t.mean.average());
                    falloff.solid_angle() * intensity.average() * tint
                }
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
