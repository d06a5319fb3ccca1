//! risotto's engine: the scene world, scene loading and compilation, the plug-in traits
//! (Bxdf factories, Bxdfs, volume integrators), the scheduler and global integrators, output.

pub mod builtin;
pub mod compare;
pub mod context;
pub mod converge;
pub mod integrator;
pub mod load;
pub mod output;
pub mod plot;
pub mod plugin;
pub mod render;
pub mod scene;
pub mod scene_file;
pub mod stats;
pub mod technique;
pub mod transmission;
