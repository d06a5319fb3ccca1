//! Pass-through stage: index-matched surfaces and false boundaries (a shape inside a volume
//! of higher priority) are never shaded, and a surface with opacity `a` is passed with
//! probability `1 - a` (`crate::opacity`). Their points leave the hit queue and their rays go
//! on along the same line as new rays to trace, without costing a bounce.

use super::queues::{HitQueue, RayQueue};
use super::{non_finite_case, PathTracer};
use crate::integrator::PathBatch;
use crate::opacity::{eval_opacity, passes, OPACITY_SEED_SALT};
use crate::plugin::{InstanceHints, PatternCounters};
use crate::scene::CompiledScene;
use crate::shade_groups::{ShadeGroup, ShadingMode};
use crate::stats::{Stage, SystemStats, Termination};
use bumpalo::Bump;
use risotto_components::StackEvent;
use risotto_systems::ray::skip_tmin;
use risotto_systems::sampler::sample_1d;

/// Moves the points of `hits` that lie on pass-through boundaries out of their groups and
/// queues their rays, continued past the boundary, in `rays`. Emission on such a surface still
/// reaches the path. Surfaces with opacity are tested only in scenes with the `opacity`
/// feature; their opacity is evaluated through a parameter cache in `arena` counting into
/// `counters`.
#[allow(
    clippy::too_many_arguments,
    reason = "the stage's inputs, each named; grouping them would hide which it reads"
)]
pub(super) fn boundaries(
    tracer: &PathTracer,
    scene: &CompiledScene,
    hits: &mut HitQueue,
    rays: &mut RayQueue,
    batch: &mut PathBatch,
    stats: &mut SystemStats,
    arena: &Bump,
    counters: &PatternCounters,
) {
    // Only this round's groups (the last ones) can hold pass-through points: earlier rounds'
    // groups were examined by earlier calls. Most rounds have none; the new rows are
    // compacted (in place) only when some point leaves them. `keep[i]`: point `p0 + i`
    // stays (points outside every group do not).
    let mut groups = std::mem::take(&mut hits.groups.groups);
    let g0 = hits.examined_groups.min(groups.len());
    let new_groups = groups.split_off(g0);
    hits.examined_groups = g0;
    let pts = &hits.groups.points;
    let p0 = new_groups.first().map_or(pts.len(), |g| g.range.start);
    let n = pts.len() - p0;
    let mut keep = std::mem::take(&mut hits.keep);
    keep.clear();
    keep.resize(n, false);
    let mut any_pass = false;
    for g in &new_groups {
        if g.mode != ShadingMode::Scatter {
            keep[g.range.start - p0..g.range.end - p0].fill(true);
            continue;
        }
        let info = &scene.material_info[g.material as usize];
        let index_matched = info.hints.contains(InstanceHints::INDEX_MATCHED);
        let opacity = scene.features.opacity && info.hints.contains(InstanceHints::OPACITY);
        if opacity {
            let range = g.range.clone();
            eval_opacity(
                scene,
                pts,
                range,
                g.material,
                arena,
                counters,
                &mut hits.opacity,
            );
        }
        for i in g.range.clone() {
            let r = pts.ray_id[i] as usize;
            let mut pass = index_matched
                || scene.is_false_boundary(&hits.incoming.volume_stack[r], pts.shape[i]);
            if opacity && !pass {
                // The choice's own sequence (`OPACITY_SEED_SALT`): no other dimension moves.
                let inc = &hits.incoming;
                let path = inc.path[r] as usize;
                let u = sample_1d(
                    batch.seeds[path] ^ OPACITY_SEED_SALT,
                    batch.paths.sample[path],
                    inc.dimension[r] + inc.passes[r] as u32,
                );
                pass = passes(u, hits.opacity[i - g.range.start]);
                stats.opacity_tests += 1;
                stats.opacity_passes += pass as u64;
            }
            keep[i - p0] = !pass;
            any_pass |= pass;
        }
    }
    if !any_pass && keep.iter().all(|&k| k) {
        groups.extend(new_groups);
        hits.examined_groups = groups.len();
        hits.groups.groups = groups;
        hits.keep = keep;
        return;
    }
    // Which passing points go on (in point order: the rays keep the order they had); their
    // rays are then copied in one gather per column (no capacity check or length store per
    // column and ray, as pushing rows would do) and updated in place.
    let mut going = std::mem::take(&mut hits.going);
    going.rays.clear();
    going.points.clear();
    for g in new_groups.iter().filter(|g| g.mode == ShadingMode::Scatter) {
        for i in g.range.clone() {
            if keep[i - p0] {
                continue;
            }
            let r = pts.ray_id[i] as usize;
            let tr = pts.transmission[i];
            let bad =
                tracer.surface_emission(scene, pts, &hits.incoming, &mut batch.paths, r, i, tr);
            stats.non_finite(Stage::Emission, bad);
            if bad > 0 {
                let (path, depth) = (hits.incoming.path[r], hits.incoming.depth[r]);
                let material = Some(g.material);
                non_finite_case(stats, &batch.paths, path, depth, Stage::Emission, material);
            }
            if hits.incoming.passes[r] as u32 >= scene.settings.max_passes {
                stats.terminate(Termination::PassLimit, 1);
                continue;
            }
            if (hits.incoming.throughput[r] * tr).is_black() {
                stats.terminate(Termination::Absorbed, 1);
                continue;
            }
            going.rays.push(r as u32);
            going.points.push(i as u32);
        }
    }
    let start = rays.rays.len();
    rays.rays.extend_gather(&hits.incoming, &going.rays);
    let out = &mut rays.rays;
    for (j, &i) in going.points.iter().enumerate() {
        let (row, i) = (start + j, i as usize);
        let (shape, p, front) = (pts.shape[i], pts.p[i], pts.front_face[i]);
        out.passes[row] += 1;
        out.throughput[row] *= pts.transmission[i];
        // The ray goes on along the same line. It restarts on the boundary itself, so
        // that the next segment's length (what volume integrators attenuate by) is the
        // true distance, and skips the boundary with `tmin`: the point's error offset,
        // measured along the ray (clamped for grazing rays).
        out.origin[row] = p;
        out.tmin[row] = skip_tmin(p, pts.p_offset[i], pts.ng[i], out.direction[row]);
        out.tmax[row] = f32::INFINITY;
        if scene.tracks_interior(shape) {
            match out.volume_stack[row].cross(scene.volume_entry(shape), front) {
                StackEvent::UnmatchedExit => stats.unmatched_exit(shape),
                StackEvent::EnteredAgain => stats.entered_twice(shape),
                _ => {}
            }
        }
    }
    hits.going = going;
    // Compact: a group's range moves to the number of kept points before it.
    let mut kept_before = std::mem::take(&mut hits.kept_before);
    kept_before.clear();
    kept_before.push(0);
    let mut kept = 0;
    for &k in &keep {
        kept += k as u32;
        kept_before.push(kept);
    }
    hits.groups.points.retain_rows_from(p0, &keep);
    let moved = |i: usize| p0 + kept_before[i - p0] as usize;
    groups.extend(new_groups.into_iter().filter_map(|g| {
        let range = moved(g.range.start)..moved(g.range.end);
        // Surface groups left empty are dropped; volume groups stay as they were.
        (g.mode != ShadingMode::Scatter || !range.is_empty()).then_some(ShadeGroup { range, ..g })
    }));
    hits.examined_groups = groups.len();
    hits.groups.groups = groups;
    hits.keep = keep;
    hits.kept_before = kept_before;
}
