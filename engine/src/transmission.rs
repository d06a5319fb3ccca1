//! The transmission system: shadow rays never bend (the seed's "non-refractive, non-bending"
//! transmission rays). Each one walks from its origin to its light sample; surfaces whose
//! material lets shadows pass ([`InstanceHints::TRANSMISSION_SHADOWS`], e.g. index-matched
//! boundaries or glass with cheap shadows) attenuate it by their shadow transmittance, false
//! boundaries (priorities) pass it unchanged, every other surface blocks it, and each interval
//! inside a volume is attenuated by that volume's `transmission`.
//!
//! What volumes emit along a shadow ray (the `emission` output of `transmission`, radiance
//! reaching the interval's start) is added too, attenuated by everything before the interval
//! and weighted like the light's radiance (`ShadowRays::weight`): radiance arriving along the
//! shadow ray's direction, even from in front of a surface that then blocks the light; only
//! in scenes with emissive media (`InstanceHints::INTERIOR_EMITS`). The path tracer leaves
//! out the volumes that report their emission along path rays instead
//! (`InstanceHints::INTERIOR_EMITS_ALONG_PATHS`, the built-in media:
//! [`ShadowEmission::NotAlongPaths`]), which would otherwise count twice.
//!
//! Work is batch-shaped: all live shadow rays advance to their next surface in one intersect
//! call per round, and the intervals of one round are grouped by volume so that each volume
//! integrator answers once per round.

use crate::integrator::PathBatch;
use crate::interior::bind_interior;
use crate::plugin::*;
use crate::scene::CompiledScene;
use crate::stats::{System, SystemStats, VolumeEvent};
use bumpalo::Bump;
use glam::Vec3;
use risotto_components::{Rgb, ShadingPoints, ShadowRays, VolumeStack, NO_HIT};
use risotto_systems::intersect::{intersect_all, intersect_occluded, NextHit, RayHits};
use risotto_systems::ray::tmin_past_hit;
use risotto_systems::sampler::PathSampler;

/// Seed salt of shadow rays' sampler sequences: decorrelated from the camera path's sequence
/// at the same dimensions (the shadow ray starts at its vertex's first dimension).
const SHADOW_SEED_SALT: u32 = 0x5bd1_e995;

/// Which volumes' emission a shadow-ray walk adds to the contributions (in scenes with
/// emissive media).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ShadowEmission {
    /// Every volume's (what [`trace_shadow_rays`] does): for integrators that gather no
    /// emission along path rays.
    #[default]
    All,
    /// Only volumes whose material lacks [`InstanceHints::INTERIOR_EMITS_ALONG_PATHS`]:
    /// the path tracer, which adds the others' emission along its path rays.
    NotAlongPaths,
}

/// Attenuates `contribution[i]` of every shadow ray by the transmittance to its light sample
/// (0 when blocked), and adds what emissive volumes send along it
/// ([`ShadowEmission::All`]). `volume` is handed to the volumes' `transmission` (through
/// [`IntegratorContext::volume_techniques`](crate::context::IntegratorContext::volume_techniques)).
pub fn trace_shadow_rays(
    scene: &CompiledScene,
    shadow: &ShadowRays,
    batch: &PathBatch,
    volume: crate::plugin::VolumeTechniques,
    contribution: &mut [Rgb],
    stats: &mut SystemStats,
    arena: &Bump,
) {
    trace_shadow_rays_with(
        scene,
        shadow,
        batch,
        volume,
        contribution,
        stats,
        arena,
        ShadowEmission::All,
    );
}

/// [`trace_shadow_rays`], adding the emission of the volumes `gather` names.
#[allow(clippy::too_many_arguments, reason = "the stage's inputs, named")]
pub fn trace_shadow_rays_with(
    scene: &CompiledScene,
    shadow: &ShadowRays,
    batch: &PathBatch,
    volume: crate::plugin::VolumeTechniques,
    contribution: &mut [Rgb],
    stats: &mut SystemStats,
    arena: &Bump,
    gather: ShadowEmission,
) {
    let n = shadow.len();
    let f = scene.features;
    if !f.volumes && !f.transmission_shadows && !f.transmissive {
        // Fast path: opaque surfaces only, a single any-hit query per ray (counted as
        // `occlusion`, so the stats show which path shadow rays took).
        // Scratch from the batch arena (reset after each batch): no heap traffic per bounce.
        let occluded = arena.alloc_slice_fill_copy(n, false);
        let tmin = arena.alloc_slice_fill_copy(n, 0.0f32);
        stats.time(System::Occlusion, n, || {
            intersect_occluded(
                &scene.geometry,
                &shadow.origin,
                &shadow.direction,
                tmin,
                &shadow.tmax,
                occluded,
            )
        });
        for i in 0..n {
            if occluded[i] {
                contribution[i] = Rgb::BLACK;
            }
        }
        return;
    }

    let mut active: Vec<u32> = (0..n as u32).collect();
    // `t0`: where the next intersect query starts (past the last boundary by the spawn
    // offset); `entered`: where the ray crossed that boundary, the true start of the interval
    // inside the volume it entered (measuring from `t0` would lose the offset on every
    // interval, 33 ulps of the coordinates each).
    let mut t0 = vec![0.0f32; n];
    let mut entered = vec![0.0f32; n];
    let mut stacks: Vec<VolumeStack> = shadow.volume_stack.clone();
    // Per shadow ray: transmittance so far (for what volumes emit), the emitted radiance
    // gathered, and the next sampler dimension of its own sequence.
    let mut walk = Walk {
        transmittance: vec![Rgb::WHITE; n],
        emitted: vec![Rgb::BLACK; n],
        dimension: shadow.dimension.clone(),
        counters: PatternCounters::default(),
        gather,
    };
    // Each ray's hits from one traversal of its whole segment, taken one per round:
    // `RayHits::next_after` says what a closest-hit query from `t0` would find, and where
    // it cannot (a hit within its error bound of `t0`, a full list), the ray queries again
    // from `t0`. The same hits as one closest-hit query per round, for a third of the
    // traversals on a shadow ray that leaves a medium.
    let lists = arena.alloc_slice_fill_copy(n, RayHits::EMPTY);
    let taken = arena.alloc_slice_fill_copy(n, 0u8);
    stats.time(System::Intersect, n, || {
        intersect_all(
            &scene.geometry,
            &shadow.origin,
            &shadow.direction,
            &t0,
            &shadow.tmax,
            lists,
        )
    });
    let mut query: Vec<(usize, usize)> = Vec::new();
    let (mut origin, mut direction) = (Vec::new(), Vec::new());
    let (mut tmin, mut tmax, mut found) = (Vec::new(), Vec::new(), Vec::new());
    let (mut t, mut prim) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let (mut b1, mut b2) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let mut segs: Vec<(usize, f32, f32)> = Vec::with_capacity(n);
    let mut next = Vec::with_capacity(n);
    let mut rounds = 0;
    while !active.is_empty() && rounds < scene.settings.max_passes {
        rounds += 1;
        let m = active.len();
        t.clear();
        t.resize(m, f32::INFINITY);
        prim.clear();
        prim.resize(m, NO_HIT);
        b1.clear();
        b1.resize(m, 0.0);
        b2.clear();
        b2.resize(m, 0.0);
        query.clear();
        for (k, &i) in active.iter().enumerate() {
            let i = i as usize;
            let h = &lists[i];
            // The nearest hit of a new list is the closest-hit query's answer.
            let next_hit = match (rounds, h.len) {
                (1, 0) => NextHit::Miss,
                (1, _) => NextHit::Hit(0),
                _ => h.next_after(taken[i] as usize, t0[i]),
            };
            match next_hit {
                NextHit::Hit(j) => {
                    taken[i] = j as u8 + 1;
                    (t[k], prim[k], b1[k], b2[k]) = (h.t[j], h.prim[j], h.b1[j], h.b2[j]);
                }
                NextHit::Query => query.push((k, i)),
                NextHit::Miss => {}
            }
        }
        if !query.is_empty() {
            origin.clear();
            direction.clear();
            tmin.clear();
            tmax.clear();
            for &(_, i) in &query {
                origin.push(shadow.origin[i]);
                direction.push(shadow.direction[i]);
                tmin.push(t0[i]);
                tmax.push(shadow.tmax[i]);
            }
            found.clear();
            found.resize(query.len(), RayHits::EMPTY);
            stats.time(System::Intersect, query.len(), || {
                intersect_all(
                    &scene.geometry,
                    &origin,
                    &direction,
                    &tmin,
                    &tmax,
                    &mut found,
                )
            });
            for (&(k, i), h) in query.iter().zip(&found) {
                lists[i] = *h;
                if h.len > 0 {
                    taken[i] = 1;
                    (t[k], prim[k], b1[k], b2[k]) = (h.t[0], h.prim[0], h.b1[0], h.b2[0]);
                }
            }
        }
        // Intervals inside volumes for this round: (ray, start, length).
        if f.volumes {
            segs.clear();
            for (k, &i) in active.iter().enumerate() {
                let i = i as usize;
                let end = if prim[k] == NO_HIT {
                    shadow.tmax[i]
                } else {
                    t[k]
                };
                if stacks[i].innermost().is_some() && end > entered[i] {
                    segs.push((i, entered[i], end - entered[i]));
                }
            }
            attenuate_in_volumes(
                scene,
                shadow,
                batch,
                &mut walk,
                &stacks,
                &segs,
                volume,
                contribution,
                stats,
                arena,
            );
        }
        next.clear();
        for (k, &i) in active.iter().enumerate() {
            let iu = i as usize;
            if prim[k] == NO_HIT || contribution[iu].is_black() {
                continue;
            }
            let shape = scene.prim_shape[prim[k] as usize];
            let material = scene.shapes[shape as usize].material;
            let info = &scene.material_info[material as usize];
            let false_boundary = scene.is_false_boundary(&stacks[iu], shape);
            if !false_boundary {
                if !info.hints.contains(InstanceHints::TRANSMISSION_SHADOWS) {
                    contribution[iu] = Rgb::BLACK;
                    continue;
                }
                contribution[iu] *= info.shadow_transmittance;
                walk.transmittance[iu] *= info.shadow_transmittance;
            }
            if scene.tracks_interior(shape) {
                let (o, d) = (shadow.origin[iu], shadow.direction[iu]);
                let front = scene.geometry.hit_is_front(prim[k], o, d, t[k], b1[k]);
                stacks[iu].cross(scene.volume_entry(shape), front);
            }
            // Past the hit by its surface's error offset along the ray (coincident hits,
            // such as an edge two triangles share, count once).
            let (o, d) = (shadow.origin[iu], shadow.direction[iu]);
            let s = scene.geometry.surface_at(prim[k], o, d, t[k], b1[k], b2[k]);
            entered[iu] = t[k];
            t0[iu] = tmin_past_hit(t[k], s.offset(), s.ng, d);
            if t0[iu] < shadow.tmax[iu] {
                next.push(i);
            }
        }
        std::mem::swap(&mut active, &mut next);
    }
    // Rays still walking after the pass budget are treated as blocked (never silently lit).
    for &i in &active {
        contribution[i as usize] = Rgb::BLACK;
    }
    if f.emissive_media {
        for (c, e) in contribution.iter_mut().zip(&walk.emitted) {
            *c += *e;
        }
    }
    stats.pattern_cache_hits += walk.counters.hits.take();
    stats.pattern_evals += walk.counters.evals.take();
    stats.volume_pattern_evals += walk.counters.volume_evals.take();
}

/// The state of every shadow ray's walk that volume intervals update.
struct Walk {
    /// Transmittance from the origin to where the ray has got.
    transmittance: Vec<Rgb>,
    /// Radiance emitted by volumes along the way, weighted and attenuated.
    emitted: Vec<Rgb>,
    /// Next sampler dimension.
    dimension: Vec<u32>,
    /// Parameter-cache counts of the volumes' contexts.
    counters: PatternCounters,
    /// Which volumes' emission is gathered.
    gather: ShadowEmission,
}

/// Runs each volume's `transmission` on the intervals of one round that lie in it.
#[allow(clippy::too_many_arguments, reason = "the stage's inputs, named")]
fn attenuate_in_volumes(
    scene: &CompiledScene,
    shadow: &ShadowRays,
    batch: &PathBatch,
    walk: &mut Walk,
    stacks: &[VolumeStack],
    segs: &[(usize, f32, f32)],
    volume: crate::plugin::VolumeTechniques,
    contribution: &mut [Rgb],
    stats: &mut SystemStats,
    arena: &Bump,
) {
    if segs.is_empty() {
        return;
    }
    let start = std::time::Instant::now();
    // Group by volume stack (few distinct ones per round): the innermost volume's integrator
    // answers, and it sees the other volumes of the same stack as overlapping ones (the seed:
    // "that single integrator is allowed to query properties of all other overlapping
    // volumes", for GetTransmission as for GetNearestHits).
    let mut keys: Vec<&VolumeStack> = vec![&stacks[segs[0].0]];
    for &(i, _, _) in segs {
        if !keys.contains(&&stacks[i]) {
            keys.push(&stacks[i]);
        }
    }
    let single_stack = keys.len() == 1;
    let computes_interior = |e: &risotto_components::VolumeEntry| {
        scene.material_info[e.material as usize]
            .hints
            .contains(InstanceHints::COMPUTES_INTERIOR)
    };
    for stack in keys {
        let entry = stack.innermost().expect("filtered above");
        if !computes_interior(&entry) {
            continue;
        }
        let members: Vec<&(usize, f32, f32)> = if single_stack {
            segs.iter().collect()
        } else {
            segs.iter()
                .filter(|(i, _, _)| &stacks[*i] == stack)
                .collect()
        };
        let m = members.len();
        let mut segments = Segments::default();
        let mut samplers = Vec::with_capacity(m);
        for &&(i, s0, len) in &members {
            let o: Vec3 = shadow.origin[i] + shadow.direction[i] * s0;
            segments.push(o, shadow.direction[i], len);
            let path = shadow.path[i] as usize;
            // Each shadow ray draws from its own sequence (see `SHADOW_SEED_SALT`), from
            // where its previous interval left it.
            samplers.push(PathSampler {
                seed: batch.seeds[path] ^ SHADOW_SEED_SALT,
                sample: batch.paths.sample[path],
                dimension: walk.dimension[i],
            });
        }
        let mut pts = ShadingPoints::with_capacity(m);
        pts.extend_in_volume(&segments.origin, &segments.direction, entry.material);
        // The points stay on this stack frame (the arena runs no destructors: a table moved
        // there would never free its columns); the arena holds only the plain contexts.
        let pts = &pts;
        let cache = arena.alloc(ParamCache::new(arena, &walk.counters));
        let Some((_, integrator)) = bind_interior(scene, stack, entry, pts, cache, arena) else {
            continue;
        };
        let hints = scene.material_info[entry.material as usize].hints;
        let gathers = scene.features.emissive_media
            && hints.contains(InstanceHints::INTERIOR_EMITS)
            && !(walk.gather == ShadowEmission::NotAlongPaths
                && hints.contains(InstanceHints::INTERIOR_EMITS_ALONG_PATHS));
        let mut trans = vec![Rgb::WHITE; m];
        let mut emission = vec![Rgb::BLACK; m];
        let mut scratch_stats = SystemStats::default();
        let ictx = crate::context::IntegratorContext::new(scene, &mut scratch_stats)
            .with_volume_techniques(volume)
            .with_emission_wanted(gathers);
        integrator.transmission(&segments, &mut samplers, &ictx, &mut trans, &mut emission);
        stats.majorant_violations += ictx.take_majorant_violations();
        if gathers {
            stats.volume_event(VolumeEvent::Emission, m);
        }
        for (k, &&(i, _, _)) in members.iter().enumerate() {
            if gathers {
                walk.emitted[i] += shadow.weight[i] * walk.transmittance[i] * emission[k];
            }
            contribution[i] *= trans[k];
            walk.transmittance[i] *= trans[k];
            walk.dimension[i] = samplers[k].dimension;
        }
    }
    stats.record(System::Volume, segs.len(), start.elapsed().as_secs_f64());
}
