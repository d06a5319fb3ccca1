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

mod bricks;
mod channels;
mod exact_depth;
pub use bricks::{BrickBuilder, Bricks, BRICK};
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

/// A scalar grid over the unit cube (see the module docs), its voxels held dense or
/// block-sparse ([`Bricks`]); every lookup returns the same bits either way.
#[derive(Clone, Debug, PartialEq)]
pub struct DensityGrid {
    dims: [usize; 3],
    voxels: Voxels,
    max: f32,
    mean: f64,
}

/// How a [`DensityGrid`] holds its voxels.
#[derive(Clone, Debug, PartialEq)]
enum Voxels {
    /// Every voxel, x fastest.
    Dense(Vec<f32>),
    /// `8^3` bricks, uniform ones as one value.
    /// (Boxed: the table's shape would triple the size of every dense grid's struct.)
    Sparse(Box<Bricks>),
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
            voxels: Voxels::Dense(data),
            max,
            mean,
        })
    }

    /// A grid held block-sparse (values checked as by [`Self::new`]; the dims are the
    /// bricks'). Its lookups return the bits of the dense grid of the same voxels.
    pub fn from_bricks(bricks: Bricks) -> Result<Self, GridValueError> {
        let dims = bricks.dims();
        let (valid, stored_max, stored_sum) = scan(bricks.values());
        if !valid {
            let index = bricks
                .values()
                .iter()
                .position(|v| !(v.is_finite() && *v >= 0.0))
                .expect("scan found a value that is not finite and >= 0");
            return Err(GridValueError::Value {
                index,
                voxel: bricks.voxel_of_value(index),
                value: bricks.values()[index],
            });
        }
        if let Some((voxel, value)) = bricks.bad_uniform() {
            let [nx, ny, _] = dims;
            return Err(GridValueError::Value {
                index: voxel[0] + nx * (voxel[1] + ny * voxel[2]),
                voxel,
                value,
            });
        }
        let n = dims.iter().map(|&d| d as f64).product::<f64>();
        let mean = (stored_sum + bricks.uniform_sum()) / n;
        Ok(DensityGrid {
            dims,
            max: stored_max.max(bricks.uniform_max()),
            mean,
            voxels: Voxels::Sparse(Box::new(bricks)),
        })
    }

    /// The same voxels held dense (a copy when sparse).
    pub fn to_dense(&self) -> DensityGrid {
        match &self.voxels {
            Voxels::Dense(_) => self.clone(),
            Voxels::Sparse(b) => DensityGrid {
                voxels: Voxels::Dense(b.to_dense()),
                ..*self
            },
        }
    }

    /// The block-sparse storage, if the grid is held so.
    pub fn bricks(&self) -> Option<&Bricks> {
        match &self.voxels {
            Voxels::Sparse(b) => Some(b),
            Voxels::Dense(_) => None,
        }
    }

    /// Bytes the voxels take (the dense values, or the brick table and stored bricks).
    pub fn heap_bytes(&self) -> usize {
        match &self.voxels {
            Voxels::Dense(d) => 4 * d.len(),
            Voxels::Sparse(b) => b.heap_bytes(),
        }
    }

    /// This grid with one voxel of 0 added on every side (`[nx + 2, ny + 2, nz + 2]`): read
    /// over the same cell centres, its field is the one of a grid whose voxels beyond the
    /// edge are 0 (pbrt-v4's `SampledGrid`, OpenVDB's background) instead of the clamp.
    pub fn padded_with_zeros(&self) -> Self {
        let [nx, ny, nz] = self.dims;
        let dims = [nx + 2, ny + 2, nz + 2];
        let n = (dims[0] * dims[1] * dims[2]) as f64;
        let mean = self.mean * (nx * ny * nz) as f64 / n;
        let max = self.max.max(0.0);
        let this = match &self.voxels {
            Voxels::Dense(d) => d,
            Voxels::Sparse(b) => {
                return DensityGrid {
                    dims,
                    voxels: Voxels::Sparse(Box::new(b.padded_with_zeros())),
                    max,
                    mean,
                }
            }
        };
        let mut data = vec![0.0; dims[0] * dims[1] * dims[2]];
        for z in 0..nz {
            for y in 0..ny {
                let to = 1 + dims[0] * ((y + 1) + dims[1] * (z + 1));
                let from = nx * (y + ny * z);
                data[to..to + nx].copy_from_slice(&this[from..from + nx]);
            }
        }
        DensityGrid {
            dims,
            voxels: Voxels::Dense(data),
            max,
            mean,
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

    /// The voxel values, x fastest, if the grid is held dense.
    pub fn dense_data(&self) -> Option<&[f32]> {
        match &self.voxels {
            Voxels::Dense(d) => Some(d),
            Voxels::Sparse(_) => None,
        }
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
        match &self.voxels {
            Voxels::Dense(d) => d[ix + nx * (iy + ny * iz)],
            Voxels::Sparse(b) => b.voxel(ix, iy, iz),
        }
    }

    /// The trilinearly interpolated value at `uvw` (unit-cube coordinates; any point, clamped
    /// to the outermost cell centres; NaN coordinates read voxel 0).
    #[inline]
    pub fn lookup(&self, uvw: Vec3) -> f32 {
        let [nx, ny, _] = self.dims;
        match &self.voxels {
            Voxels::Dense(d) => trilinear(self.dims, uvw, |x, y, z| d[x + nx * (y + ny * z)]),
            Voxels::Sparse(b) => trilinear(self.dims, uvw, |x, y, z| b.voxel(x, y, z)),
        }
    }
}

/// The trilinear interpolation of the voxels `at` of a `dims` grid at `uvw` (module docs):
/// one body for dense and sparse grids, so both round alike.
#[inline(always)]
fn trilinear(dims: [usize; 3], uvw: Vec3, at: impl Fn(usize, usize, usize) -> f32) -> f32 {
    let (x0, x1, fx) = axis(uvw.x, dims[0]);
    let (y0, y1, fy) = axis(uvw.y, dims[1]);
    let (z0, z1, fz) = axis(uvw.z, dims[2]);
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
                    match &grid.voxels {
                        Voxels::Dense(data) => {
                            for z in z0..=z1 {
                                for y in y0..=y1 {
                                    let row = dims[0] * (y + dims[1] * z);
                                    bounds = bounds_of(&data[row + x0..=row + x1], bounds);
                                }
                            }
                        }
                        // Brick by brick: a uniform brick is one value, never expanded.
                        Voxels::Sparse(b) => {
                            bounds = b.bounds_in([x0, y0, z0], [x1, y1, z1], bounds);
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
mod tests;
