//! Built-in materials (factories), their Bxdf closures, the phase function and the built-in
//! interiors (`null`, `beer`).
//!
//! Scene-file material types: `diffuse`, `dielectric`, `conductor` / `mirror`,
//! `rough_conductor`, `rough_dielectric`, `interface`.
//! Any of them may carry an `interior = { type = "null" | "beer", ... }` table that makes the
//! shape's inside a volume with that integrator (see `docs/scene-format.md`).
//!
//! Four files: [`bxdfs`] (the closures), [`rough`] (the GGX closures), [`interiors`] (which volume integrator a
//! material's inside gets, and the `null` and `beer` ones) and [`material`] (the factory).
//! Everything is re-exported here.

pub mod bxdfs;
pub mod interiors;
pub mod material;
pub mod rough;

pub use bxdfs::*;
pub use interiors::*;
pub use material::*;
pub use rough::*;
