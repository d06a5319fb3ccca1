//! Plain data for risotto: colours, lobe bits, volume stacks and the structure-of-arrays
//! tables (rays, hits, shading points, shadow rays) that systems transform in batches.
//!
//! # Conventions (stated once, kept everywhere)
//! - Units: one world unit is one length unit; extinction/absorption coefficients are per
//!   world unit.
//! - Colour: linear Rec.709 RGB, radiance in W sr^-1 m^-2 per channel ([`Rgb`]).
//! - Directions are unit vectors. A ray direction points *away* from its origin. A shading
//!   point's `vn` points from the point back towards where the ray came from (so `vn = -d`).
//! - Geometric normals of closed shapes point outwards; a hit is on the *front face* when the
//!   ray arrives against the normal (`dot(d, ng) < 0`).
//! - Throughput and Bxdf weights are dimensionless per channel (`f * |cos| / pdf`).

mod color;
mod lobe;
mod tables;
mod volume_stack;

pub use color::Rgb;
pub use lobe::LobeSampled;
pub use tables::{
    HitColumns, HitRow, Hits, PathColumns, PathRow, Paths, RayColumns, RayRow, Rays,
    ShadingPointColumns, ShadingPointRow, ShadingPoints, ShadowRayColumns, ShadowRayRow,
    ShadowRays, NO_HIT,
};
pub use volume_stack::{StackEvent, VolumeEntry, VolumeStack};

/// Re-exported so users of the tables name the same vector types.
pub use glam::{Vec2, Vec3};
