//! risotto's core engine: the plug-in contract (Bxdf factories, Bxdfs, volume integrators,
//! the integrator context they get, shading contexts and shade groups, technique
//! declarations, diagnostics), the scene world and its compilation, the scheduler and the
//! global integrators (`trait Integrator`, the path tracer), transmission, render, output
//! and stats.
//!
//! The built-in materials and media are plug-ins written against this crate's public API
//! (`risotto-builtins`), exactly as a user's are; scene files are read by `risotto-loader`,
//! and the converge / merge / compare tools are `risotto-tools`.

pub mod bidir;
pub mod context;
pub mod diagnostics;
pub mod expected_panic;
pub mod features;
pub mod global_integrator;
pub mod integrator;
mod interior;
pub mod memory;
pub mod opacity;
pub mod output;
pub mod path_record;
pub mod path_tracer;
pub mod plugin;
pub mod render;
pub mod replay;
pub mod scene;
pub mod scratch_dir;
pub mod shade_groups;
pub mod side_files;
pub mod stats;
pub mod technique;
pub mod transmission;
