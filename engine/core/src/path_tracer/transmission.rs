//! Transmission stage: every queued shadow ray walks to its light sample through the
//! surfaces that let shadows pass and the volumes it crosses (`crate::transmission`); the
//! surviving contributions, and what volumes emit along the way, reach their paths.

use super::non_finite_case;
use super::queues::ShadowRayQueue;
use crate::integrator::PathBatch;
use crate::scene::CompiledScene;
use crate::stats::{Stage, System, SystemStats};
use crate::transmission::block_occluded;
use bumpalo::Bump;
use risotto_components::Rays;

/// Traces the shadow rays of `shadow`, adds their contributions to the paths and empties the
/// queue (its rows become storage for the next shade stage). `incoming` are the bounce's
/// rays (the hit queue's): non-finite cases take their path's depth from them.
pub(super) fn shadow_rays(
    scene: &CompiledScene,
    volume: crate::plugin::PluginTechniques,
    shadow: &mut ShadowRayQueue,
    incoming: &Rays,
    batch: &mut PathBatch,
    stats: &mut SystemStats,
    arena: &Bump,
) {
    let n = shadow.rays.len();
    if n == 0 {
        return;
    }
    let start = std::time::Instant::now();
    if crate::transmission::shadows_only_blocked(scene) {
        // Each contribution arrives whole or is blocked: attenuated in place, without the
        // copy the general walk below keeps for NaN provenance (blocking makes nothing
        // non-finite).
        let rays = &mut shadow.rays;
        let geometry = (&rays.origin[..], &rays.direction[..], &rays.tmax[..]);
        let contribution = &mut rays.contribution[..];
        block_occluded(scene, geometry, contribution, stats, arena);
        for (&path, &c) in rays.path.iter().zip(&rays.contribution) {
            batch.paths.radiance[path as usize] += c;
        }
    } else {
        walk_shadow_rays(scene, volume, shadow, incoming, batch, stats, arena);
    }
    stats.record(System::Transmission, n, start.elapsed().as_secs_f64());
    // Keep the dead rows as storage for the next shade stage's shadow rays (until then they
    // hold the contributions after transmission, which the path-trace recorder reads).
    std::mem::swap(&mut shadow.rays, &mut shadow.spare);
    shadow.rays.clear();
}

/// The transmission stage in scenes where shadow rays may pass surfaces or cross volumes:
/// the walk attenuates a copy of the contributions (`shadow.contribution`), which then
/// replaces them in `shadow.rays`.
fn walk_shadow_rays(
    scene: &CompiledScene,
    volume: crate::plugin::PluginTechniques,
    shadow: &mut ShadowRayQueue,
    incoming: &Rays,
    batch: &mut PathBatch,
    stats: &mut SystemStats,
    arena: &Bump,
) {
    shadow.contribution.clear();
    shadow
        .contribution
        .extend_from_slice(&shadow.rays.contribution);
    // Built-in media add their emission along path rays (`trace.rs`), not here.
    crate::transmission::trace_shadow_rays_with(
        scene,
        &shadow.rays,
        batch,
        volume,
        &mut shadow.contribution,
        stats,
        arena,
        crate::transmission::ShadowEmission::NotAlongPaths,
        &mut shadow.walk,
    );
    // NaN provenance: contributions the walk made non-finite (those non-finite before it
    // came from upstream and were counted there).
    let mut walk = 0;
    let before = &shadow.rays.contribution;
    let rows = shadow
        .rays
        .path
        .iter()
        .zip(&shadow.contribution)
        .zip(before);
    for ((&path, &c), b) in rows {
        batch.paths.radiance[path as usize] += c;
        walk += (b.is_finite() & !c.is_finite()) as usize;
    }
    stats.non_finite(Stage::Transmission, walk);
    if walk > 0 {
        // The depth of each path's vertex this bounce: that of the last ray of the path that
        // arrived (the one shaded, after any pass-throughs).
        let mut depth = vec![0u16; batch.paths.len()];
        for (&path, &d) in incoming.path.iter().zip(&incoming.depth) {
            depth[path as usize] = d;
        }
        let rows = shadow
            .rays
            .path
            .iter()
            .zip(&shadow.contribution)
            .zip(before);
        for ((&path, c), b) in rows {
            if b.is_finite() & !c.is_finite() {
                let d = depth[path as usize];
                non_finite_case(stats, &batch.paths, path, d, Stage::Transmission, None);
            }
        }
    }
    // The same length: the table stays consistent.
    std::mem::swap(&mut shadow.contribution, &mut shadow.rays.contribution);
}
