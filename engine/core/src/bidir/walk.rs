//! What camera and light subpaths share: tracing one bounce through the path tracer's own
//! trace and pass-through stages (volumes handed to their integrators without a lighting
//! delegate, so media return their scattering points), and the shadow rays of connections.

use super::mis::SubpathMis;
use super::volume_emission::CameraEmission;
use super::StrategyAlone;
use crate::integrator::{LightingTechnique, PathBatch};
use crate::path_tracer::queues::Queues;
use crate::path_tracer::{pass_through_boundaries, trace_nearest_hits, PathTracer, TraceRole};
use crate::plugin::{EmissionStrategies, PatternCounters, PluginTechniques};
use crate::scene::CompiledScene;
use crate::stats::SystemStats;
use bumpalo::Bump;
use glam::Vec3;
use risotto_components::{Rays, Rgb, ShadingPoints, ShadowRayRow, ShadowRays, VolumeStack};
use risotto_systems::ray::{shadow_ray, spawn_origin};

/// The path tracer's stages configured as a bidirectional integrator uses them: no
/// lighting delegate for volume integrators (`BxdfOnly` offers none), the render's plug-in
/// technique choices; the camera subpaths gather the directly visible emission themselves
/// (no extra camera points).
pub(super) fn stages(techniques: PluginTechniques) -> PathTracer {
    PathTracer {
        technique: LightingTechnique::BxdfOnly,
        techniques,
        visible_emitters: crate::path_tracer::visible_emitters::VisibleEmitters::Paths,
    }
}

/// Traces the rays of `q.rays` to their next scattering vertices (in `q.hits`), past
/// index-matched boundaries, false boundaries and surfaces their opacity lets them pass.
/// The rays that left the scene go to `escaped` (rows of `q.hits.incoming`, with the
/// transmission of their last segment). `light_path`: the rays are a light subpath's (the
/// seed's `isLightPath`, [`VolumeServices::light_path`](crate::plugin::VolumeServices)); `alone`:
/// the strategy alone, if any ([`StrategyAlone`]).
#[allow(clippy::too_many_arguments, reason = "the stage's inputs, named")]
pub(super) fn trace_bounce(
    stages: &PathTracer,
    scene: &CompiledScene,
    batch: &mut PathBatch,
    q: &mut Queues,
    escaped: &mut Vec<(u32, Rgb)>,
    stats: &mut SystemStats,
    arena: &Bump,
    counters: &PatternCounters,
    light_path: bool,
    sent_depth: &mut Vec<u16>,
    mis: &mut [SubpathMis],
    alone: Option<StrategyAlone>,
) {
    q.hits.recycle_into(&mut q.next);
    escaped.clear();
    // Each path's depth as it leaves, to find the rays a volume integrator walked.
    sent_depth.clear();
    sent_depth.resize(batch.paths.len(), 0);
    for (&path, &depth) in q.rays.rays.path.iter().zip(&q.rays.rays.depth) {
        sent_depth[path as usize] = depth;
    }
    // Camera rays weigh the emission of media that are lights (`volume_emission.rs`); light
    // subpaths gather none.
    let emission = CameraEmission {
        mis,
        sent_depth,
        alone,
    };
    let role = TraceRole {
        light_path,
        emission: (!light_path && scene.features.emissive_volume_lights).then(|| {
            (
                scene.bidirectional_lights(),
                &emission as &dyn EmissionStrategies,
            )
        }),
    };
    while !q.rays.rays.is_empty() {
        trace_nearest_hits(stages, scene, batch, q, stats, arena, counters, role);
        let e = &mut q.escaped;
        escaped.extend(e.ray.iter().copied().zip(e.transmission.iter().copied()));
        e.ray.clear();
        e.transmission.clear();
        if scene.features.transmissive || scene.features.opacity {
            pass_through_boundaries(stages, scene, q, batch, stats, arena, counters);
        }
    }
    stats.walked_subpath_rays += forget_walks(&q.hits.incoming, sent_depth, mis);
}

/// A volume integrator that walks many scattering events in one call (a random walk in a
/// dense medium or under a surface) hands back only the walk's exit: its events are not
/// vertices any strategy can connect or merge at, and their pdfs are unknown. Such a walk is
/// what a chain of Dirac vertices is to the weights (strategies that would end inside it
/// cannot make the path, and its pdfs cancel between the two directions, see
/// [`SubpathMis::scatter`]), so a walked path's `dVCM` is set to 0, as a Dirac vertex sets
/// it; `dVC` is unchanged (cosines in a medium are 1). Walked rays are those whose depth
/// grew in the trace (`WalkedRays::apply` adds the walk's events).
/// Returns the number of walked rays.
fn forget_walks(incoming: &Rays, sent_depth: &[u16], mis: &mut [SubpathMis]) -> u64 {
    let mut walked = 0;
    for (&path, &depth) in incoming.path.iter().zip(&incoming.depth) {
        let path = path as usize;
        if depth > sent_depth[path] {
            mis[path].vcm = 0.0;
            walked += 1;
        }
    }
    walked
}

/// The volumes a straight ray leaving row `i` of `pts` in direction `w` travels in: the
/// arriving ray's `stack`, crossed into the shape's interior (or out of it) when `w` leaves
/// a surface on the side opposite its viewer.
pub(super) fn stack_toward(
    scene: &CompiledScene,
    stack: &VolumeStack,
    pts: &ShadingPoints,
    i: usize,
    w: Vec3,
) -> VolumeStack {
    let mut s = stack.clone();
    let shape = pts.shape[i];
    if shape != u32::MAX && scene.tracks_interior(shape) {
        let ng = pts.ng[i];
        if (w.dot(ng) > 0.0) != (pts.vn[i].dot(ng) > 0.0) {
            let _ = s.cross(scene.volume_entry(shape), pts.front_face[i]);
        }
    }
    s
}

/// Queues a shadow ray from row `i` of `pts` to the point `distance` away along unit `w`
/// (stopping `margin` short of it), carrying `contribution` for `path`. It carries no
/// weight for volume emission: a connection is not a light sample of emissive media
/// (camera subpaths gather what media emit).
#[allow(clippy::too_many_arguments, reason = "a shadow ray's fields, named")]
pub(super) fn push_connection(
    shadow: &mut ShadowRays,
    pts: &ShadingPoints,
    i: usize,
    w: Vec3,
    distance: f32,
    margin: f32,
    contribution: Rgb,
    path: u32,
    dimension: u32,
    stack: VolumeStack,
) {
    let on_surface = pts.shape[i] != u32::MAX;
    let p = pts.p[i];
    let origin = spawn_origin(p, pts.ng[i], pts.p_offset[i], w, on_surface);
    let (direction, tmax) = shadow_ray(p, origin, w, distance, margin);
    shadow.push(ShadowRayRow {
        origin,
        direction,
        tmax,
        contribution,
        weight: Rgb::BLACK,
        path,
        dimension,
        volume_stack: stack,
    });
}

/// How far short of a surface vertex at row `i` of `pts` a connection arriving along `w`
/// stops: its error offset along the ray (clamped for grazing directions); 0 in a medium.
pub(super) fn arrival_margin(pts: &ShadingPoints, i: usize, w: Vec3) -> f32 {
    if pts.shape[i] == u32::MAX {
        0.0
    } else {
        2.0 * pts.p_offset[i] / pts.ng[i].dot(w).abs().max(1e-3)
    }
}
