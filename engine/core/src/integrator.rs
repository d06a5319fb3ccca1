//! The global integrator contract (RIS `RixIntegrator`) and the tile loop every integrator
//! shares: a tile's samples are cut into batches of paths, the integrator runs each batch to
//! completion, and the paths' radiance is splatted into the tile's film.
//!
//! The path tracer ([`PathTracer`](crate::path_tracer::PathTracer)) is one integrator; an
//! integrator that offers volume integrators no lighting delegate (as RenderMan's PxrVCM does
//! not) is another, and volume integrators must work with it (`tests/integrators.rs` has one).

use crate::scene::CompiledScene;
use crate::stats::{System, SystemStats};
use bumpalo::Bump;
use risotto_components::Paths;
use risotto_systems::film::{splat, AovFilm, Film, SplatFilm};
use risotto_systems::sampler::pixel_seed;

/// How direct lighting is estimated; a named technique so its cost and error can be compared.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightingTechnique {
    /// Light sampling and Bxdf sampling combined with the power heuristic (Veach 1997).
    #[default]
    Mis,
    /// Light sampling only (emitters hit by Bxdf-sampled rays after a non-specular bounce are
    /// ignored).
    NeeOnly,
    /// Bxdf sampling only (no shadow rays; Dirac lights are invisible).
    BxdfOnly,
}

pub use crate::global_integrator::GlobalIntegrator;

/// The camera samples of one batch: one path per pixel and sample, with the pixel seeds of
/// the sampler. The integrator leaves each path's radiance (and first-hit AOVs) in `paths`.
#[derive(Default)]
pub struct PathBatch {
    /// One row per camera sample: pixel, sample index, radiance, AOVs.
    pub paths: Paths,
    /// The sampler seed of each path's pixel ([`pixel_seed`]).
    pub seeds: Vec<u32>,
    /// A path-trace recorder: when `Some`, the path tracer records what path 0 did at each
    /// vertex into it (exact for a batch of one path; see
    /// [`PathTrace`](crate::path_tracer::PathTrace) and [`crate::replay`]). Defaults to
    /// `None`: nothing is recorded, and the stage loop pays one test per stage and bounce.
    /// Other integrators may ignore it.
    pub trace: Option<crate::path_record::PathTrace>,
}

/// A global integrator (RIS `RixIntegrator`): owns light transport for whole batches of
/// camera paths. It may hand volumes to their volume integrators through the renderer's
/// services ([`IntegratorContext`](crate::plugin::IntegratorContext)) and decides whether
/// to offer them a [`LightingDelegate`](crate::plugin::LightingDelegate).
pub trait Integrator: Sync {
    /// What a worker thread keeps across batches (queues, tables): created once per worker.
    type Worker: Default + Send;

    /// Runs every path of `batch` to completion, adding its radiance to
    /// `batch.paths.radiance` (and setting the first-hit AOVs). `arena` is the worker's
    /// per-batch arena (reset by the caller after the batch; plain data only).
    fn run_batch(
        &self,
        scene: &CompiledScene,
        batch: &mut PathBatch,
        worker: &mut Self::Worker,
        stats: &mut SystemStats,
        arena: &Bump,
    );

    /// Radiance this integrator carries to pixels other than its own paths' (light
    /// tracing's splats), added to the image whenever it is gathered: sums per pixel of the
    /// whole image, and the factor that makes them radiance. Defaults to none.
    fn splats(&self) -> Option<(&SplatFilm, f64)> {
        None
    }

    /// Whether this integrator renders in **iterations**: each one sample index of a group
    /// of tiles, rendered as a light pass over its batches ([`Integrator::light_pass`]) and
    /// then their camera pass ([`Integrator::run_batch`]), so that what the light pass leaves
    /// (vertex merging's light vertices) is shared by every camera path of the iteration.
    /// `Some(n)`: an iteration takes at most `n` camera samples (its memory bound; at least
    /// one tile's), so the tiles are cut into groups of that many pixels. `None` (the
    /// default): every batch is rendered on its own, and the other iteration methods are
    /// never called.
    fn iteration_paths(&self) -> Option<usize> {
        None
    }

    /// An iteration of the sample index `sample` of `camera_samples` pixels (those its group
    /// of tiles renders) begins; its light pass follows.
    fn begin_iteration(&self, sample: u32, camera_samples: usize) {
        let _ = (sample, camera_samples);
    }

    /// The light pass of one batch of the iteration: the same batch (pixels, sample indices,
    /// seeds) is handed to [`Integrator::run_batch`] after [`Integrator::end_light_pass`].
    /// Its paths' radiance is not read. Defaults to nothing.
    fn light_pass(
        &self,
        scene: &CompiledScene,
        batch: &PathBatch,
        worker: &mut Self::Worker,
        stats: &mut SystemStats,
        arena: &Bump,
    ) {
        let _ = (scene, batch, worker, stats, arena);
    }

    /// Every batch of the iteration has had its light pass; their camera passes follow.
    /// What it does between them is recorded in `stats` (one tile's of the group).
    fn end_light_pass(&self, stats: &mut SystemStats) {
        let _ = stats;
    }
}

/// Film plus AOV accumulators for one tile.
pub struct TileFilm {
    /// Beauty.
    pub film: Film,
    /// Sums of first-hit albedo, normal and depth.
    pub aovs: AovFilm,
    /// Tile origin in the image.
    pub x0: u32,
    /// Tile origin in the image.
    pub y0: u32,
    /// Adaptive sampling's sample indices for the next pass, one range per pixel (row-major
    /// in the tile): pixel `local` takes `sample_ranges[local]`, nothing when it is empty (a
    /// pixel that stopped). Empty: every pixel takes the pass's range.
    pub sample_ranges: Vec<std::ops::Range<u32>>,
    /// XORed into the scene's seed for this tile's pixel seeds: 0 for an image's tiles.
    pub seed_salt: u64,
}

impl TileFilm {
    /// An empty tile.
    pub fn new(x0: u32, y0: u32, w: u32, h: u32) -> Self {
        Self::with_aovs(x0, y0, Film::new(w, h), AovFilm::new(w, h))
    }

    /// An empty tile whose AOVs are not kept ([`AovFilm::without_sums`]): the beauty alone,
    /// 52 of a tile's 108 bytes a pixel (an adaptive render's pilot).
    pub fn without_aovs(x0: u32, y0: u32, w: u32, h: u32) -> Self {
        Self::with_aovs(x0, y0, Film::new(w, h), AovFilm::without_sums(w, h))
    }

    /// A tile at `(x0, y0)` of `film` and `aovs`, every pixel sampling.
    fn with_aovs(x0: u32, y0: u32, film: Film, aovs: AovFilm) -> Self {
        TileFilm {
            film,
            aovs,
            x0,
            y0,
            sample_ranges: Vec::new(),
            seed_salt: 0,
        }
    }

    /// How many of the tile's pixels take samples.
    pub fn active_pixels(&self) -> usize {
        let n = (self.film.width * self.film.height) as usize;
        (0..n).filter(|&local| self.is_active(local)).count()
    }

    /// Whether the pixel `local` (row-major in the tile) takes samples.
    #[inline]
    pub fn is_active(&self, local: usize) -> bool {
        self.sample_ranges.get(local).is_none_or(|r| !r.is_empty())
    }

    /// The sample indices pixel `local` takes in a pass of `samples`.
    #[inline]
    fn pixel_samples(&self, local: usize, samples: &std::ops::Range<u32>) -> std::ops::Range<u32> {
        self.sample_ranges.get(local).unwrap_or(samples).clone()
    }

    fn local(&self, pixel: u32, image_width: u32) -> u32 {
        let (x, y) = (pixel % image_width, pixel / image_width);
        (y - self.y0) * self.film.width + (x - self.x0)
    }
}

/// A worker's state for [`render_tile`]: the integrator's own, the batch and the film
/// coordinates of its paths.
#[derive(Default)]
pub struct TileWorker<W> {
    /// The integrator's worker state.
    pub integrator: W,
    /// The batch being rendered.
    pub batch: PathBatch,
    /// The film pixel (row in the tile) of each path.
    film_pixel: Vec<u32>,
    /// The next sample index of each pixel of the tile in the pass under way.
    next_sample: Vec<u32>,
}

/// Renders the samples `samples` of every pixel of `tile` (or each pixel's own range, when
/// the tile has [`TileFilm::sample_ranges`]) with `integrator`, in batches of about
/// `batch_size` paths, splatting into `tile`.
#[allow(clippy::too_many_arguments, reason = "the scheduler's inputs, named")]
pub fn render_tile<I: Integrator>(
    integrator: &I,
    scene: &CompiledScene,
    tile: &mut TileFilm,
    samples: std::ops::Range<u32>,
    batch_size: usize,
    worker: &mut TileWorker<I::Worker>,
    stats: &mut SystemStats,
    arena: &mut Bump,
    progress: &dyn Fn(u64),
) {
    for_each_batch(scene, tile, samples, batch_size, worker, |tile, w| {
        let TileWorker {
            integrator: state,
            batch,
            film_pixel,
            ..
        } = w;
        integrator.run_batch(scene, batch, state, stats, arena);
        splat_batch(tile, film_pixel, &batch.paths, stats);
        let n = batch.paths.len();
        stats.add_samples(n);
        arena.reset();
        progress(n as u64);
    })
}

/// The light pass of an iteration over `tile` ([`Integrator::light_pass`]): the batches
/// [`render_tile`] makes of the same arguments, handed to the integrator's light pass. The
/// film is not touched.
#[allow(clippy::too_many_arguments, reason = "the scheduler's inputs, named")]
pub fn light_pass_tile<I: Integrator>(
    integrator: &I,
    scene: &CompiledScene,
    tile: &mut TileFilm,
    samples: std::ops::Range<u32>,
    batch_size: usize,
    worker: &mut TileWorker<I::Worker>,
    stats: &mut SystemStats,
    arena: &mut Bump,
) {
    for_each_batch(scene, tile, samples, batch_size, worker, |_, w| {
        integrator.light_pass(scene, &w.batch, &mut w.integrator, stats, arena);
        arena.reset();
    })
}

/// Cuts the samples of `tile`'s pixels in a pass of `samples` (each pixel's own range when
/// adaptive sampling gave it one, [`TileFilm::sample_ranges`]) into batches of about
/// `batch_size` paths (one path per pixel and sample, pixel-major) and hands each, filled
/// into `worker`, to `run`.
///
/// Each batch takes the same number of samples from every pixel that has some left, as many
/// as fill the batch: so a pass whose pixels all take the same range is cut as it always
/// was, and one whose pixels take ranges of different lengths still fills its batches as
/// pixels run out. A pixel's samples go in their order, so its sums are added in sample
/// order however the pass is cut.
fn for_each_batch<W>(
    scene: &CompiledScene,
    tile: &mut TileFilm,
    samples: std::ops::Range<u32>,
    batch_size: usize,
    worker: &mut TileWorker<W>,
    mut run: impl FnMut(&mut TileFilm, &mut TileWorker<W>),
) {
    let w = tile.film.width;
    let n = (w * tile.film.height) as usize;
    worker.next_sample.clear();
    (worker.next_sample).extend((0..n).map(|local| tile.pixel_samples(local, &samples).start));
    loop {
        let TileWorker {
            batch,
            film_pixel,
            next_sample,
            ..
        } = &mut *worker;
        // The samples each pixel has left, and how many of them this batch takes.
        let left = |next_sample: &[u32], local: usize| {
            let end = tile.pixel_samples(local, &samples).end;
            end.saturating_sub(next_sample[local])
        };
        let pixels = (0..n).filter(|&local| left(next_sample, local) > 0).count();
        if pixels == 0 {
            return;
        }
        // Saturating: a batch size of 2^40 paths must mean "all samples at once", not a
        // truncated or wrapped sample range (which never advanced a pixel).
        let per_pixel = (batch_size / pixels).clamp(1, u32::MAX as usize) as u32;
        let count = (0..n)
            .map(|local| left(next_sample, local).min(per_pixel) as usize)
            .sum();
        // One path per pixel and sample, pixel-major; radiance, albedo and normal start
        // black (the defaults), depth at infinity (no hit yet). `film_pixel` is the film
        // pixel of each path: row `y * w + x` of the tile for the run of pixel (x, y)
        // (`TileFilm::local` of its image pixel, without two integer divisions per path).
        batch.paths.clear();
        film_pixel.clear();
        let paths = batch.paths.append_default(count);
        let mut at = 0;
        for local in 0..n {
            let take = left(next_sample, local).min(per_pixel);
            if take == 0 {
                continue;
            }
            let (x, y) = (local as u32 % w, local as u32 / w);
            let s0 = next_sample[local];
            paths.pixel[at..at + take as usize]
                .fill((tile.y0 + y) * scene.camera.width + tile.x0 + x);
            for (v, s) in paths.sample[at..at + take as usize].iter_mut().zip(s0..) {
                *v = s;
            }
            film_pixel.extend(std::iter::repeat_n(local as u32, take as usize));
            next_sample[local] = s0 + take;
            at += take as usize;
        }
        paths.depth.fill(f32::INFINITY);
        debug_assert!(film_pixel
            .iter()
            .zip(&batch.paths.pixel)
            .all(|(&local, &pixel)| local == tile.local(pixel, scene.camera.width)));
        // Paths come in runs of one pixel's samples: mix each pixel's seed once per run.
        let seed = scene.settings.seed ^ tile.seed_salt;
        let mut last: Option<(u32, u32)> = None;
        batch.seeds.clear();
        batch
            .seeds
            .extend(batch.paths.pixel.iter().map(|&pixel| match last {
                Some((p, s)) if p == pixel => s,
                _ => {
                    let s = pixel_seed(seed, pixel);
                    last = Some((pixel, s));
                    s
                }
            }));
        run(tile, worker);
    }
}

/// Splat stage: the film gets one sample per path, the AOV sums their first-hit values.
fn splat_batch(tile: &mut TileFilm, film_pixel: &[u32], paths: &Paths, stats: &mut SystemStats) {
    let n = paths.len();
    let dropped = stats.time(System::Splat, n, || {
        splat(&mut tile.film, film_pixel, &paths.radiance)
    });
    stats.drop_nan(dropped as usize);
    let aovs = paths.albedo.iter().zip(&paths.normal).zip(&paths.depth);
    // Runs of `spp` paths per film pixel: each pixel's sums are added up in registers, in
    // path order (the same bits as adding to the film per path, without a store and reload
    // between additions).
    let sums = &mut tile.aovs;
    if !sums.holds_sums() {
        return;
    }
    let (mut p, mut run) = (usize::MAX, ([0.0f64; 3], [0.0f64; 3], 0.0f64));
    for (&q, ((&albedo, &normal), &d)) in film_pixel.iter().zip(aovs) {
        let q = q as usize;
        if q != p {
            if p != usize::MAX {
                (sums.albedo[p], sums.normal[p], sums.depth[p]) = run;
            }
            p = q;
            run = (sums.albedo[p], sums.normal[p], sums.depth[p]);
        }
        let (a, n) = (albedo.to_array(), normal.to_array());
        for c in 0..3 {
            run.0[c] += a[c] as f64;
            run.1[c] += n[c] as f64;
        }
        run.2 += if d.is_finite() { d as f64 } else { 0.0 };
    }
    if p != usize::MAX {
        (sums.albedo[p], sums.normal[p], sums.depth[p]) = run;
    }
}
