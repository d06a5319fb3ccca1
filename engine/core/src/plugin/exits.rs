//! The exits of transport a volume integrator runs itself (a random walk, diffusion): the
//! walkers that reached a surface, and their answer to the global integrator as ordinary
//! hits, weighted by the walk, with the walk's scattering events reported so that they count
//! as bounces ([`ShadeGroups::walked`]). A service of the contract: every integrator that
//! walks its own rays answers them this way.

use super::IntegratorContext;
use crate::shade_groups::ShadeGroups;
use glam::Vec3;
use risotto_components::{Rays, Rgb};

/// Walkers that reached a surface (or left the scene): each one's ray id in the bundle,
/// last segment, weight and scattering events (0: the ray passed unscattered).
#[derive(Clone, Debug, Default)]
pub struct Exits {
    /// The walker's ray: an index into the bundle the integrator answers.
    pub ray: Vec<u32>,
    /// Start of the walk's last segment (the last event, or the ray's origin).
    pub origin: Vec<Vec3>,
    /// Direction of the last segment.
    pub direction: Vec<Vec3>,
    /// Where the last segment starts along `direction` (0 from an event).
    pub tmin: Vec<f32>,
    /// Where it ends at the most.
    pub tmax: Vec<f32>,
    /// The walk's weight (everything inside the volume; not the ray's throughput).
    pub weight: Vec<Rgb>,
    /// Scattering events of the walk (0: the ray passed unscattered).
    pub events: Vec<u32>,
}

/// Traces the exits' last segments again (one ray per walk, against hundreds traced by the
/// walk itself) and appends their hits and misses to `out` as the answers of the rays of
/// `rays` they belong to, the walk's weight multiplied into their `transmission`.
pub fn answer_exits(
    rays: &Rays,
    exits: &Exits,
    ictx: &mut dyn IntegratorContext,
    out: &mut ShadeGroups,
) {
    if exits.ray.is_empty() {
        return;
    }
    let mut last = Rays::with_capacity(exits.ray.len());
    last.extend_gather(rays, &exits.ray);
    last.origin.copy_from_slice(&exits.origin);
    last.direction.copy_from_slice(&exits.direction);
    last.tmin.copy_from_slice(&exits.tmin);
    last.tmax.copy_from_slice(&exits.tmax);
    let (p0, m0) = (out.points.len(), out.misses.len());
    ictx.trace(&last);
    ictx.shade_traced(&last, None, out);
    for k in p0..out.points.len() {
        let e = out.points.ray_id[k] as usize;
        out.points.ray_id[k] = exits.ray[e];
        out.points.transmission[k] *= exits.weight[e];
    }
    for k in m0..out.misses.len() {
        let e = out.misses[k] as usize;
        out.misses[k] = exits.ray[e];
        out.miss_transmission[k] *= exits.weight[e];
    }
    for (e, &events) in exits.events.iter().enumerate() {
        if events > 0 {
            let wk = &mut out.walked;
            wk.ray.push(exits.ray[e]);
            wk.origin.push(exits.origin[e]);
            wk.direction.push(exits.direction[e]);
            wk.tmin.push(exits.tmin[e]);
            wk.tmax.push(exits.tmax[e]);
            wk.vertices.push(events);
        }
    }
}
