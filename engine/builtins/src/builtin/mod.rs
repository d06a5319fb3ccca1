//! Built-in materials (factories), their Bxdf closures, the phase function and the built-in
//! interiors (`null`, `beer`).
//!
//! Scene-file material types: `diffuse`, `dielectric`, `conductor` / `mirror`, `interface`.
//! Any of them may carry an `interior = { type = "null" | "beer", ... }` table that makes the
//! shape's inside a volume with that integrator (see `docs/scene-format.md`).
//!
//! Any material may be wrapped in an [`OpacityMask`] ([`mask`]): opacity.
//!
//! Three files: [`bxdfs`] (the closures), [`interiors`] (which volume integrator a
//! material's inside gets, and the `null` and `beer` ones) and [`material`] (the factory).
//! Everything is re-exported here.

pub mod bxdfs;
pub mod interiors;
pub mod mask;
pub mod material;

pub use bxdfs::*;
pub use interiors::*;
pub use mask::*;
pub use material::*;
