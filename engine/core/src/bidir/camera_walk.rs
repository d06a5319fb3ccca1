//! Camera subpaths: from the camera as the path tracer's, and at every vertex each strategy
//! that ends there: the emitter or environment the subpath hits, a light sample (next-event
//! estimation, one light vertex), and connections to every stored vertex of the camera
//! sample's own light subpath, each weighted by [`super::mis`] against all the others.

use super::evaluate::{cos_at, evaluate_runs};
use super::mis::{
    connection_weight, emitter_hit_weight, light_sample_weight, merge_weight, pdf_w_to_a,
    ConnectionPdfs, SubpathMis,
};
use super::vertices::{LightVertices, NO_VERTEX};
use super::walk::{arrival_margin, push_connection, stack_toward, trace_bounce};
use super::{BidirWorker, Bidirectional, Scratch, Strategy};
use crate::integrator::PathBatch;
use crate::path_tracer::{continue_group, discard_bxdf_samples, hit_prim};
use crate::plugin::{Bxdf, ParamCache, PatternCounters, ShadingContext};
use crate::scene::CompiledScene;
use crate::shade_groups::ShadingMode;
use crate::stats::{System, SystemStats};
use bumpalo::Bump;
use glam::{Vec2, Vec3};
use risotto_components::{LobeSampled, Rays, Rgb, ShadingPoints, NO_HIT};
use risotto_systems::camera::push_camera_rays;
use risotto_systems::lights::{Light, LightSample};
use risotto_systems::path::Vertices;
use risotto_systems::sampler::{next_4d_column, PathSampler};

/// Traces the camera subpaths of `batch`, adding to each path's radiance what its strategies
/// estimate (shadow rays of its light samples and connections traced at the end).
pub(super) fn camera_subpaths(
    bd: &Bidirectional,
    scene: &CompiledScene,
    batch: &mut PathBatch,
    w: &mut BidirWorker,
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
    w.s.mis.clear();
    let rays = &q.rays.rays;
    w.s.mis
        .extend(rays.origin.iter().zip(&rays.direction).map(|(&o, &d)| {
            SubpathMis::camera_start(scene.camera.pdf_ray(o, d), f.light_paths_per_pixel)
        }));
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
        );
        environment(bd, scene, batch, w);
        camera_vertices(bd, scene, batch, w, first, stats, arena, counters);
        let q = &mut w.camera_q;
        std::mem::swap(&mut q.rays, &mut q.next);
        q.next.rays.clear();
        stats.add_rays(q.rays.rays.len());
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
    let env = scene.lights.environment_light();
    for &(r, tr) in &w.s.escaped {
        let r = r as usize;
        let path = incoming.path[r] as usize;
        let d = incoming.direction[r];
        let le = scene.lights.environment_radiance(d);
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
                let direct = scene.lights.environment_pdf(d);
                let bounds = scene.geometry.bounds();
                let (pp, pd) = scene.lights.emission_pdf(env, Vec3::ZERO, -d, -d, bounds);
                emitter_hit_weight(&w.s.mis[path], direct, pp * pd, false)
            }
        };
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
    first: bool,
    stats: &mut SystemStats,
    arena: &Bump,
    counters: &PatternCounters,
) {
    let settings = scene.settings;
    let (q, s, light) = (&mut w.camera_q, &mut w.s, &w.light);
    let f = s.factors;
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
                    .then(|| scene.lights.area_light(prim))
                    .flatten()
                else {
                    continue;
                };
                let (pp, pd) = scene
                    .lights
                    .emission_pdf(light, pts.p[i], pts.ng[i], pts.vn[i], bounds);
                emitter_hit_weight(&s.mis[path], pp, pp * pd, false)
            };
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
        s.u4.resize(m, [0.0; 4]);
        next_4d_column(&mut s.samplers, &mut s.u4);
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
            light_samples(scene, s, &at, &ctx, &mut *bxdf, arena, counters);
            connect_light_vertices(scene, s, light, &at, &ctx, &mut *bxdf, arena, counters);
            stats.record(System::Connect, m, start.elapsed().as_secs_f64());
            if s.merge_radius > 0.0 {
                let start = std::time::Instant::now();
                let radiance = &mut batch.paths.radiance;
                merge_light_vertices(scene, s, light, &at, radiance, arena, counters);
                stats.record(System::Merge, m, start.elapsed().as_secs_f64());
            }
        }
        s.samples.reset(m);
        bxdf.generate_samples(&ctx, &mut s.samplers, &mut s.samples);
        if scene.features.vertex_normals && grp.mode == ShadingMode::Scatter {
            discard_bxdf_samples(pts, range.clone(), &mut s.samples);
        }
        // The reverse pdf of each sampled direction: the closure seen from it.
        reverse_pdfs(scene, s, &at, arena, counters);
        for (k, i) in range.clone().enumerate() {
            let smp = &s.samples;
            if smp.pdf[k] <= 0.0 {
                continue;
            }
            let r = pts.ray_id[i] as usize;
            let path = incoming.path[r] as usize;
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
        let vertices = Vertices {
            points: pts,
            range: range.clone(),
            on_surface: grp.mode == ShadingMode::Scatter,
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
    finish_connections(scene, s, light, pts, incoming, arena, counters);
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

/// The reverse pdf of every sampled direction of the group (into `s.group_eval.pdf`): the
/// closure seen from the sample, light from the viewer. Rows without a non-Dirac sample
/// are evaluated towards their own viewer and ignored.
pub(super) fn reverse_pdfs(
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
}

/// Next-event estimation at the group's vertices (a light vertex sampled on a light, seen
/// from the camera vertex), weighted against every other strategy. `bxdf` is the group's
/// closure (bound to `ctx`).
#[allow(clippy::too_many_arguments, reason = "the stage's inputs, named")]
fn light_samples(
    scene: &CompiledScene,
    s: &mut Scratch,
    at: &GroupVertices<'_>,
    ctx: &ShadingContext<'_>,
    bxdf: &mut dyn Bxdf,
    arena: &Bump,
    counters: &PatternCounters,
) {
    let f = s.factors;
    let (pts, incoming) = (at.pts, at.incoming);
    let lights = &scene.lights;
    let bounds = scene.geometry.bounds();
    let normals = scene.features.vertex_normals;
    let m = at.range.len();
    s.light_hits.clear();
    s.hit_of.clear();
    s.hit_of.resize(m, u32::MAX);
    s.wi.clear();
    s.wi.extend_from_slice(&pts.vn[at.range.clone()]);
    for (k, i) in at.range.clone().enumerate() {
        let r = pts.ray_id[i] as usize;
        // The path with the light sample has depth + 2 segments.
        if incoming.depth[r] as u32 + 2 > scene.settings.max_depth {
            continue;
        }
        let u = s.u4[k];
        let Some(light) = lights.selected_light(u[2]) else {
            continue;
        };
        let Some(ls) = lights.sample(&scene.geometry, pts.p[i], u[2], Vec2::new(u[0], u[1])) else {
            continue;
        };
        if normals && !sides_agree(pts, i, ls.wi) {
            continue;
        }
        // The light's own view of the sample: where it emits from, at which cosine.
        let q = pts.p[i] + ls.wi * ls.distance;
        let (n_light, cos_at_light) = match &lights.lights()[light as usize] {
            Light::Area { prim, .. } => {
                let n = area_light_normal(scene, *prim, q);
                (n, n.dot(-ls.wi).abs())
            }
            _ => (Vec3::ZERO, 1.0),
        };
        let (pp, pd) = lights.emission_pdf(light, q, n_light, -ls.wi, bounds);
        s.wi[k] = ls.wi;
        s.hit_of[k] = s.light_hits.len() as u32;
        s.light_hits.push(LightHit {
            k: k as u32,
            sample: ls,
            emission_pdf: pp * pd,
            cos_at_light,
        });
    }
    if s.light_hits.is_empty() {
        return;
    }
    // Forward: the group's own closure towards the samples; reverse: seen from them.
    s.value.clear();
    s.value.resize(m, Rgb::BLACK);
    s.pdf.clear();
    s.pdf.resize(m, 0.0);
    bxdf.evaluate_samples(ctx, &s.wi, &mut s.value, &mut s.pdf);
    let vn = &pts.vn[at.range.clone()];
    s.group_eval
        .run(scene, at.material, at.mode, &s.wi, vn, arena, counters);
    for h in &s.light_hits {
        let k = h.k as usize;
        let i = at.range.start + k;
        let r = pts.ray_id[i] as usize;
        let ls = &h.sample;
        let cos_to_light = cos_at(pts, i, ls.wi);
        let path = incoming.path[r] as usize;
        // Next-event estimation's solid-angle pdf as the weights compare it: a point or
        // spot light's Dirac area density `P(light)` seen from `distance` away is
        // `P(light) d^2` per unit solid angle (SmallVCM's `PointLight::Illuminate`); the
        // sample's own `pdf` leaves the `d^2` in its radiance `I / d^2`.
        let direct_pdf_w = if ls.delta && ls.distance.is_finite() {
            ls.pdf * ls.distance * ls.distance
        } else {
            ls.pdf
        };
        let weight = light_sample_weight(
            &s.mis[path],
            direct_pdf_w,
            h.emission_pdf,
            s.pdf[k],
            s.group_eval.pdf[k],
            cos_to_light,
            h.cos_at_light,
            ls.delta,
            f.at(pts.shape[i] == u32::MAX),
        );
        let c = incoming.throughput[r] * s.value[k] * ls.radiance * (weight / ls.pdf);
        if c.is_black() || !c.is_finite() {
            continue;
        }
        let stack = stack_toward(scene, &incoming.volume_stack[r], pts, i, ls.wi);
        push_connection(
            &mut s.connections,
            pts,
            i,
            ls.wi,
            ls.distance,
            ls.margin,
            c,
            path as u32,
            incoming.dimension[r],
            stack,
        );
    }
}

/// The camera side of the connections of the group's vertices to every stored vertex of
/// their own light subpath, one bounce of the light subpaths at a time (one light vertex
/// per camera vertex): queued in `s.pending`, finished for the whole camera bounce by
/// [`finish_connections`].
#[allow(clippy::too_many_arguments, reason = "the stage's inputs, named")]
fn connect_light_vertices(
    scene: &CompiledScene,
    s: &mut Scratch,
    light: &LightVertices,
    at: &GroupVertices<'_>,
    ctx: &ShadingContext<'_>,
    bxdf: &mut dyn Bxdf,
    arena: &Bump,
    counters: &PatternCounters,
) {
    let (pts, incoming) = (at.pts, at.incoming);
    let lp = &light.points;
    let m = at.range.len();
    let vn = &pts.vn[at.range.clone()];
    let normals = scene.features.vertex_normals;
    while s.pending.len() < light.bounces() {
        s.pending.push(Vec::new());
    }
    for bounce in 0..light.bounces() {
        let by_path = &light.by_bounce[bounce];
        s.wi.clear();
        s.wi.extend_from_slice(vn);
        let first = s.pending[bounce].len();
        for (k, i) in at.range.clone().enumerate() {
            let r = pts.ray_id[i] as usize;
            let path = incoming.path[r] as usize;
            let v = by_path.get(path).copied().unwrap_or(NO_VERTEX);
            if v == NO_VERTEX {
                continue;
            }
            // Camera segments so far, the connection, and the light subpath's.
            let segments = incoming.depth[r] as u32 + 1 + 1 + light.segments[v as usize];
            if segments > scene.settings.max_depth {
                continue;
            }
            let d = lp.p[v as usize] - pts.p[i];
            let distance = d.length();
            if distance.is_nan() || distance <= 0.0 || !distance.is_finite() {
                continue;
            }
            let dir = d / distance;
            if normals && !(sides_agree(pts, i, dir) && sides_agree(lp, v as usize, -dir)) {
                continue;
            }
            s.wi[k] = dir;
            s.pending[bounce].push(PendingConnection {
                i: i as u32,
                v,
                camera_mis: s.mis[path],
                camera_value: Rgb::BLACK,
                camera_pdf_w: 0.0,
                camera_rev_pdf_w: 0.0,
            });
        }
        if s.pending[bounce].len() == first {
            continue;
        }
        // Forward: the group's own closure; reverse: seen from the light vertex.
        s.value.clear();
        s.value.resize(m, Rgb::BLACK);
        s.pdf.clear();
        s.pdf.resize(m, 0.0);
        bxdf.evaluate_samples(ctx, &s.wi, &mut s.value, &mut s.pdf);
        s.group_eval
            .run(scene, at.material, at.mode, &s.wi, vn, arena, counters);
        for c in &mut s.pending[bounce][first..] {
            let k = c.i as usize - at.range.start;
            c.camera_value = s.value[k];
            c.camera_pdf_w = s.pdf[k];
            c.camera_rev_pdf_w = s.group_eval.pdf[k];
        }
    }
}

/// Finishes the connections [`connect_light_vertices`] queued for one camera bounce (camera
/// vertices: rows of `pts`, reached by rows of `incoming`): the light side of each, for a
/// whole bounce of light vertices at a time (closures of the stored rows as they are for the
/// forward pdf, a copy seen from the camera vertices for the value and reverse pdf), the
/// weight and a shadow ray.
#[allow(clippy::too_many_arguments, reason = "the stage's inputs, named")]
fn finish_connections(
    scene: &CompiledScene,
    s: &mut Scratch,
    light: &LightVertices,
    pts: &ShadingPoints,
    incoming: &Rays,
    arena: &Bump,
    counters: &PatternCounters,
) {
    let f = s.factors;
    let lp = &light.points;
    for bounce in 0..s.pending.len().min(light.bounces()) {
        if s.pending[bounce].is_empty() {
            continue;
        }
        let rows = light.bounce_rows(bounce);
        let n = rows.len();
        let runs = || {
            light.runs[bounce]
                .iter()
                .map(|r| (r.material, r.mode, r.rows.clone()))
        };
        // Directions from each light vertex towards its camera vertex (its own `vn` where
        // it has none: evaluated and ignored).
        s.layer_wi.clear();
        s.layer_wi.extend_from_slice(&lp.vn[rows.clone()]);
        for c in &s.pending[bounce] {
            let (i, v) = (c.i as usize, c.v as usize);
            s.layer_wi[v - rows.start] = (pts.p[i] - lp.p[v]).normalize_or_zero();
        }
        // Forward: the light subpath's own view (its stored `vn`) towards the camera vertex.
        s.layer_value.clear();
        s.layer_value.resize(n, Rgb::BLACK);
        s.layer_pdf.clear();
        s.layer_pdf.resize(n, 0.0);
        evaluate_runs(
            scene,
            lp,
            runs(),
            rows.start,
            &s.layer_wi,
            &mut s.layer_value,
            &mut s.layer_pdf,
            arena,
            counters,
        );
        std::mem::swap(&mut s.layer_pdf, &mut s.layer_pdf_fwd);
        // Reverse and the value: seen from the camera vertex, light from the subpath.
        s.layer_copy.clear();
        s.layer_copy.extend_from_range(lp, rows.clone());
        for k in 0..n {
            let view = s.layer_wi[k];
            s.layer_copy.vn[k] = view;
            if s.layer_copy.shape[k] != u32::MAX {
                s.layer_copy.front_face[k] = view.dot(s.layer_copy.ng[k]) > 0.0;
            }
        }
        s.layer_pdf.clear();
        s.layer_pdf.resize(n, 0.0);
        let copy_runs =
            runs().map(|(m, mode, r)| (m, mode, r.start - rows.start..r.end - rows.start));
        evaluate_runs(
            scene,
            &s.layer_copy,
            copy_runs,
            0,
            &lp.vn[rows.clone()],
            &mut s.layer_value,
            &mut s.layer_pdf,
            arena,
            counters,
        );
        for c in &s.pending[bounce] {
            let (i, v) = (c.i as usize, c.v as usize);
            let k = v - rows.start;
            let r = pts.ray_id[i] as usize;
            let path = incoming.path[r] as usize;
            let d = lp.p[v] - pts.p[i];
            let distance = d.length();
            let dir = d / distance;
            let cos_camera = cos_at(pts, i, dir);
            let cos_light = cos_at(lp, v, -dir);
            let Some(adjoint) = adjoint_cosines(lp, v, -dir) else {
                continue;
            };
            // The light vertex seen from the camera vertex, light from its own subpath:
            // `f |cos of its incident direction|`, made the adjoint's `f |cos towards the
            // camera vertex|` ([`adjoint_cosines`]).
            let f_light = s.layer_value[k] * adjoint;
            let pdfs = ConnectionPdfs {
                camera_pdf_a: pdf_w_to_a(c.camera_pdf_w, distance, cos_light),
                camera_rev_pdf_w: c.camera_rev_pdf_w,
                light_pdf_a: pdf_w_to_a(s.layer_pdf_fwd[k], distance, cos_camera),
                light_rev_pdf_w: s.layer_pdf[k],
            };
            let (vc, vl) = (
                f.at(pts.shape[i] == u32::MAX),
                f.at(lp.shape[v] == u32::MAX),
            );
            let weight = connection_weight(&c.camera_mis, &light.mis[v], &pdfs, vc, vl);
            let contribution = incoming.throughput[r]
                * c.camera_value
                * f_light
                * light.throughput[v]
                * (weight / (distance * distance));
            if contribution.is_black() || !contribution.is_finite() {
                continue;
            }
            let stack = stack_toward(scene, &incoming.volume_stack[r], pts, i, dir);
            let margin = arrival_margin(lp, v, dir);
            push_connection(
                &mut s.connections,
                pts,
                i,
                dir,
                distance,
                margin,
                contribution,
                path as u32,
                incoming.dimension[r],
                stack,
            );
        }
        s.pending[bounce].clear();
    }
}

/// Vertex merging at the group's vertices: every light vertex of the batch within the merge
/// radius (of the same kind: surface points with surface points, points in media with
/// points in media) is taken as light arriving at the camera vertex, a density estimate
/// with the kernel `1 / (pi r^2 N_L)` on surfaces and `1 / (4/3 pi r^3 N_L)` in media
/// (photon mapping; Georgiev et al. 2012, eq. 9; the point-point estimator of Křivánek et
/// al. 2014), weighted against every other strategy. Added to the paths' `radiance`.
fn merge_light_vertices(
    scene: &CompiledScene,
    s: &mut Scratch,
    light: &LightVertices,
    at: &GroupVertices<'_>,
    radiance: &mut [Rgb],
    arena: &Bump,
    counters: &PatternCounters,
) {
    let f = s.factors;
    let (pts, incoming) = (at.pts, at.incoming);
    let lp = &light.points;
    let (grid, merges) = (&s.grid, &mut s.merges);
    let normals = scene.features.vertex_normals;
    merges.clear();
    for (k, i) in at.range.clone().enumerate() {
        let r = pts.ray_id[i] as usize;
        let in_medium = pts.shape[i] == u32::MAX;
        let camera_segments = incoming.depth[r] as u32 + 1;
        grid.query(&lp.p, pts.p[i], |v| {
            let fits = camera_segments + light.segments[v] <= scene.settings.max_depth;
            let agree = !normals || sides_agree(pts, i, lp.vn[v]);
            if fits && agree && (lp.shape[v] == u32::MAX) == in_medium {
                merges.push((k as u32, v as u32));
            }
        });
    }
    if merges.is_empty() {
        return;
    }
    let rows = merges.iter().map(|&(k, _)| at.range.start + k as usize);
    s.pair_eval.bind_rows(pts, rows);
    // Forward: the camera vertex's closure towards each light vertex's incident direction;
    // reverse: seen from there, towards the camera vertex's own incident direction.
    s.view.clear();
    s.view.extend(
        merges
            .iter()
            .map(|&(k, _)| pts.vn[at.range.start + k as usize]),
    );
    s.wi.clear();
    s.wi.extend(merges.iter().map(|&(_, v)| lp.vn[v as usize]));
    s.pair_eval
        .run(scene, at.material, at.mode, &s.view, &s.wi, arena, counters);
    std::mem::swap(&mut s.value, &mut s.pair_eval.value);
    std::mem::swap(&mut s.pdf, &mut s.pair_eval.pdf);
    s.pair_eval
        .run(scene, at.material, at.mode, &s.wi, &s.view, arena, counters);
    let pi = std::f32::consts::PI;
    let r = s.merge_radius;
    let light_paths = f.light_paths_in_batch;
    for (e, &(k, v)) in s.merges.iter().enumerate() {
        let (i, v) = (at.range.start + k as usize, v as usize);
        let ray = pts.ray_id[i] as usize;
        let path = incoming.path[ray] as usize;
        let in_medium = pts.shape[i] == u32::MAX;
        let cos = cos_at(pts, i, lp.vn[v]);
        if cos <= 0.0 {
            continue;
        }
        let kernel = if in_medium {
            4.0 / 3.0 * pi * r * r * r * light_paths
        } else {
            pi * r * r * light_paths
        };
        let weight = merge_weight(
            &s.mis[path],
            &light.mis[v],
            s.pdf[e],
            s.pair_eval.pdf[e],
            f.at(in_medium),
        );
        // `f` without the cosine: the light vertices' flux already is per unit projected
        // area of their own surface.
        let c =
            incoming.throughput[ray] * s.value[e] * light.throughput[v] * (weight / (cos * kernel));
        if c.is_finite() {
            radiance[path] += c;
        }
    }
}

/// The factor that makes a radiance closure's value at a light vertex (row `i` of `pts`),
/// seen from `w` with light from its `vn`, `f |vn . Nn|`, the adjoint's `f* |w . Ng|`
/// for the geometry term: `|w . Ng| / |vn . Ng|`. With shading normals the adjoint is not
/// the closure seen backwards (Veach 1997, sec. 5.3, eq. 5.19): the shading cosine belongs
/// to the incident direction, the geometric one to the outgoing; inside a medium both are
/// 1. `None` where the factor is undefined (grazing `vn`).
pub(super) fn adjoint_cosines(pts: &ShadingPoints, i: usize, w: Vec3) -> Option<f32> {
    if pts.shape[i] == u32::MAX {
        return Some(1.0);
    }
    let ng = pts.ng[i];
    let cos_in = pts.vn[i].dot(ng).abs();
    (cos_in > 0.0).then(|| w.dot(ng).abs() / cos_in)
}

/// Whether leaving row `i` of `pts` towards `w` is reflection by both its normals or
/// transmission by both (the path tracer's rule for shading normals, see
/// `path_tracer::shading_normals`); always inside a medium.
pub(super) fn sides_agree(pts: &ShadingPoints, i: usize, w: Vec3) -> bool {
    pts.shape[i] == u32::MAX || crate::path_tracer::sides_agree(pts.ng[i], pts.nn[i], pts.vn[i], w)
}

/// A connection whose camera side is evaluated: camera vertex row `i`, light vertex `v`.
#[derive(Clone, Copy, Debug)]
pub(super) struct PendingConnection {
    i: u32,
    v: u32,
    /// The camera subpath's MIS sums at the vertex (before it scatters on).
    camera_mis: SubpathMis,
    /// `f |cos|` of the camera vertex towards the light vertex.
    camera_value: Rgb,
    /// The camera vertex's pdf of that direction.
    camera_pdf_w: f32,
    /// The camera vertex's pdf of its incident direction, seen from the light vertex.
    camera_rev_pdf_w: f32,
}

/// A light sample at a camera vertex (`k` of its group) and what its weight needs.
#[derive(Clone, Copy, Debug)]
pub(super) struct LightHit {
    k: u32,
    sample: LightSample,
    emission_pdf: f32,
    cos_at_light: f32,
}

/// The outward normal of the area light on `prim` at `q`.
fn area_light_normal(scene: &CompiledScene, prim: u32, q: Vec3) -> Vec3 {
    let g = &scene.geometry;
    let p = prim as usize;
    if p < g.num_triangles() {
        g.sample_surface(prim, Vec2::ZERO).ng
    } else {
        let sphere = g.sphere(p - g.num_triangles());
        (q - sphere.center).normalize_or_zero()
    }
}
