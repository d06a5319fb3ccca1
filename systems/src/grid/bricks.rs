//! Block-sparse voxel storage for a [`DensityGrid`](super::DensityGrid): the grid's voxels in
//! `8^3` bricks (OpenVDB's leaf nodes), a top-level table of brick entries, and only the
//! bricks that are not one value stored (memory proportional to the non-uniform bricks, not
//! to the bounding box).
//!
//! # Layout
//! Voxel `(x, y, z)` of the grid sits at storage coordinate `q = (x, y, z) + shift` (`shift`
//! in `0..8` per axis, so that a reader can align the bricks with a file's own blocks, e.g.
//! a VDB's leaf nodes, whatever the grid's origin). Brick `q >> 3` has a table entry: with
//! [`UNIFORM`] set, the brick is one value and the entry's other 31 bits are that value's
//! `f32` bits (a value `>= 0` with its sign bit clear: `-0.0` keeps a stored brick, so every
//! read returns the bits the dense grid would); otherwise the entry is the brick's index
//! into `values`, 512 values each, `q & 7` x fastest.
//!
//! # Invariant
//! Storage voxels outside the grid (the `shift` margin and the tail of the last brick) are
//! 0, and a uniform brick of a value other than `+0.0` lies inside the grid: so the same
//! bricks, table moved by whole bricks, are the grid padded with zeros
//! ([`Bricks::padded_with_zeros`]).

use super::bounds_of;

/// Voxels per brick edge.
pub const BRICK: usize = 8;
/// Voxels per brick.
const BRICK_VOXELS: usize = BRICK * BRICK * BRICK;
/// A table entry's flag: the brick is one value (its `f32` bits in the other 31 bits).
pub const UNIFORM: u32 = 1 << 31;

/// The block-sparse storage (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Bricks {
    dims: [usize; 3],
    shift: [usize; 3],
    bricks: [usize; 3],
    table: Vec<u32>,
    values: Vec<f32>,
}

/// Bricks per axis for `dims` voxels stored from `shift`.
fn brick_counts(dims: [usize; 3], shift: [usize; 3]) -> [usize; 3] {
    [0, 1, 2].map(|a| (dims[a] + shift[a]).div_ceil(BRICK))
}

/// The table entry of a brick of one value, if the value can be one (module docs).
fn uniform_entry(value: f32) -> Option<u32> {
    let bits = value.to_bits();
    (bits & UNIFORM == 0).then_some(bits | UNIFORM)
}

impl Bricks {
    /// `[nx, ny, nz]` of the grid.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Bricks per axis of the table.
    pub fn brick_counts(&self) -> [usize; 3] {
        self.bricks
    }

    /// Stored (non-uniform) bricks.
    pub fn stored_bricks(&self) -> usize {
        self.values.len() / BRICK_VOXELS
    }

    /// Bytes held: the table and the stored bricks.
    pub fn heap_bytes(&self) -> usize {
        4 * self.table.len() + 4 * self.values.len()
    }

    /// The stored values (every stored brick's 512, outside-grid voxels 0 included).
    pub(super) fn values(&self) -> &[f32] {
        &self.values
    }

    /// Voxel `(x, y, z)` (inside the grid).
    #[inline]
    pub fn voxel(&self, x: usize, y: usize, z: usize) -> f32 {
        let q = [x + self.shift[0], y + self.shift[1], z + self.shift[2]];
        let b = (q[0] >> 3) + self.bricks[0] * ((q[1] >> 3) + self.bricks[1] * (q[2] >> 3));
        let e = self.table[b];
        if e & UNIFORM != 0 {
            f32::from_bits(e & !UNIFORM)
        } else {
            self.values
                [e as usize * BRICK_VOXELS + (q[0] & 7) + BRICK * ((q[1] & 7) + BRICK * (q[2] & 7))]
        }
    }

    /// `(max, min)` of the voxels of the box `lo..=hi` (grid coordinates, inside the grid)
    /// folded into `acc`: uniform bricks count once, stored ones row by row.
    pub(super) fn bounds_in(
        &self,
        lo: [usize; 3],
        hi: [usize; 3],
        mut acc: (f32, f32),
    ) -> (f32, f32) {
        let q0 = [0, 1, 2].map(|a| lo[a] + self.shift[a]);
        let q1 = [0, 1, 2].map(|a| hi[a] + self.shift[a]);
        for bz in q0[2] >> 3..=q1[2] >> 3 {
            for by in q0[1] >> 3..=q1[1] >> 3 {
                for bx in q0[0] >> 3..=q1[0] >> 3 {
                    let e = self.table[bx + self.bricks[0] * (by + self.bricks[1] * bz)];
                    if e & UNIFORM != 0 {
                        let v = f32::from_bits(e & !UNIFORM);
                        acc = (acc.0.max(v), acc.1.min(v));
                        continue;
                    }
                    let brick = &self.values[e as usize * BRICK_VOXELS..][..BRICK_VOXELS];
                    // The part of the box inside this brick, brick-local.
                    let part = |a: usize, b: usize| {
                        let base = b * BRICK;
                        (q0[a].max(base) - base, q1[a].min(base + BRICK - 1) - base)
                    };
                    let ((x0, x1), (y0, y1), (z0, z1)) = (part(0, bx), part(1, by), part(2, bz));
                    for z in z0..=z1 {
                        for y in y0..=y1 {
                            let row = BRICK * (y + BRICK * z);
                            acc = bounds_of(&brick[row + x0..=row + x1], acc);
                        }
                    }
                }
            }
        }
        acc
    }

    /// The sum (f64) over the uniform bricks of their value times their voxels inside the
    /// grid (the stored bricks' part of the grid's sum is a scan of [`Self::values`]).
    pub(super) fn uniform_sum(&self) -> f64 {
        let mut sum = 0.0;
        let inside = |a: usize, b: usize| {
            let (base, lo, hi) = (b * BRICK, self.shift[a], self.shift[a] + self.dims[a]);
            (hi.min(base + BRICK)).saturating_sub(lo.max(base))
        };
        for bz in 0..self.bricks[2] {
            for by in 0..self.bricks[1] {
                for bx in 0..self.bricks[0] {
                    let e = self.table[bx + self.bricks[0] * (by + self.bricks[1] * bz)];
                    if e & UNIFORM != 0 {
                        let v = f32::from_bits(e & !UNIFORM) as f64;
                        if v != 0.0 {
                            sum += v * (inside(0, bx) * inside(1, by) * inside(2, bz)) as f64;
                        }
                    }
                }
            }
        }
        sum
    }

    /// The largest uniform brick value (0 when none).
    pub(super) fn uniform_max(&self) -> f32 {
        self.table
            .iter()
            .filter(|&&e| e & UNIFORM != 0)
            .map(|&e| f32::from_bits(e & !UNIFORM))
            .fold(0.0, f32::max)
    }

    /// The first uniform brick value that is negative or not finite, with a voxel of it.
    pub(super) fn bad_uniform(&self) -> Option<([usize; 3], f32)> {
        let b = self.table.iter().position(|&e| {
            let v = f32::from_bits(e & !UNIFORM);
            e & UNIFORM != 0 && !v.is_finite()
        })?;
        let v = f32::from_bits(self.table[b] & !UNIFORM);
        let [nx, ny, _] = self.bricks;
        let brick = [b % nx, (b / nx) % ny, b / (nx * ny)];
        Some((
            [0, 1, 2].map(|a| (brick[a] * BRICK).saturating_sub(self.shift[a])),
            v,
        ))
    }

    /// The voxel of the `index`-th stored value (for error messages).
    pub(super) fn voxel_of_value(&self, index: usize) -> [usize; 3] {
        let (k, i) = (index / BRICK_VOXELS, index % BRICK_VOXELS);
        let b = self
            .table
            .iter()
            .position(|&e| e == k as u32)
            .expect("every stored brick has a table entry");
        let [nx, ny, _] = self.bricks;
        let brick = [b % nx, (b / nx) % ny, b / (nx * ny)];
        let local = [i % BRICK, (i / BRICK) % BRICK, i / (BRICK * BRICK)];
        [0, 1, 2].map(|a| (brick[a] * BRICK + local[a]).saturating_sub(self.shift[a]))
    }

    /// The same voxels with one voxel of 0 added on every side (module docs, invariant): the
    /// bricks are kept, the table is moved by 0 or 1 brick per axis.
    pub fn padded_with_zeros(&self) -> Bricks {
        let dims = self.dims.map(|n| n + 2);
        // Storage q' = (x + 1) + shift' must equal q (+ 8 when shift is 0).
        let shift = self.shift.map(|s| (s + BRICK - 1) % BRICK);
        let moved = self.shift.map(|s| usize::from(s == 0));
        let bricks = brick_counts(dims, shift);
        let mut table = vec![UNIFORM; bricks.iter().product()];
        for bz in 0..self.bricks[2] {
            for by in 0..self.bricks[1] {
                let from = self.bricks[0] * (by + self.bricks[1] * bz);
                let to = moved[0] + bricks[0] * ((by + moved[1]) + bricks[1] * (bz + moved[2]));
                table[to..to + self.bricks[0]]
                    .copy_from_slice(&self.table[from..from + self.bricks[0]]);
            }
        }
        Bricks {
            dims,
            shift,
            bricks,
            table,
            values: self.values.clone(),
        }
    }

    /// The dense copy, `x` fastest.
    pub fn to_dense(&self) -> Vec<f32> {
        let [nx, ny, nz] = self.dims;
        let mut data = Vec::with_capacity(nx * ny * nz);
        for z in 0..nz {
            for y in 0..ny {
                data.extend((0..nx).map(|x| self.voxel(x, y, z)));
            }
        }
        data
    }
}

/// Builds [`Bricks`] from boxes of one value: every brick starts uniform 0, a brick a box
/// covers whole becomes uniform, a brick a box covers in part is stored, and [`Self::finish`]
/// turns stored bricks of one value back into uniform ones.
#[derive(Debug)]
pub struct BrickBuilder {
    grid: Bricks,
    /// The table slot of each stored brick (for the compaction in `finish`).
    owner: Vec<usize>,
}

impl BrickBuilder {
    /// An empty (all 0) grid of `dims` voxels stored from `shift` (each taken mod 8).
    pub fn new(dims: [usize; 3], shift: [usize; 3]) -> Self {
        let shift = shift.map(|s| s % BRICK);
        let bricks = brick_counts(dims, shift);
        BrickBuilder {
            grid: Bricks {
                dims,
                shift,
                bricks,
                table: vec![UNIFORM; bricks.iter().product()],
                values: Vec::new(),
            },
            owner: Vec::new(),
        }
    }

    /// Bricks in the table of a grid of `dims` stored from `shift` (what [`Self::new`]
    /// allocates 4 bytes each for).
    pub fn table_len(dims: [usize; 3], shift: [usize; 3]) -> usize {
        brick_counts(dims, shift.map(|s| s % BRICK))
            .iter()
            .try_fold(1usize, |a, &n| a.checked_mul(n))
            .unwrap_or(usize::MAX)
    }

    /// Stored bricks so far.
    pub fn stored_bricks(&self) -> usize {
        self.owner.len()
    }

    /// Sets the voxels of the box `origin .. origin + size` (per axis; clipped to the grid)
    /// to `value`.
    pub fn fill(&mut self, origin: [usize; 3], size: [usize; 3], value: f32) {
        let g = &self.grid;
        let q0 = [0, 1, 2].map(|a| origin[a].min(g.dims[a]) + g.shift[a]);
        let q1 = [0, 1, 2].map(|a| (origin[a] + size[a]).min(g.dims[a]) + g.shift[a]);
        if (0..3).any(|a| q0[a] >= q1[a]) {
            return;
        }
        for bz in q0[2] / BRICK..q1[2].div_ceil(BRICK) {
            for by in q0[1] / BRICK..q1[1].div_ceil(BRICK) {
                for bx in q0[0] / BRICK..q1[0].div_ceil(BRICK) {
                    let b = [bx, by, bz];
                    let part = |a: usize| {
                        let base = b[a] * BRICK;
                        (q0[a].max(base) - base, q1[a].min(base + BRICK) - base)
                    };
                    let (px, py, pz) = (part(0), part(1), part(2));
                    let whole = [px, py, pz].iter().all(|&(s, e)| s == 0 && e == BRICK);
                    let slot = bx + self.grid.bricks[0] * (by + self.grid.bricks[1] * bz);
                    if whole {
                        if let Some(entry) = uniform_entry(value) {
                            // A stored brick left behind is dropped by `finish`.
                            self.grid.table[slot] = entry;
                            continue;
                        }
                    }
                    let k = self.stored(slot);
                    let brick = &mut self.grid.values[k * BRICK_VOXELS..][..BRICK_VOXELS];
                    for z in pz.0..pz.1 {
                        for y in py.0..py.1 {
                            let row = BRICK * (y + BRICK * z);
                            brick[row + px.0..row + px.1].fill(value);
                        }
                    }
                }
            }
        }
    }

    /// The stored index of the brick at table `slot`, storing it (filled with its uniform
    /// value, 0 outside the grid) if it is uniform.
    fn stored(&mut self, slot: usize) -> usize {
        let e = self.grid.table[slot];
        if e & UNIFORM == 0 {
            return e as usize;
        }
        let k = self.owner.len();
        let v = f32::from_bits(e & !UNIFORM);
        self.grid.values.resize((k + 1) * BRICK_VOXELS, v);
        if v != 0.0 {
            // Only a brick inside the grid can be uniform non-zero (module invariant), so
            // there is nothing to clear; kept as a check of that.
            debug_assert!(self.inside(slot));
        }
        self.owner.push(slot);
        self.grid.table[slot] = k as u32;
        k
    }

    /// Whether the brick at `slot` lies inside the grid.
    fn inside(&self, slot: usize) -> bool {
        let g = &self.grid;
        let b = [
            slot % g.bricks[0],
            (slot / g.bricks[0]) % g.bricks[1],
            slot / (g.bricks[0] * g.bricks[1]),
        ];
        (0..3).all(|a| b[a] * BRICK >= g.shift[a] && (b[a] + 1) * BRICK <= g.shift[a] + g.dims[a])
    }

    /// The storage: stored bricks whose 512 values have the same bits (and may be uniform)
    /// become uniform, the rest are compacted in their order.
    pub fn finish(self) -> Bricks {
        let BrickBuilder { mut grid, owner } = self;
        let mut kept = 0usize;
        for (k, &slot) in owner.iter().enumerate() {
            if grid.table[slot] != k as u32 {
                continue; // overwritten by a uniform fill
            }
            let brick = &grid.values[k * BRICK_VOXELS..][..BRICK_VOXELS];
            let first = brick[0].to_bits();
            if brick.iter().all(|v| v.to_bits() == first) {
                if let Some(entry) = uniform_entry(brick[0]) {
                    grid.table[slot] = entry;
                    continue;
                }
            }
            grid.values.copy_within(
                k * BRICK_VOXELS..(k + 1) * BRICK_VOXELS,
                kept * BRICK_VOXELS,
            );
            grid.table[slot] = kept as u32;
            kept += 1;
        }
        grid.values.truncate(kept * BRICK_VOXELS);
        grid.values.shrink_to_fit();
        grid
    }
}

#[cfg(test)]
mod tests;
