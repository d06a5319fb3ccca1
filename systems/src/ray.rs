//! Spawning rays off surfaces: how far a new ray's origin moves off the surface point, where
//! a shadow ray towards a sampled light point must stop, and crossing interior boundaries.
//!
//! Both bounds are relative to the coordinates' magnitude so that tiny and huge scenes
//! work alike, and both must cover the rounding error of the points involved: the surface
//! point the ray leaves (pbrt-v4 sec. 6.8.6 bounds a barycentric point's error by
//! `gamma(7) sum |b_i p_i|`, about 4e-7 of its largest coordinate; sphere points are
//! rounded once from double precision, see [`crate::geometry::SceneGeometry::surface_at`])
//! and, for a shadow ray, the light point it aims at, whose error is bounded the same way
//! but by *its* coordinates.

use glam::Vec3;
use risotto_components::{StackEvent, VolumeEntry, VolumeStack};

/// Per-shape data for crossing interior boundaries, from the compiled scene: whether rays
/// crossing shape `s` enter or leave a volume the renderer tracks (`tracked[s]`), and that
/// volume's stack entry (`entry[s]`).
#[derive(Clone, Copy, Debug)]
pub struct InteriorBoundaries<'a> {
    /// Whether each shape's interior is tracked on volume stacks.
    pub tracked: &'a [bool],
    /// Each shape's stack entry (meaningful where `tracked`).
    pub entry: &'a [VolumeEntry],
}

impl InteriorBoundaries<'_> {
    /// Records a crossing of `shape` on `stack` (entering on a front face, leaving on a back
    /// face) when the shape is tracked; `None` when it is not.
    #[inline]
    pub fn cross(
        &self,
        stack: &mut VolumeStack,
        shape: u32,
        front_face: bool,
    ) -> Option<StackEvent> {
        let s = shape as usize;
        self.tracked[s].then(|| stack.cross(self.entry[s], front_face))
    }
}

/// Offset for spawning rays off a surface, relative to the coordinates' magnitude so that tiny
/// and huge scenes both work: about 4 ulps of the largest coordinate (f32 ulp = 1.19e-7
/// relative). That is above the rounding error of a hit point (barycentric interpolation:
/// pbrt-v4 sec. 6.8.6 bounds it by gamma(7) sum |b_i p_i|, under one ulp; sphere points are
/// `centre + n r` rounded once or twice), and the triangle test also rejects re-hits within
/// its conservative t bound, while surfaces a few ulps apart stay separable
/// (`tests/continuation_budget.rs` crosses layers 2e-6 apart at unit scale).
#[inline]
pub fn ray_offset(p: Vec3) -> f32 {
    p.abs().max_element() * 5e-7 + 1e-9
}

/// Direction and `tmax` of a shadow ray from `origin` (the surface point `p` moved off its
/// surface) to the light point `p + distance * wi` (`wi` unit, from the light sample): the
/// ray aims at the light point from `origin` itself, and stops short of it by 1e-4 of the
/// length (the rounding of `distance` and `wi`) and by [`ray_offset`] of the light point
/// (its own rounding error is under that offset), so that it never reaches the emitter it
/// aims at. A light at infinity (`distance` infinite) keeps `wi` with no `tmax`.
///
/// The former ray kept `wi` from `p` and stopped at `distance * (1 - 1e-4) - ray_offset(p)`:
/// moved off the surface by the offset, its line misses the light point by about the
/// offset and crosses an oblique emitter `offset (1 / cos - cos)` early, and the light
/// point's own error was not allowed for. 2e3 units from the origin, where the offset
/// (1e-3) exceeds `1e-4 distance`, most shadow rays of a lamp 1 unit above a floor hit the
/// lamp itself (issue 14 item 2: 0.0259 against 0.0692 at 1e4).
#[inline]
pub fn shadow_ray(p: Vec3, origin: Vec3, wi: Vec3, distance: f32) -> (Vec3, f32) {
    if !distance.is_finite() {
        return (wi, f32::INFINITY);
    }
    let light = p + wi * distance;
    let d = light - origin;
    let length = d.length();
    if length.is_nan() || length <= 0.0 {
        return (wi, 0.0);
    }
    (d / length, length * (1.0 - 1e-4) - ray_offset(light))
}

/// `offset` signed to move a point along `ng` to the side `wi` points to: `(side of ng) *
/// offset` as `ng * toward(..)`, the same bits (negating a product's factor negates the
/// product), with the sign set by a bit operation instead of a branch on the (random)
/// direction.
#[inline]
pub fn toward(wi: Vec3, ng: Vec3, offset: f32) -> f32 {
    // Flip unless `wi . ng >= 0` (a NaN dot product flips, as the branch did).
    let keep_side = (wi.dot(ng) >= 0.0) as u32;
    f32::from_bits(offset.to_bits() ^ ((keep_side ^ 1) << 31))
}

/// Origin of a ray leaving point `p` in direction `wi`: on a surface (`on_surface`) moved
/// off it by [`ray_offset`] along the geometric normal `ng`, to the side `wi` goes to; inside
/// a volume (no surface to re-hit) `p` itself.
#[inline]
pub fn spawn_origin(p: Vec3, ng: Vec3, wi: Vec3, on_surface: bool) -> Vec3 {
    if on_surface {
        p + ng * toward(wi, ng, ray_offset(p))
    } else {
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::SceneGeometry;
    use crate::intersect::intersect_occluded;
    use crate::sampler::SplitMix64;
    use glam::Vec2;

    #[test]
    fn toward_matches_the_branch() {
        let ng = Vec3::new(0.0, 1.0, 0.0);
        for wi in [Vec3::Y, -Vec3::Y, Vec3::X, Vec3::new(0.3, -0.2, 0.9)] {
            let branch = if wi.dot(ng) >= 0.0 { 0.25 } else { -0.25 };
            assert_eq!(toward(wi, ng, 0.25).to_bits(), f32::to_bits(branch));
        }
    }

    #[test]
    fn spawn_origin_leaves_to_the_side_of_the_direction() {
        let p = Vec3::new(100.0, 2.0, -3.0);
        let ng = Vec3::Z;
        let up = spawn_origin(p, ng, Vec3::new(0.1, 0.0, 0.9), true);
        let down = spawn_origin(p, ng, Vec3::new(0.1, 0.0, -0.9), true);
        assert!(up.z > p.z && down.z < p.z);
        assert_eq!(spawn_origin(p, ng, -Vec3::Z, false), p);
        // Relative offset: 4-5 ulps of the largest coordinate.
        assert!((up.z - p.z - ray_offset(p)).abs() < 1e-6);
    }

    /// Shadow rays from a floor point to sampled points of a lamp 1 unit above (sharing the
    /// lamp's geometry as the only occluder) are never occluded by the lamp itself, near the
    /// origin and up to 1e6 units away, for origins offset along the floor normal as
    /// spawned rays are.
    #[test]
    fn shadow_rays_stop_short_of_their_light_point_at_any_offset() {
        let mut rng = SplitMix64(7);
        for far in [0.0f32, 1e2, 2e3, 1e4, 1e5, 1e6] {
            let c = Vec3::new(far, 0.0, far);
            // Lamp: the unit square at height 1 (both triangles), normal -y.
            let (a, b, d, e) = (
                c + Vec3::new(-0.5, 1.0, -0.5),
                c + Vec3::new(0.5, 1.0, -0.5),
                c + Vec3::new(0.5, 1.0, 0.5),
                c + Vec3::new(-0.5, 1.0, 0.5),
            );
            let lamp = SceneGeometry::build(vec![[a, b, d], [a, d, e]], vec![]);
            let (mut origins, mut dirs, mut tmax) = (vec![], vec![], vec![]);
            for _ in 0..2000 {
                let prim = (rng.next_u64() % 2) as u32;
                let (q, _) = lamp.sample_prim(prim, Vec2::new(rng.f32(), rng.f32()));
                let p = c + Vec3::new(rng.f32() * 4.0 - 2.0, 0.0, rng.f32() * 4.0 - 2.0);
                let dist = (q - p).length();
                let wi = (q - p) / dist;
                let origin = p + Vec3::Y * ray_offset(p);
                let (dir, t) = shadow_ray(p, origin, wi, dist);
                origins.push(origin);
                dirs.push(dir);
                tmax.push(t);
            }
            let mut occluded = vec![false; origins.len()];
            let tmin = vec![0.0; origins.len()];
            intersect_occluded(&lamp, &origins, &dirs, &tmin, &tmax, &mut occluded);
            let hits = occluded.iter().filter(|&&o| o).count();
            assert_eq!(
                hits, 0,
                "offset {far}: {hits} of 2000 rays hit their own lamp"
            );
            // And they reach almost to it: within 1e-6 relative of the coordinates plus 1e-4
            // of the distance (an occluder that close to the lamp is still seen).
            for (i, &t) in tmax.iter().enumerate() {
                let gap = (origins[i] + dirs[i] * t - c).y;
                assert!(
                    gap > 1.0 - 1e-3 - 2e-6 * far,
                    "offset {far}: ray {i} stops at {gap}"
                );
            }
        }
    }

    #[test]
    fn lights_at_infinity_have_no_tmax() {
        assert_eq!(
            shadow_ray(Vec3::ONE, Vec3::ONE, Vec3::Y, f32::INFINITY),
            (Vec3::Y, f32::INFINITY)
        );
    }
}
