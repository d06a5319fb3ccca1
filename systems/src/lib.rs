//! risotto's systems: plain functions over table columns. Each takes the slices it reads and
//! the slices it writes, knows nothing of the scene world, the scheduler or the global
//! integrator, and can be benchmarked alone.

pub mod bssrdf;
mod bvh8;
pub mod bxdf;
pub mod bxdf_samples;
pub mod camera;
pub mod clearance;
pub mod direct_lighting;
pub mod distribution;
pub mod film;
pub mod geometry;
pub mod grid;
pub mod independent_sampler;
pub mod intersect;
pub mod lights;
pub mod medium;
pub mod partition;
pub mod path;
pub mod phase;
pub mod ray;
pub mod sampler;
mod simd8;
pub mod tracking;
