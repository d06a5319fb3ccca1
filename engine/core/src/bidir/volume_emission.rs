//! Emissive media as lights of a bidirectional integrator: the weight of what a camera
//! subpath's rays gather along the way through a light-sampled medium.
//!
//! A volume light ([`crate::plugin::volume_light`]) is a light like any other here: light
//! subpaths start inside it (a point by its cells, a uniform direction), camera vertices
//! sample it by next-event estimation and connect to the vertices of those subpaths, and the
//! camera subpaths' rays gather its emission through the medium's collision estimator. That
//! last strategy's weight is [`CameraEmission::weight`], through the contract's
//! [`EmissionStrategies`], so the built-in media (and a user's) weigh what they gather
//! without knowing which global integrator asks.
//!
//! The densities of the start point `x` of a path, in volume measure (the convention of
//! [`super::mis`], with the distance-sampling pdfs left out of every strategy):
//! - next-event estimation and the light subpath: `P(light) p_V(x)`, the light set's;
//! - the camera subpath's collision estimator: `pdf_w majorant(x) / s^2` for the solid-angle
//!   pdf `pdf_w` of the direction its last vertex sampled and `s` the distance from there,
//!   the path tracer's `p_U` ([`crate::plugin::volume_light`]): tentative collisions at the
//!   rate `majorant` per unit length.
//!
//! So where a surface light has the cosine `cos_at_light` between the area density and the
//! solid-angle density of reaching it, a point of a medium has `majorant(x)`: the camera
//! subpath arrives at `x` with `arrive(s, majorant(x))`, a light subpath leaves with
//! `cos_at_light = majorant(x)` in its weights (its throughput keeps 1), and next-event
//! estimation's sample already carries `p_V s^2 / majorant` as its solid-angle pdf
//! (`risotto_systems::volume_lights`). Georgiev et al.'s recursion (eq. 42 of the report)
//! then gives the weight of the collision estimator against every other strategy.
//!
//! Walks (a volume integrator that scatters many times in one call, `walk.rs`) are chains
//! of Dirac vertices to the weights. Emission gathered after a walk's events keeps weight 1
//! (the built-in random walk gathers it exactly), so no other strategy may make such a
//! path: a light subpath from a volume light whose first segment walked is dropped
//! (`light_walk.rs`). Both sides then agree: a path whose first light segment (camera side:
//! last segment) is straight is weighed by the recursion; one through a walk is the camera
//! subpath's alone.

use super::mis::{emitter_hit_weight, SubpathMis};
use super::{strategy_weight, StrategyAlone};
use crate::plugin::{EmissionStrategies, VolumeLightMis};
use glam::Vec3;
use risotto_components::Rays;

/// The weights of the collision estimator on a batch's camera subpaths during one trace.
pub(super) struct CameraEmission<'a> {
    /// Per path: the subpath's MIS sums after its last vertex scattered.
    pub mis: &'a [SubpathMis],
    /// Per path: the ray's depth as it was sent (a deeper ray walked).
    pub sent_depth: &'a [u16],
    /// The strategy alone, if any (then every ray is weighed, by it alone).
    pub alone: Option<StrategyAlone>,
}

impl EmissionStrategies for CameraEmission<'_> {
    fn weight(&self, light: &VolumeLightMis<'_>, rays: &Rays, r: usize, x: Vec3) -> f32 {
        if self.alone.is_some() {
            // The camera subpath's vertices and the emission's point: `(0, depth + 2)`.
            return strategy_weight(self.alone, 0, rays.depth[r] as u32 + 2, 1.0);
        }
        if !self.weighs(rays, r) {
            return 1.0;
        }
        let mut camera = self.mis[rays.path[r] as usize];
        let s = (x - rays.prev_p[r]).length();
        let majorant = light.emitter.mis_majorant(x);
        if !(s > 0.0 && majorant > 0.0 && majorant.is_finite()) {
            return 1.0;
        }
        camera.arrive(s, majorant, false);
        let direct = light.selection * light.emitter.pdf(x);
        // A volume light emits uniformly over the sphere (`LightSet::sample_emission`).
        let emission = direct * (0.25 * std::f32::consts::FRAC_1_PI);
        let w = emitter_hit_weight(&camera, direct, emission, false);
        if w.is_finite() {
            w
        } else {
            1.0
        }
    }

    /// Camera rays (what the camera sees directly, which no other strategy makes) and rays
    /// that walked before reaching the medium keep weight 1.
    fn weighs(&self, rays: &Rays, r: usize) -> bool {
        if self.alone.is_some() {
            return true;
        }
        let depth = rays.depth[r];
        depth != 0 && depth <= self.sent_depth[rays.path[r] as usize]
    }
}
