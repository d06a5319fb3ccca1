//! Pattern coefficients of a heterogeneous medium: a pattern graph of the world position `P`
//! as the density or the emission, its majorant grids from the graph's interval bounds, and
//! its evaluation one point at a time along a ray.

use glam::{Affine3A, Vec3};
use risotto_components::Rgb;
use risotto_systems::grid::{DensityChannels, DensityGrid, MajorantGrid};
use risotto_systems::pattern::{self, PatternGraph};
use std::cell::{Cell, RefCell};
use std::sync::{Arc, RwLock};

/// A medium coefficient given by a pattern graph of the world position `P` (the same `P`
/// surface patterns see; `u`, `v` are not defined inside a medium, and graphs that read them
/// are refused when the scene is read). Its majorant grid is made per box (the shape's
/// object-space bounds and transform, known only once the scene is compiled, and one
/// material may fill several shapes), on first use, and kept.
///
/// A colour graph as a density is a density per channel (`sigma_t,c = scale_c
/// density_c(P)`): its bounds are then weighted per channel by `k = scale / max(scale)`
/// ([`PatternField::with_channel_weights`]), so that `max(scale)` times a cell's bound is the
/// largest channel's extinction bound and the low end the smallest channel's, as a
/// 3-channel grid's majorants are ([`risotto_systems::grid::DensityChannels::majorants`]).
#[derive(Debug)]
pub struct PatternField {
    /// The graph (shared with the medium's volume emitter).
    pub graph: Arc<PatternGraph>,
    /// Majorant cells per axis.
    pub res: [usize; 3],
    /// Per-channel weights of the bounds, for a density per channel; `None`: the bounds are
    /// the lowest channel's low end and the highest channel's high end, unweighted.
    pub channel_weights: Option<Rgb>,
    /// Majorant grids made so far, by object box and object-to-world transform.
    grids: RwLock<Vec<GridKey>>,
}

/// A majorant grid of a [`PatternField`] and the box and transform it was made for.
type GridKey = (Vec3, Vec3, Option<Affine3A>, Arc<MajorantGrid>);

impl Clone for PatternField {
    fn clone(&self) -> Self {
        PatternField::shared(self.graph.clone(), self.res)
            .with_channel_weights(self.channel_weights)
    }
}

impl PartialEq for PatternField {
    fn eq(&self, other: &Self) -> bool {
        self.graph == other.graph
            && self.res == other.res
            && self.channel_weights == other.channel_weights
    }
}

impl PatternField {
    /// The field of `graph` with majorant grids of `res` cells per axis (each at least 1).
    pub fn new(graph: PatternGraph, res: [usize; 3]) -> Self {
        PatternField::shared(Arc::new(graph), res)
    }

    /// [`PatternField::new`] of a graph shared with others.
    pub fn shared(graph: Arc<PatternGraph>, res: [usize; 3]) -> Self {
        PatternField {
            graph,
            res: res.map(|r| r.max(1)),
            channel_weights: None,
            grids: RwLock::new(Vec::new()),
        }
    }

    /// The field with its bounds weighted per channel by `weights` (a density per channel:
    /// `scale / max(scale)`; the type docs), its majorant grids made afresh.
    pub fn with_channel_weights(self, weights: Option<Rgb>) -> Self {
        PatternField {
            channel_weights: weights,
            grids: RwLock::new(Vec::new()),
            ..self
        }
    }

    /// `(low, high)` of the graph's channel intervals `[lo, hi]`: the lowest channel's low
    /// end and the highest channel's high end, each channel weighted first for a density
    /// per channel.
    fn span(&self, lo: Rgb, hi: Rgb) -> (f32, f32) {
        match self.channel_weights {
            None => (lo.min_channel(), hi.max_channel()),
            Some(k) => ((lo * k).min_channel(), (hi * k).max_channel()),
        }
    }

    /// The field's bounds over all of space: `(lowest channel, highest channel)` (weighted
    /// for a density per channel).
    pub fn global_bounds(&self) -> (f32, f32) {
        let (lo, hi) = pattern::bounds(&self.graph, Vec3::NEG_INFINITY, Vec3::INFINITY);
        self.span(lo, hi)
    }

    /// The majorant grid of the field over the world box `[lo, hi]` (the grid's unit cube
    /// mapped onto the box, as the density grid is placed): cell `c` holds the graph's
    /// interval bounds ([`pattern::bounds`]) over the cell's world box, the lowest channel's
    /// low end (at least 0) and the highest channel's high end.
    pub fn majorants(&self, lo: Vec3, hi: Vec3) -> Arc<MajorantGrid> {
        self.majorants_in(lo, hi, None)
    }

    /// The majorant grid of the field over the object box `[lo, hi]` of a shape whose
    /// object space maps to the world by `to_world` (`None`: the identity, as
    /// [`Self::majorants`]): cell `c` holds the graph's bounds over the world bounding box
    /// of the cell's object box (the graph reads world `P`).
    pub fn majorants_in(
        &self,
        lo: Vec3,
        hi: Vec3,
        to_world: Option<Affine3A>,
    ) -> Arc<MajorantGrid> {
        let read = self.grids.read().unwrap_or_else(|e| e.into_inner());
        if let Some((_, _, _, g)) = read
            .iter()
            .find(|(l, h, m, _)| *l == lo && *h == hi && *m == to_world)
        {
            return g.clone();
        }
        drop(read);
        let res = self.res;
        let extent = hi - lo;
        let cells = Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32);
        let grid = Arc::new(MajorantGrid::from_cell_bounds(res, |c| {
            let c = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32);
            // The cell's box, widened by a few ulps: the interior maps a world point to the
            // unit cube and back, and the rounded point may land just outside the cell.
            let (a, b) = (lo + extent * (c / cells), lo + extent * ((c + 1.0) / cells));
            let pad = (a.abs().max(b.abs()) + extent.abs()) * (8.0 * f32::EPSILON);
            let (a, b) = match to_world {
                None => (a - pad, b + pad),
                Some(m) => {
                    // The padded cell's corners in the world, their box padded again for
                    // the rounding of the mapping.
                    let (a, b) = (a - pad, b + pad);
                    let (mut wa, mut wb) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
                    for k in 0..8 {
                        let corner = Vec3::select(
                            glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0),
                            b,
                            a,
                        );
                        let w = m.transform_point3(corner);
                        (wa, wb) = (wa.min(w), wb.max(w));
                    }
                    let pad = (wa.abs().max(wb.abs()) + (wb - wa)) * (8.0 * f32::EPSILON);
                    (wa - pad, wb + pad)
                }
            };
            let (l, h) = pattern::bounds(&self.graph, a, b);
            let (l, h) = self.span(l, h);
            (l.max(0.0), h)
        }));
        let mut write = self.grids.write().unwrap_or_else(|e| e.into_inner());
        write.push((lo, hi, to_world, grid.clone()));
        grid
    }
}

/// A coefficient field as one integrator call evaluates it: a density grid over the unit
/// cube, or a pattern of the world point of object point `lo + uvw (hi - lo)` (the same
/// point without a transform) evaluated one point at a time
/// (the trackers ask for one point per tentative collision), with its scratch columns and an
/// evaluation count.
pub(super) enum Field<'a> {
    /// A grid lookup.
    Grid(&'a DensityGrid),
    /// A per-channel grid lookup (a 3-channel density).
    Channels(&'a DensityChannels),
    /// A pattern (`per_channel`: a colour density, one per channel).
    Pattern {
        graph: &'a PatternGraph,
        per_channel: bool,
        lo: Vec3,
        extent: Vec3,
        to_world: Option<Affine3A>,
        scratch: RefCell<Vec<Rgb>>,
        evals: Cell<u64>,
    },
}

impl<'a> Field<'a> {
    /// The pattern `graph` over the object box `[lo, hi]`, whose object space maps to the
    /// world by `to_world` (`None`: the identity).
    pub(super) fn pattern(
        graph: &'a PatternGraph,
        per_channel: bool,
        lo: Vec3,
        hi: Vec3,
        to_world: Option<Affine3A>,
    ) -> Self {
        Field::Pattern {
            graph,
            per_channel,
            lo,
            extent: hi - lo,
            to_world,
            scratch: RefCell::new(vec![Rgb::BLACK; graph.scratch_len(1)]),
            evals: Cell::new(0),
        }
    }

    /// The value at unit-cube point `uvw` (a grid's: grey; per-channel grids': each
    /// channel's density, before the scale).
    #[inline]
    pub(super) fn colour(&self, uvw: Vec3) -> Rgb {
        match self {
            Field::Grid(g) => Rgb::splat(g.lookup(uvw)),
            Field::Channels(g) => g.lookup(uvw),
            Field::Pattern {
                graph,
                lo,
                extent,
                to_world,
                scratch,
                evals,
                ..
            } => {
                evals.set(evals.get() + 1);
                let mut p = *lo + uvw * *extent;
                if let Some(m) = to_world {
                    p = m.transform_point3(p);
                }
                let mut out = [Rgb::BLACK];
                let mut scratch = scratch.borrow_mut();
                pattern::eval_with(graph, &[p], &[0.0], &[0.0], &mut out, &mut scratch);
                // Bounded below by 0 at load time up to rounding; a density is never negative.
                out[0].map(|v| v.max(0.0))
            }
        }
    }

    /// The grey value at `uvw` (a density: the first channel of a grey graph).
    #[inline]
    pub(super) fn grey(&self, uvw: Vec3) -> f32 {
        match self {
            Field::Grid(g) => g.lookup(uvw),
            // The largest channel (not read by the per-channel trackers, which take colour).
            Field::Channels(g) => g.lookup(uvw).max_channel(),
            Field::Pattern {
                per_channel: true, ..
            } => self.colour(uvw).max_channel(),
            Field::Pattern { .. } => self.colour(uvw).r,
        }
    }

    /// Pattern evaluations so far (0 for a grid).
    pub(super) fn evals(&self) -> u64 {
        match self {
            Field::Grid(_) | Field::Channels(_) => 0,
            Field::Pattern { evals, .. } => evals.get(),
        }
    }
}
