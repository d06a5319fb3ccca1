//! BVH builds and hits for scenes with large finite coordinates and degenerate box sets
//! (issue 14, item 1). Each case once panicked or overflowed the stack in the build; here
//! each must build and report the hits a brute-force look at the scene predicts.

use glam::Vec3;
use risotto_components::NO_HIT;
use risotto_systems::geometry::{SceneGeometry, Sphere};
use risotto_systems::intersect::intersect_closest;

/// The square `[c, c + s]` in x and z at height `c.y`, as two triangles.
fn quad(c: Vec3, s: f32) -> Vec<[Vec3; 3]> {
    let (a, b, cc, d) = (
        c,
        c + Vec3::X * s,
        c + Vec3::X * s + Vec3::Z * s,
        c + Vec3::Z * s,
    );
    vec![[a, b, cc], [a, cc, d]]
}

/// A `n x n` grid of unit-relative cells of size `cell` with heights varying in 0..7 cells:
/// many boxes of equal size spread over the extent `n * cell`.
fn grid(n: usize, cell: f32, offset: Vec3) -> Vec<[Vec3; 3]> {
    let mut t = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let c = Vec3::new(i as f32, ((i * j) % 7) as f32, j as f32) * cell + offset;
            t.extend(quad(c, cell));
        }
    }
    t
}

/// The closest hit `(t, prim)` of one ray, or `None`.
fn hit(geom: &SceneGeometry, o: Vec3, d: Vec3) -> Option<(f32, u32)> {
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
    (prim[0] != NO_HIT).then_some((t[0], prim[0]))
}

fn close(got: f32, want: f32, rel: f32) -> bool {
    (got - want).abs() <= rel * want.abs()
}

/// A sphere of radius 1e8 (and 1e12, 1e20, 1e30) beside a 20 x 20 floor and a unit ball:
/// the collapse's volume term overflowed f32 and put spheres into shared leaves ("sphere
/// leaves hold one sphere"); beyond 1e19 obvhs' CWBVH collapse indexed out of bounds.
#[test]
fn huge_sphere_beside_small_shapes() {
    for r in [1e8f32, 1e12, 1e20, 1e30] {
        let spheres = vec![
            Sphere {
                center: Vec3::new(0.0, -r, 0.0),
                radius: r,
            },
            Sphere {
                center: Vec3::new(0.0, 3.0, 0.0),
                radius: 1.0,
            },
        ];
        let geom = SceneGeometry::build(quad(Vec3::new(-10.0, 1.0, -10.0), 20.0), spheres);
        // Down onto the unit ball's top, then the floor from below it, then the big sphere.
        let (t, prim) = hit(&geom, Vec3::new(0.0, 10.0, 0.0), -Vec3::Y).expect("ball");
        assert_eq!(prim, 3, "r = {r}");
        assert!(close(t, 6.0, 1e-5), "r = {r}: t = {t}");
        let (t, prim) = hit(&geom, Vec3::new(5.0, 10.0, 5.0), -Vec3::Y).expect("floor");
        assert!(prim < 2 && close(t, 9.0, 1e-5), "r = {r}: {prim} at {t}");
        // 10 units above a radius-r sphere: resolved while 10 / r is above f64's precision.
        if r <= 1e12 {
            let (t, prim) = hit(&geom, Vec3::new(15.0, 10.0, 0.0), -Vec3::Y).expect("ground");
            assert_eq!(prim, 2, "r = {r}");
            assert!((t - 10.0).abs() < 1e-3, "r = {r}: t = {t}");
        }
    }
}

/// A 50 x 50 grid of 5000 triangles spanning 1e8 to 1e12 units: the collapse's costs
/// overflowed and it made leaves of more than eight triangles ("N triangles") or indexed
/// past the primitives. (Up to 1e12: the watertight triangle test's scaled `t` is a product
/// of three vertex coordinates relative to the ray origin in f32, which overflows beyond
/// about 7e12, see `docs/scene-format.md`.)
#[test]
fn huge_meshes_build_and_hit() {
    for e in [8, 10, 12] {
        let size = 10f32.powi(e);
        let cell = size / 50.0;
        let geom = SceneGeometry::build(grid(50, cell, Vec3::ZERO), vec![]);
        // Cell (10, 20) sits at height (200 % 7) = 4 cells; look down on its middle.
        let p = Vec3::new(10.5, 0.0, 20.5) * cell;
        let (t, prim) = hit(&geom, p + Vec3::Y * 100.0 * cell, -Vec3::Y)
            .unwrap_or_else(|| panic!("1e{e}: no hit"));
        assert!(close(t, 96.0 * cell, 1e-5), "1e{e}: t = {t}");
        assert_eq!(prim / 2, 10 * 50 + 20, "1e{e}");
    }
}

/// Two small quads at -+1e8 to 1e12 and a sphere between them.
#[test]
fn far_apart_shapes() {
    for e in [8, 10, 12] {
        let far = 10f32.powi(e);
        let s = far * 1e-3;
        let tris = [quad(Vec3::splat(-far), s), quad(Vec3::splat(far), s)].concat();
        let spheres = vec![Sphere {
            center: Vec3::splat(far * 0.5),
            radius: s,
        }];
        let geom = SceneGeometry::build(tris, spheres);
        let c = Vec3::splat(far * 0.5);
        let (_, prim) = hit(&geom, c + Vec3::Y * far * 0.25, -Vec3::Y).expect("sphere");
        assert_eq!(prim, 4, "1e{e}");
        let (_, prim) = hit(
            &geom,
            Vec3::splat(far) + Vec3::new(0.5, 1.0, 0.5) * s,
            -Vec3::Y,
        )
        .unwrap_or_else(|| panic!("1e{e}: far quad"));
        assert!((2..4).contains(&prim), "1e{e}: {prim}");
    }
}

/// 5000 triangles whose vertices round to the same few points (a fine mesh 1e10 from the
/// origin, where the spacing of f32 is 1024) next to a quad and a sphere at the origin:
/// PLOC chains equal boxes into a tree 5000 levels deep and the recursive collapse
/// overflowed the stack.
#[test]
fn mesh_collapsed_by_rounding_far_away() {
    let far = Vec3::splat(1e10);
    let tris = [grid(50, 1.0, far), quad(Vec3::ZERO, 1.0)].concat();
    let n = tris.len() as u32;
    let spheres = vec![Sphere {
        center: Vec3::new(0.5, 5.0, 0.5),
        radius: 0.5,
    }];
    let geom = SceneGeometry::build(tris, spheres);
    let (t, prim) = hit(&geom, Vec3::new(0.5, 10.0, 0.5), -Vec3::Y).expect("sphere");
    assert_eq!(prim, n);
    assert!(close(t, 4.5, 1e-6), "t = {t}");
    let (t, prim) = hit(&geom, Vec3::new(0.2, 1.0, 0.8), -Vec3::Y).expect("quad");
    assert!(prim == n - 1 || prim == n - 2, "{prim}");
    assert!(close(t, 1.0, 1e-6), "t = {t}");
}

/// 20000 copies of one triangle: the tree stays shallow enough to build and every ray
/// through the triangle hits one of the copies.
#[test]
fn many_identical_triangles() {
    let t = [Vec3::ZERO, Vec3::X, Vec3::Z];
    let geom = SceneGeometry::build(vec![t; 20000], vec![]);
    let (d, prim) = hit(&geom, Vec3::new(0.25, 1.0, 0.25), -Vec3::Y).expect("hit");
    assert!(prim < 20000 && close(d, 1.0, 1e-6));
}

/// Meshes of 1e15 to 1e36 units and shapes that far apart build. Their triangles are beyond
/// the f32 triangle test (see above), and beyond about 3e18 an axis-parallel ray's slab
/// distances (`1 / d` clamped to 1e20) overflow too; up to that the sphere is still hit.
#[test]
fn beyond_the_triangle_range_builds() {
    for e in [15, 20, 25, 30, 36] {
        let big = 10f32.powi(e);
        SceneGeometry::build(grid(50, big / 50.0, Vec3::ZERO), vec![]);
        let tris = [quad(Vec3::splat(-big), 1.0), quad(Vec3::splat(big), 1.0)].concat();
        let c = Vec3::splat(big * 0.5);
        let geom = SceneGeometry::build(
            tris,
            vec![Sphere {
                center: c,
                radius: 1.0,
            }],
        );
        if e <= 18 {
            let (_, prim) = hit(&geom, c + Vec3::Y * 1e-3 * big, -Vec3::Y).expect("sphere");
            assert_eq!(prim, 4, "1e{e}");
        }
    }
}

/// A sphere whose box leaves the f32 range (radius near f32::MAX) builds, and a ray from
/// inside hits it.
#[test]
fn sphere_beyond_the_f32_range() {
    let r = f32::MAX * 0.9;
    let geom = SceneGeometry::build(
        quad(Vec3::ZERO, 1.0),
        vec![Sphere {
            center: Vec3::ZERO,
            radius: r,
        }],
    );
    let (_, prim) = hit(&geom, Vec3::new(0.5, 1.0, 0.5), -Vec3::Y).expect("quad");
    assert!(prim < 2);
    let (t, prim) = hit(&geom, Vec3::new(0.5, 1.0, 0.5), Vec3::Y).expect("sphere");
    assert_eq!(prim, 2);
    assert!(close(t, r, 1e-5), "t = {t}");
}
