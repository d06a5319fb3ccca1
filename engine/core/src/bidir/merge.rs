//! Vertex merging at camera vertices (`integrator = vcm`), against the light vertices of
//! every light subpath of the iteration.

use super::camera_walk::GroupVertices;
use super::evaluate::{cos_at, sides_agree};
use super::mis::{merge_weight, SubpathMis};
use super::vertices::LightVertices;
use super::Scratch;
use crate::plugin::PatternCounters;
use crate::scene::CompiledScene;
use bumpalo::Bump;
use glam::Vec3;
use risotto_components::Rgb;
use risotto_systems::hash_grid::HashGrid;

/// The light vertices an iteration's camera vertices merge: every stored vertex of the
/// light subpaths of all its batches, in one table (what merging reads of them, 49 bytes a
/// vertex, and the hash grid's 20-24), hashed for radius queries.
#[derive(Default)]
pub struct MergeVertices {
    /// Positions.
    pub p: Vec<Vec3>,
    /// The direction back along the light subpath (the stored shading point's `vn`).
    pub toward_light: Vec<Vec3>,
    /// Whether the vertex is a point in a medium (else on a surface).
    pub in_medium: Vec<bool>,
    /// Segments from the light to the vertex.
    pub segments: Vec<u32>,
    /// Light subpath throughput arriving at the vertex.
    pub throughput: Vec<Rgb>,
    /// The light subpath's MIS sums at the vertex.
    pub mis: Vec<SubpathMis>,
    /// `p` hashed for queries of the iteration's radius.
    grid: HashGrid,
}

impl MergeVertices {
    /// Empties the table (keeping its storage).
    pub fn clear(&mut self) {
        self.p.clear();
        self.toward_light.clear();
        self.in_medium.clear();
        self.segments.clear();
        self.throughput.clear();
        self.mis.clear();
    }

    /// Appends every vertex of `light`.
    pub fn extend_from(&mut self, light: &LightVertices) {
        let pts = &light.points;
        self.p.extend_from_slice(&pts.p);
        self.toward_light.extend_from_slice(&pts.vn);
        self.in_medium
            .extend(pts.shape.iter().map(|&s| s == u32::MAX));
        self.segments.extend_from_slice(&light.segments);
        self.throughput.extend_from_slice(&light.throughput);
        self.mis.extend_from_slice(&light.mis);
    }

    /// Hashes the vertices for queries of radius `radius`.
    pub fn build(&mut self, radius: f32) {
        self.grid.build(&self.p, radius);
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.p.len()
    }

    /// True when there is no vertex.
    pub fn is_empty(&self) -> bool {
        self.p.is_empty()
    }
}

/// Vertex merging at the group's vertices: every light vertex of the iteration within the merge
/// radius (of the same kind: surface points with surface points, points in media with
/// points in media) is taken as light arriving at the camera vertex, a density estimate
/// with the kernel `1 / (pi r^2 N_L)` on surfaces and `1 / (4/3 pi r^3 N_L)` in media
/// (photon mapping; Georgiev et al. 2012, eq. 9; the point-point estimator of Křivánek et
/// al. 2014), weighted against every other strategy. Added to the paths' `radiance`.
pub(super) fn light_vertices(
    scene: &CompiledScene,
    s: &mut Scratch,
    light: &MergeVertices,
    at: &GroupVertices<'_>,
    radiance: &mut [Rgb],
    arena: &Bump,
    counters: &PatternCounters,
) {
    let f = s.factors;
    let (pts, incoming) = (at.pts, at.incoming);
    let (grid, merges) = (&light.grid, &mut s.merges);
    let normals = scene.discards_disagreeing_directions();
    merges.clear();
    for (k, i) in at.range.clone().enumerate() {
        let r = pts.ray_id[i] as usize;
        let in_medium = pts.shape[i] == u32::MAX;
        let camera_segments = incoming.depth[r] as u32 + 1;
        grid.query(pts.p[i], |v| {
            let fits = camera_segments + light.segments[v] <= scene.settings.max_depth;
            let agree = !normals || sides_agree(pts, i, light.toward_light[v]);
            if fits && agree && light.in_medium[v] == in_medium {
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
    s.wi.extend(merges.iter().map(|&(_, v)| light.toward_light[v as usize]));
    s.pair_eval
        .run(scene, at.material, at.mode, &s.view, &s.wi, arena, counters);
    std::mem::swap(&mut s.value, &mut s.pair_eval.value);
    std::mem::swap(&mut s.pdf, &mut s.pair_eval.pdf);
    s.pair_eval
        .run(scene, at.material, at.mode, &s.wi, &s.view, arena, counters);
    let pi = std::f32::consts::PI;
    let r = s.merge_radius;
    let light_paths = f.merged_light_paths;
    for (e, &(k, v)) in s.merges.iter().enumerate() {
        let (i, v) = (at.range.start + k as usize, v as usize);
        let ray = pts.ray_id[i] as usize;
        let path = incoming.path[ray] as usize;
        let in_medium = pts.shape[i] == u32::MAX;
        let cos = cos_at(pts, i, light.toward_light[v]);
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
        // No connection strategy: dropped when one is alone.
        let weight = if s.alone.is_some() { 0.0 } else { weight };
        // `f` without the cosine: the light vertices' flux already is per unit projected
        // area of their own surface.
        let c =
            incoming.throughput[ray] * s.value[e] * light.throughput[v] * (weight / (cos * kernel));
        if c.is_finite() {
            radiance[path] += c;
        }
    }
}
