//! Christensen and Burley's normalized diffusion profile (P. H. Christensen and B. Burley,
//! "Approximate Reflectance Profiles for Efficient Subsurface Scattering", Pixar Technical
//! Memo 15-04, 2015; B. Burley, "Extending the Disney BRDF to a BSDF with Integrated
//! Subsurface Scattering", SIGGRAPH 2015 course notes): the diffuse reflectance of a
//! semi-infinite medium at distance `r` from where light entered,
//!
//! `R(r) = A (e^(-r/d) + e^(-r/(3d))) / (8 pi d r)`,
//!
//! which integrates to the surface albedo `A` over the plane (`int R 2 pi r dr = A`).
//! The shape parameter is `d = l / s(A)` with `l` the volume mean free path and the fit
//! `s(A) = 1.9 - A + 3.5 (A - 0.8)^2` (their "diffuse surface transmission"
//! configuration, for light entering from all directions).
//!
//! `R(r) 2 pi r / A` is the mixture `0.25 Exp(1/d) + 0.75 Exp(1/(3d))` in `r`, sampled
//! exactly: [`sample_radius`] and [`radius_pdf`].

use std::f32::consts::PI;

/// Burley's scaling factor `s(A) = 1.9 - A + 3.5 (A - 0.8)^2`: `d = mean_free_path / s`.
pub fn scaling(albedo: f32) -> f32 {
    let a = albedo.clamp(0.0, 1.0);
    1.9 - a + 3.5 * (a - 0.8) * (a - 0.8)
}

/// `R(r)` for albedo `a` and shape `d` (per unit area, per unit incident power).
pub fn profile(a: f32, d: f32, r: f32) -> f32 {
    if d <= 0.0 || r <= 0.0 {
        return 0.0;
    }
    a * ((-r / d).exp() + (-r / (3.0 * d)).exp()) / (8.0 * PI * d * r)
}

/// Samples `r` from the density `R(r) 2 pi r / A`: with probability 1/4 an exponential of
/// mean `d`, else of mean `3d`. `u_lobe`, `u` in `[0, 1)`.
pub fn sample_radius(d: f32, u_lobe: f32, u: f32) -> f32 {
    let mean = if u_lobe < 0.25 { d } else { 3.0 * d };
    -mean * (1.0 - u.clamp(0.0, 1.0 - f32::EPSILON / 2.0)).ln()
}

/// The density of [`sample_radius`] at `r` (per unit radius).
pub fn radius_pdf(d: f32, r: f32) -> f32 {
    if d <= 0.0 || r < 0.0 {
        return 0.0;
    }
    0.25 * (-r / d).exp() / d + 0.75 * (-r / (3.0 * d)).exp() / (3.0 * d)
}

/// The radius beyond which the profile holds less than 1e-4 of `A`
/// (`0.25 e^(-x) + 0.75 e^(-x/3) = 1e-4` at `x ~ 26.7`): probe rays stay within it.
pub fn max_radius(d: f32) -> f32 {
    26.7 * d
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The profile integrates to A over the plane, the sampler's histogram follows its
    /// pdf, and the pdf is the profile's `2 pi r R / A`.
    #[test]
    fn profile_is_normalized_and_sampled_exactly() {
        let (a, d) = (0.7f32, 0.3f32);
        let (n, rmax) = (200_000, max_radius(d));
        let dr = rmax / n as f32;
        let total: f64 = (0..n)
            .map(|i| {
                let r = (i as f32 + 0.5) * dr;
                (profile(a, d, r) * 2.0 * PI * r * dr) as f64
            })
            .sum();
        assert!((total - a as f64).abs() < 1e-3, "{total}");
        for r in [0.01f32, 0.3, 1.0, 4.0] {
            let want = profile(a, d, r) * 2.0 * PI * r / a;
            assert!(
                (radius_pdf(d, r) - want).abs() < 1e-5 * want.max(1.0),
                "r {r}"
            );
        }
        // Histogram of samples on a 2^-10 grid of (u_lobe, u) against the pdf: a bin's count
        // is off by at most about one step of the u grid per lobe value (1024 counts).
        let bins = 20;
        let width = 2.0 * d / bins as f32 * 3.0;
        let mut hist = vec![0usize; bins];
        let m = 1024;
        for i in 0..m {
            for j in 0..m {
                let r = sample_radius(d, (i as f32 + 0.5) / m as f32, (j as f32 + 0.5) / m as f32);
                let b = (r / width) as usize;
                if b < bins {
                    hist[b] += 1;
                }
            }
        }
        for (b, &count) in hist.iter().enumerate() {
            let r = (b as f32 + 0.5) * width;
            let want = radius_pdf(d, r) * width * (m * m) as f32;
            assert!(
                (count as f32 - want).abs() < 0.01 * want + 2048.0,
                "bin {b}: {count} vs {want}"
            );
        }
    }
}
