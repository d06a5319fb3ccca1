use glam::Vec3;

use super::SurfaceColumns;
use crate::bvh8::{TriPacket8, WIDTH};
use crate::geometry::Triangles;
use crate::sampler::SplitMix64;
use crate::simd8::Backend;

/// A finite float of random sign and exponent `e` (a normal number).
fn with_exponent(rng: &mut SplitMix64, e: i32) -> f32 {
    let m = f32::from_bits(((e + 127) as u32) << 23);
    let x = m * (1.0 + rng.f32());
    if rng.f32() < 0.5 {
        -x
    } else {
        x
    }
}

/// Triangles of every kind `Triangle::new` and `triangle_point_error` treat apart:
/// ordinary ones, ones of any scale down to `f32::MIN_POSITIVE` (the normal's `|c|^2`
/// underflows: a zero normal) and up to `f32::MAX` (`|c|^2` overflows: the double-precision
/// cross product; points and bounds overflow), small ones far from the origin, and
/// degenerate ones (repeated vertices, collinear).
fn triangle(rng: &mut SplitMix64) -> [Vec3; 3] {
    match (rng.f32() * 6.0) as u32 {
        0 => [point(rng, 10.0), point(rng, 10.0), point(rng, 10.0)],
        kind @ (1 | 2) => {
            // Any exponent, or only those where |c|^2 may overflow.
            let e = if kind == 1 {
                (rng.f32() * 254.0) as i32 - 126
            } else {
                (60 + (rng.f32() * 68.0) as i32).min(127)
            };
            let mut c = [0.0; 9];
            for x in &mut c {
                *x = with_exponent(rng, e);
            }
            let p = |i: usize| Vec3::new(c[3 * i], c[3 * i + 1], c[3 * i + 2]);
            [p(0), p(1), p(2)]
        }
        3 => {
            let far = point(rng, 1e6);
            [0; 3].map(|_| far + point(rng, 1e-3))
        }
        4 => {
            let (a, b) = (point(rng, 5.0), point(rng, 5.0));
            [a, b, a + (b - a) * rng.f32()]
        }
        _ => {
            let (a, b) = (point(rng, 5.0), point(rng, 5.0));
            match (rng.f32() * 3.0) as u32 {
                0 => [a, a, b],
                1 => [a, b, a],
                _ => [a, b, b],
            }
        }
    }
}

/// A point uniform in the cube `[-s, s]^3`.
fn point(rng: &mut SplitMix64, s: f32) -> Vec3 {
    Vec3::new(rng.f32(), rng.f32(), rng.f32()) * (2.0 * s) - Vec3::splat(s)
}

/// Barycentrics as hits report them, and the edges of their range: inside the triangle,
/// on its edges and corners (zeros of either sign), slightly outside, subnormal.
fn barycentrics(rng: &mut SplitMix64) -> (f32, f32) {
    match (rng.f32() * 5.0) as u32 {
        0 => {
            let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (-0.0, 0.5), (0.5, -0.0)];
            corners[(rng.f32() * 5.0) as usize]
        }
        1 => (rng.f32() * 2.0 - 0.5, rng.f32() * 2.0 - 0.5),
        2 => (f32::from_bits(1 + (rng.f32() * 1e6) as u32), rng.f32()),
        _ => {
            let (a, b) = (rng.f32(), rng.f32());
            if a + b > 1.0 {
                (1.0 - a, 1.0 - b)
            } else {
                (a, b)
            }
        }
    }
}

/// The packets of `tris` in a shuffled order and the slot of each triangle.
fn packets(tris: &[[Vec3; 3]], rng: &mut SplitMix64) -> (Vec<TriPacket8>, Vec<u32>) {
    let mut order: Vec<u32> = (0..tris.len() as u32).collect();
    for i in (1..order.len()).rev() {
        order.swap(i, (rng.f32() * (i + 1) as f32) as usize % (i + 1));
    }
    let mut slots = vec![0; tris.len()];
    let mut packets = Vec::new();
    for (p, chunk) in order.chunks(WIDTH).enumerate() {
        let leaf: Vec<(u32, [Vec3; 3])> = chunk.iter().map(|&t| (t, tris[t as usize])).collect();
        packets.push(TriPacket8::new(&leaf));
        for (l, &t) in chunk.iter().enumerate() {
            slots[t as usize] = (p * WIDTH + l) as u32;
        }
    }
    (packets, slots)
}

/// Each backend's `write_surfaces` against `Triangles::surface_at` hit by hit, bit for bit,
/// over batches of every length modulo 8 with some hits on other primitives (their rows
/// untouched, reported), triangles and barycentrics of every kind.
#[test]
fn write_surfaces_is_surface_at_bit_for_bit() {
    let mut rng = SplitMix64(36);
    let tris: Vec<[Vec3; 3]> = (0..3000).map(|_| triangle(&mut rng)).collect();
    let (packets, slots) = packets(&tris, &mut rng);
    let triangles = Triangles {
        slots: &slots,
        packets: &packets,
    };
    let nt = tris.len() as u32;
    // The hit columns: about one hit in 60 on another primitive (past the triangles).
    let hits = 20_000;
    let prim: Vec<u32> = (0..hits)
        .map(|_| {
            if rng.f32() < 1.0 / 60.0 {
                nt + (rng.f32() * 10.0) as u32
            } else {
                ((rng.f32() * nt as f32) as u32).min(nt - 1)
            }
        })
        .collect();
    let (b1, b2): (Vec<f32>, Vec<f32>) = (0..hits).map(|_| barycentrics(&mut rng)).unzip();
    let (mut wide, mut zero, mut checked) = (0, 0, 0);
    let sentinel = Vec3::splat(-7.0);
    for backend in Backend::all() {
        for len in [0, 1, 7, 8, 9, 64, 1003, 4096] {
            let rows: Vec<u32> = (0..len)
                .map(|_| ((rng.f32() * hits as f32) as u32).min(hits as u32 - 1))
                .collect();
            let (mut p, mut ng) = (vec![sentinel; len], vec![sentinel; len]);
            let (mut off, mut u, mut v) = (vec![-7.0; len], vec![-7.0; len], vec![-7.0; len]);
            let out = SurfaceColumns {
                p: &mut p,
                ng: &mut ng,
                p_offset: &mut off,
                u: &mut u,
                v: &mut v,
            };
            let others = triangles.write_surfaces_on(backend, &rows, &prim, &b1, &b2, out);
            let mut any_other = false;
            for (k, &i) in rows.iter().enumerate() {
                let i = i as usize;
                let got = (p[k], ng[k], off[k], u[k], v[k]);
                let bits = |(p, ng, off, u, v): (Vec3, Vec3, f32, f32, f32)| {
                    let (p, ng) = (
                        p.to_array().map(f32::to_bits),
                        ng.to_array().map(f32::to_bits),
                    );
                    (p, ng, off.to_bits(), u.to_bits(), v.to_bits())
                };
                match triangles.surface_at(prim[i], b1[i], b2[i]) {
                    Some(s) => {
                        let want = (s.p, s.ng, s.offset(), s.uv.x, s.uv.y);
                        assert_eq!(
                            bits(got),
                            bits(want),
                            "{backend:?}, hit {i}: triangle {:?} at {:?}",
                            tris[prim[i] as usize],
                            (b1[i], b2[i])
                        );
                        let c = {
                            let t = tris[prim[i] as usize];
                            (t[1] - t[0]).cross(t[2] - t[0])
                        };
                        wide += usize::from(!c.length_squared().is_finite());
                        zero += usize::from(s.ng == Vec3::ZERO);
                        checked += 1;
                    }
                    None => {
                        any_other = true;
                        let untouched = (sentinel, sentinel, -7.0, -7.0, -7.0);
                        assert_eq!(bits(got), bits(untouched), "{backend:?}, hit {i}");
                    }
                }
            }
            assert_eq!(others, any_other, "{backend:?}, {len} rows");
        }
    }
    // Each kind of triangle was met: the double-precision normals and the zero ones.
    assert!(
        wide > 100 && zero > 100 && checked > 10_000,
        "{wide} {zero} {checked}"
    );
}
