//! risotto: a physically based CPU renderer with first-class volumes.
//!
//! This crate is the `risotto` driver (`risotto render scene.toml`) and re-exports the
//! workspace's crates under short paths:
//!
//! | path | crate | what |
//! | --- | --- | --- |
//! | [`components`] | `risotto-components` | plain data: SoA tables, lobes, colour, volume stack |
//! | [`systems`] | `risotto-systems` | functions over columns: camera, BVH, Bxdf math, trackers, lights, film |
//! | [`engine`] | `risotto-engine` | the plug-in contract, scene world, scheduler, integrators, render, output, stats |
//! | [`builtins`] | `risotto-builtins` | the built-in materials and media, plug-ins like any other |
//! | [`loader`] | `risotto-loader` | scene files, the material registry, grid / mesh / texture readers |
//! | [`tools`] | `risotto-tools` | converge, merge, compare |
//!
//! An embedder who builds scenes in code needs only `risotto-engine` (plus
//! `risotto-builtins` for the built-in materials); see the README's "Embedding".
pub use risotto_builtins as builtins;
pub use risotto_components as components;
pub use risotto_engine as engine;
pub use risotto_loader as loader;
pub use risotto_systems as systems;
pub use risotto_tools as tools;
