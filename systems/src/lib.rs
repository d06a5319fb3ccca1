//! risotto's systems: plain functions over table columns. Each takes the slices it reads and
//! the slices it writes, knows nothing of the scene world, the scheduler or the global
//! integrator, and can be benchmarked alone.

pub mod adaptive;
pub mod bssrdf;
mod build_prims;
mod bvh2_build;
mod bvh8;
pub mod bxdf;
pub mod bxdf_samples;
pub mod camera;
pub mod clearance;
pub mod conductor;
pub mod direct_lighting;
pub mod distribution;
pub mod energy_compensation;
pub mod environment_map;
pub mod film;
pub mod geometry;
pub mod grid;
pub mod hash_grid;
pub mod independent_sampler;
pub mod intersect;
pub mod layered;
pub mod lights;
mod march;
pub mod medium;
pub mod mesh_attributes;
pub mod microfacet;
pub mod partition;
pub mod path;
pub mod pattern;
pub mod phase;
pub mod pixel_filter;
mod primitive;
pub mod ray;
pub mod ray_marching;
pub mod rough_conductor;
pub mod rough_dielectric;
pub mod rough_plastic;
pub mod roughness_grid;
pub mod sampler;
mod simd8;
pub mod spectral_tracking;
mod splitmix;
pub mod terminator;
pub mod tracking;
mod triangle_mesh;
pub mod volume_lights;
mod warp;

/// Mean and standard error of `n` estimates `f()` (unit tests of the estimators).
#[cfg(test)]
pub(crate) fn mean_se(n: usize, mut f: impl FnMut() -> f32) -> (f64, f64) {
    let (mut s, mut s2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let v = f() as f64;
        s += v;
        s2 += v * v;
    }
    let m = s / n as f64;
    (m, ((s2 / n as f64 - m * m).max(0.0) / n as f64).sqrt())
}

/// Simpson's rule for `int_0^1 f` with `n` (even) intervals, in f64 (the closed forms the
/// estimators' unit tests compare against).
#[cfg(test)]
pub(crate) fn simpson_01(n: usize, f: impl Fn(f64) -> f64) -> f64 {
    let h = 1.0 / n as f64;
    let inner: f64 = (1..n)
        .map(|i| f(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 })
        .sum();
    (f(0.0) + f(1.0) + inner) * h / 3.0
}
