//! Density grids for heterogeneous media: a dense voxel grid with trilinear interpolation in
//! Mitsuba 3's cell-centred clamp convention, and a coarse majorant grid (per-cell upper
//! bounds of the interpolated field) traversed with a 3D DDA.
//!
//! # Conventions
//! - A grid covers the unit cube of its volume's `u, v, w` (the shape's world-space bounds
//!   mapped to `[0, 1]^3`; `ShadingContext::with_volume_bounds` in the engine).
//! - Voxel `(ix, iy, iz)` of an `nx x ny x nz` grid holds `data[ix + nx (iy + ny iz)]` (x
//!   fastest) and sits at the **cell centre** `((ix + 0.5) / nx, (iy + 0.5) / ny,
//!   (iz + 0.5) / nz)`. Values are trilinearly interpolated between cell centres, and
//!   coordinates are clamped to the outermost cell centres (clamp-to-edge), so the field is
//!   constant within half a voxel of each face. This is Mitsuba 3's `gridvolume` with
//!   `filter_type = "trilinear"`, `wrap_mode = "clamp"`: a 2-voxel grid `[0, 1]` evaluates
//!   to 0, 0, 0.5, 1, 1 at `u` = 0, 0.25, 0.5, 0.75, 1.
//! - Values are finite and non-negative ([`DensityGrid::new`] checks).
//!
//! ```
//! use risotto_systems::grid::DensityGrid;
//! use glam::Vec3;
//! let g = DensityGrid::new([2, 1, 1], vec![0.0, 1.0]).unwrap();
//! assert_eq!(g.lookup(Vec3::new(0.5, 0.5, 0.5)), 0.5);
//! assert_eq!(g.lookup(Vec3::new(0.9, 0.0, 1.0)), 1.0); // clamped to the last centre
//! ```

use glam::Vec3;

mod channels;
mod exact_depth;
pub use channels::DensityChannels;
pub use exact_depth::GridRay;

/// A value [`DensityGrid::new`] rejects.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GridValueError {
    /// A dimension is zero, or the voxel count does not match the data.
    #[error("grid dimensions {dims:?} need {expected} values, got {got}")]
    Size {
        /// The dimensions.
        dims: [usize; 3],
        /// `nx ny nz` (saturating).
        expected: usize,
        /// Values given.
        got: usize,
    },
    /// A voxel is negative, NaN or infinite.
    #[error("voxel ({}, {}, {}) (value index {index}): {value} is {}", voxel[0], voxel[1], voxel[2], if value.is_finite() { "negative" } else { "not finite" })]
    Value {
        /// Index into the data (x fastest).
        index: usize,
        /// `(ix, iy, iz)`.
        voxel: [usize; 3],
        /// The value.
        value: f32,
    },
}

/// A dense scalar grid over the unit cube (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct DensityGrid {
    dims: [usize; 3],
    data: Vec<f32>,
    max: f32,
    mean: f64,
}

/// Independent accumulator lanes of [`scan`] and [`bounds_of`]: eight running maxima (or
/// sums) have no dependency on each other, so a pass over a large grid is not bound by
/// the latency of one chain of `max` (or f64 add) operations, and the lanes vectorise.
const LANES: usize = 8;

/// One pass over `values`: whether every value is finite and `>= 0`, the largest (at least
/// 0) and the sum in f64 (lane-wise partial sums added at the end).
fn scan(values: &[f32]) -> (bool, f32, f64) {
    let (mut valid, mut hi, mut sum) = (true, [0.0f32; LANES], [0.0f64; LANES]);
    let chunks = values.chunks_exact(LANES);
    let rest = chunks.remainder();
    for c in chunks {
        for k in 0..LANES {
            let v = c[k];
            valid &= v.is_finite() & (v >= 0.0);
            hi[k] = hi[k].max(v);
            sum[k] += v as f64;
        }
    }
    for (k, &v) in rest.iter().enumerate() {
        valid &= v.is_finite() & (v >= 0.0);
        hi[k] = hi[k].max(v);
        sum[k] += v as f64;
    }
    (
        valid,
        hi.into_iter().fold(0.0, f32::max),
        sum.into_iter().sum(),
    )
}

/// `(max, min)` of `values` (a row of a validated grid: no NaN), `(0, inf)` when empty.
#[inline]
fn bounds_of(values: &[f32], (mut hi, mut lo): (f32, f32)) -> (f32, f32) {
    let (mut his, mut los) = ([hi; LANES], [lo; LANES]);
    let chunks = values.chunks_exact(LANES);
    let rest = chunks.remainder();
    for c in chunks {
        for k in 0..LANES {
            his[k] = his[k].max(c[k]);
            los[k] = los[k].min(c[k]);
        }
    }
    for &v in rest {
        hi = hi.max(v);
        lo = lo.min(v);
    }
    (
        his.into_iter().fold(hi, f32::max),
        los.into_iter().fold(lo, f32::min),
    )
}

impl DensityGrid {
    /// A grid of `dims = [nx, ny, nz]` voxels, `data[ix + nx (iy + ny iz)]`. Every dimension
    /// must be at least 1, `data` must hold `nx ny nz` values, each finite and >= 0.
    pub fn new(dims: [usize; 3], data: Vec<f32>) -> Result<Self, GridValueError> {
        let expected = dims
            .iter()
            .try_fold(1usize, |a, &d| a.checked_mul(d))
            .unwrap_or(usize::MAX);
        if dims.contains(&0) || expected != data.len() {
            return Err(GridValueError::Size {
                dims,
                expected,
                got: data.len(),
            });
        }
        let (valid, max, sum) = scan(&data);
        if !valid {
            let index = data
                .iter()
                .position(|v| !(v.is_finite() && *v >= 0.0))
                .expect("scan found a value that is not finite and >= 0");
            return Err(GridValueError::Value {
                index,
                voxel: voxel_of(dims, index),
                value: data[index],
            });
        }
        let mean = sum / data.len() as f64;
        Ok(DensityGrid {
            dims,
            data,
            max,
            mean,
        })
    }

    /// This grid with one voxel of 0 added on every side (`[nx + 2, ny + 2, nz + 2]`): read
    /// over the same cell centres, its field is the one of a grid whose voxels beyond the
    /// edge are 0 (pbrt-v4's `SampledGrid`, OpenVDB's background) instead of the clamp.
    pub fn padded_with_zeros(&self) -> Self {
        let [nx, ny, nz] = self.dims;
        let dims = [nx + 2, ny + 2, nz + 2];
        let mut data = vec![0.0; dims[0] * dims[1] * dims[2]];
        for z in 0..nz {
            for y in 0..ny {
                let to = 1 + dims[0] * ((y + 1) + dims[1] * (z + 1));
                let from = nx * (y + ny * z);
                data[to..to + nx].copy_from_slice(&self.data[from..from + nx]);
            }
        }
        let n = data.len() as f64;
        DensityGrid {
            dims,
            data,
            max: self.max.max(0.0),
            mean: self.mean * (nx * ny * nz) as f64 / n,
        }
    }

    /// A grid of one value everywhere (`dims` voxels of `value`).
    pub fn constant(dims: [usize; 3], value: f32) -> Result<Self, GridValueError> {
        let n = dims.iter().product();
        Self::new(dims, vec![value; n])
    }

    /// `[nx, ny, nz]`.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// The voxel values, x fastest.
    pub fn data(&self) -> &[f32] {
        &self.data
    }

    /// The largest voxel value (the largest value of the interpolated field).
    pub fn max(&self) -> f32 {
        self.max
    }

    /// The mean voxel value.
    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// Voxel `(ix, iy, iz)`.
    #[inline]
    pub fn voxel(&self, ix: usize, iy: usize, iz: usize) -> f32 {
        let [nx, ny, _] = self.dims;
        self.data[ix + nx * (iy + ny * iz)]
    }

    /// The trilinearly interpolated value at `uvw` (unit-cube coordinates; any point, clamped
    /// to the outermost cell centres; NaN coordinates read voxel 0).
    #[inline]
    pub fn lookup(&self, uvw: Vec3) -> f32 {
        let (x0, x1, fx) = axis(uvw.x, self.dims[0]);
        let (y0, y1, fy) = axis(uvw.y, self.dims[1]);
        let (z0, z1, fz) = axis(uvw.z, self.dims[2]);
        let [nx, ny, _] = self.dims;
        let at = |x: usize, y: usize, z: usize| self.data[x + nx * (y + ny * z)];
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let c00 = lerp(at(x0, y0, z0), at(x1, y0, z0), fx);
        let c10 = lerp(at(x0, y1, z0), at(x1, y1, z0), fx);
        let c01 = lerp(at(x0, y0, z1), at(x1, y0, z1), fx);
        let c11 = lerp(at(x0, y1, z1), at(x1, y1, z1), fx);
        // The weights are in [0, 1], so the result is a convex combination of the voxels:
        // never above their max (which the majorant grid relies on), up to rounding, which
        // the max() with the lower corner's bound keeps non-negative.
        lerp(lerp(c00, c10, fy), lerp(c01, c11, fy), fz).max(0.0)
    }
}

/// `(index, index + 1, fraction)` of coordinate `u` on an axis of `n` cell-centred voxels.
#[inline]
fn axis(u: f32, n: usize) -> (usize, usize, f32) {
    let last = (n - 1) as f32;
    // NaN -> 0 (f32::clamp would keep NaN).
    let g = (u * n as f32 - 0.5).max(0.0).min(last);
    let i = (g as usize).min(n.saturating_sub(2));
    let f = g - i as f32;
    (i, (i + 1).min(n - 1), f)
}

/// `(ix, iy, iz)` of value index `index`.
pub fn voxel_of(dims: [usize; 3], index: usize) -> [usize; 3] {
    let [nx, ny, _] = dims;
    [index % nx, (index / nx) % ny, index / (nx * ny)]
}

/// One interval of a ray through a majorant grid: the ray parameter range `[t0, t1)` inside
/// one cell and that cell's bound.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MajorantSegment {
    /// Start (ray parameter).
    pub t0: f32,
    /// End.
    pub t1: f32,
    /// Upper bound of the field over the interval.
    pub majorant: f32,
    /// Lower bound of the field over the interval (a control for residual ratio tracking).
    pub minorant: f32,
}

impl MajorantSegment {
    /// The segment with both bounds multiplied by `scale` (>= 0): density bounds to
    /// extinction bounds.
    #[inline]
    pub fn scaled(self, scale: f32) -> MajorantSegment {
        MajorantSegment {
            majorant: self.majorant * scale,
            minorant: self.minorant * scale,
            ..self
        }
    }
}

/// A coarse grid of upper (and lower) bounds of a [`DensityGrid`]'s interpolated field over
/// the unit cube, in `res^3`-style cells (pbrt-v4's `MajorantGrid`).
///
/// Cell `(cx, cy, cz)` covers `[cx / rx, (cx + 1) / rx] x ...` of the unit cube; its bound is
/// the max (and min) over every voxel whose value can weigh in the trilinear interpolation at
/// some point of the cell (the cell's trilinear support, clamp convention included): the
/// field is a convex combination of those voxels there, so the bound holds everywhere in the
/// cell, and it is the tightest bound made of voxel values.
#[derive(Clone, Debug, PartialEq)]
pub struct MajorantGrid {
    res: [usize; 3],
    max: Vec<f32>,
    min: Vec<f32>,
}

impl MajorantGrid {
    /// The bounds of `grid` over `res` cells per axis (each at least 1; more cells than voxels
    /// only repeats bounds).
    pub fn new(grid: &DensityGrid, res: [usize; 3]) -> Self {
        let res = res.map(|r| r.max(1));
        let dims = grid.dims();
        // Per axis and cell: the voxel index range of its trilinear support.
        let support = |a: usize| -> Vec<(usize, usize)> {
            let (n, r) = (dims[a], res[a]);
            (0..r)
                .map(|c| {
                    let last = (n - 1) as f64;
                    let g0 = (c as f64 / r as f64 * n as f64 - 0.5).clamp(0.0, last);
                    let g1 = ((c + 1) as f64 / r as f64 * n as f64 - 0.5).clamp(0.0, last);
                    (g0.floor() as usize, (g1.ceil() as usize).min(n - 1))
                })
                .collect()
        };
        let (sx, sy, sz) = (support(0), support(1), support(2));
        let cells = res[0] * res[1] * res[2];
        let mut max = Vec::with_capacity(cells);
        let mut min = Vec::with_capacity(cells);
        for &(z0, z1) in &sz {
            for &(y0, y1) in &sy {
                for &(x0, x1) in &sx {
                    let mut bounds = (0.0f32, f32::INFINITY);
                    for z in z0..=z1 {
                        for y in y0..=y1 {
                            let row = dims[0] * (y + dims[1] * z);
                            bounds = bounds_of(&grid.data[row + x0..=row + x1], bounds);
                        }
                    }
                    max.push(bounds.0);
                    min.push(bounds.1);
                }
            }
        }
        MajorantGrid { res, max, min }
    }

    /// A grid of `res` cells per axis (each at least 1) whose cell `(cx, cy, cz)` has the
    /// bounds `(min, max) = cell_bounds([cx, cy, cz])`: for fields that are not a
    /// [`DensityGrid`] (a procedural pattern's interval bounds over each cell's box). NaN
    /// bounds read as unbounded (`min` 0, `max` infinite), a `min` above `max` as `max`.
    pub fn from_cell_bounds(
        res: [usize; 3],
        mut cell_bounds: impl FnMut([usize; 3]) -> (f32, f32),
    ) -> Self {
        let res = res.map(|r| r.max(1));
        let cells = res[0] * res[1] * res[2];
        let mut max = Vec::with_capacity(cells);
        let mut min = Vec::with_capacity(cells);
        for cz in 0..res[2] {
            for cy in 0..res[1] {
                for cx in 0..res[0] {
                    let (lo, hi) = cell_bounds([cx, cy, cz]);
                    let hi = if hi.is_nan() { f32::INFINITY } else { hi };
                    let lo = if lo.is_nan() { 0.0 } else { lo.min(hi) };
                    max.push(hi);
                    min.push(lo);
                }
            }
        }
        MajorantGrid { res, max, min }
    }

    /// One cell over the whole cube holding the grid's global max (Mitsuba's majorant).
    pub fn global(grid: &DensityGrid) -> Self {
        Self::new(grid, [1, 1, 1])
    }

    /// Cells per axis.
    pub fn res(&self) -> [usize; 3] {
        self.res
    }

    /// The upper bound of cell `(cx, cy, cz)`.
    pub fn max_at(&self, cx: usize, cy: usize, cz: usize) -> f32 {
        self.max[cx + self.res[0] * (cy + self.res[1] * cz)]
    }

    /// The lower bound of cell `(cx, cy, cz)`.
    pub fn min_at(&self, cx: usize, cy: usize, cz: usize) -> f32 {
        self.min[cx + self.res[0] * (cy + self.res[1] * cz)]
    }

    /// The cell containing `uvw` (clamped into the cube).
    pub fn cell_of(&self, uvw: Vec3) -> [usize; 3] {
        let c = |u: f32, r: usize| ((u.max(0.0) * r as f32) as usize).min(r - 1);
        [
            c(uvw.x, self.res[0]),
            c(uvw.y, self.res[1]),
            c(uvw.z, self.res[2]),
        ]
    }

    /// The cells the ray `origin + t dir` (unit-cube coordinates; `dir` need not be unit
    /// length: `t` is whatever parameter the caller measures, e.g. world distance) crosses
    /// for `t` in `[tmin, tmax]` (`tmax` may be infinite), clipped to the cube, in order.
    pub fn traverse(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Dda<'_> {
        let mut dda = Dda {
            grid: self,
            t: 0.0,
            tmax: -1.0,
            cell: [0; 3],
            next: [f32::INFINITY; 3],
            delta: [f32::INFINITY; 3],
            step: [1; 3],
        };
        // Slab clip against [0, 1]^3.
        let (mut t0, mut t1) = (tmin.max(0.0), tmax);
        let (o, d) = (origin.to_array(), dir.to_array());
        for a in 0..3 {
            if d[a] == 0.0 {
                if !(0.0..=1.0).contains(&o[a]) {
                    return dda;
                }
                continue;
            }
            let inv = 1.0 / d[a];
            let (mut ta, mut tb) = (-o[a] * inv, (1.0 - o[a]) * inv);
            if ta > tb {
                std::mem::swap(&mut ta, &mut tb);
            }
            t0 = t0.max(ta);
            t1 = t1.min(tb);
        }
        if t0.partial_cmp(&t1) != Some(std::cmp::Ordering::Less) {
            return dda;
        }
        dda.t = t0;
        dda.tmax = t1;
        for a in 0..3 {
            let r = self.res[a];
            let pc = (o[a] + d[a] * t0) * r as f32;
            let dc = d[a] * r as f32;
            let c = (pc.max(0.0) as usize).min(r - 1);
            dda.cell[a] = c;
            if dc > 0.0 {
                dda.delta[a] = 1.0 / dc;
                dda.next[a] = t0 + (c as f32 + 1.0 - pc) / dc;
                dda.step[a] = 1;
            } else if dc < 0.0 {
                dda.delta[a] = -1.0 / dc;
                dda.next[a] = t0 + (c as f32 - pc) / dc;
                dda.step[a] = -1;
            }
        }
        dda
    }
}

/// The iterator of [`MajorantGrid::traverse`]: a 3D DDA over the cells (Amanatides and Woo
/// 1987; pbrt-v4's `DDAMajorantIterator`).
#[derive(Clone, Debug)]
pub struct Dda<'a> {
    grid: &'a MajorantGrid,
    t: f32,
    tmax: f32,
    cell: [usize; 3],
    next: [f32; 3],
    delta: [f32; 3],
    step: [i32; 3],
}

impl Iterator for Dda<'_> {
    type Item = MajorantSegment;
    fn next(&mut self) -> Option<MajorantSegment> {
        if self.t.partial_cmp(&self.tmax) != Some(std::cmp::Ordering::Less) {
            return None;
        }
        let a = if self.next[0] < self.next[1] {
            if self.next[0] < self.next[2] {
                0
            } else {
                2
            }
        } else if self.next[1] < self.next[2] {
            1
        } else {
            2
        };
        let [cx, cy, cz] = self.cell;
        let t1 = self.next[a].min(self.tmax);
        let seg = MajorantSegment {
            t0: self.t,
            t1,
            majorant: self.grid.max_at(cx, cy, cz),
            minorant: self.grid.min_at(cx, cy, cz),
        };
        self.t = t1;
        if self.next[a] >= self.tmax {
            self.tmax = -1.0;
        } else {
            let c = self.cell[a] as i64 + self.step[a] as i64;
            if c < 0 || c >= self.grid.res[a] as i64 {
                self.tmax = -1.0;
            } else {
                self.cell[a] = c as usize;
                self.next[a] += self.delta[a];
            }
        }
        Some(seg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::SplitMix64;

    #[test]
    fn lane_wise_scans_agree_with_plain_folds() {
        // Lengths around the lane count (the remainder path) and a long one; the first bad
        // value anywhere (in a lane or in the remainder) is found.
        let mut rng = SplitMix64(9);
        for n in [1usize, 7, 8, 9, 17, 1000, 4099] {
            let values: Vec<f32> = (0..n).map(|_| rng.f32() * 5.0).collect();
            let (valid, max, sum) = scan(&values);
            assert!(valid);
            assert_eq!(max, values.iter().copied().fold(0.0, f32::max), "n = {n}");
            let plain: f64 = values.iter().map(|&v| v as f64).sum();
            assert!((sum - plain).abs() <= 1e-12 * plain.max(1.0), "n = {n}");
            let (hi, lo) = bounds_of(&values, (0.0, f32::INFINITY));
            assert_eq!(hi, values.iter().copied().fold(0.0, f32::max));
            assert_eq!(lo, values.iter().copied().fold(f32::INFINITY, f32::min));
            for bad in [-1.0, f32::NAN, f32::INFINITY] {
                for at in [0, n / 2, n - 1] {
                    let mut v = values.clone();
                    v[at] = bad;
                    assert!(!scan(&v).0, "n = {n}, {bad} at {at} not seen");
                }
            }
        }
        assert_eq!(bounds_of(&[], (0.0, f32::INFINITY)), (0.0, f32::INFINITY));
    }

    #[test]
    fn the_harness_two_voxel_check() {
        // README section e: a 2-voxel grid [0, 1] evaluates to 0, 0, 0.5, 1, 1.
        let g = DensityGrid::new([2, 1, 1], vec![0.0, 1.0]).unwrap();
        let got: Vec<f32> = [0.0, 0.25, 0.5, 0.75, 1.0]
            .iter()
            .map(|&x| g.lookup(Vec3::new(x, 0.5, 0.5)))
            .collect();
        assert_eq!(got, vec![0.0, 0.0, 0.5, 1.0, 1.0]);
        // The same along y and z, and in between: linear between the centres.
        let gy = DensityGrid::new([1, 2, 1], vec![0.0, 1.0]).unwrap();
        assert_eq!(gy.lookup(Vec3::new(0.0, 0.625, 0.0)), 0.75);
        let gz = DensityGrid::new([1, 1, 2], vec![2.0, 4.0]).unwrap();
        assert_eq!(gz.lookup(Vec3::new(0.3, 0.3, 0.375)), 2.5); // g = 0.75 - 0.5
                                                                // Outside the cube: clamped.
        assert_eq!(g.lookup(Vec3::new(-3.0, 0.5, 0.5)), 0.0);
        assert_eq!(g.lookup(Vec3::new(7.0, 0.5, 0.5)), 1.0);
    }

    #[test]
    fn trilinear_reproduces_an_affine_field_and_the_voxels() {
        // f = 1 + 2x + 3y + 4z at the cell centres is reproduced exactly between them.
        let dims = [4, 3, 5];
        let f = |p: Vec3| 1.0 + 2.0 * p.x + 3.0 * p.y + 4.0 * p.z;
        let centre = |i: usize, n: usize| (i as f32 + 0.5) / n as f32;
        let mut data = Vec::new();
        for z in 0..5 {
            for y in 0..3 {
                for x in 0..4 {
                    data.push(f(Vec3::new(centre(x, 4), centre(y, 3), centre(z, 5))));
                }
            }
        }
        let g = DensityGrid::new(dims, data).unwrap();
        assert_eq!(g.voxel(3, 1, 2), f(Vec3::new(0.875, 0.5, 0.5)));
        let mut rng = SplitMix64(5);
        for _ in 0..1000 {
            // Points between the outermost centres.
            let p = Vec3::new(
                0.125 + 0.75 * rng.f32(),
                1.0 / 6.0 + (2.0 / 3.0) * rng.f32(),
                0.1 + 0.8 * rng.f32(),
            );
            assert!((g.lookup(p) - f(p)).abs() < 1e-5, "{p}");
        }
    }

    #[test]
    fn bad_values_and_sizes_are_located() {
        let e = DensityGrid::new([2, 2, 1], vec![0.0, 1.0, -2.0, 0.0]).unwrap_err();
        assert_eq!(
            e,
            GridValueError::Value {
                index: 2,
                voxel: [0, 1, 0],
                value: -2.0
            }
        );
        assert!(e.to_string().contains("voxel (0, 1, 0)") && e.to_string().contains("-2"));
        let e = DensityGrid::new([1, 1, 2], vec![0.0, f32::NAN]).unwrap_err();
        assert!(e.to_string().contains("not finite"), "{e}");
        let e = DensityGrid::new([2, 2, 2], vec![0.0; 7]).unwrap_err();
        assert!(matches!(
            e,
            GridValueError::Size {
                expected: 8,
                got: 7,
                ..
            }
        ));
        assert!(DensityGrid::new([0, 1, 1], vec![]).is_err());
    }

    /// A rough random grid for the majorant tests.
    fn random_grid(dims: [usize; 3], seed: u64) -> DensityGrid {
        let mut rng = SplitMix64(seed);
        let n = dims.iter().product();
        DensityGrid::new(dims, (0..n).map(|_| rng.f32() * rng.f32() * 3.0).collect()).unwrap()
    }

    #[test]
    fn majorant_bounds_hold_everywhere() {
        for (dims, res) in [
            ([64, 64, 64], [16, 16, 16]),
            ([7, 5, 3], [4, 4, 4]),
            ([2, 9, 1], [3, 2, 5]),
        ] {
            let g = random_grid(dims, dims[0] as u64);
            let m = MajorantGrid::new(&g, res);
            let mut rng = SplitMix64(11);
            for _ in 0..20000 {
                let p = Vec3::new(rng.f32(), rng.f32(), rng.f32());
                let [cx, cy, cz] = m.cell_of(p);
                let v = g.lookup(p);
                assert!(v <= m.max_at(cx, cy, cz), "{dims:?} {p}: {v}");
                assert!(v >= m.min_at(cx, cy, cz), "{dims:?} {p}: {v}");
            }
            // Cell corners and faces, the worst case for the support.
            for cz in 0..res[2] {
                for cy in 0..res[1] {
                    for cx in 0..res[0] {
                        for k in 0..8 {
                            let f = |c: usize, r: usize, bit: usize| {
                                ((c + ((k >> bit) & 1)) as f32 / r as f32).min(1.0)
                            };
                            let p = Vec3::new(f(cx, res[0], 0), f(cy, res[1], 1), f(cz, res[2], 2));
                            assert!(g.lookup(p) <= m.max_at(cx, cy, cz));
                        }
                    }
                }
            }
        }
        let g = random_grid([8, 8, 8], 3);
        let global = MajorantGrid::global(&g);
        assert_eq!(global.max_at(0, 0, 0), g.max());
    }

    #[test]
    fn the_dda_visits_the_cells_in_order_and_covers_the_clipped_segment() {
        let g = random_grid([8, 8, 8], 9);
        let m = MajorantGrid::new(&g, [4, 4, 4]);
        let mut rng = SplitMix64(2);
        for _ in 0..500 {
            let o = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 1.6 - 0.3;
            let d = (Vec3::new(rng.f32(), rng.f32(), rng.f32()) - 0.5) * 3.0;
            let tmax = 2.0 * rng.f32();
            let segs: Vec<MajorantSegment> = m.traverse(o, d, 0.0, tmax).collect();
            let mut prev: Option<f32> = None;
            for s in &segs {
                assert!(s.t0 < s.t1 || (s.t1 - s.t0).abs() < 1e-6, "{s:?}");
                if let Some(p) = prev {
                    assert_eq!(p, s.t0, "contiguous");
                }
                prev = Some(s.t1);
                // The segment's midpoint is in the cell whose bound it carries.
                let mid = o + d * (0.5 * (s.t0 + s.t1));
                let [cx, cy, cz] = m.cell_of(mid);
                assert_eq!(s.majorant, m.max_at(cx, cy, cz), "{o} {d} {s:?}");
            }
            // Total length = the part of [0, tmax] inside the cube (by sampling).
            let covered: f32 = segs.iter().map(|s| s.t1 - s.t0).sum();
            let steps = 2000;
            let inside = (0..steps)
                .filter(|&k| {
                    let t = (k as f32 + 0.5) / steps as f32 * tmax;
                    let p = o + d * t;
                    p.cmpge(Vec3::ZERO).all() && p.cmple(Vec3::ONE).all()
                })
                .count() as f32
                / steps as f32
                * tmax;
            assert!((covered - inside).abs() < 3.0 * tmax / steps as f32 + 1e-5);
        }
        // An axis-parallel ray through the middle visits 4 cells of length 0.25.
        let segs: Vec<_> = m
            .traverse(Vec3::new(-1.0, 0.6, 0.6), Vec3::X, 0.0, f32::INFINITY)
            .collect();
        assert_eq!(segs.len(), 4);
        assert!((segs[0].t0 - 1.0).abs() < 1e-6 && (segs[3].t1 - 2.0).abs() < 1e-6);
    }
}
