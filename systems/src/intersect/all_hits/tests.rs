//! Tests of `all_hits.rs`: the walk replayed from hit lists against the walk of one
//! closest-hit query per step.

use super::*;
use crate::geometry::Sphere;
use crate::sampler::SplitMix64 as Rng;

fn vec3(rng: &mut Rng, lo: f32, hi: f32) -> Vec3 {
    Vec3::new(rng.f32(), rng.f32(), rng.f32()) * (hi - lo) + Vec3::splat(lo)
}

/// The 12 triangles of an axis-aligned box (faces share edges: rays through them test
/// the coincident-hit rules).
fn box_triangles(lo: Vec3, hi: Vec3, out: &mut Vec<[Vec3; 3]>) {
    let c = |i: u32| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    for q in [
        [0, 1, 3, 2],
        [4, 6, 7, 5],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
    ] {
        out.push([c(q[0]), c(q[1]), c(q[2])]);
        out.push([c(q[0]), c(q[2]), c(q[3])]);
    }
}

/// How a walk moves `tmin` past the hit at `t` (mode per ray): exactly to it (the next
/// hit may then lie within its error bound, or tie with it), by a few ulps, or well past.
fn advance(t: f32, mode: u32) -> f32 {
    match mode % 3 {
        0 => t,
        1 => t + 4.0 * f32::EPSILON * t.abs().max(1.0),
        _ => t + 1e-4 * t.abs().max(1.0),
    }
}

type Step = (u32, u32, u32, u32);

fn step(t: f32, prim: u32, b1: f32, b2: f32) -> Step {
    (t.to_bits(), prim, b1.to_bits(), b2.to_bits())
}

/// The walk of one closest-hit query per hit.
fn walk_closest(g: &SceneGeometry, o: Vec3, d: Vec3, tmax: f32, mode: u32) -> Vec<Step> {
    let mut out = Vec::new();
    let mut t0 = 0.0f32;
    while out.len() < 64 {
        let (mut t, mut prim, mut b1, mut b2) = ([0.0], [0], [0.0], [0.0]);
        super::super::intersect_closest(
            g,
            &[o],
            &[d],
            &[t0],
            &[tmax],
            &mut t,
            &mut prim,
            &mut b1,
            &mut b2,
        );
        if prim[0] == NO_HIT {
            break;
        }
        out.push(step(t[0], prim[0], b1[0], b2[0]));
        t0 = advance(t[0], mode);
    }
    out
}

/// The same walk from hit lists, querying again where [`RayHits::next_after`] says so.
/// Also counts the steps taken from a list, the queries and the full lists.
fn walk_lists(
    g: &SceneGeometry,
    o: Vec3,
    d: Vec3,
    tmax: f32,
    mode: u32,
    counts: &mut [usize; 3],
) -> Vec<Step> {
    let mut out = Vec::new();
    let mut t0 = 0.0f32;
    let query = |t0: f32| {
        let mut h = [RayHits::EMPTY];
        intersect_all(g, &[o], &[d], &[t0], &[tmax], &mut h);
        h[0]
    };
    let mut list = query(t0);
    counts[2] += (!list.complete) as usize;
    let mut taken = 0;
    let mut fresh = true;
    while out.len() < 64 {
        let next = if fresh {
            if list.len > 0 {
                NextHit::Hit(0)
            } else {
                NextHit::Miss
            }
        } else {
            list.next_after(taken, t0)
        };
        let j = match next {
            NextHit::Hit(j) => {
                counts[0] += !fresh as usize;
                j
            }
            NextHit::Miss => break,
            NextHit::Query => {
                counts[1] += 1;
                list = query(t0);
                fresh = true;
                continue;
            }
        };
        fresh = false;
        taken = j + 1;
        out.push(step(list.t[j], list.prim[j], list.b1[j], list.b2[j]));
        t0 = advance(list.t[j], mode);
    }
    out
}

/// Random boxes (some nested, some sharing faces' planes), random spheres (some nested),
/// rays from inside and outside, aimed at random points and at box edges and corners, with
/// three ways of stepping past a hit: the hit list reproduces every step of the
/// closest-hit walk bit for bit, on every kernel. The walk takes steps from lists, queries
/// again (within-bound hits, full lists), and crosses more than `MAX_HITS` surfaces.
#[test]
fn hit_lists_replay_the_closest_hit_walk_exactly() {
    let mut rng = Rng(5);
    let mut tris = Vec::new();
    let mut corners = Vec::new();
    for _ in 0..12 {
        let c = vec3(&mut rng, -2.0, 2.0);
        let h = vec3(&mut rng, 0.1, 1.0);
        box_triangles(c - h, c + h, &mut tris);
        corners.push((c - h, c + h));
    }
    // Nested boxes around the origin: rays from it cross many walls.
    for k in 1..=5 {
        let h = Vec3::splat(0.5 * k as f32);
        box_triangles(-h, h, &mut tris);
    }
    let mut spheres = Vec::new();
    for k in 0..6 {
        let center = if k < 3 {
            Vec3::splat(0.25)
        } else {
            vec3(&mut rng, -2.0, 2.0)
        };
        spheres.push(Sphere {
            center,
            radius: 0.3 + 0.4 * k as f32 * rng.f32(),
        });
    }
    let mut counts = [0usize; 3];
    let mut longest = 0;
    let mut ties = 0;
    let mut steps = 0;
    for backend in backends() {
        let mut g = SceneGeometry::build(tris.clone(), spheres.clone());
        g.set_kernel(backend.kernel());
        for r in 0..3000u32 {
            let o = if r % 2 == 0 {
                vec3(&mut rng, -0.2, 0.2)
            } else {
                vec3(&mut rng, -4.0, 4.0)
            };
            let target = match r % 3 {
                0 => vec3(&mut rng, -3.0, 3.0),
                // An edge of a box (x free, y and z at corners).
                1 => {
                    let (lo, hi) = corners[(r as usize / 3) % corners.len()];
                    Vec3::new(lo.x + (hi.x - lo.x) * rng.f32(), hi.y, lo.z)
                }
                // A corner.
                _ => corners[(r as usize / 3) % corners.len()].1,
            };
            let d = (target - o).normalize();
            let tmax = if r % 4 == 0 { 3.0 } else { f32::INFINITY };
            let mode = r / 4;
            let want = walk_closest(&g, o, d, tmax, mode);
            let got = walk_lists(&g, o, d, tmax, mode, &mut counts);
            longest = longest.max(want.len());
            steps += want.len();
            let at = format!("{backend:?} ray {r}: o {o} d {d} mode {}", mode % 3);
            assert_eq!(got.len(), want.len(), "{at}: {got:?} vs {want:?}");
            for (g, w) in got.iter().zip(&want) {
                // Of hits at exactly the same distance either may come first (a box
                // corner ties six triangles); the walk then goes on from the same
                // distance, so every later step must agree again.
                if g.1 != w.1 {
                    assert_eq!(g.0, w.0, "{at}");
                    ties += 1;
                } else {
                    assert_eq!(g, w, "{at}: {got:?} vs {want:?}");
                }
            }
        }
    }
    let [from_lists, queries, full] = counts;
    assert!(from_lists > 10_000, "{from_lists} steps from lists");
    assert!(queries > 100, "{queries} queries");
    assert!(full > 100, "{full} full lists");
    assert!(longest > 2 * MAX_HITS, "longest walk {longest} hits");
    // Ties come from the rays aimed at edges and corners; most steps are no tie.
    assert!(ties * 20 < steps, "{ties} ties in {steps} steps");
    eprintln!(
        "{steps} steps, {ties} ties, {from_lists} from lists, {queries} queries, {full} full"
    );
}

/// Every kernel this CPU runs.
fn backends() -> Vec<Backend> {
    let all = [Kernel::Portable, Kernel::Avx2];
    all.iter().filter_map(|k| k.backend()).collect()
}

/// `next_after`'s three answers on a hand-made list: hits behind `tmin` are skipped, one
/// past its bound is taken, one within it asks for a query, and the end of a complete list
/// is a miss, of a full one a query.
#[test]
fn next_after_decides_only_what_the_bounds_decide() {
    let mut h = RayHits {
        complete: true,
        ..RayHits::EMPTY
    };
    let mut tmax = 10.0;
    h.insert(2.0, 7, 0.0, 0.0, 0.01, &mut tmax);
    h.insert(1.0, 5, 0.0, 0.0, 0.01, &mut tmax);
    assert_eq!((h.len, h.prim[0], h.prim[1]), (2, 5, 7));
    assert_eq!(h.next_after(0, 0.5), NextHit::Hit(0));
    assert_eq!(
        h.next_after(0, 1.0),
        NextHit::Hit(1),
        "the hit at tmin is skipped"
    );
    assert_eq!(h.next_after(1, 1.995), NextHit::Query, "within the bound");
    assert_eq!(h.next_after(2, 2.0), NextHit::Miss);
    h.insert(3.0, 1, 0.0, 0.0, f32::INFINITY, &mut tmax);
    assert_eq!(h.next_after(2, 2.5), NextHit::Query, "a fallback hit");
    h.insert(4.0, 2, 0.0, 0.0, 0.0, &mut tmax);
    assert!(!h.complete && tmax == 4.0, "full: {h:?}, tmax {tmax}");
    h.insert(0.5, 3, 0.0, 0.0, 0.0, &mut tmax);
    assert_eq!(
        (h.t, tmax),
        ([0.5, 1.0, 2.0, 3.0], 3.0),
        "the farthest dropped"
    );
    assert_eq!(
        h.next_after(4, 3.5),
        NextHit::Query,
        "the end of a full list"
    );
}
