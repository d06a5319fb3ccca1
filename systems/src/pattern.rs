//! Patterns: the seed's pattern graph (what RIS evaluates for `EvalParam`), as plain data
//! and functions over columns.
//!
//! A [`PatternGraph`] is a list of [`Node`]s whose children are indices of **earlier**
//! nodes; the last node is the root. Plain data was chosen over boxed trees because
//! evaluation is batch-shaped: [`eval`] walks the list once, front to back, and each node
//! fills its whole column (a block of points) from its children's columns, with no per-point
//! recursion and no pointer chasing. "Children come first" also makes cycles unrepresentable
//! ([`PatternGraph::new`] checks it).
//!
//! Every node gives a colour per point from the builtins `P` (world position), `u` and `v`:
//! `constant`, `noise` (Perlin 2002 / fBm, grey), `checker`, `gradient`, `image`, `grid`,
//! and the combinators `mix`, `multiply`, `scale`, `remap`, per channel.
//!
//! [`bounds`] gives conservative per-channel bounds of a graph over a box of `P` (any `u`,
//! `v`), for majorant grids and for checking a parameter's range at load time.
//!
//! ```
//! use risotto_systems::pattern::*;
//! use risotto_components::Rgb;
//! use glam::Vec3;
//! // mix(black, white, t = checker): a checker by P, 2 cells per unit.
//! let g = PatternGraph::new(vec![
//!     Node::Constant(Rgb::BLACK),
//!     Node::Constant(Rgb::WHITE),
//!     Node::Checker { scale: 2.0, a: Rgb::splat(0.0), b: Rgb::splat(1.0), space: Space::P },
//!     Node::Mix { a: 0, b: 1, t: 2 },
//! ]).unwrap();
//! let p = [Vec3::new(0.25, 0.0, 0.0), Vec3::new(0.75, 0.0, 0.0)];
//! let mut out = [Rgb::BLACK; 2];
//! eval(&g, &p, &[0.0; 2], &[0.0; 2], &mut out);
//! assert_eq!(out, [Rgb::BLACK, Rgb::WHITE]);
//! let (lo, hi) = bounds(&g, Vec3::splat(0.0), Vec3::splat(0.4));
//! assert_eq!((lo, hi), (Rgb::BLACK, Rgb::BLACK)); // one cell: exact
//! ```

mod noise;
mod texture;

pub use noise::{perlin, Fbm, MAX_OCTAVES, PERLIN_BOUND, PERLIN_SLOPE};
pub use texture::{ImageLookup, Texture, TextureFilter, Wrap};

use crate::grid::DensityGrid;
use glam::Vec3;
use risotto_components::Rgb;
use std::sync::Arc;

/// A graph or node that cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PatternError {
    /// The graph's structure (empty, or a child that is not an earlier node).
    #[error("pattern graph: {0}")]
    Structure(String),
    /// A node's parameter.
    #[error("{0}")]
    Parameter(String),
}

/// What a `checker` is laid out over.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Space {
    /// World position: the parity of `floor(s x) + floor(s y) + floor(s z)`.
    P,
    /// Surface parameters: the parity of `floor(s u) + floor(s v)`.
    Uv,
}

/// The coordinate a `gradient` runs along.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    /// `P.x`.
    X,
    /// `P.y`.
    Y,
    /// `P.z`.
    Z,
    /// `u`.
    U,
    /// `v`.
    V,
}

/// Index of a node in its graph.
pub type NodeId = u32;

/// What a [`Node::Grid`] reads beyond its outermost voxel centres and outside its box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridBorder {
    /// The outermost voxels extend: outside the box the faces extend outward (Mitsuba 3's
    /// `clamp` wrap mode, the convention of risotto's grid media).
    Clamp,
    /// Voxels beyond the grid read 0 and the pattern is 0 outside the box: pbrt-v4's
    /// `SampledGrid` in its cuboid media (`GridMedium`). The node's grid is then the file's
    /// grid [padded with one voxel of 0](DensityGrid::padded_with_zeros), the box being the
    /// unpadded grid's.
    Zero,
    /// The outermost voxels extend up to the box's faces, and the pattern is 0 outside the
    /// box: Mitsuba 3's heterogeneous medium, which exists only inside its grid's box (its
    /// lookups clamp there).
    ClampInBox,
}

/// One node of a [`PatternGraph`].
#[derive(Clone, Debug, PartialEq)]
#[allow(
    clippy::large_enum_variant,
    reason = "graphs hold a handful of nodes, built once per scene; the fBm's tables stay \
              inline, next to the node its lookups read (no pointer chased per shading point)"
)]
pub enum Node {
    /// One colour everywhere.
    Constant(Rgb),
    /// fBm of Perlin noise at `P`, grey (all channels equal), signed: in
    /// `[-fbm.bound(), fbm.bound()]` and 0 at the lattice points of a one-octave noise.
    Noise(Fbm),
    /// `a` on cells of even parity, `b` on odd ones; cells are `1 / scale` wide.
    Checker {
        /// Cells per unit, > 0.
        scale: f32,
        /// Colour of even cells (the one holding the origin).
        a: Rgb,
        /// Colour of odd cells.
        b: Rgb,
        /// Over `P` or `(u, v)`.
        space: Space,
    },
    /// `lerp(a, b, t)` with `t = clamp((c - from) / (to - from), 0, 1)`, `c` the axis'
    /// coordinate.
    Gradient {
        /// The coordinate.
        axis: Axis,
        /// Where `a` is reached.
        from: f32,
        /// Where `b` is reached (`!= from`).
        to: f32,
        /// Colour at `from` and before.
        a: Rgb,
        /// Colour at `to` and after.
        b: Rgb,
    },
    /// A texture by `(u, v)` ([`Texture::lookup_with`]), shared with every graph naming its
    /// file, read as the [`ImageLookup`] says.
    Image(Arc<Texture>, ImageLookup),
    /// A density grid placed in the box `[min, max]` of `P` (its unit cube mapped onto the
    /// box; outside, the grid's clamp convention extends the faces), grey. With `to_box`, the
    /// box is in a space of its own: `P` is first mapped by `to_box` (world to box space; the
    /// inverse of the box's placement), so a grid can be rotated, mirrored or sheared.
    Grid {
        /// The grid (shared with every graph and medium naming its file).
        grid: Arc<DensityGrid>,
        /// The box's low corner.
        min: Vec3,
        /// The box's high corner (> `min` on every axis).
        max: Vec3,
        /// World to box space (`None`: the box is in world space, the common case, which
        /// then costs no transform).
        to_box: Option<glam::Affine3A>,
        /// What the grid reads beyond its edge and outside the box.
        border: GridBorder,
    },
    /// `a + (b - a) t` per channel, `t` clamped to [0, 1].
    Mix {
        /// At `t = 0`.
        a: NodeId,
        /// At `t = 1`.
        b: NodeId,
        /// The blend.
        t: NodeId,
    },
    /// `a b` per channel.
    Multiply {
        /// A factor.
        a: NodeId,
        /// The other factor.
        b: NodeId,
    },
    /// `a + b` per channel.
    Add {
        /// A term.
        a: NodeId,
        /// The other term.
        b: NodeId,
    },
    /// `a / (a + b)` per channel, 0 where `a + b` is 0 (a fraction of two non-negative
    /// fields, such as a scattering albedo `sigma_s / (sigma_s + sigma_a)` from interpolated
    /// coefficients; in [0, 1] when both inputs are >= 0).
    Fraction {
        /// The part.
        a: NodeId,
        /// The rest.
        b: NodeId,
    },
    /// `a factor` per channel.
    Scale {
        /// The input.
        a: NodeId,
        /// Per-channel factor, finite and >= 0.
        factor: Rgb,
    },
    /// `to[0] + (to[1] - to[0]) clamp((a - from[0]) / (from[1] - from[0]), 0, 1)` per
    /// channel.
    Remap {
        /// The input.
        a: NodeId,
        /// The input range (`from[0] != from[1]`).
        from: [f32; 2],
        /// The output range.
        to: [f32; 2],
    },
    /// `max(a, 0)^exponent` per channel (pbrt-v4's `remaproughness`, `alpha =
    /// sqrt(roughness)`, on a roughness texture is `exponent = 0.5`).
    Power {
        /// The input.
        a: NodeId,
        /// The exponent, finite and > 0.
        exponent: f32,
    },
}

impl Node {
    /// The node's children.
    fn children(&self) -> impl Iterator<Item = NodeId> {
        let (a, b, c) = match *self {
            Node::Mix { a, b, t } => (Some(a), Some(b), Some(t)),
            Node::Multiply { a, b } | Node::Add { a, b } | Node::Fraction { a, b } => {
                (Some(a), Some(b), None)
            }
            Node::Scale { a, .. } | Node::Remap { a, .. } | Node::Power { a, .. } => {
                (Some(a), None, None)
            }
            _ => (None, None, None),
        };
        [a, b, c].into_iter().flatten()
    }

    /// Checks the parameters a [`Node`] literal may get wrong (those of [`Fbm`] and
    /// [`Texture`] are checked by their constructors).
    fn check(&self) -> Result<(), PatternError> {
        let bad = |m: String| Err(PatternError::Parameter(m));
        let colour_ok = |c: Rgb| c.is_finite() && c.min_channel() >= 0.0;
        match *self {
            Node::Constant(c) if !c.is_finite() => bad(format!("constant: {c:?} is not finite")),
            Node::Checker { scale, a, b, .. } => {
                if !(scale.is_finite() && scale > 0.0) {
                    bad(format!("checker: scale must be > 0, got {scale}"))
                } else if !(a.is_finite() && b.is_finite()) {
                    bad("checker: colours must be finite".into())
                } else {
                    Ok(())
                }
            }
            Node::Gradient { from, to, a, b, .. } => {
                if !(from.is_finite() && to.is_finite()) || from == to {
                    bad(format!(
                        "gradient: from and to must be finite and differ, got {from} and {to}"
                    ))
                } else if !(a.is_finite() && b.is_finite()) {
                    bad("gradient: colours must be finite".into())
                } else {
                    Ok(())
                }
            }
            Node::Grid { min, max, .. }
                if !(min.is_finite() && max.is_finite() && min.cmplt(max).all()) =>
            {
                bad(format!(
                    "grid: the box needs min < max on every axis, got {min} and {max}"
                ))
            }
            Node::Grid {
                to_box: Some(t), ..
            } if !t.is_finite() => bad(format!("grid: the box's transform {t} is not finite")),
            Node::Grid {
                ref grid,
                border: GridBorder::Zero,
                ..
            } if grid.dims().iter().any(|&d| d < 3) => bad(format!(
                "grid: a zero-border grid holds its padding (at least 3 voxels per axis), got {:?}",
                grid.dims()
            )),
            Node::Scale { factor, .. } if !colour_ok(factor) => {
                bad(format!("scale: factor {factor:?} must be finite and >= 0"))
            }
            Node::Power { exponent, .. } if !(exponent.is_finite() && exponent > 0.0) => bad(
                format!("power: exponent must be finite and > 0, got {exponent}"),
            ),
            Node::Remap { from, to, .. } => {
                if !(from.iter().chain(&to).all(|v| v.is_finite())) {
                    bad(format!(
                        "remap: ranges must be finite, got {from:?} -> {to:?}"
                    ))
                } else if from[0] == from[1] {
                    bad(format!(
                        "remap: the input range is empty ({} == {})",
                        from[0], from[1]
                    ))
                } else {
                    Ok(())
                }
            }
            _ => Ok(()),
        }
    }
}

/// A pattern graph: nodes in evaluation order, each child an earlier node, the root last
/// (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct PatternGraph {
    nodes: Vec<Node>,
}

/// Points per block of [`eval`]: one scratch column per node of this many colours.
pub const BLOCK: usize = 256;

impl PatternGraph {
    /// A graph from its nodes (root last); errors for an empty list, a child that is not an
    /// earlier node, or an invalid parameter.
    pub fn new(nodes: Vec<Node>) -> Result<PatternGraph, PatternError> {
        if nodes.is_empty() {
            return Err(PatternError::Structure("no nodes".into()));
        }
        for (i, node) in nodes.iter().enumerate() {
            node.check()?;
            if let Some(c) = node.children().find(|&c| c as usize >= i) {
                return Err(PatternError::Structure(format!(
                    "node {i} refers to node {c}, which is not an earlier node"
                )));
            }
        }
        Ok(PatternGraph { nodes })
    }

    /// The nodes, root last.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// Whether any node reads `u` or `v` (the renderer then computes them for hits).
    pub fn reads_uv(&self) -> bool {
        self.nodes.iter().any(|n| {
            matches!(
                n,
                Node::Image(..)
                    | Node::Checker {
                        space: Space::Uv,
                        ..
                    }
                    | Node::Gradient {
                        axis: Axis::U | Axis::V,
                        ..
                    }
            )
        })
    }

    /// Whether every value of the graph is grey (equal channels) at every point: its
    /// leaves are grey (constants and the colours of `checker` and `gradient` with equal
    /// channels; `noise` and `grid` always) and its `scale` factors are grey (`mix`,
    /// `multiply` and `remap` act per channel, so they keep grey inputs grey). An `image`
    /// is grey when every texel is (checked once when it was read).
    pub fn is_grey(&self) -> bool {
        let grey = |c: &Rgb| c.r == c.g && c.g == c.b;
        self.nodes.iter().all(|n| match n {
            Node::Constant(c) => grey(c),
            Node::Checker { a, b, .. } | Node::Gradient { a, b, .. } => grey(a) && grey(b),
            Node::Scale { factor, .. } => grey(factor),
            Node::Image(t, _) => t.is_grey(),
            Node::Noise(_)
            | Node::Grid { .. }
            | Node::Mix { .. }
            | Node::Multiply { .. }
            | Node::Add { .. }
            | Node::Fraction { .. }
            | Node::Remap { .. }
            | Node::Power { .. } => true,
        })
    }

    /// The root's value if the graph is a single constant.
    pub fn as_constant(&self) -> Option<Rgb> {
        match self.nodes.as_slice() {
            [Node::Constant(c)] => Some(*c),
            _ => None,
        }
    }

    /// Scratch colours [`eval_with`] needs for `n` points.
    pub fn scratch_len(&self, n: usize) -> usize {
        (self.nodes.len() - 1) * n.min(BLOCK)
    }
}

/// Evaluates `graph` at every point (`p[i]`, `u[i]`, `v[i]`) into `out[i]`, allocating its
/// scratch columns; see [`eval_with`].
pub fn eval(graph: &PatternGraph, p: &[Vec3], u: &[f32], v: &[f32], out: &mut [Rgb]) {
    let mut scratch = vec![Rgb::BLACK; graph.scratch_len(out.len())];
    eval_with(graph, p, u, v, out, &mut scratch);
}

/// Evaluates `graph` over columns: blocks of up to [`BLOCK`] points, and within a block node
/// after node, each over the whole block. `scratch` holds the non-root nodes' columns (at
/// least [`PatternGraph::scratch_len`] colours; the caller's arena, say).
///
/// # Panics
/// When the columns differ in length or `scratch` is too short (caller bugs, not input).
pub fn eval_with(
    graph: &PatternGraph,
    p: &[Vec3],
    u: &[f32],
    v: &[f32],
    out: &mut [Rgb],
    scratch: &mut [Rgb],
) {
    let n = out.len();
    assert!(
        p.len() == n && u.len() == n && v.len() == n,
        "one P, u, v per output"
    );
    assert!(
        scratch.len() >= graph.scratch_len(n),
        "scratch too short for the graph"
    );
    let (root, inner) = graph.nodes.split_last().expect("graphs are never empty");
    for start in (0..n).step_by(BLOCK) {
        let end = (start + BLOCK).min(n);
        let m = end - start;
        let (p, u, v) = (&p[start..end], &u[start..end], &v[start..end]);
        let columns = &mut scratch[..inner.len() * m];
        for (i, node) in inner.iter().enumerate() {
            let (done, rest) = columns.split_at_mut(i * m);
            eval_node(node, done, m, p, u, v, &mut rest[..m]);
        }
        eval_node(root, columns, m, p, u, v, &mut out[start..end]);
    }
}

/// Fills `out` (one block of `m` points) with `node`'s values; `done` holds the columns of
/// the earlier nodes, `m` colours each.
fn eval_node(
    node: &Node,
    done: &[Rgb],
    m: usize,
    p: &[Vec3],
    u: &[f32],
    v: &[f32],
    out: &mut [Rgb],
) {
    let col = |id: NodeId| &done[id as usize * m..(id as usize + 1) * m];
    match node {
        Node::Constant(c) => out.fill(*c),
        Node::Noise(fbm) => {
            for (o, p) in out.iter_mut().zip(p) {
                *o = Rgb::splat(fbm.eval(*p));
            }
        }
        Node::Checker { scale, a, b, space } => {
            for i in 0..m {
                let odd = match space {
                    Space::P => cell_parity(p[i].x * scale, p[i].y * scale, p[i].z * scale),
                    Space::Uv => cell_parity(u[i] * scale, v[i] * scale, 0.0),
                };
                out[i] = if odd { *b } else { *a };
            }
        }
        Node::Gradient {
            axis,
            from,
            to,
            a,
            b,
        } => {
            for i in 0..m {
                let c = match axis {
                    Axis::X => p[i].x,
                    Axis::Y => p[i].y,
                    Axis::Z => p[i].z,
                    Axis::U => u[i],
                    Axis::V => v[i],
                };
                out[i] = gradient_at(c, *from, *to, *a, *b);
            }
        }
        Node::Image(texture, how) => {
            if *how == ImageLookup::default() {
                for i in 0..m {
                    out[i] = texture.lookup(u[i], v[i]);
                }
            } else {
                for i in 0..m {
                    out[i] = texture.lookup_with(u[i], v[i], how);
                }
            }
        }
        Node::Grid {
            grid,
            min,
            max,
            to_box,
            border,
        } => {
            let extent = *max - *min;
            // The lookup is a convex combination of voxels; the clamp keeps rounding within
            // the grid's range, which the bounds rely on.
            let at = |q: Vec3| {
                let u = (q - *min) / extent;
                Rgb::splat(match border {
                    GridBorder::Clamp => grid.lookup(u).min(grid.max()),
                    GridBorder::Zero => zero_border_lookup(grid, u),
                    GridBorder::ClampInBox if in_unit_box(u) => grid.lookup(u).min(grid.max()),
                    GridBorder::ClampInBox => 0.0,
                })
            };
            match to_box {
                None => {
                    for (o, p) in out.iter_mut().zip(p) {
                        *o = at(*p);
                    }
                }
                Some(t) => {
                    for (o, p) in out.iter_mut().zip(p) {
                        *o = at(t.transform_point3(*p));
                    }
                }
            }
        }
        Node::Mix { a, b, t } => {
            for ((o, (a, b)), t) in out.iter_mut().zip(col(*a).iter().zip(col(*b))).zip(col(*t)) {
                *o = zip3(*a, *b, *t, mix);
            }
        }
        Node::Multiply { a, b } => {
            for (o, (a, b)) in out.iter_mut().zip(col(*a).iter().zip(col(*b))) {
                *o = *a * *b;
            }
        }
        Node::Add { a, b } => {
            for (o, (a, b)) in out.iter_mut().zip(col(*a).iter().zip(col(*b))) {
                *o = *a + *b;
            }
        }
        Node::Fraction { a, b } => {
            for (o, (a, b)) in out.iter_mut().zip(col(*a).iter().zip(col(*b))) {
                *o = zip2(*a, *b, fraction);
            }
        }
        Node::Scale { a, factor } => {
            for (o, a) in out.iter_mut().zip(col(*a)) {
                *o = *a * *factor;
            }
        }
        Node::Remap { a, from, to } => {
            for (o, a) in out.iter_mut().zip(col(*a)) {
                *o = a.map(|x| remap(x, *from, *to));
            }
        }
        Node::Power { a, exponent } => {
            for (o, a) in out.iter_mut().zip(col(*a)) {
                *o = a.map(|x| power(x, *exponent));
            }
        }
    }
}

/// Whether `floor(x) + floor(y) + floor(z)` is odd (saturating casts: defined for any input,
/// NaN reads as cell 0).
#[inline]
pub(crate) fn cell_parity(x: f32, y: f32, z: f32) -> bool {
    let c = |t: f32| t.floor() as i64;
    (c(x).wrapping_add(c(y)).wrapping_add(c(z))) & 1 == 1
}

/// The gradient's colour at coordinate `c` (NaN reads as `from`).
#[inline]
pub(crate) fn gradient_at(c: f32, from: f32, to: f32, a: Rgb, b: Rgb) -> Rgb {
    let t = unit((c - from) / (to - from));
    zip3(a, b, Rgb::splat(t), mix)
}

/// `a + (b - a) t`, `t` clamped to [0, 1]; the result is clamped to `[min(a, b), max(a, b)]`,
/// where it lies mathematically, so that rounding never leaves the hull the bounds assume.
#[inline]
pub(crate) fn mix(a: f32, b: f32, t: f32) -> f32 {
    let t = unit(t);
    (a + (b - a) * t).max(a.min(b)).min(a.max(b))
}

/// The remap of one channel (monotone in `x`: every step is).
#[inline]
pub(crate) fn remap(x: f32, from: [f32; 2], to: [f32; 2]) -> f32 {
    let t = unit((x - from[0]) / (from[1] - from[0]));
    to[0] + (to[1] - to[0]) * t
}

/// `max(x, 0)^exponent` (NaN reads as 0): increasing in `x`, so the bounds of an
/// interval are the powers of its ends.
#[inline]
pub(crate) fn power(x: f32, exponent: f32) -> f32 {
    x.max(0.0).powf(exponent)
}

/// `t` clamped to [0, 1], NaN to 0 (`f32::clamp` keeps NaN).
#[inline]
fn unit(t: f32) -> f32 {
    if t >= 0.0 {
        t.min(1.0)
    } else {
        0.0
    }
}

#[inline]
fn zip3(a: Rgb, b: Rgb, c: Rgb, f: impl Fn(f32, f32, f32) -> f32) -> Rgb {
    Rgb::new(f(a.r, b.r, c.r), f(a.g, b.g, c.g), f(a.b, b.b, c.b))
}

mod bounds;
pub use bounds::bounds;

#[cfg(test)]
mod tests;

/// A [`GridBorder::Zero`] node's value at unit-box coordinates `u` of its padded `grid`: 0
/// outside the box, else the padded grid read at the same cell centres (`(u n + 1) / (n + 2)`
/// on an axis of `n` inner voxels).
#[inline]
pub(crate) fn zero_border_lookup(grid: &DensityGrid, u: Vec3) -> f32 {
    if !in_unit_box(u) {
        return 0.0;
    }
    grid.lookup(padded_coordinates(grid, u)).min(grid.max())
}

/// Whether unit-box coordinates `u` lie in the box, faces included.
#[inline]
pub(crate) fn in_unit_box(u: Vec3) -> bool {
    u.cmpge(Vec3::ZERO).all() && u.cmple(Vec3::ONE).all()
}

/// Unit coordinates `u` of an inner grid as coordinates of its zero-padded `grid`.
#[inline]
pub(crate) fn padded_coordinates(grid: &DensityGrid, u: Vec3) -> Vec3 {
    let d = grid.dims();
    let n = Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32);
    (u * (n - 2.0) + 1.0) / n
}

/// `a / (a + b)`, 0 where `a + b` is not > 0, clamped to [0, 1] (rounding).
#[inline]
pub(crate) fn fraction(a: f32, b: f32) -> f32 {
    let sum = a + b;
    if sum > 0.0 {
        (a / sum).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// `f` per channel of `a` and `b`.
#[inline]
fn zip2(a: Rgb, b: Rgb, f: impl Fn(f32, f32) -> f32) -> Rgb {
    Rgb::new(f(a.r, b.r), f(a.g, b.g), f(a.b, b.b))
}
