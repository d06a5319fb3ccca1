//! The global integrator (a path tracer) and the per-batch scheduler that pipes tables between
//! the systems.
//!
//! One batch goes through, per bounce (compare pbrt-v4's wavefront integrator):
//! `trace` (partition -> nearest hits or a volume integrator's `nearest_hits`, repeated for
//! pass-throughs) -> `escaped` (environment) -> `shade` (emission, Bxdf, direct lighting,
//! Russian roulette, next rays) -> `transmission` (shadow rays) -> next bounce; finished paths
//! are splatted. Stages a scene does not need (volumes, partitioning, transmission walks
//! through surfaces) are skipped according to the compiled scene's [`Features`](crate::scene::Features).
//!
//! Depth convention (Mitsuba's `max_depth`): a path of `k` segments has `k - 1` scattering
//! vertices; emitters seen along segment `k` count only if `k <= max_depth`.

use crate::context::{HitScratch, IntegratorContext};
use crate::plugin::*;
use crate::scene::CompiledScene;
use crate::stats::{System, SystemStats, Termination};
use bumpalo::Bump;
use glam::{BVec4A, Vec3, Vec4};
use risotto_components::*;
use risotto_systems::camera::push_camera_rays;
use risotto_systems::film::{splat, Film};
use risotto_systems::lights::{power_heuristic, LightSample, LightSampleColumns};
use risotto_systems::partition::partition_by_key;
use risotto_systems::sampler::{next_4d_column, pixel_seed, sample_1d, PathSampler};

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

/// Sampler dimensions each scattering vertex reserves: light position (0, 1), light selection
/// (2), Russian roulette (3), Bxdf (4..8). Paths start at a multiple of 4
/// (`FIRST_PATH_DIMENSION`), so each group of four is one aligned set of the sampler (one
/// SIMD Sobol evaluation), and the 2D samples (light position, the Bxdf's first two) take
/// the set's first two dimensions, Sobol's best-stratified pair.
const DIMS_PER_VERTEX: u32 = 8;

/// Offset for spawning rays off a surface, relative to the coordinates' magnitude so that tiny
/// and huge scenes both work: about 4 ulps of the largest coordinate (f32 ulp = 1.19e-7
/// relative). That is above the rounding error of a hit point (barycentric interpolation:
/// pbrt-v4 sec. 6.8.6 bounds it by gamma(7) sum |b_i p_i|, under one ulp; sphere points are
/// `centre + n r` rounded once or twice), and the triangle test also rejects re-hits within
/// its conservative t bound, while surfaces a few ulps apart stay separable
/// (`tests/continuation_budget.rs` crosses layers 2e-6 apart at unit scale).
#[inline]
pub fn ray_offset(p: Vec3) -> f32 {
    p.abs().max_element() * 5e-7 + 1e-9
}

/// Per-worker reusable tables for one batch.
#[derive(Default)]
pub struct BatchTables {
    paths: Paths,
    rays: Rays,
    pending: Rays,
    incoming: Rays,
    bundle: Rays,
    next: Rays,
    groups: ShadeGroups,
    tmp: ShadeGroups,
    shadow: ShadowRays,
    /// Storage for the shade stage's shadow rays: the dead rows of the last transmission
    /// stage, overwritten (`ShadowRays::reuse_rows`) and then moved to `shadow`.
    shadow_spare: ShadowRays,
    samples: BxdfSamples,
    samplers: Vec<PathSampler>,
    seeds: Vec<u32>,
    pixel_tmp: Vec<u32>,
    /// Light-sample columns of the group being shaded (`LightSampleColumns`; the
    /// directions are `wi_tmp`).
    light_distance: Vec<f32>,
    light_radiance: Vec<Rgb>,
    light_pdf: Vec<f32>,
    light_delta: Vec<bool>,
    eval_value: Vec<Rgb>,
    eval_pdf: Vec<f32>,
    wi_tmp: Vec<Vec3>,
    keys: Vec<u32>,
    order: Vec<u32>,
    runs: Vec<(u32, std::ops::Range<usize>)>,
    albedo_tmp: Vec<Rgb>,
    hit_scratch: HitScratch,
    /// The vertex's first four sampler dimensions (light position, light selection, Russian
    /// roulette) of each point of the group being shaded; without light sampling only the
    /// roulette's (index 3) is drawn.
    u4: Vec<[f32; 4]>,
    /// Whether some emissive shape has the material (per material index): the shade stage
    /// looks for emitters only in the groups of those materials.
    emissive_material: Vec<bool>,
    /// Contributions of the shadow rays, attenuated by the transmission stage.
    contribution: Vec<Rgb>,
    /// Points of the group being shaded whose light sample may give a shadow ray.
    shadow_points: Vec<u32>,
    /// Whether each point of the group being shaded may continue its path (the next
    /// segment fits in `max_depth`): light sampling skips the others.
    active: Vec<bool>,
    /// Which shading points stay in the groups (pass-through points leave).
    keep: Vec<bool>,
    /// Number of kept points before each point (prefix sums of `keep`).
    kept_before: Vec<u32>,
}

/// Film plus optional AOV accumulators for one tile.
pub struct TileFilm {
    /// Beauty.
    pub film: Film,
    /// Sum of first-hit albedo.
    pub albedo: Vec<Rgb>,
    /// Sum of first-hit normals.
    pub normal: Vec<Vec3>,
    /// Sum of first-hit depths.
    pub depth: Vec<f32>,
    /// Tile origin in the image.
    pub x0: u32,
    /// Tile origin in the image.
    pub y0: u32,
}

impl TileFilm {
    /// An empty tile.
    pub fn new(x0: u32, y0: u32, w: u32, h: u32) -> Self {
        let n = (w * h) as usize;
        TileFilm {
            film: Film::new(w, h),
            albedo: vec![Rgb::BLACK; n],
            normal: vec![Vec3::ZERO; n],
            depth: vec![0.0; n],
            x0,
            y0,
        }
    }
    fn local(&self, pixel: u32, image_width: u32) -> u32 {
        let (x, y) = (pixel % image_width, pixel / image_width);
        (y - self.y0) * self.film.width + (x - self.x0)
    }
}

/// The path tracer.
#[derive(Clone, Copy, Debug, Default)]
pub struct PathTracer {
    /// Direct-lighting technique.
    pub technique: LightingTechnique,
}

/// Lighting delegate the path tracer hands to volume integrators: it samples lights at
/// volume points and queues shadow rays, traced with all others in the batch's transmission
/// stage.
struct DirectLighting<'a> {
    scene: &'a CompiledScene,
    shadow: &'a mut ShadowRays,
    light_samples: Vec<Option<LightSample>>,
    wi: Vec<Vec3>,
    value: Vec<Rgb>,
    pdf: Vec<f32>,
}

impl LightingDelegate for DirectLighting<'_> {
    fn perform_direct_lighting(
        &mut self,
        ctx: &ShadingContext<'_>,
        bxdf: &mut dyn Bxdf,
        rays: &Rays,
        samplers: &mut [PathSampler],
        weight: &[Rgb],
    ) {
        let n = ctx.num_points();
        self.light_samples.clear();
        self.wi.clear();
        for i in 0..n {
            let ray = ctx.ray_id()[i] as usize;
            let s = &mut samplers[ray];
            let sel = s.next_1d();
            let u = s.next_2d();
            let ls = self
                .scene
                .lights
                .sample(&self.scene.geometry, ctx.p()[i], sel, u);
            self.wi.push(ls.map_or(Vec3::Z, |l| l.wi));
            self.light_samples.push(ls);
        }
        self.value.resize(n, Rgb::BLACK);
        self.pdf.resize(n, 0.0);
        bxdf.evaluate_samples(ctx, &self.wi, &mut self.value, &mut self.pdf);
        for i in 0..n {
            let Some(ls) = self.light_samples[i] else {
                continue;
            };
            let ray = ctx.ray_id()[i] as usize;
            let mis = if ls.delta {
                1.0
            } else {
                power_heuristic(ls.pdf, self.pdf[i])
            };
            let c = rays.throughput[ray] * weight[i] * self.value[i] * ls.radiance * (mis / ls.pdf);
            if c.is_black() {
                continue;
            }
            self.shadow.push(ShadowRayRow {
                origin: ctx.p()[i],
                direction: ls.wi,
                tmax: ls.distance * (1.0 - 1e-4),
                contribution: c,
                path: rays.path[ray],
                volume_stack: rays.volume_stack[ray].clone(),
            });
        }
    }
}

impl PathTracer {
    /// Renders the samples `samples` of every pixel of `tile`, in batches of about
    /// `batch_size` paths, splatting into `tile`.
    #[allow(clippy::too_many_arguments, reason = "the scheduler's inputs, named")]
    pub fn render_tile(
        &self,
        scene: &CompiledScene,
        tile: &mut TileFilm,
        samples: std::ops::Range<u32>,
        batch_size: usize,
        tables: &mut BatchTables,
        stats: &mut SystemStats,
        arena: &mut Bump,
        progress: &dyn Fn(u64),
    ) {
        let w = tile.film.width;
        let h = tile.film.height;
        let pixels = (w * h) as usize;
        let per_batch = (batch_size / pixels.max(1)).max(1) as u32;
        let mut s0 = samples.start;
        while s0 < samples.end {
            let s1 = (s0 + per_batch).min(samples.end);
            let t = &mut *tables;
            // One path per pixel and sample, pixel-major; radiance, albedo and normal start
            // black (the defaults), depth at infinity (no hit yet).
            t.paths.clear();
            let count = pixels * (s1 - s0) as usize;
            let paths = t.paths.append_default(count);
            let spp = (s1 - s0) as usize;
            let mut rows = paths
                .pixel
                .chunks_exact_mut(spp)
                .zip(paths.sample.chunks_exact_mut(spp));
            for y in 0..h {
                for x in 0..w {
                    let (pixel, sample) = rows.next().expect("one run of rows per pixel");
                    pixel.fill((tile.y0 + y) * scene.camera.width + tile.x0 + x);
                    for (v, s) in sample.iter_mut().zip(s0..s1) {
                        *v = s;
                    }
                }
            }
            paths.depth.fill(f32::INFINITY);
            // The film pixel of each path: row `y * w + x` of the tile for the run of
            // pixel (x, y) (`TileFilm::local` of its image pixel, without two integer
            // divisions per path).
            t.pixel_tmp.clear();
            for local in 0..pixels as u32 {
                t.pixel_tmp.extend(std::iter::repeat_n(local, spp));
            }
            debug_assert!(t
                .pixel_tmp
                .iter()
                .zip(&t.paths.pixel)
                .all(|(&local, &pixel)| local == tile.local(pixel, scene.camera.width)));
            self.run_batch(scene, t, stats, arena);
            // Splat: the film gets one sample per path.
            let n = t.paths.len();
            let dropped = stats.time(System::Splat, n, || {
                splat(&mut tile.film, &t.pixel_tmp, &t.paths.radiance)
            });
            stats.drop_nan(dropped as usize);
            let aovs = t
                .paths
                .albedo
                .iter()
                .zip(&t.paths.normal)
                .zip(&t.paths.depth);
            // Runs of `spp` paths per film pixel (see `pixel_tmp`): each pixel's sums are
            // added up in registers, in path order (the same bits as adding to the film
            // per path, without a store and reload between additions).
            let (mut p, mut sums) = (usize::MAX, (Rgb::BLACK, Vec3::ZERO, 0.0));
            for (&q, ((&albedo, &normal), &d)) in t.pixel_tmp.iter().zip(aovs) {
                let q = q as usize;
                if q != p {
                    if p != usize::MAX {
                        (tile.albedo[p], tile.normal[p], tile.depth[p]) = sums;
                    }
                    p = q;
                    sums = (tile.albedo[p], tile.normal[p], tile.depth[p]);
                }
                sums.0 += albedo;
                sums.1 += normal;
                sums.2 += if d.is_finite() { d } else { 0.0 };
            }
            if p != usize::MAX {
                (tile.albedo[p], tile.normal[p], tile.depth[p]) = sums;
            }
            stats.add_samples(n);
            arena.reset();
            progress(n as u64);
            s0 = s1;
        }
    }

    /// Runs every path of `t.paths` to completion, leaving their radiance in the table.
    pub fn run_batch(
        &self,
        scene: &CompiledScene,
        t: &mut BatchTables,
        stats: &mut SystemStats,
        arena: &Bump,
    ) {
        let n = t.paths.len();
        t.seeds.clear();
        let seed = scene.settings.seed;
        // Paths come in runs of one pixel's samples: mix each pixel's seed once per run.
        let mut last: Option<(u32, u32)> = None;
        t.seeds
            .extend(t.paths.pixel.iter().map(|&pixel| match last {
                Some((p, s)) if p == pixel => s,
                _ => {
                    let s = pixel_seed(seed, pixel);
                    last = Some((pixel, s));
                    s
                }
            }));
        // Camera rays, generated straight into the table's columns.
        t.rays.clear();
        stats.time(System::Camera, n, || {
            push_camera_rays(
                &scene.camera,
                &t.paths.pixel,
                &t.paths.sample,
                &t.seeds,
                &scene.camera_stack,
                &mut t.rays,
            )
        });
        t.rays.debug_check();
        stats.add_rays(n);
        // A point's material is its shape's (`IntegratorContext::nearest_hits`).
        t.emissive_material.clear();
        t.emissive_material.resize(scene.materials.len(), false);
        for shape in scene.shapes.iter().filter(|s| s.emission.is_some()) {
            t.emissive_material[shape.material as usize] = true;
        }
        let mut first_bounce = true;
        while !t.rays.is_empty() {
            self.trace(scene, t, stats, arena);
            self.shade(scene, t, stats, arena, first_bounce);
            self.transmission(scene, t, stats, arena);
            std::mem::swap(&mut t.rays, &mut t.next);
            t.next.clear();
            stats.add_rays(t.rays.len());
            first_bounce = false;
        }
    }

    fn sampler(&self, t: &BatchTables, rays: &Rays, i: usize) -> PathSampler {
        let path = rays.path[i] as usize;
        PathSampler {
            seed: t.seeds[path],
            sample: t.paths.sample[path],
            dimension: rays.dimension[i],
        }
    }

    /// Trace stage: finds the next shading points of `t.rays` (through volume integrators
    /// where rays travel in a volume), following pass-throughs, and handles escaped rays.
    /// Leaves `t.incoming` (the rays, with throughput including transmission) and
    /// `t.groups` (points whose `ray_id` indexes `t.incoming`).
    fn trace(
        &self,
        scene: &CompiledScene,
        t: &mut BatchTables,
        stats: &mut SystemStats,
        arena: &Bump,
    ) {
        let features = scene.features;
        // The last bounce's rays are dead: their rows become the storage the shade stage
        // overwrites with the next rays (`Rays::reuse_rows`), which spares it writing
        // defaults into every column of fresh rows first.
        std::mem::swap(&mut t.incoming, &mut t.next);
        t.incoming.clear();
        t.groups.clear();
        std::mem::swap(&mut t.pending, &mut t.rays);
        t.rays.clear();
        while !t.pending.is_empty() {
            if features.volumes {
                self.trace_partitioned(scene, t, stats, arena);
            } else if t.incoming.is_empty() && t.groups.points.is_empty() {
                // First round (the only one unless there are pass-throughs): answer straight
                // into the groups and move the rays over instead of copying them.
                let scratch = std::mem::take(&mut t.hit_scratch);
                let mut ictx = IntegratorContext::with_scratch(scene, stats, scratch);
                ictx.nearest_hits(&t.pending, &mut t.groups);
                t.hit_scratch = ictx.into_scratch();
                std::mem::swap(&mut t.incoming, &mut t.pending);
            } else {
                t.tmp.clear();
                let scratch = std::mem::take(&mut t.hit_scratch);
                let mut ictx = IntegratorContext::with_scratch(scene, stats, scratch);
                ictx.nearest_hits(&t.pending, &mut t.tmp);
                t.hit_scratch = ictx.into_scratch();
                append_groups(&mut t.groups, &mut t.incoming, &t.tmp, &t.pending);
            }
            t.pending.clear();
            self.escaped_and_passes(scene, t, stats);
        }
    }

    /// Partitions `t.pending` into bundles by the volumes the rays travel in and the transmit
    /// bit, and runs each bundle through its innermost volume's integrator (or plain nearest
    /// hits when in no volume).
    fn trace_partitioned(
        &self,
        scene: &CompiledScene,
        t: &mut BatchTables,
        stats: &mut SystemStats,
        arena: &Bump,
    ) {
        let n = t.pending.len();
        // Distinct stacks of this round (few: rays in one scene share a handful of states).
        let mut stacks: Vec<VolumeStack> = Vec::new();
        t.keys.clear();
        stats.time(System::Partition, n, || {
            for i in 0..n {
                let s = &t.pending.volume_stack[i];
                let id = match stacks.iter().position(|x| x == s) {
                    Some(id) => id,
                    None => {
                        stacks.push(s.clone());
                        stacks.len() - 1
                    }
                };
                let transmit = t.pending.lobe[i].is_transmit() as u32;
                t.keys.push(id as u32 * 2 + transmit);
            }
            partition_by_key(&t.keys, stacks.len() * 2, &mut t.order, &mut t.runs);
        });
        let runs = std::mem::take(&mut t.runs);
        for (key, range) in &runs {
            let stack = &stacks[(*key / 2) as usize];
            t.bundle.clear();
            t.bundle.extend_gather(&t.pending, &t.order[range.clone()]);
            for (k, s) in t.bundle.shading_ctx_index.iter_mut().enumerate() {
                *s = k as u32;
            }
            t.tmp.clear();
            let inner = stack.innermost().filter(|e| {
                scene.material_info[e.material as usize]
                    .hints
                    .contains(InstanceHints::COMPUTES_INTERIOR)
            });
            match inner {
                None => {
                    let scratch = std::mem::take(&mut t.hit_scratch);
                    let mut ictx = IntegratorContext::with_scratch(scene, stats, scratch);
                    ictx.nearest_hits(&t.bundle, &mut t.tmp);
                    t.hit_scratch = ictx.into_scratch();
                }
                Some(entry) => {
                    let m = t.bundle.len();
                    let points = volume_points(&t.bundle, entry.material);
                    let others: Vec<VolumeEntry> = stack
                        .overlapping()
                        .filter(|e| {
                            scene.material_info[e.material as usize]
                                .hints
                                .contains(InstanceHints::COMPUTES_INTERIOR)
                        })
                        .collect();
                    let points = arena.alloc(points);
                    let ctx_plain = arena.alloc(ShadingContext::new(
                        points,
                        0..m,
                        ShadingMode::Interior,
                        entry.material,
                        &[],
                    ));
                    let overlapping: &[OverlappingVolume] =
                        arena.alloc_slice_fill_iter(others.iter().map(|e| {
                            let factory = scene.materials[e.material as usize].factory.as_ref();
                            OverlappingVolume {
                                entry: *e,
                                factory,
                                integrator: factory
                                    .begin_interior(ctx_plain, ShadingMode::Interior, arena)
                                    .map(|v| &*v),
                            }
                        }));
                    let ctx = arena.alloc(ShadingContext::new(
                        points,
                        0..m,
                        ShadingMode::Interior,
                        entry.material,
                        overlapping,
                    ));
                    let factory = scene.materials[entry.material as usize].factory.as_ref();
                    let integrator = factory
                        .begin_interior(ctx, ShadingMode::Interior, arena)
                        .expect("hint COMPUTES_INTERIOR promised an interior");
                    t.samplers.clear();
                    for i in 0..m {
                        let s = self.sampler(t, &t.bundle, i);
                        t.samplers.push(s);
                    }
                    let mut delegate = DirectLighting {
                        scene,
                        shadow: &mut t.shadow,
                        light_samples: Vec::new(),
                        wi: Vec::new(),
                        value: Vec::new(),
                        pdf: Vec::new(),
                    };
                    let lighting: Option<&mut dyn LightingDelegate> =
                        if self.technique == LightingTechnique::BxdfOnly {
                            None
                        } else {
                            Some(&mut delegate)
                        };
                    let scratch = std::mem::take(&mut t.hit_scratch);
                    let mut ictx = IntegratorContext::with_scratch(scene, stats, scratch);
                    let start = std::time::Instant::now();
                    integrator.nearest_hits(
                        &t.bundle,
                        &mut t.samplers,
                        LobeSampled(0xff),
                        &mut ictx,
                        lighting,
                        &mut t.tmp,
                    );
                    let elapsed = start.elapsed().as_secs_f64();
                    t.hit_scratch = ictx.into_scratch();
                    stats.record(System::Volume, m, elapsed);
                    for (i, s) in t.samplers.iter().enumerate() {
                        t.bundle.dimension[i] = s.dimension;
                    }
                    // Rays the integrator returned nothing for were absorbed in the volume.
                    let mut answered = vec![false; m];
                    for &r in t.tmp.points.ray_id.iter().chain(&t.tmp.misses) {
                        answered[r as usize] = true;
                    }
                    let absorbed = answered.iter().filter(|a| !**a).count();
                    stats.terminate(Termination::Absorbed, absorbed);
                }
            }
            append_groups(&mut t.groups, &mut t.incoming, &t.tmp, &t.bundle);
        }
        t.runs = runs;
    }

    /// Handles the rays that escaped (environment emission) and the points on pass-through
    /// boundaries (index-matched or false): those continue as new pending rays and are removed
    /// from the groups.
    fn escaped_and_passes(
        &self,
        scene: &CompiledScene,
        t: &mut BatchTables,
        stats: &mut SystemStats,
    ) {
        // Escaped rays: only misses appended this round are new; process and clear.
        let misses = std::mem::take(&mut t.groups.misses);
        let miss_tr = std::mem::take(&mut t.groups.miss_transmission);
        for (k, &r) in misses.iter().enumerate() {
            let r = r as usize;
            let path = t.incoming.path[r] as usize;
            let d = t.incoming.direction[r];
            let le = scene.lights.environment_radiance(d);
            if !le.is_black() && self.emission_counts(scene, &t.incoming, r) {
                let w = self.emitter_mis(&t.incoming, r, || scene.lights.environment_pdf(d));
                t.paths.radiance[path] += t.incoming.throughput[r] * miss_tr[k] * le * w;
            }
            if t.incoming.depth[r] == 0 && t.paths.depth[path].is_infinite() {
                t.paths.albedo[path] = le;
            }
        }
        stats.terminate(Termination::Escaped, misses.len());
        t.groups.misses = misses;
        t.groups.misses.clear();
        t.groups.miss_transmission = miss_tr;
        t.groups.miss_transmission.clear();

        if !scene.features.transmissive {
            return;
        }
        // Pass-throughs: index-matched surfaces and false boundaries never get shaded. Most
        // rounds have none; the points table is compacted (in place) only when some point
        // leaves it. `keep[i]`: point `i` stays (points outside every group do not).
        let groups = std::mem::take(&mut t.groups.groups);
        let n = t.groups.points.len();
        t.keep.clear();
        t.keep.resize(n, false);
        let mut passes = false;
        for g in &groups {
            if g.mode != ShadingMode::Scatter {
                t.keep[g.range.clone()].fill(true);
                continue;
            }
            let info = &scene.material_info[g.material as usize];
            let index_matched = info.hints.contains(InstanceHints::INDEX_MATCHED);
            let pts = &t.groups.points;
            for i in g.range.clone() {
                let r = pts.ray_id[i] as usize;
                let pass = index_matched
                    || t.incoming.volume_stack[r].is_false_boundary(pts.shape[i], info.priority);
                t.keep[i] = !pass;
                passes |= pass;
            }
        }
        if !passes && t.keep.iter().all(|&k| k) {
            t.groups.groups = groups;
            return;
        }
        for g in groups.iter().filter(|g| g.mode == ShadingMode::Scatter) {
            for i in g.range.clone() {
                if t.keep[i] {
                    continue;
                }
                let r = t.groups.points.ray_id[i] as usize;
                let shape = t.groups.points.shape[i];
                let p = t.groups.points.p[i];
                let front = t.groups.points.front_face[i];
                let tr = t.groups.points.transmission[i];
                // Emission on a pass-through surface still reaches the path.
                self.surface_emission(scene, t, r, i, tr);
                let mut row = t.incoming.row(r);
                if row.passes as u32 >= scene.settings.max_passes {
                    stats.terminate(Termination::PassLimit, 1);
                    continue;
                }
                row.passes += 1;
                row.throughput *= tr;
                if row.throughput.is_black() {
                    stats.terminate(Termination::Absorbed, 1);
                    continue;
                }
                // The ray goes on along the same line. It restarts on the boundary itself, so
                // that the next segment's length (what volume integrators attenuate by) is the
                // true distance, and skips the boundary with `tmin`: the spawn offset, measured
                // along the ray (clamped for grazing rays).
                let cos = row.direction.dot(t.groups.points.ng[i]).abs().max(1e-3);
                row.origin = p;
                row.tmin = ray_offset(p) / cos;
                row.tmax = f32::INFINITY;
                if scene.tracks_interior(shape)
                    && row.volume_stack.cross(scene.volume_entry(shape), front)
                        == StackEvent::UnmatchedExit
                {
                    stats.unmatched_exit(shape);
                }
                t.pending.push(row);
            }
        }
        // Compact: a group's range moves to the number of kept points before it.
        t.kept_before.clear();
        t.kept_before.push(0);
        let mut kept = 0;
        for &k in &t.keep {
            kept += k as u32;
            t.kept_before.push(kept);
        }
        t.groups.points.retain_rows(&t.keep);
        let kept_before = &t.kept_before;
        t.groups.groups = groups
            .into_iter()
            .filter_map(|g| {
                let range = kept_before[g.range.start] as usize..kept_before[g.range.end] as usize;
                // Surface groups left empty are dropped; volume groups stay as they were.
                (g.mode != ShadingMode::Scatter || !range.is_empty())
                    .then_some(ShadeGroup { range, ..g })
            })
            .collect();
    }

    /// Whether an emitter seen along ray `r` is inside the path-length budget.
    fn emission_counts(&self, scene: &CompiledScene, rays: &Rays, r: usize) -> bool {
        // The ray is segment depth+1 of its path.
        (rays.depth[r] as u32 + 1) <= scene.settings.max_depth
    }

    /// MIS weight of an emitter hit by ray `r` (Bxdf-sampled) against light sampling.
    fn emitter_mis(&self, rays: &Rays, r: usize, light_pdf: impl FnOnce() -> f32) -> f32 {
        if rays.depth[r] == 0 || rays.lobe[r].is_specular() || rays.pdf[r] <= 0.0 {
            return 1.0;
        }
        match self.technique {
            LightingTechnique::BxdfOnly => 1.0,
            LightingTechnique::NeeOnly => 0.0,
            LightingTechnique::Mis => power_heuristic(rays.pdf[r], light_pdf()),
        }
    }

    /// Adds the emission of the surface at point `i` (hit by incoming ray `r`), if any.
    fn surface_emission(
        &self,
        scene: &CompiledScene,
        t: &mut BatchTables,
        r: usize,
        i: usize,
        transmission: Rgb,
    ) {
        let pts = &t.groups.points;
        let shape = pts.shape[i];
        if shape == u32::MAX || !pts.front_face[i] {
            return;
        }
        let Some(le) = scene.shapes[shape as usize].emission else {
            return;
        };
        self.add_emission(
            scene,
            pts,
            &t.incoming,
            &mut t.paths,
            r,
            i,
            le,
            transmission,
        );
    }

    /// Adds the emission `le` of the front face of emissive shape at point `i` (hit by
    /// incoming ray `r`) to the ray's path, if inside the depth budget, MIS-weighted. Kept
    /// out of line: the shade loop tests the (rare) emissive front faces itself.
    #[allow(clippy::too_many_arguments, reason = "the columns it reads, named")]
    #[inline(never)]
    fn add_emission(
        &self,
        scene: &CompiledScene,
        pts: &ShadingPoints,
        incoming: &Rays,
        paths: &mut Paths,
        r: usize,
        i: usize,
        le: Rgb,
        transmission: Rgb,
    ) {
        if !self.emission_counts(scene, incoming, r) {
            return;
        }
        let shape = pts.shape[i];
        let p = pts.p[i];
        let ng = pts.ng[i];
        let prev = incoming.prev_p[r];
        let w = self.emitter_mis(incoming, r, || {
            light_pdf_at(scene, shape, prev, p, ng, incoming, r)
        });
        let path = incoming.path[r] as usize;
        paths.radiance[path] += incoming.throughput[r] * transmission * le * w;
    }

    /// Shade stage: emission, Bxdf sampling, direct lighting, Russian roulette, next rays.
    /// `first_bounce` is true when `t.incoming` may hold camera rays (the first iteration of
    /// the batch; later rays have scattered at least once), the only ones that record AOVs.
    ///
    /// The loops write the next rays and the shadow rays into rows appended up front for all
    /// groups ([`Rays::append_default`]) and truncate the unused ones at the end, instead of
    /// pushing row by row: a push checks capacity and stores the length of each of the 15
    /// columns.
    fn shade(
        &self,
        scene: &CompiledScene,
        t: &mut BatchTables,
        stats: &mut SystemStats,
        arena: &Bump,
        first_bounce: bool,
    ) {
        let settings = scene.settings;
        let features = scene.features;
        let BatchTables {
            paths,
            incoming,
            next,
            groups: shade_groups,
            shadow,
            shadow_spare,
            samples,
            samplers,
            seeds,
            light_distance,
            light_radiance,
            light_pdf,
            light_delta,
            eval_value,
            eval_pdf,
            wi_tmp,
            albedo_tmp,
            u4,
            emissive_material,
            shadow_points,
            active: active_tmp,
            ..
        } = t;
        let groups = std::mem::take(&mut shade_groups.groups);
        let pts = &shade_groups.points;
        let total: usize = groups.iter().map(|g| g.range.len()).sum();
        let shade_start = std::time::Instant::now();
        // Without materials that compute interiors or let rays cross their surface, no stack
        // ever gets an entry (only shapes of such materials are tracked, see
        // `CompiledScene::tracks_interior`): every stack is the empty default and the stack
        // columns need no per-row copies.
        let stacks = features.volumes || features.transmissive || !scene.camera_stack.is_empty();
        let light_sampling_possible =
            self.technique != LightingTechnique::BxdfOnly && !scene.lights.is_empty();
        // Every point spawns at most one shadow ray and one next ray: room for all of them
        // at once, truncated to the rows written after the last group.
        // `next` holds no live rows here, only the dead rows of an earlier bounce (see
        // `trace`), which `continue_paths` overwrites column by column.
        let mut shadow_out = shadow_spare.reuse_rows(total);
        let mut next_out = next.reuse_rows(total);
        next_out.tmin.fill(0.0);
        next_out.tmax.fill(f32::INFINITY);
        // Without stacks (see above) every stack, dead rows' included, is the empty default.
        debug_assert!(stacks || next_out.volume_stack.iter().all(VolumeStack::is_empty));
        debug_assert!(stacks || shadow_out.volume_stack.iter().all(VolumeStack::is_empty));
        let (mut shadow_len, mut next_len) = (0, 0);
        for g in &groups {
            let range = g.range.clone();
            let ray_id = &pts.ray_id[range.clone()];
            // The group's length as the slices' length, so that every column re-sliced to
            // it shares one bounds check.
            let m = ray_id.len();
            // Transmission of the incident segment multiplies the throughput first (only
            // volume integrators return points with transmission other than 1).
            if features.volumes {
                for (&r, &tr) in ray_id.iter().zip(&pts.transmission[range.clone()]) {
                    incoming.throughput[r as usize] *= tr;
                }
            }
            if features.area_lights && emissive_material[g.material as usize] {
                let shape = &pts.shape[range.clone()];
                let front = &pts.front_face[range.clone()];
                for (k, ((&r, &shape), &front)) in ray_id.iter().zip(shape).zip(front).enumerate() {
                    // The cheap tests of `surface_emission` first: most points are not on
                    // emitters.
                    if shape == u32::MAX || !front {
                        continue;
                    }
                    if let Some(le) = scene.shapes[shape as usize].emission {
                        // Throughput already includes the transmission.
                        let i = range.start + k;
                        self.add_emission(
                            scene,
                            pts,
                            incoming,
                            paths,
                            r as usize,
                            i,
                            le,
                            Rgb::WHITE,
                        );
                    }
                }
            }
            let ctx = ShadingContext::new(pts, range.clone(), g.mode, g.material, &[]);
            let factory = scene.materials[g.material as usize].factory.as_ref();
            let bxdf_start = std::time::Instant::now();
            let bxdf = factory.begin_scatter(&ctx, g.mode, arena);
            let lobes = bxdf.lobes();

            // Incoming-ray columns re-sliced to one length (one bounds check per gather).
            let n = incoming.len();
            let (in_depth, in_passes, in_path, in_dimension) = (
                &incoming.depth[..n],
                &incoming.passes[..n],
                &incoming.path[..n],
                &incoming.dimension[..n],
            );

            // AOVs at the first vertex.
            let first_vertex = |r: usize| in_depth[r] == 0 && in_passes[r] == 0;
            if first_bounce && ray_id.iter().any(|&r| first_vertex(r as usize)) {
                let albedo = scratch(albedo_tmp, m, Rgb::BLACK);
                bxdf.albedo(&ctx, albedo);
                let (nn, vlen) = (&pts.nn[range.clone()][..m], &pts.vlen[range.clone()][..m]);
                for k in 0..m {
                    let r = ray_id[k] as usize;
                    if first_vertex(r) {
                        let path = in_path[r] as usize;
                        paths.albedo[path] = albedo[k];
                        paths.normal[path] = nn[k];
                        paths.depth[path] = vlen[k];
                    }
                }
            }

            // Per-point samplers at this vertex's dimensions.
            let num_paths = paths.len();
            let (seed, sample) = (&seeds[..num_paths], &paths.sample[..num_paths]);
            // And which points may continue (the next segment must fit in max_depth), in
            // the same pass over the incoming rays.
            let active = scratch(active_tmp, m, false);
            samplers.clear();
            samplers.extend(ray_id.iter().zip(active.iter_mut()).map(|(&r, active)| {
                let r = r as usize;
                let path = in_path[r] as usize;
                *active = (in_depth[r] as u32 + 2) <= settings.max_depth;
                PathSampler {
                    seed: seed[path],
                    sample: sample[path],
                    dimension: in_dimension[r],
                }
            }));

            // The vertex's first four dimensions: light position, light selection, Russian
            // roulette (one SIMD Sobol evaluation when aligned, see DIMS_PER_VERTEX).
            // A buffer kept across groups: the draw overwrites it (an arena slice would be
            // zero-filled for every group first).
            let u4 = scratch(u4, m, [0.0; 4]);
            if light_sampling_possible && lobes.contains(LobeSampled::DIFFUSE) {
                let lstart = std::time::Instant::now();
                // The light samples' directions are where the Bxdf evaluates (`Vec3::Z`
                // where there is no sample).
                let mut light = LightSampleColumns {
                    wi: scratch(wi_tmp, m, Vec3::Z),
                    distance: scratch(light_distance, m, 0.0),
                    radiance: scratch(light_radiance, m, Rgb::BLACK),
                    pdf: scratch(light_pdf, m, 0.0),
                    delta: scratch(light_delta, m, false),
                };
                // One column draw for the group; leaves the samplers at the vertex's
                // dimension 4, where the Bxdf starts.
                next_4d_column(&mut samplers[..m], u4);
                scene.lights.sample_column(
                    &scene.geometry,
                    &pts.p[range.clone()][..m],
                    &*u4,
                    &*active,
                    &mut light,
                );
                stats.record(System::Lights, m, lstart.elapsed().as_secs_f64());
                let (value, pdf) = (
                    scratch(eval_value, m, Rgb::BLACK),
                    scratch(eval_pdf, m, 0.0),
                );
                bxdf.evaluate_samples(&ctx, light.wi, value, pdf);
                let (no_mis, mode) = (self.technique == LightingTechnique::NeeOnly, g.mode);
                let (shadow_scene, incoming) = (stacks.then_some(scene), &*incoming);
                let light = LightColumns {
                    samples: light,
                    value,
                    pdf,
                    points: scratch(shadow_points, m, 0),
                };
                shadow_len += spawn_shadow_rays(
                    shadow_scene,
                    mode,
                    pts,
                    range.clone(),
                    incoming,
                    light,
                    no_mis,
                    &mut shadow_out,
                    shadow_len,
                );
            } else {
                for (s, u) in samplers.iter_mut().zip(u4.iter_mut()) {
                    u[3] = sample_1d(s.seed, s.sample, s.dimension + 3);
                    // The Bxdf starts at the vertex's dimension 4.
                    s.dimension += 4;
                }
            }

            // Bxdf sampling for the next bounce.
            samples.reset(m);
            bxdf.generate_samples(&ctx, samplers, samples);
            stats.record(System::Bxdf, m, bxdf_start.elapsed().as_secs_f64());

            let stack_scene = stacks.then_some(scene);
            let (written, max_depth, absorbed, roulette) = continue_paths(
                stack_scene,
                settings,
                g.mode,
                pts,
                range.clone(),
                incoming,
                samples,
                u4,
                &mut next_out,
                next_len,
                stats,
            );
            next_len += written;
            stats.terminate(Termination::MaxDepth, max_depth);
            stats.terminate(Termination::Absorbed, absorbed);
            stats.terminate(Termination::RussianRoulette, roulette);
        }
        next.truncate(next_len);
        // The shadow rays go after those volume integrators queued during the trace stage.
        shadow_spare.truncate(shadow_len);
        if shadow.is_empty() {
            std::mem::swap(shadow, shadow_spare);
        } else {
            shadow.extend_from(shadow_spare);
        }
        stats.record(System::Shade, total, shade_start.elapsed().as_secs_f64());
        shade_groups.groups = groups;
    }

    /// Transmission stage: walks every shadow ray through the surfaces that let shadows pass
    /// and the volumes it crosses, then adds the surviving contributions to their paths.
    fn transmission(
        &self,
        scene: &CompiledScene,
        t: &mut BatchTables,
        stats: &mut SystemStats,
        arena: &Bump,
    ) {
        let n = t.shadow.len();
        if n == 0 {
            return;
        }
        let start = std::time::Instant::now();
        t.contribution.clear();
        t.contribution.extend_from_slice(&t.shadow.contribution);
        crate::transmission::trace_shadow_rays(
            scene,
            &t.shadow,
            &t.paths,
            &t.seeds,
            &mut t.contribution,
            stats,
            arena,
        );
        for (&path, &c) in t.shadow.path.iter().zip(&t.contribution) {
            t.paths.radiance[path as usize] += c;
        }
        stats.record(System::Transmission, n, start.elapsed().as_secs_f64());
        // Keep the dead rows as storage for the next shade stage's shadow rays.
        std::mem::swap(&mut t.shadow, &mut t.shadow_spare);
        t.shadow.clear();
    }
}

/// Light samples of a group's points and the Bxdf's response to them.
struct LightColumns<'a> {
    /// Light sample per point (pdf 0: no shadow ray).
    samples: LightSampleColumns<'a>,
    /// Bxdf value `f * |cos|` for the sample's direction.
    value: &'a [Rgb],
    /// Bxdf pdf of the sample's direction (for MIS); overwritten with the contribution
    /// factor [`light_weights`].
    pdf: &'a mut [f32],
    /// Scratch: the points that may get a shadow ray.
    points: &'a mut [u32],
}

/// Overwrites `b_pdf[k]` (the Bxdf pdf of light sample `k`) with `w / l_pdf[k]`, the factor
/// of the sample's shadow-ray contribution: `w` the power heuristic against the Bxdf pdf,
/// or 1 for Dirac lights and without MIS. Four points per SSE operation, the operations of
/// `power_heuristic` and the division in the same order (IEEE operations round the same in
/// any lane), so the same bits as the scalar formula; the two divisions leave the
/// spawn loop's dependency chain. Values where `l_pdf` is 0 are meaningless.
fn light_weights(l_pdf: &[f32], b_pdf: &mut [f32], delta: &[bool], no_mis: bool) {
    let m = b_pdf.len();
    let (l_pdf, delta) = (&l_pdf[..m], &delta[..m]);
    let (l4, l_rest) = l_pdf.as_chunks::<4>();
    let (d4, d_rest) = delta.as_chunks::<4>();
    let (b4, b_rest) = b_pdf.as_chunks_mut::<4>();
    for ((l, d), b) in l4.iter().zip(d4).zip(b4) {
        let (pa, pb) = (Vec4::from_array(*l), Vec4::from_array(*b));
        let (a, bb) = (pa * pa, pb * pb);
        let w = a / (a + bb);
        let w = Vec4::select(w.is_finite_mask() & a.is_finite_mask(), w, Vec4::ONE);
        let w = Vec4::select(a.cmpne(Vec4::ZERO), w, Vec4::ZERO);
        let dirac = BVec4A::new(d[0] | no_mis, d[1] | no_mis, d[2] | no_mis, d[3] | no_mis);
        let w = Vec4::select(dirac, Vec4::ONE, w);
        *b = (w / pa).to_array();
    }
    for ((&l, &d), b) in l_rest.iter().zip(d_rest).zip(b_rest) {
        let w = if d | no_mis {
            1.0
        } else {
            power_heuristic(l, *b)
        };
        *b = w / l;
    }
}

/// Direct-lighting system: writes to `out` from row `start` on one shadow ray per point of
/// `range` whose light sample has a non-black contribution `throughput * f * Le * w / pdf`
/// (power heuristic weight `w` unless the sample is a Dirac light or `no_mis`), and returns
/// the number of rows written. `stacks` (the scene, when volume stacks can be non-empty)
/// copies the rays' stacks and records crossings of the surface the shadow ray starts on;
/// `None` means every stack is empty, and the rows' stacks are left as they are. Every
/// other column of the rows written is overwritten.
///
/// Written for few instructions per row: the output rows exist up front (no per-column
/// capacity checks), columns are re-sliced to one length each so that a row
/// needs at most one bounds check per length, and one pass in point order both decides
/// which points get a ray and fills the row (three passes, the later ones gathering the
/// point columns by a stored point index, took 2.7M more Ir at cornell 2 spp).
#[allow(clippy::too_many_arguments, reason = "the columns it reads, named")]
#[inline(never)]
fn spawn_shadow_rays(
    stacks: Option<&CompiledScene>,
    mode: ShadingMode,
    pts: &ShadingPoints,
    range: std::ops::Range<usize>,
    incoming: &Rays,
    light: LightColumns<'_>,
    no_mis: bool,
    out: &mut ShadowRayColumns<'_>,
    start: usize,
) -> usize {
    let ray_id = &pts.ray_id[range.clone()];
    let (m, n) = (ray_id.len(), incoming.len());
    let rows = start..start + m;
    let (o_origin, o_direction, o_tmax, o_contribution, o_path, o_stack) = (
        &mut out.origin[rows.clone()],
        &mut out.direction[rows.clone()],
        &mut out.tmax[rows.clone()],
        &mut out.contribution[rows.clone()],
        &mut out.path[rows.clone()],
        &mut out.volume_stack[rows],
    );
    // One pass: the point columns are read in order, the incoming-ray columns through the
    // one `r` loaded per point.
    let in_throughput = &incoming.throughput[..n];
    let in_path = &incoming.path[..n];
    let ls = &light.samples;
    let (l_wi, l_distance, l_radiance) = (&ls.wi[..m], &ls.distance[..m], &ls.radiance[..m]);
    let l_pdf = &ls.pdf[..m];
    let value = &light.value[..m];
    let (p, ng) = (&pts.p[range.clone()][..m], &pts.ng[range.clone()][..m]);
    let scatter = mode == ShadingMode::Scatter;
    // The factors `w / pdf` of all points, vectorised.
    light_weights(l_pdf, &mut light.pdf[..m], &ls.delta[..m], no_mis);
    let factor = &light.pdf[..m];
    // The points with a sample the Bxdf reflects (two thirds at cornell), listed without a
    // branch: a branch on it in the loop below mispredicted about 55k times per spp.
    let points = &mut light.points[..m];
    let mut listed = 0;
    for k in 0..m {
        points[listed] = k as u32;
        listed += ((l_pdf[k] != 0.0) & !is_black(value[k])) as usize;
    }
    let mut count = 0;
    for &k in &points[..listed] {
        let k = k as usize;
        let r = ray_id[k] as usize;
        let c = in_throughput[r] * value[k] * l_radiance[k] * factor[k];
        if is_black(c) {
            continue;
        }
        let wi = l_wi[k];
        o_contribution[count] = c;
        o_direction[count] = wi;
        o_path[count] = in_path[r];
        // Origin offset to the side of the surface the ray leaves to; the length stops
        // short of the light by the same offset.
        let (p, ng) = (p[k], ng[k]);
        let offset = ray_offset(p);
        o_origin[count] = if scatter {
            p + ng * toward(wi, ng, offset)
        } else {
            p
        };
        let distance = l_distance[k];
        o_tmax[count] = if distance.is_finite() {
            distance * (1.0 - 1e-4) - offset
        } else {
            f32::INFINITY
        };
        if let Some(scene) = stacks {
            let stack = &mut o_stack[count];
            *stack = incoming.volume_stack[r].clone();
            // A shadow ray leaving through the surface it starts on enters (or leaves) that
            // shape's interior.
            let i = range.start + k;
            let shape = pts.shape[i];
            if scatter
                && (wi.dot(ng) >= 0.0) != (pts.vn[i].dot(ng) >= 0.0)
                && scene.tracks_interior(shape)
            {
                stack.cross(scene.volume_entry(shape), pts.front_face[i]);
            }
        }
        count += 1;
    }
    count
}

/// Path-continuation system: writes to `out` from row `start` on the ray each point of
/// `range` continues its path with (direction, weight, pdf and lobe from `samples`, Russian
/// roulette with `u4[k][3]`), unless the path reached `max_depth`, the sample was absorbed or
/// the roulette ended it. Returns the number of rows written and those three counts.
/// `stacks` as in [`spawn_shadow_rays`]; a transmitted ray crosses the surface's interior
/// boundary. The caller sets `tmin` and `tmax`; `stacks` being `None` means every stack is
/// empty, and the rows' stacks are left as they are.
///
/// A first pass decides which points continue and writes the columns that decision computes
/// (throughput, `eta_scale`, depth, lobe, pdf, point index); a second pass, driven by the
/// point index (increasing, so the point columns are still read in order), writes the
/// geometry and what the path carries over. One pass doing both kept about twenty column
/// pointers live and spilled a quarter of its instructions to the stack (measured at
/// cornell 2 spp: 2.4M fewer Ir split, and continue_paths 6.7% -> 6.3% of the perf
/// profile). The stack pass, when needed, follows.
#[allow(clippy::too_many_arguments, reason = "the columns it reads, named")]
#[inline(never)]
fn continue_paths(
    stacks: Option<&CompiledScene>,
    settings: crate::scene::RenderSettings,
    mode: ShadingMode,
    pts: &ShadingPoints,
    range: std::ops::Range<usize>,
    incoming: &Rays,
    samples: &BxdfSamples,
    u4: &[[f32; 4]],
    out: &mut RayColumns<'_>,
    start: usize,
    stats: &mut SystemStats,
) -> (usize, usize, usize, usize) {
    let ray_id = &pts.ray_id[range.clone()];
    let (m, n) = (ray_id.len(), incoming.len());
    let rows = start..start + m;
    let (o_origin, o_direction, o_path, o_throughput, o_lobe, o_depth, o_passes) = (
        &mut out.origin[rows.clone()],
        &mut out.direction[rows.clone()],
        &mut out.path[rows.clone()],
        &mut out.throughput[rows.clone()],
        &mut out.lobe[rows.clone()],
        &mut out.depth[rows.clone()],
        &mut out.passes[rows.clone()],
    );
    let (o_pdf, o_eta_scale, o_dimension, o_ctx, o_prev_p, o_stack) = (
        &mut out.pdf[rows.clone()],
        &mut out.eta_scale[rows.clone()],
        &mut out.dimension[rows.clone()],
        &mut out.shading_ctx_index[rows.clone()],
        &mut out.prev_p[rows.clone()],
        &mut out.volume_stack[rows],
    );
    // Pass 1: which points continue, with which throughput.
    let (in_throughput, in_eta_scale, in_depth) = (
        &incoming.throughput[..n],
        &incoming.eta_scale[..n],
        &incoming.depth[..n],
    );
    let (s_pdf, s_weight, s_lobe, s_eta, rr_u) = (
        &samples.pdf[..m],
        &samples.weight[..m],
        &samples.lobe[..m],
        &samples.eta[..m],
        &u4[..m],
    );
    let (mut max_depth, mut absorbed, mut roulette) = (0, 0, 0);
    let (p, ng, s_wi) = (
        &pts.p[range.clone()][..m],
        &pts.ng[range.clone()][..m],
        &samples.wi[..m],
    );
    let (in_path, in_passes, in_dimension) = (
        &incoming.path[..n],
        &incoming.passes[..n],
        &incoming.dimension[..n],
    );
    let scatter = mode == ShadingMode::Scatter;
    let mut count = 0;
    // The point columns are read in order, and the incoming-ray columns through the one `r`
    // loaded per point.
    for k in 0..m {
        let r = ray_id[k] as usize;
        // The next segment must fit in max_depth.
        if in_depth[r] as u32 + 2 > settings.max_depth {
            max_depth += 1;
            continue;
        }
        let pdf = s_pdf[k];
        let weight = s_weight[k];
        if pdf <= 0.0 || is_black_or_not_finite(weight) {
            absorbed += 1;
            continue;
        }
        let mut throughput = in_throughput[r] * weight;
        let lobe = s_lobe[k];
        let eta = s_eta[k];
        let eta_scale = in_eta_scale[r] * if lobe.is_transmit() { eta * eta } else { 1.0 };
        let depth = in_depth[r] + 1;
        // Russian roulette (pbrt-v4 / Mitsuba: survival min(max(beta) * eta^2, 0.95)).
        if depth as u32 > settings.rr_depth {
            let q = (throughput.max_channel() * eta_scale).min(0.95);
            if rr_u[k][3] >= q {
                roulette += 1;
                continue;
            }
            throughput *= 1.0 / q;
        }
        o_throughput[count] = throughput;
        o_eta_scale[count] = eta_scale;
        o_depth[count] = depth;
        o_lobe[count] = lobe;
        o_pdf[count] = if lobe.is_specular() { 0.0 } else { pdf };
        o_ctx[count] = k as u32;
        count += 1;
    }
    let ctx = &o_ctx[..count];
    // Pass 2: geometry and carried-over columns of the continuing rays, by their point index
    // (increasing, so the point columns are still read in order). Its own loop: with these
    // few columns live it keeps everything in registers, where one loop spilled.
    let (o_origin, o_direction, o_prev_p) = (
        &mut o_origin[..count],
        &mut o_direction[..count],
        &mut o_prev_p[..count],
    );
    let (o_path, o_passes, o_dimension) = (
        &mut o_path[..count],
        &mut o_passes[..count],
        &mut o_dimension[..count],
    );
    for (j, &k) in ctx.iter().enumerate() {
        let k = k as usize;
        // What the path carries over from the incoming ray.
        let r = ray_id[k] as usize;
        o_path[j] = in_path[r];
        o_passes[j] = in_passes[r];
        o_dimension[j] = in_dimension[r] + DIMS_PER_VERTEX;
        // Rays leave from the side of the surface they go to.
        let (p, wi) = (p[k], s_wi[k]);
        o_origin[j] = if scatter {
            let ng = ng[k];
            p + ng * toward(wi, ng, ray_offset(p))
        } else {
            p
        };
        o_direction[j] = wi;
        o_prev_p[j] = p;
    }
    // Pass 3: volume stacks; a transmitted ray crosses the surface's interior boundary.
    if let Some(scene) = stacks {
        let in_stack = &incoming.volume_stack[..n];
        for ((stack, &lobe), &k) in o_stack[..count].iter_mut().zip(&o_lobe[..count]).zip(ctx) {
            let k = k as usize;
            *stack = in_stack[ray_id[k] as usize].clone();
            let i = range.start + k;
            let shape = pts.shape[i];
            if mode == ShadingMode::Scatter
                && lobe.is_transmit()
                && scene.tracks_interior(shape)
                && stack.cross(scene.volume_entry(shape), pts.front_face[i])
                    == StackEvent::UnmatchedExit
            {
                stats.unmatched_exit(shape);
            }
        }
    }
    (count, max_depth, absorbed, roulette)
}

/// The first `n` elements of a per-group scratch buffer, grown with `fill` when shorter.
/// The callers overwrite what they read, so the buffer is filled once per size reached
/// rather than cleared and refilled for every group.
#[inline]
fn scratch<T: Clone>(v: &mut Vec<T>, n: usize, fill: T) -> &mut [T] {
    if v.len() < n {
        v.resize(n, fill);
    }
    &mut v[..n]
}

/// `offset` signed to move a point along `ng` to the side `wi` points to: `(side of ng) *
/// offset` as `ng * toward(..)`, the same bits (negating a product's factor negates the
/// product), with the sign set by a bit operation instead of a branch on the (random)
/// direction.
#[inline]
fn toward(wi: Vec3, ng: Vec3, offset: f32) -> f32 {
    // Flip unless `wi . ng >= 0` (a NaN dot product flips, as the branch did).
    let keep_side = (wi.dot(ng) >= 0.0) as u32;
    f32::from_bits(offset.to_bits() ^ ((keep_side ^ 1) << 31))
}

/// `c.is_black()` without a branch per channel.
#[inline]
fn is_black(c: Rgb) -> bool {
    (c.r == 0.0) & (c.g == 0.0) & (c.b == 0.0)
}

/// `weight.is_black() || !weight.is_finite()`, exactly, in fewer instructions: `x * 0` is
/// (signed) zero for finite `x` and NaN for infinities and NaN, so the sum of the three
/// products is zero exactly when every channel is finite; then the sum of the absolute
/// values is zero exactly when every channel is (a sum of non-negative numbers is at least
/// its largest term; overflow gives infinity, not zero).
#[inline]
fn is_black_or_not_finite(w: Rgb) -> bool {
    let finite = w.r * 0.0 + w.g * 0.0 + w.b * 0.0 == 0.0;
    !finite || w.r.abs() + w.g.abs() + w.b.abs() == 0.0
}

/// Light-sampling pdf (solid angle at `from`, including selection) of the point `p` on the
/// emissive shape `shape` hit by ray `r`.
fn light_pdf_at(
    scene: &CompiledScene,
    shape: u32,
    from: Vec3,
    p: Vec3,
    ng: Vec3,
    rays: &Rays,
    r: usize,
) -> f32 {
    // The hit primitive is not stored on the point; find it by re-intersecting the ray (cheap
    // and rare: only for emitter hits after a non-specular bounce).
    let mut t = [0.0f32];
    let mut prim = [NO_HIT];
    let (mut b1, mut b2) = ([0.0f32], [0.0f32]);
    risotto_systems::intersect::intersect_closest(
        &scene.geometry,
        &[rays.origin[r]],
        &[rays.direction[r]],
        &[rays.tmin[r]],
        &[rays.tmax[r]],
        &mut t,
        &mut prim,
        &mut b1,
        &mut b2,
    );
    if prim[0] == NO_HIT || scene.prim_shape[prim[0] as usize] != shape {
        return 0.0;
    }
    scene.lights.area_pdf(prim[0], from, p, ng)
}

/// Shading points at the rays' origins, for binding a volume integrator to the bundle.
fn volume_points(rays: &Rays, material: u32) -> ShadingPoints {
    let mut pts = ShadingPoints::with_capacity(rays.len());
    for i in 0..rays.len() {
        pts.push(volume_point(
            rays.origin[i],
            rays.direction[i],
            i as u32,
            material,
        ));
    }
    pts
}

/// A shading point at the start of a segment inside a volume (no surface: normals face the
/// viewer, transmission 1). Binds volume integrators to the rays or shadow segments they
/// answer.
pub(crate) fn volume_point(
    p: Vec3,
    direction: Vec3,
    ray_id: u32,
    material: u32,
) -> ShadingPointRow {
    ShadingPointRow {
        p,
        ng: -direction,
        nn: -direction,
        vn: -direction,
        vlen: 0.0,
        u: 0.0,
        v: 0.0,
        w: 0.0,
        transmission: Rgb::WHITE,
        ray_id,
        material,
        shape: u32::MAX,
        front_face: true,
        ior_outside: 1.0,
    }
}

/// Appends `src`'s groups and misses to `dst`, re-indexing ray ids into `incoming`, to which
/// `rays` (the table `src` answers) is appended.
fn append_groups(dst: &mut ShadeGroups, incoming: &mut Rays, src: &ShadeGroups, rays: &Rays) {
    let offset = incoming.len() as u32;
    incoming.extend_from(rays);
    for g in &src.groups {
        let start = dst.points.len();
        dst.points.extend_from_range(&src.points, g.range.clone());
        for id in &mut dst.points.ray_id[start..] {
            *id += offset;
        }
        dst.groups.push(ShadeGroup {
            material: g.material,
            mode: g.mode,
            range: start..dst.points.len(),
        });
    }
    for (k, &r) in src.misses.iter().enumerate() {
        dst.push_miss(r + offset, src.miss_transmission[k]);
    }
}
