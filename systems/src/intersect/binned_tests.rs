//! Tests of the binned 8-wide build (`bvh8/binned.rs`), here beside the traversal they
//! check it with (in `bvh8/` they would make the modules depend on each other in a circle).
//! Its structure (every primitive in one
//! leaf, every child box around its subtree, the depth, the leaf flags) is checked with the
//! other builder's in `intersect/tests.rs` (`bvh8_collapse_is_a_complete_bounding_tree`).

use glam::Vec3;

use crate::bvh8::{Bvh8, PARALLEL_BINNING_MIN, PARALLEL_MIN, WIDTH};
use crate::geometry::{BvhBuilder, SceneGeometry};
use crate::intersect::tests::closest_one;
use crate::intersect::WatertightRay;
use crate::sampler::SplitMix64 as Rng;

fn vec(rng: &mut Rng, lo: f32, hi: f32) -> Vec3 {
    Vec3::new(rng.f32(), rng.f32(), rng.f32()) * (hi - lo) + Vec3::splat(lo)
}

/// `n` random small triangles in a cube.
fn soup(rng: &mut Rng, n: usize) -> Vec<[Vec3; 3]> {
    (0..n)
        .map(|_| {
            let c = vec(rng, -10.0, 10.0);
            [c, c + vec(rng, -0.4, 0.4), c + vec(rng, -0.4, 0.4)]
        })
        .collect()
}

fn binned(tris: &[[Vec3; 3]]) -> SceneGeometry {
    SceneGeometry::build_with_builder(tris.to_vec(), Vec::new(), BvhBuilder::Binned)
}

/// The closest hit of random rays through the tree equals a loop over every triangle with
/// the same watertight test: the distance bit for bit, and the triangle where it is the
/// only one at that distance.
#[test]
fn closest_hits_equal_brute_force() {
    let mut rng = Rng(36);
    let tris = soup(&mut rng, 3000);
    let geom = binned(&tris);
    let mut hits = 0;
    for _ in 0..2000 {
        let o = vec(&mut rng, -12.0, 12.0);
        let d = (vec(&mut rng, -8.0, 8.0) - o).normalize();
        let ray = WatertightRay::new(o, d);
        let mut brute = (f32::INFINITY, u32::MAX, 0);
        for (i, t) in tris.iter().enumerate() {
            let Some(h) =
                ray.intersect_triangle(t[0].into(), t[1].into(), t[2].into(), 0.0, f32::INFINITY)
            else {
                continue;
            };
            if h.t < brute.0 {
                brute = (h.t, i as u32, 1);
            } else if h.t == brute.0 {
                brute.2 += 1;
            }
        }
        let (t, prim, ..) = closest_one(&geom, o, d);
        assert_eq!(t, brute.0, "o {o} d {d}");
        if brute.0.is_finite() {
            hits += 1;
            if brute.2 == 1 {
                assert_eq!(prim, brute.1, "o {o} d {d}");
            }
        }
    }
    assert!(hits > 300, "only {hits} rays hit");
}

/// The tree of a scene large enough to be built on several tasks, and to bin its root's
/// splits on several, is the same, node for node and packet for packet, whatever the
/// number of threads.
#[test]
fn the_tree_does_not_depend_on_the_thread_count() {
    let mut rng = Rng(7);
    let tris = soup(&mut rng, PARALLEL_BINNING_MIN + 3 * PARALLEL_MIN);
    let build = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool");
        pool.install(|| binned(&tris))
    };
    let one = build(1);
    let (a, _) = one.bvh8().expect("a tree");
    for threads in [2, 3, 4] {
        let many = build(threads);
        let (b, _) = many.bvh8().expect("a tree");
        assert_eq!(a.nodes.len(), b.nodes.len(), "{threads} threads");
        for (x, y) in a.nodes.iter().zip(&b.nodes) {
            let bits = |n: &crate::bvh8::Node8| n.bounds.map(|r| r.0.map(f32::to_bits));
            assert_eq!(bits(x), bits(y), "{threads} threads");
            assert_eq!(
                (x.child, x.leaf_mask, x.valid, x.tri_only),
                (y.child, y.leaf_mask, y.valid, y.tri_only),
                "{threads} threads"
            );
        }
        assert_eq!(a.packets, b.packets, "{threads} threads");
        assert_eq!(a.depth, b.depth, "{threads} threads");
    }
}

/// Packets are full where the SAH allows: on a mesh-like soup most leaves hold eight
/// triangles (a child of at most eight is never split), well above the 4.7 a leaf of the
/// collapsed one-primitive tree.
#[test]
fn leaves_fill_their_packets() {
    let mut rng = Rng(3);
    let tris = soup(&mut rng, 20_000);
    let geom = binned(&tris);
    let (bvh, _) = geom.bvh8().expect("a tree");
    let fill = tris.len() as f64 / bvh.packets.len() as f64;
    assert!(
        fill > 6.5 && fill <= WIDTH as f64,
        "{fill:.2} triangles a packet"
    );
}

/// Coincident triangles (binning cannot separate them) are split by count: every one is
/// kept, in one leaf, and the tree stays shallow.
#[test]
fn coincident_triangles_are_split_by_count() {
    let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let mut tris = vec![t; 10_000];
    tris.push([
        Vec3::splat(5.0),
        Vec3::splat(5.0) + Vec3::X,
        Vec3::splat(6.0),
    ]);
    let geom = binned(&tris);
    let (bvh, _) = geom.bvh8().expect("a tree");
    // Panics unless every triangle is in exactly one packet lane.
    let slots = bvh.triangle_slots(tris.len());
    for (&slot, t) in slots.iter().zip(&tris) {
        assert_eq!(
            Bvh8::slot_triangle(&bvh.packets, slot).v.map(Vec3::from),
            *t
        );
    }
    assert!(bvh.depth <= 8, "depth {}", bvh.depth);
}

/// A mesh built as a mesh gives the tree, the packets and the hits of its soup built
/// with the weld, bit for bit: here a 100 x 100 grid of bumped quads with its vertices
/// listed in reverse (not the weld's first-use order), large enough for the binned build.
#[test]
fn a_mesh_builds_as_its_soup_does() {
    use crate::geometry::{TriangleMesh, TriangleSet};
    use crate::intersect::intersect_closest;
    let n = 100u32;
    let mut rng = Rng(11);
    let mut positions: Vec<Vec3> = (0..(n + 1) * (n + 1))
        .map(|k| {
            let (x, y) = ((k % (n + 1)) as f32, (k / (n + 1)) as f32);
            Vec3::new(x, y, rng.f32() * 0.5)
        })
        .collect();
    positions.reverse();
    let at = |x: u32, y: u32| (n + 1) * (n + 1) - 1 - (y * (n + 1) + x);
    let mut triangles = Vec::new();
    for y in 0..n {
        for x in 0..n {
            triangles.push([at(x, y), at(x + 1, y), at(x + 1, y + 1)]);
            triangles.push([at(x, y), at(x + 1, y + 1), at(x, y + 1)]);
        }
    }
    let mesh = TriangleMesh {
        positions,
        triangles,
    };
    assert!(mesh.len() >= crate::geometry::BINNED_MIN);
    let soup: Vec<[Vec3; 3]> = (0..mesh.len()).map(|i| mesh.triangle(i)).collect();
    let a = SceneGeometry::build(soup, Vec::new());
    let set = TriangleSet::Mesh(mesh);
    let b = SceneGeometry::build_set_with_instances(set, Vec::new(), Vec::new(), &[]);
    let ((ta, _), (tb, _)) = (a.bvh8().unwrap(), b.bvh8().unwrap());
    assert_eq!(ta.packets, tb.packets);
    assert_eq!(ta.nodes.len(), tb.nodes.len());
    assert_eq!(a.bounds(), b.bounds());
    let m = 4096;
    let origin: Vec<Vec3> = (0..m)
        .map(|_| Vec3::new(rng.f32() * n as f32, rng.f32() * n as f32, 5.0))
        .collect();
    let direction: Vec<Vec3> = (0..m)
        .map(|_| Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, -1.0).normalize())
        .collect();
    let hits = |g: &SceneGeometry| {
        let (mut t, mut prim) = (vec![0.0; m], vec![0; m]);
        let (mut b1, mut b2) = (vec![0.0; m], vec![0.0; m]);
        let (tmin, tmax) = (vec![0.0; m], vec![f32::INFINITY; m]);
        intersect_closest(
            g, &origin, &direction, &tmin, &tmax, &mut t, &mut prim, &mut b1, &mut b2,
        );
        (
            t.iter().map(|t| t.to_bits()).collect::<Vec<_>>(),
            prim,
            b1,
            b2,
        )
    };
    let (ha, hb) = (hits(&a), hits(&b));
    assert!(
        ha.1.iter()
            .filter(|&&p| p != risotto_components::NO_HIT)
            .count()
            > m / 2
    );
    assert_eq!(ha, hb);
}
