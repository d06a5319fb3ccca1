//! Tables over roughness, for microfacet lobes whose roughness varies per shading point (a
//! pattern on `alpha`, `alpha_u` or `alpha_v`).
//!
//! A lobe with one roughness integrates its energy-compensation table once
//! ([`crate::energy_compensation::AlbedoTable`]); with a roughness pattern the table must
//! follow the roughness at each point. Integrating one per point would cost a millisecond
//! or two each, so [`RoughnessGrid`] holds tables at roughnesses on a regular grid over the
//! interval the pattern's values lie in (its interval bounds, as the scene loader computes
//! them) and interpolates them linearly per point: in `ln alpha` for an isotropic lobe, or
//! bilinearly in `(ln alpha_u, ln alpha_v)` for an anisotropic one. The grid is uniform in
//! `ln alpha` because the albedo near grazing changes fastest where the roughness is
//! comparable to the cosine (`alpha tan theta ~ 1` in Smith's `Lambda`), i.e. over a
//! fixed ratio of roughnesses rather than a fixed difference: a grid uniform in `alpha`
//! over `[0.01, 1]` with 24 points errs by 0.037 at `alpha ~ 0.03`, one uniform in
//! `ln alpha` by 0.0055, and with [`POINTS_1D`] points by 0.0041 (GGX) and 0.0052 (Beckmann), the
//! worst entry at a cell's geometric midpoint over `[0.01, 1]`: a furnace is off by as much (this module's tests).
//!
//! Interpolating the tables entry by entry keeps each table's own consistency: the average
//! `E_avg` of an interpolated [`AlbedoTable`] is the same interpolation of the averages,
//! because the average is linear in the entries.

use crate::energy_compensation::{AlbedoTable, MU_POINTS};

/// Grid points along a roughness axis when only one roughness varies (isotropic `alpha`, or
/// one of `alpha_u`, `alpha_v`).
pub const POINTS_1D: usize = 32;

/// Grid points along each axis when both `alpha_u` and `alpha_v` vary (each grid point is
/// an anisotropic table, four azimuths, so the grid is kept coarser).
pub const POINTS_2D: usize = 10;

/// A table that can be blended linearly with another of the same shape.
pub trait Lerp: Sized {
    /// `self (1 - t) + other t`, entry by entry.
    fn lerp(&self, other: &Self, t: f32) -> Self;
}

impl Lerp for AlbedoTable {
    fn lerp(&self, other: &Self, t: f32) -> Self {
        let mut e = [0.0; MU_POINTS];
        for (k, e) in e.iter_mut().enumerate() {
            *e = self.e[k] * (1.0 - t) + other.e[k] * t;
        }
        AlbedoTable {
            e,
            e_avg: self.e_avg * (1.0 - t) + other.e_avg * t,
        }
    }
}

impl<T: Lerp, const N: usize> Lerp for [T; N] {
    fn lerp(&self, other: &Self, t: f32) -> Self {
        std::array::from_fn(|k| self[k].lerp(&other[k], t))
    }
}

/// A grid of roughnesses over `[lo, hi]`, `0 < lo <= hi`, uniform in `ln alpha` (one
/// point when `lo == hi`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughnessAxis {
    /// The smallest roughness.
    pub lo: f32,
    /// The largest roughness.
    pub hi: f32,
    /// Grid points, `>= 1`.
    pub points: usize,
}

impl RoughnessAxis {
    /// `points` roughnesses spread evenly in `ln alpha` over `[lo, hi]` (`lo > 0`); one
    /// point when the interval is empty.
    pub fn new(lo: f32, hi: f32, points: usize) -> Self {
        let points = if hi > lo { points.max(2) } else { 1 };
        RoughnessAxis { lo, hi, points }
    }

    /// The roughness at grid point `i`.
    pub fn at(&self, i: usize) -> f32 {
        if i == 0 {
            return self.lo;
        }
        if i + 1 >= self.points {
            return self.hi;
        }
        let t = i as f32 / (self.points - 1) as f32;
        (self.lo.ln() + (self.hi.ln() - self.lo.ln()) * t).exp()
    }

    /// The grid cell holding `alpha` (clamped to the interval) and the position in it.
    #[inline]
    fn cell(&self, alpha: f32) -> (usize, f32) {
        if self.points == 1 {
            return (0, 0.0);
        }
        let x = (alpha.max(self.lo).ln() - self.lo.ln()) / (self.hi.ln() - self.lo.ln());
        let x = x.clamp(0.0, 1.0);
        let x = x * (self.points - 1) as f32;
        let i = (x as usize).min(self.points - 2);
        (i, x - i as f32)
    }
}

/// Tables at the roughnesses of a grid, interpolated per shading point.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughnessGrid<T> {
    /// The `alpha_u` axis (the only one of an isotropic grid).
    u: RoughnessAxis,
    /// The `alpha_v` axis; `None` when the lobe is isotropic (`alpha_v = alpha_u`).
    v: Option<RoughnessAxis>,
    /// `tables[j * u.points + i]` at `(u.at(i), v.at(j))`.
    tables: Vec<T>,
}

impl<T: Lerp + Clone> RoughnessGrid<T> {
    /// The tables `table(alpha_u, alpha_v)` at every grid point: along `u` with
    /// `alpha_v = alpha_u` when `v` is `None` (isotropic), else over the product grid.
    pub fn new(u: RoughnessAxis, v: Option<RoughnessAxis>, table: impl Fn(f32, f32) -> T) -> Self {
        let rows = v.map_or(1, |v| v.points);
        let mut tables = Vec::with_capacity(u.points * rows);
        for j in 0..rows {
            for i in 0..u.points {
                let au = u.at(i);
                tables.push(table(au, v.map_or(au, |v| v.at(j))));
            }
        }
        RoughnessGrid { u, v, tables }
    }

    /// The number of tables the grid holds.
    pub fn len(&self) -> usize {
        self.tables.len()
    }

    /// True when the grid holds no table (never: an axis has at least one point).
    pub fn is_empty(&self) -> bool {
        self.tables.is_empty()
    }

    /// The table at `(alpha_u, alpha_v)` (`alpha_v` ignored by an isotropic grid), by linear
    /// (bilinear) interpolation between the neighbouring grid points; roughnesses outside
    /// the grid are clamped to it.
    pub fn at(&self, alpha_u: f32, alpha_v: f32) -> T {
        let (i, s) = self.u.cell(alpha_u);
        let along_u = |j: usize| {
            let row = j * self.u.points;
            if self.u.points == 1 {
                self.tables[row].clone()
            } else {
                self.tables[row + i].lerp(&self.tables[row + i + 1], s)
            }
        };
        match self.v {
            Some(v) if v.points > 1 => {
                let (j, t) = v.cell(alpha_v);
                along_u(j).lerp(&along_u(j + 1), t)
            }
            _ => along_u(0),
        }
    }
}

#[cfg(test)]
mod tests;
