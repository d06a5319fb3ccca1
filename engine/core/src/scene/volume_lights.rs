//! The scene's glue around volume emitters: which shapes' interiors offer one, and their
//! lights ([`crate::plugin::volume_light`] has the contract's part and the design).

use super::CompiledScene;
use crate::plugin::{BxdfFactory, EmitterSupport, InstanceHints, VolumeEmitter};
use glam::Vec3;
use risotto_systems::geometry::SceneGeometry;
use risotto_systems::lights::Light;
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
pub(super) fn collect(scene: &CompiledScene) -> Vec<(u32, Arc<VolumeEmitter>)> {
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
pub(super) fn lights(emitters: &[(u32, Arc<VolumeEmitter>)]) -> impl Iterator<Item = Light> + '_ {
    emitters
        .iter()
        .map(|(_, e)| Light::Volume { emitter: e.clone() })
}
