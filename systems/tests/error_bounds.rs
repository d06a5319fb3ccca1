//! Error-bounded ray origins (pbrt-v4 sec. 6.8): surface points' error bounds against double
//! precision, and rays spawned off them with `spawn_origin` never finding their own surface
//! again, over scales from 1e-6 to 1e6 and offsets from the origin up to 1e6.

use glam::{DVec3, Vec2, Vec3};
use risotto_components::NO_HIT;
use risotto_systems::geometry::{SceneGeometry, Sphere, SurfaceSample};
use risotto_systems::intersect::intersect_closest;
use risotto_systems::ray::spawn_origin;
use risotto_systems::sampler::SplitMix64 as Rng;

fn range(rng: &mut Rng, lo: f32, hi: f32) -> f32 {
    lo + (hi - lo) * rng.f32()
}

fn unit(rng: &mut Rng) -> Vec3 {
    loop {
        let v = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - Vec3::ONE;
        let l = v.length_squared();
        if l > 1e-4 && l <= 1.0 {
            return v / l.sqrt();
        }
    }
}

/// A scale `10^[-6, 6]` and an offset from the origin for it: none, or up to `1e3` times the
/// scale (at most 1e6), in a random direction. Beyond about `1e6` times its size a shape is
/// not representable in f32 (its coordinates' ulps exceed it).
fn scale_and_centre(rng: &mut Rng) -> (f32, Vec3) {
    let scale = 10f32.powf(range(rng, -6.0, 6.0));
    let far = if rng.f32() < 0.2 {
        0.0
    } else {
        (scale * 10f32.powf(range(rng, 0.0, 3.0))).min(1e6)
    };
    (scale, unit(rng) * far)
}

/// Triangles: a centre and three vertices, sometimes one of them much farther out (slivers
/// whose vertices differ in magnitude: the rounding of `b0 = 1 - b1 - b2` then multiplies a
/// large vertex while `b0` is small).
fn random_triangle(rng: &mut Rng) -> [Vec3; 3] {
    let (scale, c) = scale_and_centre(rng);
    let mut v = [0; 3].map(|_| c + unit(rng) * scale);
    if rng.f32() < 0.3 {
        let k = (rng.next_u64() % 3) as usize;
        v[k] = c + unit(rng) * scale * 1e3;
    }
    v
}

fn random_sphere(rng: &mut Rng) -> Sphere {
    let (scale, c) = scale_and_centre(rng);
    Sphere {
        center: c,
        radius: scale,
    }
}

/// Nearest hits of rays on `geom` (tmin +0.0, as spawned rays have).
fn trace(geom: &SceneGeometry, o: &[Vec3], d: &[Vec3]) -> (Vec<f32>, Vec<u32>, Vec<f32>, Vec<f32>) {
    let m = o.len();
    let (mut t, mut prim) = (vec![0.0; m], vec![NO_HIT; m]);
    let (mut b1, mut b2) = (vec![0.0; m], vec![0.0; m]);
    let (tmin, tmax) = (vec![0.0; m], vec![f32::INFINITY; m]);
    intersect_closest(
        geom, o, d, &tmin, &tmax, &mut t, &mut prim, &mut b1, &mut b2,
    );
    (t, prim, b1, b2)
}

/// Rays from random points around `geom`'s only primitive aimed at random points of it:
/// `(origin, direction, hit)` of those that hit it.
fn hits_on(
    geom: &SceneGeometry,
    size: f32,
    n: usize,
    rng: &mut Rng,
) -> Vec<(Vec3, Vec3, SurfaceSample)> {
    let (mut o, mut d) = (vec![], vec![]);
    for _ in 0..n {
        let target = geom.sample_surface(0, Vec2::new(rng.f32(), rng.f32())).p;
        let from = target + unit(rng) * size * range(rng, 0.5, 4.0);
        o.push(from);
        d.push((target - from).normalize());
    }
    let (t, prim, b1, b2) = trace(geom, &o, &d);
    (0..n)
        .filter(|&i| prim[i] == 0)
        .map(|i| {
            (
                o[i],
                d[i],
                geom.surface_at(0, o[i], d[i], t[i], b1[i], b2[i]),
            )
        })
        .collect()
}

/// `|p64 - p| <= p_error` per component, `p64` the same barycentric point in double precision
/// (`b0 = 1 - b1 - b2` exact), for hit points (`surface_at`) and light samples
/// (`sample_surface`) of random triangles at every scale and offset.
#[test]
fn triangle_points_are_within_their_error_bound() {
    let mut rng = Rng(31);
    let (mut checked, mut violations, mut worst) = (0, 0, 0.0f64);
    for _ in 0..4000 {
        let v = random_triangle(&mut rng);
        let geom = SceneGeometry::build(vec![v], vec![]);
        let [a, b, c] = v.map(Vec3::as_dvec3);
        for _ in 0..25 {
            // Barycentrics as hits produce them: every mantissa bit set at random (not
            // multiples of 2^-24, for which `1 - b1` is exact), inside, sometimes on an edge.
            let mut full = || (rng.next_u64() as f64 / 2f64.powi(64)) as f32;
            let (mut b1, mut b2) = (full(), full());
            if b1 + b2 > 1.0 {
                (b1, b2) = (1.0 - b1, 1.0 - b2);
            }
            if rng.f32() < 0.1 {
                b2 = 1.0 - b1;
            }
            let s = geom.surface_at(0, Vec3::ZERO, Vec3::Z, 1.0, b1, b2);
            let (b1d, b2d) = (b1 as f64, b2 as f64);
            let p64 = a * (1.0 - b1d - b2d) + b * b1d + c * b2d;
            let err = (p64 - s.p.as_dvec3()).abs();
            let bound = s.p_error.as_dvec3();
            checked += 1;
            if err.cmpgt(bound).any() {
                violations += 1;
            }
            worst = worst.max((err / bound.max(DVec3::splat(1e-300))).max_element());
            // A light sample (its barycentrics are not returned): its box meets the plane of
            // the triangle, `|n . (q - a)| <= dot(|n|, q_error)`.
            let q = geom.sample_surface(0, Vec2::new(rng.f32(), rng.f32()));
            let n = (b - a).cross(c - a);
            if n.length() > 0.0 && q.ng != Vec3::ZERO {
                let n = n.normalize();
                let dist = (q.p.as_dvec3() - a).dot(n).abs();
                let allowed = q.p_error.as_dvec3().dot(n.abs()) * (1.0 + 1e-6);
                checked += 1;
                if dist > allowed {
                    violations += 1;
                }
            }
        }
    }
    assert_eq!(
        violations, 0,
        "{violations} of {checked} points outside their bound"
    );
    assert!(worst <= 1.0, "worst error / bound {worst}");
}

/// Whether the box `p +- e` meets the sphere's surface (in f64): the box's nearest point to
/// the centre is within the radius and its farthest is beyond it.
fn box_meets_sphere(p: Vec3, e: Vec3, s: Sphere) -> bool {
    let (lo, hi) = ((p - e).as_dvec3(), (p + e).as_dvec3());
    let (lo, hi) = (lo.min(hi), lo.max(hi));
    let c = s.center.as_dvec3();
    let nearest = c.clamp(lo, hi);
    let far = DVec3::select((c - lo).abs().cmpgt((c - hi).abs()), lo, hi);
    let r = s.radius as f64;
    (nearest - c).length() <= r && (far - c).length() >= r
}

/// A sphere point's bound box contains a point of the exact sphere (there is no
/// barycentric f64 twin of a sphere point: the box meeting the surface is what the bound
/// means), for hits from outside and inside and for light samples, at every scale and
/// offset; and the f64 hit point from an independent quadratic is within the bound plus the
/// tangential uncertainty of the ray's hit itself.
#[test]
fn sphere_points_are_within_their_error_bound() {
    let mut rng = Rng(32);
    let (mut checked, mut violations) = (0, 0);
    for _ in 0..2000 {
        let s = random_sphere(&mut rng);
        let geom = SceneGeometry::build(vec![], vec![s]);
        for (_, _, h) in hits_on(&geom, s.radius, 20, &mut rng) {
            checked += 1;
            violations += !box_meets_sphere(h.p, h.p_error, s) as usize;
        }
        for _ in 0..20 {
            let q = geom.sample_surface(0, Vec2::new(rng.f32(), rng.f32()));
            checked += 1;
            violations += !box_meets_sphere(q.p, q.p_error, s) as usize;
        }
    }
    assert!(checked > 50000, "{checked} points");
    assert_eq!(
        violations, 0,
        "{violations} of {checked} points outside their bound"
    );
}

/// Rays spawned off hits on a lone triangle or sphere, to either side (reflection: the side
/// the ray came from; transmission: the other side), never hit that surface again: a
/// triangle not at all, a sphere not within half the chord the direction has through it.
#[test]
fn spawned_rays_never_re_hit_their_own_surface() {
    let mut rng = Rng(33);
    let (mut spawned, mut rehits) = (0usize, 0usize);
    for shape in 0..3000 {
        let sphere = shape % 2 == 1;
        let (geom, size) = if sphere {
            let s = random_sphere(&mut rng);
            (SceneGeometry::build(vec![], vec![s]), s.radius)
        } else {
            let v = random_triangle(&mut rng);
            let size = (v[1] - v[0]).length().max((v[2] - v[0]).length());
            (SceneGeometry::build(vec![v], vec![]), size)
        };
        let hits = hits_on(&geom, size, 20, &mut rng);
        let (mut o, mut d, mut chord) = (vec![], vec![], vec![]);
        for (_, dir, h) in hits {
            if h.ng == Vec3::ZERO {
                continue;
            }
            for transmit in [false, true] {
                // A random direction on the chosen side, not grazing.
                let incoming_side = if dir.dot(h.ng) < 0.0 { 1.0 } else { -1.0 };
                let side = if transmit {
                    -incoming_side
                } else {
                    incoming_side
                };
                let mut w = unit(&mut rng);
                if w.dot(h.ng) * side < 0.0 {
                    w -= 2.0 * w.dot(h.ng) * h.ng;
                }
                let cos = w.dot(h.ng).abs();
                if cos < 0.01 {
                    continue;
                }
                o.push(spawn_origin(h.p, h.ng, h.offset(), w, true));
                d.push(w);
                // Into a sphere (against its outward normal) the ray crosses it over
                // `2 r cos`; out of it, never again.
                let inward = w.dot(h.ng) < 0.0;
                chord.push(if sphere && inward {
                    2.0 * size * cos
                } else {
                    0.0
                });
            }
        }
        let (t, prim, ..) = trace(&geom, &o, &d);
        for i in 0..o.len() {
            spawned += 1;
            if prim[i] != NO_HIT && t[i] < 0.5 * chord[i].max(f32::MIN_POSITIVE) {
                rehits += 1;
            }
            if chord[i] > 0.0 && prim[i] == NO_HIT {
                // A ray into a sphere must find its far side.
                rehits += 1;
            }
        }
    }
    assert!(spawned > 50000, "{spawned} rays");
    assert_eq!(
        rehits, 0,
        "{rehits} of {spawned} spawned rays re-hit their own surface"
    );
}
