//! The binary BVH build: obvhs' PLOC builder and reinsertion optimizer, with the runs of
//! primitives on which PLOC's merging stalls built apart, so the build stays `O(n log n)` on
//! coincident and degenerate input.
//!
//! PLOC (Meister and Bittner 2018, "Parallel Locally-Ordered Clustering for Bounding Volume
//! Hierarchy Construction") sorts the boxes along a Morton curve and, each pass, merges the
//! pairs of neighbours (within a search window) that choose each other as the partner of
//! least union area. A pass merges at least one pair, and on ordinary meshes a constant
//! fraction of them, so there are `O(log n)` passes. On equal costs it degenerates: obvhs
//! takes the farthest of tied candidates (`<=`), so in a run of equal boxes (one triangle
//! listed 100,000 times, a mesh listed 10,000 times), of boxes whose unions all have zero
//! area (degenerate triangles along one axis-aligned line) or of nested boxes whose union
//! areas grow monotonically along the curve (a fan of slivers from one polygon), only the
//! pair at the run's end agrees. Every pass then merges one pair per run and costs `O(n)`:
//! `O(n * run)` in all, and a chain `run` levels deep.
//!
//! [`build_bvh2`] finds such runs before PLOC by replaying its first pass (search distance
//! 1: a node points at the side of the cheaper pair, equal costs pointing right) on a
//! Morton order close to PLOC's: a stretch of more than [`STALL_RUN`] consecutive
//! primitives none of which is merged, or a block of [`STALL_BLOCK`] of which fewer than
//! half are, is a run. Each run is built apart by median splits (by count where centroids
//! coincide, so every primitive is kept: a duplicated emitter keeps its power) and given to
//! PLOC as one box, and its subtree is grafted where PLOC placed that box. Input without
//! runs (meshes, and every scene under `scenes/`) takes PLOC's path unchanged, bit for bit;
//! the replay costs about 4 % of a mesh's build (instructions, 200k triangles).
//!
//! A stall that shows only in PLOC's later passes is not seen: the fan's slivers next to
//! the shared vertex merge like a mesh's at first and are left to PLOC, where they chain
//! a little (depth 60 for 100,000 slivers); a tree deeper than [`MAX_BVH2_DEPTH`] is still
//! replaced by a median-split one.

use glam::Vec3A;
use obvhs::{
    aabb::Aabb,
    bvh2::{node::Bvh2Node, reinsertion::ReinsertionOptimizer, Bvh2, DEFAULT_MAX_STACK_DEPTH},
    ploc::{morton::morton_encode_u32, PlocBuilder, PlocSearchDistance},
    BvhBuildParams,
};

use crate::build_prims::PrimBoxes;

use crate::bvh8::{bvh2_depth, median_bvh2, node_box, MAX_BVH2_DEPTH};

/// Longest stretch of primitives, consecutive on the Morton curve, that PLOC's first pass
/// may leave entirely unmerged before they are built apart. On meshes the stretches are a
/// few primitives (a merge wherever the neighbour costs have a local minimum); a longer
/// one costs PLOC up to one pass over the whole scene per primitive of the stretch.
pub(crate) const STALL_RUN: usize = 64;

/// Nodes per block of the merge-density test of [`stalled_runs`].
const STALL_BLOCK: usize = 1024;

/// A block of [`STALL_BLOCK`] nodes stalls when fewer than one node in this many is merged
/// by PLOC's first pass: on meshes (a bumpy or flat grid, a UV sphere) about seven in
/// eight are, on a fan of slivers from one polygon about one in six.
const STALL_DENSITY: usize = 2;

/// Below this many primitives stalls are not looked for: PLOC's worst case,
/// `O(n^2)` box unions, is then a few million.
const STALL_MIN_PRIMS: usize = STALL_BLOCK;

/// The binary BVH over `prims` (primitive `i` bounded by `prims.aabb(i)`; at least one):
/// PLOC with `params`' search distance and sort precision, then the reinsertion optimizer,
/// with the runs on which PLOC stalls built by median splits (see the module doc); a tree
/// still deeper than [`MAX_BVH2_DEPTH`] is replaced by a median-split one. The boxes are
/// computed where they are read, never stored for all primitives at once (32 bytes a
/// primitive less at the build's peak, issue 36).
pub(crate) fn build_bvh2<P: PrimBoxes + ?Sized>(prims: &P, params: &BvhBuildParams) -> Bvh2 {
    let runs = stalled_runs(prims);
    let mut bvh2 = if runs.is_empty() {
        ploc(prims, params)
    } else {
        ploc_around_runs(prims, &runs, params)
    };
    if bvh2_depth(&bvh2) <= MAX_BVH2_DEPTH {
        ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
    }
    // PLOC chains equal boxes that escaped the run detection; a median split bounds the
    // depth whatever the boxes.
    if bvh2_depth(&bvh2) > MAX_BVH2_DEPTH {
        bvh2 = median_bvh2(prims, &(0..prims.count() as u32).collect::<Vec<_>>());
    }
    bvh2
}

/// obvhs' PLOC build of `prims`, primitive `i` at position `i`: its `PlocBuilder::build`
/// step for step, but with the leaves made here from [`PrimBoxes`] (obvhs wants a slice of
/// boxable items, and the welded triangles are not one: issue 36).
fn ploc<P: PrimBoxes + ?Sized>(prims: &P, params: &BvhBuildParams) -> Bvh2 {
    let n = prims.count();
    let mut bvh = Bvh2::zeroed(n);
    bvh.reset_for_reuse(n, Some((0..n as u32).collect()));
    if n == 0 {
        return bvh;
    }
    let mut builder = PlocBuilder::new();
    let mut total = Aabb::empty();
    builder.current_nodes = (0..n)
        .map(|i| {
            let b = prims.aabb(i);
            total.extend(b.min);
            total.extend(b.max);
            Bvh2Node::new(b, 1, i as u32)
        })
        .collect();
    let (precision, depth) = (params.sort_precision, params.search_depth_threshold);
    // obvhs' `build_with_bvh`: the search distance is a const parameter.
    macro_rules! merge {
        ($distance:literal) => {
            builder.build_ploc_from_leaves::<$distance, false>(&mut bvh, total, precision, depth)
        };
    }
    match params.ploc_search_distance {
        PlocSearchDistance::Minimum => merge!(1),
        PlocSearchDistance::VeryLow => merge!(2),
        PlocSearchDistance::Low => merge!(6),
        PlocSearchDistance::Medium => merge!(14),
        PlocSearchDistance::High => merge!(24),
        PlocSearchDistance::VeryHigh => merge!(32),
    }
    bvh
}

/// The primitives (positions in `aabbs`) of each run on which PLOC would stall: stretches
/// of primitives, consecutive in PLOC's Morton order, that its first pass leaves unmerged
/// (more than [`STALL_RUN`] in a row, or most of a block of [`STALL_BLOCK`]). Empty for
/// fewer than [`STALL_MIN_PRIMS`] primitives.
pub(crate) fn stalled_runs<P: PrimBoxes + ?Sized>(aabbs: &P) -> Vec<Vec<u32>> {
    if aabbs.count() < STALL_MIN_PRIMS {
        return Vec::new();
    }
    stalls(aabbs, 0..aabbs.count(), STALL_RUN)
}

/// The stalls of PLOC's first pass over the primitives `prims` (positions in `aabbs`):
/// stretches of more than `run` unmerged ones in Morton order, or blocks of
/// [`STALL_BLOCK`] mostly unmerged, joined where they overlap or touch, as lists of
/// positions.
fn stalls<P: PrimBoxes + ?Sized>(
    aabbs: &P,
    prims: impl Iterator<Item = usize> + Clone,
    run: usize,
) -> Vec<Vec<u32>> {
    // Morton order of the box centres in the unit cube of all boxes' bounds, 10 bits an
    // axis, equal codes in input order: PLOC's order (21 bits an axis) up to the order
    // within cells, which on meshes holds a few neighbouring primitives at most and in a
    // run of equal boxes does not matter. Codes and positions share one `u64` key.
    let total = prims.clone().fold(Aabb::empty(), |mut t, p| {
        let b = aabbs.aabb(p);
        t.extend(b.min);
        t.extend(b.max);
        t
    });
    let cells = Vec3A::splat(1023.0);
    let scale = cells / total.diagonal().max(Vec3A::splat(f32::MIN_POSITIVE));
    let mut order: Vec<u64> = prims
        .map(|i| {
            let b = aabbs.aabb(i);
            // Float to integer casts saturate: NaN (an infinite extent) and negatives to 0.
            let c = ((b.center() - total.min) * scale).min(cells);
            let code = morton_encode_u32(c.x as u16, c.y as u16, c.z as u16);
            (u64::from(code) << 32) | i as u64
        })
        .collect();
    sort_by_code(&mut order);
    let n = order.len();
    let prim = |i: usize| order[i] as u32 as usize;

    // PLOC's first pass (search distance 1): node `i` points left when the pair on its left
    // is strictly cheaper than the pair on its right, else right; the last node points left.
    // Pair `(i, i + 1)` merges when `i` points right and `i + 1` points left. A stall: a
    // stretch of more than `STALL_RUN` unmerged nodes, or a block of `STALL_BLOCK` nodes (the
    // last one absorbing the remainder) of which fewer than one in `STALL_DENSITY` is merged
    // (a fan's slivers merge in short pieces between long unmerged stretches, and the pieces
    // stall again in later passes).
    let blocks = (n / STALL_BLOCK).max(1);
    let block_of = |i: usize| (i / STALL_BLOCK).min(blocks - 1);
    let mut merged_in_block = vec![0usize; blocks];
    let mut stalls: Vec<(usize, usize)> = Vec::new();
    let cost = |i: usize| {
        aabbs
            .aabb(prim(i))
            .union(&aabbs.aabb(prim(i + 1)))
            .half_area()
    };
    // First node of the current unmerged stretch.
    let mut start = 0;
    let (mut left, mut here) = (f32::INFINITY, cost(0));
    for i in 0..n - 1 {
        let right = if i + 2 < n {
            cost(i + 1)
        } else {
            f32::NEG_INFINITY
        };
        // `i` points right (ties included), `i + 1` left (always, if it is the last node).
        if left.partial_cmp(&here) != Some(std::cmp::Ordering::Less) && here < right {
            if i - start > run {
                stalls.push((start, i));
            }
            start = i + 2;
            merged_in_block[block_of(i)] += 1;
            merged_in_block[block_of(i + 1)] += 1;
        }
        (left, here) = (here, right);
    }
    if n - start > run {
        stalls.push((start, n));
    }
    for (b, merged) in merged_in_block.iter().enumerate() {
        let end = if b + 1 == blocks {
            n
        } else {
            (b + 1) * STALL_BLOCK
        };
        if merged * STALL_DENSITY < end - b * STALL_BLOCK {
            stalls.push((b * STALL_BLOCK, end));
        }
    }

    // Runs: the union of the stalls, overlapping or touching ones joined.
    stalls.sort_unstable();
    let mut joined: Vec<(usize, usize)> = Vec::new();
    for (s, e) in stalls {
        match joined.last_mut() {
            Some(last) if s <= last.1 => last.1 = last.1.max(e),
            _ => joined.push((s, e)),
        }
    }
    joined
        .into_iter()
        .map(|(s, e)| (s..e).map(|i| prim(i) as u32).collect())
        .collect()
}

/// PLOC over the primitives outside `runs` and one box per run, each run's leaf replaced by
/// the run's median-split subtree.
fn ploc_around_runs<P: PrimBoxes + ?Sized>(
    aabbs: &P,
    runs: &[Vec<u32>],
    params: &BvhBuildParams,
) -> Bvh2 {
    let mut in_run = vec![false; aabbs.count()];
    for &p in runs.iter().flatten() {
        in_run[p as usize] = true;
    }
    // PLOC's primitives: the positions outside runs, then one per run (its local index
    // `loose.len() + r`).
    let loose: Vec<u32> = (0..aabbs.count() as u32)
        .filter(|&p| !in_run[p as usize])
        .collect();
    let mut boxes: Vec<Aabb> = loose.iter().map(|&p| aabbs.aabb(p as usize)).collect();
    let subtrees: Vec<Bvh2> = runs
        .iter()
        .map(|run| {
            let run_boxes: Vec<Aabb> = run.iter().map(|&p| aabbs.aabb(p as usize)).collect();
            median_bvh2(run_boxes.as_slice(), run)
        })
        .collect();
    boxes.extend(subtrees.iter().map(|t| node_box(&t.nodes[0])));
    let top = ploc(boxes.as_slice(), params);

    // Copy the top tree from its root down, children after parents as PLOC lays them out,
    // mapping its leaves back to primitive indices or grafting a run's subtree.
    let mut nodes = vec![Bvh2Node::default()];
    let mut primitive_indices = Vec::with_capacity(aabbs.count());
    let mut stack = vec![(0usize, 0usize)];
    while let Some((src, dst)) = stack.pop() {
        let node = top.nodes[src];
        if node.prim_count == 0 {
            let first = nodes.len();
            nodes.extend([Bvh2Node::default(); 2]);
            nodes[dst] = Bvh2Node::new(node_box(&node), 0, first as u32);
            stack.push((node.first_index as usize + 1, first + 1));
            stack.push((node.first_index as usize, first));
            continue;
        }
        let local = top.primitive_indices[node.first_index as usize] as usize;
        if let Some(&p) = loose.get(local) {
            nodes[dst] = Bvh2Node::new(node_box(&node), 1, primitive_indices.len() as u32);
            primitive_indices.push(p);
            continue;
        }
        let sub = &subtrees[local - loose.len()];
        // The subtree's root takes the leaf's slot; its other nodes follow, their child
        // and primitive offsets moved by where they land.
        let (node_base, prim_base) = (nodes.len() as u32 - 1, primitive_indices.len() as u32);
        let moved = |n: &Bvh2Node| {
            let first = if n.prim_count == 0 {
                n.first_index + node_base
            } else {
                n.first_index + prim_base
            };
            Bvh2Node::new(node_box(n), n.prim_count, first)
        };
        let mut moved_nodes = sub.nodes.iter().map(moved);
        nodes[dst] = moved_nodes.next().expect("a subtree has a root");
        nodes.extend(moved_nodes);
        primitive_indices.extend_from_slice(&sub.primitive_indices);
    }
    let mut bvh2 = Bvh2 {
        nodes,
        primitive_indices,
        children_are_ordered_after_parents: true,
        ..Default::default()
    };
    bvh2.max_depth = DEFAULT_MAX_STACK_DEPTH.max(bvh2_depth(&bvh2) + 1);
    bvh2
}

/// Sorts `keys` (a 30-bit Morton code above a 32-bit position) by code, equal codes kept in
/// order: a least significant digit radix sort, three passes of 10 bits (Knuth, TAOCP
/// vol. 3, sec. 5.2.5), where a comparison sort cost half the detection on a mesh.
fn sort_by_code(keys: &mut Vec<u64>) {
    const BITS: u32 = 10;
    const BUCKETS: usize = 1 << BITS;
    let digit = |key: u64, pass: u32| ((key >> (32 + BITS * pass)) as usize) & (BUCKETS - 1);
    let mut counts = [[0usize; BUCKETS]; 3];
    for &key in keys.iter() {
        for (pass, count) in counts.iter_mut().enumerate() {
            count[digit(key, pass as u32)] += 1;
        }
    }
    let mut out = vec![0u64; keys.len()];
    for (pass, count) in counts.iter().enumerate() {
        if count.contains(&keys.len()) {
            continue; // every key has this digit: the pass would not move anything
        }
        let mut offsets = [0usize; BUCKETS];
        let mut sum = 0;
        for (offset, c) in offsets.iter_mut().zip(count) {
            *offset = sum;
            sum += c;
        }
        for &key in keys.iter() {
            let d = digit(key, pass as u32);
            out[offsets[d]] = key;
            offsets[d] += 1;
        }
        std::mem::swap(keys, &mut out);
    }
}

#[cfg(test)]
mod tests;
