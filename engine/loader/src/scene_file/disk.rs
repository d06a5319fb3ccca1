//! `type = "disk"`: Mitsuba 3's disk shape (`src/shapes/disk.cpp`), the disk of radius 1
//! centred at the object-space origin in the z = 0 plane with normal +z, placed by
//! `transform`; optionally an annulus (`inner_radius`, pbrt-v4's `innerradius`) and a
//! `radius` other than 1. It is tessellated into triangles whose rim is the regular
//! [`RIM_SEGMENTS`]-gon inscribed in the circle, with texture coordinates in Mitsuba's
//! polar convention, `u = r / radius`, `v = phi / (2 pi)`, `phi` in [0, 2 pi) measured
//! from object +x towards +y, given per vertex (the seam at `phi = 0` has its own vertices
//! with `v = 1` on the side that ends there). The normal is the plane's: no vertex normals,
//! so hits are shaded with the geometric normal.
//!
//! Area: a regular n-gon inscribed in a circle of radius R has area `n/2 R^2 sin(2 pi / n)`,
//! so the tessellation's area is the disk's (or annulus') times `sin(x) / x` with
//! `x = 2 pi / n`: for n = 512 it is short by `1 - sin(x)/x ~= x^2 / 6 = 2.5e-5`, below the
//! 1e-4 asked of it (n = 256 would be 1.0e-4).
//!
//! Layout: a full disk is not a fan of 512 slivers from the centre (their bounding boxes
//! would all overlap at the centre, and a ray there would test a quarter of them) but rings
//! whose radius doubles outwards from a fan of 8 triangles at radius 1/64, each ring with
//! twice the segments of the one inside it (three triangles per inner segment: no
//! T-junction, so no cracks): 1520 triangles, none longer than half the radius. An annulus
//! is one strip of 2 x 512 triangles.

use glam::{DAffine3, DVec2, DVec3, Vec2};

use super::geometry::{mirrors, read_transform, to_world, wound, Triangle};
use super::params::Reader;
use risotto_engine::diagnostics::SceneError;
use risotto_systems::mesh_attributes::VertexAttributes;

/// Segments of the rim: the tessellation's area is short of the disk's by `1 - sin(x) / x`,
/// `x = 2 pi / RIM_SEGMENTS` (2.5e-5).
pub(crate) const RIM_SEGMENTS: usize = 512;

/// Segments of the innermost fan of a full disk; each ring outwards doubles them.
const CENTRE_SEGMENTS: usize = 8;

/// A disk's triangles in object space with one texture coordinate per corner.
#[derive(Default)]
struct Tessellation {
    positions: Vec<DVec3>,
    uvs: Vec<Vec2>,
    triangles: Vec<[u32; 3]>,
}

impl Tessellation {
    /// Adds a vertex at polar coordinates `(r, segment k of n)` of a disk of radius
    /// `radius`; `k = n` is the seam's end: the position of `k = 0` (bit for bit, so the
    /// rings close without a crack) with `v = 1`.
    fn vertex(&mut self, r: f64, k: usize, n: usize, radius: f64) -> u32 {
        let phi = std::f64::consts::TAU * (k % n) as f64 / n as f64;
        let (sin, cos) = phi.sin_cos();
        self.positions.push(DVec3::new(r * cos, r * sin, 0.0));
        self.uvs
            .push(DVec2::new(r / radius, k as f64 / n as f64).as_vec2());
        (self.positions.len() - 1) as u32
    }

    /// The `n + 1` vertices of a ring (the last one the seam's end).
    fn ring(&mut self, r: f64, n: usize, radius: f64) -> Vec<u32> {
        (0..=n).map(|k| self.vertex(r, k, n, radius)).collect()
    }
}

/// The disk of radius `radius` (or the annulus from `inner` to `radius`) in the z = 0 plane,
/// every triangle wound counter-clockwise seen from +z (geometric normal +z).
fn tessellate(radius: f64, inner: f64) -> Tessellation {
    let mut t = Tessellation::default();
    if inner > 0.0 {
        let n = RIM_SEGMENTS;
        let (i, o) = (t.ring(inner, n, radius), t.ring(radius, n, radius));
        for k in 0..n {
            t.triangles.push([i[k], o[k], o[k + 1]]);
            t.triangles.push([i[k], o[k + 1], i[k + 1]]);
        }
        return t;
    }
    // The centre fan: one centre vertex per triangle, with the v of its segment's middle
    // (v is undefined at r = 0; this keeps it continuous across each triangle).
    let rings = (RIM_SEGMENTS / CENTRE_SEGMENTS).trailing_zeros() as i32;
    let mut n = CENTRE_SEGMENTS;
    let mut r = radius * 0.5f64.powi(rings);
    let mut inside = t.ring(r, n, radius);
    for k in 0..n {
        let phi = std::f64::consts::TAU * (k as f64 + 0.5) / n as f64;
        t.positions.push(DVec3::ZERO);
        t.uvs
            .push(Vec2::new(0.0, (phi / std::f64::consts::TAU) as f32));
        let centre = (t.positions.len() - 1) as u32;
        t.triangles.push([centre, inside[k], inside[k + 1]]);
    }
    while n < RIM_SEGMENTS {
        let outside = t.ring(2.0 * r, 2 * n, radius);
        for k in 0..n {
            let (a, b) = (inside[k], inside[k + 1]);
            let (o0, o1, o2) = (outside[2 * k], outside[2 * k + 1], outside[2 * k + 2]);
            t.triangles.push([a, o0, o1]);
            t.triangles.push([a, o1, b]);
            t.triangles.push([b, o1, o2]);
        }
        (inside, n, r) = (outside, 2 * n, 2.0 * r);
    }
    t
}

/// `disk`: `radius` (default 1) and `inner_radius` (default 0, below `radius`) in object
/// space, placed by `transform`; world-space triangles, the transform, and the texture
/// coordinates as attributes (corners swapped with the vertices under a mirroring
/// transform, as [`to_world`] swaps them).
pub(crate) fn disk(
    r: &Reader<'_>,
) -> Result<(Vec<Triangle>, DAffine3, VertexAttributes), SceneError> {
    let radius = r.f32_where(
        "radius",
        Some(1.0),
        "must be finite and > 0 (object space; the transform scales it too)",
        |v| v.is_finite() && v > 0.0,
    )?;
    let inner = r.f32_where(
        "inner_radius",
        Some(0.0),
        &format!("must be >= 0 and below the radius ({radius})"),
        |v| v >= 0.0 && v < radius,
    )?;
    let m = read_transform(r)?;
    let t = tessellate(f64::from(radius), f64::from(inner));
    let p = &t.positions;
    let local = t
        .triangles
        .iter()
        .map(|c| [p[c[0] as usize], p[c[1] as usize], p[c[2] as usize]]);
    let triangles = to_world(&m, local);
    let flip = mirrors(&m);
    let attributes = VertexAttributes {
        normals: Vec::new(),
        uvs: t.uvs,
        corners: t.triangles.iter().map(|&t| wound(t, flip)).collect(),
        shadow_terminator_offset: false,
    };
    Ok((triangles, m, attributes))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tessellation is the inscribed regular 512-gon (annulus): its area is the closed
    /// form `n/2 sin(2 pi/n) (R^2 - ri^2)`, within 1e-4 of the disk's, and every triangle is
    /// wound towards +z.
    #[test]
    fn tessellation_area_is_the_polygon_and_within_1e_4_of_the_disk() {
        for (radius, inner) in [(1.0, 0.0), (2.5, 0.0), (1.0, 0.3), (3.0, 2.9)] {
            let t = tessellate(radius, inner);
            let p = &t.positions;
            let mut area = 0.0;
            for &[a, b, c] in &t.triangles {
                let (a, b, c) = (p[a as usize], p[b as usize], p[c as usize]);
                let n = (b - a).cross(c - a);
                assert!(n.z > 0.0 && n.x == 0.0 && n.y == 0.0, "winding");
                area += 0.5 * n.z;
            }
            let x = std::f64::consts::TAU / RIM_SEGMENTS as f64;
            let polygon = 0.5 * RIM_SEGMENTS as f64 * x.sin() * (radius * radius - inner * inner);
            assert!(
                (area - polygon).abs() < 1e-12 * polygon,
                "{area} vs {polygon}"
            );
            let exact = std::f64::consts::PI * (radius * radius - inner * inner);
            let error = 1.0 - area / exact;
            assert!(error > 0.0 && error < 1e-4, "relative area error {error}");
            // Every vertex is on the disk, and its uv is Mitsuba's polar pair.
            for (q, uv) in p.iter().zip(&t.uvs) {
                let rho = q.truncate().length();
                assert!(rho <= radius * (1.0 + 1e-12) && rho >= inner * (1.0 - 1e-12));
                assert!((f64::from(uv.x) - rho / radius).abs() < 1e-6);
                if rho > 0.0 {
                    let phi = q.y.atan2(q.x).rem_euclid(std::f64::consts::TAU);
                    let v = f64::from(uv.y);
                    // The seam's end vertices carry v = 1 for phi = 0.
                    let d = (v - phi / std::f64::consts::TAU).abs();
                    assert!(d < 1e-6 || (d - 1.0).abs() < 1e-6, "v {v} at phi {phi}");
                }
            }
        }
        assert_eq!(tessellate(1.0, 0.0).triangles.len(), 1520);
    }
}
