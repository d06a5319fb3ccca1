//! risotto systems.
pub mod bxdf;
