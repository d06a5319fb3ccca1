//! Interval bounds of a pattern graph over a box of `P` (any `u`, `v`): per node, per
//! channel, front to back like [`super::eval`], combinators by interval arithmetic.
//!
//! Every bound is conservative in floating point, not only in real arithmetic: where a node
//! is a composition of monotone steps (gradient, remap, scale, a product in one sign
//! quadrant), rounding is monotone too, so the node evaluated at the interval's ends bounds
//! it evaluated anywhere inside; where it interpolates (grid, mix), the bound is widened by
//! a few ulps of its magnitude, within a hull the node clamps its values to.

use super::{
    cell_parity, gradient_at, mix, power, remap, Axis, GridBorder, Node, PatternGraph, Space,
};
use crate::grid::DensityGrid;
use glam::Vec3;
use risotto_components::Rgb;

/// Per-channel `(lo, hi)`.
type Interval = (Rgb, Rgb);

/// Relative widening of interpolating nodes: eight ulps of the values' magnitude covers
/// the rounding of a lerp (`a + (b - a) t`: three roundings of at most half an ulp of
/// `2 max(|a|, |b|)`) at the evaluated point and at the interval's ends.
const WIDEN: f32 = 8.0 * f32::EPSILON;

/// Conservative per-channel bounds `(lo, hi)` of `graph`'s value at every `P` in the box
/// `[lo, hi]` (infinite corners allowed; a NaN corner reads as unbounded) and every `u`, `v`:
///
/// - `constant`: exact. `checker` by `P`: exact (one colour when the box lies in one cell,
///   both otherwise); by `uv`: both colours. `gradient` along `x`/`y`/`z`: exact (the colours
///   at the box's two ends on the axis); along `u`/`v`: the two colours.
/// - `noise`: per octave, the value at the box's centre plus or minus a Lipschitz bound
///   times the box's half-extents, within `+-PERLIN_BOUND` ([`super::Fbm::bounds_over`]);
///   over an unbounded box `+-PERLIN_BOUND sum_k gain^k` ([`super::Fbm::bound`]).
/// - `image`: the texture's per-channel range. `grid`: the min and max of the voxels whose
///   trilinear support meets the box (after the box is mapped into the grid's unit cube and
///   clamped like the lookup).
/// - `mix`: the extremes of `a + (b - a) t` over the corners of the three intervals (the
///   expression is multilinear in `a`, `b`, `t`), within the hull of `a` and `b`;
///   `multiply`: the extremes of the four end products; `scale`, `remap`: the ends mapped.
pub fn bounds(graph: &PatternGraph, lo: Vec3, hi: Vec3) -> (Rgb, Rgb) {
    let lo = Vec3::select(lo.is_nan_mask(), Vec3::NEG_INFINITY, lo);
    let hi = Vec3::select(hi.is_nan_mask(), Vec3::INFINITY, hi);
    let mut done: Vec<Interval> = Vec::with_capacity(graph.nodes.len());
    for node in &graph.nodes {
        let b = node_bounds(node, &done, lo, hi);
        done.push(b);
    }
    done[done.len() - 1]
}

fn node_bounds(node: &Node, done: &[Interval], lo: Vec3, hi: Vec3) -> Interval {
    let at = |id: u32| done[id as usize];
    match node {
        Node::Constant(c) => (*c, *c),
        Node::Noise(fbm) => {
            let (l, h) = fbm.bounds_over(lo, hi);
            (Rgb::splat(l), Rgb::splat(h))
        }
        Node::Checker { scale, a, b, space } => {
            let both = hull(*a, *b);
            if *space == Space::Uv {
                return both;
            }
            let (l, h) = (lo * *scale, hi * *scale);
            let cell = |x: f32| x.floor() as i64;
            let one_cell =
                cell(l.x) == cell(h.x) && cell(l.y) == cell(h.y) && cell(l.z) == cell(h.z);
            if one_cell {
                let c = if cell_parity(l.x, l.y, l.z) { *b } else { *a };
                (c, c)
            } else {
                both
            }
        }
        Node::Gradient {
            axis,
            from,
            to,
            a,
            b,
        } => {
            let (c0, c1) = match axis {
                Axis::X => (lo.x, hi.x),
                Axis::Y => (lo.y, hi.y),
                Axis::Z => (lo.z, hi.z),
                Axis::U | Axis::V => return hull(*a, *b),
            };
            hull(
                gradient_at(c0, *from, *to, *a, *b),
                gradient_at(c1, *from, *to, *a, *b),
            )
        }
        Node::Image(texture, _) => texture.range(),
        Node::Grid {
            grid,
            min,
            max,
            to_box,
            border,
        } => {
            let extent = *max - *min;
            // In box space the region is the bounding box of its eight mapped corners (an
            // affine map takes the box to a parallelepiped inside that box).
            let (lo, hi) = match to_box {
                None => (lo, hi),
                // An unbounded region (an infinite corner, or 0 x inf in the map) may reach
                // every voxel.
                Some(_) if !(lo.is_finite() && hi.is_finite()) => {
                    (Vec3::NEG_INFINITY, Vec3::INFINITY)
                }
                Some(t) => (0..8).fold(
                    (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                    |(l, h), i| {
                        let c = Vec3::new(
                            if i & 1 == 0 { lo.x } else { hi.x },
                            if i & 2 == 0 { lo.y } else { hi.y },
                            if i & 4 == 0 { lo.z } else { hi.z },
                        );
                        let q = t.transform_point3(c);
                        (l.min(q), h.max(q))
                    },
                ),
            };
            let (ulo, uhi) = ((lo - *min) / extent, (hi - *min) / extent);
            let (g0, g1) = match border {
                GridBorder::Clamp => grid_range(grid, ulo, uhi),
                GridBorder::Zero | GridBorder::ClampInBox => {
                    // 0 outside the box; inside, the grid over the clamped region (the padded
                    // grid's coordinates for a zero border).
                    let leaves = !(super::in_unit_box(ulo) && super::in_unit_box(uhi));
                    let (mut a, mut b) = (
                        ulo.clamp(Vec3::ZERO, Vec3::ONE),
                        uhi.clamp(Vec3::ZERO, Vec3::ONE),
                    );
                    if *border == GridBorder::Zero {
                        a = super::padded_coordinates(grid, a);
                        b = super::padded_coordinates(grid, b);
                    }
                    let (g0, g1) = grid_range(grid, a, b);
                    (if leaves { 0.0 } else { g0 }, g1)
                }
            };
            // Widened for the lerps' rounding, within the grid's range [0, max], to which
            // the node clamps.
            let (l, h) = widen((Rgb::splat(g0), Rgb::splat(g1)));
            (l.map(|v| v.max(0.0)), h.map(|v| v.min(grid.max())))
        }
        Node::Mix { a, b, t } => {
            let (a, b, t) = (at(*a), at(*b), at(*t));
            let channel = |al: f32, ah: f32, bl: f32, bh: f32, tl: f32, th: f32| {
                // Exact cases: `t <= 0` everywhere gives `a` itself (`a + (b - a) 0`), and
                // three points give the one value the same arithmetic computes.
                if th <= 0.0 {
                    return (al, ah);
                }
                if al == ah && bl == bh && tl == th {
                    let v = mix(al, bl, tl);
                    return (v, v);
                }
                let (mut l, mut h) = (f32::INFINITY, f32::NEG_INFINITY);
                for a in [al, ah] {
                    for b in [bl, bh] {
                        for t in [tl, th] {
                            let v = mix(a, b, t);
                            l = l.min(v);
                            h = h.max(v);
                        }
                    }
                }
                let m = al.abs().max(ah.abs()).max(bl.abs()).max(bh.abs());
                let (hull_lo, hull_hi) = (al.min(bl), ah.max(bh));
                ((l - WIDEN * m).max(hull_lo), (h + WIDEN * m).min(hull_hi))
            };
            per_channel(a, b, t, channel)
        }
        Node::Add { a, b } => {
            let ((al, ah), (bl, bh)) = (at(*a), at(*b));
            let (l, h) = widen((al + bl, ah + bh));
            // The sum of two non-negative floats is never below 0: no widening there.
            let floor = |l: f32, x: f32, y: f32| if x >= 0.0 && y >= 0.0 { l.max(0.0) } else { l };
            (
                Rgb::new(
                    floor(l.r, al.r, bl.r),
                    floor(l.g, al.g, bl.g),
                    floor(l.b, al.b, bl.b),
                ),
                h,
            )
        }
        Node::Fraction { a, b } => {
            // Increasing in `a`, decreasing in `b` (for non-negative inputs): the corners
            // give the range; anything below 0 or unbounded reads as the whole of [0, 1].
            let ((al, ah), (bl, bh)) = (at(*a), at(*b));
            let ch = |al: f32, ah: f32, bl: f32, bh: f32| {
                if !(al >= 0.0 && bl >= 0.0 && ah.is_finite() && bh.is_finite()) {
                    return (0.0, 1.0);
                }
                (
                    super::fraction(al, bh) * (1.0 - WIDEN),
                    (super::fraction(ah, bl) * (1.0 + WIDEN)).min(1.0),
                )
            };
            let r = ch(al.r, ah.r, bl.r, bh.r);
            let g = ch(al.g, ah.g, bl.g, bh.g);
            let bb = ch(al.b, ah.b, bl.b, bh.b);
            (Rgb::new(r.0, g.0, bb.0), Rgb::new(r.1, g.1, bb.1))
        }
        Node::Multiply { a, b } => {
            let (a, b) = (at(*a), at(*b));
            let ch = |al: f32, ah: f32, bl: f32, bh: f32, _: f32, _: f32| {
                let p = [al * bl, al * bh, ah * bl, ah * bh];
                if p.iter().any(|v| v.is_nan()) {
                    return (f32::NEG_INFINITY, f32::INFINITY);
                }
                (
                    p.iter().copied().fold(f32::INFINITY, f32::min),
                    p.iter().copied().fold(f32::NEG_INFINITY, f32::max),
                )
            };
            per_channel(a, b, (Rgb::BLACK, Rgb::BLACK), ch)
        }
        Node::Scale { a, factor } => {
            let (l, h) = at(*a);
            (l * *factor, h * *factor)
        }
        Node::Power { a, exponent } => {
            let (l, h) = at(*a);
            (
                l.map(|x| power(x, *exponent)),
                h.map(|x| power(x, *exponent)),
            )
        }
        Node::Remap { a, from, to } => {
            let (l, h) = at(*a);
            hull(
                l.map(|x| remap(x, *from, *to)),
                h.map(|x| remap(x, *from, *to)),
            )
        }
    }
}

/// Per-channel `[min(a, b), max(a, b)]`.
fn hull(a: Rgb, b: Rgb) -> Interval {
    (
        Rgb::new(a.r.min(b.r), a.g.min(b.g), a.b.min(b.b)),
        Rgb::new(a.r.max(b.r), a.g.max(b.g), a.b.max(b.b)),
    )
}

/// The interval widened by [`WIDEN`] of its magnitude on both sides.
fn widen((l, h): Interval) -> Interval {
    let m = |l: f32, h: f32| WIDEN * l.abs().max(h.abs());
    (
        Rgb::new(l.r - m(l.r, h.r), l.g - m(l.g, h.g), l.b - m(l.b, h.b)),
        Rgb::new(h.r + m(l.r, h.r), h.g + m(l.g, h.g), h.b + m(l.b, h.b)),
    )
}

/// Applies `f(al, ah, bl, bh, cl, ch) -> (lo, hi)` to each channel of three intervals.
fn per_channel(
    a: Interval,
    b: Interval,
    c: Interval,
    f: impl Fn(f32, f32, f32, f32, f32, f32) -> (f32, f32),
) -> Interval {
    let [al, ah, bl, bh, cl, ch] = [a.0, a.1, b.0, b.1, c.0, c.1].map(Rgb::to_array);
    let mut lo = [0.0; 3];
    let mut hi = [0.0; 3];
    for k in 0..3 {
        (lo[k], hi[k]) = f(al[k], ah[k], bl[k], bh[k], cl[k], ch[k]);
    }
    (Rgb::from_array(lo), Rgb::from_array(hi))
}

/// Min and max of the voxels the trilinear lookup can read at any `uvw` in `[lo, hi]`
/// (unit-cube coordinates of the grid).
fn grid_range(grid: &DensityGrid, lo: Vec3, hi: Vec3) -> (f32, f32) {
    let dims = grid.dims();
    let (x0, x1) = support(lo.x, hi.x, dims[0]);
    let (y0, y1) = support(lo.y, hi.y, dims[1]);
    let (z0, z1) = support(lo.z, hi.z, dims[2]);
    let (mut l, mut h) = (f32::INFINITY, 0.0f32);
    for z in z0..=z1 {
        for y in y0..=y1 {
            for x in x0..=x1 {
                let v = grid.voxel(x, y, z);
                l = l.min(v);
                h = h.max(v);
            }
        }
    }
    (l, h)
}

/// The voxel index range the lookup reads for coordinates in `[lo, hi]` on an axis of `n`
/// cell-centred voxels: the lookup's own index arithmetic (`grid.rs`'s `axis`) at both ends,
/// which is monotone in the coordinate. NaN ends read as the whole axis.
fn support(lo: f32, hi: f32, n: usize) -> (usize, usize) {
    let last = (n - 1) as f32;
    let g = |u: f32| (u * n as f32 - 0.5).max(0.0).min(last);
    let index = |g: f32| (g as usize).min(n.saturating_sub(2));
    let (l, h) = if lo.is_nan() || hi.is_nan() {
        (0.0, last)
    } else {
        (g(lo), g(hi))
    };
    (index(l), (index(h) + 1).min(n - 1))
}
