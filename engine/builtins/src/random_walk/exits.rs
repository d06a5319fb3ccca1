//! The exits of transport run inside a volume integrator (the random walk, diffusion): the
//! walkers that reached a surface, and their answer to the global integrator as ordinary
//! hits.

use glam::Vec3;
use risotto_components::{Rays, Rgb};
use risotto_engine::context::IntegratorContext;
use risotto_engine::shade_groups::ShadeGroups;

/// Walkers that reached a surface (or left the scene): each one's ray id in the bundle,
/// last segment, weight and scattering events (0: the ray passed unscattered).
#[derive(Default)]
pub(crate) struct Exits {
    pub(crate) ray: Vec<u32>,
    pub(crate) origin: Vec<Vec3>,
    pub(crate) direction: Vec<Vec3>,
    pub(crate) tmin: Vec<f32>,
    pub(crate) tmax: Vec<f32>,
    pub(crate) weight: Vec<Rgb>,
    pub(crate) events: Vec<u32>,
}

/// Traces the exits' last segments again (one ray per walk, against hundreds traced by the
/// walk itself) and appends their hits and misses to `out` as the rays' answers.
pub(crate) fn answer_exits(
    rays: &Rays,
    exits: &Exits,
    ictx: &mut IntegratorContext<'_>,
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
