//! Built-in materials (factories), their Bxdf closures, the phase function and the built-in
//! interiors (`null`, `beer`).
//!
//! Scene-file material types: `diffuse`, `dielectric`, `conductor` / `mirror`,
//! `rough_conductor`, `rough_dielectric`, `interface`, `plastic`, `thin_dielectric`,
//! `coated_diffuse`, `coated_conductor` ([`coated`], pbrt-v4's layered materials) (and
//! `two_sided = true` on the one-sided reflectors).
//! Any of them may carry an `interior = { type = "null" | "beer", ... }` table that makes the
//! shape's inside a volume with that integrator (see `docs/scene-format.md`).
//!
//! Any material may be wrapped in an [`OpacityMask`] ([`mask`]): opacity.
//!
//! Files: [`bxdfs`] (the first closures), [`coated`] (the layered closure), [`rough`] (the
//! microfacet closures: rough conductor, dielectric and plastic), [`rough_patterns`] (the
//! same with a roughness or complex-index pattern), [`plastic`],
//! [`thin_dielectric`] and [`two_sided`] (one closure each), [`interiors`] (which volume
//! integrator a material's inside gets, and the `null` and `beer` ones), [`mask`] (opacity)
//! and [`material`] (the factory).
//! Everything is re-exported here.

pub mod bxdfs;
pub mod coated;
pub mod interiors;
pub mod mask;
pub mod material;
pub mod mix;
pub mod plastic;
pub mod rough;
pub mod rough_patterns;
pub mod thin_dielectric;
pub mod two_sided;

pub use bxdfs::*;
pub use coated::{CoatedBase, CoatedBxdf};
pub use interiors::*;
pub use mask::*;
pub use material::*;
pub use mix::{MixAmount, MixBxdf, MixMaterial};
pub use plastic::PlasticBxdf;
pub use rough::*;
pub use rough_patterns::*;
pub use thin_dielectric::ThinDielectricBxdf;
pub use two_sided::TwoSidedBxdf;
