//! The integrator context (RIS `RixIntegratorContext`): the renderer's ray-tracing services
//! for global and volume integrators.

use crate::plugin::{ShadeGroup, ShadeGroups, ShadingMode};
use crate::scene::CompiledScene;
use crate::stats::{System, SystemStats};
use risotto_components::{Hits, Rays, Rgb, VolumeStack, NO_HIT};
use risotto_systems::geometry::SurfaceSample;
use risotto_systems::intersect::intersect_closest;

/// Reusable buffers of [`IntegratorContext::nearest_hits`], kept by a worker across calls so
/// the per-bounce path does not allocate.
#[derive(Debug, Default)]
pub struct HitScratch {
    hits: Hits,
    /// Material of each ray's hit (`u32::MAX` for a miss).
    material: Vec<u32>,
    counts: Vec<u32>,
    cursor: Vec<u32>,
    sorted: Vec<u32>,
    /// Geometry of each hit, in sorted order.
    surface: Vec<SurfaceSample>,
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
        // Counting sort of hit rays by material: groups come out contiguous and in material
        // order, so each factory runs once per call.
        let num_materials = scene.materials.len();
        s.counts.clear();
        s.counts.resize(num_materials + 1, 0);
        s.material.clear();
        for i in 0..n {
            let prim = hits.prim[i];
            if prim == NO_HIT {
                out.push_miss(i as u32, Rgb::WHITE);
                s.material.push(u32::MAX);
            } else {
                let shape = scene.prim_shape[prim as usize];
                let m = scene.shapes[shape as usize].material;
                s.counts[m as usize + 1] += 1;
                s.material.push(m);
            }
        }
        for m in 0..num_materials {
            s.counts[m + 1] += s.counts[m];
        }
        s.cursor.clear();
        s.cursor.extend_from_slice(&s.counts);
        s.sorted.resize(s.counts[num_materials] as usize, 0);
        for i in 0..n {
            let m = s.material[i];
            if m != u32::MAX {
                s.sorted[s.cursor[m as usize] as usize] = i as u32;
                s.cursor[m as usize] += 1;
            }
        }
        // The shading points of all hits, in sorted order, written column by column: each
        // column is one tight loop (one capacity check, no row structs), which measured
        // faster than pushing 14-column rows.
        let count = s.sorted.len();
        let base = out.points.len();
        s.surface.clear();
        s.surface.extend(s.sorted.iter().map(|&i| {
            let i = i as usize;
            geometry.surface_at(
                hits.prim[i],
                rays.origin[i],
                rays.direction[i],
                hits.t[i],
                hits.b1[i],
                hits.b2[i],
            )
        }));
        let (sorted, surface) = (&s.sorted, &s.surface);
        let shape_of = |i: u32| scene.prim_shape[hits.prim[i as usize] as usize];
        let pts = &mut out.points;
        pts.p.extend(surface.iter().map(|x| x.p));
        pts.ng.extend(surface.iter().map(|x| x.ng));
        pts.nn.extend(surface.iter().map(|x| x.ng));
        pts.vn
            .extend(sorted.iter().map(|&i| -rays.direction[i as usize]));
        pts.vlen.extend(sorted.iter().map(|&i| hits.t[i as usize]));
        pts.u.extend(surface.iter().map(|x| x.uv.x));
        pts.v.extend(surface.iter().map(|x| x.uv.y));
        pts.w.extend(std::iter::repeat_n(0.0, count));
        pts.transmission
            .extend(std::iter::repeat_n(Rgb::WHITE, count));
        pts.ray_id.extend_from_slice(sorted);
        pts.material
            .extend(sorted.iter().map(|&i| s.material[i as usize]));
        pts.shape.extend(sorted.iter().map(|&i| shape_of(i)));
        pts.front_face.extend(
            sorted
                .iter()
                .zip(surface)
                .map(|(&i, x)| rays.direction[i as usize].dot(x.ng) < 0.0),
        );
        pts.ior_outside.extend(sorted.iter().map(|&i| {
            let stack = &rays.volume_stack[i as usize];
            if stack.is_empty() {
                1.0
            } else {
                ior_outside(scene, stack, shape_of(i))
            }
        }));
        debug_assert!(pts.is_consistent(), "a shading-point column was not filled");
        for m in 0..num_materials {
            let range = s.counts[m] as usize..s.counts[m + 1] as usize;
            if !range.is_empty() {
                out.groups.push(ShadeGroup {
                    material: m as u32,
                    mode: ShadingMode::Scatter,
                    range: base + range.start..base + range.end,
                });
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
