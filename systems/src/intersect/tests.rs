//! Tests of `intersect.rs`.

use super::*;
use crate::geometry::{BvhBuilder, Sphere};

use crate::sampler::SplitMix64 as Rng;

/// The branch-free axis choice of `shear` against the paper's nested comparisons,
/// ties included (a tie never picks the earlier axis: `>` is strict).
#[test]
fn shear_picks_the_dominant_axis_as_the_nested_comparisons_do() {
    let reference = |a: Vec3A| {
        if a.x > a.y {
            if a.x > a.z {
                Axis::X
            } else {
                Axis::Z
            }
        } else if a.y > a.z {
            Axis::Y
        } else {
            Axis::Z
        }
    };
    let values = [0.0f32, 0.5, 1.0, -1.0, 2.0, -2.0];
    for &x in &values {
        for &y in &values {
            for &z in &values {
                let d = Vec3A::new(x, y, z);
                let o = Vec3A::new(10.0, 20.0, 30.0);
                let (kx, ky, kz, po, _) = shear(o, d);
                assert_eq!(kz, reference(d.abs()), "direction {d}");
                assert_eq!(kx as usize, (kz as usize + 1) % 3, "direction {d}");
                assert_eq!(ky as usize, (kx as usize + 1) % 3, "direction {d}");
                let expected = Vec3A::new(o[kx as usize], o[ky as usize], o[kz as usize]);
                assert_eq!(po, expected, "direction {d}");
            }
        }
    }
}

/// Test-input helpers on top of the shared generator.
trait RngExt {
    fn vec(&mut self, lo: f32, hi: f32) -> Vec3;
}

impl RngExt for Rng {
    fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.f32(), self.f32(), self.f32()) * (hi - lo) + Vec3::splat(lo)
    }
}

/// The closest hit of the one ray `o + t d` (`t` in `[0, inf)`) in `geom`: `(t, prim, b1, b2)`
/// as [`intersect_closest`] writes them.
pub(super) fn closest_one(geom: &SceneGeometry, o: Vec3, d: Vec3) -> (f32, u32, f32, f32) {
    let (mut t, mut prim, mut b1, mut b2) = ([0.0], [0], [0.0], [0.0]);
    intersect_closest(
        geom,
        &[o],
        &[d],
        &[0.0],
        &[f32::INFINITY],
        &mut t,
        &mut prim,
        &mut b1,
        &mut b2,
    );
    (t[0], prim[0], b1[0], b2[0])
}

/// Every kernel this CPU runs.
fn backends() -> Vec<Backend> {
    let all = [Kernel::Portable, Kernel::Avx2];
    let b: Vec<Backend> = all.iter().filter_map(|k| k.backend()).collect();
    assert!(!b.is_empty());
    b
}

/// Evaluates `$e` with `$s` bound to the lane implementation of backend `$b`.
macro_rules! with_simd {
    ($b:expr, $s:ident => $e:expr) => {
        match $b {
            Backend::Portable => {
                let $s = Portable;
                $e
            }
            #[cfg(target_arch = "x86_64")]
            Backend::Avx2(tok) => {
                let $s = tok;
                $e
            }
        }
    };
}

fn node_mask<S: Simd>(
    s: S,
    node: &Node8,
    o: Vec3,
    d: Vec3,
    tmin: f32,
    tmax: f32,
    max_abs: Vec3A,
) -> u32 {
    let mut block = RayBlock::zero();
    // The slab test alone: a NaN `tmin` turns the cull off (see
    // `node_cull_only_removes_children_the_packet_test_rejects` for the cull).
    block.set(s, &[o], &[d], &[f32::NAN], max_abs);
    let ray = NodeRay::new(s, &block, 0, tmin);
    intersect_node8(s, node, &ray, tmax).0
}

/// The 8-wide node test of every kernel against an exact slab test in f64 on the same
/// clamped inverse direction: every child box the ray truly meets within `[tmin, tmax]`
/// must be hit (conservative), and boxes it misses by more than the widening must not be.
#[test]
fn node8_test_is_conservative_and_tight() {
    for backend in backends() {
        let mut rng = Rng(3);
        let tris: Vec<[Vec3; 3]> = (0..3000)
            .map(|_| {
                let c = rng.vec(-10.0, 10.0);
                [
                    c + rng.vec(-0.5, 0.5),
                    c + rng.vec(-0.5, 0.5),
                    c + rng.vec(-0.5, 0.5),
                ]
            })
            .collect();
        let spheres = vec![Sphere {
            center: Vec3::ONE,
            radius: 0.3,
        }];
        let geom = SceneGeometry::build(tris, spheres);
        let (bvh, _) = geom.bvh8().unwrap();
        let (mut hits, mut misses, mut touching) = (0, 0, 0);
        for k in 0..3000 {
            let o = rng.vec(-12.0, 12.0);
            // Mostly aimed at a box corner, so the ray grazes that box (without the
            // widening rounding culls some of these boxes; checked), else near a
            // triangle.
            let node = &bvh.nodes[(rng.next_u64() % bvh.nodes.len() as u64) as usize];
            let c = (rng.next_u64() % WIDTH as u64) as usize;
            let target = if k % 3 != 2 && node.bounds[0].0[c].is_finite() {
                Vec3::new(
                    node.bounds[0].0[c],
                    node.bounds[3].0[c],
                    node.bounds[4].0[c],
                )
            } else {
                geom.triangle((rng.next_u64() % 3000) as usize)[0] + rng.vec(-0.1, 0.1)
            };
            let mut d = target - o;
            // Axis-parallel directions, including negative zeros.
            match k % 7 {
                1 => d.x = 0.0,
                2 => d.y = -0.0,
                4 => d = Vec3::new(0.0, -0.0, d.z),
                _ => {}
            }
            let (tmin, tmax) = if k % 2 == 0 {
                (0.0, f32::INFINITY)
            } else {
                (rng.f32() * 0.5, 0.5 + rng.f32())
            };
            let inv = |x: f32| -> f64 {
                if x.abs() < MIN_DIR {
                    (1.0 / MIN_DIR as f64).copysign(x as f64)
                } else {
                    1.0 / x as f64
                }
            };
            let inv = [inv(d.x), inv(d.y), inv(d.z)];
            let (o64, b64) = (o.as_dvec3().to_array(), bvh.max_abs.as_dvec3().to_array());
            for node in &bvh.nodes {
                let mask =
                    with_simd!(backend, s => node_mask(s, node, o, d, tmin, tmax, bvh.max_abs));
                for c in 0..WIDTH {
                    if node.valid & (1 << c) == 0 {
                        assert_eq!(mask & (1 << c), 0, "empty slot hit");
                        continue;
                    }
                    let (mut tn, mut tf) = (tmin as f64, tmax as f64);
                    let mut margin = 0.0f64;
                    for a in 0..3 {
                        let lo = (node.bounds[2 * a].0[c] as f64 - o64[a]) * inv[a];
                        let hi = (node.bounds[2 * a + 1].0[c] as f64 - o64[a]) * inv[a];
                        tn = tn.max(lo.min(hi));
                        tf = tf.min(lo.max(hi));
                        margin = margin.max(1e-5 * (b64[a] + o64[a].abs()) * inv[a].abs());
                    }
                    let got = mask & (1 << c) != 0;
                    if tn <= tf {
                        assert!(
                            got,
                            "{backend:?} ray {k}: o={o:?} d={d:?} misses child {c} of {node:?}"
                        );
                        hits += 1;
                        touching += (tn == tf) as usize;
                    } else if tn > tf + margin {
                        assert!(
                            !got,
                            "{backend:?} ray {k}: o={o:?} d={d:?} hits child {c} of {node:?}"
                        );
                        misses += 1;
                    }
                }
            }
        }
        assert!(
            hits > 3_000 && misses > 50_000 && touching > 10,
            "{backend:?}: {hits} child hits ({touching} touching), {misses} misses"
        );
    }
}

/// The collapse keeps every primitive exactly once, every child box contains what it
/// holds, packets hold their triangles' vertices exactly (padding repeats lane 0), and
/// every node is reachable from the root exactly once.
#[test]
fn bvh8_collapse_is_a_complete_bounding_tree() {
    for builder in [BvhBuilder::Ploc, BvhBuilder::Binned] {
        complete_bounding_tree(builder);
    }
}

/// [`bvh8_collapse_is_a_complete_bounding_tree`] of one builder.
fn complete_bounding_tree(builder: BvhBuilder) {
    let mut rng = Rng(5);
    for n in [1usize, 2, 3, 5, 8, 9, 17, 2000] {
        let tris: Vec<[Vec3; 3]> = (0..n)
            .map(|_| {
                let c = rng.vec(-10.0, 10.0);
                [c, c + rng.vec(-0.5, 0.5), c + rng.vec(-3.0, 3.0)]
            })
            .collect();
        let spheres: Vec<Sphere> = (0..n / 4)
            .map(|_| Sphere {
                center: rng.vec(-10.0, 10.0),
                radius: 0.1 + rng.f32(),
            })
            .collect();
        let geom = SceneGeometry::build_with_builder(tris.clone(), spheres.clone(), builder);
        let (bvh, _) = geom.bvh8().unwrap();
        let mut seen = vec![0u32; n + spheres.len()];
        let mut reached = vec![0u32; bvh.nodes.len()];
        let mut leaves = (vec![0u32; bvh.packets.len()], vec![0u32; bvh.spheres.len()]);
        let mut stack = vec![(0usize, 1usize)];
        let mut depth = 0;
        reached[0] = 1;
        let child_box = |node: &Node8, c: usize| {
            let b = |r: usize| node.bounds[r].0[c];
            (Vec3::new(b(0), b(2), b(4)), Vec3::new(b(1), b(3), b(5)))
        };
        while let Some((i, level)) = stack.pop() {
            depth = depth.max(level);
            let node = &bvh.nodes[i];
            for c in 0..WIDTH {
                let (lo, hi) = child_box(node, c);
                if !lo.is_finite() {
                    continue;
                }
                let child = node.child[c];
                assert_eq!(node.leaf_mask & (1 << c) != 0, child & LEAF != 0);
                let index = (child & INDEX_MASK) as usize;
                let tri_only = if child & LEAF != 0 {
                    child & SPHERE == 0
                } else {
                    let below = &bvh.nodes[index];
                    below.tri_only == below.valid
                };
                assert_eq!(node.tri_only & (1 << c) != 0, tri_only, "n = {n}");
                let index = (child & INDEX_MASK) as usize;
                if child & LEAF == 0 {
                    reached[index] += 1;
                    stack.push((index, level + 1));
                    for cc in 0..WIDTH {
                        let (clo, chi) = child_box(&bvh.nodes[index], cc);
                        if clo.is_finite() {
                            assert!(clo.cmpge(lo).all() && chi.cmple(hi).all());
                        }
                    }
                } else if child & SPHERE != 0 {
                    leaves.1[index] += 1;
                    let s = &bvh.spheres[index];
                    seen[s.prim as usize] += 1;
                    let want = spheres[s.prim as usize - n];
                    assert_eq!(s.center_radius, want.center.extend(want.radius));
                    let r = Vec3::splat(want.radius);
                    assert!((want.center - r).cmpge(lo).all());
                    assert!((want.center + r).cmple(hi).all());
                } else {
                    leaves.0[index] += 1;
                    let p = &bvh.packets[index];
                    assert_eq!(p.valid, (1 << p.valid.count_ones()) - 1);
                    for l in 0..WIDTH {
                        let prim = p.prim[l] as usize;
                        assert_eq!(p.triangle(l), tris[prim]);
                        if p.valid & (1 << l) != 0 {
                            seen[prim] += 1;
                        } else {
                            // Padding: a copy of lane 0.
                            assert_eq!(p.prim[l], p.prim[0]);
                        }
                        for v in tris[prim] {
                            assert!(v.cmpge(lo).all() && v.cmple(hi).all());
                        }
                    }
                }
            }
        }
        assert!(
            seen.iter().all(|&s| s == 1),
            "{builder:?} n = {n}: {seen:?}"
        );
        assert!(reached.iter().all(|&r| r == 1), "n = {n}: {reached:?}");
        assert!(leaves.0.iter().chain(&leaves.1).all(|&r| r == 1));
        assert_eq!(
            bvh.depth, depth,
            "n = {n}: depth (sizes the traversal stacks)"
        );
    }
}

/// A chain of triangles at geometrically shrinking scales around one point builds a
/// deep, lopsided tree; rays through the point visit every level, with many children
/// stacked at each. The fixed-size traversal stacks must hold them
/// ([`Bvh8::stack_capacity`]) and the hits must equal brute force.
#[test]
fn deep_tree_traversal_matches_brute_force() {
    for builder in [BvhBuilder::Ploc, BvhBuilder::Binned] {
        deep_tree_traversal(builder);
    }
}

/// [`deep_tree_traversal_matches_brute_force`] of one builder.
fn deep_tree_traversal(builder: BvhBuilder) {
    let mut rng = Rng(11);
    let mut tris = Vec::new();
    for k in 0..400 {
        let scale = 0.9f32.powi(k);
        for _ in 0..3 {
            let c = rng.vec(-1.0, 1.0) * scale;
            tris.push([
                c,
                c + rng.vec(-0.3, 0.3) * scale,
                c + rng.vec(-0.3, 0.3) * scale,
            ]);
        }
    }
    let geom = SceneGeometry::build_with_builder(tris.clone(), Vec::new(), builder);
    let (bvh, _) = geom.bvh8().unwrap();
    assert!(bvh.depth >= 6, "tree only {} levels deep", bvh.depth);
    for backend in backends() {
        let mut g = SceneGeometry::build_with_builder(tris.clone(), Vec::new(), builder);
        g.set_kernel(backend.kernel());
        for _ in 0..500 {
            // From outside, through a point near the centre of the chain.
            let o = rng.vec(-1.0, 1.0).normalize() * 3.0;
            let target = rng.vec(-1.0, 1.0) * 1e-3;
            let d = (target - o).normalize();
            let brute = tris
                .iter()
                .filter_map(|t| {
                    WatertightRay::new(o, d)
                        .intersect_triangle(
                            t[0].into(),
                            t[1].into(),
                            t[2].into(),
                            0.0,
                            f32::INFINITY,
                        )
                        .map(|h| h.t)
                })
                .fold(f32::INFINITY, f32::min);
            let (t, ..) = closest_one(&g, o, d);
            assert_eq!(t, brute, "{backend:?}: o {o} d {d}");
            let mut occluded = [false];
            intersect_occluded(&g, &[o], &[d], &[0.0], &[f32::INFINITY], &mut occluded);
            assert_eq!(
                occluded[0],
                brute < f32::INFINITY,
                "{backend:?}: o {o} d {d}"
            );
        }
    }
}

fn packet_hits<S: Simd>(
    s: S,
    p: &TriPacket8,
    o: Vec3,
    d: Vec3,
    tmin: f32,
    tmax: f32,
) -> (u32, u32, [f32; 8], [f32; 8], [f32; 8]) {
    let mut block = RayBlock::zero();
    block.set(s, &[o], &[d], &[0.0], Vec3A::ONE);
    let r = intersect_packet(s, &PacketRay::new(s, &block, 0), p, tmin, tmax);
    (
        r.hit,
        r.fallback,
        r.t.to_array(),
        r.b1.to_array(),
        r.b2.to_array(),
    )
}

/// The 8-lane test of every kernel against the scalar test on each lane's triangle: the
/// same accepted lanes with bit-identical `t` and barycentrics, on rays aimed at
/// vertices and edges of a grid of triangles with small integer coordinates (edge
/// functions exactly zero, so lanes go to the scalar fallback) and at random points.
#[test]
fn packet_test_matches_scalar_test_bit_for_bit() {
    for backend in backends() {
        let mut rng = Rng(11);
        let (mut hits, mut fallbacks) = (0, 0);
        for k in 0..20_000 {
            let n = 1 + (k % WIDTH);
            let grid = k % 2 == 0;
            let tris: Vec<(u32, [Vec3; 3])> = (0..n as u32)
                .map(|i| {
                    let mut v = [Vec3::ZERO; 3];
                    for vi in &mut v {
                        *vi = if grid {
                            (rng.vec(0.0, 4.0) * 4.0).floor() * 0.25
                        } else {
                            rng.vec(-1.0, 1.0)
                        };
                    }
                    (i, v)
                })
                .collect();
            let p = TriPacket8::new(&tris);
            let o = if grid {
                // Origins on the grid too, so the sheared coordinates are often exact.
                (rng.vec(0.0, 4.0)).floor() * 0.5 + Vec3::new(0.0, 0.0, 5.0)
            } else {
                rng.vec(-3.0, 3.0) + Vec3::new(0.0, 0.0, 5.0)
            };
            let target = if grid {
                (rng.vec(0.0, 4.0) * 8.0).floor() * 0.125
            } else {
                rng.vec(-1.0, 1.0)
            };
            let d = target - o;
            let ray = WatertightRay::new(o, d);
            let (tmin, tmax) = if k % 3 == 0 {
                (0.0, f32::INFINITY)
            } else {
                (rng.f32() * 0.9, 0.9 + rng.f32())
            };
            let (hit, fallback, t, b1, b2) =
                with_simd!(backend, s => packet_hits(s, &p, o, d, tmin, tmax));
            assert_eq!(hit & fallback, 0);
            assert_eq!(hit >> WIDTH, 0);
            for l in 0..WIDTH {
                let [v0, v1, v2] = p.triangle(l);
                let want = ray.intersect_triangle(v0.into(), v1.into(), v2.into(), tmin, tmax);
                if fallback & (1 << l) != 0 {
                    fallbacks += 1;
                    assert_eq!(
                        packet_lane_scalar(&p, l, o.into(), d.into(), tmin, tmax),
                        want,
                        "{backend:?} ray {k} lane {l}"
                    );
                    continue;
                }
                let got = (hit & (1 << l) != 0).then(|| TriangleHit {
                    t: t[l],
                    b1: b1[l],
                    b2: b2[l],
                });
                let bits = |h: Option<TriangleHit>| h.map(|h| [h.t, h.b1, h.b2].map(f32::to_bits));
                assert_eq!(bits(got), bits(want), "{backend:?} ray {k} lane {l}");
                hits += got.is_some() as usize;
            }
        }
        assert!(
            hits > 1000 && fallbacks > 50,
            "{backend:?}: {hits} hits, {fallbacks} fallbacks"
        );
    }
}

/// The node test's cull of boxes behind the origin only removes children whose every
/// triangle the packet test rejects: packets (axis-aligned planar ones, as walls, and
/// general ones) and rays leaving them from a few ulps off a box face (spawned rays),
/// from on it, and from farther away, in every direction including parallel to it.
#[test]
fn node_cull_only_removes_children_the_packet_test_rejects() {
    for backend in backends() {
        let mut rng = Rng(13);
        let (mut culled, mut hits) = (0, 0);
        for k in 0..20_000 {
            let axis = k % 3;
            let scale = if k % 5 == 0 { 1e3 } else { 1.0 };
            let c = (rng.f32() * 8.0 - 4.0) * scale;
            let n = 1 + (k / 3) % WIDTH;
            let planar = k % 4 != 3;
            let tris: Vec<(u32, [Vec3; 3])> = (0..n as u32)
                .map(|i| {
                    let mut v = [rng.vec(-2.0, 2.0), rng.vec(-2.0, 2.0), rng.vec(-2.0, 2.0)];
                    for vi in &mut v {
                        vi[axis] = if planar {
                            c
                        } else {
                            c + rng.f32() * 0.5 * scale
                        };
                    }
                    (i, v)
                })
                .collect();
            let p = TriPacket8::new(&tris);
            // The packet's box, in slot 0 of an otherwise empty node.
            let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
            for (_, v) in &tris {
                for vi in v {
                    (lo, hi) = (lo.min(*vi), hi.max(*vi));
                }
            }
            let mut bounds = [Row8([f32::INFINITY; WIDTH]); 6];
            for a in 0..3 {
                bounds[2 * a].0[0] = lo[a];
                bounds[2 * a + 1] = Row8([f32::NEG_INFINITY; WIDTH]);
                bounds[2 * a + 1].0[0] = hi[a];
            }
            // Origins near the face at the box minimum along `axis` (the plane itself
            // for planar packets).
            let mut o = rng.vec(-1.5, 1.5);
            let ulps = (rng.next_u64() % 9) as i32 - 4;
            o[axis] = match k % 4 {
                0 => f32::from_bits((c.to_bits() as i32 + ulps) as u32),
                1 => c + (rng.f32() - 0.5) * 1e-5 * c.abs().max(1.0),
                2 => c,
                _ => c + (rng.f32() * 4.0 - 2.0) * scale,
            };
            let mut d = rng.vec(-1.0, 1.0);
            if k % 11 == 0 {
                d[axis] = 0.0;
            }
            let tmin = if k % 2 == 0 { 0.0 } else { rng.f32() * 1e-3 };
            let mut block = RayBlock::zero();
            block.set(Portable, &[o], &[d], &[tmin], Vec3A::ONE);
            let cull = with_simd!(backend, s => {
                (behind_axis(s, &bounds, &block.cull, 0, 0)
                    | behind_axis(s, &bounds, &block.cull, 0, 1)
                    | behind_axis(s, &bounds, &block.cull, 0, 2))
                .bits()
            }) & 1
                != 0;
            let (hit, fallback, ..) =
                with_simd!(backend, s => packet_hits(s, &p, o, d, tmin, f32::INFINITY));
            let fallback_hit = (0..WIDTH).any(|l| {
                fallback & p.valid & (1 << l) != 0
                    && packet_lane_scalar(&p, l, o.into(), d.into(), tmin, f32::INFINITY).is_some()
            });
            let any = hit & p.valid != 0 || fallback_hit;
            assert!(
                !(cull && any),
                "{backend:?} ray {k}: o={o:?} d={d:?} culled a hit"
            );
            culled += cull as usize;
            hits += any as usize;
        }
        assert!(culled > 5000 && hits > 500, "{culled} culled, {hits} hits");
    }
}

/// Every lane of a [`RayBlock`], on every backend and for full and partial blocks,
/// holds the bits of the per-ray formulas: `NodeRay`'s documented rows computed one
/// ray at a time with `Vec3A` operations, and [`shear`]'s permutation and constants.
/// Directions include zero, negative zero, tiny and axis-tied components.
#[test]
fn ray_block_lanes_equal_the_per_ray_constants() {
    let mut rng = Rng(21);
    let max_abs = Vec3A::new(3.0, 1e4, 0.5);
    let special = [0.0f32, -0.0, 1e-25, -1e-25, 1e-20, 0.5, -0.5, 1.0, 1e30];
    for backend in backends() {
        for k in 0..400 {
            let len = 1 + k % BLOCK;
            let mut origin = Vec::new();
            let mut direction = Vec::new();
            for _ in 0..len {
                origin.push(rng.vec(-10.0, 10.0));
                let mut d = rng.vec(-1.0, 1.0);
                for a in 0..3 {
                    if rng.next_u64().is_multiple_of(3) {
                        d[a] = special[(rng.next_u64() % special.len() as u64) as usize];
                    }
                }
                if k % 7 == 0 {
                    d.y = d.x.abs().copysign(d.y);
                }
                direction.push(d);
            }
            let mut block = RayBlock::zero();
            let tmin: Vec<f32> = (0..len)
                .map(|l| [0.0, 1e-4, -1.0, f32::NAN][(k + l) % 4])
                .collect();
            with_simd!(backend, s => block.set(s, &origin, &direction, &tmin, max_abs));
            for l in 0..len {
                let (o, d) = (Vec3A::from(origin[l]), Vec3A::from(direction[l]));
                let tiny = d.abs().cmplt(Vec3A::splat(MIN_DIR));
                let inv = Vec3A::select(
                    tiny,
                    Vec3A::splat(1.0 / MIN_DIR).copysign(d),
                    Vec3A::ONE / d,
                );
                let c = -(o * inv);
                let slack = ((max_abs + o.abs()) * (inv.abs() * NODE_SLACK)).copysign(inv);
                let (kx, ky, kz, po, sh) = shear(o, d);
                let rows = [inv, c - slack, c + slack];
                for a in 0..3 {
                    for (r, row) in rows.iter().enumerate() {
                        let got = block.node[3 * r + a][l];
                        assert_eq!(
                            got.to_bits(),
                            row[a].to_bits(),
                            "{backend:?} ray {k}/{l} row {r} axis {a}: d {d}"
                        );
                    }
                    assert_eq!(
                        block.tri[a][l].to_bits(),
                        po[a].to_bits(),
                        "{backend:?} ray {k}/{l} origin {a}: d {d}"
                    );
                    assert_eq!(
                        block.tri[3 + a][l].to_bits(),
                        sh[a].to_bits(),
                        "{backend:?} ray {k}/{l} shear {a}: d {d}"
                    );
                }
                assert_eq!(
                    block.axes(l),
                    [kx, ky, kz],
                    "{backend:?} ray {k}/{l}: d {d}"
                );
                for a in 0..3 {
                    let sign = if d[a] < 0.0 { -1.0 } else { 1.0 };
                    let live = d[a] != 0.0 && tmin[l] >= 0.0;
                    let threshold = if live { sign * o[a] } else { f32::NEG_INFINITY };
                    assert_eq!(block.cull[a][l], sign, "{backend:?} ray {k}/{l}: d {d}");
                    assert_eq!(
                        block.cull[3 + a][l].to_bits(),
                        threshold.to_bits(),
                        "{backend:?} ray {k}/{l}: d {d}, tmin {}",
                        tmin[l]
                    );
                }
                assert_eq!(block.origin(l), origin[l]);
                assert_eq!(block.direction(l), direction[l]);
            }
        }
    }
}
