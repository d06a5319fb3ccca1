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
pub mod pattern;
pub mod phase;
pub mod ray;
pub mod ray_marching;
pub mod sampler;
mod simd8;
pub mod spectral_tracking;
pub mod tracking;
pub mod volume_lights;

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
