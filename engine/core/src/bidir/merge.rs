//! Vertex merging at camera vertices (`integrator = vcm`).

use super::camera_walk::GroupVertices;
use super::evaluate::{cos_at, sides_agree};
use super::mis::merge_weight;
use super::vertices::LightVertices;
use super::Scratch;
use crate::plugin::PatternCounters;
use crate::scene::CompiledScene;
use bumpalo::Bump;
use risotto_components::Rgb;

/// Vertex merging at the group's vertices: every light vertex of the batch within the merge
/// radius (of the same kind: surface points with surface points, points in media with
/// points in media) is taken as light arriving at the camera vertex, a density estimate
/// with the kernel `1 / (pi r^2 N_L)` on surfaces and `1 / (4/3 pi r^3 N_L)` in media
/// (photon mapping; Georgiev et al. 2012, eq. 9; the point-point estimator of Křivánek et
/// al. 2014), weighted against every other strategy. Added to the paths' `radiance`.
pub(super) fn light_vertices(
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
    let normals = scene.discards_disagreeing_directions();
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
