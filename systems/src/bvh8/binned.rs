//! The 8-wide tree built directly, top down, by binned SAH (issue 36): no binary tree, no
//! PLOC working set and no collapse, so a large mesh's build needs little more than a box
//! and an index per primitive.
//!
//! A node's primitive range is split by binned SAH (Wald 2007, "On fast Construction of
//! SAH-based Bounding Volume Hierarchies": 32 bins of the centroids per axis, the split
//! between bins of least `A(L) C(L) + A(R) C(R)`), and the child of largest surface area
//! is split again until the node has eight children or none can be split, as Embree's
//! BVH8 builders fill a node. The primitives are partitioned in place, so every child, and
//! every leaf, is a contiguous range of one array.
//!
//! A leaf is a packet of up to eight triangles, one test whatever their number
//! ([`super::TriPacket8`]), or a single sphere or instance: the SAH prices a side by its
//! packets, `ceil(triangles / 8)`, plus [`SPHERE_COST`] a sphere or instance (Embree's
//! block-rounded primitive counts), which prefers full packets; a child of at most eight
//! triangles is never split (4.7 triangles a packet on a 2M-triangle mesh with the
//! one-primitive SAH collapse; see `benches/README.md`).
//!
//! Subtrees of at least [`PARALLEL_MIN`] primitives are built on rayon tasks into arrays of
//! their own and appended in child order: the tree is the same whatever the number of
//! threads. Below [`MAX_SAH_LEVEL`] node levels the splits become median splits by count
//! of the child with the most primitives, so the depth is bounded whatever the boxes
//! (coincident or degenerate primitives, a geometric series of sizes).

use glam::{Vec3, Vec3A};

use super::{cost_scale, SPHERE_COST};
use super::{Bvh8, Node8, TriPacket8, INDEX_MASK, WIDTH};
use crate::build_prims::{BuildPrims, PrimBoxes};
use crate::primitive::Sphere;

mod subtree;
use subtree::Out;

/// Centroid bins per axis.
const BINS: usize = 32;

/// Nodes with at least this many primitives build their inner children on rayon tasks
/// (each into arrays of its own, appended in child order).
pub(crate) const PARALLEL_MIN: usize = 16 * 1024;

/// Deepest node level split by SAH; below it, median splits by count.
const MAX_SAH_LEVEL: usize = 48;

/// A primitive's box as the build partitions it (24 bytes), beside its index: the build's
/// only per-primitive arrays besides the primitives themselves.
#[derive(Clone, Copy, Debug)]
struct PrimBox {
    min: Vec3,
    max: Vec3,
}

/// Primitive boxes and indices, partitioned together: kept apart so the indices, in leaf
/// order once built, outlive the boxes (4 bytes a primitive, not 28, alive beside the
/// packets at the build's peak; issue 36).
struct Refs<'a> {
    boxes: &'a mut [PrimBox],
    prims: &'a mut [u32],
}

impl<'a> Refs<'a> {
    fn len(&self) -> usize {
        self.prims.len()
    }

    fn swap(&mut self, i: usize, j: usize) {
        self.boxes.swap(i, j);
        self.prims.swap(i, j);
    }

    /// The primitives `range` (reborrowed).
    fn slice(&mut self, range: std::ops::Range<usize>) -> Refs<'_> {
        Refs {
            boxes: &mut self.boxes[range.clone()],
            prims: &mut self.prims[range],
        }
    }

    /// The first `mid` primitives and the rest.
    fn split_at(self, mid: usize) -> (Refs<'a>, Refs<'a>) {
        let (b0, b1) = self.boxes.split_at_mut(mid);
        let (p0, p1) = self.prims.split_at_mut(mid);
        (
            Refs {
                boxes: b0,
                prims: p0,
            },
            Refs {
                boxes: b1,
                prims: p1,
            },
        )
    }
}

impl PrimBox {
    /// The box's centre, halves summed (no overflow near `f32::MAX`).
    #[inline(always)]
    fn centroid(&self) -> Vec3A {
        Vec3A::from(self.min) * 0.5 + Vec3A::from(self.max) * 0.5
    }
}

/// An axis-aligned box; empty when inverted.
#[derive(Clone, Copy, Debug)]
struct Bounds {
    min: Vec3A,
    max: Vec3A,
}

impl Bounds {
    const EMPTY: Bounds = Bounds {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
    };

    #[inline(always)]
    fn extend(&mut self, lo: Vec3A, hi: Vec3A) {
        self.min = self.min.min(lo);
        self.max = self.max.max(hi);
    }

    #[inline(always)]
    fn union(&self, o: &Bounds) -> Bounds {
        Bounds {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Half the surface area of the box scaled by `s` ([`cost_scale`]: finite for any
    /// finite box); 0 when empty.
    #[inline(always)]
    fn half_area(&self, s: f32) -> f32 {
        let d = ((self.max - self.min) * s).max(Vec3A::ZERO);
        (d.x + d.y) * d.z + d.x * d.y
    }
}

/// A contiguous range of the build's [`PrimRef`]s (relative to the node's slice), with the
/// union of their boxes, the bounds of their centroids and the number of triangles among
/// them (the others are spheres or instances).
#[derive(Clone, Copy, Debug)]
struct Set {
    start: usize,
    end: usize,
    bounds: Bounds,
    centroids: Bounds,
    tris: usize,
}

impl Set {
    fn len(&self) -> usize {
        self.end - self.start
    }

    /// A single primitive, or up to [`WIDTH`] triangles: one leaf.
    fn is_leaf(&self) -> bool {
        self.len() == 1 || (self.tris == self.len() && self.len() <= WIDTH)
    }

    /// The set of `boxes` and `prims` (all of them, from 0).
    fn of(boxes: &[PrimBox], prims: &[u32], tri_count: u32) -> Set {
        let mut s = Set {
            start: 0,
            end: prims.len(),
            bounds: Bounds::EMPTY,
            centroids: Bounds::EMPTY,
            tris: 0,
        };
        for (b, &p) in boxes.iter().zip(prims) {
            s.bounds.extend(b.min.into(), b.max.into());
            let c = b.centroid();
            s.centroids.extend(c, c);
            s.tris += usize::from(p < tri_count);
        }
        s
    }
}

/// SAH cost factor of a side: its leaf tests, a packet per eight triangles and
/// [`SPHERE_COST`] a sphere or instance.
#[inline(always)]
fn tests(tris: usize, others: usize) -> f32 {
    tris.div_ceil(WIDTH) as f32 + SPHERE_COST * others as f32
}

/// One bin of one axis: the union of its primitives' boxes, and their counts.
#[derive(Clone, Copy, Debug)]
struct Bin {
    bounds: Bounds,
    tris: u32,
    others: u32,
}

const EMPTY_BIN: Bin = Bin {
    bounds: Bounds::EMPTY,
    tris: 0,
    others: 0,
};

/// What the build reads: the primitives' kinds and the spheres, and the cost scale.
struct Ctx<'a> {
    tri_count: u32,
    instance_first: u32,
    spheres: &'a [Sphere],
    scale: f32,
}

/// The centroid-to-bin map of one set: bin `((c - min) * k)` per axis, on centroids scaled
/// by the cost scale so the extents are finite, `bins` bins ([`BINS`], fewer for a small
/// set). Binning and partitioning compute the same operations (all axes, and the one axis
/// split), so a primitive lands on the side its bin was counted on.
#[derive(Clone, Copy)]
struct Binning {
    min: Vec3A,
    k: Vec3A,
    scale: f32,
    bins: usize,
}

impl Binning {
    fn new(set: &Set, scale: f32) -> Self {
        let bins = set.len().clamp(2, BINS);
        let min = set.centroids.min * scale;
        let extent = set.centroids.max * scale - min;
        // Slightly below `bins` so the largest centroid maps to the last bin; an axis with
        // no extent has k = 0 (every centroid in bin 0: no split along it).
        let k = Vec3A::select(
            extent.cmpgt(Vec3A::ZERO),
            Vec3A::splat(bins as f32 * (1.0 - 1e-6)) / extent,
            Vec3A::ZERO,
        );
        Binning {
            min,
            k,
            scale,
            bins,
        }
    }

    /// The bin of centroid `c` along `axis` alone: the same operations as that lane of
    /// [`Self::bins`], so the same bin.
    #[inline(always)]
    fn bin(&self, c: Vec3A, axis: usize) -> usize {
        let last = (self.bins - 1) as f32;
        ((c[axis] * self.scale - self.min[axis]) * self.k[axis]).min(last) as usize
    }

    #[inline(always)]
    fn bins(&self, c: Vec3A) -> [usize; 3] {
        let last = (self.bins - 1) as f32;
        let b = ((c * self.scale - self.min) * self.k).min(Vec3A::splat(last));
        // Float to integer casts saturate: a negative rounding or NaN goes to bin 0.
        [b.x as usize, b.y as usize, b.z as usize]
    }
}

/// Splits `refs[set.start..set.end]` in two non-empty sets, reordering it in place: the
/// least-cost binned SAH split when `sah` and one exists, else the median by count along
/// the axis of largest centroid extent (in input order where the centroids coincide).
fn split(refs: &mut Refs, set: &Set, ctx: &Ctx, sah: bool) -> (Set, Set) {
    let mut part = refs.slice(set.start..set.end);
    let empty = |start, end| Set {
        start,
        end,
        bounds: Bounds::EMPTY,
        centroids: Bounds::EMPTY,
        tris: 0,
    };
    let binning = Binning::new(set, ctx.scale);
    if let Some((axis, at)) = sah
        .then(|| best_binned_split(part.boxes, part.prims, &binning, ctx))
        .flatten()
    {
        // Hoare-style partition; each primitive is classified once, and the sides' boxes,
        // centroid bounds and triangle counts are gathered on the way.
        let (mut l, mut r) = (empty(0, 0), empty(0, 0));
        let (mut i, mut j) = (0, part.len());
        while i < j {
            let (p, prim) = (part.boxes[i], part.prims[i]);
            let c = p.centroid();
            let side = if binning.bin(c, axis) < at {
                i += 1;
                &mut l
            } else {
                j -= 1;
                part.swap(i, j);
                &mut r
            };
            side.bounds.extend(p.min.into(), p.max.into());
            side.centroids.extend(c, c);
            side.tris += usize::from(prim < ctx.tri_count);
        }
        (l.start, l.end) = (set.start, set.start + i);
        (r.start, r.end) = (set.start + i, set.end);
        return (l, r);
    }
    // Extents compared in f64: differences of f32 extents can overflow.
    let c = &set.centroids;
    let extent = |a: usize| c.max[a] as f64 - c.min[a] as f64;
    let axis = (0..3)
        .max_by(|&a, &b| extent(a).total_cmp(&extent(b)))
        .expect("three axes");
    let mid = part.len() / 2;
    if extent(axis) > 0.0 {
        // Sorted as (centroid, primitive) pairs, then written back: the two arrays move
        // together (a rare fallback, so the pairs' copy is affordable).
        let mut pairs: Vec<(PrimBox, u32)> = part
            .boxes
            .iter()
            .copied()
            .zip(part.prims.iter().copied())
            .collect();
        pairs.select_nth_unstable_by(mid, |a, b| {
            a.0.centroid()[axis]
                .total_cmp(&b.0.centroid()[axis])
                .then(a.1.cmp(&b.1))
        });
        for (i, (b, p)) in pairs.into_iter().enumerate() {
            (part.boxes[i], part.prims[i]) = (b, p);
        }
    }
    let mut l = Set::of(&part.boxes[..mid], &part.prims[..mid], ctx.tri_count);
    let mut r = Set::of(&part.boxes[mid..], &part.prims[mid..], ctx.tri_count);
    (l.start, l.end) = (set.start, set.start + mid);
    (r.start, r.end) = (set.start + mid, set.end);
    (l, r)
}

/// Sets of at least this many primitives count their bins on rayon tasks.
pub(crate) const PARALLEL_BINNING_MIN: usize = 128 * 1024;

/// Primitives a task bins (of a set of at least [`PARALLEL_BINNING_MIN`]).
const BINNING_CHUNK: usize = 32 * 1024;

/// Bins of every axis.
type AxisBins = [[Bin; BINS]; 3];

/// The bins of `boxes` (primitives `prims`; below `tri_count` a triangle) under `binning`.
fn bin_prims(boxes: &[PrimBox], prims: &[u32], binning: &Binning, tri_count: u32) -> AxisBins {
    let mut bins = [[EMPTY_BIN; BINS]; 3];
    for (r, &prim) in boxes.iter().zip(prims) {
        let (lo, hi) = (Vec3A::from(r.min), Vec3A::from(r.max));
        let tri = u32::from(prim < tri_count);
        for (axis, b) in binning.bins(r.centroid()).into_iter().enumerate() {
            let bin = &mut bins[axis][b];
            bin.bounds.extend(lo, hi);
            bin.tris += tri;
            bin.others += 1 - tri;
        }
    }
    bins
}

/// The bins of two disjoint sets of primitives merged.
fn merge_bins(mut a: AxisBins, b: AxisBins) -> AxisBins {
    for (a, b) in a.iter_mut().flatten().zip(b.iter().flatten()) {
        a.bounds = a.bounds.union(&b.bounds);
        a.tris += b.tris;
        a.others += b.others;
    }
    a
}

/// The binned SAH split of `part`: `(axis, first bin of the right side)` of least cost,
/// the first of equal costs in axis and bin order; `None` when every axis has all
/// centroids in one bin.
fn best_binned_split(
    boxes: &[PrimBox],
    prims: &[u32],
    binning: &Binning,
    ctx: &Ctx,
) -> Option<(usize, usize)> {
    let n = binning.bins;
    let tri_count = ctx.tri_count;
    // The bins of a large set are counted on rayon tasks, a chunk each, and merged: unions
    // and sums, exact in any order, so the split is the same whatever the threads. The
    // root's splits otherwise ran on one thread (issue 36: a tenth of a 2M-triangle
    // mesh's build on two cores).
    let bins = if boxes.len() >= PARALLEL_BINNING_MIN {
        use rayon::prelude::*;
        boxes
            .par_chunks(BINNING_CHUNK)
            .zip(prims.par_chunks(BINNING_CHUNK))
            .map(|(b, p)| bin_prims(b, p, binning, tri_count))
            .reduce(|| [[EMPTY_BIN; BINS]; 3], merge_bins)
    } else {
        bin_prims(boxes, prims, binning, tri_count)
    };
    let mut best: Option<(f32, usize, usize)> = None;
    for (axis, bins) in bins.iter().enumerate() {
        // Right sides from the last bin down: `right_cost[i]` prices bins `i..n`.
        let mut right_cost = [0.0f32; BINS];
        let mut right_count = [0u32; BINS];
        let mut acc = EMPTY_BIN;
        for i in (1..n).rev() {
            let b = &bins[i];
            acc.bounds = acc.bounds.union(&b.bounds);
            acc.tris += b.tris;
            acc.others += b.others;
            right_count[i] = acc.tris + acc.others;
            right_cost[i] =
                acc.bounds.half_area(ctx.scale) * tests(acc.tris as usize, acc.others as usize);
        }
        let mut left = EMPTY_BIN;
        for i in 1..n {
            let b = &bins[i - 1];
            left.bounds = left.bounds.union(&b.bounds);
            left.tris += b.tris;
            left.others += b.others;
            if left.tris + left.others == 0 || right_count[i] == 0 {
                continue;
            }
            let cost = left.bounds.half_area(ctx.scale)
                * tests(left.tris as usize, left.others as usize)
                + right_cost[i];
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, axis, i));
            }
        }
    }
    best.map(|(_, axis, at)| (axis, at))
}

/// Appends to `out` the node over `refs` (the primitives of `set`, which spans all of it;
/// `refs[0]` is at `base` of the whole array) at node level `level`, and its subtree;
/// returns the node's index.
fn build_node(
    mut refs: Refs,
    base: usize,
    set: Set,
    level: usize,
    ctx: &Ctx,
    out: &mut Out,
) -> u32 {
    out.depth = out.depth.max(level);
    let sah = level <= MAX_SAH_LEVEL;
    // The children, in array order: keep splitting the one of largest area (then most
    // primitives; by count alone below MAX_SAH_LEVEL), the first of equals, until there
    // are eight or all are leaves.
    let mut kids: Vec<Set> = Vec::with_capacity(WIDTH);
    kids.push(set);
    while kids.len() < WIDTH {
        let mut pick: Option<(usize, (f32, usize))> = None;
        for (i, k) in kids.iter().enumerate() {
            if k.is_leaf() {
                continue;
            }
            let area = if sah {
                k.bounds.half_area(ctx.scale)
            } else {
                0.0
            };
            let size = (area, k.len());
            if pick.is_none_or(|(_, s)| size > s) {
                pick = Some((i, size));
            }
        }
        let Some((i, _)) = pick else { break };
        let (l, r) = split(&mut refs, &kids[i], ctx, sah);
        kids[i] = l;
        kids.insert(i + 1, r);
    }

    let index = out.nodes.len() as u32;
    let mut node = Node8::with_slots(kids.len());
    for (c, k) in kids.iter().enumerate() {
        for a in 0..3 {
            node.bounds[2 * a].0[c] = k.bounds.min[a];
            node.bounds[2 * a + 1].0[c] = k.bounds.max[a];
        }
    }
    out.nodes.push(node);

    // Leaves first (they need no recursion), then the inner children: on rayon tasks for a
    // large node, each into arrays of its own appended in child order, else in order.
    let mut inner: Vec<(usize, Refs, usize, Set)> = Vec::new();
    let mut rest = refs;
    let mut offset = 0;
    for (c, k) in kids.iter().enumerate() {
        let (part, tail) = rest.split_at(k.len());
        rest = tail;
        let node = &mut out.nodes[index as usize];
        if k.is_leaf() {
            node.leaf_mask |= 1 << c;
            if k.tris == k.len() {
                node.tri_only |= 1 << c;
            }
            let whole = Set {
                start: 0,
                end: k.len(),
                ..*k
            };
            let child = out.leaf(part.prims, base + offset, &whole, ctx);
            out.nodes[index as usize].child[c] = child;
        } else {
            let whole = Set {
                start: 0,
                end: k.len(),
                ..*k
            };
            inner.push((c, part, base + offset, whole));
        }
        offset += k.len();
    }
    let place = |out: &mut Out, c: usize, child: u32| {
        let below = &out.nodes[child as usize];
        let tri_only = below.tri_only == below.valid;
        let node = &mut out.nodes[index as usize];
        node.child[c] = child;
        node.tri_only |= u32::from(tri_only) << c;
    };
    if set.len() >= PARALLEL_MIN && inner.len() > 1 {
        use rayon::prelude::*;
        let subs: Vec<(usize, Out)> = inner
            .into_par_iter()
            .map(|(c, part, base, whole)| {
                let mut sub = Out::default();
                build_node(part, base, whole, level + 1, ctx, &mut sub);
                (c, sub)
            })
            .collect();
        for (c, sub) in subs {
            let below = &sub.nodes[0];
            out.nodes[index as usize].tri_only |= u32::from(below.tri_only == below.valid) << c;
            out.subs.push((index, c, sub));
        }
    } else {
        for (c, part, base, whole) in inner {
            let child = build_node(part, base, whole, level + 1, ctx, out);
            place(out, c, child);
        }
    }
    index
}

impl Bvh8 {
    /// The 8-wide tree over `prims` (at least one; triangles `0..num_triangles()`, then
    /// `spheres`, then instance leaves: primitive `num_triangles() + spheres.len() + k` is
    /// instance `k`) built top down by binned SAH (see the module doc). Deterministic: the
    /// same tree for any number of threads.
    pub(crate) fn binned(prims: &BuildPrims, spheres: &[Sphere]) -> Self {
        let tri_count = prims.num_triangles() as u32;
        let mut boxes: Vec<PrimBox> = (0..prims.count())
            .map(|i| {
                let b = prims.aabb(i);
                PrimBox {
                    min: b.min.into(),
                    max: b.max.into(),
                }
            })
            .collect();
        let mut order: Vec<u32> = (0..prims.count() as u32).collect();
        let set = Set::of(&boxes, &order, tri_count);
        let root = set.bounds;
        let ctx = Ctx {
            tri_count,
            instance_first: tri_count + spheres.len() as u32,
            spheres,
            scale: cost_scale(&obvhs::aabb::Aabb::new(root.min, root.max)),
        };
        let mut out = Out::default();
        let refs = Refs {
            boxes: &mut boxes,
            prims: &mut order,
        };
        build_node(refs, 0, set, 1, &ctx, &mut out);
        // `order` now lists the leaves' primitives leaf by leaf. The boxes are freed before
        // the packets are made: the two never coexist (issue 36, peak memory).
        drop(boxes);
        // Joined (a copy) before the packets exist, below the build's peak.
        let out = out.flatten();
        assert!(
            out.leaves.len() <= INDEX_MASK as usize && out.spheres.len() <= INDEX_MASK as usize,
            "too many leaves"
        );
        // Filled on rayon tasks, in leaf order (the same packets whatever the threads): on
        // a large mesh most of this is the first touch of the packets' pages, which the
        // main thread alone took after the subtrees were built (0.15 s of a 2M-triangle
        // mesh's build).
        use rayon::prelude::*;
        let packets: Vec<TriPacket8> = out
            .leaves
            .par_iter()
            .map(|&(start, count)| {
                let mut tris = [(0u32, [Vec3::ZERO; 3]); WIDTH];
                let leaf = &order[start as usize..(start + count) as usize];
                for (t, &p) in tris.iter_mut().zip(leaf) {
                    *t = (p, prims.triangle(p as usize));
                }
                TriPacket8::new(&tris[..leaf.len()])
            })
            .collect();
        Bvh8 {
            nodes: out.nodes,
            packets,
            spheres: out.spheres,
            instances: Vec::new(),
            objects: Vec::new(),
            max_abs: root.min.abs().max(root.max.abs()),
            depth: out.depth,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::SplitMix64 as Rng;

    /// Bins counted a chunk at a time and merged, in either order, are the bins of the
    /// whole set, bit for bit: the parallel binning's split is the serial one.
    #[test]
    fn merged_bins_are_the_bins_of_the_whole() {
        let mut rng = Rng(3);
        let n = 3 * BINNING_CHUNK / 2 + 17;
        let mut f = || rng.f32() * 10.0 - 5.0;
        let boxes: Vec<PrimBox> = (0..n)
            .map(|_| {
                let c = Vec3::new(f(), f(), f());
                let h = Vec3::new(f(), f(), f()).abs() * 0.01;
                PrimBox {
                    min: c - h,
                    max: c + h,
                }
            })
            .collect();
        let prims: Vec<u32> = (0..n as u32).collect();
        let tri_count = n as u32 / 3;
        let set = Set::of(&boxes, &prims, tri_count);
        let binning = Binning::new(&set, 1.0);
        let whole = bin_prims(&boxes, &prims, &binning, tri_count);
        let parts: Vec<AxisBins> = boxes
            .chunks(BINNING_CHUNK)
            .zip(prims.chunks(BINNING_CHUNK))
            .map(|(b, p)| bin_prims(b, p, &binning, tri_count))
            .collect();
        let forward = parts
            .iter()
            .copied()
            .fold([[EMPTY_BIN; BINS]; 3], merge_bins);
        let backward = parts
            .iter()
            .rev()
            .copied()
            .fold([[EMPTY_BIN; BINS]; 3], merge_bins);
        let bits = |b: &AxisBins| {
            b.iter()
                .flatten()
                .map(|b| {
                    let (lo, hi) = (b.bounds.min.to_array(), b.bounds.max.to_array());
                    (lo.map(f32::to_bits), hi.map(f32::to_bits), b.tris, b.others)
                })
                .collect::<Vec<_>>()
        };
        assert!(whole.iter().flatten().all(|b| b.tris + b.others < n as u32));
        assert_eq!(bits(&whole), bits(&forward));
        assert_eq!(bits(&whole), bits(&backward));
    }

    /// The partition's one-axis bin is the binning's bin on that axis, for centroids inside,
    /// beyond and below the set's, huge, tiny, signed zero and NaN: a primitive goes to the
    /// side its bin was counted on.
    #[test]
    fn one_axis_bins_are_the_binnings() {
        let mut rng = Rng(9);
        let set = Set {
            start: 0,
            end: 1000,
            bounds: Bounds::EMPTY,
            centroids: Bounds {
                min: Vec3A::new(-3.0, 0.0, 1e-30),
                max: Vec3A::new(5.0, 0.0, 2e-30),
            },
            tris: 1000,
        };
        let special = [
            0.0,
            -0.0,
            f32::NAN,
            f32::INFINITY,
            -f32::INFINITY,
            f32::MAX,
            1e-30,
            2e-30,
            -3.0,
            5.0,
        ];
        for scale in [1.0, 0.5, 0.3, 1e-20] {
            let binning = Binning::new(&set, scale);
            let mut f = || rng.f32() * 12.0 - 5.0;
            // And the floats at and beside every bin edge of x, where a rounding decides.
            let edges = (0..=binning.bins).flat_map(|b| {
                let v = (binning.min.x + b as f32 / binning.k.x) / scale;
                [v.next_down(), v, v.next_up()].map(|x| Vec3A::new(x, 0.0, 0.0))
            });
            let centroids = (0..10_000)
                .map(|_| Vec3A::new(f(), f(), f() * 1e-30))
                .chain(special.iter().map(|&v| Vec3A::splat(v)))
                .chain(edges);
            let mut spread = [0usize; BINS];
            for c in centroids {
                let all = binning.bins(c);
                for axis in 0..3 {
                    assert_eq!(binning.bin(c, axis), all[axis], "{c} axis {axis}");
                }
                spread[all[0]] += 1;
            }
            assert!(
                spread.iter().all(|&n| n > 0),
                "every bin reached: {spread:?}"
            );
        }
    }
}
