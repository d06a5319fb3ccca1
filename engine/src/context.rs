//! The integrator context (RIS `RixIntegratorContext`): the renderer's ray-tracing services
//! for global and volume integrators.

use crate::plugin::{ShadeGroups, ShadingMode};
use crate::scene::CompiledScene;
use crate::stats::{System, SystemStats};
use risotto_components::{Hits, Rays, Rgb, ShadingPointRow, VolumeStack, NO_HIT};
use risotto_systems::intersect::intersect_closest;

/// Ray-tracing services bound to one compiled scene and one worker.
pub struct IntegratorContext<'s> {
    /// The scene.
    pub scene: &'s CompiledScene,
    /// The worker's statistics.
    pub stats: &'s mut SystemStats,
    hits: Hits,
    order: Vec<u32>,
    rows: Vec<ShadingPointRow>,
}

impl<'s> IntegratorContext<'s> {
    /// A context for `scene`, recording into `stats`.
    pub fn new(scene: &'s CompiledScene, stats: &'s mut SystemStats) -> Self {
        IntegratorContext {
            scene,
            stats,
            hits: Hits::default(),
            order: Vec::new(),
            rows: Vec::new(),
        }
    }

    /// IOR outside `shape` for a ray travelling with `stack`: the IOR of the innermost volume
    /// that is not `shape`'s own interior (1 in vacuum).
    pub fn ior_outside(&self, stack: &VolumeStack, shape: u32) -> f32 {
        let mut best: Option<risotto_components::VolumeEntry> = None;
        for e in stack.entries() {
            if e.shape != shape && best.is_none_or(|b| e.priority >= b.priority) {
                best = Some(*e);
            }
        }
        best.map_or(1.0, |e| self.scene.material_info[e.material as usize].ior)
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
        let hits = &mut self.hits;
        hits.t.resize(n, 0.0);
        hits.prim.resize(n, NO_HIT);
        hits.b1.resize(n, 0.0);
        hits.b2.resize(n, 0.0);
        let geometry = &self.scene.geometry;
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
        let scene = self.scene;
        let num_materials = scene.materials.len();
        let mut counts = vec![0u32; num_materials + 1];
        self.order.clear();
        for i in 0..n {
            let prim = self.hits.prim[i];
            if prim == NO_HIT {
                out.push_miss(i as u32, Rgb::WHITE);
            } else {
                let shape = scene.prim_shape[prim as usize];
                counts[scene.shapes[shape as usize].material as usize + 1] += 1;
                self.order.push(i as u32);
            }
        }
        for m in 0..num_materials {
            counts[m + 1] += counts[m];
        }
        let mut cursor = counts.clone();
        let mut sorted = vec![0u32; self.order.len()];
        for &i in &self.order {
            let shape = scene.prim_shape[self.hits.prim[i as usize] as usize];
            let m = scene.shapes[shape as usize].material as usize;
            sorted[cursor[m] as usize] = i;
            cursor[m] += 1;
        }
        for m in 0..num_materials {
            let range = counts[m] as usize..counts[m + 1] as usize;
            if range.is_empty() {
                continue;
            }
            self.rows.clear();
            for &i in &sorted[range] {
                let i = i as usize;
                let prim = self.hits.prim[i];
                let shape = scene.prim_shape[prim as usize];
                let d = rays.direction[i];
                let s = geometry.surface_at(
                    prim,
                    rays.origin[i],
                    d,
                    self.hits.t[i],
                    self.hits.b1[i],
                    self.hits.b2[i],
                );
                self.rows.push(ShadingPointRow {
                    p: s.p,
                    ng: s.ng,
                    nn: s.ng,
                    vn: -d,
                    vlen: self.hits.t[i],
                    u: s.uv.x,
                    v: s.uv.y,
                    w: 0.0,
                    transmission: Rgb::WHITE,
                    ray_id: i as u32,
                    material: m as u32,
                    shape,
                    front_face: d.dot(s.ng) < 0.0,
                    ior_outside: self.ior_outside(&rays.volume_stack[i], shape),
                });
            }
            out.push_group(m as u32, ShadingMode::Scatter, self.rows.drain(..));
        }
    }
}
