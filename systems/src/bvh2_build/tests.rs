//! The build's shape on coincident and degenerate input (structural: depth and work, never
//! time), and that the runs it sets apart leave ordinary meshes to PLOC untouched.

use glam::{Vec3, Vec3A};
use obvhs::{aabb::Aabb, bvh2::Bvh2, BvhBuildParams};

use obvhs::ploc::PlocBuilder;

use super::{build_bvh2, sort_by_code, stalled_runs, STALL_RUN};
use crate::bvh2_build::ReinsertionOptimizer;
use crate::bvh8::bvh2_depth;

fn boxes(tris: &[[Vec3; 3]]) -> Vec<Aabb> {
    tris.iter()
        .map(|t| {
            Aabb::new(
                Vec3A::from(t[0].min(t[1]).min(t[2])),
                Vec3A::from(t[0].max(t[1]).max(t[2])),
            )
        })
        .collect()
}

/// A bumpy `side` x `side` grid of quads, two triangles each.
fn grid(side: usize) -> Vec<[Vec3; 3]> {
    let p = |a: usize, b: usize| {
        let (x, y) = (a as f32 / side as f32, b as f32 / side as f32);
        Vec3::new(x, y, 0.1 * (7.0 * x).sin() * (5.0 * y).cos())
    };
    let mut t = Vec::new();
    for i in 0..side {
        for j in 0..side {
            t.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
            t.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
        }
    }
    t
}

/// The fan an OBJ loader makes of one polygon of `n` vertices on the unit circle.
fn fan(n: usize) -> Vec<[Vec3; 3]> {
    let v = |k: usize| {
        let a = k as f32 / n as f32 * std::f32::consts::TAU;
        Vec3::new(a.cos(), a.sin(), 0.0)
    };
    (1..n - 1).map(|k| [v(0), v(k), v(k + 1)]).collect()
}

/// Checks that `bvh2` is a binary tree over exactly the primitives `0..n`, one a leaf, each
/// leaf's box that of its primitive and each inner box the union of its children's; returns
/// its depth.
fn check_tree(bvh2: &Bvh2, aabbs: &[Aabb]) -> usize {
    let n = aabbs.len();
    assert_eq!(
        bvh2.nodes.len(),
        2 * n - 1,
        "a binary tree of one-primitive leaves"
    );
    let mut seen = vec![false; n];
    let mut stack = vec![0usize];
    while let Some(i) = stack.pop() {
        let node = &bvh2.nodes[i];
        if node.prim_count == 0 {
            let (l, r) = (node.first_index as usize, node.first_index as usize + 1);
            assert_eq!(
                node.aabb(),
                &bvh2.nodes[l].aabb().union(bvh2.nodes[r].aabb())
            );
            stack.extend([l, r]);
        } else {
            assert_eq!(node.prim_count, 1);
            let p = bvh2.primitive_indices[node.first_index as usize] as usize;
            assert!(!seen[p], "primitive {p} twice");
            seen[p] = true;
            assert_eq!(node.aabb(), &aabbs[p]);
        }
    }
    assert!(seen.iter().all(|s| *s), "a primitive is missing");
    bvh2_depth(bvh2)
}

fn build(aabbs: &[Aabb]) -> Bvh2 {
    build_bvh2(aabbs, &BvhBuildParams::medium_build())
}

/// `2 log2(n) + 8`: the depth a build over `n` primitives may reach.
fn log_depth(n: usize) -> usize {
    2 * (n as f64).log2().ceil() as usize + 8
}

#[test]
fn coincident_triangles_build_a_tree_of_logarithmic_depth() {
    // One triangle listed 100,000 times: PLOC alone merged one pair a pass (over 120 s).
    let n = 100_000;
    let aabbs = boxes(&vec![[Vec3::ZERO, Vec3::X, Vec3::Y]; n]);
    let runs = stalled_runs(&aabbs);
    assert_eq!(runs.len(), 1);
    assert_eq!(runs[0].len(), n, "the whole input is one stalled run");
    let depth = check_tree(&build(&aabbs), &aabbs);
    assert!(depth <= log_depth(n), "depth {depth}");
}

#[test]
fn a_mesh_listed_many_times_builds_a_tree_of_logarithmic_depth() {
    // A 200-triangle mesh listed 500 times, copy after copy.
    let mesh = grid(10);
    let tris: Vec<_> = (0..500).flat_map(|_| mesh.iter().copied()).collect();
    let aabbs = boxes(&tris);
    let covered: usize = stalled_runs(&aabbs).iter().map(Vec::len).sum();
    assert!(covered > tris.len() * 9 / 10, "{covered} of {}", tris.len());
    let depth = check_tree(&build(&aabbs), &aabbs);
    assert!(depth <= log_depth(tris.len()), "depth {depth}");
}

#[test]
fn degenerate_triangles_on_one_line_build_a_tree_of_logarithmic_depth() {
    // Every union of boxes on one axis-aligned line has zero area: all PLOC costs tie.
    let n = 50_000;
    let tris: Vec<_> = (0..n)
        .map(|k| {
            let x = k as f32;
            [
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + 0.5, 0.0, 0.0),
                Vec3::new(x + 1.0, 0.0, 0.0),
            ]
        })
        .collect();
    let aabbs = boxes(&tris);
    assert_eq!(stalled_runs(&aabbs).iter().map(Vec::len).sum::<usize>(), n);
    let depth = check_tree(&build(&aabbs), &aabbs);
    assert!(depth <= log_depth(n), "depth {depth}");
}

#[test]
fn a_fan_of_slivers_builds_a_tree_of_logarithmic_depth() {
    // One 100,000-vertex polygon triangulated as a fan: nested boxes whose union areas grow
    // along the Morton curve, so only the pair at a stretch's start merges.
    let tris = fan(100_000);
    let aabbs = boxes(&tris);
    let covered: usize = stalled_runs(&aabbs).iter().map(Vec::len).sum();
    assert!(covered > tris.len() * 3 / 4, "{covered} of {}", tris.len());
    // The slivers next to the shared vertex merge like a mesh's in PLOC's first pass and are
    // left to it; they chain a little in later passes (depth 60 here, against over 10,000
    // without the runs set apart), so twice the general bound.
    let depth = check_tree(&build(&aabbs), &aabbs);
    assert!(depth <= 2 * log_depth(tris.len()), "depth {depth}");
}

#[test]
fn coincident_copies_inside_a_mesh_are_grafted_and_the_mesh_left_to_ploc() {
    // A mesh with 20,000 copies of one of its triangles: the copies form one run, the rest
    // goes through PLOC, and the run's subtree is grafted where PLOC placed its box.
    let mut tris = grid(60);
    let mesh = tris.len();
    tris.extend(std::iter::repeat_n(tris[1234], 20_000));
    let aabbs = boxes(&tris);
    let runs = stalled_runs(&aabbs);
    let covered: usize = runs.iter().map(Vec::len).sum();
    assert!(
        (20_000..20_000 + mesh / 10).contains(&covered),
        "{covered} primitives set apart"
    );
    let depth = check_tree(&build(&aabbs), &aabbs);
    assert!(depth <= log_depth(tris.len()), "depth {depth}");
}

#[test]
fn meshes_take_plocs_path_unchanged() {
    // Nothing stalls on a mesh, so the tree is obvhs' own build, node for node (the leaves
    // PLOC starts from are made by `ploc`, not by obvhs: the same ones).
    for tris in [grid(160), fan(600)] {
        let aabbs = boxes(&tris);
        assert!(stalled_runs(&aabbs).is_empty());
        let params = BvhBuildParams::medium_build();
        let mut plain = PlocBuilder::with_capacity(aabbs.len()).build(
            params.ploc_search_distance,
            &aabbs,
            (0..aabbs.len() as u32).collect(),
            params.sort_precision,
            params.search_depth_threshold,
        );
        ReinsertionOptimizer::default().run(&mut plain, params.reinsertion_batch_ratio, None);
        let ours = build(&aabbs);
        assert_eq!(ours.primitive_indices, plain.primitive_indices);
        assert_eq!(ours.nodes.len(), plain.nodes.len());
        for (a, b) in ours.nodes.iter().zip(&plain.nodes) {
            assert_eq!(
                (a.aabb(), a.prim_count, a.first_index),
                (b.aabb(), b.prim_count, b.first_index)
            );
        }
    }
}

#[test]
fn short_stalls_are_left_to_ploc() {
    // A run of `STALL_RUN` equal boxes costs PLOC at most `STALL_RUN` passes: not set apart.
    let mut tris = grid(40);
    tris.extend(std::iter::repeat_n(tris[7], STALL_RUN - 2));
    assert!(stalled_runs(&boxes(&tris)).is_empty());
    tris.extend(std::iter::repeat_n(tris[7], 8));
    assert_eq!(stalled_runs(&boxes(&tris)).len(), 1);
}

#[test]
fn sort_by_code_orders_codes_and_keeps_equal_codes_in_order() {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut keys: Vec<u64> = (0..5000u64)
        .map(|i| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            // Codes of 30 bits, some repeated (low digits dropped every third key).
            let code = (state >> 34) & !(if i % 3 == 0 { 0xfffff } else { 0 });
            (code << 32) | i
        })
        .collect();
    let mut expected = keys.clone();
    expected.sort_unstable(); // by code, then position: what a stable sort by code gives
    sort_by_code(&mut keys);
    assert_eq!(keys, expected);
}
