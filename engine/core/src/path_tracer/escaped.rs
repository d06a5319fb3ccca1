//! Escaped stage: rays that left the scene take the environment's radiance (MIS-weighted
//! against light sampling of the environment).

use super::queues::{EscapedRayQueue, HitQueue};
use super::{non_finite_case, PathTracer};
use crate::integrator::PathBatch;
use crate::scene::CompiledScene;
use crate::stats::{Stage, SystemStats, Termination};

/// Adds the environment radiance seen by every escaped ray to its path, records the
/// environment as the first-hit albedo of camera rays that saw nothing, and empties `escaped`.
pub(super) fn environment(
    tracer: &PathTracer,
    scene: &CompiledScene,
    escaped: &mut EscapedRayQueue,
    hits: &HitQueue,
    batch: &mut PathBatch,
    stats: &mut SystemStats,
) {
    let incoming = &hits.incoming;
    let paths = &mut batch.paths;
    let mut bad = 0;
    for (&r, &tr) in escaped.ray.iter().zip(&escaped.transmission) {
        let r = r as usize;
        let path = incoming.path[r] as usize;
        let d = incoming.direction[r];
        let le = scene.lights.environment_radiance(d);
        if !le.is_black() && tracer.emission_counts(scene, incoming, r) {
            let w = tracer.emitter_mis(incoming, r, || scene.mis_lights.environment_pdf(d));
            let c = incoming.throughput[r] * tr * le * w;
            // Counted here only when made here (a non-finite throughput or transmission
            // was counted where it was produced).
            let made_here = !c.is_finite() & incoming.throughput[r].is_finite() & tr.is_finite();
            if made_here {
                bad += 1;
                let (p, depth) = (incoming.path[r], incoming.depth[r]);
                non_finite_case(stats, paths, p, depth, Stage::Environment, None);
            }
            paths.radiance[path] += c;
        }
        if incoming.depth[r] == 0 && paths.depth[path].is_infinite() {
            paths.albedo[path] = le;
        }
        if scene.features.volumes && !incoming.volume_stack[r].is_empty() {
            // A ray that leaves the scene while its stack says it is inside a volume: some
            // boundary it crossed was not closed (the validator's warning names the shape).
            if let Some(e) = incoming.volume_stack[r].innermost() {
                stats.escaped_inside(e.shape);
            }
        }
    }
    stats.non_finite(Stage::Environment, bad);
    stats.terminate(Termination::Escaped, escaped.ray.len());
    escaped.ray.clear();
    escaped.transmission.clear();
}
