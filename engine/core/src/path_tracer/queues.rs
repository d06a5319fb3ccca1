//! The typed queues between the path tracer's stages, each named by what it holds (pbrt-v4's
//! wavefront `RayQueue`, `EscapedRayQueue`, `ShadowRayQueue`, ...), and the stages' reusable
//! scratch. Everything here lives in the worker across batches: no stage allocates per bounce
//! once the tables have grown, and nothing is moved into the batch arena.

use crate::context::HitScratch;
use crate::shade_groups::ShadeGroups;
use glam::Vec3;
use risotto_components::{Rays, Rgb, ShadingPoints, ShadowRays};
use risotto_systems::bxdf_samples::BxdfSamples;
use risotto_systems::sampler::PathSampler;

/// Rays waiting to be traced: camera rays, the next bounce's rays, or rays continuing past a
/// pass-through boundary.
#[derive(Default)]
pub struct RayQueue {
    /// The rays.
    pub rays: Rays,
}

/// What the trace stage found for the rays of one bounce: shading points grouped by material
/// and mode (surface hits and points inside volumes), and the rays that arrived at them
/// (`groups.points.ray_id` indexes `incoming`).
#[derive(Default)]
pub struct HitQueue {
    /// The rays that produced the points (their throughput already includes pass-throughs).
    pub incoming: Rays,
    /// The points, grouped (contiguous by material and mode).
    pub groups: ShadeGroups,
    /// Pass-through compaction: which points stay in the groups.
    pub(super) keep: Vec<bool>,
    /// Pass-through compaction: number of kept points before each point.
    pub(super) kept_before: Vec<u32>,
    /// Groups the pass-through stage has already examined this bounce (the earlier trace
    /// rounds' groups, which it left holding no pass-through points).
    pub(super) examined_groups: usize,
    /// Pass-through continuation: the rays that go on past their boundary.
    pub(super) going: PassingRays,
    /// Pass-through of surfaces with opacity: the opacity of one group's points.
    pub(super) opacity: Vec<f32>,
}

/// The rays the pass-through stage continues: rows of [`HitQueue::incoming`] and the
/// boundary points (rows of the groups' points) they continue from, in step.
#[derive(Default)]
pub(super) struct PassingRays {
    /// Ray rows.
    pub(super) rays: Vec<u32>,
    /// Point rows.
    pub(super) points: Vec<u32>,
}

/// Rays that left the scene in the last trace round (ids into [`HitQueue::incoming`]) with
/// the transmission of their last segment.
#[derive(Default)]
pub struct EscapedRayQueue {
    /// Ray ids.
    pub ray: Vec<u32>,
    /// Transmission of the escaping segment (volume integrators may attenuate it).
    pub transmission: Vec<Rgb>,
}

/// Shadow rays towards light samples, queued by the shade stage and the lighting delegate,
/// traced by the transmission stage.
#[derive(Default)]
pub struct ShadowRayQueue {
    /// The rays to trace.
    pub rays: ShadowRays,
    /// Storage for the shade stage's rows: the dead rows of the last transmission stage,
    /// overwritten (`ShadowRays::reuse_rows`) and then moved to `rays`.
    pub spare: ShadowRays,
    /// The walk's copy of the contributions in scenes where shadow rays may pass surfaces
    /// or cross volumes (the transmission stage then swaps it into `rays`: the contributions
    /// after transmission are those of the dead rows of `spare` until the next shade stage).
    pub contribution: Vec<Rgb>,
    /// The transmission walk's buffers.
    pub walk: crate::transmission::ShadowWalkScratch,
}

/// Per-group buffers of the shade, direct-lighting and continue stages (overwritten for every
/// group; grown to the largest group).
#[derive(Default)]
pub struct GroupScratch {
    /// Bxdf samples of the group's points.
    pub samples: BxdfSamples,
    /// One sampler per point of the group, at the vertex's dimensions.
    pub samplers: Vec<PathSampler>,
    /// The vertex's first four sampler dimensions (light position, light selection, Russian
    /// roulette) per point; without light sampling only index 3 is drawn.
    pub u4: Vec<[f32; 4]>,
    /// Whether each point may continue its path (the next segment fits in `max_depth`):
    /// light sampling skips the others.
    pub active: Vec<bool>,
    /// Light samples and the Bxdf's response to them.
    pub light: LightBuffers,
    /// Per incoming ray: the first sampler dimension of its shadow rays (the delegate's).
    pub ray_dimension: Vec<u32>,
    /// Albedo AOV of the group's points.
    pub albedo: Vec<Rgb>,
    /// Boundary crossings of continuing rays that corrupted their stacks (shape, event).
    pub stack_errors: Vec<(u32, risotto_components::StackEvent)>,
}

/// The light-sampling columns of one group (direct lighting).
#[derive(Default)]
pub struct LightBuffers {
    /// Direction of each light sample.
    pub wi: Vec<Vec3>,
    /// Distance to each light sample.
    pub distance: Vec<f32>,
    /// Radiance of each light sample.
    pub radiance: Vec<Rgb>,
    /// Pdf of each light sample.
    pub pdf: Vec<f32>,
    /// Whether each light sample is a Dirac light.
    pub delta: Vec<bool>,
    /// Where each light sample's shadow ray stops short of it.
    pub margin: Vec<f32>,
    /// Bxdf value at each light sample's direction.
    pub value: Vec<Rgb>,
    /// Bxdf pdf at each light sample's direction.
    pub eval_pdf: Vec<f32>,
    /// Points that may get a shadow ray.
    pub points: Vec<u32>,
}

/// Buffers of the trace stage (partition into volume bundles, volume integrators,
/// pass-throughs).
#[derive(Default)]
pub struct TraceScratch {
    /// Answers of one `nearest_hits` call before they are appended to the hit queue.
    pub answers: ShadeGroups,
    /// The rays of one volume bundle (moved on to the hit queue's incoming rays when they
    /// are its first).
    pub bundle: Rays,
    /// Where the last bundle's rays start in the hit queue's incoming rays (what the
    /// answers' `walked` rows index from).
    pub bundle_start: usize,
    /// Shading points at the bundle rays' origins, bound to the bundle's volume integrator.
    pub bundle_points: ShadingPoints,
    /// Samplers of the bundle's rays.
    pub samplers: Vec<PathSampler>,
    /// Partition keys (stack id and transmit bit) per ray.
    pub keys: Vec<u32>,
    /// Rays in key order.
    pub order: Vec<u32>,
    /// Runs of `order` with one key.
    pub runs: Vec<(u32, std::ops::Range<usize>)>,
    /// Whether the bundle's integrator answered each ray (unanswered rays were absorbed).
    pub answered: Vec<bool>,
    /// Buffers of the renderer's nearest-hit queries.
    pub hits: HitScratch,
}

/// Everything a path-tracer worker keeps across batches.
#[derive(Default)]
pub struct Queues {
    /// Rays to trace.
    pub rays: RayQueue,
    /// The next bounce's rays (written by the continue stage).
    pub next: RayQueue,
    /// Shading points of the current bounce.
    pub hits: HitQueue,
    /// Escaped rays of the current trace round.
    pub escaped: EscapedRayQueue,
    /// Shadow rays of the current bounce.
    pub shadow: ShadowRayQueue,
    /// Per-group buffers.
    pub group: GroupScratch,
    /// Trace-stage buffers.
    pub trace: TraceScratch,
    /// Whether some emissive shape has the material (per material index): the shade stage
    /// looks for emitters only in the groups of those materials.
    pub emissive_material: Vec<bool>,
    /// The extra camera rays of the directly visible emission (`visible_emitters`).
    pub visible_emitters: super::visible_emitters::VisibleEmitterScratch,
}

/// The first `n` elements of a per-group scratch buffer, grown with `fill` when shorter.
/// The callers overwrite what they read, so the buffer is filled once per size reached
/// rather than cleared and refilled for every group.
#[inline]
pub fn scratch<T: Clone>(v: &mut Vec<T>, n: usize, fill: T) -> &mut [T] {
    if v.len() < n {
        v.resize(n, fill);
    }
    &mut v[..n]
}
