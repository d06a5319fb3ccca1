//! Rendering a compiled scene: the image is cut into tiles (work items); each rayon worker
//! renders whole tiles, batch by batch, with its own tables and arena. A tile's samples are
//! splatted in a fixed order, so the image does not depend on the number of threads.
//!
//! A render may cover only a window of the image ([`RenderOptions::crop`]) and a range of
//! each pixel's sample indices ([`RenderOptions::samples`]): pixel seeds and sample indices
//! are those of the whole render, so such pieces are independent farm tasks that
//! `risotto merge` (`risotto-tools`) puts back together.

use crate::bidir::{Bidirectional, Strategy};
use crate::integrator::{
    light_pass_tile, render_tile, GlobalIntegrator, Integrator, LightingTechnique, TileFilm,
    TileWorker,
};
use crate::output::Image;
use crate::path_tracer::PathTracer;
use crate::scene::CompiledScene;
use crate::stats::{RenderStats, SystemStats};
use bumpalo::Bump;
use rayon::prelude::*;
use risotto_systems::film::{AovFilm, Film};
use risotto_systems::independent_sampler::SamplerKind;
use std::sync::Mutex;

mod adaptive;
mod film_memory;
mod gather;
mod splats;
use adaptive::{adaptive_summary, plan_next_pass};
pub use film_memory::{
    check_film_memory, film_bytes, physical_memory, proc_bytes, ADAPTIVE_BYTES_PER_PIXEL,
    AOV_BYTES_PER_PIXEL, FILM_BYTES_PER_PIXEL, PILOT_BYTES_PER_PIXEL,
};
pub use gather::aov_means;
use gather::gather;
pub(crate) use gather::name_non_finite_cases;
use risotto_systems::adaptive::AdaptiveSummary;
mod window;
pub use window::{SampleRange, Window};

/// Largest `width * height` of a render's image ([`risotto_systems::film::MAX_PIXELS`]:
/// 2^26 pixels, 8192 x 8192, whose render takes about 7 GB at [`FILM_BYTES_PER_PIXEL`],
/// 15 GB with [`AOV_BYTES_PER_PIXEL`]).
/// Scene files, scenes built in code and partial renders asking for more are an error
/// naming the value rather than an allocation abort; a smaller film that needs more than
/// the machine's memory is refused when the render starts ([`check_film_memory`]).
pub const MAX_FILM_PIXELS: u64 = risotto_systems::film::MAX_PIXELS;

/// The most worker threads a render starts. Far above any core count a render uses; a
/// larger request is a typo, and honouring it aborts the process when the operating system
/// runs out of thread stacks (100 000 threads did), so it is an error instead.
pub const MAX_THREADS: usize = 1024;

/// Whether a render starts `threads` worker threads: `Err` says why not (0, or more than
/// [`MAX_THREADS`]); a caller checks with it before loading the scene.
pub fn check_threads(threads: usize) -> Result<(), String> {
    if threads == 0 || threads > MAX_THREADS {
        return Err(format!("must be 1 to {MAX_THREADS}"));
    }
    Ok(())
}

/// Options of one render that are not part of the scene.
#[derive(Clone, Copy, Debug)]
pub struct RenderOptions {
    /// Worker threads of the render, 1 to [`MAX_THREADS`]. Defaults to `None`: all cores.
    /// Loading and compiling a scene run on the calling thread's rayon pool (the global one
    /// unless inside `rayon::ThreadPool::install`), which this does not size: the `risotto`
    /// driver sizes the global pool to `--threads` before it reads the scene.
    pub threads: Option<usize>,
    /// Paths per batch. Defaults to 4096.
    pub batch_size: usize,
    /// Tile edge in pixels. Defaults to 16.
    pub tile_size: u32,
    /// Direct-lighting technique. Defaults to MIS.
    pub technique: LightingTechnique,
    /// Sampler (the `sampler` technique). Defaults to Sobol.
    pub sampler: SamplerKind,
    /// The values chosen for plug-in techniques (those the scene's materials declare, such
    /// as the built-in media's `scattering`, `subsurface` and `tracking`). Defaults to none:
    /// every one at its default.
    pub plugin_techniques: crate::plugin::PluginTechniques,
    /// Only this window of the image is rendered (same camera, same per-pixel seeds: its
    /// pixels are the bits of the same pixels of the whole render). Defaults to `None`: the
    /// whole image.
    pub crop: Option<Window>,
    /// Only these sample indices of each pixel are rendered. Defaults to `None`: all of
    /// `0..spp`.
    pub samples: Option<SampleRange>,
    /// A flag that, once set (by a signal handler, another thread), ends the render after
    /// the pass in flight: the render then runs in passes over every pixel of about
    /// [`INTERRUPTIBLE_PASS`] each (or the checkpoint interval), and the output holds the
    /// samples of the passes done ([`RenderOutput::samples`] says which; the same bits those
    /// samples have in the whole render). Defaults to `None`: one pass, not interruptible.
    pub interrupt: Option<&'static std::sync::atomic::AtomicBool>,
    /// Adaptive sampling: pixels stop taking samples once their estimated relative error
    /// reaches the target ([`NoiseTarget`]); the scene's spp is then the most a pixel
    /// takes. Defaults to `None`: every pixel takes every sample.
    pub noise_target: Option<NoiseTarget>,
    /// The global integrator (the `integrator` technique). Defaults to `None`: the one the
    /// scene asks for ([`RenderSettings::integrator`](crate::scene::RenderSettings::integrator)).
    pub integrator: Option<GlobalIntegrator>,
    /// Whether the path tracer samples the directly visible emission with extra camera
    /// points (the `visible_emitters` technique). Defaults to supersampled.
    pub visible_emitters: crate::path_tracer::visible_emitters::VisibleEmitters,
    /// Whether the render keeps the first-hit AOVs (the sums of albedo, shading normal and
    /// depth in every tile and in the gathered image, and their means in
    /// [`RenderOutput::albedo`], [`RenderOutput::normal`] and [`RenderOutput::depth`]):
    /// [`AOV_BYTES_PER_PIXEL`] of the film's memory. Without them those layers are empty
    /// (0 x 0) and [`RenderOutput::aovs`] holds no sums. What the denoiser and `--aovs`
    /// read. Defaults to `true`; the `risotto` driver keeps them only for `--aovs` and
    /// `--denoise`.
    pub aovs: bool,
}

/// Adaptive sampling's request ([`RenderOptions::noise_target`]).
///
/// Every pixel first takes `min_spp` samples; then, after each pass, the pixels whose
/// relative error (estimated from film variances as the [`StoppingRule`] says, relative to
/// 1 % of the image's mean for dark pixels: [`risotto_systems::adaptive`]) is at or below
/// `relative_error` stop for good (none before `2 min_spp` samples), and each of the others
/// takes the samples its estimate says bring it to the target, 10 % more, at least a
/// quarter and at most as many again as it has
/// ([`risotto_systems::adaptive::next_sample_count`]; fewer when the render is
/// interruptible or checkpointed). A pixel's
/// samples are the first indices of its sequence, so the `sampleCount` layer says how many
/// it took; the output's [`RenderOutput::samples`] is the range the most-sampled pixels
/// took. Which samples decide that a pixel stops is the [`StoppingRule`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseTarget {
    /// The relative error (standard error over value) at which a pixel stops, > 0.
    pub relative_error: f32,
    /// Samples every pixel takes before any stops, >= 1 (the driver's default: 16).
    pub min_spp: u32,
    /// Which samples decide that a pixel stops.
    pub rule: StoppingRule,
}

/// Which samples an adaptive render's stopping decisions read ([`NoiseTarget::rule`]).
///
/// A rule that reads the samples a pixel keeps biases its mean where light arrives by rare
/// paths: a pixel that has not yet drawn one shows a low mean and a low variance together,
/// and stops low (Kirk and Arvo 1991). `Window` has this bias and spends the samples best;
/// `Unbiased` does not read a pixel's samples at all. README, "Renders that stop at a
/// requested accuracy", has both measured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StoppingRule {
    /// The worst estimate of the pixel and its eight neighbours
    /// ([`risotto_systems::adaptive::windowed_relative_error`]): a pixel that drew a rare
    /// bright sample samples on until the sample is averaged down.
    #[default]
    Window,
    /// The worst of two estimates that never read the pixel's own samples, each a
    /// per-sample error pooled over a neighbourhood
    /// ([`risotto_systems::adaptive::pooled_relative_error`]) and taken at the pixel's
    /// count: a pilot of `min_spp` independently scrambled samples of every pixel,
    /// rendered first and discarded (its 9 x 9 pixels around the pixel), and the image's
    /// pixels before it in raster order (the 8 rows above, 17 pixels each, and the 8 to
    /// its left). A pixel's sample count is then independent of its samples, and its mean
    /// unbiased. Costs the pilot (`min_spp` more samples a pixel) and, where a pixel draws
    /// a rare bright sample the estimates did not foresee, keeps it at the pixel's count.
    Unbiased,
}

/// The largest tile edge of an adaptive render ([`RenderOptions::noise_target`]).
pub const ADAPTIVE_TILE_SIZE: u32 = 8;

/// The fraction of the image's mean value (per channel) below which a pixel's error is
/// measured against that floor rather than its own value.
pub const NOISE_FLOOR_FRACTION: f32 = 0.01;

/// How long each pass of an interruptible render ([`RenderOptions::interrupt`]) without
/// checkpoints is sized to take: the longest an interrupt waits for the passes in flight
/// (after the first pass, one sample per pixel). Passes cost one barrier each, negligible
/// at this length.
pub const INTERRUPTIBLE_PASS: std::time::Duration = std::time::Duration::from_secs(2);

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            threads: None,
            batch_size: 4096,
            tile_size: 16,
            technique: LightingTechnique::Mis,
            sampler: SamplerKind::Sobol,
            plugin_techniques: Default::default(),
            crop: None,
            samples: None,
            interrupt: None,
            noise_target: None,
            integrator: None,
            visible_emitters: Default::default(),
            aovs: true,
        }
    }
}

/// What a render produces. The images cover [`window`](Self::window) (the whole image
/// unless the render was cropped), row-major from its top-left pixel.
pub struct RenderOutput {
    /// Mean radiance per pixel.
    pub beauty: Image,
    /// Variance of the mean per pixel and channel.
    pub variance: Image,
    /// Samples per pixel.
    pub sample_count: Vec<f32>,
    /// Mean first-hit albedo (empty, 0 x 0, without [`RenderOptions::aovs`]).
    pub albedo: Image,
    /// Mean first-hit shading normal (empty without [`RenderOptions::aovs`]).
    pub normal: Image,
    /// Mean first-hit distance, 0 where the camera saw nothing (empty without
    /// [`RenderOptions::aovs`]).
    pub depth: Vec<f32>,
    /// The per-pixel sums (f64) and counts the means come from, over the window: what
    /// merging partial renders adds up.
    pub film: Film,
    /// The per-pixel sums (f64) the AOV means come from (divided by `film.count`); none
    /// ([`AovFilm::holds_sums`] false) without [`RenderOptions::aovs`].
    pub aovs: AovFilm,
    /// The window of the full image these pixels are.
    pub window: Window,
    /// The sample indices rendered (of every pixel of the window).
    pub samples: SampleRange,
    /// Statistics.
    pub stats: RenderStats,
}

impl RenderOutput {
    /// The layers [`write_exr`](crate::output::write_exr) writes: beauty, variance and
    /// sample count, and with `aovs` the albedo, normal and depth means (when the render
    /// kept them, [`RenderOptions::aovs`]).
    pub fn film_output(&self, aovs: bool) -> crate::output::FilmOutput<'_> {
        let aovs = aovs && self.aovs.holds_sums();
        crate::output::FilmOutput {
            beauty: &self.beauty,
            variance: &self.variance,
            sample_count: &self.sample_count,
            albedo: aovs.then_some(&self.albedo),
            normal: aovs.then_some(&self.normal),
            depth: aovs.then_some(self.depth.as_slice()),
        }
    }
}

/// Errors of [`render`].
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The thread pool could not be built.
    #[error("cannot start {threads} render threads: {message}")]
    ThreadPool {
        /// Requested threads.
        threads: usize,
        /// Cause.
        message: String,
    },
    /// The crop window is empty or not inside the image.
    #[error("crop window {window}: {reason}")]
    Crop {
        /// The window asked for.
        window: Window,
        /// What is wrong with it.
        reason: String,
    },
    /// The sample range is empty or beyond the scene's samples per pixel.
    #[error("sample range {samples}: {reason}")]
    Samples {
        /// The range asked for.
        samples: SampleRange,
        /// What is wrong with it.
        reason: String,
    },
    /// The film of the window asked for needs more memory than the machine has
    /// ([`check_film_memory`]).
    #[error("image {window}: {reason}")]
    FilmMemory {
        /// The window asked for.
        window: Window,
        /// The memory it needs and the machine has.
        reason: String,
    },
    /// A checkpoint could not be written.
    #[error("checkpoint: {0}")]
    Checkpoint(String),
    /// The pixel or sample to replay ([`crate::replay::replay`]) is not part of the render.
    #[error("replay of pixel ({x}, {y}) sample {sample}: {reason}")]
    Replay {
        /// Pixel column asked for.
        x: u32,
        /// Pixel row asked for.
        y: u32,
        /// Sample index asked for.
        sample: u32,
        /// What is wrong with it.
        reason: String,
    },
}

/// Periodic checkpoints of a render ([`render_checkpointed`]).
pub struct Checkpoints<'a> {
    /// Wanted time between checkpoints. The render runs in passes over every pixel of the
    /// window, each sized from the previous one's speed to take about this long, and
    /// `write` is called after each pass but the last.
    pub every: std::time::Duration,
    /// Receives the render so far (its `samples` say which indices are done).
    pub write: &'a mut dyn FnMut(&RenderOutput) -> Result<(), String>,
}

/// Renders `scene` with the global integrator `options.integrator` (or the scene's): the
/// path tracer (`options.technique` for direct lighting) or a bidirectional one
/// ([`crate::bidir`]). `progress` is called with the number of samples finished, from worker
/// threads.
pub fn render(
    scene: &CompiledScene,
    options: &RenderOptions,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<RenderOutput, RenderError> {
    render_dispatch(scene, options, progress, None)
}

/// [`render`] with checkpoints: the partial render so far is handed to
/// `checkpoints.write` about every `checkpoints.every`. Tiles keep their films across
/// passes, so every pixel's sums are added in sample order and the result is the same bits
/// as [`render`]'s.
pub fn render_checkpointed(
    scene: &CompiledScene,
    options: &RenderOptions,
    progress: &(dyn Fn(u64) + Sync),
    checkpoints: Checkpoints,
) -> Result<RenderOutput, RenderError> {
    render_dispatch(scene, options, progress, Some(checkpoints))
}

/// The integrator `options` and `scene` ask for, rendering.
fn render_dispatch(
    scene: &CompiledScene,
    options: &RenderOptions,
    progress: &(dyn Fn(u64) + Sync),
    checkpoints: Option<Checkpoints>,
) -> Result<RenderOutput, RenderError> {
    let tracer = PathTracer {
        technique: options.technique,
        techniques: options.plugin_techniques,
        visible_emitters: crate::path_tracer::visible_emitters::for_scene(
            scene,
            options.visible_emitters,
        ),
    };
    let strategy = match options.integrator.unwrap_or(scene.settings.integrator) {
        GlobalIntegrator::Path => {
            return render_passes(&tracer, scene, options, progress, checkpoints)
        }
        GlobalIntegrator::Light => Strategy::Light,
        GlobalIntegrator::Bdpt => Strategy::Bdpt,
        GlobalIntegrator::Vcm => Strategy::Vcm,
    };
    if let Err(reason) = Bidirectional::supports(scene) {
        // The documented fallback: the path tracer renders what the bidirectional
        // integrator cannot, and the stats say so.
        let mut out = render_passes(&tracer, scene, options, progress, checkpoints)?;
        out.stats.warnings.push(format!(
            "integrator {} cannot render this scene ({reason}); the path tracer rendered it",
            strategy.name()
        ));
        return Ok(out);
    }
    let (window, samples) = checked_extent(scene, options)?;
    if options.noise_target.is_some() {
        return Err(RenderError::Samples {
            samples,
            reason: format!(
                "adaptive sampling (a noise target) needs the path tracer: integrator {} \
                 splats light paths onto every pixel, stopped or not",
                strategy.name()
            ),
        });
    }
    let integrator =
        Bidirectional::new(scene, strategy, options.plugin_techniques, window.pixels())
            .map_err(|reason| RenderError::Samples { samples, reason })?;
    let mut out = render_passes(&integrator, scene, options, progress, checkpoints)?;
    let walked = out.stats.counters.walked_subpath_rays;
    if strategy == Strategy::Light && walked > 0 {
        out.stats.warnings.push(format!(
            "{walked} rays of light subpaths were walked through a medium in one call \
             (scattering = \"walk\", or a dense medium inside glass): light tracing cannot \
             connect the walks' inner events to the camera, so the image lacks the light \
             those media scatter towards it; bdpt and vcm render it"
        ));
    }
    Ok(out)
}

/// Renders `scene` with any global integrator (`options.technique` is the path tracer's and
/// is ignored here). `progress` is called with the number of samples finished, from worker
/// threads.
pub fn render_with<I: Integrator>(
    integrator: &I,
    scene: &CompiledScene,
    options: &RenderOptions,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<RenderOutput, RenderError> {
    render_passes(integrator, scene, options, progress, None)
}

/// The window and sample range `options` ask for, checked against `scene`.
pub fn checked_extent(
    scene: &CompiledScene,
    options: &RenderOptions,
) -> Result<(Window, SampleRange), RenderError> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let window = options.crop.unwrap_or(Window::full(w, h));
    let crop_err = |reason: String| RenderError::Crop { window, reason };
    if window.x0 >= window.x1 || window.y0 >= window.y1 {
        return Err(crop_err("empty window (need X0 < X1 and Y0 < Y1)".into()));
    }
    if window.x1 > w || window.y1 > h {
        return Err(crop_err(format!("outside the {w}x{h} image")));
    }
    let adaptive = match options.noise_target {
        None => 0,
        Some(t) if t.rule == StoppingRule::Unbiased => {
            ADAPTIVE_BYTES_PER_PIXEL + PILOT_BYTES_PER_PIXEL
        }
        Some(_) => ADAPTIVE_BYTES_PER_PIXEL,
    };
    let aovs = if options.aovs { AOV_BYTES_PER_PIXEL } else { 0 };
    check_film_memory(
        window.pixels() as u64,
        FILM_BYTES_PER_PIXEL + aovs + adaptive,
        physical_memory(),
    )
    .map_err(|reason| RenderError::FilmMemory { window, reason })?;
    let spp = scene.settings.spp;
    let samples = options
        .samples
        .unwrap_or(SampleRange { start: 0, end: spp });
    if samples.start >= samples.end {
        return Err(RenderError::Samples {
            samples,
            reason: "empty range (need START < END)".into(),
        });
    }
    if samples.end > spp {
        return Err(RenderError::Samples {
            samples,
            reason: format!("beyond the scene's {spp} samples per pixel"),
        });
    }
    Ok((window, samples))
}

/// One tile of a render: its film (kept across passes) and its workers' counters.
type Tile = (TileFilm, SystemStats);

/// Runs `f` on `pool` (the render's, when `threads` asked for one) or on rayon's global
/// pool: adaptive sampling's estimates between passes run in parallel too, and `threads`
/// holds for them as for the passes.
fn in_pool<R: Send>(pool: Option<&rayon::ThreadPool>, f: impl FnOnce() -> R + Send) -> R {
    match pool {
        Some(pool) => pool.install(f),
        None => f(),
    }
}

fn render_passes<I: Integrator>(
    integrator: &I,
    scene: &CompiledScene,
    options: &RenderOptions,
    progress: &(dyn Fn(u64) + Sync),
    mut checkpoints: Option<Checkpoints>,
) -> Result<RenderOutput, RenderError> {
    let start = std::time::Instant::now();
    let (window, samples) = checked_extent(scene, options)?;
    // Adaptive sampling's late passes have work only where the noise is: smaller tiles let
    // every thread take part there (16 x 16 tiles left one of two threads idle on a
    // 32 x 24 test image).
    let ts = match options.noise_target {
        Some(_) => options.tile_size.clamp(1, ADAPTIVE_TILE_SIZE),
        None => options.tile_size.max(1),
    };
    let mut tiles: Vec<Tile> = Vec::new();
    for y0 in (window.y0..window.y1).step_by(ts as usize) {
        for x0 in (window.x0..window.x1).step_by(ts as usize) {
            let (w, h) = (ts.min(window.x1 - x0), ts.min(window.y1 - y0));
            let tile = if options.aovs {
                TileFilm::new(x0, y0, w, h)
            } else {
                TileFilm::without_aovs(x0, y0, w, h)
            };
            tiles.push((tile, SystemStats::default()));
        }
    }
    let pool = match options.threads {
        Some(threads) => {
            let error = |message| RenderError::ThreadPool { threads, message };
            check_threads(threads).map_err(error)?;
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build();
            Some(pool.map_err(|e| error(e.to_string()))?)
        }
        None => None,
    };
    // One worker (tables and arena) per thread of the pool, kept for the whole render:
    // `for_each_init` would make one per job rayon splits off (up to one per tile), and each
    // new worker allocates and first touches its tables again (a bidirectional integrator's
    // light vertices and queues are megabytes). A thread only ever locks its own.
    let threads = pool
        .as_ref()
        .map_or_else(rayon::current_num_threads, |p| p.current_num_threads());
    let workers: Vec<Mutex<(TileWorker<I::Worker>, Bump)>> = (0..threads.max(1))
        .map(|_| Mutex::new((TileWorker::default(), Bump::new())))
        .collect();
    // Renders the sample indices `range` of `tiles` in parallel, continuing their films and
    // reporting the samples to `progress`, or (`light`) runs the integrator's light pass of
    // an iteration over them.
    let run_tiles = |tiles: &mut [Tile],
                     range: std::ops::Range<u32>,
                     light: bool,
                     progress: &(dyn Fn(u64) + Sync)| {
        // The sampler travels in the sample addresses (`SamplerKind::address`).
        let addresses = options.sampler.addresses(range);
        let workers = &workers;
        let work = move || {
            tiles.par_iter_mut().for_each(|(tile, stats)| {
                let i = rayon::current_thread_index().unwrap_or(0) % workers.len();
                // A worker is plain scratch: one left poisoned by a panicking tile is as good.
                // Held already (a plug-in's own rayon work let this thread steal another
                // tile while its worker is in use, or the render runs inside another pool):
                // this tile gets a fresh one rather than waiting on itself.
                let mut held = match workers[i].try_lock() {
                    Ok(guard) => Some(guard),
                    Err(std::sync::TryLockError::Poisoned(e)) => Some(e.into_inner()),
                    Err(std::sync::TryLockError::WouldBlock) => None,
                };
                let mut fresh = None;
                let (tables, arena) = match held.as_deref_mut() {
                    Some((tables, arena)) => (tables, arena),
                    None => {
                        let (tables, arena) =
                            fresh.insert((TileWorker::<I::Worker>::default(), Bump::new()));
                        (tables, arena)
                    }
                };
                let (samples, batch_size) = (addresses.clone(), options.batch_size);
                if light {
                    light_pass_tile(
                        integrator, scene, tile, samples, batch_size, tables, stats, arena,
                    );
                } else {
                    render_tile(
                        integrator, scene, tile, samples, batch_size, tables, stats, arena,
                        progress,
                    );
                }
            })
        };
        in_pool(pool.as_ref(), work)
    };
    // A render in iterations: one sample index of a group of tiles each, the groups as
    // large as the integrator's bound allows (at least one tile).
    let tiles_per_group = integrator.iteration_paths().map(|max| {
        let tile_pixels = tiles.iter().map(|(t, _)| t.active_pixels()).max();
        (max / tile_pixels.unwrap_or(1).max(1)).max(1)
    });
    // One pass renders the sample indices `range` of every tile, continuing its film: in
    // iterations (a light pass, then the camera pass) when the integrator works in them.
    let pass = |tiles: &mut Vec<Tile>, range: std::ops::Range<u32>| match tiles_per_group {
        None => run_tiles(tiles, range, false, progress),
        Some(group_size) => {
            for sample in range {
                for group in tiles.chunks_mut(group_size) {
                    let camera_samples = group.iter().map(|(t, _)| t.active_pixels()).sum();
                    integrator.begin_iteration(sample, camera_samples);
                    run_tiles(group, sample..sample + 1, true, progress);
                    if let Some((_, stats)) = group.first_mut() {
                        integrator.end_light_pass(stats);
                    }
                    run_tiles(group, sample..sample + 1, false, progress);
                }
            }
        }
    };
    let mut done = samples.start;
    let interrupted = || {
        options
            .interrupt
            .is_some_and(|f| f.load(std::sync::atomic::Ordering::Relaxed))
    };
    let every = match (&checkpoints, options.interrupt) {
        (Some(cp), _) => Some(cp.every),
        (None, Some(_)) => Some(INTERRUPTIBLE_PASS),
        (None, None) => None,
    };
    if let Some(target) = options.noise_target {
        // Adaptive: a first pass of `min_spp`, then passes in which each pixel still above
        // the target takes the samples its estimate says it needs (at most as many again as
        // it has; `adaptive::plan_next_pass`), or what `every` allows at the last pass's
        // speed, whichever is fewer.
        let next = samples
            .start
            .saturating_add(target.min_spp.max(1))
            .min(samples.end);
        // The unbiased rule's pilot (`adaptive`): the first `min_spp` sample indices of every
        // pixel, independently scrambled, counted in the work but not in the progress. Its
        // films are dropped once its pooled errors are made; its work is the render's (its
        // rays and time), not its image.
        let pilot = (target.rule == StoppingRule::Unbiased).then(|| {
            let mut pilots = adaptive::pilot_tiles(&tiles);
            run_tiles(&mut pilots, done..next, false, &|_| {});
            for ((_, stats), (_, pilot_stats)) in tiles.iter_mut().zip(&pilots) {
                stats.merge(pilot_stats);
            }
            in_pool(pool.as_ref(), || adaptive::PilotErrors::of(&pilots, window))
        });
        // The passes' ranges: the first is every pixel's `done..next`; later ones are each
        // pixel's own (`TileFilm::sample_ranges`), `pass` taking them from the tiles.
        let mut range = done..next;
        let (mut passes, mut plan_seconds) = (0u32, 0.0f64);
        let mut buffers = adaptive::PlanBuffers::new(window);
        loop {
            let t = std::time::Instant::now();
            pass(&mut tiles, range.clone());
            passes += 1;
            // The pass's time per sample of its longest pixel range.
            let longest = (tiles.iter())
                .flat_map(|(t, _)| t.sample_ranges.iter().map(|r| r.len()))
                .max()
                .unwrap_or(range.len())
                .max(1);
            let per_sample = t.elapsed().as_secs_f64() / longest as f64;
            done = (tiles.iter())
                .flat_map(|(t, _)| t.film.count.iter())
                .max()
                .map_or(done, |&c| samples.start + c);
            if interrupted() {
                break;
            }
            let (all, t) = (samples.start..samples.end, std::time::Instant::now());
            let active = in_pool(pool.as_ref(), || {
                plan_next_pass(
                    &mut tiles,
                    pilot.as_ref(),
                    window,
                    target,
                    all,
                    &mut buffers,
                )
            });
            plan_seconds += t.elapsed().as_secs_f64();
            if active == 0 {
                break;
            }
            if let Some(every) = every {
                let mut write_seconds = 0.0;
                if let Some(cp) = &mut checkpoints {
                    let t = std::time::Instant::now();
                    let so_far = gather(
                        scene,
                        window,
                        samples.start..done,
                        &tiles,
                        start,
                        integrator.splats(),
                    );
                    (cp.write)(&so_far).map_err(RenderError::Checkpoint)?;
                    write_seconds = t.elapsed().as_secs_f64();
                }
                // At most what takes `every` at this pass's speed, for every pixel.
                let limit = next_pass_samples(every.as_secs_f64(), write_seconds, per_sample);
                for r in tiles
                    .iter_mut()
                    .flat_map(|(t, _)| t.sample_ranges.iter_mut())
                {
                    r.end = r.end.min(r.start.saturating_add(limit));
                }
            }
            // Each pixel's range is in its tile; the pass's own is not read.
            range = samples.start..samples.end;
        }
        // Not held beside the gathered image: the render's peak is there.
        drop(buffers);
        let mut out = gather(
            scene,
            window,
            samples.start..done,
            &tiles,
            start,
            integrator.splats(),
        );
        let summary = in_pool(pool.as_ref(), || {
            adaptive_summary(&out, target, pilot.as_ref())
        });
        out.stats.adaptive = Some(AdaptiveSummary {
            passes,
            plan_seconds,
            ..summary
        });
        return Ok(out);
    }
    match every {
        None => {
            pass(&mut tiles, samples.start..samples.end);
            done = samples.end;
        }
        Some(every) => {
            // The first pass takes one sample per pixel and measures the speed; each later
            // pass is sized to take about `every` at the speed of the one before.
            let mut chunk = 1u32;
            while done < samples.end {
                let next = done.saturating_add(chunk).min(samples.end);
                let t = std::time::Instant::now();
                pass(&mut tiles, done..next);
                let per_sample = t.elapsed().as_secs_f64() / (next - done) as f64;
                done = next;
                if interrupted() {
                    break;
                }
                let mut write_seconds = 0.0;
                if let (Some(cp), true) = (&mut checkpoints, done < samples.end) {
                    let t = std::time::Instant::now();
                    let so_far = gather(
                        scene,
                        window,
                        samples.start..done,
                        &tiles,
                        start,
                        integrator.splats(),
                    );
                    (cp.write)(&so_far).map_err(RenderError::Checkpoint)?;
                    write_seconds = t.elapsed().as_secs_f64();
                }
                chunk = next_pass_samples(every.as_secs_f64(), write_seconds, per_sample);
            }
        }
    }
    Ok(gather(
        scene,
        window,
        samples.start..done,
        tiles,
        start,
        integrator.splats(),
    ))
}

/// Samples per pixel of the next pass of a render in passes: the time between checkpoints,
/// `every` seconds, counts the last checkpoint's gathering and writing (`write_seconds`), and
/// the pass renders at least 9 times as long as that write, so checkpoints never take more
/// than about a tenth of the render however slow the disk (`--checkpoint 0.3` with 0.5 s
/// writes once rendered 2.55 s of work in 12.4 s). `per_sample` is the last pass's time per
/// sample per pixel. At least 1.
pub fn next_pass_samples(every: f64, write_seconds: f64, per_sample: f64) -> u32 {
    let pass_seconds = (every - write_seconds).max(9.0 * write_seconds);
    let want = pass_seconds / per_sample.max(1e-9);
    if want.is_nan() {
        return 1;
    }
    want.clamp(1.0, u32::MAX as f64) as u32
}

#[cfg(test)]
mod tests {
    use super::next_pass_samples;

    #[test]
    fn passes_count_the_checkpoint_write_and_outweigh_it_ninefold() {
        // Without checkpoints (or instant ones) a pass fills the interval.
        assert_eq!(next_pass_samples(2.0, 0.0, 0.01), 200);
        // A write's time is part of the interval.
        assert_eq!(next_pass_samples(1.0, 0.05, 0.01), 95);
        // ... unless that would let writes take more than a tenth.
        assert_eq!(next_pass_samples(1.0, 0.2, 0.01), 180);
        // A write slower than the interval: the pass is nine writes long, so writes take a
        // tenth of the time (the reported --checkpoint 0.3 case spent 80 % writing).
        for (every, write) in [(0.3, 0.5), (0.01, 2.0), (1.0, 0.5)] {
            let per_sample = 0.001;
            let pass = f64::from(next_pass_samples(every, write, per_sample)) * per_sample;
            let share = write / (pass + write);
            assert!(share <= 0.1 + 1e-3, "every {every}, write {write}: {share}");
        }
        // Degenerate timings still give a pass of at least one sample.
        assert_eq!(next_pass_samples(0.0, 0.0, 0.01), 1);
        assert_eq!(next_pass_samples(f64::NAN, 0.0, 0.01), 1);
        assert!(next_pass_samples(1.0, 0.0, 0.0) >= 999_999_999);
    }
}
