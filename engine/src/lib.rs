//! risotto engine.

pub mod compare;
pub mod output;
pub mod stats;
