//! Bidirectional global integrators: light tracing, bidirectional path tracing and vertex
//! connection and merging, over the same volume integrators as the path tracer.
//!
//! This is the seed's other kind of global integrator (its example is RenderMan's
//! `PxrVCM`): it offers volume integrators **no lighting delegate**, so media return their
//! scattering points as `VolumeScatter` groups ("the only way to perform volume scattering"
//! then), and it traces paths that start at the lights through the same trace stage
//! (`GetNearestHits(..., isLightPath)`).
//!
//! Each camera sample of a batch gets one light subpath (`light_walk.rs`): a light chosen by
//! power emits a ray, and the subpath scatters as a camera path would, its throughput
//! carrying importance (the adjoint Bxdf). Every vertex with a non-Dirac lobe is stored and
//! connected to the camera (splatted wherever it lands on the film). The camera subpath
//! (`camera_walk.rs`) then, at each vertex, adds the emitter it hit, a light sample, and a
//! connection to every stored vertex of its own light subpath. The strategies are weighted
//! with the power heuristic over all of them ([`mis`]).
//!
//! | strategy (`integrator =`) | camera subpaths | light subpaths | weights |
//! |---|---|---|---|
//! | `light` | first segment only (emitters seen directly) | splatted at every vertex | none needed |
//! | `bdpt` | every strategy | splatted, and connected to | MIS over connections and light tracing |
//! | `vcm` | every strategy, and merging | splatted, connected to, and merged | MIS over all of them |
//!
//! `vcm` renders in iterations ([`Integrator::iteration_paths`]): one sample index of a group
//! of tiles (every pixel, up to [`ITERATION_LIGHT_PATHS`]). The iteration's light pass
//! ([`Integrator::light_pass`]) traces each batch's light subpaths and keeps them; between the
//! passes their vertices are gathered into one table in batch order and hashed
//! ([`merge::MergeVertices`]); the camera pass ([`Integrator::run_batch`]) takes each
//! batch's own light subpaths back for its connections, and every camera vertex merges the
//! vertices of them all (SmallVCM's loop: all light subpaths of an iteration, then all
//! camera subpaths). One sample index an iteration: samples of one pixel never share light
//! vertices, so their merges are independent, as the weights assume.
//!
//! What media and materials do here:
//! - Emissive media that offer a volume light ([`crate::plugin::volume_light`]) are lights
//!   like the others ([`CompiledScene::bidirectional_lights`]): light subpaths start inside
//!   them, camera vertices light-sample them and connect to those subpaths, and what the
//!   camera subpaths' rays gather in them is weighed against every other strategy through
//!   the contract's [`EmissionStrategies`](crate::plugin::EmissionStrategies)
//!   (`volume_emission.rs`). Media that offer none (behind a dielectric, in a turned shape)
//!   are gathered by the camera subpaths alone: `light` shows their glow only where the
//!   camera sees them directly (the `emissive_media_without_lights` feature).
//! - Volume integrators that walk many events per call (`scattering = "walk"`, dense media
//!   inside glass) hand back only the walk's exit: their inner events are not vertices to
//!   connect to, and the weights treat the walk as a chain of Dirac vertices (`walk.rs`,
//!   `forget_walks`). Subsurface interiors are refused ([`Bidirectional::supports`]) and the
//!   render falls back to the path tracer.
//! - The distance-sampling pdfs of media and Russian roulette are not in the MIS weights
//!   (see [`mis`]): the estimate stays unbiased.

mod camera_walk;
mod connect;
pub mod evaluate;
mod light_walk;
pub mod merge;
pub mod mis;
pub mod vertices;
mod volume_emission;
mod walk;

use crate::integrator::{Integrator, PathBatch};
use crate::path_tracer::queues::Queues;
use crate::plugin::{PatternCounters, PluginTechniques};
use crate::scene::CompiledScene;
use crate::stats::{System, SystemStats};
use bumpalo::Bump;
use glam::Vec2;
use merge::MergeVertices;
use mis::{MisFactors, SubpathMis};
use risotto_components::{Rgb, ShadowRays, StackEvent, VolumeStack};
use risotto_systems::bxdf_samples::BxdfSamples;
use risotto_systems::camera::CameraConnection;
use risotto_systems::film::SplatFilm;
use risotto_systems::sampler::PathSampler;
use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, PoisonError, RwLock};
pub use vertices::LightVertices;

/// Seed salt of light subpaths' sampler sequences (decorrelated from their camera sample's).
const LIGHT_SEED_SALT: u32 = 0x9e37_79b9;

/// The first sampler dimension of a light subpath's vertices: the emission draws 0-4.
const WALK_FIRST_DIMENSION: u32 = 8;

/// At most how many light subpaths one iteration of `vcm` traces and merges (its memory
/// bound, [`Integrator::iteration_paths`]; at least one sample index of one tile). Every
/// stored vertex of them is held from the iteration's light pass to its camera pass, at most
/// 250 bytes each (the vertex, [`LightVertices`], and its copy for merging,
/// [`MergeVertices`]), at most `max_depth - 1` of them a subpath: 115 MB at `max_depth = 8`.
pub const ITERATION_LIGHT_PATHS: usize = 1 << 16;

/// The first iteration's merge radius as a fraction of the scene's bounding-sphere radius
/// (SmallVCM's default).
pub const MERGE_RADIUS_FACTOR: f32 = 0.003;

/// How fast the merge radius shrinks (`alpha` of progressive photon mapping, Hachisuka and
/// Jensen 2009; SmallVCM's default).
pub const RADIUS_ALPHA: f32 = 0.75;

/// Which strategies a [`Bidirectional`] integrator combines.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    /// Light tracing: light subpaths splatted at the camera; camera rays only for what
    /// they see directly.
    Light,
    /// Bidirectional path tracing: every connection strategy and light tracing, MIS-weighted.
    Bdpt,
    /// Vertex connection and merging: bidirectional path tracing and, at every camera
    /// vertex, the light vertices of the iteration's light subpaths within a shrinking
    /// radius (Georgiev et al. 2012).
    Vcm,
}

impl Strategy {
    /// The technique name (`integrator = ...`).
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Light => "light",
            Strategy::Bdpt => "bdpt",
            Strategy::Vcm => "vcm",
        }
    }
}

/// One connection strategy alone, unweighted: a check of the strategies one by one (the
/// issue's "each strategy alone, MIS off"). Strategy `(s, t)` joins `s` light vertices (the
/// point on the light counted) and `t` camera vertices (the camera's counted) into a path of
/// `s + t - 1` segments (Veach 1997, sec. 10.2): `s = 0` is a camera subpath that hits the
/// emitter (or gathers a medium's emission), `s = 1` next-event estimation, `t = 1` light
/// tracing, the others connections. Each is an unbiased estimator on its own of the paths
/// it can make, so on a scene where every strategy can make every path (diffuse surfaces, an
/// area light, a pinhole camera), the image of one `(s, t)` alone is the image of the paths
/// of `s + t - 1` segments (pbrt-v4's `visualizestrategies`, without MIS). Merges are
/// dropped. Emission a volume integrator gathers without asking for its weight (after a
/// walk's events) is kept.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StrategyAlone {
    /// `s`: vertices on the light subpath, the light's point counted.
    pub light_vertices: u32,
    /// `t`: vertices on the camera subpath, the camera's counted.
    pub camera_vertices: u32,
}

/// The weight of a contribution of strategy `(s, t)` whose MIS weight is `mis`: `mis` when
/// no strategy is alone; 1 for the strategy alone, 0 for the others.
#[inline]
pub(crate) fn strategy_weight(alone: Option<StrategyAlone>, s: u32, t: u32, mis: f32) -> f32 {
    match alone {
        None => mis,
        Some(a) => (a.light_vertices == s && a.camera_vertices == t) as u32 as f32,
    }
}

/// A bidirectional global integrator.
pub struct Bidirectional {
    /// The strategies combined.
    pub strategy: Strategy,
    /// One strategy alone, unweighted ([`StrategyAlone`]); `None`: all of them, weighted.
    pub alone: Option<StrategyAlone>,
    /// Technique choices handed to volume integrators.
    pub techniques: PluginTechniques,
    /// The volumes each light's subpaths start in.
    light_stacks: Vec<VolumeStack>,
    /// Light subpaths splatted to the camera, over the whole image.
    splats: SplatFilm,
    /// Light subpaths traced so far (the splats' normalisation).
    light_paths: AtomicU64,
    /// Light subpaths per iteration over the image's pixels ([`MisFactors`]).
    light_paths_per_pixel: f32,
    /// The first iteration's merge radius ([`MERGE_RADIUS_FACTOR`]).
    merge_radius: f32,
    /// The iteration in progress (`vcm`): its constants and the light vertices its camera
    /// vertices merge; written between its passes, read by its camera pass.
    iteration: RwLock<Iteration>,
    /// The light subpaths the iteration's light pass traced, by batch ([`batch_key`]),
    /// waiting for their camera pass.
    traced: Mutex<HashMap<(u32, u32), LightVertices>>,
    /// Tables camera passes are done with, for the next light passes.
    spare: Mutex<Vec<LightVertices>>,
}

/// One iteration of `vcm`: a light subpath per camera sample of its batches, traced first,
/// then every camera subpath, merging at its vertices the light vertices of them all.
#[derive(Default)]
struct Iteration {
    /// Its MIS constants.
    factors: MisFactors,
    /// Its merge radius.
    radius: f32,
    /// Every light vertex of its light subpaths.
    vertices: MergeVertices,
}

/// Which batch a batch is, the same in an iteration's two passes: its first path's pixel
/// and sample address (a tile's batches are its pixels over disjoint sample ranges).
fn batch_key(batch: &PathBatch) -> (u32, u32) {
    let p = &batch.paths;
    (
        p.pixel.first().copied().unwrap_or(u32::MAX),
        p.sample.first().copied().unwrap_or(u32::MAX),
    )
}

impl Bidirectional {
    /// The integrator for `scene`, rendering the pixels `window_pixels` of its image per
    /// sample index (light subpaths per iteration); `Err` when its splat film cannot be
    /// allocated.
    pub fn new(
        scene: &CompiledScene,
        strategy: Strategy,
        techniques: PluginTechniques,
        window_pixels: usize,
    ) -> Result<Self, String> {
        let (w, h) = (scene.camera.width, scene.camera.height);
        let light_stacks = scene
            .bidirectional_lights()
            .lights()
            .iter()
            .map(|l| light_stack(scene, l))
            .collect();
        let splats = SplatFilm::new(w, h)
            .ok_or_else(|| format!("a {w} x {h} splat film cannot be allocated"))?;
        Ok(Bidirectional {
            strategy,
            alone: None,
            techniques,
            light_stacks,
            splats,
            light_paths: AtomicU64::new(0),
            light_paths_per_pixel: window_pixels as f32 / (w as f32 * h as f32),
            merge_radius: MERGE_RADIUS_FACTOR * scene.radius,
            iteration: RwLock::default(),
            traced: Mutex::default(),
            spare: Mutex::default(),
        })
    }

    /// Whether this integrator can render `scene`; `Err` says why not (a volume integrator
    /// that walks many events per call, whose inner vertices no strategy can connect to).
    pub fn supports(scene: &CompiledScene) -> Result<(), String> {
        if scene.features.subsurface {
            return Err(
                "subsurface interiors walk inside the surface in one call; their \
                        inner scattering events are not vertices a bidirectional \
                        integrator can connect to"
                    .into(),
            );
        }
        Ok(())
    }

    /// The MIS constants of a `vcm` iteration of `paths` camera samples at sample index
    /// `sample`, and its merge radius. Progressive merging (Hachisuka and Jensen 2009;
    /// Georgiev et al. 2012, sec. 5): the radius shrinks as `r_i = r_0 / (i + 1)^((1 -
    /// alpha) / 2)`, so the merged estimate's bias vanishes as its variance does.
    fn iteration_factors(&self, paths: usize, sample: u32) -> (MisFactors, f32) {
        let i = sample as f32;
        let r = self.merge_radius / (i + 1.0).powf(0.5 * (1.0 - RADIUS_ALPHA));
        (
            MisFactors::vcm(r, paths as f32, self.light_paths_per_pixel),
            r,
        )
    }

    /// The iteration in progress (read-locked), its constants set into `s`.
    fn iteration_into(&self, s: &mut Scratch) -> std::sync::RwLockReadGuard<'_, Iteration> {
        let it = self
            .iteration
            .read()
            .unwrap_or_else(PoisonError::into_inner);
        s.factors = it.factors;
        s.merge_radius = it.radius;
        it
    }

    /// The volumes subpaths of light `light` start in.
    fn light_stack(&self, light: u32) -> &VolumeStack {
        &self.light_stacks[light as usize]
    }

    fn splat_film(&self) -> &SplatFilm {
        &self.splats
    }

    /// The light-traced image so far: pixel sums over the whole image and the factor that
    /// makes them radiance (`width * height / light subpaths`).
    pub fn splats(&self) -> (&SplatFilm, f64) {
        let n = self.light_paths.load(Ordering::Relaxed).max(1) as f64;
        let (w, h) = (self.splats.width() as f64, self.splats.height() as f64);
        (&self.splats, w * h / n)
    }
}

/// The volumes a light's subpaths start in: probed from a point of the light (its centre
/// for lights with a position; outside everything for lights at infinity). Subpaths from a
/// volume light probe their own start points (`light_walk.rs`).
fn light_stack(scene: &CompiledScene, light: &risotto_systems::lights::Light) -> VolumeStack {
    use risotto_systems::lights::Light;
    match light {
        Light::Point { position, .. } | Light::Spot { position, .. } => {
            scene.probe_stack(*position, glam::Vec3::Z)
        }
        Light::Area { prim, .. } => {
            let s = scene.geometry.sample_surface(*prim, Vec2::splat(0.5));
            // Just off the emitting side: an emitter on a medium's boundary emits into it.
            let offset = s.ng * (s.ng.abs().dot(s.p_error) * 4.0 + 1e-4 * s.p.abs().max_element());
            scene.probe_stack(s.p + offset, s.ng)
        }
        _ => VolumeStack::default(),
    }
}

/// What a worker keeps across batches.
#[derive(Default)]
pub struct BidirWorker {
    /// The light subpaths of the batch, one per camera sample.
    light_batch: PathBatch,
    /// The light subpaths' queues (the path tracer's).
    light_q: Queues,
    /// The camera subpaths' queues.
    camera_q: Queues,
    /// The batch's stored light vertices.
    light: LightVertices,
    /// Per-stage buffers.
    s: Scratch,
}

/// The stages' buffers.
#[derive(Default)]
pub(crate) struct Scratch {
    /// The batch's MIS constants.
    factors: MisFactors,
    /// The batch's merge radius (0 without merging).
    merge_radius: f32,
    /// The strategy alone, if any ([`Bidirectional::alone`]).
    alone: Option<StrategyAlone>,
    /// Per camera vertex of a group: the light vertices to merge.
    merges: Vec<(u32, u32)>,
    /// MIS sums of every subpath of the walk in progress.
    mis: Vec<SubpathMis>,
    /// Light subpaths from lights at infinity.
    at_infinity: Vec<bool>,
    /// Light subpaths from emissive media.
    in_volume_light: Vec<bool>,
    /// Rays that left the scene this bounce, with their last transmission.
    escaped: Vec<(u32, Rgb)>,
    /// Each path's ray depth as it was sent to the trace stage (walks add to it).
    sent_depth: Vec<u16>,
    samplers: Vec<PathSampler>,
    u4: Vec<[f32; 4]>,
    samples: BxdfSamples,
    group_eval: evaluate::GroupEvaluations,
    pair_eval: evaluate::GroupEvaluations,
    eval_rows: Vec<(u32, u32)>,
    /// Per-point query columns of a group (viewer and light directions) and answers.
    view: Vec<glam::Vec3>,
    wi: Vec<glam::Vec3>,
    value: Vec<Rgb>,
    pdf: Vec<f32>,
    /// Per point of a group: its light sample (`u32::MAX`: none).
    hit_of: Vec<u32>,
    /// Per light bounce: the connections of this camera bounce waiting for their light side.
    pending: Vec<Vec<connect::PendingConnection>>,
    /// One light bounce's rows: directions, a copy, answers.
    layer_wi: Vec<glam::Vec3>,
    layer_copy: risotto_components::ShadingPoints,
    layer_value: Vec<Rgb>,
    layer_pdf: Vec<f32>,
    layer_pdf_fwd: Vec<f32>,
    camera_hits: Vec<CameraConnection>,
    light_hits: Vec<connect::LightHit>,
    /// Light vertices connected to the camera, and where on the film.
    splats: ShadowRays,
    splat_film_pos: Vec<Vec2>,
    splat_contribution: Vec<Rgb>,
    /// Camera vertices' light samples and connections.
    connections: ShadowRays,
    connection_contribution: Vec<Rgb>,
    stack_errors: Vec<(u32, StackEvent)>,
    albedo: Vec<Rgb>,
}

impl Integrator for Bidirectional {
    type Worker = BidirWorker;

    fn run_batch(
        &self,
        scene: &CompiledScene,
        batch: &mut PathBatch,
        worker: &mut BidirWorker,
        stats: &mut SystemStats,
        arena: &Bump,
    ) {
        let counters: &PatternCounters = arena.alloc(PatternCounters::default());
        worker.s.alone = self.alone;
        let traced = match self.strategy {
            Strategy::Vcm => lock(&self.traced).remove(&batch_key(batch)),
            _ => None,
        };
        match traced {
            // The camera pass of an iteration: this batch's light subpaths were traced by
            // its light pass, and every camera vertex merges the iteration's light vertices.
            Some(mut light) => {
                std::mem::swap(&mut worker.light, &mut light);
                lock(&self.spare).push(light);
                let it = self.iteration_into(&mut worker.s);
                let merge = Some(&it.vertices);
                camera_walk::camera_subpaths(
                    self, scene, batch, worker, merge, stats, arena, counters,
                );
            }
            // A batch of its own (`light`, `bdpt`; `vcm` only when run outside the renderer's
            // iterations, then without merging, as `bdpt`: one batch's light vertices merged
            // at several samples of a pixel would be correlated): its light subpaths, then its
            // camera subpaths.
            None => {
                worker.s.factors = MisFactors::connections_only(self.light_paths_per_pixel);
                worker.s.merge_radius = 0.0;
                light_walk::light_subpaths(self, scene, batch, worker, stats, arena, counters);
                self.light_paths
                    .fetch_add(batch.paths.len() as u64, Ordering::Relaxed);
                camera_walk::camera_subpaths(
                    self, scene, batch, worker, None, stats, arena, counters,
                );
            }
        }
        add_pattern_counters(stats, counters);
    }

    fn splats(&self) -> Option<(&SplatFilm, f64)> {
        Some(Bidirectional::splats(self))
    }

    /// `vcm` merges across the batches of an iteration; the others need no iterations.
    fn iteration_paths(&self) -> Option<usize> {
        (self.strategy == Strategy::Vcm).then_some(ITERATION_LIGHT_PATHS)
    }

    fn begin_iteration(&self, sample: u32, camera_samples: usize) {
        let mut it = self
            .iteration
            .write()
            .unwrap_or_else(PoisonError::into_inner);
        (it.factors, it.radius) = self.iteration_factors(camera_samples, sample);
        it.vertices.clear();
    }

    fn light_pass(
        &self,
        scene: &CompiledScene,
        batch: &PathBatch,
        worker: &mut BidirWorker,
        stats: &mut SystemStats,
        arena: &Bump,
    ) {
        let counters: &PatternCounters = arena.alloc(PatternCounters::default());
        drop(self.iteration_into(&mut worker.s));
        worker.s.alone = self.alone;
        let mut light = lock(&self.spare).pop().unwrap_or_default();
        std::mem::swap(&mut worker.light, &mut light);
        light_walk::light_subpaths(self, scene, batch, worker, stats, arena, counters);
        std::mem::swap(&mut worker.light, &mut light);
        self.light_paths
            .fetch_add(batch.paths.len() as u64, Ordering::Relaxed);
        lock(&self.traced).insert(batch_key(batch), light);
        add_pattern_counters(stats, counters);
    }

    /// Gathers the iteration's light vertices for merging, in batch order (so the image
    /// does not depend on which thread traced which batch), and hashes them.
    fn end_light_pass(&self, stats: &mut SystemStats) {
        let start = std::time::Instant::now();
        let traced = lock(&self.traced);
        let mut keys: Vec<_> = traced.keys().copied().collect();
        keys.sort_unstable();
        let mut it = self
            .iteration
            .write()
            .unwrap_or_else(PoisonError::into_inner);
        let it = &mut *it;
        it.vertices.clear();
        for k in keys {
            it.vertices.extend_from(&traced[&k]);
        }
        it.vertices.build(it.radius.max(f32::MIN_POSITIVE));
        let seconds = start.elapsed().as_secs_f64();
        stats.record(System::Merge, it.vertices.len(), seconds);
    }
}

/// Adds a batch's pattern counters to the stats.
fn add_pattern_counters(stats: &mut SystemStats, counters: &PatternCounters) {
    stats.pattern_cache_hits += counters.hits.get();
    stats.pattern_cache_shared += counters.shared.get();
    stats.pattern_evals += counters.evals.get();
    stats.volume_pattern_evals += counters.volume_evals.get();
}

/// `m` locked; one a panicking thread poisoned is as good (plain tables).
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}
