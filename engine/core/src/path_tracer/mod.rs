//! The path tracer: a loop of stages over typed queues (pbrt-v4's wavefront integrator is the
//! model), one file per stage.
//!
//! | stage | file | reads | writes |
//! |---|---|---|---|
//! | generate | `generate.rs` | the batch's paths | [`RayQueue`] (camera rays) |
//! | trace | `trace.rs` | [`RayQueue`] | [`HitQueue`], [`EscapedRayQueue`]; volume integrators may queue shadow rays through the lighting delegate |
//! | escaped | `escaped.rs` | [`EscapedRayQueue`] | path radiance (environment) |
//! | pass-through | `pass_through.rs` | [`HitQueue`] | [`RayQueue`] (rays past index-matched and false boundaries) |
//! | shade | `shade.rs` | one group of the [`HitQueue`] | emission, AOVs, the vertex's samplers, Bxdf samples |
//! | direct lighting | `direct_lighting.rs` | the group, its Bxdf | [`ShadowRayQueue`] |
//! | continue | `continuation.rs` | the group, its Bxdf samples | the next bounce's [`RayQueue`] |
//! | transmission | `transmission.rs` | [`ShadowRayQueue`] | path radiance |
//!
//! Splatting the finished paths is the tile loop's ([`crate::integrator::render_tile`]).
//! Stages a scene does not need are never entered: partitioning and volume integrators only
//! with volumes, pass-throughs only with transmissive surfaces or opacity, the walk of shadow rays
//! through surfaces only where some surface lets them pass ([`Features`](crate::scene::Features)).
//!
//! Depth convention (Mitsuba's `max_depth`): a path of `k` segments has `k - 1` scattering
//! vertices (surface or volume events); emitters seen along segment `k` count only if
//! `k <= max_depth`. Crossings of index-matched and false boundaries are not vertices.

mod continuation;
pub(crate) use continuation::continue_group;
mod direct_lighting;
mod emitters;
pub(crate) use emitters::hit_prim;
mod escaped;
mod generate;
mod pass_through;
pub mod queues;
mod recorder;
mod shade;
mod shading_normals;
pub(crate) use shading_normals::{discard_bxdf_samples, sides_agree};
mod surface_caches;
mod trace;
pub(crate) use trace::TraceRole;
mod transmission;
pub mod visible_emitters;

use crate::integrator::{Integrator, LightingTechnique, PathBatch};
pub use crate::path_record::{
    BxdfSampleRecord, LightSampleRecord, PathTrace, ShadowRayRecord, TraceSegment, TraceVertex,
    VertexEvent,
};
use crate::plugin::PatternCounters;
use crate::scene::CompiledScene;
use crate::stats::{NonFiniteEvent, Stage, SystemStats};
use bumpalo::Bump;
pub use direct_lighting::DirectLighting;
use queues::*;
use recorder::Recorder;
use risotto_components::Paths;
use risotto_systems::independent_sampler::INDEPENDENT_BIT;
use surface_caches::SurfaceCaches;

/// Sampler dimensions each scattering vertex reserves: light position (0, 1), light selection
/// (2), Russian roulette (3), Bxdf (4..8). Paths start at a multiple of 4, so each group of
/// four is one aligned set of the sampler (one SIMD Sobol evaluation), and the 2D samples
/// (light position, the Bxdf's first two) take the set's first two dimensions, Sobol's
/// best-stratified pair.
pub const DIMS_PER_VERTEX: u32 = 8;

/// The path tracer.
#[derive(Clone, Copy, Debug, Default)]
pub struct PathTracer {
    /// Direct-lighting technique.
    pub technique: LightingTechnique,
    /// Technique choices handed to volume integrators.
    pub techniques: crate::plugin::PluginTechniques,
    /// The `visible_emitters` technique as it applies to the scene rendered
    /// ([`visible_emitters::for_scene`]).
    pub visible_emitters: visible_emitters::VisibleEmitters,
}

impl Integrator for PathTracer {
    type Worker = Queues;

    fn run_batch(
        &self,
        scene: &CompiledScene,
        batch: &mut PathBatch,
        q: &mut Queues,
        stats: &mut SystemStats,
        arena: &Bump,
    ) {
        // The path-trace recorder, when the batch asks for one (`PathBatch::trace`): it reads
        // the queues between the stages; the stages do not know it.
        let mut rec = batch.trace.take().map(Recorder::new);
        generate::camera_rays(scene, batch, &mut q.rays, stats);
        if self.visible_emitters == visible_emitters::VisibleEmitters::Supersampled {
            visible_emitters::add_extra_samples(scene, batch, &mut q.visible_emitters, stats);
        }
        q.emissive_material.clear();
        q.emissive_material.resize(scene.materials.len(), false);
        for shape in scene.shapes.iter().filter(|s| s.emission.is_some()) {
            q.emissive_material[shape.material as usize] = true;
        }
        let mut first_bounce = true;
        // The batch's pattern counters and the last shade stage's surface caches live in the
        // arena, so the caches can outlive the stage that filled them (`surface_caches`).
        let counters: &PatternCounters = arena.alloc(PatternCounters::default());
        let mut surfaces = SurfaceCaches::default();
        while !q.rays.rays.is_empty() {
            // The last bounce's arrived rays are dead: their rows become the storage the
            // continue stage overwrites with the next rays.
            q.hits.recycle_into(&mut q.next);
            if let Some(r) = &mut rec {
                r.begin_bounce(batch, stats);
            }
            while !q.rays.rays.is_empty() {
                let role = TraceRole::default();
                trace::nearest_hits(
                    self, scene, batch, q, stats, arena, counters, &surfaces, role,
                );
                // Later rounds trace rays past boundaries, which left no shaded point.
                surfaces.clear();
                if let Some(r) = &mut rec {
                    r.traced(scene, q);
                }
                escaped::environment(self, scene, &mut q.escaped, &q.hits, batch, stats);
                if scene.features.transmissive || scene.features.opacity {
                    let (hits, rays) = (&mut q.hits, &mut q.rays);
                    pass_through::boundaries(
                        self, scene, hits, rays, batch, stats, arena, counters,
                    );
                    if let Some(r) = &mut rec {
                        r.passed(q);
                    }
                }
            }
            if let Some(r) = &mut rec {
                r.before_shade(q);
            }
            shade::shade_groups(
                self,
                scene,
                batch,
                q,
                stats,
                arena,
                counters,
                &mut surfaces,
                first_bounce,
            );
            if let Some(r) = &mut rec {
                r.shaded(q);
            }
            let shadow_rays = q.shadow.rays.len();
            transmission::shadow_rays(
                scene,
                self.techniques,
                &mut q.shadow,
                &q.hits.incoming,
                batch,
                stats,
                arena,
            );
            if let Some(r) = &mut rec {
                r.end_bounce(q, shadow_rays, batch, stats);
            }
            std::mem::swap(&mut q.rays, &mut q.next);
            q.next.rays.clear();
            stats.add_rays(q.rays.rays.len());
            first_bounce = false;
        }
        stats.pattern_cache_hits += counters.hits.get();
        stats.pattern_cache_shared += counters.shared.get();
        stats.pattern_evals += counters.evals.get();
        stats.volume_pattern_evals += counters.volume_evals.get();
        batch.trace = rec.map(|r| r.trace);
    }
}

/// The trace stage for other global integrators (`crate::bidir`): traces `q.rays` into
/// `q.hits` and `q.escaped` with `tracer`'s techniques (a `BxdfOnly` tracer offers volume
/// integrators no lighting delegate), no surface caches shared; `role` tells volume
/// integrators whether the rays come from the lights and how the integrator weighs the
/// emission of media it samples as lights.
#[allow(clippy::too_many_arguments, reason = "the stage's inputs, named")]
pub(crate) fn trace_nearest_hits(
    tracer: &PathTracer,
    scene: &CompiledScene,
    batch: &mut PathBatch,
    q: &mut Queues,
    stats: &mut SystemStats,
    arena: &Bump,
    counters: &PatternCounters,
    role: TraceRole<'_>,
) {
    let surfaces = SurfaceCaches::default();
    trace::nearest_hits(
        tracer, scene, batch, q, stats, arena, counters, &surfaces, role,
    );
}

/// The pass-through stage for other global integrators (`crate::bidir`): moves the points
/// of `q.hits` on pass-through boundaries out and queues their rays in `q.rays`.
pub(crate) fn pass_through_boundaries(
    tracer: &PathTracer,
    scene: &CompiledScene,
    q: &mut Queues,
    batch: &mut PathBatch,
    stats: &mut SystemStats,
    arena: &Bump,
    counters: &PatternCounters,
) {
    let (hits, rays) = (&mut q.hits, &mut q.rays);
    pass_through::boundaries(tracer, scene, hits, rays, batch, stats, arena, counters);
}

/// NaN provenance: records that `stage` made a value of path `path` (a row of the batch's
/// `paths`) non-finite at a vertex of depth `depth`, with the material involved where there is
/// one ([`SystemStats::non_finite_event`]). Out of line: it runs only for non-finite values.
#[cold]
#[inline(never)]
pub(crate) fn non_finite_case(
    stats: &mut SystemStats,
    paths: &Paths,
    path: u32,
    depth: u16,
    stage: Stage,
    material: Option<u32>,
) {
    let p = path as usize;
    let (pixel, sample) = (paths.pixel[p], paths.sample[p] & !INDEPENDENT_BIT);
    if stats.wants_non_finite_case((pixel, sample)) {
        stats.non_finite_event(NonFiniteEvent {
            pixel,
            sample,
            depth: depth as u32,
            stage,
            material,
        });
    }
}

impl HitQueue {
    /// Starts a bounce: empties the queue, handing the dead rows of the last bounce's rays to
    /// `next` as storage (`Rays::reuse_rows` then spares writing defaults into them).
    pub(crate) fn recycle_into(&mut self, next: &mut RayQueue) {
        std::mem::swap(&mut self.incoming, &mut next.rays);
        self.incoming.clear();
        self.groups.clear();
        self.examined_groups = 0;
    }
}
