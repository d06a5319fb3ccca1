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
//! [`build_bvh2`] finds such runs before PLOC from its first pass, which it replays exactly
//! on the same Morton order (search distance 1: `merge` points at the cheaper side, equal
//! costs pointing right): a stretch of more than [`STALL_RUN`] consecutive primitives of
//! which none is merged is a run. Each run is built apart by median splits (by count where
//! centroids coincide, so every primitive is kept) and given to PLOC as one box, and its
//! subtree is grafted where PLOC placed that box. Input without such runs (every scene
//! that built in reasonable time before) takes PLOC's path unchanged, bit for bit.

use glam::DVec3;
use obvhs::{
    aabb::Aabb,
    bvh2::{node::Bvh2Node, reinsertion::ReinsertionOptimizer, Bvh2, DEFAULT_MAX_STACK_DEPTH},
    ploc::{morton::morton_encode_u64_unorm, PlocBuilder},
    BvhBuildParams,
};

use crate::bvh8::{bvh2_depth, median_bvh2, MAX_BVH2_DEPTH};

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

/// The binary BVH over `aabbs` (primitive `indices[i]` has box `aabbs[i]`; at least one):
/// PLOC with `params`' search distance and sort precision, then the reinsertion optimizer,
/// with the runs on which PLOC stalls built by median splits (see the module doc); a tree
/// still deeper than [`MAX_BVH2_DEPTH`] is replaced by a median-split one.
pub(crate) fn build_bvh2(aabbs: &[Aabb], indices: Vec<u32>, params: &BvhBuildParams) -> Bvh2 {
    let runs = stalled_runs(aabbs);
    let mut bvh2 = if runs.is_empty() {
        ploc(aabbs, indices.clone(), params)
    } else {
        ploc_around_runs(aabbs, &indices, &runs, params)
    };
    if bvh2_depth(&bvh2) <= MAX_BVH2_DEPTH {
        ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
    }
    // PLOC chains equal boxes that escaped the run detection; a median split bounds the
    // depth whatever the boxes.
    if bvh2_depth(&bvh2) > MAX_BVH2_DEPTH {
        bvh2 = median_bvh2(aabbs, &indices);
    }
    bvh2
}

/// obvhs' PLOC build of `aabbs` with `indices`.
fn ploc(aabbs: &[Aabb], indices: Vec<u32>, params: &BvhBuildParams) -> Bvh2 {
    PlocBuilder::with_capacity(aabbs.len()).build(
        params.ploc_search_distance,
        aabbs,
        indices,
        params.sort_precision,
        params.search_depth_threshold,
    )
}

/// The primitives (positions in `aabbs`) of each run on which PLOC would stall: stretches
/// of more than [`STALL_RUN`] primitives, consecutive in PLOC's Morton order, that its first
/// pass leaves unmerged. Empty for fewer than [`STALL_MIN_PRIMS`] primitives.
pub(crate) fn stalled_runs(aabbs: &[Aabb]) -> Vec<Vec<u32>> {
    let n = aabbs.len();
    if n < STALL_MIN_PRIMS {
        return Vec::new();
    }
    // PLOC's Morton codes: box centres mapped into the unit cube of all boxes' bounds, 21
    // bits an axis (obvhs' `SortPrecision::U64`; the order only decides which neighbours
    // are compared, and runs of equal codes are equal or nearly equal boxes either way).
    let total = aabbs.iter().fold(Aabb::empty(), |mut t, b| {
        t.extend(b.min);
        t.extend(b.max);
        t
    });
    let scale = 1.0 / total.diagonal().as_dvec3();
    let offset = -total.min.as_dvec3() * scale;
    let mut order: Vec<(u64, u32)> = aabbs
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let c: DVec3 = b.center().as_dvec3() * scale + offset;
            (morton_encode_u64_unorm(c), i as u32)
        })
        .collect();
    radix_sort(&mut order);

    // PLOC's first pass (search distance 1): node `i` points left when the pair on its left
    // is strictly cheaper than the pair on its right, else right; the last node points left.
    // Pair `(i, i + 1)` merges when `i` points right and `i + 1` points left.
    let cost = |i: usize| {
        aabbs[order[i].1 as usize]
            .union(&aabbs[order[i + 1].1 as usize])
            .half_area()
    };
    // Whether each node stays unmerged by the pass.
    let mut unmerged = vec![true; n];
    let (mut left, mut here) = (f32::INFINITY, cost(0));
    for i in 0..n - 1 {
        let right = if i + 2 < n { cost(i + 1) } else { f32::NEG_INFINITY };
        // `i` points right (ties included), `i + 1` left (always, if it is the last node).
        if !(left < here) && here < right {
            unmerged[i] = false;
            unmerged[i + 1] = false;
        }
        (left, here) = (here, right);
    }

    // A stall: a stretch of more than `STALL_RUN` unmerged nodes, or a block of
    // `STALL_BLOCK` nodes (the last one absorbing the remainder) of which fewer than one in
    // `STALL_DENSITY` is merged (a fan's slivers merge in short pieces between long
    // unmerged stretches, and the pieces stall again in later passes).
    let mut stalled = vec![false; n];
    let mut start = 0;
    for i in 0..=n {
        if i == n || !unmerged[i] {
            if i - start > STALL_RUN {
                stalled[start..i].fill(true);
            }
            start = i + 1;
        }
    }
    let blocks = n / STALL_BLOCK;
    for b in 0..blocks {
        let end = if b + 1 == blocks { n } else { (b + 1) * STALL_BLOCK };
        let block = b * STALL_BLOCK..end;
        let merged = unmerged[block.clone()].iter().filter(|u| !**u).count();
        if merged * STALL_DENSITY < block.len() {
            stalled[block].fill(true);
        }
    }

    // Runs: maximal stretches of stalled nodes.
    let mut runs = Vec::new();
    let mut i = 0;
    while i < n {
        if !stalled[i] {
            i += 1;
            continue;
        }
        let start = i;
        while i < n && stalled[i] {
            i += 1;
        }
        runs.push(order[start..i].iter().map(|o| o.1).collect());
    }
    runs
}

/// PLOC over the primitives outside `runs` and one box per run, each run's leaf replaced by
/// the run's median-split subtree.
fn ploc_around_runs(
    aabbs: &[Aabb],
    indices: &[u32],
    runs: &[Vec<u32>],
    params: &BvhBuildParams,
) -> Bvh2 {
    let mut in_run = vec![false; aabbs.len()];
    for &p in runs.iter().flatten() {
        in_run[p as usize] = true;
    }
    // PLOC's primitives: the positions outside runs, then one per run (its local index
    // `loose.len() + r`).
    let loose: Vec<u32> = (0..aabbs.len() as u32)
        .filter(|&p| !in_run[p as usize])
        .collect();
    let mut boxes: Vec<Aabb> = loose.iter().map(|&p| aabbs[p as usize]).collect();
    let subtrees: Vec<Bvh2> = runs
        .iter()
        .map(|run| {
            let run_boxes: Vec<Aabb> = run.iter().map(|&p| aabbs[p as usize]).collect();
            let run_indices: Vec<u32> = run.iter().map(|&p| indices[p as usize]).collect();
            median_bvh2(&run_boxes, &run_indices)
        })
        .collect();
    boxes.extend(subtrees.iter().map(|t| t.nodes[0].aabb));
    let top = ploc(&boxes, (0..boxes.len() as u32).collect(), params);

    // Copy the top tree from its root down, children after parents as PLOC lays them out,
    // mapping its leaves back to primitive indices or grafting a run's subtree.
    let mut nodes = vec![Bvh2Node::default()];
    let mut primitive_indices = Vec::with_capacity(aabbs.len());
    let mut stack = vec![(0usize, 0usize)];
    while let Some((src, dst)) = stack.pop() {
        let node = top.nodes[src];
        if node.prim_count == 0 {
            let first = nodes.len();
            nodes.extend([Bvh2Node::default(); 2]);
            nodes[dst] = Bvh2Node::new(node.aabb, 0, first as u32);
            stack.push((node.first_index as usize + 1, first + 1));
            stack.push((node.first_index as usize, first));
            continue;
        }
        let local = top.primitive_indices[node.first_index as usize] as usize;
        if let Some(&p) = loose.get(local) {
            nodes[dst] = Bvh2Node::new(node.aabb, 1, primitive_indices.len() as u32);
            primitive_indices.push(indices[p as usize]);
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
            Bvh2Node::new(n.aabb, n.prim_count, first)
        };
        nodes[dst] = moved(&sub.nodes[0]);
        nodes.extend(sub.nodes[1..].iter().map(moved));
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

/// Sorts `(key, index)` pairs by key (least significant digit radix sort, 8 bits a pass;
/// passes where every key has the same digit are skipped): `O(n)` for the Morton codes of
/// [`stalled_runs`], where a comparison sort cost as much as a tenth of the whole build.
fn radix_sort(pairs: &mut Vec<(u64, u32)>) {
    let n = pairs.len();
    let mut counts = [[0usize; 256]; 8];
    for &(key, _) in pairs.iter() {
        for (d, count) in counts.iter_mut().enumerate() {
            count[((key >> (8 * d)) & 0xff) as usize] += 1;
        }
    }
    let mut out = vec![(0u64, 0u32); n];
    for (d, count) in counts.iter().enumerate() {
        if count.contains(&n) {
            continue;
        }
        let mut offsets = [0usize; 256];
        let mut sum = 0;
        for (o, c) in offsets.iter_mut().zip(count) {
            *o = sum;
            sum += c;
        }
        for &pair in pairs.iter() {
            let digit = ((pair.0 >> (8 * d)) & 0xff) as usize;
            out[offsets[digit]] = pair;
            offsets[digit] += 1;
        }
        std::mem::swap(pairs, &mut out);
    }
}

#[cfg(test)]
mod tests;
