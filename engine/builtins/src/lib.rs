//! risotto's built-in materials, Bxdfs, phase functions and volume integrators: `null`,
//! `beer`, homogeneous, heterogeneous and emissive media, the random walk, diffusion and the
//! `subsurface` material. Every one is a plug-in written against `risotto-engine`'s public
//! API only, exactly as a user's plug-in in its own crate would be (Mitsuba 3's model: a
//! built-in plugin is an ordinary plugin); Cargo enforces it, since this crate sees nothing
//! else of the engine.

pub mod builtin;
pub mod diffusion;
pub mod heterogeneous;
pub mod media;
pub mod phase;
pub mod scatter_patterns;
pub mod subsurface;
