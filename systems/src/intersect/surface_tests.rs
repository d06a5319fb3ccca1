//! Tests of the geometry's surface records (`crate::geometry`) against what the
//! intersector reports: they live here because they need both.

use crate::geometry::*;
use crate::intersect::tests::closest_one;
use crate::primitive::sphere_hit_dir;
use crate::sampler::SplitMix64;
use glam::{DVec3, Vec2, Vec3};

/// The triangles as the geometry gives them (read from the BVH's packets, normal and area
/// computed there) against the vertices they were built from, in double precision:
/// interpolated points, normals, areas; spheres are not triangles.
#[test]
fn triangles_match_their_vertices() {
    let mut rng = SplitMix64(3);
    let mut v = || Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 20.0 - Vec3::splat(10.0);
    let tris: Vec<[Vec3; 3]> = (0..50).map(|_| [v(), v(), v()]).collect();
    let sphere = Sphere {
        center: Vec3::new(1.0, 2.0, 3.0),
        radius: 0.5,
    };
    let geom = SceneGeometry::build(tris.clone(), vec![sphere]);
    let view = geom.triangles();
    let mut rng = SplitMix64(4);
    for (i, t) in tris.iter().enumerate() {
        assert_eq!(geom.triangle(i), *t);
        let [a, b, c] = t.map(|x| x.as_dvec3());
        let cross = (b - a).cross(c - a);
        let area = geom.prim_area(i as u32) as f64;
        assert!((area - 0.5 * cross.length()).abs() <= 1e-5 * area.max(1.0));
        let (b1, b2) = (rng.f32() * 0.5, rng.f32() * 0.5);
        let s = view.surface_at(i as u32, b1, b2).unwrap();
        let d = f32::MAX;
        assert_eq!(s, geom.surface_at(i as u32, Vec3::ZERO, Vec3::Z, d, b1, b2));
        let (b1d, b2d) = (b1 as f64, b2 as f64);
        let p = a * (1.0 - b1d - b2d) + b * b1d + c * b2d;
        assert!((s.p.as_dvec3() - p).length() < 1e-5, "{:?} {p:?}", s.p);
        assert!((s.ng.as_dvec3() - cross.normalize()).length() < 1e-6);
        assert_eq!(s.uv, Vec2::new(b1, b2));
        let (q, n) = geom.sample_prim(i as u32, Vec2::new(b1, b2));
        assert_eq!(n, s.ng);
        assert!((q.as_dvec3() - a).dot(n.as_dvec3()).abs() < 1e-4);
    }
    assert!(view.surface_at(tris.len() as u32, 0.25, 0.5).is_none());
    assert_eq!(geom.num_prims(), tris.len() + 1);
}

#[test]
fn hit_is_front_agrees_with_the_surface_normal() {
    let tri = [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    let ball = Sphere {
        center: Vec3::new(0.0, 0.0, 5.0),
        radius: 1.0,
    };
    let geom = SceneGeometry::build(vec![tri], vec![ball]);
    let cases = [
        (Vec3::new(0.0, 0.0, 2.0), -Vec3::Z), // triangle, from its front
        (Vec3::new(0.0, 0.0, -2.0), Vec3::Z), // triangle, from behind
        (Vec3::new(0.2, 0.1, 10.0), -Vec3::Z), // sphere from outside
        (Vec3::new(0.2, 0.1, 5.0), Vec3::new(0.6, 0.0, 0.8)), // sphere from inside
    ];
    for (o, d) in cases {
        let (t, prim, b1, b2) = closest_one(&geom, o, d);
        let s = geom.surface_at(prim, o, d, t, b1, b2);
        assert_eq!(
            geom.hit_is_front(prim, o, d, t, b1),
            d.dot(s.ng) < 0.0,
            "ray from {o:?} along {d:?}"
        );
    }
    let front = |o: Vec3, d: Vec3| {
        let (t, prim, b1, _) = closest_one(&geom, o, d);
        geom.hit_is_front(prim, o, d, t, b1)
    };
    assert!(front(Vec3::new(0.0, 0.0, 2.0), -Vec3::Z));
    assert!(!front(Vec3::new(0.0, 0.0, -2.0), Vec3::Z));
    assert!(front(Vec3::new(0.2, 0.1, 10.0), -Vec3::Z));
    assert!(!front(Vec3::new(0.2, 0.1, 5.0), Vec3::Z));
}

#[test]
fn sphere_normals_come_from_the_double_precision_root() {
    // A tiny sphere far away: the f32 `t` alone is off by ~1e-3 of the radius, so a
    // normal from `origin + t direction` would tilt by ~1e-3 rad; `t + b1` keeps it to
    // f32 rounding of the normal.
    let sphere = Sphere {
        center: Vec3::new(1.0e4, 3.0, -2.0),
        radius: 1.0e-3,
    };
    let geom = SceneGeometry::build(vec![], vec![sphere]);
    let n = 2000;
    let (mut origin, mut direction) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
    for k in 0..n {
        // Aim at points of a spiral on the sphere's visible side.
        let z = 1.0 - (k as f64 + 0.5) / n as f64;
        let (sn, cs) = (k as f64 * 2.399963).sin_cos();
        let r = (1.0 - z * z).sqrt();
        let target = sphere.center.as_dvec3()
            + DVec3::new(-z, r * cs, r * sn) * (0.9 * sphere.radius as f64);
        direction[k] = target.normalize().as_vec3();
    }
    let (tmin, tmax) = (vec![0.0; n], vec![f32::INFINITY; n]);
    let (mut t, mut prim) = (vec![0.0; n], vec![0; n]);
    let (mut b1, mut b2) = (vec![0.0; n], vec![0.0; n]);
    crate::intersect::intersect_closest(
        &geom, &origin, &direction, &tmin, &tmax, &mut t, &mut prim, &mut b1, &mut b2,
    );
    let mut worst = 0.0f64;
    for k in 0..n {
        assert_eq!(prim[k], 0, "ray {k} aims inside the sphere");
        // Reference: the near root in f64 from the same f32 inputs.
        let (f, d) = (-sphere.center.as_dvec3(), direction[k].as_dvec3());
        let (a, b) = (d.length_squared(), f.dot(d));
        let l = f - d * (b / a);
        let rr = (sphere.radius as f64).powi(2);
        let q = -(b + (a * (rr - l.length_squared())).sqrt().copysign(b));
        let t_ref = (f.length_squared() - rr) / q;
        let n_ref = (f + d * t_ref).normalize();
        let s = geom.surface_at(0, origin[k], direction[k], t[k], b1[k], b2[k]);
        worst = worst.max(s.ng.as_dvec3().angle_between(n_ref));
    }
    assert!(worst < 1e-6, "worst normal error {worst} rad");
    origin.clear();
    // The parameters of a hit at the pole.
    let up = SceneGeometry::build(
        vec![],
        vec![Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        }],
    );
    let uv = up.surface_uv(0, Vec3::new(0.0, 0.0, 3.0), -Vec3::Z, 2.0, 0.0, 0.0);
    assert_eq!(uv.y, 0.0, "+z is the pole theta = 0");
}

/// The hit direction's series for 1/|h| against `normalize` (a square root and a
/// division) over spheres from tiny to huge, near and far from the origin, for hits with
/// and without the f64 residual: equal to within a few f64 ulps, far under the f32
/// rounding of the normal and the 2^-48 f64 part of the point's error bound.
#[test]
fn sphere_hit_direction_series_matches_normalize() {
    let mut rng = SplitMix64(11);
    let mut worst = 0.0f64;
    for k in 0..20_000 {
        let scale = 10f32.powi((k % 13) as i32 - 6);
        let center = Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5)
            * scale
            * [1.0, 1e3][k % 2];
        let s = Sphere {
            center,
            radius: scale * (0.1 + rng.f32()),
        };
        // A ray from outside at the sphere's centre, slightly off.
        let d = Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5).normalize();
        let o = center - d * s.radius * 3.0 + d.any_orthonormal_vector() * s.radius * 0.3;
        let Some(t64) = crate::intersect::sphere_root_for_tests(o, d, s) else {
            continue;
        };
        let t = t64 as f32;
        for b1 in [(t64 - t as f64) as f32, f32::NAN] {
            let n = sphere_hit_dir(s, o, d, t, b1);
            let t64b = t as f64 + if b1.is_finite() { b1 as f64 } else { 0.0 };
            let h = (o.as_dvec3() - center.as_dvec3()) + d.as_dvec3() * t64b;
            let exact = h.normalize();
            worst = worst.max((n - exact).abs().max_element());
        }
    }
    assert!(worst < 8.0 * f64::EPSILON, "largest difference {worst:e}");
}
