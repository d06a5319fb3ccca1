//! The binary tree the collapse reads ([`super::Collapse`]): obvhs' binary BVH (or a median
//! or sweep build where PLOC's is too deep or a small scene is better served) turned into
//! one-primitive leaves, with the cost scale that keeps SAH costs finite.

use glam::Vec3;
use obvhs::{
    aabb::Aabb,
    bvh2::{node::Bvh2Node, Bvh2},
};

use crate::build_prims::PrimBoxes;

/// A node of the binary BVH with every leaf holding exactly one primitive (multi-primitive
/// leaves of obvhs' tree are split, their box repeated).
#[derive(Clone, Copy, Debug)]
pub(super) struct Bin {
    /// The box as two `Vec3`s, not an [`Aabb`] (two padded `Vec3A`s): 32 bytes a node
    /// instead of 48, and the tree has two nodes per primitive (issue 36, peak memory).
    pub(super) min: Vec3,
    pub(super) max: Vec3,
    /// Children (inner node) or `[primitive, u32::MAX]` (leaf).
    pub(super) kids: [u32; 2],
}

impl Bin {
    pub(super) fn new(aabb: Aabb, kids: [u32; 2]) -> Self {
        Bin {
            min: aabb.min.into(),
            max: aabb.max.into(),
            kids,
        }
    }

    pub(super) fn aabb(&self) -> Aabb {
        Aabb::new(self.min.into(), self.max.into())
    }

    pub(super) fn is_leaf(&self) -> bool {
        self.kids[1] == u32::MAX
    }
}

/// The box of an obvhs node with its padding lanes zeroed: with obvhs' `small_bvh2_node`
/// (32-byte nodes, issue 36) they hold the node's primitive count and first index.
pub(crate) fn node_box(node: &Bvh2Node) -> Aabb {
    let b = node.aabb();
    Aabb::new(Vec3::from(b.min).into(), Vec3::from(b.max).into())
}

/// The power of two that maps the largest coordinate magnitude of `root` into `[1, 2)` (1
/// for a box at the origin): the SAH costs of the build are computed on boxes scaled by it.
///
/// Areas and volumes of boxes far from the origin or spanning more than about 1e13 units
/// overflow f32 (a half area beyond 3.4e38, the volume term's product `area * volume` beyond
/// it much earlier: a sphere of radius 1e8 suffices), and infinite costs make every choice a
/// tie, so the collapse put spheres and more than eight triangles in one leaf. Scaling by a
/// power of two is exact and multiplies every cost by the same power of two, so the trees of
/// scenes that did not overflow are unchanged, bit for bit.
pub(super) fn cost_scale(root: &Aabb) -> f32 {
    let m = root.min.abs().max(root.max.abs()).max_element();
    if !(m.is_finite() && m >= f32::MIN_POSITIVE) {
        return 1.0;
    }
    // 2^-floor(log2 m), built from the exponent bits (m is normal, so the result is a normal
    // power of two between 2^-127 and 2^126).
    let exponent = ((m.to_bits() >> 23) & 0xff) as i32 - 127;
    f32::from_bits(((127 - exponent) as u32) << 23)
}

/// `b` with both corners multiplied by `s` (a power of two: exact but for underflow).
pub(super) fn scaled(b: &Aabb, s: f32) -> Aabb {
    Aabb::new(b.min * s, b.max * s)
}

/// Deepest binary tree passed on to the collapse and to obvhs' CWBVH conversion (both
/// recurse over it). obvhs' PLOC builder makes a chain of `n` levels from `n` primitives with
/// equal boxes (a far-away mesh whose vertices round to a few points, thousands of copies of
/// one shape), which overflowed the stack; built trees of real scenes are far shallower.
pub(crate) const MAX_BVH2_DEPTH: usize = 256;

/// Number of node levels of `bvh2` on its longest root-to-leaf path.
pub(crate) fn bvh2_depth(bvh2: &Bvh2) -> usize {
    let mut depth = 0;
    let mut stack = vec![(0u32, 1usize)];
    while let Some((n, level)) = stack.pop() {
        depth = depth.max(level);
        let node = &bvh2.nodes[n as usize];
        if node.prim_count == 0 {
            stack.push((node.first_index, level + 1));
            stack.push((node.first_index + 1, level + 1));
        }
    }
    depth
}

/// A binary BVH over `aabbs` (primitive `indices[i]` has box `aabbs[i]`; at least one)
/// with one primitive per leaf, built top down by median splits: along the longest axis of
/// the centroid bounds, or by count when the centroids coincide. Depth `ceil(log2 n) + 1`
/// whatever the boxes: the fallback when PLOC's tree is deeper than [`MAX_BVH2_DEPTH`].
pub(crate) fn median_bvh2<P: PrimBoxes + ?Sized>(aabbs: &P, indices: &[u32]) -> Bvh2 {
    let mut prims: Vec<(Aabb, u32)> = (0..aabbs.count())
        .map(|i| aabbs.aabb(i))
        .zip(indices.iter().copied())
        .collect();
    let mut nodes = vec![Bvh2Node::default()];
    let mut primitive_indices = Vec::with_capacity(prims.len());
    let mut stack = vec![(0usize, prims.len(), 0usize)];
    while let Some((lo, hi, slot)) = stack.pop() {
        let set = &mut prims[lo..hi];
        let aabb = set.iter().fold(Aabb::INVALID, |a, p| a.union(&p.0));
        if set.len() == 1 {
            nodes[slot] = Bvh2Node::new(aabb, 1, primitive_indices.len() as u32);
            primitive_indices.push(set[0].1);
            continue;
        }
        let centroids = set.iter().fold(Aabb::INVALID, |a, p| {
            let mut a = a;
            a.extend(p.0.center());
            a
        });
        // Differences of f32 extents can overflow: compare them in f64.
        let extent = |a: usize| centroids.max[a] as f64 - centroids.min[a] as f64;
        let axis = (0..3)
            .max_by(|&a, &b| extent(a).total_cmp(&extent(b)))
            .expect("three axes");
        let mid = set.len() / 2;
        if extent(axis) > 0.0 {
            set.select_nth_unstable_by(mid, |a, b| {
                a.0.center_axis(axis).total_cmp(&b.0.center_axis(axis))
            });
        }
        let first = nodes.len();
        nodes.extend([Bvh2Node::default(); 2]);
        nodes[slot] = Bvh2Node::new(aabb, 0, first as u32);
        stack.push((lo + mid, hi, first + 1));
        stack.push((lo, lo + mid, first));
    }
    Bvh2 {
        nodes,
        primitive_indices,
        ..Default::default()
    }
}

/// Largest scene for which [`sweep_tree`] is tried (it sorts every node's primitives three
/// times).
pub(super) const SWEEP_MAX: usize = 4096;

/// Makes `out[slot]` an inner node with box `aabb` over two new (yet unfilled) slots
/// appended to `out`; returns the index of the first.
pub(super) fn split_slot(out: &mut Vec<Bin>, slot: usize, aabb: Aabb) -> usize {
    let l = out.len();
    let empty = Bin::new(Aabb::INVALID, [0, 0]);
    out.extend([empty, empty]);
    out[slot] = Bin::new(aabb, [l as u32, l as u32 + 1]);
    l
}

/// A binary tree over the primitives of `bvh2` by top-down full-sweep SAH (every centroid
/// split on every axis, cost `A(L) N(L) + A(R) N(R)`), from the primitive boxes of its
/// leaves.
pub(super) fn sweep_tree(bvh2: &Bvh2, s: f32) -> Vec<Bin> {
    let mut prims: Vec<(Aabb, u32)> = Vec::new();
    for n in &bvh2.nodes {
        for k in 0..n.prim_count {
            prims.push((
                node_box(n),
                bvh2.primitive_indices[(n.first_index + k) as usize],
            ));
        }
    }
    let mut out = vec![Bin::new(Aabb::INVALID, [0, 0])];
    let mut stack = vec![(0usize, prims.len(), 0usize)];
    let mut areas = vec![0.0f32; prims.len() + 1];
    while let Some((lo, hi, slot)) = stack.pop() {
        let set = &mut prims[lo..hi];
        let aabb = set.iter().fold(Aabb::INVALID, |a, p| a.union(&p.0));
        if set.len() == 1 {
            out[slot] = Bin::new(aabb, [set[0].1, u32::MAX]);
            continue;
        }
        let n = set.len();
        let mut best = (f32::INFINITY, 0usize, n / 2);
        for axis in 0..3 {
            set.sort_by(|a, b| a.0.center_axis(axis).total_cmp(&b.0.center_axis(axis)));
            let mut acc = Aabb::INVALID;
            for i in 0..n {
                acc = acc.union(&set[i].0);
                areas[i + 1] = scaled(&acc, s).half_area();
            }
            let mut acc = Aabb::INVALID;
            for i in (1..n).rev() {
                acc = acc.union(&set[i].0);
                let cost = areas[i] * i as f32 + scaled(&acc, s).half_area() * (n - i) as f32;
                if cost < best.0 {
                    best = (cost, axis, i);
                }
            }
        }
        let (_, axis, split) = best;
        set.sort_by(|a, b| a.0.center_axis(axis).total_cmp(&b.0.center_axis(axis)));
        let l = split_slot(&mut out, slot, aabb);
        stack.push((lo, lo + split, l));
        stack.push((lo + split, hi, l + 1));
    }
    out
}

/// Copies `bvh2` into one-primitive leaves; returns the nodes, root first.
pub(super) fn binary_tree(bvh2: &Bvh2) -> Vec<Bin> {
    let mut out = Vec::with_capacity(bvh2.nodes.len());
    // (bvh2 node or primitive range, output slot)
    enum Src {
        Node(u32),
        Prims(Aabb, u32, u32),
    }
    out.push(Bin::new(node_box(&bvh2.nodes[0]), [0, 0]));
    let mut stack = vec![(Src::Node(0), 0usize)];
    while let Some((src, slot)) = stack.pop() {
        let (aabb, kids) = match src {
            Src::Node(n) => {
                let node = &bvh2.nodes[n as usize];
                if node.prim_count == 0 {
                    (
                        node_box(node),
                        [Src::Node(node.first_index), Src::Node(node.first_index + 1)],
                    )
                } else {
                    let (first, count) = (node.first_index, node.prim_count);
                    if count == 1 {
                        out[slot] = Bin::new(
                            node_box(node),
                            [bvh2.primitive_indices[first as usize], u32::MAX],
                        );
                        continue;
                    }
                    let half = count / 2;
                    (
                        node_box(node),
                        [
                            Src::Prims(node_box(node), first, half),
                            Src::Prims(node_box(node), first + half, count - half),
                        ],
                    )
                }
            }
            Src::Prims(aabb, first, count) => {
                if count == 1 {
                    out[slot] = Bin::new(aabb, [bvh2.primitive_indices[first as usize], u32::MAX]);
                    continue;
                }
                let half = count / 2;
                (
                    aabb,
                    [
                        Src::Prims(aabb, first, half),
                        Src::Prims(aabb, first + half, count - half),
                    ],
                )
            }
        };
        let l = split_slot(&mut out, slot, aabb);
        let [a, b] = kids;
        stack.push((a, l));
        stack.push((b, l + 1));
    }
    out
}
