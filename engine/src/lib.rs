//! risotto's engine: the scene world, scene loading and compilation, the plug-in traits
//! (Bxdf factories, Bxdfs, volume integrators), the scheduler and global integrators, output.

pub mod builtin;
pub mod compare;
pub mod context;
pub mod converge;
pub mod diagnostics;
pub mod diffusion;
pub mod grid_file;
pub mod heterogeneous;
pub mod homogeneous_emission;
pub mod integrator;
mod interior;
pub mod load;
pub mod media;
pub mod merge;
pub mod output;
pub mod path_tracer;
pub mod plot;
pub mod plugin;
pub mod random_walk;
pub mod render;
pub mod replay;
pub mod scatter_patterns;
pub mod scene;
pub mod scene_file;
#[cfg(test)]
mod scratch_dir;
pub mod shade_groups;
pub mod shading_context;
pub mod stats;
pub mod subsurface;
pub mod technique;
pub mod texture_file;
pub mod transmission;
pub mod vdb_file;
pub mod volume_lights;
