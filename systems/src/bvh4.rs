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

/// A child during the collapse: a binary BVH node index and its primitive count.
#[derive(Clone, Copy)]
struct Pending {
    node: u32,
    prims: u32,
}

impl Bvh4 {
    /// Collapses `bvh2` (non-empty) into 4-wide nodes: each node takes the two children of
    /// a binary node and repeatedly opens the child with the largest surface area until it
    /// has four (the usual greedy collapse, e.g. Wald et al. 2008, "Getting Rid of Packets",
    /// sec. 3), never opening a subtree small enough to be a leaf.
    pub(crate) fn from_bvh2(bvh2: &Bvh2) -> Self {
        let nodes2 = &bvh2.nodes;
        // Primitive count of every binary subtree (children come after parents in obvhs'
        // PLOC output, but do not rely on it: a post-order walk with an explicit stack).
        let mut counts = vec![0u32; nodes2.len()];
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
        for &n in order.iter().rev() {
            let node = &nodes2[n as usize];
            counts[n as usize] = if node.prim_count == 0 {
                counts[node.first_index as usize] + counts[node.first_index as usize + 1]
            } else {
                node.prim_count
            };
        }
        let root = &nodes2[0];
        let max_abs = root.aabb.min.abs().max(root.aabb.max.abs());
        let mut out = Bvh4 {
            nodes: Vec::new(),
            prim_indices: Vec::with_capacity(counts[0] as usize),
            max_abs,
        };
        out.build_node(bvh2, &counts, 0);
        out
    }

    /// Appends the 4-wide node whose children are collapsed from binary node `n`, and its
    /// subtree; returns its index.
    fn build_node(&mut self, bvh2: &Bvh2, counts: &[u32], n: u32) -> u32 {
        let nodes2 = &bvh2.nodes;
        let is_leaf = |p: &Pending| p.prims <= MAX_LEAF || nodes2[p.node as usize].prim_count != 0;
        let mut kids: Vec<Pending> = Vec::with_capacity(4);
        let root = Pending {
            node: n,
            prims: counts[n as usize],
        };
        if is_leaf(&root) {
            // Only for the root of a tiny scene: one node with one leaf child.
            kids.push(root);
        } else {
            let first = nodes2[n as usize].first_index;
            for c in [first, first + 1] {
                kids.push(Pending {
                    node: c,
                    prims: counts[c as usize],
                });
            }
            while kids.len() < 4 {
                let open = kids
                    .iter()
                    .enumerate()
                    .filter(|(_, k)| !is_leaf(k))
                    .max_by(|a, b| {
                        let area = |k: &Pending| nodes2[k.node as usize].aabb.half_area();
                        area(a.1).total_cmp(&area(b.1))
                    })
                    .map(|(i, _)| i);
                let Some(i) = open else { break };
                let first = nodes2[kids[i].node as usize].first_index;
                kids[i] = Pending {
                    node: first,
                    prims: counts[first as usize],
                };
                kids.push(Pending {
                    node: first + 1,
                    prims: counts[first as usize + 1],
                });
            }
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
        for (c, k) in kids.iter().enumerate() {
            let aabb: Aabb = nodes2[k.node as usize].aabb;
            let node = &mut self.nodes[index as usize];
            for a in 0..3 {
                node.bounds[2 * a][c] = aabb.min[a];
                node.bounds[2 * a + 1][c] = aabb.max[a];
            }
            if is_leaf(k) {
                let first = self.prim_indices.len() as u32;
                self.gather_prims(bvh2, k.node);
                let node = &mut self.nodes[index as usize];
                node.child[c] = first;
                node.count[c] = (self.prim_indices.len() as u32 - first) as u8;
                node.leaf_mask |= 1 << c;
            } else {
                let child = self.build_node(bvh2, counts, k.node);
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
            self.prim_indices
                .extend_from_slice(&bvh2.primitive_indices[first..first + node.prim_count as usize]);
        }
    }
}
