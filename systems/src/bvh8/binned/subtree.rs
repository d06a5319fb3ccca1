//! The arrays of a subtree of the binned build ([`super`]) as it is made, and how the
//! subtrees built on tasks of their own are joined into one tree.

use super::{Ctx, Set};
use crate::bvh8::{Node8, SphereLeaf, INDEX_MASK, INSTANCE, LEAF, SPHERE, WIDTH};

/// A subtree's arrays: its nodes (its root first), its triangle leaves as ranges
/// `(start, count)` of the whole primitive array, its sphere leaves, its depth in node
/// levels counted from the whole tree's root, and the subtrees built on tasks of their own
/// (`(node, child slot, subtree)`), joined into one array once the build is done
/// ([`Out::flatten`]).
#[derive(Default)]
pub(super) struct Out {
    pub(super) nodes: Vec<Node8>,
    pub(super) leaves: Vec<(u32, u32)>,
    pub(super) spheres: Vec<SphereLeaf>,
    pub(super) depth: usize,
    pub(super) subs: Vec<(u32, usize, Out)>,
}

impl Out {
    /// Node, leaf and sphere counts of the subtree and its subtrees.
    fn sizes(&self) -> (usize, usize, usize) {
        self.subs.iter().fold(
            (self.nodes.len(), self.leaves.len(), self.spheres.len()),
            |(n, l, s), (_, _, sub)| {
                let (a, b, c) = sub.sizes();
                (n + a, l + b, s + c)
            },
        )
    }

    /// The tree as one set of arrays, reserved exactly: each subtree's nodes follow its
    /// parent's, in the order the subtrees were made, so the layout is the same whatever
    /// the number of threads. The pieces are freed as they are copied.
    pub(super) fn flatten(self) -> Out {
        let (nodes, leaves, spheres) = self.sizes();
        let mut dst = Out {
            nodes: Vec::with_capacity(nodes),
            leaves: Vec::with_capacity(leaves),
            spheres: Vec::with_capacity(spheres),
            depth: 0,
            subs: Vec::new(),
        };
        self.append_to(&mut dst);
        dst
    }

    /// Appends the subtree to `dst`, moving its node, leaf and sphere indices by where they
    /// land; returns the index of its root.
    fn append_to(self, dst: &mut Out) -> u32 {
        let (nodes, leaves, spheres) = (
            dst.nodes.len() as u32,
            dst.leaves.len() as u32,
            dst.spheres.len() as u32,
        );
        dst.nodes.extend(self.nodes.into_iter().map(|mut n| {
            for c in (0..WIDTH).filter(|c| n.valid & (1 << c) != 0) {
                let child = &mut n.child[c];
                // A subtree's slot holds 0 until the subtree lands (below).
                *child += if *child & LEAF == 0 {
                    nodes
                } else if *child & SPHERE == 0 {
                    leaves
                } else if *child & INSTANCE == 0 {
                    spheres
                } else {
                    0
                };
            }
            n
        }));
        dst.leaves.extend(self.leaves);
        dst.spheres.extend(self.spheres);
        dst.depth = dst.depth.max(self.depth);
        for (node, c, sub) in self.subs {
            let root = sub.append_to(dst);
            dst.nodes[(nodes + node) as usize].child[c] = root;
        }
        nodes
    }

    /// The leaf child of `set` (a leaf: see [`Set::is_leaf`]) of the node's slice `refs`,
    /// which starts at `base` in the whole array.
    pub(super) fn leaf(&mut self, prims: &[u32], base: usize, set: &Set, ctx: &Ctx) -> u32 {
        let prim = prims[set.start];
        if set.tris == set.len() {
            let index = self.leaves.len() as u32;
            self.leaves
                .push(((base + set.start) as u32, set.len() as u32));
            LEAF | index
        } else if prim >= ctx.instance_first {
            let index = prim - ctx.instance_first;
            assert!(index <= INDEX_MASK, "too many instances");
            LEAF | SPHERE | INSTANCE | index
        } else {
            let s = ctx.spheres[(prim - ctx.tri_count) as usize];
            let index = self.spheres.len() as u32;
            self.spheres.push(SphereLeaf {
                center_radius: s.center.extend(s.radius),
                prim,
            });
            LEAF | SPHERE | index
        }
    }
}
