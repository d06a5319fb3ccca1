//! The transmission system: shadow rays never bend (the seed's "non-refractive, non-bending"
//! transmission rays). Each one walks from its origin to its light sample; surfaces whose
//! material lets shadows pass ([`InstanceHints::TRANSMISSION_SHADOWS`], e.g. index-matched
//! boundaries or glass with cheap shadows) attenuate it by their shadow transmittance, false
//! boundaries (priorities) pass it unchanged, every other surface blocks it, and each interval
//! inside a volume is attenuated by that volume's `transmission`. A surface with opacity `a`
//! ([`InstanceHints::OPACITY`]) attenuates it by `1 - a` (plus `a` times its shadow
//! transmittance) at each crossing, in addition to the volumes (`crate::opacity`).
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
/// `IntegratorContext::technique`).
pub fn trace_shadow_rays(
    scene: &CompiledScene,
    shadow: &ShadowRays,
    batch: &PathBatch,
    volume: crate::plugin::PluginTechniques,
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
        &mut ShadowWalkScratch::default(),
    );
}

/// Whether every surface of `scene` blocks shadow rays and nothing between surfaces
/// attenuates them (no volumes, no surfaces that let shadows pass or have opacity): a shadow
/// ray's contribution then arrives whole or not at all ([`block_occluded`]).
pub(crate) fn shadows_only_blocked(scene: &CompiledScene) -> bool {
    let f = scene.features;
    !f.volumes && !f.transmission_shadows && !f.transmissive && !f.opacity
}

/// The walk of shadow rays in a scene where [`shadows_only_blocked`]: a single any-hit query
/// per ray `(origin, direction, tmax)` (counted as `occlusion`, so the stats show which path
/// shadow rays took), and the contribution of each ray that hits something set to black.
/// Nothing becomes non-finite.
pub(crate) fn block_occluded(
    scene: &CompiledScene,
    (origin, direction, tmax): (&[Vec3], &[Vec3], &[f32]),
    contribution: &mut [Rgb],
    stats: &mut SystemStats,
    arena: &Bump,
) {
    let n = origin.len();
    // Scratch from the batch arena (reset after each batch): no heap traffic per bounce.
    let occluded = arena.alloc_slice_fill_copy(n, false);
    let tmin = arena.alloc_slice_fill_copy(n, 0.0f32);
    stats.time(System::Occlusion, n, || {
        intersect_occluded(&scene.geometry, origin, direction, tmin, tmax, occluded)
    });
    for (c, &occluded) in contribution[..n].iter_mut().zip(&*occluded) {
        if occluded {
            *c = Rgb::BLACK;
        }
    }
}

/// [`trace_shadow_rays`], adding the emission of the volumes `gather` names, with the walk's
/// buffers in `scratch`.
#[allow(clippy::too_many_arguments, reason = "the stage's inputs, named")]
pub fn trace_shadow_rays_with(
    scene: &CompiledScene,
    shadow: &ShadowRays,
    batch: &PathBatch,
    volume: crate::plugin::PluginTechniques,
    contribution: &mut [Rgb],
    stats: &mut SystemStats,
    arena: &Bump,
    gather: ShadowEmission,
    scratch: &mut ShadowWalkScratch,
) {
    let n = shadow.len();
    let f = scene.features;
    if shadows_only_blocked(scene) {
        let rays = (&shadow.origin[..], &shadow.direction[..], &shadow.tmax[..]);
        block_occluded(scene, rays, contribution, stats, arena);
        return;
    }

    let ShadowWalkScratch {
        active,
        next,
        t0,
        entered,
        stacks,
        transmittance,
        emitted,
        dimension,
        query,
        origin,
        direction,
        tmin,
        tmax,
        found,
        t,
        prim,
        b1,
        b2,
        segs,
        volumes,
        lists,
        crossings,
    } = scratch;
    active.clear();
    active.extend(0..n as u32);
    // `t0`: where the next intersect query starts (past the last boundary by the spawn
    // offset); `entered`: where the ray crossed that boundary, the true start of the interval
    // inside the volume it entered (measuring from `t0` would lose the offset on every
    // interval, 33 ulps of the coordinates each).
    refill(t0, n, 0.0f32);
    refill(entered, n, 0.0f32);
    stacks.clear();
    stacks.extend_from_slice(&shadow.volume_stack);
    // Per shadow ray: transmittance so far (for what volumes emit), the emitted radiance
    // gathered, and the next sampler dimension of its own sequence.
    refill(transmittance, n, Rgb::WHITE);
    refill(emitted, n, Rgb::BLACK);
    dimension.clear();
    dimension.extend_from_slice(&shadow.dimension);
    let mut walk = Walk {
        transmittance,
        emitted,
        dimension,
        counters: PatternCounters::default(),
        gather,
    };
    // Each ray's hits from one traversal of its whole segment, taken one per round:
    // `RayHits::next_after` says what a closest-hit query from `t0` would find, and where
    // it cannot (a hit within its error bound of `t0`, a full list), the ray queries again
    // from `t0`. The same hits as one closest-hit query per round, for a third of the
    // traversals on a shadow ray that leaves a medium.
    let lists = stale_lists(lists, n);
    let taken = arena.alloc_slice_fill_copy(n, 0u8);
    stats.time(System::Intersect, n, || {
        intersect_all(
            &scene.geometry,
            &shadow.origin,
            &shadow.direction,
            t0,
            &shadow.tmax,
            lists,
        )
    });
    let mut rounds = 0;
    while !active.is_empty() && rounds < scene.settings.max_passes {
        rounds += 1;
        let m = active.len();
        refill(t, m, f32::INFINITY);
        refill(prim, m, NO_HIT);
        refill(b1, m, 0.0);
        refill(b2, m, 0.0);
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
            for &(_, i) in query.iter() {
                origin.push(shadow.origin[i]);
                direction.push(shadow.direction[i]);
                tmin.push(t0[i]);
                tmax.push(shadow.tmax[i]);
            }
            let found = stale_lists(found, query.len());
            stats.time(System::Intersect, query.len(), || {
                intersect_all(&scene.geometry, origin, direction, tmin, tmax, found)
            });
            for (&(k, i), h) in query.iter().zip(found.iter()) {
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
                stacks,
                segs,
                volumes,
                volume,
                contribution,
                stats,
                arena,
            );
        }
        next.clear();
        let triangles = scene.geometry.triangles();
        for (k, &i) in active.iter().enumerate() {
            let iu = i as usize;
            if prim[k] == NO_HIT || contribution[iu].is_black() {
                continue;
            }
            let shape = scene.shape_of_prim(prim[k]);
            let material = scene.shapes[shape as usize].material;
            let info = &scene.material_info[material as usize];
            let false_boundary = scene.is_false_boundary(&stacks[iu], shape);
            if !false_boundary && f.opacity && info.hints.contains(InstanceHints::OPACITY) {
                // Attenuated after the round, all crossings of a material at once.
                crossings.crossings.push(crate::opacity::ShadowCrossing {
                    ray: i,
                    prim: prim[k],
                    t: t[k],
                    b1: b1[k],
                    b2: b2[k],
                    material,
                    shape,
                    ior_outside: crate::context::ior_outside(scene, &stacks[iu], shape),
                });
            } else if !false_boundary {
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
            // Each branch takes what it needs of its own surface (merging two whole
            // surfaces through memory would stall on the store).
            let (offset, ng) = match triangles.surface_at(prim[k], b1[k], b2[k]) {
                Some(s) => (s.offset(), s.ng),
                None => {
                    let s = scene.geometry.surface_at(prim[k], o, d, t[k], b1[k], b2[k]);
                    (s.offset(), s.ng)
                }
            };
            entered[iu] = t[k];
            t0[iu] = tmin_past_hit(t[k], offset, ng, d);
            if t0[iu] < shadow.tmax[iu] {
                next.push(i);
            }
        }
        if !crossings.crossings.is_empty() {
            stats.opacity_shadow_crossings += crossings.crossings.len() as u64;
            crate::opacity::attenuate_shadow_crossings(
                scene,
                &shadow.origin,
                &shadow.direction,
                crossings,
                arena,
                &walk.counters,
                contribution,
                walk.transmittance,
            );
        }
        std::mem::swap(active, next);
    }
    // Rays still walking after the pass budget are treated as blocked (never silently lit).
    for &i in active.iter() {
        contribution[i as usize] = Rgb::BLACK;
    }
    if f.emissive_media {
        for (c, e) in contribution.iter_mut().zip(walk.emitted.iter()) {
            *c += *e;
        }
    }
    stats.pattern_cache_hits += walk.counters.hits.take();
    stats.pattern_evals += walk.counters.evals.take();
    stats.volume_pattern_evals += walk.counters.volume_evals.take();
}

/// The first `n` lists of `v`, holding whatever earlier walks left there, for
/// [`intersect_all`] to overwrite (it writes every one): `v` only grows, and nothing is
/// written twice.
fn stale_lists(v: &mut Vec<RayHits>, n: usize) -> &mut [RayHits] {
    if v.len() < n {
        // Exactly the largest walk's size: no doubling of a buffer that lives on.
        v.reserve_exact(n - v.len());
        v.resize(n, RayHits::EMPTY);
    }
    &mut v[..n]
}

/// `v` as `n` copies of `value`, in its existing allocation.
fn refill<T: Copy>(v: &mut Vec<T>, n: usize, value: T) {
    v.clear();
    v.resize(n, value);
}

/// The buffers of the shadow-ray walk. A caller that traces shadow rays again and again keeps
/// one (the path tracer: one per worker) so that, once they have grown to its largest batch,
/// a walk allocates nothing; [`trace_shadow_rays`] starts from an empty one.
#[derive(Default)]
pub struct ShadowWalkScratch {
    active: Vec<u32>,
    next: Vec<u32>,
    t0: Vec<f32>,
    entered: Vec<f32>,
    stacks: Vec<VolumeStack>,
    transmittance: Vec<Rgb>,
    emitted: Vec<Rgb>,
    dimension: Vec<u32>,
    query: Vec<(usize, usize)>,
    origin: Vec<Vec3>,
    direction: Vec<Vec3>,
    tmin: Vec<f32>,
    tmax: Vec<f32>,
    found: Vec<RayHits>,
    t: Vec<f32>,
    prim: Vec<u32>,
    b1: Vec<f32>,
    b2: Vec<f32>,
    segs: Vec<(usize, f32, f32)>,
    volumes: VolumeScratch,
    /// Each ray's hits ([`intersect_all`] overwrites the first `n`).
    lists: Vec<RayHits>,
    /// The round's crossings of surfaces with opacity.
    crossings: crate::opacity::CrossingScratch,
}

/// The buffers of one round's volume intervals ([`attenuate_in_volumes`]).
#[derive(Default)]
struct VolumeScratch {
    /// One ray per distinct volume stack of the round (the stack is that ray's).
    keys: Vec<usize>,
    /// The intervals (indices into the round's list) in the current stack.
    members: Vec<usize>,
    segments: Segments,
    samplers: Vec<PathSampler>,
    points: ShadingPoints,
    trans: Vec<Rgb>,
    emission: Vec<Rgb>,
}

/// The state of every shadow ray's walk that volume intervals update.
struct Walk<'a> {
    /// Transmittance from the origin to where the ray has got.
    transmittance: &'a mut [Rgb],
    /// Radiance emitted by volumes along the way, weighted and attenuated.
    emitted: &'a mut [Rgb],
    /// Next sampler dimension.
    dimension: &'a mut [u32],
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
    walk: &mut Walk<'_>,
    stacks: &[VolumeStack],
    segs: &[(usize, f32, f32)],
    scratch: &mut VolumeScratch,
    volume: crate::plugin::PluginTechniques,
    contribution: &mut [Rgb],
    stats: &mut SystemStats,
    arena: &Bump,
) {
    if segs.is_empty() {
        return;
    }
    let start = std::time::Instant::now();
    let VolumeScratch {
        keys,
        members,
        segments,
        samplers,
        points,
        trans,
        emission,
    } = scratch;
    // Group by volume stack (few distinct ones per round): the innermost volume's integrator
    // answers, and it sees the other volumes of the same stack as overlapping ones (the seed:
    // "that single integrator is allowed to query properties of all other overlapping
    // volumes", for GetTransmission as for GetNearestHits).
    keys.clear();
    keys.push(segs[0].0);
    for &(i, _, _) in segs {
        if !keys.iter().any(|&k| stacks[k] == stacks[i]) {
            keys.push(i);
        }
    }
    let single_stack = keys.len() == 1;
    let computes_interior = |e: &risotto_components::VolumeEntry| {
        scene.material_info[e.material as usize]
            .hints
            .contains(InstanceHints::COMPUTES_INTERIOR)
    };
    for &key in keys.iter() {
        let stack = &stacks[key];
        let entry = stack.innermost().expect("filtered above");
        if !computes_interior(&entry) {
            continue;
        }
        members.clear();
        if single_stack {
            members.extend(0..segs.len());
        } else {
            members.extend((0..segs.len()).filter(|&j| &stacks[segs[j].0] == stack));
        }
        let m = members.len();
        segments.clear();
        samplers.clear();
        for &j in members.iter() {
            let (i, s0, len) = segs[j];
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
        // The points live in the walk's scratch (the arena runs no destructors: a table
        // moved there would never free its columns); the arena holds only the plain
        // contexts.
        points.clear();
        points.extend_in_volume(&segments.origin, &segments.direction, entry.material);
        let cache = arena.alloc(ParamCache::new(arena, &walk.counters));
        let Some((_, integrator)) = bind_interior(scene, stack, entry, points, cache, arena) else {
            continue;
        };
        let hints = scene.material_info[entry.material as usize].hints;
        let gathers = scene.features.emissive_media
            && hints.contains(InstanceHints::INTERIOR_EMITS)
            && !(walk.gather == ShadowEmission::NotAlongPaths
                && hints.contains(InstanceHints::INTERIOR_EMITS_ALONG_PATHS));
        refill(trans, m, Rgb::WHITE);
        refill(emission, m, Rgb::BLACK);
        let mut scratch_stats = SystemStats::default();
        let ictx = crate::context::RenderContext::new(scene, &mut scratch_stats)
            .with_techniques(volume)
            .with_emission_wanted(gathers);
        integrator.transmission(segments, samplers, &ictx, trans, emission);
        stats.majorant_violations += ictx.take_majorant_violations();
        let (segments, lookups) = ictx.take_dense_segments();
        stats.dense_segments += segments;
        stats.dense_lookups += lookups;
        stats.shadow_collisions += ictx.take_shadow_collisions();
        if gathers {
            stats.volume_event(VolumeEvent::Emission, m);
        }
        for (k, &j) in members.iter().enumerate() {
            let i = segs[j].0;
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
