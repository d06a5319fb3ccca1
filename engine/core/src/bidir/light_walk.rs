//! Light subpaths: one per camera sample of the batch, leaving a light sampled by power,
//! traced through the same trace stage as camera paths (media answer it as a light path,
//! without a lighting delegate), with every vertex that has a non-Dirac lobe stored for the
//! camera subpaths and connected to the camera (the light-tracing strategy).
//!
//! Importance transport: a light subpath carries `Le cos / pdf` times the adjoint Bxdf
//! `f*(wo, wi) = f(wi, wo)` of every vertex. The plug-in closures evaluate radiance
//! transport; the two differ where a lobe refracts, by the squared relative IOR (Veach 1997,
//! sec. 5.2; pbrt-v4's `TransportMode::Importance`), so a transmitted sample's weight is
//! multiplied by `eta^2` here, and a connection's value is the closure seen from the camera
//! side ([`super::evaluate`]).

use super::camera_walk::{scatter_mis, vertex_samplers, GroupVertices};
use super::evaluate::{adjoint_cosines, cos_at, sides_agree};
use super::mis::{camera_connection_weight, SubpathMis};
use super::vertices::LightVertices;
use super::walk::{push_connection, stack_toward, trace_bounce};
use super::{
    strategy_weight, BidirWorker, Bidirectional, Scratch, Strategy, LIGHT_SEED_SALT,
    WALK_FIRST_DIMENSION,
};
use crate::integrator::PathBatch;
use crate::path_tracer::{continue_group, discard_bxdf_samples};
use crate::plugin::{ParamCache, PatternCounters, ShadingContext};
use crate::scene::CompiledScene;
use crate::shade_groups::ShadingMode;
use crate::stats::{System, SystemStats};
use bumpalo::Bump;
use glam::Vec2;
use risotto_components::{LobeSampled, RayRow, Rgb};
use risotto_systems::camera::CameraConnection;
use risotto_systems::lights::Light;
use risotto_systems::path::Vertices;
use risotto_systems::ray::offset_origin;
use risotto_systems::sampler::{sample_1d, sample_2d};

/// Traces the light subpaths of `batch` (one per camera sample, row for row): stores their
/// vertices in `w.light` and splats their connections to the camera into the integrator's
/// splat film.
pub(super) fn light_subpaths(
    bd: &Bidirectional,
    scene: &CompiledScene,
    batch: &PathBatch,
    w: &mut BidirWorker,
    stats: &mut SystemStats,
    arena: &Bump,
    counters: &PatternCounters,
) {
    let n = batch.paths.len();
    // The light subpaths as a batch of their own: the camera samples' pixels and indices,
    // seeds salted so that their numbers are not the camera paths'.
    let lb = &mut w.light_batch;
    lb.paths.clear();
    lb.paths.extend_from(&batch.paths);
    lb.seeds.clear();
    lb.seeds
        .extend(batch.seeds.iter().map(|s| s ^ LIGHT_SEED_SALT));
    w.light.clear();
    w.s.mis.clear();
    w.s.mis.resize(n, SubpathMis::default());
    w.s.at_infinity.clear();
    w.s.at_infinity.resize(n, false);
    w.s.in_volume_light.clear();
    w.s.in_volume_light.resize(n, false);
    let lights = scene.bidirectional_lights();
    let bounds = scene.geometry.bounds();
    let q = &mut w.light_q;
    q.rays.rays.clear();
    let start = std::time::Instant::now();
    for i in 0..n {
        let (seed, sample) = (lb.seeds[i], lb.paths.sample[i]);
        let u_position = sample_2d(seed, sample, 0);
        let u_direction = sample_2d(seed, sample, 2);
        let u_select = sample_1d(seed, sample, 4);
        let Some(e) =
            lights.sample_emission(&scene.geometry, bounds, u_select, u_position, u_direction)
        else {
            continue;
        };
        let emission_pdf = e.pdf_position * e.pdf_direction;
        let throughput = e.radiance * (e.cos_at_light / emission_pdf);
        if emission_pdf.is_nan()
            || emission_pdf <= 0.0
            || throughput.is_black()
            || !throughput.is_finite()
        {
            continue;
        }
        // The density with which next-event estimation picks the start (SmallVCM's
        // `directPdfA`): per unit area for lights with a position (`pdf_position` includes
        // the selection; for point and spot lights it is the selection alone), per unit
        // solid angle for the environment, the selection alone for distant lights.
        let direct_pdf = match (e.at_infinity, e.delta_direction) {
            // A distant light: next-event estimation picks it and its one direction.
            (true, true) => lights.selection_pmf(e.light),
            (true, false) => lights.environment_pdf(-e.direction),
            _ => e.pdf_position,
        };
        let delta = e.delta_position || e.delta_direction;
        // A point of an emissive medium: the camera side reaches it per unit volume at its
        // majorant's rate, which takes the cosine's place in the weights
        // (`volume_emission.rs`).
        let volume = match &lights.lights()[e.light as usize] {
            Light::Volume { emitter } => Some(emitter.mis_majorant(e.p)),
            _ => None,
        };
        let cos_at_light = volume.unwrap_or(e.cos_at_light);
        w.s.mis[i] = SubpathMis::light_start(direct_pdf, emission_pdf, cos_at_light, delta);
        w.s.at_infinity[i] = e.at_infinity;
        w.s.in_volume_light[i] = volume.is_some();
        let offset = e.n.abs().dot(e.p_error);
        let origin = if e.n == glam::Vec3::ZERO {
            e.p
        } else {
            offset_origin(e.p, e.n, offset, e.direction)
        };
        q.rays.rays.push(RayRow {
            origin,
            direction: e.direction,
            tmin: 0.0,
            tmax: f32::INFINITY,
            path: i as u32,
            throughput,
            lobe: LobeSampled::NONE,
            depth: 0,
            passes: 0,
            pdf: 0.0,
            eta_scale: 1.0,
            dimension: WALK_FIRST_DIMENSION,
            shading_ctx_index: u32::MAX,
            prev_p: e.p,
            // A medium's point: the volumes around it (other lights: around the light).
            volume_stack: match volume {
                Some(_) => scene.probe_stack(e.p, e.direction),
                None => bd.light_stack(e.light).clone(),
            },
        });
    }
    stats.record(System::Emit, n, start.elapsed().as_secs_f64());
    stats.add_rays(q.rays.rays.len());
    stats.bidir_rays.light += q.rays.rays.len() as u64;
    w.s.splats.clear();
    w.s.splat_film_pos.clear();
    let stages = super::walk::stages(bd.techniques);
    let mut bounce = 0;
    while !w.light_q.rays.rays.is_empty() {
        trace_bounce(
            &stages,
            scene,
            &mut w.light_batch,
            &mut w.light_q,
            &mut w.s.escaped,
            stats,
            arena,
            counters,
            true,
            &mut w.s.sent_depth,
            &mut w.s.mis,
            w.s.alone,
        );
        scatter_light_vertices(bd, scene, w, bounce, stats, arena, counters);
        let q = &mut w.light_q;
        std::mem::swap(&mut q.rays, &mut q.next);
        q.next.rays.clear();
        stats.add_rays(q.rays.rays.len());
        stats.bidir_rays.light += q.rays.rays.len() as u64;
        bounce += 1;
    }
    // The connections to the camera, through every volume and surface in between.
    let splats = &w.s.splats;
    stats.bidir_rays.camera_connections += splats.len() as u64;
    if !splats.is_empty() {
        let mut contribution = std::mem::take(&mut w.s.splat_contribution);
        contribution.clear();
        contribution.extend_from_slice(&splats.contribution);
        crate::transmission::trace_shadow_rays(
            scene,
            splats,
            &w.light_batch,
            bd.techniques,
            &mut contribution,
            stats,
            arena,
        );
        let film = bd.splat_film();
        stats.time(System::Splat, contribution.len(), || {
            for (&pos, &c) in w.s.splat_film_pos.iter().zip(&contribution) {
                film.add_filtered(&scene.camera.filter, pos, c);
            }
        });
        w.s.splat_contribution = contribution;
    }
}

/// The vertices of one bounce of the light subpaths: arrive (throughput, MIS), store, connect
/// to the camera, sample the next direction and continue.
fn scatter_light_vertices(
    bd: &Bidirectional,
    scene: &CompiledScene,
    w: &mut BidirWorker,
    bounce: usize,
    stats: &mut SystemStats,
    arena: &Bump,
    counters: &PatternCounters,
) {
    let normals = scene.features.vertex_normals;
    let discards = scene.discards_disagreeing_directions();
    let q = &mut w.light_q;
    let groups = std::mem::take(&mut q.hits.groups.groups);
    let total: usize = groups.iter().map(|g| g.range.len()).sum();
    let n_paths = w.light_batch.paths.len();
    let mut next_len = 0;
    let mut next_out = q.next.rays.reuse_rows(total);
    // The dead rows reused here hold old bounds; continuing rays are unbounded.
    next_out.tmin.fill(0.0);
    next_out.tmax.fill(f32::INFINITY);
    let by_bounce_len = n_paths;
    // Light tracing alone connects only to the camera: nothing to store, no weights.
    let bidirectional = bd.strategy != Strategy::Light;
    for grp in &groups {
        let range = grp.range.clone();
        let pts = &q.hits.groups.points;
        let incoming = &mut q.hits.incoming;
        let m = range.len();
        // Arrive: transmission of the segment, MIS sums.
        for i in range.clone() {
            let r = pts.ray_id[i] as usize;
            incoming.throughput[r] *= pts.transmission[i];
            let path = incoming.path[r] as usize;
            let distance = (pts.p[i] - incoming.prev_p[r]).length();
            let first_from_infinity = incoming.depth[r] == 0 && w.s.at_infinity[path];
            // A subpath from an emissive medium whose first segment walked: the camera
            // subpaths gather that emission alone (`volume_emission.rs`).
            if bounce == 0 && w.s.in_volume_light[path] && incoming.depth[r] > 0 && bidirectional {
                incoming.throughput[r] = Rgb::BLACK;
            }
            let cos_in = cos_at(pts, i, pts.vn[i]);
            w.s.mis[path].arrive(distance, cos_in, first_from_infinity);
        }
        let factory = scene.materials[grp.material as usize].factory.as_ref();
        let cache = arena.alloc(ParamCache::new(arena, counters));
        let ctx = ShadingContext::new(pts, range.clone(), grp.mode, grp.material, &[])
            .with_factory(factory)
            .with_cache(cache);
        let bxdf = factory.begin_scatter(&ctx, grp.mode, arena);
        let connectable = bxdf.lobes().contains(LobeSampled::DIFFUSE);
        // Samplers at the vertex's dimensions: 0-1 the lens sample of the camera
        // connection, 3 Russian roulette, 4.. the Bxdf.
        vertex_samplers(&mut w.s, &w.light_batch, pts, range.clone(), incoming);
        w.s.group_eval.bind(pts, range.clone());
        let at = GroupVertices {
            pts,
            incoming,
            range: range.clone(),
            material: grp.material,
            mode: grp.mode,
        };
        if connectable {
            let start = std::time::Instant::now();
            if bidirectional {
                store_vertices(&mut w.light, &w.s.mis, &at, bounce, by_bounce_len);
            }
            connect_to_camera(bd, scene, &mut w.s, &at, arena, counters);
            stats.record(System::Connect, m, start.elapsed().as_secs_f64());
        }
        // Sample the next direction; the reverse pdf of each non-Dirac sample.
        w.s.samples.reset(m);
        bxdf.generate_samples(&ctx, &mut w.s.samplers, &mut w.s.samples);
        if discards && grp.mode == ShadingMode::Scatter {
            discard_bxdf_samples(pts, range.clone(), false, &mut w.s.samples);
        }
        if bidirectional {
            scatter_mis(scene, &mut w.s, &at, arena, counters);
        }
        for (k, i) in range.clone().enumerate() {
            let s = &mut w.s.samples;
            if s.pdf[k] <= 0.0 {
                continue;
            }
            if s.lobe[k].is_transmit() {
                // Importance is not compressed by refraction as radiance is.
                s.weight[k] = s.weight[k] * (s.eta[k] * s.eta[k]);
            }
            // With shading normals, the adjoint's cosines (Veach 1997, eq. 5.19):
            // `|wo . Nn| |wi . Ng| / (|wo . Ng| |wi . Nn|)` for the subpath's incident `wo`
            // and sampled `wi`.
            if normals && grp.mode == ShadingMode::Scatter {
                let (ng, nn, wo, wi) = (pts.ng[i], pts.nn[i], pts.vn[i], s.wi[k]);
                let den = wo.dot(ng).abs() * wi.dot(nn).abs();
                let num = wo.dot(nn).abs() * wi.dot(ng).abs();
                s.weight[k] = if den > 0.0 {
                    s.weight[k] * (num / den)
                } else {
                    Rgb::BLACK
                };
            }
        }
        let vertices = Vertices {
            points: pts,
            range: range.clone(),
            on_surface: grp.mode == ShadingMode::Scatter,
            terminator_lift: false,
            incoming,
        };
        next_len += continue_group(
            scene,
            &w.light_batch.paths,
            vertices,
            &w.s.samples,
            &w.s.u4,
            &mut w.s.stack_errors,
            &mut next_out,
            next_len,
            stats,
        );
    }
    q.next.rays.truncate(next_len);
    q.hits.groups.groups = groups;
}

/// Stores the group's vertices as light vertices of bounce `bounce` (`paths` light
/// subpaths).
fn store_vertices(
    light: &mut LightVertices,
    mis: &[SubpathMis],
    at: &GroupVertices<'_>,
    bounce: usize,
    paths: usize,
) {
    let (pts, incoming) = (at.pts, at.incoming);
    let first = light.len();
    light.points.extend_from_range(pts, at.range.clone());
    for i in at.range.clone() {
        let r = pts.ray_id[i] as usize;
        let path = incoming.path[r] as usize;
        let v = light.throughput.len() as u32;
        light.throughput.push(incoming.throughput[r]);
        light.mis.push(mis[path]);
        light.segments.push(incoming.depth[r] as u32 + 1);
        light.stack.push(incoming.volume_stack[r].clone());
        light.bounce_mut(bounce, paths)[path] = v;
    }
    light.push_run(bounce, at.material, at.mode, first..light.len());
}

/// Connects the group's vertices to the camera (light tracing): a lens point and film
/// position each, the closure seen from the camera, a shadow ray to trace and splat.
fn connect_to_camera(
    bd: &Bidirectional,
    scene: &CompiledScene,
    s: &mut Scratch,
    at: &GroupVertices<'_>,
    arena: &Bump,
    counters: &PatternCounters,
) {
    let f = s.factors;
    let (pts, incoming) = (at.pts, at.incoming);
    let vn = &pts.vn[at.range.clone()];
    let normals = scene.discards_disagreeing_directions();
    s.view.clear();
    s.view.extend_from_slice(vn);
    s.camera_hits.clear();
    s.eval_rows.clear();
    let camera = scene.camera.endpoint();
    for (k, i) in at.range.clone().enumerate() {
        let r = pts.ray_id[i] as usize;
        if incoming.depth[r] as u32 + 2 > scene.settings.max_depth {
            continue;
        }
        let u_lens = Vec2::new(s.u4[k][0], s.u4[k][1]);
        let connection = camera.connect(pts.p[i], u_lens);
        let agrees = |c: &CameraConnection| !normals || sides_agree(pts, i, c.wi);
        if let Some(c) = connection.filter(agrees) {
            s.view[k] = c.wi;
            s.eval_rows.push((k as u32, s.camera_hits.len() as u32));
            s.camera_hits.push(c);
        }
    }
    if s.camera_hits.is_empty() {
        return;
    }
    s.group_eval
        .run(scene, at.material, at.mode, &s.view, vn, arena, counters);
    for &(k, j) in &s.eval_rows {
        let (k, c) = (k as usize, s.camera_hits[j as usize]);
        let i = at.range.start + k;
        let r = pts.ray_id[i] as usize;
        let path = incoming.path[r] as usize;
        // The closure seen from the camera, light from the subpath, made the adjoint's
        // `f* |cos to the camera|`.
        let Some(adjoint) = adjoint_cosines(pts, i, c.wi) else {
            continue;
        };
        let fc = s.group_eval.value[k] * adjoint;
        let cos_cam = cos_at(pts, i, c.wi);
        let camera_pdf_a = scene.camera.pdf_area(c.pdf_dir, c.distance, cos_cam);
        let weight = match bd.strategy {
            Strategy::Light => 1.0,
            _ => camera_connection_weight(
                &s.mis[path],
                camera_pdf_a,
                s.group_eval.pdf[k],
                f.at(pts.shape[i] == u32::MAX),
                f.light_paths_per_pixel,
            ),
        };
        let weight = strategy_weight(s.alone, incoming.depth[r] as u32 + 2, 1, weight);
        let contribution = incoming.throughput[r] * fc * (c.importance * weight);
        if contribution.is_black() || !contribution.is_finite() {
            continue;
        }
        let stack = stack_toward(scene, &incoming.volume_stack[r], pts, i, c.wi);
        push_connection(
            &mut s.splats,
            pts,
            i,
            c.wi,
            c.distance,
            0.0,
            contribution,
            path as u32,
            incoming.dimension[r],
            stack,
        );
        s.splat_film_pos.push(c.film);
    }
}
