//! The space a volume's `u, v, w` and grids are measured in: its shape's object space.

use glam::{Affine3A, Vec3};

/// The space a volume's `u, v, w` and grids are measured in: its shape's object space (the
/// space its geometry was written in, before the scene file's `transform`), with the
/// shape's bounds there. `u, v, w` of a world point `P` are
/// `(world_to_object(P) - min) / (max - min)`, so a volume's grid turns, moves and scales
/// with its shape. For a shape written directly in world coordinates (a `sphere`, or any
/// shape without a `transform`) the transforms are the identity, and the object-space
/// bounds are the world-space ones.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeSpace {
    /// The object-space bounds `(min, max)` of the shape: `u, v, w` are 0 at `min` and 1
    /// at `max`.
    pub bounds: (Vec3, Vec3),
    /// The world-space bounding box `(min, max)` of the shape's geometry.
    pub world_bounds: (Vec3, Vec3),
    /// From world to object space.
    pub world_to_object: Affine3A,
    /// From object to world space (the shape's transform).
    pub object_to_world: Affine3A,
}

impl VolumeSpace {
    /// The space of a shape written in world coordinates: identity transforms, the same
    /// bounds `(min, max)` in both spaces.
    pub fn world(min: Vec3, max: Vec3) -> Self {
        VolumeSpace {
            bounds: (min, max),
            world_bounds: (min, max),
            world_to_object: Affine3A::IDENTITY,
            object_to_world: Affine3A::IDENTITY,
        }
    }

    /// The space of a shape whose object space maps to the world by `object_to_world`,
    /// with object-space bounds `bounds` and world-space bounds `world_bounds`.
    pub fn new(
        bounds: (Vec3, Vec3),
        world_bounds: (Vec3, Vec3),
        object_to_world: Affine3A,
    ) -> Self {
        VolumeSpace {
            bounds,
            world_bounds,
            world_to_object: object_to_world.inverse(),
            object_to_world,
        }
    }

    /// True when object space is world space (no transform): users may then skip the
    /// mapping (the built-ins do, so such scenes render exactly as without transforms).
    #[inline]
    pub fn is_identity(&self) -> bool {
        self.object_to_world == Affine3A::IDENTITY
    }

    /// True when object space is the world box up to a positive scale per axis and a
    /// translation (no turn, no mirror): `u, v, w` are then the world point's position in
    /// [`world_bounds`](Self::world_bounds), up to rounding.
    pub fn is_axis_aligned(&self) -> bool {
        let m = glam::Mat3::from(self.object_to_world.matrix3);
        let d = Vec3::new(m.x_axis.x, m.y_axis.y, m.z_axis.z);
        d.cmpgt(Vec3::ZERO).all() && m == glam::Mat3::from_diagonal(d)
    }

    /// World point `p` in object space.
    #[inline]
    pub fn point_to_object(&self, p: Vec3) -> Vec3 {
        if self.is_identity() {
            p
        } else {
            self.world_to_object.transform_point3(p)
        }
    }

    /// World direction `d` in object space (not renormalised: a ray's parameter `t` is the
    /// same in both spaces).
    #[inline]
    pub fn vector_to_object(&self, d: Vec3) -> Vec3 {
        if self.is_identity() {
            d
        } else {
            self.world_to_object.transform_vector3(d)
        }
    }

    /// `u, v, w` of world point `p`: its object-space position relative to
    /// [`bounds`](Self::bounds) (an axis without extent divides by the smallest normal
    /// float).
    #[inline]
    pub fn uvw(&self, p: Vec3) -> Vec3 {
        let (lo, hi) = self.bounds;
        let extent = (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
        (self.point_to_object(p) - lo) / extent
    }
}
