//! Camera subpaths: from the camera as the path tracer's, and at every vertex each strategy
//! that ends there: the emitter or environment the subpath hits, a light sample (next-event
//! estimation, one light vertex), and connections to every stored vertex of the camera
//! sample's own light subpath, each weighted by [`super::mis`] against all the others.

use super::evaluate::cos_at;
use super::merge::MergeVertices;
use super::mis::{emitter_hit_weight, SubpathMis};
use super::walk::trace_bounce;
use super::{connect, merge, strategy_weight, BidirWorker, Bidirectional, Scratch, Strategy};
use crate::integrator::PathBatch;
use crate::path_tracer::{continue_group, discard_bxdf_samples, hit_prim};
use crate::plugin::{Bxdf, ParamCache, PatternCounters, ShadingContext};
use crate::scene::CompiledScene;
use crate::shade_groups::ShadingMode;
use crate::stats::{System, SystemStats};
use bumpalo::Bump;
use glam::Vec3;
use risotto_components::{LobeSampled, Rays, Rgb, ShadingPoints, NO_HIT};
use risotto_systems::camera::push_camera_rays;
use risotto_systems::path::Vertices;
use risotto_systems::sampler::{next_4d_column, PathSampler};

/// Traces the camera subpaths of `batch`, adding to each path's radiance what its strategies
/// estimate (shadow rays of its light samples and connections traced at the end).
#[allow(clippy::too_many_arguments, reason = "the stage's inputs, named")]
pub(super) fn camera_subpaths(
    bd: &Bidirectional,
    scene: &CompiledScene,
    batch: &mut PathBatch,
    w: &mut BidirWorker,
    merge: Option<&MergeVertices>,
    stats: &mut SystemStats,
    arena: &Bump,
    counters: &PatternCounters,
) {
    let n = batch.paths.len();
    let f = w.s.factors;
    let q = &mut w.camera_q;
    q.rays.rays.clear();
    push_camera_rays(
        &scene.camera,
        &batch.paths.pixel,
        &batch.paths.sample,
        &batch.seeds,
        &scene.camera_stack,
        &mut q.rays.rays,
    );
    stats.add_rays(n);
    stats.bidir_rays.camera += n as u64;
    w.s.mis.clear();
    let rays = &q.rays.rays;
    let camera = scene.camera.endpoint();
    w.s.mis.extend(
        rays.origin.iter().zip(&rays.direction).map(|(&o, &d)| {
            SubpathMis::camera_start(camera.pdf_ray(o, d), f.light_paths_per_pixel)
        }),
    );
    w.s.connections.clear();
    let stages = super::walk::stages(bd.techniques);
    let mut first = true;
    while !w.camera_q.rays.rays.is_empty() {
        trace_bounce(
            &stages,
            scene,
            batch,
            &mut w.camera_q,
            &mut w.s.escaped,
            stats,
            arena,
            counters,
            false,
            &mut w.s.sent_depth,
            &mut w.s.mis,
            w.s.alone,
        );
        environment(bd, scene, batch, w);
        camera_vertices(bd, scene, batch, w, merge, first, stats, arena, counters);
        let q = &mut w.camera_q;
        std::mem::swap(&mut q.rays, &mut q.next);
        q.next.rays.clear();
        stats.add_rays(q.rays.rays.len());
        stats.bidir_rays.camera += q.rays.rays.len() as u64;
        first = false;
    }
    let shadow = &w.s.connections;
    if !shadow.is_empty() {
        let mut contribution = std::mem::take(&mut w.s.connection_contribution);
        contribution.clear();
        contribution.extend_from_slice(&shadow.contribution);
        crate::transmission::trace_shadow_rays(
            scene,
            shadow,
            batch,
            bd.techniques,
            &mut contribution,
            stats,
            arena,
        );
        for (&path, &c) in shadow.path.iter().zip(&contribution) {
            batch.paths.radiance[path as usize] += c;
        }
        w.s.connection_contribution = contribution;
    }
}

/// The environment seen by the rays that left the scene.
fn environment(
    bd: &Bidirectional,
    scene: &CompiledScene,
    batch: &mut PathBatch,
    w: &mut BidirWorker,
) {
    let incoming = &w.camera_q.hits.incoming;
    let lights = scene.bidirectional_lights();
    let env = lights.environment_light();
    for &(r, tr) in &w.s.escaped {
        let r = r as usize;
        let path = incoming.path[r] as usize;
        let d = incoming.direction[r];
        let le = lights.environment_radiance(d);
        let depth = incoming.depth[r];
        if depth == 0 && batch.paths.depth[path].is_infinite() {
            batch.paths.albedo[path] = le;
        }
        if le.is_black() || depth as u32 + 1 > scene.settings.max_depth {
            continue;
        }
        let weight = match (depth, bd.strategy, env) {
            (0, _, _) => 1.0,
            (_, Strategy::Light, _) | (_, _, None) => continue,
            (_, _, Some(env)) => {
                let direct = lights.environment_pdf(d);
                let bounds = scene.geometry.bounds();
                let (pp, pd) = lights.emission_pdf(env, Vec3::ZERO, -d, -d, bounds);
                emitter_hit_weight(&w.s.mis[path], direct, pp * pd, false)
            }
        };
        let weight = strategy_weight(w.s.alone, 0, depth as u32 + 2, weight);
        batch.paths.radiance[path] += incoming.throughput[r] * tr * le * weight;
    }
}

/// The camera vertices of one bounce: emitters hit, the strategies that connect there, and
/// the next direction.
#[allow(clippy::too_many_arguments, reason = "the stage's inputs, named")]
fn camera_vertices(
    bd: &Bidirectional,
    scene: &CompiledScene,
    batch: &mut PathBatch,
    w: &mut BidirWorker,
    merge: Option<&MergeVertices>,
    first: bool,
    stats: &mut SystemStats,
    arena: &Bump,
    counters: &PatternCounters,
) {
    let settings = scene.settings;
    let (q, s, light) = (&mut w.camera_q, &mut w.s, &w.light);
    let orthographic = matches!(
        scene.camera.projection,
        risotto_systems::camera::Projection::Orthographic { .. }
    );
    let groups = std::mem::take(&mut q.hits.groups.groups);
    let total: usize = groups.iter().map(|g| g.range.len()).sum();
    let mut next_len = 0;
    let mut next_out = q.next.rays.reuse_rows(total);
    // The dead rows reused here hold old bounds; continuing rays are unbounded.
    next_out.tmin.fill(0.0);
    next_out.tmax.fill(f32::INFINITY);
    let bounds = scene.geometry.bounds();
    for grp in &groups {
        let range = grp.range.clone();
        let pts = &q.hits.groups.points;
        let incoming = &mut q.hits.incoming;
        let m = range.len();
        for i in range.clone() {
            let r = pts.ray_id[i] as usize;
            incoming.throughput[r] *= pts.transmission[i];
            let path = incoming.path[r] as usize;
            let distance = (pts.p[i] - incoming.prev_p[r]).length();
            // An orthographic camera's density is per unit film area: it reaches the first
            // vertex along parallel rays, without a distance term (`Camera::pdf_area`).
            let parallel = orthographic && incoming.depth[r] == 0;
            s.mis[path].arrive(distance, cos_at(pts, i, pts.vn[i]), parallel);
            // An emitter hit: the strategy that finds the light by following the camera.
            let shape = pts.shape[i];
            if shape == u32::MAX || !pts.front_face[i] {
                continue;
            }
            let Some(le) = scene.shapes[shape as usize].emission else {
                continue;
            };
            let depth = incoming.depth[r];
            if depth as u32 + 1 > settings.max_depth {
                continue;
            }
            let weight = if depth == 0 {
                1.0
            } else if bd.strategy == Strategy::Light {
                continue;
            } else {
                let prim = hit_prim(scene, incoming, r);
                let Some(light) = (prim != NO_HIT)
                    .then(|| scene.bidirectional_lights().area_light(prim))
                    .flatten()
                else {
                    continue;
                };
                let (pp, pd) = scene
                    .bidirectional_lights()
                    .emission_pdf(light, pts.p[i], pts.ng[i], pts.vn[i], bounds);
                emitter_hit_weight(&s.mis[path], pp, pp * pd, false)
            };
            let weight = strategy_weight(s.alone, 0, depth as u32 + 2, weight);
            batch.paths.radiance[path] += incoming.throughput[r] * le * weight;
        }
        let factory = scene.materials[grp.material as usize].factory.as_ref();
        let cache = arena.alloc(ParamCache::new(arena, counters));
        let ctx = ShadingContext::new(pts, range.clone(), grp.mode, grp.material, &[])
            .with_factory(factory)
            .with_cache(cache);
        let bxdf = factory.begin_scatter(&ctx, grp.mode, arena);
        if first {
            first_hit_aovs(
                batch,
                incoming,
                pts,
                range.clone(),
                &ctx,
                &mut *bxdf,
                &mut s.albedo,
            );
        }
        if bd.strategy == Strategy::Light {
            // Light tracing alone: camera rays only see what they hit directly.
            continue;
        }
        let connectable = bxdf.lobes().contains(LobeSampled::DIFFUSE);
        vertex_samplers(s, batch, pts, range.clone(), incoming);
        s.group_eval.bind(pts, range.clone());
        let at = GroupVertices {
            pts,
            incoming,
            range: range.clone(),
            material: grp.material,
            mode: grp.mode,
        };
        if connectable {
            let start = std::time::Instant::now();
            let queued = s.connections.len();
            connect::light_samples(scene, s, &at, &ctx, &mut *bxdf, arena, counters);
            stats.bidir_rays.light_samples += (s.connections.len() - queued) as u64;
            connect::light_vertices(scene, s, light, &at, &ctx, &mut *bxdf, arena, counters);
            stats.record(System::Connect, m, start.elapsed().as_secs_f64());
            if let Some(merge) = merge.filter(|_| s.merge_radius > 0.0) {
                let start = std::time::Instant::now();
                let radiance = &mut batch.paths.radiance;
                merge::light_vertices(scene, s, merge, &at, radiance, arena, counters);
                stats.record(System::Merge, m, start.elapsed().as_secs_f64());
            }
        }
        s.samples.reset(m);
        bxdf.generate_samples(&ctx, &mut s.samplers, &mut s.samples);
        if scene.discards_disagreeing_directions() && grp.mode == ShadingMode::Scatter {
            discard_bxdf_samples(pts, range.clone(), false, &mut s.samples);
        }
        scatter_mis(scene, s, &at, arena, counters);
        let vertices = Vertices {
            points: pts,
            range: range.clone(),
            on_surface: grp.mode == ShadingMode::Scatter,
            // The bidirectional integrators spawn from the flat triangles (their
            // connections have no such offset, and subpaths must meet them).
            terminator_lift: false,
            incoming,
        };
        next_len += continue_group(
            scene,
            &batch.paths,
            vertices,
            &s.samples,
            &s.u4,
            &mut s.stack_errors,
            &mut next_out,
            next_len,
            stats,
        );
    }
    q.next.rays.truncate(next_len);
    let (pts, incoming) = (&q.hits.groups.points, &q.hits.incoming);
    let start = std::time::Instant::now();
    let queued = s.connections.len();
    connect::finish(scene, s, light, pts, incoming, arena, counters);
    stats.bidir_rays.connections += (s.connections.len() - queued) as u64;
    stats.record(System::Connect, 0, start.elapsed().as_secs_f64());
    q.hits.groups.groups = groups;
}

/// The vertices of one shading group: rows `range` of `pts` (of `material`, in `mode`),
/// reached by rows of `incoming`.
pub(super) struct GroupVertices<'a> {
    pub(super) pts: &'a ShadingPoints,
    pub(super) incoming: &'a Rays,
    pub(super) range: std::ops::Range<usize>,
    pub(super) material: u32,
    pub(super) mode: ShadingMode,
}

/// First-hit AOVs of the camera rays' vertices (as the path tracer's shade stage).
fn first_hit_aovs(
    batch: &mut PathBatch,
    incoming: &Rays,
    pts: &ShadingPoints,
    range: std::ops::Range<usize>,
    ctx: &ShadingContext<'_>,
    bxdf: &mut dyn Bxdf,
    albedo: &mut Vec<Rgb>,
) {
    albedo.clear();
    albedo.resize(range.len(), Rgb::BLACK);
    bxdf.albedo(ctx, albedo);
    for (k, i) in range.enumerate() {
        let r = pts.ray_id[i] as usize;
        if incoming.depth[r] == 0 && incoming.passes[r] == 0 {
            let path = incoming.path[r] as usize;
            batch.paths.albedo[path] = albedo[k];
            batch.paths.normal[path] = pts.nn[i];
            batch.paths.depth[path] = pts.vlen[i];
        }
    }
}

/// Samplers at the vertex dimensions of the group's points (rows `range` of `pts`, reached
/// by rows of `incoming`, paths of `batch`) and their first four dimensions, drawn into
/// `s.u4` (light sample or lens sample, selection, Russian roulette); the samplers are left
/// where the Bxdf starts.
pub(super) fn vertex_samplers(
    s: &mut Scratch,
    batch: &PathBatch,
    pts: &ShadingPoints,
    range: std::ops::Range<usize>,
    incoming: &Rays,
) {
    s.samplers.clear();
    s.samplers
        .extend(pts.ray_id[range.clone()].iter().map(|&r| {
            let r = r as usize;
            let path = incoming.path[r] as usize;
            PathSampler {
                seed: batch.seeds[path],
                sample: batch.paths.sample[path],
                dimension: incoming.dimension[r],
            }
        }));
    s.u4.clear();
    s.u4.resize(range.len(), [0.0; 4]);
    next_4d_column(&mut s.samplers, &mut s.u4);
}

/// Updates the subpaths' MIS sums for the group's sampled directions (`s.samples`), with
/// the reverse pdf of each non-Dirac sample: the closure seen from the sample, light from
/// the viewer (evaluated into `s.group_eval`, bound to the group; rows without such a
/// sample are evaluated towards their own viewer and ignored).
pub(super) fn scatter_mis(
    scene: &CompiledScene,
    s: &mut Scratch,
    at: &GroupVertices<'_>,
    arena: &Bump,
    counters: &PatternCounters,
) {
    let vn = &at.pts.vn[at.range.clone()];
    s.view.clear();
    s.view.extend(vn.iter().enumerate().map(|(k, &vn)| {
        let smp = &s.samples;
        match smp.pdf[k] > 0.0 && !smp.lobe[k].is_specular() {
            true => smp.wi[k],
            false => vn,
        }
    }));
    s.group_eval
        .run(scene, at.material, at.mode, &s.view, vn, arena, counters);
    let (pts, f, smp) = (at.pts, s.factors, &s.samples);
    for (k, i) in at.range.clone().enumerate() {
        if smp.pdf[k] <= 0.0 {
            continue;
        }
        let path = at.incoming.path[pts.ray_id[i] as usize] as usize;
        let specular = smp.lobe[k].is_specular();
        let pdf_rev = if specular {
            smp.pdf[k]
        } else {
            s.group_eval.pdf[k]
        };
        let cos_out = cos_at(pts, i, smp.wi[k]);
        let v = f.at(pts.shape[i] == u32::MAX);
        s.mis[path].scatter(smp.pdf[k], pdf_rev, cos_out, specular, v);
    }
}
