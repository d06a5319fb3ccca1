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

/// One shading group's points seen from other viewers: a copy of the group's rows, made
/// once, whose `Vn` each evaluation round overwrites (one closure per round for the whole
/// group; rows without a query of their own take any direction and are ignored).
#[derive(Default)]
pub struct GroupEvaluations {
    points: ShadingPoints,
    /// Answer of the last round, per row: `f(view, wi) |cos wi|`.
    pub value: Vec<Rgb>,
    /// Answer of the last round, per row: the pdf of sampling `wi` seen from `view`.
    pub pdf: Vec<f32>,
}

impl GroupEvaluations {
    /// Copies the rows `range` of `pts`.
    pub fn bind(&mut self, pts: &ShadingPoints, range: std::ops::Range<usize>) {
        self.points.clear();
        self.points.extend_from_range(pts, range);
    }

    /// Copies the rows `rows` of `pts` (all of one material and mode), in order.
    pub fn bind_rows(&mut self, pts: &ShadingPoints, rows: impl Iterator<Item = usize>) {
        self.points.clear();
        for i in rows {
            self.points.push_from(pts, i);
        }
    }

    /// Evaluates every row's closure seen from `view[k]` for light from `wi[k]`; `mode` and
    /// `material` are the group's.
    #[allow(
        clippy::too_many_arguments,
        reason = "the group and the queries, named"
    )]
    pub fn run(
        &mut self,
        scene: &CompiledScene,
        material: u32,
        mode: ShadingMode,
        view: &[Vec3],
        wi: &[Vec3],
        arena: &Bump,
        counters: &PatternCounters,
    ) {
        let m = self.points.len();
        for k in 0..m {
            self.points.vn[k] = view[k];
            if self.points.shape[k] != u32::MAX {
                self.points.front_face[k] = view[k].dot(self.points.ng[k]) > 0.0;
            }
        }
        self.value.clear();
        self.value.resize(m, Rgb::BLACK);
        self.pdf.clear();
        self.pdf.resize(m, 0.0);
        let factory = scene.materials[material as usize].factory.as_ref();
        let cache = arena.alloc(ParamCache::new(arena, counters));
        let ctx = ShadingContext::new(&self.points, 0..m, mode, material, &[])
            .with_factory(factory)
            .with_cache(cache);
        let bxdf = factory.begin_scatter(&ctx, mode, arena);
        bxdf.evaluate_samples(&ctx, &wi[..m], &mut self.value, &mut self.pdf);
    }
}

/// Evaluates the closures of rows of `table` in runs of one material and mode each (`runs`:
/// material, mode, rows), each row seen from its own `vn`, for light from `wi[row - offset]`;
/// the answers go to `value` and `pdf` at the same index.
#[allow(
    clippy::too_many_arguments,
    reason = "the table, the queries and the answers, named"
)]
pub fn evaluate_runs<'r>(
    scene: &CompiledScene,
    table: &ShadingPoints,
    runs: impl Iterator<Item = (u32, ShadingMode, std::ops::Range<usize>)>,
    offset: usize,
    wi: &[Vec3],
    value: &mut [Rgb],
    pdf: &mut [f32],
    arena: &'r Bump,
    counters: &'r PatternCounters,
) {
    for (material, mode, rows) in runs {
        let local = rows.start - offset..rows.end - offset;
        let factory = scene.materials[material as usize].factory.as_ref();
        let cache = arena.alloc(ParamCache::new(arena, counters));
        let ctx = ShadingContext::new(table, rows, mode, material, &[])
            .with_factory(factory)
            .with_cache(cache);
        let bxdf = factory.begin_scatter(&ctx, mode, arena);
        bxdf.evaluate_samples(
            &ctx,
            &wi[local.clone()],
            &mut value[local.clone()],
            &mut pdf[local],
        );
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
