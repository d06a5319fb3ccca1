//! An uncompressed 8-wide BVH with triangle-packet leaves, collapsed from obvhs' binary BVH,
//! for the traversal kernels in [`crate::intersect`].
//!
//! Every node stores the boxes of its up to eight children as f32 structure-of-arrays rows
//! (`bounds[2a]` the minima and `bounds[2a + 1]` the maxima along axis `a`, one child per
//! lane), so one ray is tested against eight children with a handful of 8-lane operations
//! and no decoding; empty slots hold inverted boxes (`+inf` minima, `-inf` maxima) that no
//! ray hits. A leaf child is either a packet of up to eight triangles, stored coordinate by
//! coordinate with one triangle per lane so that the watertight test runs on all of them at
//! once, or a single sphere.

use std::sync::Arc;

use glam::{Affine3A, Vec3, Vec3A, Vec4};
use obvhs::{aabb::Aabb, bvh2::Bvh2};

use crate::build_prims::BuildPrims;
use crate::primitive::{Sphere, Triangle};

mod binary;
mod binned;
use crate::simd8::Row8;
use binary::*;
pub(crate) use binary::{bvh2_depth, median_bvh2, node_box, MAX_BVH2_DEPTH};
#[cfg(test)]
pub(crate) use binned::{PARALLEL_BINNING_MIN, PARALLEL_MIN};

/// Number of children of a node and of triangles in a leaf packet.
pub(crate) const WIDTH: usize = 8;

/// [`Node8::child`] flag: the child is a leaf (the low bits index [`Bvh8::packets`], or
/// [`Bvh8::spheres`] with [`SPHERE`] also set).
pub(crate) const LEAF: u32 = 1 << 31;
/// [`Node8::child`] flag of a sphere leaf.
pub(crate) const SPHERE: u32 = 1 << 30;
/// [`Node8::child`] flag of an instance leaf (set together with [`SPHERE`]: like a sphere it
/// is a single-primitive leaf with no triangle packet, so the triangle path never sees it
/// and only the sphere branch of a kernel tests this bit; the low bits index
/// [`Bvh8::instances`]).
pub(crate) const INSTANCE: u32 = 1 << 29;
/// The index bits of a leaf child.
pub(crate) const INDEX_MASK: u32 = INSTANCE - 1;

/// One node of the 8-wide BVH.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(crate) struct Node8 {
    /// Child boxes: `bounds[2a]` minima, `bounds[2a + 1]` maxima along axis `a`, lane `c`
    /// child `c`.
    pub(crate) bounds: [Row8; 6],
    /// Inner child: node index. Leaf child: [`LEAF`] (and [`SPHERE`]) plus its index.
    pub(crate) child: [u32; WIDTH],
    /// Bit `c` set when child `c` is a leaf.
    pub(crate) leaf_mask: u32,
    /// Bit `c` set when slot `c` holds a child.
    pub(crate) valid: u32,
    /// Bit `c` set when child `c`'s subtree holds triangles only, no sphere: the node
    /// test's exact cull of boxes behind the ray origin applies to it (see
    /// `intersect_node8` in [`crate::intersect`]).
    pub(crate) tri_only: u32,
}

impl Node8 {
    /// A node of `count` valid slots (1 to [`WIDTH`]), every box still empty (inverted: no
    /// ray hits it), no child set.
    pub(crate) fn with_slots(count: usize) -> Self {
        let empty_min = Row8([f32::INFINITY; WIDTH]);
        let empty_max = Row8([f32::NEG_INFINITY; WIDTH]);
        Node8 {
            bounds: [
                empty_min, empty_max, empty_min, empty_max, empty_min, empty_max,
            ],
            child: [0; WIDTH],
            leaf_mask: 0,
            valid: (1 << count) - 1,
            tri_only: 0,
        }
    }
}

/// Up to eight triangles of one leaf, coordinate by coordinate: `v[i][a]` holds coordinate
/// `a` of vertex `i`, lane `l` triangle `l`. A leaf of fewer than eight triangles repeats
/// its first triangle in the remaining lanes (finite values, the same result as lane 0),
/// which [`TriPacket8::valid`] masks off.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct TriPacket8 {
    pub(crate) v: [[Row8; 3]; 3],
    /// Scene primitive index of lane `l`.
    pub(crate) prim: [u32; WIDTH],
    /// Bit `l` set for the lanes that hold a triangle of the leaf.
    pub(crate) valid: u32,
}

impl TriPacket8 {
    /// The packet of `tris` (one to eight `(primitive index, vertices)`).
    pub(crate) fn new(tris: &[(u32, [Vec3; 3])]) -> Self {
        assert!(
            (1..=WIDTH).contains(&tris.len()),
            "{} triangles",
            tris.len()
        );
        let mut p = TriPacket8 {
            v: [[Row8([0.0; WIDTH]); 3]; 3],
            prim: [0; WIDTH],
            valid: (1 << tris.len()) - 1,
        };
        for l in 0..WIDTH {
            let (prim, v) = tris.get(l).unwrap_or(&tris[0]);
            p.prim[l] = *prim;
            for i in 0..3 {
                for a in 0..3 {
                    p.v[i][a].0[l] = v[i][a];
                }
            }
        }
        p
    }

    /// Vertices of lane `l`.
    #[inline(always)]
    pub(crate) fn triangle(&self, l: usize) -> [Vec3; 3] {
        let v = |i: usize| Vec3::new(self.v[i][0].0[l], self.v[i][1].0[l], self.v[i][2].0[l]);
        [v(0), v(1), v(2)]
    }
}

/// A sphere leaf: `(center, radius)` and its scene primitive index.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SphereLeaf {
    pub(crate) center_radius: Vec4,
    pub(crate) prim: u32,
}

/// An instance leaf: how a ray reaches its object's BVH ([`Bvh8::objects`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct InstanceLeaf {
    /// World to object space (the inverse of the instance's transform).
    pub(crate) to_object: Affine3A,
    /// Index into [`Bvh8::objects`].
    pub(crate) object: u32,
    /// Scene primitive index of the object's primitive 0 in this instance.
    pub(crate) prim_base: u32,
}

/// The 8-wide BVH: nodes (root at 0), triangle packets and sphere leaves, and in a scene
/// with instances the instance leaves and the BVHs of the objects they place (two levels:
/// the objects' BVHs hold no instances).
#[derive(Clone, Debug)]
pub(crate) struct Bvh8 {
    pub(crate) nodes: Vec<Node8>,
    pub(crate) packets: Vec<TriPacket8>,
    pub(crate) spheres: Vec<SphereLeaf>,
    /// Instance leaves (empty without instances).
    pub(crate) instances: Vec<InstanceLeaf>,
    /// The objects' BVHs, in object space (empty without instances), shared with the
    /// objects' geometries, whose triangles are read from their packets.
    pub(crate) objects: Vec<Arc<Bvh8>>,
    /// Per axis, the largest magnitude of any box coordinate: bounds the rounding error of
    /// the slab distances (see [`crate::intersect`]).
    pub(crate) max_abs: Vec3A,
    /// Number of node levels on the longest root-to-leaf path (1 for a root with only
    /// leaf children): bounds the traversal stacks ([`Self::stack_capacity`]).
    pub(crate) depth: usize,
}

/// Cost of a node visit relative to one leaf-packet test (any number of triangles), for
/// the SAH of the collapse.
const NODE_COST: f32 = 1.0;
/// Weight of the volume term of the visit probability relative to the area term (see
/// [`Collapse::new`]).
const VOLUME_WEIGHT: f32 = 1.0;
/// Cost of a sphere test (double precision) relative to a packet test.
const SPHERE_COST: f32 = 2.0;

/// How a binary subtree is represented in the 8-wide BVH when it is given `i` child slots
/// of a parent (`i` in 1..=8).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Split {
    /// One slot: a leaf with all of the subtree's primitives.
    Leaf,
    /// One slot: an 8-wide node whose children are the subtree's split into 8 slots.
    Node,
    /// `k` slots to the left binary child and `i - k` to the right one.
    Distribute(LeftSlots),
}

/// The `k` of [`Split::Distribute`], 1 to 7: an enum rather than a `u8` so that `Split`
/// fits one byte (the compiler puts `Leaf` and `Node` in the values it leaves unused), and
/// the collapse stores eight per binary node (issue 36, peak memory).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(u8)]
enum LeftSlots {
    K1 = 1,
    K2,
    K3,
    K4,
    K5,
    K6,
    K7,
}

impl LeftSlots {
    /// `k` in 1..WIDTH.
    fn new(k: usize) -> Self {
        match k {
            1 => Self::K1,
            2 => Self::K2,
            3 => Self::K3,
            4 => Self::K4,
            5 => Self::K5,
            6 => Self::K6,
            7 => Self::K7,
            _ => unreachable!("{k} slots of {WIDTH} to the left child"),
        }
    }
}

const _: () = assert!(std::mem::size_of::<Split>() == 1 && WIDTH == 8);

/// The SAH-optimal collapse of a binary BVH into 8-wide nodes by dynamic programming over
/// (binary node, number of child slots), the method of Ylitie, Karras and Laine 2017
/// ("Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs", sec. 4.1):
/// `cost[n][i - 1]` is the least SAH cost of subtree `n` spread over at most `i` slots of
/// its parent, with surface areas (plus a volume term, see [`Collapse::new`]) as visit
/// probabilities. A leaf holds up to eight triangles (one packet test) or one sphere.
struct Collapse {
    /// SAH cost of the 8-wide tree: the root node and everything below it.
    root_cost: f32,
    split: Vec<[Split; WIDTH]>,
    /// For an inner node that becomes an 8-wide node: the slots (1 to 7) of its left child,
    /// the rest going to the right one, at the least cost.
    node_split: Vec<u8>,
}

/// What the collapse's dynamic programme keeps of a finished subtree until its parent reads
/// it: the least costs over 1 to 8 slots and its triangle count (`u32::MAX` if a sphere is
/// among its primitives).
struct Subtree {
    cost: [f32; WIDTH],
    tris: u32,
}

impl Collapse {
    /// The collapse of `bins` (root first) with costs computed on boxes scaled by `s`
    /// ([`cost_scale`]).
    ///
    /// The subtrees are costed in post-order with their costs on a stack, popped by the
    /// parent: only the root-to-node path's siblings are alive at once (at most twice the
    /// depth), not a cost row per binary node (32 bytes, two nodes a primitive: 128 MB on
    /// a 2M-triangle mesh, issue 36). The arithmetic is the same, node by node.
    fn new(bins: &[Bin], s: f32, is_sphere: impl Fn(u32) -> bool) -> Self {
        let root = scaled(&bins[0].aabb(), s);
        let volume = |b: &Aabb| {
            let e = (b.max - b.min).max(Vec3A::ZERO);
            e.x * e.y * e.z
        };
        let (root_area, root_volume) = (root.half_area().max(0.0), volume(&root));
        // Visit probability up to a common factor: surface area (the share of random lines
        // that cross the box, Cauchy-Crofton) plus volume (the share of ray origins inside
        // it, which test it whatever their direction). Area alone prices a leaf spanning a
        // room as cheaply as the three walls in it, though every ray in the room tests it.
        let weight = |b: &Aabb| {
            let b = &scaled(b, s);
            let a = b.half_area().max(0.0);
            if root_volume > 0.0 {
                a + VOLUME_WEIGHT * root_area * volume(b) / root_volume
            } else {
                a
            }
        };
        let mut c = Collapse {
            root_cost: 0.0,
            split: vec![[Split::Leaf; WIDTH]; bins.len()],
            node_split: vec![0; bins.len()],
        };
        // Post-order with an explicit stack: `(node, children done)`; a node's children
        // are pushed right then left, so the left one's subtree is finished (and lies
        // below the right one's on `done`) when the node comes back.
        let mut todo = vec![(0u32, false)];
        let mut done: Vec<Subtree> = Vec::new();
        while let Some((n, kids_done)) = todo.pop() {
            let b = &bins[n as usize];
            let area = weight(&b.aabb());
            if b.is_leaf() {
                let sphere = is_sphere(b.kids[0]);
                done.push(Subtree {
                    cost: [area * if sphere { SPHERE_COST } else { 1.0 }; WIDTH],
                    tris: if sphere { u32::MAX } else { 1 },
                });
                continue;
            }
            if !kids_done {
                todo.extend([(n, true), (b.kids[1], false), (b.kids[0], false)]);
                continue;
            }
            let r = done.pop().expect("the right subtree is costed");
            let l = done.pop().expect("the left subtree is costed");
            let n = n as usize;
            let tris = l.tris.saturating_add(r.tris);
            let mut cost = [f32::INFINITY; WIDTH];
            let split = &mut c.split[n];
            // Spread over i >= 2 slots: the best split of the slots between the children,
            // or fewer slots.
            for i in 2..=WIDTH {
                let (mut best, mut how) = (cost[i - 2], split[i - 2]);
                for k in 1..i {
                    let v = l.cost[k - 1] + r.cost[i - k - 1];
                    if v < best {
                        (best, how) = (v, Split::Distribute(LeftSlots::new(k)));
                    }
                }
                cost[i - 1] = best;
                split[i - 1] = how;
            }
            // As an 8-wide node, at least one slot to each child (the first of equal costs).
            let spread = |k: usize| l.cost[k - 1] + r.cost[WIDTH - 1 - k];
            c.node_split[n] = (1..WIDTH)
                .min_by(|&a, &b| spread(a).total_cmp(&spread(b)))
                .expect("non-empty range") as u8;
            // One slot: a leaf, or a node with all slots below it.
            let node_cost = area * NODE_COST + cost[WIDTH - 1];
            let fits = tris as usize <= WIDTH;
            let leaf_cost = if fits { area } else { f32::INFINITY };
            // `fits` as well: a leaf must never be chosen for a subtree it cannot hold, even
            // if a cost is infinite or NaN.
            (cost[0], split[0]) = if fits && leaf_cost <= node_cost {
                (leaf_cost, Split::Leaf)
            } else {
                (node_cost, Split::Node)
            };
            // "At most i slots" also allows one slot.
            for i in 2..=WIDTH {
                if cost[0] < cost[i - 1] {
                    cost[i - 1] = cost[0];
                    split[i - 1] = split[0];
                }
            }
            done.push(Subtree { cost, tris });
        }
        let root = done.pop().expect("the root is costed");
        c.root_cost = weight(&bins[0].aabb()) * NODE_COST + root.cost[WIDTH - 1];
        c
    }

    /// The binary nodes that fill the slots of subtree `n` given `i` slots: each is either
    /// a leaf (`true`) or an 8-wide node (`false`).
    fn slots(&self, bins: &[Bin], n: u32, i: usize, out: &mut Vec<(u32, bool)>) {
        match self.split[n as usize][i - 1] {
            Split::Leaf => out.push((n, true)),
            Split::Node => out.push((n, false)),
            Split::Distribute(k) => {
                let k = k as u8;
                let [l, r] = bins[n as usize].kids;
                self.slots(bins, l, k as usize, out);
                self.slots(bins, r, i - k as usize, out);
            }
        }
    }
}

impl Source<'_> {
    /// The children of the 8-wide node made of binary subtree `n`: each a binary node and
    /// whether it is a leaf.
    fn kids(&self, n: u32) -> Vec<(u32, bool)> {
        let (bins, collapse) = (self.bins, self.collapse);
        let mut kids = Vec::with_capacity(WIDTH);
        if bins[n as usize].is_leaf() || collapse.split[n as usize][0] == Split::Leaf {
            // Only for the root of a tiny scene: one node with one leaf child.
            kids.push((n, true));
        } else {
            let [l, r] = bins[n as usize].kids;
            let best = collapse.node_split[n as usize] as usize;
            collapse.slots(bins, l, best, &mut kids);
            collapse.slots(bins, r, WIDTH - best, &mut kids);
        }
        kids
    }

    /// How many 8-wide nodes and triangle packets the node made of binary subtree `n` and
    /// those below it take: the build reserves exactly that much, so the arrays never grow
    /// by doubling (a copy of the old array alongside the new one at the build's peak).
    fn sizes(&self, n: u32) -> (usize, usize) {
        let (mut nodes, mut leaves) = (1, 0);
        for (mut k, is_leaf) in self.kids(n) {
            if is_leaf {
                // A leaf's primitives are all triangles or one sphere or instance: its
                // first primitive tells.
                while !self.bins[k as usize].is_leaf() {
                    k = self.bins[k as usize].kids[0];
                }
                leaves += usize::from(
                    (self.bins[k as usize].kids[0] as usize) < self.prims.num_triangles(),
                );
            } else {
                let (a, b) = self.sizes(k);
                (nodes, leaves) = (nodes + a, leaves + b);
            }
        }
        (nodes, leaves)
    }
}

/// The triangle leaves as the recursion makes them, before their packets are filled: leaf
/// `i`'s primitives are `prims[ends[i - 1]..ends[i]]` (from 0 for the first).
struct PacketLeaves {
    prims: Vec<u32>,
    ends: Vec<u32>,
}

/// Inputs of the build that the recursion reads.
struct Source<'a> {
    bins: &'a [Bin],
    collapse: &'a Collapse,
    prims: &'a BuildPrims,
    spheres: &'a [Sphere],
}

impl Bvh8 {
    /// Collapses `bvh2` (non-empty, over `triangles` as primitives `0..triangles.len()`
    /// and `spheres` after them, then instance leaves: primitive `triangles.len() +
    /// spheres.len() + k` is instance `k`, priced as a sphere) into 8-wide nodes with the SAH-optimal assignment of
    /// binary subtrees to child slots and leaves ([`Collapse`]).
    /// The binary tree is taken, and dropped as soon as it is copied into one-primitive
    /// leaves: at most one of the two is alive at a time (issue 36, peak memory).
    pub(crate) fn from_bvh2(bvh2: Bvh2, prims: &BuildPrims, spheres: &[Sphere]) -> Self {
        let tri_count = prims.num_triangles() as u32;
        let is_sphere = |p: u32| p >= tri_count;
        // obvhs' tree, and for small scenes the full-sweep SAH tree: whichever collapses
        // to the lower SAH cost.
        let root = node_box(&bvh2.nodes[0]);
        let s = cost_scale(&root);
        let mut bins = binary_tree(&bvh2);
        let sweep = (bvh2.primitive_indices.len() <= SWEEP_MAX).then(|| sweep_tree(&bvh2, s));
        drop(bvh2);
        let mut collapse = Collapse::new(&bins, s, is_sphere);
        if let Some(sweep) = sweep {
            let sweep_collapse = Collapse::new(&sweep, s, is_sphere);
            if sweep_collapse.root_cost < collapse.root_cost {
                (bins, collapse) = (sweep, sweep_collapse);
            }
        }
        let mut out = Bvh8 {
            nodes: Vec::new(),
            packets: Vec::new(),
            spheres: Vec::new(),
            instances: Vec::new(),
            objects: Vec::new(),
            max_abs: root.min.abs().max(root.max.abs()),
            depth: 0,
        };
        let src = Source {
            bins: &bins,
            collapse: &collapse,
            prims,
            spheres,
        };
        let (nodes, packets) = src.sizes(0);
        out.nodes.reserve_exact(nodes);
        let mut leaves = PacketLeaves {
            prims: Vec::with_capacity(prims.num_triangles()),
            ends: Vec::with_capacity(packets),
        };
        out.build_node(&src, 0, 1, &mut leaves);
        // The packets are made once the binary tree and its split table are gone: the two
        // never coexist with them (issue 36, peak memory).
        drop(bins);
        drop(collapse);
        out.packets.reserve_exact(leaves.ends.len());
        let mut start = 0;
        for &end in &leaves.ends {
            let mut tris = [(0u32, [Vec3::ZERO; 3]); WIDTH];
            let leaf = &leaves.prims[start as usize..end as usize];
            for (t, &p) in tris.iter_mut().zip(leaf) {
                *t = (p, prims.triangle(p as usize));
            }
            out.packets.push(TriPacket8::new(&tris[..leaf.len()]));
            start = end;
        }
        out
    }

    /// Where each of triangle primitives `0..count` lies: `packet * WIDTH + lane` (the
    /// packets hold the vertices the build was given, unchanged, every triangle in exactly
    /// one lane): 4 bytes a triangle instead of a record of its own (issue 36).
    ///
    /// # Panics
    /// If the packets do not hold each of the `count` triangles once (a build bug).
    pub(crate) fn triangle_slots(&self, count: usize) -> Vec<u32> {
        const UNSET: u32 = u32::MAX;
        let mut out = vec![UNSET; count];
        let mut filled = 0usize;
        for (i, p) in self.packets.iter().enumerate() {
            for l in (0..WIDTH).filter(|l| p.valid & (1 << l) != 0) {
                let slot = &mut out[p.prim[l] as usize];
                assert_eq!(*slot, UNSET, "the packets hold each triangle once");
                // `i <= INDEX_MASK < 2^29`, so the slot fits 32 bits.
                *slot = (i * WIDTH + l) as u32;
                filled += 1;
            }
        }
        assert_eq!(filled, count, "the packets hold each triangle once");
        out
    }

    /// The triangle in `slot` (as [`Self::triangle_slots`] numbers them).
    #[inline(always)]
    pub(crate) fn slot_triangle(packets: &[TriPacket8], slot: u32) -> Triangle {
        Triangle::new(packets[slot as usize / WIDTH].triangle(slot as usize % WIDTH))
    }

    /// Entries a traversal stack can hold at most: a node pushes at most its [`WIDTH`] hit
    /// children and the traversal then takes one of them, so the stack holds at most
    /// `WIDTH - 1` entries per level above the current node plus `WIDTH` for it.
    pub(crate) fn stack_capacity(&self) -> usize {
        (WIDTH - 1) * self.depth + 1
    }

    /// [`Self::stack_capacity`] of the deepest object BVH (0 without instances): the stack
    /// a traversal of an instance's object uses, separate from the top-level one it
    /// interrupts.
    pub(crate) fn object_stack_capacity(&self) -> usize {
        self.objects
            .iter()
            .map(|o| o.stack_capacity())
            .max()
            .unwrap_or(0)
    }

    /// Bytes held by the nodes, leaves and instances (the objects' BVHs are their
    /// geometries' to count).
    pub(crate) fn bytes(&self) -> usize {
        use std::mem::size_of;
        self.nodes.capacity() * size_of::<Node8>()
            + self.packets.capacity() * size_of::<TriPacket8>()
            + self.spheres.capacity() * size_of::<SphereLeaf>()
            + self.instances.capacity() * size_of::<InstanceLeaf>()
            + self.objects.capacity() * size_of::<Arc<Self>>()
            + size_of::<Self>()
    }

    /// Appends the 8-wide node whose children are the slots of binary subtree `n`, and the
    /// nodes below it; returns its index.
    fn build_node(&mut self, src: &Source, n: u32, level: usize, leaves: &mut PacketLeaves) -> u32 {
        self.depth = self.depth.max(level);
        let bins = src.bins;
        let kids = src.kids(n);
        let index = self.nodes.len() as u32;
        self.nodes.push(Node8::with_slots(kids.len()));
        for (c, &(k, is_leaf)) in kids.iter().enumerate() {
            let aabb = bins[k as usize].aabb();
            let node = &mut self.nodes[index as usize];
            for a in 0..3 {
                node.bounds[2 * a].0[c] = aabb.min[a];
                node.bounds[2 * a + 1].0[c] = aabb.max[a];
            }
            let (child, tri_only) = if is_leaf {
                self.nodes[index as usize].leaf_mask |= 1 << c;
                let child = self.build_leaf(src, k, leaves);
                (child, child & SPHERE == 0)
            } else {
                let child = self.build_node(src, k, level + 1, leaves);
                let below = &self.nodes[child as usize];
                (child, below.tri_only == below.valid)
            };
            let node = &mut self.nodes[index as usize];
            node.child[c] = child;
            node.tri_only |= (tri_only as u32) << c;
        }
        index
    }

    /// Appends the leaf of binary subtree `n` (a sphere, or up to eight triangles) and
    /// returns its child entry.
    fn build_leaf(&mut self, src: &Source, n: u32, leaves: &mut PacketLeaves) -> u32 {
        let mut prims = Vec::with_capacity(WIDTH);
        let mut stack = vec![n];
        while let Some(k) = stack.pop() {
            let b = &src.bins[k as usize];
            if b.is_leaf() {
                prims.push(b.kids[0]);
            } else {
                // Right first, so the primitives come out left to right.
                stack.push(b.kids[1]);
                stack.push(b.kids[0]);
            }
        }
        let tri_count = src.prims.num_triangles() as u32;
        let instance_first = tri_count as usize + src.spheres.len();
        if prims[0] as usize >= instance_first {
            assert_eq!(prims.len(), 1, "instance leaves hold one instance");
            let index = prims[0] - instance_first as u32;
            assert!(index <= INDEX_MASK, "too many instances");
            LEAF | SPHERE | INSTANCE | index
        } else if prims[0] >= tri_count {
            assert_eq!(prims.len(), 1, "sphere leaves hold one sphere");
            let s = src.spheres[(prims[0] - tri_count) as usize];
            let index = self.spheres.len() as u32;
            self.spheres.push(SphereLeaf {
                center_radius: s.center.extend(s.radius),
                prim: prims[0],
            });
            LEAF | SPHERE | index
        } else {
            assert!(
                prims.len() <= WIDTH,
                "a packet holds at most {WIDTH} triangles"
            );
            let index = leaves.ends.len() as u32;
            assert!(index <= INDEX_MASK, "too many leaves");
            leaves.prims.extend(&prims);
            leaves.ends.push(leaves.prims.len() as u32);
            LEAF | index
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use obvhs::bvh2::node::Bvh2Node;

    fn leaf_node(aabb: Aabb, first: u32, count: u32) -> Bvh2Node {
        Bvh2Node::new(aabb, count, first)
    }

    /// obvhs' builder makes one-primitive leaves, but a binary tree with larger leaves (13
    /// triangles; two triangles and a sphere) still collapses to a tree holding every
    /// primitive once, triangles in packets and the sphere alone, inside its child box.
    #[test]
    fn multi_primitive_leaves_are_split() {
        let tris: Vec<[Vec3; 3]> = (0..15)
            .map(|i| {
                let c = Vec3::new(i as f32, 0.0, 0.0);
                [c, c + Vec3::X * 0.5, c + Vec3::Y]
            })
            .collect();
        let spheres = vec![Sphere {
            center: Vec3::new(20.0, 0.0, 0.0),
            radius: 0.5,
        }];
        let bounds = |prims: &[u32]| {
            let mut b = Aabb::INVALID;
            for &p in prims {
                if p < 15 {
                    for v in tris[p as usize] {
                        b.extend(v.into());
                    }
                } else {
                    b.extend(Vec3A::new(19.5, -0.5, -0.5));
                    b.extend(Vec3A::new(20.5, 0.5, 0.5));
                }
            }
            b
        };
        let left: Vec<u32> = (0..13).collect();
        let right = [13, 14, 15];
        let all: Vec<u32> = (0..16).collect();
        let bvh2 = Bvh2 {
            nodes: vec![
                Bvh2Node::new(bounds(&all), 0, 1),
                leaf_node(bounds(&left), 0, 13),
                leaf_node(bounds(&right), 13, 3),
            ],
            primitive_indices: all.clone(),
            ..Default::default()
        };
        let prims = BuildPrims::new(tris.clone(), Vec::new());
        let bvh = Bvh8::from_bvh2(bvh2, &prims, &spheres);
        let mut seen = [0u32; 16];
        for node in &bvh.nodes {
            for c in 0..WIDTH {
                let child = node.child[c];
                if node.valid & (1 << c) == 0 || child & LEAF == 0 {
                    continue;
                }
                let b = |r: usize| node.bounds[r].0[c];
                let (lo, hi) = (Vec3::new(b(0), b(2), b(4)), Vec3::new(b(1), b(3), b(5)));
                let index = (child & INDEX_MASK) as usize;
                let prims: Vec<u32> = if child & SPHERE != 0 {
                    vec![bvh.spheres[index].prim]
                } else {
                    let p = &bvh.packets[index];
                    (0..p.valid.count_ones() as usize)
                        .map(|l| p.prim[l])
                        .collect()
                };
                let pb = bounds(&prims);
                assert!(Vec3::from(pb.min).cmpge(lo).all() && Vec3::from(pb.max).cmple(hi).all());
                for p in prims {
                    seen[p as usize] += 1;
                }
            }
        }
        assert_eq!(seen, [1; 16]);
        assert_eq!(bvh.spheres.len(), 1);
        // The arrays were reserved exactly (counted before the build, the sphere's leaf
        // not among the packets).
        assert_eq!(bvh.nodes.capacity(), bvh.nodes.len());
        assert_eq!(bvh.packets.capacity(), bvh.packets.len());
        // Triangles from the packets by their slots: each triangle's own vertices.
        let slots = bvh.triangle_slots(tris.len());
        for (&slot, t) in slots.iter().zip(&tris) {
            let r = Bvh8::slot_triangle(&bvh.packets, slot);
            assert_eq!(r.v.map(Vec3::from), *t);
        }
    }
}
