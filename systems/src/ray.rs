//! Spawning rays off surfaces: the offset rule shared by every stage that starts a ray (or a
//! shadow ray) on a surface it must not hit again.

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
}
