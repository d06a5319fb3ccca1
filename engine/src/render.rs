//! Rendering a compiled scene: the image is cut into tiles (work items); each rayon worker
//! renders whole tiles, batch by batch, with its own tables and arena. A tile's samples are
//! splatted in a fixed order, so the image does not depend on the number of threads.

use crate::integrator::{
    render_tile, Integrator, LightingTechnique, PathTracer, TileFilm, TileWorker,
};
use crate::output::Image;
use crate::scene::CompiledScene;
use crate::stats::{RenderStats, SystemStats};
use bumpalo::Bump;
use glam::Vec3;
use rayon::prelude::*;
use risotto_components::Rgb;
use risotto_systems::film::Film;
use risotto_systems::independent_sampler::SamplerKind;

/// Options of one render that are not part of the scene.
#[derive(Clone, Copy, Debug)]
pub struct RenderOptions {
    /// Worker threads. Defaults to `None`: all cores.
    pub threads: Option<usize>,
    /// Paths per batch. Defaults to 4096.
    pub batch_size: usize,
    /// Tile edge in pixels. Defaults to 16.
    pub tile_size: u32,
    /// Direct-lighting technique. Defaults to MIS.
    pub technique: LightingTechnique,
    /// Sampler (the `sampler` technique). Defaults to Sobol.
    pub sampler: SamplerKind,
    /// Scattering-media techniques over what each medium says (the `scattering` technique).
    /// Defaults to none (as the scene says).
    pub volume: crate::plugin::VolumeTechniques,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            threads: None,
            batch_size: 4096,
            tile_size: 16,
            technique: LightingTechnique::Mis,
            sampler: SamplerKind::Sobol,
            volume: Default::default(),
        }
    }
}

/// What a render produces.
pub struct RenderOutput {
    /// Mean radiance per pixel.
    pub beauty: Image,
    /// Variance of the mean per pixel and channel.
    pub variance: Image,
    /// Samples per pixel.
    pub sample_count: Vec<f32>,
    /// Mean first-hit albedo.
    pub albedo: Image,
    /// Mean first-hit shading normal.
    pub normal: Image,
    /// Mean first-hit distance (0 where the camera saw nothing).
    pub depth: Vec<f32>,
    /// Statistics.
    pub stats: RenderStats,
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
}

/// Renders `scene` with the path tracer (`options.technique` for direct lighting).
/// `progress` is called with the number of samples finished, from worker threads.
pub fn render(
    scene: &CompiledScene,
    options: &RenderOptions,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<RenderOutput, RenderError> {
    let tracer = PathTracer {
        technique: options.technique,
        volume: options.volume,
    };
    render_with(&tracer, scene, options, progress)
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
    let start = std::time::Instant::now();
    let (w, h) = (scene.camera.width, scene.camera.height);
    let ts = options.tile_size.max(1);
    let mut tiles = Vec::new();
    for y0 in (0..h).step_by(ts as usize) {
        for x0 in (0..w).step_by(ts as usize) {
            tiles.push((x0, y0, ts.min(w - x0), ts.min(h - y0)));
        }
    }
    // The sampler travels in the sample addresses (`SamplerKind::address`).
    let samples = options.sampler.addresses(0..scene.settings.spp);
    let work = || -> Vec<(TileFilm, SystemStats)> {
        tiles
            .par_iter()
            .map_init(
                || (TileWorker::<I::Worker>::default(), Bump::new()),
                |(tables, arena), &(x0, y0, tw, th)| {
                    let mut tile = TileFilm::new(x0, y0, tw, th);
                    let mut stats = SystemStats::default();
                    render_tile(
                        integrator,
                        scene,
                        &mut tile,
                        samples.clone(),
                        options.batch_size,
                        tables,
                        &mut stats,
                        arena,
                        progress,
                    );
                    (tile, stats)
                },
            )
            .collect()
    };
    let results = match options.threads {
        Some(threads) => rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| RenderError::ThreadPool {
                threads,
                message: e.to_string(),
            })?
            .install(work),
        None => work(),
    };

    let mut film = Film::new(w, h);
    let n = (w * h) as usize;
    let mut albedo = vec![Rgb::BLACK; n];
    let mut normal = vec![Vec3::ZERO; n];
    let mut depth = vec![0.0f32; n];
    let mut counters = SystemStats::default();
    for (tile, stats) in &results {
        film.add_tile(&tile.film, tile.x0, tile.y0);
        for ty in 0..tile.film.height {
            for tx in 0..tile.film.width {
                let src = (ty * tile.film.width + tx) as usize;
                let dst = ((tile.y0 + ty) * w + tile.x0 + tx) as usize;
                albedo[dst] = tile.albedo[src];
                normal[dst] = tile.normal[src];
                depth[dst] = tile.depth[src];
            }
        }
        counters.merge(stats);
    }
    let mean = |v: Rgb, i: usize| {
        let c = film.count[i].max(1) as f32;
        v / c
    };
    let image = |f: &dyn Fn(usize) -> Rgb| Image {
        width: w as usize,
        height: h as usize,
        pixels: (0..n).map(f).collect(),
    };
    let beauty = image(&|i| film.mean(i));
    let variance = image(&|i| film.variance_of_mean(i));
    let albedo_img = image(&|i| mean(albedo[i], i));
    let normal_img = image(&|i| {
        let v = normal[i] / film.count[i].max(1) as f32;
        Rgb::new(v.x, v.y, v.z)
    });
    let depth = (0..n)
        .map(|i| depth[i] / film.count[i].max(1) as f32)
        .collect();
    let sample_count = film.count.iter().map(|&c| c as f32).collect();
    let mut stats = RenderStats::new(counters, start.elapsed().as_secs_f64());
    stats.features = scene.features.names();
    validate_boundaries(scene, &mut stats);
    Ok(RenderOutput {
        beauty,
        variance,
        sample_count,
        albedo: albedo_img,
        normal: normal_img,
        depth,
        stats,
    })
}

/// The boundary validator: one warning per shape whose crossings corrupted volume stacks
/// (rays leaving it without having entered, entering it twice, or escaping the scene while
/// inside it), when that happened often enough not to be floating-point chance: at grazing
/// angles a ray can miss the far side of a closed shape by an ulp, which no scene can avoid
/// and which costs nothing visible. The threshold: at least 16 rays and one in 10^5 of all
/// rays traced.
fn validate_boundaries(scene: &CompiledScene, stats: &mut RenderStats) {
    let threshold = (stats.counters.rays / 100_000).max(16);
    let c = &stats.counters;
    let kinds: [(&[u64], &str); 3] = [
        (
            &c.unmatched_exits,
            "rays crossed its back face without having entered it",
        ),
        (
            &c.entered_twice,
            "rays crossed its front face while already inside it",
        ),
        (
            &c.escaped_inside,
            "rays left the scene while inside its volume",
        ),
    ];
    let mut warnings = Vec::new();
    for (counts, what) in kinds {
        for (shape, &n) in counts.iter().enumerate() {
            if n >= threshold {
                warnings.push(format!(
                    "shape \"{}\": {n} {what}; its boundary may not be closed (or its \
                     normals are inconsistent)",
                    scene.shapes[shape].name
                ));
            }
        }
    }
    stats.warnings.extend(warnings);
}
