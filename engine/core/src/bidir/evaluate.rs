//! Bxdf evaluation at any set of stored vertices, seen from any direction.
//!
//! A bidirectional integrator evaluates scattering where the path tracer never does: at a
//! light vertex towards a camera vertex found much later, and "backwards" (the pdf of
//! sampling a vertex's incident direction given its outgoing one, the reverse pdf every MIS
//! weight needs). The plug-in contract has one evaluation, `Bxdf::evaluate_samples`, of a
//! closure bound to a shading context whose viewer direction `Vn` is fixed; so each query
//! here is a shading point row whose `Vn` is replaced by the query's viewer direction, the
//! rows are grouped by material and mode, and each group gets a fresh context and closure
//! from its factory (`begin_scatter`) -- exactly what a user's Bxdf sees in the path tracer.
//!
//! Evaluating with viewer and light directions swapped is also how radiance-mode closures
//! give the adjoint (importance) Bxdf `f*(wo, wi) = f(wi, wo)` (Veach 1997, sec. 3.7.6): the
//! value light carried from a light vertex towards a camera vertex is the closure seen from
//! the camera side, light arriving from the light side.

use crate::plugin::{ParamCache, PatternCounters, ShadingContext};
use crate::scene::CompiledScene;
use crate::shade_groups::ShadingMode;
use bumpalo::Bump;
use glam::Vec3;
use risotto_components::{Rgb, ShadingPoints};
use risotto_systems::partition::partition_by_key;

/// Queries of Bxdf values: one shading point row per query (its `vn` the viewer direction
/// of the query), the direction light arrives from, and the answers.
#[derive(Default)]
pub struct Evaluations {
    /// The rows, `vn` set to each query's viewer direction.
    pub points: ShadingPoints,
    /// Unit direction light arrives from (the `wi` of `evaluate_samples`).
    pub wi: Vec<Vec3>,
    /// Answer: `f(vn, wi) |cos wi|` (shading normal; 1 inside media).
    pub value: Vec<Rgb>,
    /// Answer: the solid-angle pdf with which the closure seen from `vn` samples `wi`.
    pub pdf: Vec<f32>,
    grouped: ShadingPoints,
    grouped_wi: Vec<Vec3>,
    keys: Vec<u32>,
    order: Vec<u32>,
    runs: Vec<(u32, std::ops::Range<usize>)>,
    value_tmp: Vec<Rgb>,
    pdf_tmp: Vec<f32>,
}

impl Evaluations {
    /// Removes every query.
    pub fn clear(&mut self) {
        self.points.clear();
        self.wi.clear();
        self.value.clear();
        self.pdf.clear();
    }

    /// Number of queries.
    pub fn len(&self) -> usize {
        self.wi.len()
    }

    /// True when there is no query.
    pub fn is_empty(&self) -> bool {
        self.wi.is_empty()
    }

    /// Queues the closure of row `i` of `pts`, seen from `view`, for light from `wi`;
    /// returns the query's index.
    pub fn push(&mut self, pts: &ShadingPoints, i: usize, view: Vec3, wi: Vec3) -> usize {
        let k = self.wi.len();
        self.points.extend_from_range(pts, i..i + 1);
        self.points.vn[k] = view;
        // A surface point is on the front face when its viewer is on the side `ng` faces
        // (what the trace stage sets from the arriving ray).
        if pts.shape[i] != u32::MAX {
            self.points.front_face[k] = view.dot(pts.ng[i]) > 0.0;
        }
        self.wi.push(wi);
        k
    }

    /// Answers every query (`value`, `pdf`), one closure per material and mode.
    pub fn run(&mut self, scene: &CompiledScene, arena: &Bump, counters: &PatternCounters) {
        let n = self.wi.len();
        self.value.clear();
        self.value.resize(n, Rgb::BLACK);
        self.pdf.clear();
        self.pdf.resize(n, 0.0);
        if n == 0 {
            return;
        }
        self.keys.clear();
        self.keys.extend((0..n).map(|k| {
            let volume = (self.points.shape[k] == u32::MAX) as u32;
            self.points.material[k] * 2 + volume
        }));
        partition_by_key(
            &self.keys,
            scene.materials.len() * 2,
            &mut self.order,
            &mut self.runs,
        );
        self.grouped.clear();
        self.grouped_wi.clear();
        for &k in &self.order {
            let k = k as usize;
            self.grouped.extend_from_range(&self.points, k..k + 1);
            self.grouped_wi.push(self.wi[k]);
        }
        for (key, range) in &self.runs {
            let material = key / 2;
            let mode = match key % 2 {
                0 => ShadingMode::Scatter,
                _ => ShadingMode::VolumeScatter,
            };
            let factory = scene.materials[material as usize].factory.as_ref();
            let cache = arena.alloc(ParamCache::new(arena, counters));
            let ctx = ShadingContext::new(&self.grouped, range.clone(), mode, material, &[])
                .with_factory(factory)
                .with_cache(cache);
            let bxdf = factory.begin_scatter(&ctx, mode, arena);
            let m = range.len();
            self.value_tmp.clear();
            self.value_tmp.resize(m, Rgb::BLACK);
            self.pdf_tmp.clear();
            self.pdf_tmp.resize(m, 0.0);
            bxdf.evaluate_samples(
                &ctx,
                &self.grouped_wi[range.clone()],
                &mut self.value_tmp,
                &mut self.pdf_tmp,
            );
            for (j, &k) in self.order[range.clone()].iter().enumerate() {
                self.value[k as usize] = self.value_tmp[j];
                self.pdf[k as usize] = self.pdf_tmp[j];
            }
        }
    }
}

/// `|cos|` of direction `w` at row `i` of `pts` against its shading normal; 1 inside a
/// medium (no surface).
#[inline]
pub fn cos_at(pts: &ShadingPoints, i: usize, w: Vec3) -> f32 {
    if pts.shape[i] == u32::MAX {
        1.0
    } else {
        pts.nn[i].dot(w).abs()
    }
}
