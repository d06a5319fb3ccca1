//! risotto systems.

pub mod geometry;
pub mod intersect;
