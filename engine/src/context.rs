//! The integrator context (RIS `RixIntegratorContext`): the renderer's ray-tracing services
//! for global and volume integrators.

use crate::plugin::{ShadeGroup, ShadeGroups, ShadingMode};
use crate::scene::CompiledScene;
use crate::stats::{System, SystemStats};
use glam::Vec3;
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
        s.material.resize(n, 0);
        let (prims, material) = (&hits.prim[..n], &mut s.material[..n]);
        for i in 0..n {
            let prim = prims[i];
            material[i] = if prim == NO_HIT {
                out.push_miss(i as u32, Rgb::WHITE);
                u32::MAX
            } else {
                let shape = scene.prim_shape[prim as usize];
                let m = scene.shapes[shape as usize].material;
                s.counts[m as usize + 1] += 1;
                m
            };
        }
        for m in 0..num_materials {
            s.counts[m + 1] += s.counts[m];
        }
        let count = s.counts[num_materials] as usize;
        s.cursor.clear();
        s.cursor.extend_from_slice(&s.counts[..num_materials]);
        s.sorted.resize(count, 0);
        for (i, &m) in material.iter().enumerate() {
            if m != u32::MAX {
                let slot = &mut s.cursor[m as usize];
                s.sorted[*slot as usize] = i as u32;
                *slot += 1;
            }
        }
        // The shading points of all hits, in sorted order. The columns that vary per point are
        // sized first and then written in one pass over the sorted rays (every slice is cut to
        // its exact length, so the compiler drops the bounds checks); the columns that are
        // constant per group or copies of another column are filled in bulk afterwards.
        let base = out.points.len();
        let pts = &mut out.points;
        let end = base + count;
        pts.p.resize(end, Vec3::ZERO);
        pts.ng.resize(end, Vec3::ZERO);
        pts.vn.resize(end, Vec3::ZERO);
        pts.vlen.resize(end, 0.0);
        pts.u.resize(end, 0.0);
        pts.v.resize(end, 0.0);
        pts.shape.resize(end, 0);
        pts.front_face.resize(end, false);
        pts.ior_outside.resize(end, 0.0);
        {
            let sorted = &s.sorted[..count];
            let (p, ng, vn, vlen) = (
                &mut pts.p[base..end],
                &mut pts.ng[base..end],
                &mut pts.vn[base..end],
                &mut pts.vlen[base..end],
            );
            let (u, v) = (&mut pts.u[base..end], &mut pts.v[base..end]);
            let (shape_out, front_face, ior_out) = (
                &mut pts.shape[base..end],
                &mut pts.front_face[base..end],
                &mut pts.ior_outside[base..end],
            );
            let (t, b1, b2) = (&hits.t[..n], &hits.b1[..n], &hits.b2[..n]);
            let (origin, direction, stacks) = (
                &rays.origin[..n],
                &rays.direction[..n],
                &rays.volume_stack[..n],
            );
            // Two passes over the sorted rays rather than one: each needs few enough pointers
            // to stay in registers. First the surface geometry...
            for k in 0..count {
                let i = sorted[k] as usize;
                let prim = prims[i];
                // Written from each branch, so the triangle case stays in registers.
                macro_rules! emit {
                    ($surf:expr) => {{
                        let surf: SurfaceSample = $surf;
                        p[k] = surf.p;
                        ng[k] = surf.ng;
                        u[k] = surf.uv.x;
                        v[k] = surf.uv.y;
                    }};
                }
                match geometry.triangle_surface_at(prim, b1[i], b2[i]) {
                    Some(surf) => emit!(surf),
                    None => emit!(geometry.surface_at(
                        prim,
                        origin[i],
                        direction[i],
                        t[i],
                        b1[i],
                        b2[i]
                    )),
                }
            }
            // ...then what comes from the ray.
            let ng = &*ng;
            for k in 0..count {
                let i = sorted[k] as usize;
                let d = direction[i];
                let shape = scene.prim_shape[prims[i] as usize];
                vn[k] = -d;
                vlen[k] = t[i];
                front_face[k] = d.dot(ng[k]) < 0.0;
                shape_out[k] = shape;
                let stack = &stacks[i];
                ior_out[k] = if stack.is_empty() {
                    1.0
                } else {
                    ior_outside(scene, stack, shape)
                };
            }
        }
        pts.nn.extend_from_slice(&pts.ng[base..end]);
        pts.w.resize(end, 0.0);
        pts.transmission.resize(end, Rgb::WHITE);
        pts.ray_id.extend_from_slice(&s.sorted[..count]);
        for m in 0..num_materials {
            let range = s.counts[m] as usize..s.counts[m + 1] as usize;
            if !range.is_empty() {
                pts.material.resize(base + range.end, m as u32);
                out.groups.push(ShadeGroup {
                    material: m as u32,
                    mode: ShadingMode::Scatter,
                    range: base + range.start..base + range.end,
                });
            }
        }
        debug_assert!(pts.is_consistent(), "a shading-point column was not filled");
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
