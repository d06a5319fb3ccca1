//! The exact optical depth of a [`DensityGrid`] along a ray, for majorant cells too dense to
//! track ([`crate::tracking::dense`]).
//!
//! Between the planes through the voxel centres (the "dual cells" of the cell-centred
//! convention, and the clamped half-voxel slabs at the faces) the grid's field is
//! trilinear, `sum c_ijk x^i y^j z^k` with `i, j, k` in `{0, 1}`; along a ray each of `x, y,
//! z` is linear in `t`, so the field restricted to one such piece is a polynomial of degree
//! at most 3 in `t`. Two-point Gauss-Legendre quadrature integrates cubics exactly
//! (Abramowitz and Stegun 25.4.29; nodes `+-1 / sqrt 3`, weights 1), so the optical depth
//! of a piece costs two lookups and has no error beyond rounding, whatever the density; the
//! depth of any interval is the sum over the pieces it crosses, and the point where a given
//! depth is reached is found by bisection on the (monotone) depth within one piece. The
//! cost is bounded by the number of voxel planes the interval crosses, not by the density:
//! what a majorant cell of extreme bound needs (pbrt-v4's `DDAMajorantIterator` and every
//! null-collision tracker take `majorant x length` steps there).

use super::DensityGrid;
use glam::Vec3;

/// A ray `o + t d` through a [`DensityGrid`]'s unit cube (the grid's coordinates; `t` any
/// parameter, e.g. world distance), its field times `scale` (density to extinction).
#[derive(Clone, Copy, Debug)]
pub struct GridRay<'g> {
    /// The grid.
    pub grid: &'g DensityGrid,
    /// Origin (unit-cube coordinates).
    pub origin: Vec3,
    /// Direction (unit-cube coordinates per unit `t`).
    pub direction: Vec3,
    /// Multiplies the field (extinction per density).
    pub scale: f32,
}

/// `1 / sqrt 3`, the two-point Gauss-Legendre node on `[-1, 1]`.
const GAUSS_NODE: f64 = 0.577_350_269_189_625_8;

impl GridRay<'_> {
    /// `scale x field` at `t`.
    #[inline]
    fn sigma(&self, t: f64) -> f64 {
        let p = self.origin + self.direction * t as f32;
        self.scale as f64 * self.grid.lookup(p) as f64
    }

    /// The depth of `[a, b]` inside one piece (exact for the piece's cubic).
    #[inline]
    fn piece_depth(&self, a: f64, b: f64) -> f64 {
        let (m, h) = (0.5 * (a + b), 0.5 * (b - a));
        if h <= 0.0 {
            return 0.0;
        }
        h * (self.sigma(m - h * GAUSS_NODE) + self.sigma(m + h * GAUSS_NODE))
    }

    /// The pieces of `[t0, t1]` (consecutive `(a, b)`), cut where the ray crosses a plane
    /// through voxel centres.
    fn pieces(&self, t0: f32, t1: f32) -> impl Iterator<Item = (f64, f64)> {
        let (t0, t1) = (t0 as f64, t1 as f64);
        let dims = self.grid.dims();
        let (o, d) = (self.origin.to_array(), self.direction.to_array());
        // Per axis: the next crossing of a centre plane after t0 and the spacing of the
        // crossings; planes at u = (k + 0.5) / n for k in 0..n (the outermost bound the
        // clamped slabs, where the field is constant along that axis).
        let mut next = [f64::INFINITY; 3];
        let mut delta = [f64::INFINITY; 3];
        let mut last = [f64::INFINITY; 3];
        for a in 0..3 {
            let (n, da) = (dims[a] as f64, d[a] as f64);
            if da == 0.0 || dims[a] < 2 {
                continue;
            }
            let g = |t: f64| (o[a] as f64 + da * t) * n - 0.5;
            let at = |k: f64| ((k + 0.5) / n - o[a] as f64) / da;
            let (k0, kl) = if da > 0.0 {
                (g(t0).floor() + 1.0, n - 1.0)
            } else {
                (g(t0).ceil() - 1.0, 0.0)
            };
            let k0 = k0.clamp(0.0, n - 1.0);
            if (da > 0.0 && g(t0) >= n - 1.0) || (da < 0.0 && g(t0) <= 0.0) {
                continue; // no plane ahead
            }
            next[a] = at(k0);
            delta[a] = 1.0 / (n * da.abs());
            last[a] = at(kl);
        }
        let mut t = t0;
        std::iter::from_fn(move || {
            if t >= t1 {
                return None;
            }
            let a = (0..3)
                .min_by(|&i, &j| next[i].total_cmp(&next[j]))
                .unwrap_or(0);
            let b = next[a].min(t1).max(t);
            if next[a] <= t1 {
                next[a] = if next[a] >= last[a] - 0.5 * delta[a] {
                    f64::INFINITY
                } else {
                    next[a] + delta[a]
                };
            }
            let piece = (t, b);
            t = b;
            Some(piece)
        })
    }

    /// The optical depth `int_t0^t1 scale field(o + t d) dt` (exact up to rounding; 0 for
    /// `t1 <= t0`). Adds the grid lookups it made to `lookups`.
    pub fn depth(&self, t0: f32, t1: f32, lookups: &mut u32) -> f64 {
        self.pieces(t0, t1)
            .map(|(a, b)| {
                *lookups += 2;
                self.piece_depth(a, b)
            })
            .sum()
    }

    /// Where the optical depth from `t0` reaches `target` (>= 0) before `t1`: `Ok(t)`, or
    /// `Err(depth)` with the whole interval's depth (below `target`). Bisection inside the
    /// piece where the target is crossed (at most 64 halvings of an `f64` interval, stopping
    /// when the `f32` parameter no longer changes). Adds the grid lookups it made to
    /// `lookups`.
    pub fn invert(&self, t0: f32, t1: f32, target: f64, lookups: &mut u32) -> Result<f32, f64> {
        let mut done = 0.0;
        for (a, b) in self.pieces(t0, t1) {
            *lookups += 2;
            let piece = self.piece_depth(a, b);
            if done + piece < target {
                done += piece;
                continue;
            }
            let want = target - done;
            let (mut lo, mut hi) = (a, b);
            for _ in 0..64 {
                let mid = 0.5 * (lo + hi);
                if mid as f32 == lo as f32 || mid as f32 == hi as f32 {
                    break;
                }
                *lookups += 2;
                if self.piece_depth(a, mid) < want {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            return Ok((hi as f32).clamp(t0, t1));
        }
        Err(done)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::SplitMix64;

    /// The depth by a fine midpoint rule (the reference, independent of the pieces).
    fn midpoint(r: &GridRay<'_>, t0: f32, t1: f32, n: usize) -> f64 {
        let h = (t1 - t0) as f64 / n as f64;
        (0..n)
            .map(|k| h * r.sigma(t0 as f64 + (k as f64 + 0.5) * h))
            .sum()
    }

    fn random_grid(dims: [usize; 3], seed: u64) -> DensityGrid {
        let mut rng = SplitMix64(seed);
        let n = dims.iter().product();
        DensityGrid::new(dims, (0..n).map(|_| rng.f32() * 3.0).collect()).unwrap()
    }

    #[test]
    fn depth_matches_a_fine_quadrature_on_random_rays() {
        for dims in [[4, 4, 4], [7, 3, 5], [1, 6, 2]] {
            let g = random_grid(dims, dims[0] as u64);
            let mut rng = SplitMix64(3);
            for _ in 0..200 {
                let o = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 1.4 - 0.2;
                let d = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - 1.0;
                let r = GridRay {
                    grid: &g,
                    origin: o,
                    direction: d,
                    scale: 2.5,
                };
                let (t0, t1) = (0.1 * rng.f32(), 0.2 + rng.f32());
                let exact = r.depth(t0, t1, &mut 0);
                let fine = midpoint(&r, t0, t1, 20000);
                assert!(
                    (exact - fine).abs() < 1e-4 * (1.0 + fine),
                    "{dims:?} {o} {d}: {exact} vs {fine}"
                );
            }
        }
    }

    #[test]
    fn an_extreme_voxel_costs_a_few_pieces_and_inversion_hits_the_target() {
        // The case: one voxel of 1e9 among 0.1.
        let mut data = vec![0.1; 64];
        data[1 + 4 * (1 + 4)] = 1e9;
        let g = DensityGrid::new([4, 4, 4], data).unwrap();
        let r = GridRay {
            grid: &g,
            origin: Vec3::new(0.0, 0.37, 0.4),
            direction: Vec3::new(1.0, 0.01, -0.02),
            scale: 10.0,
        };
        assert!(r.pieces(0.0, 1.0).count() <= 12);
        let mut lookups = 0;
        let total = r.depth(0.0, 1.0, &mut lookups);
        assert!(lookups <= 24, "{lookups}");
        let fine = midpoint(&r, 0.0, 1.0, 200000);
        assert!((total - fine).abs() < 1e-3 * fine, "{total} vs {fine}");
        assert!(total > 1e8);
        for target in [0.5, 3.0, 1e3, 1e8] {
            let mut lookups = 0;
            let t = r.invert(0.0, 1.0, target, &mut lookups).unwrap();
            assert!(lookups <= 24 + 2 * 64, "{lookups}");
            let got = r.depth(0.0, t, &mut 0);
            // At the found point, up to one f32 step of depth (the field there times an ulp).
            let slack = r.sigma(t as f64) * (t.abs() * f32::EPSILON * 4.0) as f64;
            assert!(
                (got - target).abs() <= 1e-6 * target + slack,
                "{target}: {got} at {t}"
            );
        }
        assert_eq!(r.invert(0.0, 1.0, 2.0 * total, &mut 0), Err(total));
    }
}
