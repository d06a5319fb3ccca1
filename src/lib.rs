//! risotto: a physically based CPU renderer with first-class volumes.
//!
//! This crate is the one an embedder depends on: it re-exports the workspace's crates under
//! short paths, and [`glam`] and [`bumpalo`] at the versions the contract uses, so a plug-in
//! needs nothing else. The `risotto` command-line driver is the default feature `cli`
//! (clap, indicatif, signal-hook, ...); a library user turns it off. The package is
//! `risotto-renderer` (the crates.io name `risotto` is another project's); its library is
//! `risotto`:
//!
//! ```toml
//! [dependencies]
//! risotto-renderer = { git = "...", default-features = false }
//! ```
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
//! # Quick start
//!
//! Read a scene (a file with [`loader::load::load_scene_file`], or text as here), compile it,
//! render it and write the EXR:
//!
//! ```
//! use risotto::engine::output::write_exr;
//! use risotto::engine::render::{render, RenderOptions};
//! use risotto::loader::load::{scene_from_desc, MaterialRegistry};
//! use risotto::loader::scene_file::parse_scene;
//!
//! let text = r#"
//! [render]
//! width = 32
//! height = 24
//! spp = 4
//!
//! [camera]
//! from = [0, 1, 4]
//! to = [0, 0.5, 0]
//! fov = 40
//!
//! [materials.white]
//! type = "diffuse"
//! reflectance = 0.8
//!
//! [[shapes]]
//! type = "sphere"
//! material = "white"
//! center = [0, 0.5, 0]
//! radius = 0.5
//!
//! [[lights]]
//! type = "environment"
//! radiance = 1
//! "#;
//! // Relative paths in the text resolve against the directory of this (unread) path.
//! let desc = parse_scene(text, std::path::Path::new("quick_start.toml"))?;
//! // Your own material types are registered by name here (`MaterialRegistry::register`).
//! let scene = scene_from_desc(desc, &MaterialRegistry::with_builtins())?.compile()?;
//! let output = render(&scene, &RenderOptions::default(), &|_samples_done| {})?;
//! assert_eq!((output.beauty.width, output.beauty.height), (32, 24));
//! // A white furnace seen around the sphere: the sky is exactly 1.
//! assert_eq!(output.beauty.get(0, 0).to_array(), [1.0; 3]);
//! let path = std::env::temp_dir().join("risotto_quick_start.exr");
//! write_exr(&path, &output.film_output(false))?;
//! # std::fs::remove_file(&path)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! A scene can also be built in code ([`engine::scene::Scene`]), and materials and volume
//! integrators of your own implement [`engine::plugin::BxdfFactory`]: see the README's
//! "Embedding" and the examples (`cargo run --release --example custom_bxdf`).
#[cfg(feature = "denoise")]
pub mod denoise;

pub use bumpalo;
pub use glam;
pub use risotto_builtins as builtins;
pub use risotto_components as components;
pub use risotto_engine as engine;
pub use risotto_loader as loader;
pub use risotto_systems as systems;
pub use risotto_tools as tools;
