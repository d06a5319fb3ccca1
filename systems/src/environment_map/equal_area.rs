//! The equal-area octahedral mapping between the unit square and the unit sphere (Clarberg,
//! "Fast Equal-Area Mapping of the (Hemi)Sphere using SIMD", JGT 2008), the parameterisation
//! of pbrt-v4's image infinite lights (Pharr, Jakob, Humphreys, *Physically Based
//! Rendering*, 4th ed., §3.8.3, `EqualAreaSquareToSphere` / `EqualAreaSphereToSquare`).
//!
//! The square `[0, 1]^2`, recentred to `[-1, 1]^2`, is folded as an octahedron: the diamond
//! `|u| + |v| <= 1` is the hemisphere `z >= 0` (its centre `+z`), the four corner triangles
//! the hemisphere `z < 0` (the corners `-z`); the signs of `u` and `v` are those of `x` and
//! `y`. The radius `r = 1 - |1 - (|u| + |v|)|` (0 at the poles, the centre and the
//! corners; 1 on the diamond's edge, the equator) sets `z = ±(1 - r^2)`, and the position
//! along the square ring of radius `r` the azimuth. Area is preserved exactly: the Jacobian of square
//! to sphere is `4π` (the sphere's area over the square's), so a density `p(u, v)` on the
//! square is `p(u, v) / 4π` per unit solid angle. The map is continuous across the square's
//! edges when it is read with its octahedral wrap, and `+-x`, `+-y` lie on the diamond's
//! corners (`(1, 0.5)` is `+x`, `(0.5, 1)` is `+y` in `[0, 1]^2` coordinates).
//!
//! Image rows follow pbrt's image convention: `v = 0` is the first row of the file (the top
//! row), as for the latitude-longitude maps here.

use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_PI_4;

/// The direction of square point `p` in `[0, 1]^2`.
#[inline]
pub fn square_to_sphere(p: Vec2) -> Vec3 {
    let (u, v) = (2.0 * p.x - 1.0, 2.0 * p.y - 1.0);
    let (up, vp) = (u.abs(), v.abs());
    // Signed distance from the diamond's edge: > 0 inside (z > 0).
    let signed = 1.0 - (up + vp);
    let r = 1.0 - signed.abs();
    // The azimuth within the quadrant, 0 along +u to π/2 along +v.
    let phi = if r == 0.0 { 1.0 } else { (vp - up) / r + 1.0 } * FRAC_PI_4;
    let z = (1.0 - r * r).copysign(signed);
    let (sin_phi, cos_phi) = phi.sin_cos();
    let ring = r * (2.0 - r * r).max(0.0).sqrt();
    Vec3::new(cos_phi.copysign(u) * ring, sin_phi.copysign(v) * ring, z)
}

/// The square point in `[0, 1]^2` of the unit direction `d` (the inverse of
/// [`square_to_sphere`]); the azimuth by `atan` itself, where pbrt uses a minimax polynomial
/// of `atan` (their points differ by about 1e-6 of the square).
#[inline]
pub fn sphere_to_square(d: Vec3) -> Vec2 {
    let (x, y, z) = (d.x.abs(), d.y.abs(), d.z.abs());
    let r = (1.0 - z).max(0.0).sqrt();
    let (a, b) = (x.max(y), x.min(y));
    let b = if a == 0.0 { 0.0 } else { b / a };
    // The azimuth's share of the quadrant, in [0, 1].
    let mut phi = b.atan() * std::f32::consts::FRAC_2_PI;
    if x < y {
        phi = 1.0 - phi;
    }
    let mut v = phi * r;
    let mut u = r - v;
    if d.z < 0.0 {
        // The lower hemisphere is the corner triangle: mirror across the diamond's edge.
        (u, v) = (1.0 - v, 1.0 - u);
    }
    let (u, v) = (u.copysign(d.x), v.copysign(d.y));
    Vec2::new(
        ((u + 1.0) * 0.5).clamp(0.0, 1.0),
        ((v + 1.0) * 0.5).clamp(0.0, 1.0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn halton(i: u32, base: u32) -> f32 {
        let (mut f, mut r, mut i) = (1.0f64, 0.0f64, i);
        while i > 0 {
            f /= base as f64;
            r += f * (i % base) as f64;
            i /= base;
        }
        r as f32
    }

    #[test]
    fn the_map_is_pbrts_orientation_and_round_trips() {
        let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-6;
        assert!(close(square_to_sphere(Vec2::new(0.5, 0.5)), Vec3::Z));
        assert!(close(square_to_sphere(Vec2::new(1.0, 0.5)), Vec3::X));
        assert!(close(square_to_sphere(Vec2::new(0.0, 0.5)), -Vec3::X));
        assert!(close(square_to_sphere(Vec2::new(0.5, 1.0)), Vec3::Y));
        assert!(close(square_to_sphere(Vec2::new(0.5, 0.0)), -Vec3::Y));
        for corner in [
            Vec2::ZERO,
            Vec2::ONE,
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
        ] {
            assert!(close(square_to_sphere(corner), -Vec3::Z), "{corner}");
        }
        for i in 1..4096 {
            let p = Vec2::new(halton(i, 2), halton(i, 3));
            let d = square_to_sphere(p);
            assert!((d.length() - 1.0).abs() < 1e-5, "{p}: |{d}|");
            let q = sphere_to_square(d);
            assert!((q - p).abs().max_element() < 2e-5, "{p} -> {d} -> {q}");
            // The signs of x, y follow u - 1/2, v - 1/2; z > 0 inside the diamond.
            let (u, v) = (2.0 * p.x - 1.0, 2.0 * p.y - 1.0);
            assert_eq!(d.z > 0.0, u.abs() + v.abs() < 1.0, "{p}: {d}");
            assert!(d.x * u >= 0.0 && d.y * v >= 0.0, "{p}: {d}");
        }
    }

    #[test]
    fn uniform_square_points_are_uniform_on_the_sphere() {
        // Equal area: uniform points of the square land uniformly on the sphere. Chi-square
        // over 8 bands of equal solid angle in z times 16 sectors of azimuth (128 cells of
        // equal probability), 128k Halton points; the 0.1 % quantile of chi-square with 127
        // degrees of freedom is about 181. A map off by a factor in r (e.g. z = 1 - r) fails.
        let (bands, sectors, n) = (8usize, 16usize, 128 * 1024u32);
        let mut counts = vec![0u32; bands * sectors];
        for i in 0..n {
            let d = square_to_sphere(Vec2::new(halton(i + 1, 2), halton(i + 1, 3)));
            let band = (((d.z + 1.0) * 0.5 * bands as f32) as usize).min(bands - 1);
            let phi = d.y.atan2(d.x) + std::f32::consts::PI;
            let sector = ((phi / std::f32::consts::TAU * sectors as f32) as usize).min(sectors - 1);
            counts[band * sectors + sector] += 1;
        }
        let expected = n as f64 / counts.len() as f64;
        let chi2: f64 = counts
            .iter()
            .map(|&c| (c as f64 - expected).powi(2) / expected)
            .sum();
        assert!(chi2 < 181.0, "chi-square {chi2}");
    }
}
