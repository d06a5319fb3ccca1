//! The integrator context (RIS `RixIntegratorContext`): the renderer's ray-tracing services
//! for global and volume integrators.

use crate::plugin::{ShadeGroup, ShadeGroups, ShadingMode};
use crate::scene::CompiledScene;
use crate::stats::{System, SystemStats};
use glam::Vec3;
use risotto_components::{Hits, Rays, Rgb, ShadingPoints, VolumeStack, NO_HIT};
use risotto_systems::geometry::SceneGeometry;
use risotto_systems::intersect::intersect_closest;

/// Reusable buffers of [`IntegratorContext::nearest_hits`], kept by a worker across calls so
/// the per-bounce path does not allocate.
#[derive(Debug, Default)]
pub struct HitScratch {
    hits: Hits,
    /// Rays that hit a surface of material `m`, in ray order.
    buckets: Vec<Vec<u32>>,
    /// Rays that hit nothing.
    escaped: Vec<u32>,
    /// The buckets concatenated: the rays of the shading points, in point order.
    sorted: Vec<u32>,
    /// At least as many zero vectors and white colours as the largest batch so far: the
    /// 12-byte columns are sized by copying from these (`Vec::resize` writes 12-byte values
    /// one at a time; a copy is a memcpy).
    zeros: Vec<Vec3>,
    whites: Vec<Rgb>,
}

/// Ray-tracing services bound to one compiled scene and one worker.
pub struct IntegratorContext<'s> {
    /// The scene.
    pub scene: &'s CompiledScene,
    /// The worker's statistics.
    pub stats: &'s mut SystemStats,
    scratch: HitScratch,
}

impl<'s> IntegratorContext<'s> {
    /// A context for `scene`, recording into `stats`.
    pub fn new(scene: &'s CompiledScene, stats: &'s mut SystemStats) -> Self {
        Self::with_scratch(scene, stats, HitScratch::default())
    }

    /// A context reusing the buffers of an earlier one ([`Self::into_scratch`]).
    pub fn with_scratch(
        scene: &'s CompiledScene,
        stats: &'s mut SystemStats,
        scratch: HitScratch,
    ) -> Self {
        IntegratorContext {
            scene,
            stats,
            scratch,
        }
    }

    /// Gives the buffers back for the next context.
    pub fn into_scratch(self) -> HitScratch {
        self.scratch
    }

    /// IOR outside `shape` for a ray travelling with `stack`: the IOR of the innermost volume
    /// that is not `shape`'s own interior (1 in vacuum).
    pub fn ior_outside(&self, stack: &VolumeStack, shape: u32) -> f32 {
        ior_outside(self.scene, stack, shape)
    }

    /// Traces `rays` to their nearest surface hits and appends the hits to `out`, grouped by
    /// material (each group contiguous), as [`ShadingMode::Scatter`] groups; rays that escape
    /// are appended to `out.misses`. Points carry `ray_id` = index into `rays` and
    /// transmission 1.
    pub fn nearest_hits(&mut self, rays: &Rays, out: &mut ShadeGroups) {
        let n = rays.len();
        if n == 0 {
            return;
        }
        let scene = self.scene;
        let geometry = &scene.geometry;
        let s = &mut self.scratch;
        let hits = &mut s.hits;
        hits.t.resize(n, 0.0);
        hits.prim.resize(n, NO_HIT);
        hits.b1.resize(n, 0.0);
        hits.b2.resize(n, 0.0);
        self.stats.time(System::Intersect, n, || {
            intersect_closest(
                geometry,
                &rays.origin,
                &rays.direction,
                &rays.tmin,
                &rays.tmax,
                &mut hits.t,
                &mut hits.prim,
                &mut hits.b1,
                &mut hits.b2,
            )
        });
        // Hit rays are grouped by material (a bucket per material, concatenated in material
        // order: groups come out contiguous, so each factory runs once per call), escaped
        // rays go to their own list. Every array is taken as a slice before its loop: stores
        // into the scratch could otherwise alias the `Vec` headers, and the compiler would
        // reload pointers and lengths on every iteration.
        s.buckets.resize_with(scene.materials.len(), Vec::new);
        group_by_material(scene, &hits.prim[..n], &mut s.buckets, &mut s.escaped);
        s.sorted.clear();
        for b in &s.buckets {
            s.sorted.extend_from_slice(b);
        }
        let count = s.sorted.len();
        if s.zeros.len() < n {
            s.zeros.resize(n, Vec3::ZERO);
            s.whites.resize(n, Rgb::WHITE);
        }
        out.misses.extend_from_slice(&s.escaped);
        out.miss_transmission
            .extend_from_slice(&s.whites[..s.escaped.len()]);
        // The shading points of all hits, in sorted order. The columns that vary per point are
        // sized first (12-byte ones by copying from prepared constants: `Vec::resize` writes
        // 12-byte values one at a time) and then written by index in passes over the sorted
        // rays; the columns that are constant per group or copies of another column are
        // filled in bulk afterwards.
        let base = out.points.len();
        let pts = &mut out.points;
        let end = base + count;
        pts.p.extend_from_slice(&s.zeros[..count]);
        pts.ng.extend_from_slice(&s.zeros[..count]);
        pts.vn.extend_from_slice(&s.zeros[..count]);
        pts.vlen.resize(end, 0.0);
        pts.u.resize(end, 0.0);
        pts.v.resize(end, 0.0);
        pts.shape.resize(end, 0);
        pts.front_face.resize(end, false);
        // Vacuum unless the ray travels inside volumes (`write_ray_columns`).
        pts.ior_outside.resize(end, 1.0);
        let sorted = &s.sorted[..count];
        write_surfaces(geometry, sorted, hits, rays, pts, base);
        write_ray_columns(scene, sorted, hits, rays, pts, base);
        pts.nn.extend_from_slice(&pts.ng[base..end]);
        pts.w.resize(end, 0.0);
        pts.transmission.extend_from_slice(&s.whites[..count]);
        pts.ray_id.extend_from_slice(&s.sorted[..count]);
        let mut start = base;
        for (m, b) in s.buckets.iter().enumerate() {
            if !b.is_empty() {
                let end = start + b.len();
                pts.material.resize(end, m as u32);
                out.groups.push(ShadeGroup {
                    material: m as u32,
                    mode: ShadingMode::Scatter,
                    range: start..end,
                });
                start = end;
            }
        }
        debug_assert!(pts.is_consistent(), "a shading-point column was not filled");
    }
}

// The passes that write the shading-point columns `base..base + sorted.len()` from the hits
// of the rays `sorted` (rows of `hits` and `rays`). Each is its own function, and each loop
// leaves the rare cases (spheres, rays inside volumes) to a second loop: a loop with few
// pointers and no call inside keeps everything in registers, where one loop inside the big
// function spilled about a dozen values per point. Every slice is cut to its exact length
// first, so the compiler drops the bounds checks on the outputs.

/// Clears `buckets` (one per material) and `escaped`, then appends the index of every ray
/// whose hit is on a surface of material `m` to `buckets[m]` and of every miss to `escaped`.
/// Its own function for the same reason as the passes below.
#[inline(never)]
fn group_by_material(
    scene: &CompiledScene,
    prims: &[u32],
    buckets: &mut [Vec<u32>],
    escaped: &mut Vec<u32>,
) {
    for b in buckets.iter_mut() {
        b.clear();
    }
    escaped.clear();
    let prim_material = &scene.prim_material[..];
    for (i, &prim) in prims.iter().enumerate() {
        if prim == NO_HIT {
            escaped.push(i as u32);
        } else {
            buckets[prim_material[prim as usize] as usize].push(i as u32);
        }
    }
}

/// Pass 1: `p`, `ng`, `u`, `v`.
#[inline(never)]
fn write_surfaces(
    geometry: &SceneGeometry,
    sorted: &[u32],
    hits: &Hits,
    rays: &Rays,
    pts: &mut ShadingPoints,
    base: usize,
) {
    let (n, count) = (hits.len(), sorted.len());
    let (p, ng) = (&mut pts.p[base..][..count], &mut pts.ng[base..][..count]);
    let (u, v) = (&mut pts.u[base..][..count], &mut pts.v[base..][..count]);
    let (prims, b1, b2) = (&hits.prim[..n], &hits.b1[..n], &hits.b2[..n]);
    let triangles = geometry.triangles();
    let mut spheres = false;
    for k in 0..count {
        let i = sorted[k] as usize;
        if let Some(surf) = triangles.surface_at(prims[i], b1[i], b2[i]) {
            p[k] = surf.p;
            ng[k] = surf.ng;
            u[k] = surf.uv.x;
            v[k] = surf.uv.y;
        } else {
            spheres = true;
        }
    }
    if spheres {
        for (k, &i) in sorted.iter().enumerate() {
            let i = i as usize;
            if triangles.surface_at(prims[i], b1[i], b2[i]).is_none() {
                let surf = geometry.surface_at(
                    prims[i],
                    rays.origin[i],
                    rays.direction[i],
                    hits.t[i],
                    b1[i],
                    b2[i],
                );
                p[k] = surf.p;
                ng[k] = surf.ng;
                u[k] = surf.uv.x;
                v[k] = surf.uv.y;
            }
        }
    }
}

/// Pass 2 (after [`write_surfaces`], it reads `ng`): `vn`, `vlen`, `front_face`, `shape`,
/// `ior_outside`.
#[inline(never)]
fn write_ray_columns(
    scene: &CompiledScene,
    sorted: &[u32],
    hits: &Hits,
    rays: &Rays,
    pts: &mut ShadingPoints,
    base: usize,
) {
    let (n, count) = (hits.len(), sorted.len());
    let (ng, vn, vlen) = (
        &pts.ng[base..][..count],
        &mut pts.vn[base..][..count],
        &mut pts.vlen[base..][..count],
    );
    let (shape, front_face, ior) = (
        &mut pts.shape[base..][..count],
        &mut pts.front_face[base..][..count],
        &mut pts.ior_outside[base..][..count],
    );
    let (prims, t) = (&hits.prim[..n], &hits.t[..n]);
    let (direction, stacks) = (&rays.direction[..n], &rays.volume_stack[..n]);
    let prim_shape = &scene.prim_shape[..];
    let mut in_volumes = false;
    for k in 0..count {
        let i = sorted[k] as usize;
        let d = direction[i];
        vn[k] = -d;
        vlen[k] = t[i];
        front_face[k] = d.dot(ng[k]) < 0.0;
        shape[k] = prim_shape[prims[i] as usize];
        in_volumes |= !stacks[i].is_empty();
    }
    if in_volumes {
        for (k, &i) in sorted.iter().enumerate() {
            let stack = &stacks[i as usize];
            if !stack.is_empty() {
                ior[k] = ior_outside(scene, stack, shape[k]);
            }
        }
    }
}

/// IOR of the innermost volume of `stack` that is not `shape`'s own interior (1 in vacuum).
fn ior_outside(scene: &CompiledScene, stack: &VolumeStack, shape: u32) -> f32 {
    let mut best: Option<risotto_components::VolumeEntry> = None;
    for e in stack.entries() {
        if e.shape != shape && best.is_none_or(|b| e.priority >= b.priority) {
            best = Some(*e);
        }
    }
    best.map_or(1.0, |e| scene.material_info[e.material as usize].ior)
}
