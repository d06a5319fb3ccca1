//! Pattern coefficients of a heterogeneous medium: a pattern graph of the world position `P`
//! as the density or the emission, its majorant grids from the graph's interval bounds, and
//! its evaluation one point at a time along a ray.

use glam::Vec3;
use risotto_components::Rgb;
use risotto_systems::grid::{DensityGrid, MajorantGrid};
use risotto_systems::pattern::{self, PatternGraph};
use std::cell::{Cell, RefCell};
use std::sync::{Arc, RwLock};

/// A medium coefficient given by a pattern graph of the world position `P` (the same `P`
/// surface patterns see; `u`, `v` are not defined inside a medium, and graphs that read them
/// are refused when the scene is read). Its majorant grid is made per world box (the
/// shape's bounds, known only once the scene is compiled, and one material may fill several
/// shapes), on first use, and kept.
#[derive(Debug)]
pub struct PatternField {
    /// The graph (shared with the medium's volume emitter).
    pub graph: Arc<PatternGraph>,
    /// Majorant cells per axis.
    pub res: [usize; 3],
    /// Majorant grids made so far, by world box.
    grids: RwLock<Vec<(Vec3, Vec3, Arc<MajorantGrid>)>>,
}

impl Clone for PatternField {
    fn clone(&self) -> Self {
        PatternField::new((*self.graph).clone(), self.res)
    }
}

impl PartialEq for PatternField {
    fn eq(&self, other: &Self) -> bool {
        self.graph == other.graph && self.res == other.res
    }
}

impl PatternField {
    /// The field of `graph` with majorant grids of `res` cells per axis (each at least 1).
    pub fn new(graph: PatternGraph, res: [usize; 3]) -> Self {
        PatternField {
            graph: Arc::new(graph),
            res: res.map(|r| r.max(1)),
            grids: RwLock::new(Vec::new()),
        }
    }

    /// The field's bounds over all of space: `(lowest channel, highest channel)`.
    pub fn global_bounds(&self) -> (f32, f32) {
        let (lo, hi) = pattern::bounds(&self.graph, Vec3::NEG_INFINITY, Vec3::INFINITY);
        (lo.min_channel(), hi.max_channel())
    }

    /// The majorant grid of the field over the world box `[lo, hi]` (the grid's unit cube
    /// mapped onto the box, as the density grid is placed): cell `c` holds the graph's
    /// interval bounds ([`pattern::bounds`]) over the cell's world box, the lowest channel's
    /// low end (at least 0) and the highest channel's high end.
    pub fn majorants(&self, lo: Vec3, hi: Vec3) -> Arc<MajorantGrid> {
        let read = self.grids.read().unwrap_or_else(|e| e.into_inner());
        if let Some((_, _, g)) = read.iter().find(|(l, h, _)| *l == lo && *h == hi) {
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
            let (l, h) = pattern::bounds(&self.graph, a - pad, b + pad);
            (l.min_channel().max(0.0), h.max_channel())
        }));
        let mut write = self.grids.write().unwrap_or_else(|e| e.into_inner());
        write.push((lo, hi, grid.clone()));
        grid
    }
}

/// A coefficient field as one integrator call evaluates it: a density grid over the unit
/// cube, or a pattern of the world point `lo + uvw (hi - lo)` evaluated one point at a time
/// (the trackers ask for one point per tentative collision), with its scratch columns and an
/// evaluation count.
pub(super) enum Field<'a> {
    /// A grid lookup.
    Grid(&'a DensityGrid),
    /// A pattern.
    Pattern {
        graph: &'a PatternGraph,
        lo: Vec3,
        extent: Vec3,
        scratch: RefCell<Vec<Rgb>>,
        evals: Cell<u64>,
    },
}

impl<'a> Field<'a> {
    /// The pattern `graph` over the world box `[lo, hi]`.
    pub(super) fn pattern(graph: &'a PatternGraph, lo: Vec3, hi: Vec3) -> Self {
        Field::Pattern {
            graph,
            lo,
            extent: hi - lo,
            scratch: RefCell::new(vec![Rgb::BLACK; graph.scratch_len(1)]),
            evals: Cell::new(0),
        }
    }

    /// The value at unit-cube point `uvw` (a grid's: grey).
    #[inline]
    pub(super) fn colour(&self, uvw: Vec3) -> Rgb {
        match self {
            Field::Grid(g) => Rgb::splat(g.lookup(uvw)),
            Field::Pattern {
                graph,
                lo,
                extent,
                scratch,
                evals,
            } => {
                evals.set(evals.get() + 1);
                let p = *lo + uvw * *extent;
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
            Field::Pattern { .. } => self.colour(uvw).r,
        }
    }

    /// Pattern evaluations so far (0 for a grid).
    pub(super) fn evals(&self) -> u64 {
        match self {
            Field::Grid(_) => 0,
            Field::Pattern { evals, .. } => evals.get(),
        }
    }
}
