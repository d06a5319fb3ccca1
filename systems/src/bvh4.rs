//! An uncompressed 4-wide BVH, collapsed from obvhs' binary BVH, for the traversal kernel in
//! [`crate::intersect`].
//!
//! Every node stores the boxes of its up to four children as f32 structure-of-arrays rows
//! (`bounds[2a]` the minima and `bounds[2a + 1]` the maxima along axis `a`, one child per
//! lane), so one ray is tested against four children with a few SIMD operations and no
//! decoding; empty slots hold inverted boxes (`+inf` minima, `-inf` maxima) that no ray hits.
//! Leaf children are ranges of leaf slots; the leaf entries are stored in the order the
//! collapse visits them.

use glam::{Vec3A, Vec4};
use obvhs::{aabb::Aabb, bvh2::Bvh2};

/// Largest number of primitives in one leaf child. A subtree of the binary BVH with at most
/// this many primitives becomes one leaf, tested without another node visit.
pub(crate) const MAX_LEAF: u32 = 3;

/// One node of the 4-wide BVH.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(crate) struct Bvh4Node {
    /// Child boxes: `bounds[2a]` minima, `bounds[2a + 1]` maxima along axis `a`, lane `c`
    /// child `c`.
    pub(crate) bounds: [Vec4; 6],
    /// Inner child: node index. Leaf child: first leaf slot.
    pub(crate) child: [u32; 4],
    /// Number of primitives of a leaf child (0 for inner and empty children).
    pub(crate) count: [u8; 4],
    /// Bit `c` set when child `c` is a leaf.
    pub(crate) leaf_mask: u32,
}

/// The 4-wide BVH: nodes (root at 0) and the binary BVH's primitive indices in leaf order.
#[derive(Clone, Debug)]
pub(crate) struct Bvh4 {
    pub(crate) nodes: Vec<Bvh4Node>,
    /// Primitive index of leaf slot `i`.
    pub(crate) prim_indices: Vec<u32>,
    /// Per axis, the largest magnitude of any box coordinate: bounds the rounding error of
    /// the slab distances (see [`crate::intersect`]).
    pub(crate) max_abs: Vec3A,
}

/// Cost of a node visit relative to one primitive test, for the SAH of the collapse
/// (callgrind on cornell: ~100 instructions per 4-wide node visit, ~50-80 per triangle).
const NODE_COST: f32 = 1.6;

/// How a binary subtree is represented in the 4-wide BVH when it is given `i` child slots
/// of a parent (`i` in 1..=4).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Split {
    /// One slot: a leaf with all of the subtree's primitives.
    Leaf,
    /// One slot: a 4-wide node whose children are the subtree's split into 4 slots.
    Node,
    /// `k` slots to the left binary child and `i - k` to the right one.
    Distribute(u8),
}

/// The SAH-optimal collapse of a binary BVH into 4-wide nodes by dynamic programming over
/// (binary node, number of child slots), the method of Ylitie, Karras and Laine 2017
/// ("Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs", sec. 4.1)
/// for width 4: `cost[n][i - 1]` is the least SAH cost of subtree `n` spread over at most `i`
/// slots of its parent, with surface areas as visit probabilities.
struct Collapse {
    cost: Vec<[f32; 4]>,
    split: Vec<[Split; 4]>,
    counts: Vec<u32>,
}

impl Collapse {
    fn new(bvh2: &Bvh2) -> Self {
        let nodes2 = &bvh2.nodes;
        // Post-order with an explicit stack (children are not assumed to follow parents).
        let mut order = Vec::with_capacity(nodes2.len());
        let mut stack = vec![0u32];
        while let Some(n) = stack.pop() {
            order.push(n);
            let node = &nodes2[n as usize];
            if node.prim_count == 0 {
                stack.push(node.first_index);
                stack.push(node.first_index + 1);
            }
        }
        let mut c = Collapse {
            cost: vec![[f32::INFINITY; 4]; nodes2.len()],
            split: vec![[Split::Leaf; 4]; nodes2.len()],
            counts: vec![0; nodes2.len()],
        };
        for &n in order.iter().rev() {
            let n = n as usize;
            let node = &nodes2[n];
            let area = node.aabb.half_area().max(0.0);
            if node.prim_count != 0 {
                c.counts[n] = node.prim_count;
                c.cost[n] = [area * node.prim_count as f32; 4];
                continue;
            }
            let (l, r) = (node.first_index as usize, node.first_index as usize + 1);
            c.counts[n] = c.counts[l] + c.counts[r];
            // Spread over i >= 2 slots: the best split of the slots between the children,
            // or fewer slots.
            for i in 2..=4usize {
                let (mut best, mut how) = (c.cost[n][i - 2], c.split[n][i - 2]);
                for k in 1..i {
                    let v = c.cost[l][k - 1] + c.cost[r][i - k - 1];
                    if v < best {
                        (best, how) = (v, Split::Distribute(k as u8));
                    }
                }
                c.cost[n][i - 1] = best;
                c.split[n][i - 1] = how;
            }
            // One slot: a leaf, or a node with four slots below it.
            let node_cost = area * NODE_COST + c.cost[n][3];
            let leaf_cost = if c.counts[n] <= MAX_LEAF {
                area * c.counts[n] as f32
            } else {
                f32::INFINITY
            };
            (c.cost[n][0], c.split[n][0]) = if leaf_cost <= node_cost {
                (leaf_cost, Split::Leaf)
            } else {
                (node_cost, Split::Node)
            };
            // "At most i slots" also allows one slot.
            for i in 2..=4usize {
                if c.cost[n][0] < c.cost[n][i - 1] {
                    c.cost[n][i - 1] = c.cost[n][0];
                    c.split[n][i - 1] = c.split[n][0];
                }
            }
        }
        c
    }

    /// The binary nodes that fill the slots of subtree `n` given `i` slots: each is either
    /// a leaf (`true`) or a 4-wide node (`false`).
    fn slots(&self, bvh2: &Bvh2, n: u32, i: usize, out: &mut Vec<(u32, bool)>) {
        match self.split[n as usize][i - 1] {
            Split::Leaf => out.push((n, true)),
            Split::Node => out.push((n, false)),
            Split::Distribute(k) => {
                let l = bvh2.nodes[n as usize].first_index;
                self.slots(bvh2, l, k as usize, out);
                self.slots(bvh2, l + 1, i - k as usize, out);
            }
        }
    }
}

impl Bvh4 {
    /// Collapses `bvh2` (non-empty) into 4-wide nodes with the SAH-optimal assignment of
    /// binary subtrees to child slots and leaves ([`Collapse`]).
    pub(crate) fn from_bvh2(bvh2: &Bvh2) -> Self {
        let collapse = Collapse::new(bvh2);
        let root = &bvh2.nodes[0];
        let mut out = Bvh4 {
            nodes: Vec::new(),
            prim_indices: Vec::with_capacity(collapse.counts[0] as usize),
            max_abs: root.aabb.min.abs().max(root.aabb.max.abs()),
        };
        out.build_node(bvh2, &collapse, 0);
        out
    }

    /// Appends the 4-wide node whose children are the slots of binary subtree `n`, and the
    /// nodes below it; returns its index.
    fn build_node(&mut self, bvh2: &Bvh2, collapse: &Collapse, n: u32) -> u32 {
        let mut kids = Vec::with_capacity(4);
        if collapse.split[n as usize][0] == Split::Leaf {
            // Only for the root of a tiny scene: one node with one leaf child.
            kids.push((n, true));
        } else {
            let l = bvh2.nodes[n as usize].first_index;
            let best = (1..4)
                .min_by(|&a, &b| {
                    let cost = |k: usize| {
                        collapse.cost[l as usize][k - 1] + collapse.cost[l as usize + 1][3 - k]
                    };
                    cost(a).total_cmp(&cost(b))
                })
                .expect("non-empty range");
            collapse.slots(bvh2, l, best, &mut kids);
            collapse.slots(bvh2, l + 1, 4 - best, &mut kids);
        }
        let index = self.nodes.len() as u32;
        self.nodes.push(Bvh4Node {
            bounds: [
                Vec4::INFINITY,
                Vec4::NEG_INFINITY,
                Vec4::INFINITY,
                Vec4::NEG_INFINITY,
                Vec4::INFINITY,
                Vec4::NEG_INFINITY,
            ],
            child: [0; 4],
            count: [0; 4],
            leaf_mask: 0,
        });
        for (c, &(k, is_leaf)) in kids.iter().enumerate() {
            let aabb: Aabb = bvh2.nodes[k as usize].aabb;
            let node = &mut self.nodes[index as usize];
            for a in 0..3 {
                node.bounds[2 * a][c] = aabb.min[a];
                node.bounds[2 * a + 1][c] = aabb.max[a];
            }
            if is_leaf {
                let first = self.prim_indices.len() as u32;
                self.gather_prims(bvh2, k);
                let count = self.prim_indices.len() as u32 - first;
                assert!(count <= u8::MAX as u32, "leaf of {count} primitives");
                let node = &mut self.nodes[index as usize];
                node.child[c] = first;
                node.count[c] = count as u8;
                node.leaf_mask |= 1 << c;
            } else {
                let child = self.build_node(bvh2, collapse, k);
                self.nodes[index as usize].child[c] = child;
            }
        }
        index
    }
    /// Appends the primitives of binary subtree `n` to the leaf order.
    fn gather_prims(&mut self, bvh2: &Bvh2, n: u32) {
        let node = &bvh2.nodes[n as usize];
        if node.prim_count == 0 {
            self.gather_prims(bvh2, node.first_index);
            self.gather_prims(bvh2, node.first_index + 1);
        } else {
            let first = node.first_index as usize;
            self.prim_indices.extend_from_slice(
                &bvh2.primitive_indices[first..first + node.prim_count as usize],
            );
        }
    }
}
