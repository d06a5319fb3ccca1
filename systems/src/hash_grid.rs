//! A hashed uniform grid over points, for radius queries (the light vertices vertex merging
//! gathers around each camera vertex).
//!
//! Cells are cubes of edge `2 r`, hashed into a table as long as the point count (Teschner et
//! al. 2003, "Optimized spatial hashing for collision detection of deformable objects": the
//! three cell coordinates times large primes, xor-ed). A ball of radius `r` around `p` overlaps
//! at most the 2 x 2 x 2 cells nearest to `p`, so a query visits eight table slots; points of
//! other cells that hash to the same slot are rejected by their distance. Built by a counting
//! sort (no per-cell allocation), as SmallVCM's `HashGrid` and pbrt-v4's SPPM grid do.

use glam::{IVec3, Vec3};

/// Points hashed by cell for radius queries.
#[derive(Clone, Debug, Default)]
pub struct HashGrid {
    /// Point indices, grouped by slot.
    indices: Vec<u32>,
    /// Slot `s` holds `indices[start[s]..start[s + 1]]`.
    start: Vec<u32>,
    /// Cell edge (`2 r`) and its inverse.
    cell: f32,
    inv_cell: f32,
    /// Query radius squared.
    radius2: f32,
}

impl HashGrid {
    /// Hashes `points` for queries of radius `radius` (> 0, finite). Reuses the grid's
    /// storage.
    pub fn build(&mut self, points: &[Vec3], radius: f32) {
        let n = points.len();
        self.cell = 2.0 * radius;
        self.inv_cell = 1.0 / self.cell;
        self.radius2 = radius * radius;
        let slots = n.max(1);
        self.start.clear();
        self.start.resize(slots + 1, 0);
        // Count per slot, shifted by one, then prefix sums give each slot's start.
        for &p in points {
            let s = self.slot(self.cell_of(p), slots);
            self.start[s + 1] += 1;
        }
        for s in 0..slots {
            self.start[s + 1] += self.start[s];
        }
        self.indices.clear();
        self.indices.resize(n, 0);
        // Fill with a cursor per slot (the starts, moved along), then restore the starts.
        for (i, &p) in points.iter().enumerate() {
            let s = self.slot(self.cell_of(p), slots);
            self.indices[self.start[s] as usize] = i as u32;
            self.start[s] += 1;
        }
        for s in (1..=slots).rev() {
            self.start[s] = self.start[s - 1];
        }
        self.start[0] = 0;
    }

    /// Calls `found(i)` for every point `i` of the build within the radius of `p` (each
    /// once). `points` must be the slice the grid was built from.
    pub fn query(&self, points: &[Vec3], p: Vec3, mut found: impl FnMut(usize)) {
        let slots = self.start.len().saturating_sub(1);
        if slots == 0 || points.is_empty() {
            return;
        }
        let x = p * self.inv_cell;
        let c = x.floor();
        // The 2 x 2 x 2 cells nearest to p: the own cell and, per axis, the neighbour on the
        // side of the cell's centre p is closer to the edge of.
        let base = c.as_ivec3();
        let side = IVec3::new(
            if x.x - c.x < 0.5 { -1 } else { 1 },
            if x.y - c.y < 0.5 { -1 } else { 1 },
            if x.z - c.z < 0.5 { -1 } else { 1 },
        );
        let mut visited = [usize::MAX; 8];
        for k in 0..8 {
            let offset = IVec3::new(
                if k & 1 == 0 { 0 } else { side.x },
                if k & 2 == 0 { 0 } else { side.y },
                if k & 4 == 0 { 0 } else { side.z },
            );
            let s = self.slot(base + offset, slots);
            // Two cells hashing to one slot: visit it once.
            if visited[..k].contains(&s) {
                continue;
            }
            visited[k] = s;
            let range = self.start[s] as usize..self.start[s + 1] as usize;
            for &i in &self.indices[range] {
                let i = i as usize;
                if (points[i] - p).length_squared() <= self.radius2 {
                    found(i);
                }
            }
        }
    }

    #[inline]
    fn cell_of(&self, p: Vec3) -> IVec3 {
        (p * self.inv_cell).floor().as_ivec3()
    }

    #[inline]
    fn slot(&self, c: IVec3, slots: usize) -> usize {
        let h = (c.x as u32).wrapping_mul(73_856_093)
            ^ (c.y as u32).wrapping_mul(19_349_663)
            ^ (c.z as u32).wrapping_mul(83_492_791);
        h as usize % slots
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every query finds exactly the points a brute-force scan finds, each once.
    #[test]
    fn queries_find_exactly_the_points_within_the_radius() {
        let mut state = 12345u64;
        let mut next = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
            ((state >> 40) as f32) / (1u64 << 24) as f32
        };
        for &(n, radius) in &[(1usize, 0.1f32), (50, 0.2), (2000, 0.05), (2000, 0.5)] {
            let points: Vec<Vec3> = (0..n)
                .map(|_| Vec3::new(next(), next(), next()) * 4.0 - 2.0)
                .collect();
            let mut grid = HashGrid::default();
            grid.build(&points, radius);
            for q in 0..300 {
                let p = if q % 3 == 0 {
                    points[q % n]
                } else {
                    Vec3::new(next(), next(), next()) * 4.0 - 2.0
                };
                let mut got = Vec::new();
                grid.query(&points, p, |i| got.push(i));
                let len = got.len();
                got.sort_unstable();
                got.dedup();
                assert_eq!(got.len(), len, "a point reported twice");
                let want: Vec<usize> = (0..n)
                    .filter(|&i| (points[i] - p).length_squared() <= radius * radius)
                    .collect();
                assert_eq!(got, want, "n = {n}, radius = {radius}, query {q} at {p}");
            }
        }
    }

    #[test]
    fn an_empty_grid_finds_nothing() {
        let mut grid = HashGrid::default();
        grid.build(&[], 1.0);
        grid.query(&[], Vec3::ZERO, |_| panic!("nothing to find"));
    }
}
