//! Volume emitters as lights: next-event estimation towards emissive media.
//!
//! A [`VolumeEmitter`] is plain data made from an emissive interior: the medium's cells (an
//! axis-aligned box cut into `res` cells, the majorant grid's), an emission bound
//! `j_max(cell)` per cell, a [`Distribution1D`] over the cells in proportion to their power
//! `j_max * V(cell)` (channels averaged), the tracking bound `majorant(cell)` the medium's
//! free flights use there, and the emission field `j(x)` ([`EmissionField`]: a grid placed
//! in the box, or a pattern graph of the world position, times a colour), clipped to the
//! shape's support (the whole box, or the ball a sphere encloses).
//!
//! Sampling picks a cell by power and a uniform point in it: the density in **volume
//! measure** is `p_V(x) = P(cell(x)) / V(cell)` (times the light's selection probability in
//! a [`LightSet`](crate::lights::LightSet)). A light sample at `x` seen from `p`, at distance
//! `s` along `w`, estimates the in-scattered emission `int int f T j ds dw` with `dV = s^2 ds
//! dw` (Novák et al. 2018, "Monte Carlo methods for volumetric light transport simulation",
//! sec. on emission: the emitted radiance is `j` per unit length, so a point of a volume
//! emitter contributes `f T j / (p_V s^2)`).
//!
//! # MIS against the collision estimator
//! The medium's free flights gather `j(x) / majorant(x)` at every tentative collision (the
//! collision estimator): its expectation along a direction `w` is `int T j ds`, so as a
//! technique over `(w, s)` it has the density `pdf_dir(w) * majorant(x)` (tentative
//! collisions happen at rate `majorant` per unit length, the survival factor `exp(-int
//! majorant)` cancelling against the `T / T_majorant` of the estimator) and, in volume
//! measure, `p_U(x) = pdf_dir(w) * majorant(x) / s^2`. Both techniques estimate the same
//! integral, so with weights `w_U + w_V = 1` at every `x` the sum is unbiased (Veach 1997,
//! sec. 9.2, eq. 9.3); the power heuristic on `p_U` and `p_V` (eq. 9.13) is one such pair,
//! and any deterministic `majorant(x)` both sides agree on keeps it a partition of unity
//! (only the variance depends on how well `p_U` matches the tracker's true rate).
//!
//! [`LightSet`](crate::lights::LightSet) reports a volume light sample with `radiance =
//! j(x) / majorant(x)` and `pdf = p_V(x) s^2 / majorant(x)`: the contribution `f * radiance *
//! w / pdf` is `f j w / (p_V s^2)`, and the power heuristic of `pdf` against the Bxdf pdf
//! `pdf_dir` is `p_V^2 / (p_V^2 + p_U^2)`, the `w_V` above, without a special case in the
//! direct-lighting system.

use crate::distribution::{Distribution1D, ONE_MINUS_EPSILON};
use crate::grid::DensityGrid;
use crate::pattern::PatternGraph;
use glam::Vec3;
use risotto_components::Rgb;
use std::sync::Arc;

/// Where inside its box a volume emitter emits (the shape that encloses the medium).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EmitterSupport {
    /// The whole box (a box-shaped boundary).
    Box,
    /// The ball of `radius` around `center` (a sphere's interior).
    Ball {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
    },
}

/// What a [`VolumeEmitter`]'s emission coefficient `j(x)` is made of.
#[derive(Clone, Debug)]
pub enum EmissionField {
    /// `j(x) = scale * grid(uvw)`, `uvw` the point's coordinates in the box's unit cube.
    Grid {
        /// The grid (placed in the box).
        grid: Arc<DensityGrid>,
        /// Per channel, >= 0.
        scale: Rgb,
    },
    /// `j(x) = scale * graph(x)` per channel, the graph a pattern of the world position
    /// (values >= 0; `u = v = 0`: medium patterns read `P` only).
    Pattern {
        /// The graph.
        graph: Arc<PatternGraph>,
        /// Per channel, >= 0.
        scale: Rgb,
    },
}

/// Scratch colours kept on the stack for a one-point pattern evaluation (graphs of more
/// nodes use the heap).
const STACK_SCRATCH: usize = 32;

impl EmissionField {
    /// `j` at world point `x`, `uvw` its coordinates in the emitter's box.
    #[inline]
    fn at(&self, x: Vec3, uvw: Vec3) -> Rgb {
        match self {
            EmissionField::Grid { grid, scale } => *scale * grid.lookup(uvw),
            EmissionField::Pattern { graph, scale } => {
                let need = graph.scratch_len(1);
                let mut stack = [Rgb::BLACK; STACK_SCRATCH];
                let mut heap = Vec::new();
                let scratch: &mut [Rgb] = if need <= STACK_SCRATCH {
                    &mut stack[..need]
                } else {
                    heap.resize(need, Rgb::BLACK);
                    &mut heap
                };
                let mut out = [Rgb::BLACK];
                crate::pattern::eval_with(graph, &[x], &[0.0], &[0.0], &mut out, scratch);
                // Bounded below by 0 at load time up to rounding.
                *scale * out[0].map(|v| v.max(0.0))
            }
        }
    }
}

/// Why a [`VolumeEmitter`] could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum VolumeEmitterError {
    /// The cell table is not `res[0] * res[1] * res[2]` long (or `res` has a zero).
    #[error("volume emitter: {got} cells for a resolution of {res:?}")]
    Cells {
        /// The resolution.
        res: [usize; 3],
        /// The table lengths.
        got: usize,
    },
    /// The box has no volume (or is not finite).
    #[error("volume emitter: the box {lo:?}..{hi:?} has no volume")]
    Box {
        /// Lower corner.
        lo: Vec3,
        /// Upper corner.
        hi: Vec3,
    },
    /// No cell has a positive, finite power.
    #[error("volume emitter: no cell emits")]
    Dark,
}

/// An emissive medium as a light (see the [module docs](self)).
#[derive(Clone, Debug)]
pub struct VolumeEmitter {
    lo: Vec3,
    extent: Vec3,
    res: [usize; 3],
    cell_size: Vec3,
    cell_volume: f32,
    cells: Distribution1D,
    majorant: Vec<f32>,
    field: EmissionField,
    support: EmitterSupport,
    power: f32,
}

/// Smallest tracking bound the MIS weights use (a cell bound of 0 would make the reported
/// radiance `j / majorant` infinite; such cells have no tentative collisions, so any small
/// positive value gives them the weight `w_V = 1` they need).
const MIN_MAJORANT: f32 = 1e-12;

impl VolumeEmitter {
    /// An emitter over the box `lo..hi` cut into `res` cells (x fastest, then y, then z),
    /// `j_max[c]` bounding the emission in cell `c` and `majorant[c]` the medium's tracking
    /// bound there (per world unit); the emission is `field`'s ([`EmissionField`]), zero
    /// outside `support`.
    pub fn new(
        (lo, hi): (Vec3, Vec3),
        res: [usize; 3],
        j_max: &[Rgb],
        majorant: Vec<f32>,
        field: EmissionField,
        support: EmitterSupport,
    ) -> Result<Self, VolumeEmitterError> {
        let n = res.iter().try_fold(1usize, |a, &r| a.checked_mul(r));
        if res.contains(&0) || n != Some(j_max.len()) || majorant.len() != j_max.len() {
            return Err(VolumeEmitterError::Cells {
                res,
                got: j_max.len().min(majorant.len()),
            });
        }
        let extent = hi - lo;
        let cell_size = extent / Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32);
        let cell_volume = cell_size.x * cell_size.y * cell_size.z;
        if !(cell_volume > 0.0 && cell_volume.is_finite() && lo.is_finite()) {
            return Err(VolumeEmitterError::Box { lo, hi });
        }
        let power: Vec<f32> = j_max.iter().map(|j| j.average() * cell_volume).collect();
        let total: f32 = power.iter().filter(|p| p.is_finite() && **p > 0.0).sum();
        if !(total > 0.0 && total.is_finite()) {
            return Err(VolumeEmitterError::Dark);
        }
        Ok(VolumeEmitter {
            lo,
            extent,
            res,
            cell_size,
            cell_volume,
            cells: Distribution1D::new(&power),
            majorant,
            field,
            support,
            power: total,
        })
    }

    /// The emitter's power estimate for light selection: `sum j_max * V` (channels averaged;
    /// the radiant power is `4 pi` times this, a factor every light kind's estimate would
    /// share only approximately, so it is left out as for the other bounds).
    pub fn power(&self) -> f32 {
        self.power
    }

    /// Number of cells.
    pub fn num_cells(&self) -> usize {
        self.majorant.len()
    }

    /// The box `(lo, hi)`.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (self.lo, self.lo + self.extent)
    }

    /// The cell of world point `x`, `None` outside the box.
    #[inline]
    pub fn cell_of(&self, x: Vec3) -> Option<usize> {
        let uvw = (x - self.lo) / self.extent;
        if !(uvw.cmpge(Vec3::ZERO).all() && uvw.cmple(Vec3::ONE).all()) {
            return None;
        }
        let c = |a: usize| ((uvw[a] * self.res[a] as f32) as usize).min(self.res[a] - 1);
        Some(c(0) + self.res[0] * (c(1) + self.res[1] * c(2)))
    }

    /// The sampling density at `x` in volume measure, `P(cell(x)) / V(cell)` (without the
    /// light's selection probability); 0 outside the box.
    #[inline]
    pub fn pdf(&self, x: Vec3) -> f32 {
        self.cell_of(x)
            .map_or(0.0, |c| self.cells.pmf(c) / self.cell_volume)
    }

    /// The tracking bound the MIS weights use at `x` (the medium's in `x`'s cell, at least
    /// a tiny positive value; see [`VolumeEmitter::new`]).
    #[inline]
    pub fn mis_majorant(&self, x: Vec3) -> f32 {
        self.cell_of(x)
            .map_or(MIN_MAJORANT, |c| self.majorant[c].max(MIN_MAJORANT))
    }

    /// The emission coefficient `j(x)` (0 outside the box or the support).
    #[inline]
    pub fn emission(&self, x: Vec3) -> Rgb {
        let uvw = (x - self.lo) / self.extent;
        let inside_box = uvw.cmpge(Vec3::ZERO).all() && uvw.cmple(Vec3::ONE).all();
        let inside = inside_box
            && match self.support {
                EmitterSupport::Box => true,
                EmitterSupport::Ball { center, radius } => {
                    (x - center).length_squared() <= radius * radius
                }
            };
        if inside {
            self.field.at(x, uvw)
        } else {
            Rgb::BLACK
        }
    }

    /// A point by power: the cell from `u_cell`, the position in it from `u` (x and y) and
    /// from `u_cell`'s position within the cell's interval of the CDF (z: a uniform variable
    /// independent of the cell chosen, so the four dimensions of a light sample suffice).
    /// Returns the point and its density in volume measure (as [`VolumeEmitter::pdf`], the
    /// sampled cell's); `None` if the cell has probability 0.
    pub fn sample(&self, u: [f32; 2], u_cell: f32) -> Option<(Vec3, f32)> {
        let (xc, _, c) = self.cells.sample_continuous(u_cell);
        let pmf = self.cells.pmf(c);
        if pmf.is_nan() || pmf <= 0.0 {
            return None;
        }
        let n = self.num_cells();
        let z = (xc * n as f32 - c as f32).clamp(0.0, ONE_MINUS_EPSILON);
        let [nx, ny, _] = self.res;
        let cell = Vec3::new(
            (c % nx) as f32,
            ((c / nx) % ny) as f32,
            (c / (nx * ny)) as f32,
        );
        let u = Vec3::new(u[0], u[1], z).clamp(Vec3::ZERO, Vec3::splat(ONE_MINUS_EPSILON));
        let x = self.lo + (cell + u) * self.cell_size;
        Some((x, pmf / self.cell_volume))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A 4 x 2 x 3 emitter over `[-1, 1] x [0, 1] x [0, 3]` with cell powers 0..23 (cell 0
    /// dark) and a linear field.
    pub(crate) fn emitter() -> VolumeEmitter {
        let res = [4, 2, 3];
        let n = 24;
        let j_max: Vec<Rgb> = (0..n).map(|c| Rgb::splat(c as f32)).collect();
        let field = DensityGrid::constant([2, 2, 2], 1.0).unwrap();
        VolumeEmitter::new(
            (Vec3::new(-1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 3.0)),
            res,
            &j_max,
            vec![2.0; n],
            EmissionField::Grid {
                grid: Arc::new(field),
                scale: Rgb::splat(1.0),
            },
            EmitterSupport::Box,
        )
        .unwrap()
    }

    /// A Halton-like low-discrepancy-free stream: a small xorshift, enough for histograms.
    pub(crate) fn rng(seed: u64) -> impl FnMut() -> f32 {
        let mut s = seed.max(1);
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    #[test]
    fn sampled_points_follow_p_v_chi_square() {
        // Histogram over the cells and, within each cell, over its two halves along each
        // axis: 24 * 8 bins with expected counts N * P(cell) / 8.
        let e = emitter();
        let mut r = rng(7);
        let n = 200_000usize;
        let bins = 24 * 8;
        let mut count = vec![0u32; bins];
        let (lo, _) = e.bounds();
        for _ in 0..n {
            let (x, pdf) = e.sample([r(), r()], r()).unwrap();
            let c = e.cell_of(x).unwrap();
            assert!(
                (pdf - e.pdf(x)).abs() <= 1e-6 * pdf,
                "pdf of the sampled cell"
            );
            let f = (x - lo) / e.cell_size
                - Vec3::new((c % 4) as f32, ((c / 4) % 2) as f32, (c / 8) as f32);
            let o = (f.x >= 0.5) as usize + 2 * (f.y >= 0.5) as usize + 4 * (f.z >= 0.5) as usize;
            count[c * 8 + o] += 1;
        }
        let total: f32 = (0..24).map(|c| c as f32).sum();
        let mut chi2 = 0.0f64;
        let mut dof = 0;
        for (b, &k) in count.iter().enumerate() {
            let expected = n as f64 * (b / 8) as f64 / total as f64 / 8.0;
            if expected == 0.0 {
                assert_eq!(k, 0, "bin {b} of a dark cell was sampled");
                continue;
            }
            chi2 += (k as f64 - expected).powi(2) / expected;
            dof += 1;
        }
        // 184 degrees of freedom (less one): mean 183, sd ~19; 5 sd is a false alarm in
        // about one run in a million.
        let dof = (dof - 1) as f64;
        assert!(
            chi2 < dof + 5.0 * (2.0 * dof).sqrt(),
            "chi2 {chi2} for {dof} dof"
        );
    }

    #[test]
    fn p_v_integrates_to_one_over_the_box() {
        let e = emitter();
        let (lo, hi) = e.bounds();
        // Midpoint rule on a grid that refines every cell (8 x 4 x 6 points per cell).
        let m = [32usize, 8, 18];
        let step = (hi - lo) / Vec3::new(m[0] as f32, m[1] as f32, m[2] as f32);
        let dv = (step.x * step.y * step.z) as f64;
        let mut sum = 0.0f64;
        for k in 0..m[2] {
            for j in 0..m[1] {
                for i in 0..m[0] {
                    let x = lo + (Vec3::new(i as f32, j as f32, k as f32) + 0.5) * step;
                    sum += e.pdf(x) as f64 * dv;
                }
            }
        }
        assert!((sum - 1.0).abs() < 1e-5, "integral of p_V = {sum}");
        assert_eq!(e.pdf(hi + Vec3::ONE), 0.0);
    }

    #[test]
    fn bad_tables_are_errors_not_panics() {
        let f = Arc::new(DensityGrid::constant([1, 1, 1], 1.0).unwrap());
        let b = (Vec3::ZERO, Vec3::ONE);
        let new = |res, j: &[Rgb], maj: Vec<f32>, b| {
            let field = EmissionField::Grid {
                grid: f.clone(),
                scale: Rgb::WHITE,
            };
            VolumeEmitter::new(b, res, j, maj, field, EmitterSupport::Box)
        };
        assert!(new([2, 1, 1], &[Rgb::WHITE], vec![1.0], b).is_err());
        assert!(new([0, 1, 1], &[], vec![], b).is_err());
        assert!(new([1, 1, 1], &[Rgb::BLACK], vec![1.0], b).is_err());
        let flat = (Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0));
        assert!(new([1, 1, 1], &[Rgb::WHITE], vec![1.0], flat).is_err());
        assert!(new([usize::MAX, 2, 1], &[Rgb::WHITE], vec![1.0], b).is_err());
    }

    #[test]
    fn a_ball_support_emits_inside_only() {
        let f = Arc::new(DensityGrid::constant([1, 1, 1], 1.0).unwrap());
        let ball = EmitterSupport::Ball {
            center: Vec3::ZERO,
            radius: 1.0,
        };
        let b = (Vec3::splat(-1.0), Vec3::splat(1.0));
        let field = EmissionField::Grid {
            grid: f,
            scale: Rgb::WHITE,
        };
        let e = VolumeEmitter::new(b, [1, 1, 1], &[Rgb::WHITE], vec![1.0], field, ball).unwrap();
        assert_eq!(e.emission(Vec3::splat(0.1)), Rgb::WHITE);
        assert_eq!(e.emission(Vec3::splat(0.9)), Rgb::BLACK);
    }

    /// `j(x) = (2, 1, 0.5) * clamp(x.y, 0, 1)` over the box `[-1, 1] x [0, 2] x [-1, 1]` in
    /// two cells along `y`, both with the bound `(2, 1, 0.5)` (so sampled equally often
    /// although the lower one emits half as much): `int j dV = (12, 6, 3)`.
    pub(crate) fn gradient_emitter() -> VolumeEmitter {
        use crate::pattern::{Axis, Node};
        let graph = PatternGraph::new(vec![Node::Gradient {
            axis: Axis::Y,
            from: 0.0,
            to: 1.0,
            a: Rgb::BLACK,
            b: Rgb::WHITE,
        }])
        .unwrap();
        let field = EmissionField::Pattern {
            graph: Arc::new(graph),
            scale: Rgb::new(2.0, 1.0, 0.5),
        };
        let b = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 2.0, 1.0));
        let j_max = [Rgb::new(2.0, 1.0, 0.5); 2];
        VolumeEmitter::new(
            b,
            [1, 2, 1],
            &j_max,
            vec![1.0; 2],
            field,
            EmitterSupport::Box,
        )
        .unwrap()
    }

    #[test]
    fn a_pattern_field_emits_the_pattern_at_world_points_times_its_scale() {
        // The graph sees world x (not the box's unit cube, where uvw.y = x.y / 2).
        let e = gradient_emitter();
        let j = e.emission(Vec3::new(0.3, 0.25, -0.2));
        assert_eq!(j, Rgb::new(0.5, 0.25, 0.125));
        assert_eq!(
            e.emission(Vec3::new(0.0, 1.5, 0.0)),
            Rgb::new(2.0, 1.0, 0.5)
        );
        // Outside the box: nothing.
        assert_eq!(e.emission(Vec3::new(0.0, 2.5, 0.0)), Rgb::BLACK);
    }
}
