//! The connection strategies at camera vertices: a light sample (next-event estimation:
//! one light vertex on a light) and connections to every stored vertex of the camera
//! sample's own light subpath, each weighted by [`super::mis`] against every other strategy
//! and queued as a shadow ray.

use super::camera_walk::GroupVertices;
use super::evaluate::{adjoint_cosines, cos_at, evaluate_runs, sides_agree};
use super::mis::{connection_weight, light_sample_weight, pdf_w_to_a, ConnectionPdfs, SubpathMis};
use super::vertices::{LightVertices, NO_VERTEX};
use super::walk::{arrival_margin, push_connection, stack_toward};
use super::{strategy_weight, Scratch};
use crate::plugin::{Bxdf, PatternCounters, ShadingContext};
use crate::scene::CompiledScene;
use bumpalo::Bump;
use glam::{Vec2, Vec3};
use risotto_components::{Rays, Rgb, ShadingPoints};
use risotto_systems::lights::{Light, LightSample};

/// Next-event estimation at the group's vertices (a light vertex sampled on a light, seen
/// from the camera vertex), weighted against every other strategy. `bxdf` is the group's
/// closure (bound to `ctx`).
#[allow(clippy::too_many_arguments, reason = "the stage's inputs, named")]
pub(super) fn light_samples(
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
    let lights = scene.bidirectional_lights();
    let bounds = scene.geometry.bounds();
    let normals = scene.discards_disagreeing_directions();
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
            // A point of a medium: its majorant, the camera side's density of reaching it
            // per unit solid angle and distance^-2 (`volume_emission.rs`).
            Light::Volume { emitter } => (Vec3::ZERO, emitter.mis_majorant(q)),
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
        let weight = strategy_weight(s.alone, 1, incoming.depth[r] as u32 + 2, weight);
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
/// [`finish`].
#[allow(clippy::too_many_arguments, reason = "the stage's inputs, named")]
pub(super) fn light_vertices(
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
    let normals = scene.discards_disagreeing_directions();
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

/// Finishes the connections [`light_vertices`] queued for one camera bounce (camera
/// vertices: rows of `pts`, reached by rows of `incoming`): the light side of each, for a
/// whole bounce of light vertices at a time (closures of the stored rows as they are for the
/// forward pdf, a copy seen from the camera vertices for the value and reverse pdf), the
/// weight and a shadow ray.
#[allow(clippy::too_many_arguments, reason = "the stage's inputs, named")]
pub(super) fn finish(
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
            let (s_light, t_camera) = (light.segments[v] + 1, incoming.depth[r] as u32 + 2);
            let weight = strategy_weight(s.alone, s_light, t_camera, weight);
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
