//! The scene's glue around volume emitters: which shapes' interiors offer one, their lights,
//! the light sets they join (the path tracer's MIS set and the bidirectional integrators'),
//! and the MIS data a volume integrator gets for its own ([`crate::plugin::volume_light`]
//! has the contract's part and the design).

use super::CompiledScene;
use crate::plugin::{BxdfFactory, EmitterSupport, InstanceHints, VolumeEmitter};
use glam::Vec3;
use risotto_systems::geometry::SceneGeometry;
use risotto_systems::lights::{Light, LightSet};
use std::sync::Arc;

/// Where the medium of `shape` emits, when the shape is one a volume emitter can cover:
/// a sphere (its ball), or a triangle mesh that is its own bounding box (every triangle on
/// a face of the box, their areas summing to the box's surface). `None` for other shapes.
fn support(
    geometry: &SceneGeometry,
    prims: &[usize],
    (lo, hi): (Vec3, Vec3),
) -> Option<EmitterSupport> {
    let nt = geometry.num_triangles();
    if let [p] = prims {
        if *p >= nt {
            let s = geometry.sphere(*p - nt);
            return Some(EmitterSupport::Ball {
                center: s.center,
                radius: s.radius,
            });
        }
    }
    if prims.iter().any(|&p| p >= nt) {
        return None;
    }
    let e = hi - lo;
    let tol = 1e-5 * e.max_element();
    let mut area = 0.0f64;
    for &p in prims {
        let v = geometry.triangle(p);
        let on_face = (0..3).any(|a| {
            [lo[a], hi[a]]
                .iter()
                .any(|&f| v.iter().all(|q| (q[a] - f).abs() <= tol))
        });
        if !on_face {
            return None;
        }
        area += 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length() as f64;
    }
    let box_area = 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x) as f64;
    ((area - box_area).abs() <= 1e-4 * box_area).then_some(EmitterSupport::Box)
}

/// The emitters of `scene`'s emissive interiors, as `(shape, emitter)`.
fn collect(scene: &CompiledScene) -> Vec<(u32, Arc<VolumeEmitter>)> {
    let mut prims: Vec<Vec<usize>> = vec![Vec::new(); scene.shapes.len()];
    for (p, &s) in scene.prim_shape.iter().enumerate() {
        prims[s as usize].push(p);
    }
    let mut out = Vec::new();
    for (s, shape) in scene.shapes.iter().enumerate() {
        let material = &scene.materials[shape.material as usize];
        let factory: &dyn BxdfFactory = material.factory.as_ref();
        if !factory
            .instance_hints()
            .contains(InstanceHints::INTERIOR_EMITS)
        {
            continue;
        }
        // The emitters place their fields in the world box: a shape whose transform turns
        // or mirrors it (its medium's grid is in object space, which the world box is not)
        // offers none, and its emission is gathered by the interior's collision estimator
        // alone.
        if !scene.shape_space[s].is_axis_aligned() {
            continue;
        }
        let bounds = scene.shape_bounds[s];
        let Some(support) = support(&scene.geometry, &prims[s], bounds) else {
            continue;
        };
        if let Some(e) = factory.volume_emitter(bounds, support) {
            out.push((s as u32, Arc::new(e)));
        }
    }
    out
}

/// The light of each emitter.
fn emitter_lights(emitters: &[(u32, Arc<VolumeEmitter>)]) -> impl Iterator<Item = Light> + '_ {
    emitters
        .iter()
        .map(|(_, e)| Light::Volume { emitter: e.clone() })
}

impl CompiledScene {
    /// Adds the volume emitters of the emissive interiors to both light sets (after the
    /// shapes' bounds are known), and records each shape's light.
    pub(super) fn add_volume_lights(&mut self) {
        self.volume_light = vec![u32::MAX; self.shapes.len()];
        let emitters = collect(self);
        let emissive_interiors = self
            .shapes
            .iter()
            .filter(|s| {
                let factory = &self.materials[s.material as usize].factory;
                factory
                    .instance_hints()
                    .contains(crate::plugin::InstanceHints::INTERIOR_EMITS)
            })
            .count();
        self.features.emissive_media_without_lights = emissive_interiors > emitters.len();
        if emitters.is_empty() {
            return;
        }
        // Only the MIS set: light sampling alone (`lighting = nee`, the lighting delegate)
        // leaves emissive media to their collision estimator (crate::plugin::volume_light).
        let mut lights = self.mis_lights.lights().to_vec();
        for ((shape, _), light) in emitters.iter().zip(emitter_lights(&emitters)) {
            self.volume_light[*shape as usize] = lights.len() as u32;
            lights.push(light);
        }
        // Every light sampled, and the volume lights after them: a bidirectional
        // integrator's set (light subpaths start in emissive media too).
        let mut all = self.lights.lights().to_vec();
        all.extend_from_slice(&lights[all.len()..]);
        self.lights_with_volumes = Some(LightSet::new(all, &self.geometry, self.radius));
        self.mis_lights =
            LightSet::with_environment_sampling(lights, &self.geometry, self.radius, false);
        self.features.emissive_volume_lights = true;
    }

    /// The MIS data of the volume light of `shape`'s interior, if it has one and the render
    /// samples volume lights under MIS (`mis`: the path tracer's `lighting = mis`; neither
    /// light nor Bxdf sampling alone weighs path rays against volume light samples).
    pub fn volume_light_mis(
        &self,
        shape: u32,
        mis: bool,
    ) -> Option<crate::plugin::VolumeLightMis<'_>> {
        if !mis {
            return None;
        }
        self.volume_light_in(&self.mis_lights, shape)
    }

    /// The MIS data of the volume light of `shape`'s interior in the light set `set` (one
    /// of [`Self::mis_lights`] and [`Self::bidirectional_lights`], which list the volume
    /// lights at the same indices), with the path tracer's weights
    /// ([`crate::plugin::VolumeLightMis::strategies`] `None`).
    pub fn volume_light_in<'a>(
        &self,
        set: &'a LightSet,
        shape: u32,
    ) -> Option<crate::plugin::VolumeLightMis<'a>> {
        let index = *self.volume_light.get(shape as usize)?;
        match set.lights().get(index as usize)? {
            Light::Volume { emitter } => Some(crate::plugin::VolumeLightMis {
                emitter,
                selection: set.selection_pmf(index),
                strategies: None,
            }),
            _ => None,
        }
    }

    /// The lights a bidirectional integrator samples, for its light subpaths and its
    /// next-event estimation: every light of [`Self::lights`], then the volume lights of
    /// [`Self::mis_lights`] at the same indices as there.
    pub fn bidirectional_lights(&self) -> &LightSet {
        self.lights_with_volumes.as_ref().unwrap_or(&self.lights)
    }
}
