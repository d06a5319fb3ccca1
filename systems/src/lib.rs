//! risotto systems.

pub mod distribution;
