//! Bounded work in dense majorant segments: a segment on which null-collision tracking
//! would take more than [`TRACKING_CAP`] tentative collisions in expectation
//! (`majorant x length`, the cost of delta, ratio and residual ratio tracking there) is not
//! tracked but integrated exactly, when the caller can give the exact optical depth of any
//! interval of it ([`DenseSegments`]; for a trilinear grid, [`crate::grid::GridRay`]).
//!
//! # Why, and why it stays unbiased
//! A single extreme voxel (1e9 among 0.1) gives every majorant cell its trilinear support
//! touches a bound of 1e9, while the field falls to the background over most of those
//! cells: `majorant x length` tentative collisions per crossing (about 1e9, or one per
//! float step of `t`), each a lookup. Ratio tracking's Russian roulette on a low estimate
//! (`roulette`) cannot end that walk, because where the field is far below the bound each
//! collision multiplies the estimate by `1 - sigma_t / majorant`, about 1: the estimate
//! stays high, step after step. Delta tracking of free flights is the same walk.
//!
//! Each estimator here is unchanged on the other segments and replaces the walk on a dense
//! segment by its exact counterpart, which is the limit of the tracker as the majorant
//! tightens (Novák et al. 2014 sec. 3, "regular tracking" when the optical depth is known
//! in closed form; Sutton et al. 1999):
//! - **Free flights** (delta tracking, Woodcock et al. 1965): the tentative collisions are a
//!   Poisson process of rate `majorant` and the real ones its thinning, a Poisson process of
//!   rate `sigma_t`. At the segment's start the optical depth still to go before the next
//!   tentative collision is `Exp(1)` and independent of the walk so far (memorylessness:
//!   the carried draw, `DepthToNext`); the real collision in the segment is where the exact
//!   optical depth `int_t0^t sigma_t` reaches that draw ([`DenseSegments::invert`]), and a
//!   flight that passes carries the draw minus the segment's depth, again `Exp(1)` given
//!   that it passed. The distance then has exactly delta tracking's density
//!   `sigma_t(t) exp(-int sigma_t)`, and no random number is drawn besides the carried one.
//! - **Transmittance** (ratio and residual ratio tracking): `T = prod_segments T_s`, and the
//!   product of independent unbiased estimates of the factors is unbiased; on a dense
//!   segment the factor is `exp(-tau_s)` exactly (zero variance), then one roulette decision
//!   on the running estimate as after any collision (expectation 1). Delta-tracking
//!   transmittance is the free flight's pass indicator, so it follows the free flights.
//!
//! Cost: one interval depth per dense segment (for a grid, two lookups per voxel plane the
//! segment crosses), plus a bisection for a collision inside it; never `majorant x length`.
//! Segments below the cap are tracked exactly as before (the same random numbers), so a
//! scene without dense segments renders the same image.

use super::DepthToNext;
use crate::grid::{GridRay, MajorantSegment};
use crate::medium::sample_optical_depth;

/// Expected tentative collisions (`majorant x length`) above which a segment is integrated
/// exactly instead of tracked, when the medium can ([`DenseSegments`]). About the cost of
/// a few hundred lookups; ordinary media (extinction bounds of up to thousands per unit, in
/// majorant cells a small fraction of a unit across) stay far below it.
pub const TRACKING_CAP: f32 = 1024.0;

/// The exact optical depth of the segments a tracker should not walk.
pub trait DenseSegments {
    /// Whether `seg` is integrated exactly (and counts it): `majorant x length` above
    /// [`TRACKING_CAP`], for a medium that knows its exact depth.
    fn takes(&mut self, seg: &MajorantSegment) -> bool;
    /// The optical depth of `[t0, t1]`.
    fn depth(&mut self, t0: f32, t1: f32) -> f64;
    /// Where the optical depth from `t0` reaches `target` before `t1` (`Ok(t)`), else the
    /// depth of `[t0, t1]` (`Err`).
    fn invert(&mut self, t0: f32, t1: f32, target: f64) -> Result<f32, f64>;
}

/// Tracks every segment (no exact depth): the trackers as they always were.
#[derive(Clone, Copy, Debug, Default)]
pub struct TrackAll;

impl DenseSegments for TrackAll {
    #[inline(always)]
    fn takes(&mut self, _: &MajorantSegment) -> bool {
        false
    }
    fn depth(&mut self, _: f32, _: f32) -> f64 {
        0.0
    }
    fn invert(&mut self, _: f32, _: f32, _: f64) -> Result<f32, f64> {
        Err(0.0)
    }
}

/// A medium that may know its exact depth (`None` tracks every segment).
impl<D: DenseSegments> DenseSegments for Option<D> {
    #[inline]
    fn takes(&mut self, seg: &MajorantSegment) -> bool {
        self.as_mut().is_some_and(|d| d.takes(seg))
    }
    fn depth(&mut self, t0: f32, t1: f32) -> f64 {
        self.as_mut().map_or(0.0, |d| d.depth(t0, t1))
    }
    fn invert(&mut self, t0: f32, t1: f32, target: f64) -> Result<f32, f64> {
        self.as_mut().map_or(Err(0.0), |d| d.invert(t0, t1, target))
    }
}

/// A grid's dense segments, integrated exactly along the ray ([`GridRay`]): the
/// heterogeneous medium's density grid scaled to extinction.
#[derive(Clone, Copy, Debug)]
pub struct DenseGrid<'g> {
    /// The ray through the grid (its `scale` must be the segments' density-to-extinction
    /// scale).
    pub ray: GridRay<'g>,
    /// Segments taken so far (the stats' `dense_segments`).
    pub taken: u32,
    /// Grid lookups their exact depths took (the stats' `dense_lookups`).
    pub lookups: u32,
}

impl<'g> DenseGrid<'g> {
    /// No segment taken yet.
    pub fn new(ray: GridRay<'g>) -> Self {
        DenseGrid {
            ray,
            taken: 0,
            lookups: 0,
        }
    }
}

impl DenseSegments for DenseGrid<'_> {
    #[inline]
    fn takes(&mut self, seg: &MajorantSegment) -> bool {
        let dense = seg.majorant * (seg.t1 - seg.t0) > TRACKING_CAP;
        self.taken += dense as u32;
        dense
    }
    fn depth(&mut self, t0: f32, t1: f32) -> f64 {
        self.ray.depth(t0, t1, &mut self.lookups)
    }
    fn invert(&mut self, t0: f32, t1: f32, target: f64) -> Result<f32, f64> {
        self.ray.invert(t0, t1, target, &mut self.lookups)
    }
}

/// A free flight across a dense segment (module docs): the real collision's distance, or
/// `None` with the carried draw reduced by the segment's depth.
pub(crate) fn dense_flight(
    dense: &mut impl DenseSegments,
    seg: &MajorantSegment,
    depth: &mut DepthToNext,
    rand: &mut impl FnMut() -> f32,
) -> Option<f32> {
    if depth.0.is_nan() {
        depth.0 = sample_optical_depth(rand());
    }
    match dense.invert(seg.t0, seg.t1, depth.0 as f64) {
        Ok(t) => {
            *depth = DepthToNext::NONE;
            Some(t)
        }
        Err(tau) => {
            depth.0 = (depth.0 as f64 - tau).max(0.0) as f32;
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{DensityGrid, MajorantGrid};
    use crate::sampler::SplitMix64;
    use crate::tracking::{
        delta_tracking_dense, delta_tracking_transmittance_dense, ratio_tracking_dense,
    };
    use glam::Vec3;

    /// The grid: 4^3 of 0.1 with one voxel of 1e9, scaled by 10.
    fn hot_grid(peak: f32) -> DensityGrid {
        let mut data = vec![0.1; 64];
        data[1 + 4 * (1 + 4)] = peak;
        DensityGrid::new([4, 4, 4], data).unwrap()
    }

    /// Rays that graze the hot voxel's support, where the bound is extreme and the field
    /// from moderate to huge: the exact transmittance of each, and the mean of many
    /// estimates.
    #[test]
    fn dense_estimators_are_unbiased_and_bounded_on_an_extreme_voxel() {
        let g = hot_grid(1e9);
        let m = MajorantGrid::new(&g, [16, 16, 16]);
        let scale = 10.0;
        for (o, d) in [
            // Grazing a corner of the voxel's support: a bound of 1e10 per unit, a field of
            // a few units (the trilinear weights' product about 1e-11), so a moderate
            // optical depth through extreme cells.
            (Vec3::new(0.0, 0.125 + 1e-6, 0.125 + 1e-6), Vec3::X),
            (Vec3::new(0.0, 0.125 + 2e-6, 0.125 + 3e-6), Vec3::X),
            (
                Vec3::new(0.0, 0.125 + 3e-6, 0.125 + 1e-6),
                Vec3::new(1.0, 0.0, 2e-6),
            ),
        ] {
            let segs = || m.traverse(o, d, 0.0, 1.0).map(|s| s.scaled(scale));
            let ray = GridRay {
                grid: &g,
                origin: o,
                direction: d,
                scale,
            };
            let sigma = |t: f32| scale * g.lookup(o + d * t);
            // The reference: a fine midpoint rule (not the exact depth under test).
            let steps = 400_000;
            let h = 1.0 / steps as f64;
            let tau: f64 = (0..steps)
                .map(|k| h * sigma(((k as f64 + 0.5) * h) as f32) as f64)
                .sum();
            let exact = (-tau).exp();
            assert!(exact > 0.05 && exact < 0.95, "{o} {d}: {exact}");
            let n = 20000;
            let (mut ratio, mut resid, mut delta, mut taken) = (0.0f64, 0.0f64, 0.0f64, 0u32);
            let mut rng = SplitMix64(7);
            for _ in 0..n {
                let mut dense = DenseGrid::new(ray);
                let r = ratio_tracking_dense(segs(), sigma, &mut dense, || rng.f32(), false);
                assert!(r.nulls < 4 * TRACKING_CAP as u32, "{o} {d}: {}", r.nulls);
                ratio += r.value as f64;
                taken += dense.taken;
                let mut dense = DenseGrid::new(ray);
                resid += ratio_tracking_dense(segs(), sigma, &mut dense, || rng.f32(), true).value
                    as f64;
                let mut dense = DenseGrid::new(ray);
                let t = delta_tracking_transmittance_dense(segs(), sigma, &mut dense, || rng.f32());
                delta += t.value as f64;
            }
            assert!(taken > 0, "{o} {d}: no dense segment");
            let sd = (exact * (1.0 - exact) / n as f64).sqrt().max(1e-4);
            for (name, mean) in [("ratio", ratio), ("residual", resid), ("delta", delta)] {
                let mean = mean / n as f64;
                assert!(
                    (mean - exact).abs() < 5.0 * sd,
                    "{name} {o} {d}: {mean} vs exact {exact}"
                );
            }
        }
    }

    /// Free flights across a dense cell: the collision distances' histogram against the
    /// exact distribution `1 - exp(-tau(t))` (a Kolmogorov-Smirnov bound), and the pass
    /// probability.
    #[test]
    fn dense_free_flights_follow_the_exact_distance_distribution() {
        let g = hot_grid(1e4);
        let m = MajorantGrid::new(&g, [16, 16, 16]);
        let scale = 10.0;
        let (o, d) = (Vec3::new(0.0, 0.2, 0.3), Vec3::new(1.0, 0.05, 0.02));
        let ray = GridRay {
            grid: &g,
            origin: o,
            direction: d,
            scale,
        };
        let segs = || m.traverse(o, d, 0.0, 1.0).map(|s| s.scaled(scale));
        let sigma = |t: f32| scale * g.lookup(o + d * t);
        let n = 20000;
        let mut rng = SplitMix64(3);
        let mut ts = Vec::new();
        let mut taken = 0;
        for _ in 0..n {
            let mut dense = DenseGrid::new(ray);
            let f = delta_tracking_dense(segs(), sigma, &mut dense, || rng.f32());
            taken += dense.taken;
            ts.push(if f.collided { f.t } else { f32::INFINITY });
        }
        assert!(taken > 0);
        ts.sort_by(f32::total_cmp);
        let cdf = |t: f32| 1.0 - (-ray.depth(0.0, t.min(1.0), &mut 0)).exp();
        let ks = ts
            .iter()
            .enumerate()
            .filter(|(_, t)| t.is_finite())
            .map(|(k, &t)| ((k + 1) as f64 / n as f64 - cdf(t)).abs())
            .fold(0.0, f64::max);
        assert!(ks < 1.63 / (n as f64).sqrt(), "KS distance {ks}");
    }
}
