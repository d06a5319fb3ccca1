//! risotto engine.

pub mod scene_file;
