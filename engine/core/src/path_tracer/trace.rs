//! Trace stage: the next shading points of the queued rays. Rays in no volume go to the
//! renderer's nearest-hit query; rays in a volume are partitioned into bundles by (volume
//! stack, transmit bit), and each bundle goes to its innermost volume's integrator
//! (`VolumeIntegrator::nearest_hits`), which may return surface hits with transmission,
//! points inside the volume (a `VolumeScatter` group), escaped rays, or nothing (absorbed),
//! and may light in-volume points through the lighting delegate.

use super::direct_lighting::DirectLighting;
use super::queues::{EscapedRayQueue, HitQueue, Queues, TraceScratch};
use super::surface_caches::SurfaceCaches;
use super::{non_finite_case, PathTracer};
use crate::context::RenderContext;
use crate::integrator::{LightingTechnique, PathBatch};
use crate::interior::bind_interior;
use crate::plugin::*;
use crate::scene::CompiledScene;
use crate::stats::{count_non_finite, Stage, System, SystemStats, Termination};
use bumpalo::Bump;
use risotto_components::{LobeSampled, Rays, VolumeEntry, VolumeStack};
use risotto_systems::lights::LightSet;
use risotto_systems::partition::partition_by_key;
use risotto_systems::sampler::PathSampler;

/// Whose rays a trace stage traces, as the volume integrators it calls are told.
#[derive(Clone, Copy, Default)]
pub(crate) struct TraceRole<'a> {
    /// The rays start at the lights ([`VolumeServices::light_path`]).
    pub light_path: bool,
    /// A global integrator's own weights for the emission of light-sampled media, and the
    /// light set whose selection probabilities they use
    /// ([`VolumeLightMis::strategies`]); `None`: the path tracer's.
    pub emission: Option<(&'a LightSet, &'a dyn EmissionStrategies)>,
}

/// Traces every ray of `q.rays` (leaving it empty), appending the rays to `q.hits.incoming`,
/// their points to `q.hits.groups` and the escaped ones to `q.escaped`.
/// Interiors whose rays all left one group of `surfaces` share that group's parameter cache.
#[allow(
    clippy::too_many_arguments,
    reason = "the stage's inputs, each named; grouping them would hide which it reads"
)]
pub(super) fn nearest_hits<'a>(
    tracer: &PathTracer,
    scene: &CompiledScene,
    batch: &mut PathBatch,
    q: &mut Queues,
    stats: &mut SystemStats,
    arena: &'a Bump,
    counters: &'a PatternCounters,
    surfaces: &SurfaceCaches<'a>,
    role: TraceRole<'_>,
) {
    let (rays, hits, t) = (&mut q.rays.rays, &mut q.hits, &mut q.trace);
    if scene.features.volumes {
        partitioned(
            tracer,
            role,
            scene,
            batch,
            rays,
            hits,
            &mut q.shadow.rays,
            &mut q.group,
            t,
            counters,
            surfaces,
            stats,
            arena,
        );
    } else if hits.incoming.is_empty() && hits.groups.points.is_empty() {
        // First round (the only one unless there are pass-throughs): answer straight into
        // the groups and move the rays over instead of copying them.
        let mut ictx = RenderContext::with_scratch(scene, stats, std::mem::take(&mut t.hits))
            .with_techniques(tracer.techniques);
        ictx.nearest_hits(rays, &mut hits.groups);
        t.hits = ictx.into_scratch();
        std::mem::swap(&mut hits.incoming, rays);
    } else {
        t.answers.clear();
        let mut ictx = RenderContext::with_scratch(scene, stats, std::mem::take(&mut t.hits))
            .with_techniques(tracer.techniques);
        ictx.nearest_hits(rays, &mut t.answers);
        t.hits = ictx.into_scratch();
        append(hits, &mut t.answers, rays);
    }
    rays.clear();
    take_misses(hits, &mut q.escaped);
}

/// Moves the escaped rays out of the groups into their own queue.
fn take_misses(hits: &mut HitQueue, escaped: &mut EscapedRayQueue) {
    std::mem::swap(&mut escaped.ray, &mut hits.groups.misses);
    std::mem::swap(
        &mut escaped.transmission,
        &mut hits.groups.miss_transmission,
    );
    hits.groups.misses.clear();
    hits.groups.miss_transmission.clear();
}

/// Appends `answers` (the answer for `rays`) to the hit queue, `rays` to its incoming rays
/// (moved there when the queue is empty, so `rays` is left empty or unchanged; the answers
/// too, see [`ShadeGroups::take_or_append`]).
fn append(hits: &mut HitQueue, answers: &mut ShadeGroups, rays: &mut Rays) {
    let offset = hits.incoming.len() as u32;
    if offset == 0 {
        std::mem::swap(&mut hits.incoming, rays);
        rays.clear();
    } else {
        hits.incoming.extend_from(rays);
    }
    hits.groups.take_or_append(answers, offset);
}

/// Adds what a volume emitted along the bundle's rays ([`ShadeGroups::emitted`]) to their
/// paths, times each ray's throughput (with weight 1: the path tracer samples no light
/// towards media), for rays whose segment is inside the path-length budget. NaN provenance:
/// a non-finite radiance is the volume integrator's (`Stage::Volume`), a product that is not
/// finite although its factors are, the emission stage's.
fn add_emitted(
    scene: &CompiledScene,
    bundle: &Rays,
    emitted: &EmittedRadiance,
    batch: &mut PathBatch,
    stats: &mut SystemStats,
) {
    let (mut bad_volume, mut bad_product) = (0, 0);
    for (&r, &e) in emitted.ray.iter().zip(&emitted.radiance) {
        let r = r as usize;
        // The ray is segment depth + 1 of its path.
        if bundle.depth[r] as u32 + 1 > scene.settings.max_depth {
            continue;
        }
        let c = bundle.throughput[r] * e;
        bad_volume += !e.is_finite() as usize;
        bad_product += (!c.is_finite() & e.is_finite() & bundle.throughput[r].is_finite()) as usize;
        batch.paths.radiance[bundle.path[r] as usize] += c;
    }
    stats.non_finite(Stage::Volume, bad_volume);
    stats.non_finite(Stage::Emission, bad_product);
}

/// Partitions `rays` into bundles by the volumes the rays travel in and the transmit bit, and
/// runs each bundle through its innermost volume's integrator (or plain nearest hits when in
/// no volume).
#[allow(
    clippy::too_many_arguments,
    reason = "the queues it reads and writes, named"
)]
fn partitioned<'a>(
    tracer: &PathTracer,
    role: TraceRole<'_>,
    scene: &CompiledScene,
    batch: &mut PathBatch,
    rays: &mut Rays,
    hits: &mut HitQueue,
    shadow: &mut risotto_components::ShadowRays,
    group: &mut super::queues::GroupScratch,
    t: &mut TraceScratch,
    counters: &'a PatternCounters,
    surfaces: &SurfaceCaches<'a>,
    stats: &mut SystemStats,
    arena: &'a Bump,
) {
    let n = rays.len();
    // Distinct stacks of this round (few: rays in one scene share a handful of states).
    let mut stacks: smallvec::SmallVec<[VolumeStack; 8]> = smallvec::SmallVec::new();
    t.keys.clear();
    stats.time(System::Partition, n, || {
        for i in 0..n {
            let s = &rays.volume_stack[i];
            let id = match stacks.iter().position(|x| x == s) {
                Some(id) => id,
                None => {
                    stacks.push(s.clone());
                    stacks.len() - 1
                }
            };
            let transmit = rays.lobe[i].is_transmit() as u32;
            t.keys.push(id as u32 * 2 + transmit);
        }
        partition_by_key(&t.keys, stacks.len() * 2, &mut t.order, &mut t.runs);
    });
    let computes_interior = |e: &VolumeEntry| {
        scene.material_info[e.material as usize]
            .hints
            .contains(InstanceHints::COMPUTES_INTERIOR)
    };
    let mut runs = std::mem::take(&mut t.runs);
    // The largest bundle first: the first answers of a bounce move their rays into the
    // empty hit queue instead of copying them (`append`).
    runs.sort_by_key(|(_, range)| std::cmp::Reverse(range.len()));
    for (key, range) in &runs {
        let stack = &stacks[(*key / 2) as usize];
        t.bundle.clear();
        let whole = runs.len() == 1;
        if whole {
            // One bundle holds every ray, in order (the partition is stable): take the
            // table instead of copying it (the caller clears `rays` after the round).
            std::mem::swap(&mut t.bundle, rays);
        } else {
            t.bundle.extend_gather(rays, &t.order[range.clone()]);
        }
        // Rays that all left one shaded group of the interior's material share its cache,
        // point `shading_ctx_index` of its context each (module docs of `surface_caches`).
        let shared = stack
            .innermost()
            .filter(computes_interior)
            .and_then(|e| match whole {
                true => surfaces.common(0..t.bundle.len(), e.material),
                false => surfaces.common(
                    t.order[range.clone()].iter().map(|&r| r as usize),
                    e.material,
                ),
            })
            .map(|cache| (cache, &*arena.alloc_slice_copy(&t.bundle.shading_ctx_index)));
        for (k, s) in t.bundle.shading_ctx_index.iter_mut().enumerate() {
            *s = k as u32;
        }
        t.answers.clear();
        match stack.innermost().filter(computes_interior) {
            None => {
                let mut ictx =
                    RenderContext::with_scratch(scene, stats, std::mem::take(&mut t.hits))
                        .with_techniques(tracer.techniques);
                ictx.nearest_hits(&t.bundle, &mut t.answers);
                t.hits = ictx.into_scratch();
            }
            Some(entry) => {
                let m = t.bundle.len();
                // The bundle's shading context: points at the rays' origins, in the worker's
                // reused table (never in the arena: it owns heap memory).
                t.bundle_points.clear();
                t.bundle_points.extend_in_volume(
                    &t.bundle.origin,
                    &t.bundle.direction,
                    entry.material,
                );
                let cache = arena.alloc(match shared {
                    Some((surface, rows)) => ParamCache::sharing(arena, counters, surface, rows),
                    None => ParamCache::new(arena, counters),
                });
                let (factory, integrator) =
                    bind_interior(scene, stack, entry, &t.bundle_points, cache, arena)
                        .expect("hint COMPUTES_INTERIOR promised an interior");
                t.samplers.clear();
                t.samplers.extend((0..m).map(|i| PathSampler {
                    seed: batch.seeds[t.bundle.path[i] as usize],
                    sample: batch.paths.sample[t.bundle.path[i] as usize],
                    dimension: t.bundle.dimension[i],
                }));
                let mut delegate =
                    DirectLighting::new(scene, tracer.technique, &batch.paths, shadow, group);
                let lighting: Option<&mut dyn LightingDelegate> = if tracer.technique
                    == LightingTechnique::BxdfOnly
                    || !scene.lights.can_sample()
                {
                    None
                } else {
                    Some(&mut delegate)
                };
                let mut ictx =
                    RenderContext::with_scratch(scene, stats, std::mem::take(&mut t.hits))
                        .with_techniques(tracer.techniques);
                let start = std::time::Instant::now();
                integrator.nearest_hits(
                    &t.bundle,
                    &mut t.samplers,
                    LobeSampled(0xff),
                    VolumeServices {
                        ictx: &mut ictx,
                        lighting,
                        factory,
                        arena,
                        volume_light: match role.emission {
                            Some((set, strategies)) => {
                                scene
                                    .volume_light_in(set, entry.shape)
                                    .map(|l| VolumeLightMis {
                                        strategies: Some(strategies),
                                        ..l
                                    })
                            }
                            None => scene.volume_light_mis(
                                entry.shape,
                                tracer.technique == LightingTechnique::Mis,
                            ),
                        },
                        light_path: role.light_path,
                    },
                    &mut t.answers,
                );
                let elapsed = start.elapsed().as_secs_f64();
                t.hits = ictx.into_scratch();
                stats.record(System::Volume, m, elapsed);
                let answers = &t.answers;
                let bad = count_non_finite(&answers.points.transmission)
                    + count_non_finite(&answers.miss_transmission);
                stats.non_finite(Stage::Volume, bad);
                delegate.finish(stats);
                for (i, s) in t.samplers.iter().enumerate() {
                    t.bundle.dimension[i] = s.dimension;
                }
                // Rays the integrator returned nothing for were absorbed in the volume.
                t.answered.clear();
                t.answered.resize(m, false);
                for &r in t.answers.points.ray_id.iter().chain(&t.answers.misses) {
                    t.answered[r as usize] = true;
                }
                let absorbed = t.answered.iter().filter(|a| !**a).count();
                stats.terminate(Termination::Absorbed, absorbed);
                if !t.answers.emitted.is_empty() {
                    add_emitted(scene, &t.bundle, &t.answers.emitted, batch, stats);
                }
                // Rays walked inside the volume arrive along their walk's last segment.
                t.answers.walked.apply(&mut t.bundle);
                if bad > 0 {
                    // At the depth of the rays as they arrive (after the walk's events).
                    let answers = &t.answers;
                    let points = answers
                        .points
                        .ray_id
                        .iter()
                        .zip(&answers.points.transmission);
                    let misses = answers.misses.iter().zip(&answers.miss_transmission);
                    for (&r, _) in points.chain(misses).filter(|(_, tr)| !tr.is_finite()) {
                        let r = r as usize;
                        non_finite_case(
                            stats,
                            &batch.paths,
                            t.bundle.path[r],
                            t.bundle.depth[r],
                            Stage::Volume,
                            Some(entry.material),
                        );
                    }
                }
            }
        }
        t.bundle_start = hits.incoming.len();
        append(hits, &mut t.answers, &mut t.bundle);
    }
    t.runs = runs;
}
