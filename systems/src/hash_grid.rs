//! A hashed uniform grid over points, for radius queries (the light vertices vertex merging
//! gathers around each camera vertex).
//!
//! Cells are cubes of edge `2 r`, hashed into a table as long as the point count (Teschner et
//! al. 2003, "Optimized spatial hashing for collision detection of deformable objects": the
//! three cell coordinates times large primes, xor-ed). A ball of radius `r` around `p` overlaps
//! at most the 2 x 2 x 2 cells nearest to `p`, so a query visits eight table slots; points of
//! other cells that hash to the same slot are rejected by their distance. Built by a counting
//! sort (no per-cell allocation), as SmallVCM's `HashGrid` and pbrt-v4's SPPM grid do.
//!
//! The grid keeps its own copy of the points, in slot order beside their indices (16 bytes a
//! point), and a query loads its eight slots' bounds before reading any of them: with an
//! iteration's light vertices (hundreds of thousands, megabytes) nearly every load misses the
//! cache, and this way a query's misses overlap and its points are read from one place
//! instead of through their indices.

use glam::{IVec3, Vec3};

/// A point of the grid and its index in the build's slice.
#[derive(Clone, Copy, Debug, Default)]
struct Entry {
    p: Vec3,
    index: u32,
}

/// Points hashed by cell for radius queries.
#[derive(Clone, Debug, Default)]
pub struct HashGrid {
    /// The points and their indices, grouped by slot.
    entries: Vec<Entry>,
    /// Slot `s` holds `entries[start[s]..start[s + 1]]`.
    start: Vec<u32>,
    /// Cell edge (`2 r`) and its inverse.
    cell: f32,
    inv_cell: f32,
    /// Query radius squared.
    radius2: f32,
    /// `h % slots` as a multiplication ([`FastMod`]): a query hashes eight cells.
    modulo: FastMod,
}

/// `a % d` for 32-bit `a` by a multiplication (Lemire, Kaser and Kurz 2019, "Faster remainder
/// by direct computation"): `M = floor((2^64 - 1) / d) + 1`, then `a % d` is the high 64 bits
/// of `(M a mod 2^64) d`, exact for every 32-bit `a` and `d`. An integer division costs tens
/// of cycles, and a query's eight slots each took one.
#[derive(Clone, Copy, Debug, Default)]
struct FastMod {
    m: u64,
    d: u64,
}

impl FastMod {
    fn new(d: u32) -> Self {
        let d = u64::from(d.max(1));
        FastMod {
            m: (u64::MAX / d).wrapping_add(1),
            d,
        }
    }

    #[inline]
    fn rem(self, a: u32) -> usize {
        let low = self.m.wrapping_mul(u64::from(a));
        ((u128::from(low) * u128::from(self.d)) >> 64) as usize
    }
}

impl HashGrid {
    /// Hashes `points` for queries of radius `radius` (> 0, finite). Reuses the grid's
    /// storage.
    pub fn build(&mut self, points: &[Vec3], radius: f32) {
        let n = points.len();
        self.cell = 2.0 * radius;
        self.inv_cell = 1.0 / self.cell;
        self.radius2 = radius * radius;
        // Slots are counted in u32 (the point indices are), so the table never outgrows it.
        let slots = n.clamp(1, u32::MAX as usize);
        self.modulo = FastMod::new(slots as u32);
        self.start.clear();
        self.start.resize(slots + 1, 0);
        // Count per slot, shifted by one, then prefix sums give each slot's start.
        for &p in points {
            let s = self.slot(self.cell_of(p));
            self.start[s + 1] += 1;
        }
        for s in 0..slots {
            self.start[s + 1] += self.start[s];
        }
        self.entries.clear();
        self.entries.resize(n, Entry::default());
        // Fill with a cursor per slot (the starts, moved along), then restore the starts.
        for (i, &p) in points.iter().enumerate() {
            let s = self.slot(self.cell_of(p));
            self.entries[self.start[s] as usize] = Entry { p, index: i as u32 };
            self.start[s] += 1;
        }
        for s in (1..=slots).rev() {
            self.start[s] = self.start[s - 1];
        }
        self.start[0] = 0;
    }

    /// Calls `found(i)` for every point `i` of the build (its index in the slice the grid
    /// was built from) within the radius of `p`, each once.
    pub fn query(&self, p: Vec3, mut found: impl FnMut(usize)) {
        if self.entries.is_empty() {
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
        let mut slots = [0usize; 8];
        for (k, slot) in slots.iter_mut().enumerate() {
            let offset = IVec3::new(
                if k & 1 == 0 { 0 } else { side.x },
                if k & 2 == 0 { 0 } else { side.y },
                if k & 4 == 0 { 0 } else { side.z },
            );
            *slot = self.slot(base + offset);
        }
        // Every slot's bounds first (independent loads, whose misses overlap), then the
        // points. Two cells hashing to one slot: it is visited once.
        let mut ranges = [(0u32, 0u32); 8];
        for k in 0..8 {
            let s = slots[k];
            if !slots[..k].contains(&s) {
                ranges[k] = (self.start[s], self.start[s + 1]);
            }
        }
        for (a, b) in ranges {
            for e in &self.entries[a as usize..b as usize] {
                if (e.p - p).length_squared() <= self.radius2 {
                    found(e.index as usize);
                }
            }
        }
    }

    #[inline]
    fn cell_of(&self, p: Vec3) -> IVec3 {
        (p * self.inv_cell).floor().as_ivec3()
    }

    /// The table slot of cell `c`: its hash modulo the slot count.
    #[inline]
    fn slot(&self, c: IVec3) -> usize {
        let h = (c.x as u32).wrapping_mul(73_856_093)
            ^ (c.y as u32).wrapping_mul(19_349_663)
            ^ (c.z as u32).wrapping_mul(83_492_791);
        self.modulo.rem(h)
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
                grid.query(p, |i| got.push(i));
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

    /// The multiplication remainder equals `%` for divisors and dividends at the ends of
    /// the 32-bit range and in between.
    #[test]
    fn fast_remainders_are_remainders() {
        let values = [
            0u32,
            1,
            2,
            3,
            7,
            1000,
            4095,
            4096,
            65_537,
            1 << 31,
            u32::MAX - 1,
            u32::MAX,
        ];
        for &d in values.iter().filter(|&&d| d > 0) {
            let m = FastMod::new(d);
            for &a in &values {
                assert_eq!(m.rem(a), (a % d) as usize, "{a} % {d}");
            }
        }
    }

    #[test]
    fn an_empty_grid_finds_nothing() {
        let mut grid = HashGrid::default();
        grid.build(&[], 1.0);
        grid.query(Vec3::ZERO, |_| panic!("nothing to find"));
    }
}
