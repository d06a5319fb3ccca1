//! Render statistics: per-system call/item/time counters, ray and sample counts, path
//! termination reasons.
//!
//! Workers each own a [`SystemStats`] (plain arrays indexed by enum discriminants: no locks,
//! no hashing on the hot path) and the scheduler [`merge`](SystemStats::merge)s them into a
//! [`RenderStats`] at the end. [`RenderStats`] serialises to this JSON:
//!
//! ```json
//! {"systems": {"intersect": {"calls": 12, "items": 4096, "seconds": 0.01}},
//!  "rays": 4096, "samples": 1024, "terminated": {"escaped": 900, "max_depth": 124},
//!  "nan_dropped": 0, "wall_seconds": 1.5, "features": ["volumes"]}
//! ```
//!
//! Systems that never ran (zero calls) and termination reasons with a zero count are left
//! out; a `"warnings": [...]` array is appended only when there are warnings, and a
//! `"run": {...}` object ([`RunInfo`]: version, commit, resolution, window, spp, samples,
//! threads, load / build / render seconds, peak resident bytes) when the driver set it.
//!
//! NaN provenance: each stage checks the values it produced (one pass over a column it has
//! just written) and counts the non-finite ones by [`Stage`]; values that are non-finite
//! only because their input was (a path throughput poisoned upstream) are not counted again,
//! so each count names where a NaN or infinity first appeared. When any is non-zero the JSON
//! has `"non_finite": {"bxdf": 3, "volume": 1}` (zero counts left out) and the summary a
//! `non-finite values by stage:` line. A NaN or infinite Bxdf or phase weight ends its path
//! (counted as absorbed) and other non-finite radiance is dropped at the film
//! (`nan_dropped`), so these counts say where a silent loss or a dropped sample came from.
//!
//! Besides the counts, the first few cases are kept ([`MAX_NON_FINITE_CASES`], the camera
//! samples with the smallest `(pixel index, sample index)`, each at its shallowest event):
//! pixel, sample, path depth, stage, material (where the stage has one) and seed, in the
//! JSON as
//!
//! ```json
//! "non_finite_cases": [{"x": 9, "y": 7, "sample": 2, "depth": 0, "stage": "bxdf",
//!                       "material": "ball", "seed": 0,
//!                       "replay": "risotto render scene.toml --replay 9,7,2"}]
//! ```
//!
//! and as one `non-finite sample:` line each in the summary, ending in the command that
//! re-runs that one path and prints its vertices ([`crate::replay`]).
//!
//! Which systems appear shows which stages a scene needed: without volumes there is no
//! `partition` or `volume`; shadow rays of scenes whose surfaces are all opaque (no volumes,
//! no transmissive surface, no surface that lets shadows pass) are answered by one any-hit
//! query each and counted under `occlusion`, while shadow rays that must walk through
//! surfaces use closest-hit queries counted under `intersect`. Times of nested systems
//! (`intersect`/`occlusion`/`volume` inside `transmission`, `bxdf`/`lights` inside `shade`)
//! are counted in both.

use std::path::Path;
use std::time::Instant;

/// A system whose work is timed. The discriminant indexes [`SystemStats::systems`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum System {
    /// Camera ray generation.
    Camera,
    /// Closest-hit ray-scene intersection (camera and continuation rays, shadow rays that
    /// walk through surfaces).
    Intersect,
    /// Building shading points from hits.
    Shade,
    /// Surface and phase-function sampling/evaluation.
    Bxdf,
    /// Light sampling and MIS.
    Lights,
    /// Shadow-ray transmission (visibility and transmittance).
    Transmission,
    /// Any-hit shadow-ray queries of the transmission system's fast path (scenes whose
    /// surfaces are all opaque and that have no volumes); never runs otherwise.
    Occlusion,
    /// Partitioning/grouping rays (transmit/reflect, by volume).
    Partition,
    /// Volume tracking and volume integrators.
    Volume,
    /// Phase-function sampling and evaluation at points inside scattering media (the
    /// volume-scatter shade groups); never runs in scenes without scattering media.
    Phase,
    /// Splatting samples into the film.
    Splat,
    /// Light subpaths leaving the lights (emission sampling); never runs under the path
    /// tracer.
    Emit,
    /// Connections of bidirectional integrators: light vertices to the camera, camera
    /// vertices to light samples and to light vertices (the Bxdf evaluations and MIS
    /// weights; their shadow rays count as transmission); never runs under the path tracer.
    Connect,
    /// Vertex merging (`integrator = vcm`): hashing the light vertices and gathering them
    /// at camera vertices; never runs otherwise.
    Merge,
}

impl System {
    /// Number of systems.
    pub const COUNT: usize = 14;
    /// Every system, in discriminant order.
    pub const ALL: [System; System::COUNT] = [
        System::Camera,
        System::Intersect,
        System::Shade,
        System::Bxdf,
        System::Lights,
        System::Transmission,
        System::Occlusion,
        System::Partition,
        System::Volume,
        System::Phase,
        System::Splat,
        System::Emit,
        System::Connect,
        System::Merge,
    ];

    /// The lower-case name used in JSON and in the summary table.
    pub const fn name(self) -> &'static str {
        match self {
            System::Camera => "camera",
            System::Intersect => "intersect",
            System::Shade => "shade",
            System::Bxdf => "bxdf",
            System::Lights => "lights",
            System::Transmission => "transmission",
            System::Occlusion => "occlusion",
            System::Partition => "partition",
            System::Volume => "volume",
            System::Phase => "phase",
            System::Splat => "splat",
            System::Emit => "emit",
            System::Connect => "connect",
            System::Merge => "merge",
        }
    }
}

/// What happened to a ray's free flight in a medium. The discriminant indexes
/// [`SystemStats::volume_events`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum VolumeEvent {
    /// A real scattering event (a point inside the medium was shaded or lit).
    Scatter,
    /// A fictitious (null) collision of a tracking estimator.
    Null,
    /// The path was absorbed in the medium.
    Absorbed,
    /// The flight passed its segment (left the medium or reached a surface inside it).
    Pass,
    /// A medium's emission was gathered along a segment: a path ray's (or a random-walk
    /// step's) in an emissive medium, or a shadow-ray interval whose emission is added.
    /// Zero in scenes without emissive media, where that code never runs.
    Emission,
    /// A light sample of a volume emitter (next-event estimation towards an emissive
    /// medium, [`crate::plugin::volume_light`]). Zero in scenes without the
    /// `emissive_volume_lights` feature.
    LightSample,
    /// A scattering event where the medium's free flights can no longer move the point
    /// ([`flights_frozen`](risotto_systems::medium::flights_frozen): its mean free path is
    /// far below the float spacing of the coordinates there): the path ended (absorbed),
    /// and the summary warns.
    Frozen,
}

impl VolumeEvent {
    /// Number of kinds.
    pub const COUNT: usize = 7;
    /// Every kind, in discriminant order.
    pub const ALL: [VolumeEvent; VolumeEvent::COUNT] = [
        VolumeEvent::Scatter,
        VolumeEvent::Null,
        VolumeEvent::Absorbed,
        VolumeEvent::Pass,
        VolumeEvent::Emission,
        VolumeEvent::LightSample,
        VolumeEvent::Frozen,
    ];
    /// The snake_case name used in JSON and in the summary.
    pub const fn name(self) -> &'static str {
        match self {
            VolumeEvent::Scatter => "scatter",
            VolumeEvent::Null => "null",
            VolumeEvent::Absorbed => "absorbed",
            VolumeEvent::Pass => "pass",
            VolumeEvent::Emission => "emission",
            VolumeEvent::LightSample => "light_sample",
            VolumeEvent::Frozen => "frozen",
        }
    }
}

/// Why a path stopped. The discriminant indexes [`SystemStats::terminated`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Termination {
    /// Left the scene (missed all geometry; environment light, if any, was added).
    Escaped,
    /// Throughput became exactly zero (black surface, zero-weight sample, opaque medium).
    Absorbed,
    /// Killed by Russian roulette.
    RussianRoulette,
    /// Reached the maximum path depth.
    MaxDepth,
    /// Ran out of the per-pass continuation budget.
    PassLimit,
    /// Throughput became NaN or infinite; the path was dropped.
    NonFinite,
    /// Reached the most scattering vertices a path can have
    /// ([`MAX_PATH_VERTICES`](risotto_systems::path::MAX_PATH_VERTICES)) with a `max_depth`
    /// that let it go on: light that cannot leave a region (the summary warns).
    DepthLimit,
}

impl Termination {
    /// Number of reasons.
    pub const COUNT: usize = 7;
    /// Every reason, in discriminant order.
    pub const ALL: [Termination; Termination::COUNT] = [
        Termination::Escaped,
        Termination::Absorbed,
        Termination::RussianRoulette,
        Termination::MaxDepth,
        Termination::PassLimit,
        Termination::NonFinite,
        Termination::DepthLimit,
    ];

    /// The snake_case name used in JSON and in the summary table.
    pub const fn name(self) -> &'static str {
        match self {
            Termination::Escaped => "escaped",
            Termination::Absorbed => "absorbed",
            Termination::RussianRoulette => "russian_roulette",
            Termination::MaxDepth => "max_depth",
            Termination::PassLimit => "pass_limit",
            Termination::NonFinite => "non_finite",
            Termination::DepthLimit => "depth_limit",
        }
    }
}

mod bidir_rays;
mod non_finite;
pub use bidir_rays::BidirRays;
pub use non_finite::*;

/// Counters of one system.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SystemCounter {
    /// Number of (batched) invocations.
    pub calls: u64,
    /// Items processed over all calls (rays, shading points, samples...).
    pub items: u64,
    /// Wall time spent inside the system, summed over workers.
    pub seconds: f64,
}

impl SystemCounter {
    fn add(&mut self, o: &SystemCounter) {
        self.calls += o.calls;
        self.items += o.items;
        self.seconds += o.seconds;
    }
}

/// Per-worker accumulator. Cheap to update: every counter is a fixed array slot.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SystemStats {
    /// Counters indexed by `System as usize`.
    pub systems: [SystemCounter; System::COUNT],
    /// Rays traced (camera, continuation and shadow rays).
    pub rays: u64,
    /// Camera samples completed.
    pub samples: u64,
    /// Path terminations indexed by `Termination as usize`.
    pub terminated: [u64; Termination::COUNT],
    /// Samples dropped at the film because they were NaN or infinite.
    pub nan_dropped: u64,
    /// Non-finite values by the stage that produced them, indexed by `Stage as usize`.
    pub non_finite: [u64; Stage::COUNT],
    /// The first non-finite cases: at most [`MAX_NON_FINITE_CASES`], one per camera sample
    /// (its shallowest event), those of the smallest [`NonFiniteEvent::key`]s seen, sorted by
    /// key. Filled by [`non_finite_event`](Self::non_finite_event).
    pub non_finite_events: Vec<NonFiniteEvent>,
    /// Per shape index: rays that crossed a back face of the shape without having entered it
    /// (a hint that its boundary is not closed). Grown on demand.
    pub unmatched_exits: Vec<u64>,
    /// Per shape index: rays that crossed a front face of the shape while already inside it.
    pub entered_twice: Vec<u64>,
    /// Per shape index: rays that left the scene while their stack said they were inside the
    /// shape (innermost volume).
    pub escaped_inside: Vec<u64>,
    /// Volume events indexed by `VolumeEvent as usize`.
    pub volume_events: [u64; VolumeEvent::COUNT],
    /// Pattern-cache lookups answered from a shading context's cache.
    pub pattern_cache_hits: u64,
    /// Parameter columns an interior's context took from the cache of the surface its rays
    /// left from (the seed's shared pattern cache: not evaluated again); not in
    /// `pattern_evals`.
    pub pattern_cache_shared: u64,
    /// Parameter evaluations (pattern-cache misses).
    pub pattern_evals: u64,
    /// Of `pattern_evals`, the patterns volumes evaluated (medium coefficients, point by
    /// point): 0 in a scene without pattern-driven media.
    pub volume_pattern_evals: u64,
    /// Sampled extinctions above their majorant's bound (heterogeneous media): 0 when the
    /// bounds are right. The estimators stay finite but lose their guarantees: reported,
    /// never clamped silently.
    pub majorant_violations: u64,
    /// Majorant segments on which null-collision tracking would have taken more than
    /// `risotto_systems::tracking::dense::TRACKING_CAP` tentative collisions (a majorant
    /// cell of extreme bound, e.g. one voxel far denser than its neighbours), integrated
    /// exactly instead (unbiased, bounded work): 0 in ordinary media.
    pub dense_segments: u64,
    /// The density lookups of `dense_segments`' exact integrals (two per voxel piece, and
    /// two per bisection step locating a collision).
    pub dense_lookups: u64,
    /// Tentative collisions (density lookups) of the transmittance estimators of shadow
    /// rays in heterogeneous media (the free flights' are the `null` volume events): with
    /// them, the tracking work of a render.
    pub shadow_collisions: u64,
    /// Surface hits on meshes with the shadow-terminator offset whose rays to the viewer's
    /// side leave from the smooth surface, above the flat triangle
    /// (`risotto_systems::terminator`): 0, and not reported, in scenes without such meshes.
    pub terminator_lifts: u64,
    /// Path-ray hits on surfaces with opacity whose opacity was tested (stochastic
    /// pass-through, [`InstanceHints::OPACITY`](crate::plugin::InstanceHints::OPACITY)): 0
    /// in a scene without opacity, where no opacity stage runs.
    pub opacity_tests: u64,
    /// Of `opacity_tests`, the hits the ray passed through.
    pub opacity_passes: u64,
    /// Shadow-ray crossings of surfaces with opacity (each attenuates by `1 - opacity`).
    pub opacity_shadow_crossings: u64,
    /// Rays of a bidirectional integrator's subpaths that a volume integrator walked
    /// through many events in one call (whose inner events no strategy connects to): 0 under
    /// the path tracer and where no medium walks.
    pub walked_subpath_rays: u64,
    /// A bidirectional integrator's rays by kind (0 under the path tracer).
    pub bidir_rays: BidirRays,
}

/// Adds 1 to `v[i]`, growing `v`.
fn count_at(v: &mut Vec<u64>, i: u32) {
    let i = i as usize;
    if v.len() <= i {
        v.resize(i + 1, 0);
    }
    v[i] += 1;
}

/// Adds `b` into `a` element by element, growing `a`.
fn add_counts(a: &mut Vec<u64>, b: &[u64]) {
    if a.len() < b.len() {
        a.resize(b.len(), 0);
    }
    for (a, b) in a.iter_mut().zip(b) {
        *a += b;
    }
}

impl SystemStats {
    /// Empty counters.
    pub fn new() -> Self {
        Self::default()
    }

    /// Records a crossing of `shape`'s back face by a ray that was not inside it.
    pub fn unmatched_exit(&mut self, shape: u32) {
        count_at(&mut self.unmatched_exits, shape);
    }

    /// Records a crossing of `shape`'s front face by a ray already inside it.
    pub fn entered_twice(&mut self, shape: u32) {
        count_at(&mut self.entered_twice, shape);
    }

    /// Counts `n` volume events of kind `event`.
    #[inline]
    pub fn volume_event(&mut self, event: VolumeEvent, n: usize) {
        self.volume_events[event as usize] += n as u64;
    }

    /// Records a ray that escaped the scene while inside `shape`'s volume.
    pub fn escaped_inside(&mut self, shape: u32) {
        count_at(&mut self.escaped_inside, shape);
    }

    /// Runs `f`, recording one call of `sys` over `items` items and the elapsed wall time.
    #[inline]
    pub fn time<R>(&mut self, sys: System, items: usize, f: impl FnOnce() -> R) -> R {
        let start = Instant::now();
        let r = f();
        self.record(sys, items, start.elapsed().as_secs_f64());
        r
    }

    /// Records one call of `sys` over `items` items that took `seconds`.
    #[inline]
    pub fn record(&mut self, sys: System, items: usize, seconds: f64) {
        let c = &mut self.systems[sys as usize];
        c.calls += 1;
        c.items += items as u64;
        c.seconds += seconds;
    }

    /// Counts `n` traced rays.
    #[inline]
    pub fn add_rays(&mut self, n: usize) {
        self.rays += n as u64;
    }

    /// Counts `n` completed camera samples.
    #[inline]
    pub fn add_samples(&mut self, n: usize) {
        self.samples += n as u64;
    }

    /// Counts `n` paths that stopped for `reason`.
    #[inline]
    pub fn terminate(&mut self, reason: Termination, n: usize) {
        self.terminated[reason as usize] += n as u64;
    }

    /// Counts `n` non-finite samples dropped at the film.
    #[inline]
    pub fn drop_nan(&mut self, n: usize) {
        self.nan_dropped += n as u64;
    }

    /// Counts `n` non-finite values produced by `stage`.
    #[inline]
    pub fn non_finite(&mut self, stage: Stage, n: usize) {
        self.non_finite[stage as usize] += n as u64;
    }

    /// Whether an event of camera sample `key` (pixel, sample) would be kept by
    /// [`non_finite_event`](Self::non_finite_event): a cheap test before gathering what
    /// the event needs.
    #[inline]
    pub fn wants_non_finite_case(&self, key: (u32, u32)) -> bool {
        self.non_finite_events.len() < MAX_NON_FINITE_CASES
            || self
                .non_finite_events
                .last()
                .is_some_and(|e| key <= e.key())
    }

    /// Records a non-finite case: kept when its camera sample is among the
    /// [`MAX_NON_FINITE_CASES`] smallest keys seen; a camera sample keeps its shallowest event
    /// (then the earliest stage). The result depends only on the set of events recorded, not
    /// on their order, so merging workers' stats keeps the same cases whatever the threads.
    pub fn non_finite_event(&mut self, event: NonFiniteEvent) {
        let v = &mut self.non_finite_events;
        match v.binary_search_by_key(&event.key(), NonFiniteEvent::key) {
            Ok(i) => {
                if event.rank() < v[i].rank() {
                    v[i] = event;
                }
            }
            Err(i) if i < MAX_NON_FINITE_CASES => {
                v.insert(i, event);
                v.truncate(MAX_NON_FINITE_CASES);
            }
            Err(_) => {}
        }
    }

    /// Counters of one system.
    pub fn system(&self, sys: System) -> &SystemCounter {
        &self.systems[sys as usize]
    }

    /// Adds another worker's counters into these.
    pub fn merge(&mut self, other: &Self) {
        for (a, b) in self.systems.iter_mut().zip(&other.systems) {
            a.add(b);
        }
        self.rays += other.rays;
        self.samples += other.samples;
        for (a, b) in self.terminated.iter_mut().zip(&other.terminated) {
            *a += b;
        }
        self.nan_dropped += other.nan_dropped;
        self.majorant_violations += other.majorant_violations;
        self.dense_segments += other.dense_segments;
        self.dense_lookups += other.dense_lookups;
        self.shadow_collisions += other.shadow_collisions;
        self.terminator_lifts += other.terminator_lifts;
        for (a, b) in self.non_finite.iter_mut().zip(&other.non_finite) {
            *a += b;
        }
        for &e in &other.non_finite_events {
            self.non_finite_event(e);
        }
        add_counts(&mut self.unmatched_exits, &other.unmatched_exits);
        add_counts(&mut self.entered_twice, &other.entered_twice);
        add_counts(&mut self.escaped_inside, &other.escaped_inside);
        for (a, b) in self.volume_events.iter_mut().zip(&other.volume_events) {
            *a += b;
        }
        self.pattern_cache_hits += other.pattern_cache_hits;
        self.pattern_cache_shared += other.pattern_cache_shared;
        self.pattern_evals += other.pattern_evals;
        self.volume_pattern_evals += other.volume_pattern_evals;
        self.opacity_tests += other.opacity_tests;
        self.walked_subpath_rays += other.walked_subpath_rays;
        self.bidir_rays.merge(&other.bidir_rays);
        self.opacity_passes += other.opacity_passes;
        self.opacity_shadow_crossings += other.opacity_shadow_crossings;
    }
}

/// Statistics of a whole render: merged worker counters plus run-level facts.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Merged counters of all workers.
    pub counters: SystemStats,
    /// Wall-clock duration of the render.
    pub wall_seconds: f64,
    /// Features the compiled scene used (e.g. "volumes", "environment").
    pub features: Vec<String>,
    /// Problems worth telling the user about (serialised only when non-empty).
    pub warnings: Vec<String>,
    /// The kept non-finite cases ([`SystemStats::non_finite_events`], named; serialised
    /// only when non-empty).
    pub non_finite_cases: Vec<NonFiniteCase>,
    /// The command that renders this scene with the options that decide its paths
    /// (`risotto render scene.toml --seed 3`), to which each case's
    /// [`replay_arg`](NonFiniteCase::replay_arg) is appended in the JSON and the summary.
    /// Defaults to `None`: `risotto render SCENE`.
    pub render_command: Option<String>,
    /// Facts about the run for benchmarkers (version, image, threads, phase times, peak
    /// memory), set by the program that ran the render; serialised as `"run"` when set.
    pub run: Option<RunInfo>,
    /// Where an adaptive render's samples went and the relative error it estimates at the
    /// end ([`RenderOptions::noise_target`](crate::render::RenderOptions::noise_target));
    /// serialised as `"adaptive"` when set.
    pub adaptive: Option<risotto_systems::adaptive::AdaptiveSummary>,
}

/// What a benchmark needs to know about a run besides the counters: which build, which
/// image and samples, how many threads, where the time went and the peak memory. The
/// driver fills it (`--stats`); an embedder may.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct RunInfo {
    /// The renderer's version (`CARGO_PKG_VERSION`).
    pub version: String,
    /// The source commit it was built from, when known (`git rev-parse` at build time).
    pub commit: Option<String>,
    /// The whole image, `[width, height]`.
    pub resolution: [u32; 2],
    /// The rendered window `[x0, y0, x1, y1]` (half-open).
    pub window: [u32; 4],
    /// The scene's samples per pixel.
    pub spp: u32,
    /// The sample indices rendered, `[start, end)`.
    pub samples: [u32; 2],
    /// Worker threads.
    pub threads: usize,
    /// Reading and parsing the scene and the files it references, in seconds.
    pub load_seconds: f64,
    /// Compiling the scene: flattening and the BVH build, in seconds.
    pub build_seconds: f64,
    /// The render itself (`wall_seconds`), in seconds.
    pub render_seconds: f64,
    /// Denoising the image (`render --denoise`), in seconds; absent without it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub denoise_seconds: Option<f64>,
    /// Writing the image files (the EXR, and the PNG preview unless `--no-preview`), in
    /// seconds; absent until they are written (and in the stats of a render that wrote
    /// none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub output_seconds: Option<f64>,
    /// Peak resident memory of the process in bytes (Linux `VmHWM`), when the platform
    /// reports it.
    pub peak_resident_bytes: Option<u64>,
}

impl RenderStats {
    /// Stats from merged counters and the wall time.
    pub fn new(counters: SystemStats, wall_seconds: f64) -> Self {
        RenderStats {
            counters,
            wall_seconds,
            ..Default::default()
        }
    }

    /// The command that re-runs `case` alone (`risotto render SCENE --replay X,Y,SAMPLE`,
    /// with [`render_command`](Self::render_command) when set).
    pub fn replay_command(&self, case: &NonFiniteCase) -> String {
        let render = self
            .render_command
            .as_deref()
            .unwrap_or("risotto render SCENE");
        format!("{render} {}", case.replay_arg())
    }

    /// Pretty-printed JSON (schema in the module docs).
    pub fn to_json(&self) -> String {
        // Serialising plain numbers, strings and maps with string keys cannot fail.
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Writes [`to_json`](Self::to_json) (plus a trailing newline) to `path`.
    /// Written as a whole or not at all ([`crate::output::write_atomically`]).
    pub fn write_json(&self, path: &Path) -> Result<(), crate::output::OutputError> {
        let mut s = self.to_json();
        s.push('\n');
        crate::output::write_file_atomically(path, s.as_bytes())
    }
}

mod report;
#[cfg(test)]
mod tests;
