//! Christensen and Burley's normalized diffusion profile (P. H. Christensen and B. Burley,
//! "Approximate Reflectance Profiles for Efficient Subsurface Scattering", Pixar Technical
//! Memo 15-04, 2015; B. Burley, "Extending the Disney BRDF to a BSDF with Integrated
//! Subsurface Scattering", SIGGRAPH 2015 course notes): the diffuse reflectance of a
//! semi-infinite medium at distance `r` from where light entered,
//!
//! `R(r) = A (e^(-r/d) + e^(-r/(3d))) / (8 pi d r)`,
//!
//! which integrates to the surface albedo `A` over the plane (`int R 2 pi r dr = A`).
//!
//! # Which fit of the shape `d`
//! The memo fits the shape `d = l / s(A)` to brute-force Monte Carlo particle tracing of
//! the volume (all orders of scattering), for three parameterizations:
//! - the mean free path `l` with perpendicular (searchlight) illumination:
//!   `s = 1.85 - A + 7 |A - 0.8|^3`;
//! - the mean free path `l` with **diffuse surface transmission** (light entering from all
//!   directions, so that the illumination direction does not matter):
//!   `s = 1.9 - A + 3.5 (A - 0.8)^2`;
//! - the *diffuse* mean free path `l_d` instead of `l`: `s = 3.5 + 100 (A - 0.33)^4`
//!   (the memo's eq. 8).
//!
//! Here `mean_free_path` is the volume mean free path `1 / sigma_t` (the walk uses it as
//! such) and the profile is used for light refracted in from every direction, so
//! [`scaling`] is the diffuse-surface-transmission fit; the dmfp fit would need the
//! artist's length to be a diffuse mean free path, which it is not.
//!
//! # Single scattering
//! The Monte Carlo references the fits were made to include single scattering, so the
//! profile carries it: Christensen's SIGGRAPH 2015 talk ("An Approximate Reflectance Profile
//! for Efficient Subsurface Scattering") lists a "built-in single-scattering term" among the
//! model's advantages, and the sharp `e^(-r/d)` lobe near `r = 0` is where it sits. No
//! separate single-scattering lobe is added: it would count that light twice. The talk
//! gives the fit's accuracy as an average relative error of 5.3 % against the references
//! over the full range of albedos (for the searchlight fit); the test
//! `diffusion_matches_the_walk_on_a_thick_ball` (`tests/subsurface.rs`) holds the
//! rendered reflectance of a thick ball to 3 % of the random walk's, within that figure,
//! and the unit test `profile_is_normalized_and_sampled_exactly` checks that the profile
//! integrates to `A`.
//!
//! `R(r) 2 pi r / A` is the mixture `0.25 Exp(1/d) + 0.75 Exp(1/(3d))` in `r`, sampled
//! exactly: [`sample_radius`] and [`radius_pdf`].
//!
//! [`slab_reflectance_transmittance`] is the Kubelka-Munk split the diffusion mode uses on
//! objects thinner than the profile's reach.

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

/// Kubelka and Munk's reflectance and transmittance of a layer of scattering thickness
/// `s_x = S X` (the two-flux scattering coefficient `S` times the thickness `X`) over a
/// black background, for diffuse light, with the absorption ratio `K / S` chosen so that
/// the infinitely thick layer reflects `a`: `R_inf = a` (P. Kubelka, "New Contributions to
/// the Optics of Intensely Light-Scattering Materials. Part I", JOSA 38, 1948, eqs. 2a-2b
/// and the hyperbolic solution there):
///
/// `R = sinh(b S X) / (a' sinh(b S X) + b cosh(b S X))`,
/// `T = b / (a' sinh(b S X) + b cosh(b S X))`,
///
/// with `a' = 1 + K / S = (1 + a^2) / (2 a)` and `b = sqrt(a'^2 - 1) = (1 - a^2) / (2 a)`
/// (so that `a' - b = R_inf = a`). Limits: `s_x -> inf` gives `(a, 0)`, `s_x = 0` gives
/// `(0, 1)`, and `a = 1` (no absorption) gives `R = S X / (1 + S X)`, `R + T = 1`. Returns
/// `(R, T)`; `a = 0` (infinite absorption for the fixed `R_inf`) gives `(0, 0)` for any
/// positive thickness.
pub fn slab_reflectance_transmittance(a: f32, s_x: f32) -> (f32, f32) {
    let (a, x) = (a.clamp(0.0, 1.0) as f64, s_x.max(0.0) as f64);
    if x == 0.0 {
        return (0.0, 1.0);
    }
    if a == 0.0 {
        return (0.0, 0.0);
    }
    let ap = (1.0 + a * a) / (2.0 * a);
    let b = (1.0 - a * a) / (2.0 * a);
    let y = b * x;
    let (r, t) = if y < 1e-3 {
        // sinh(y) / b and cosh(y) by their series: exact at b = 0 (no absorption).
        let sh = x * (1.0 + y * y / 6.0);
        let ch = 1.0 + y * y / 2.0;
        let den = ap * sh + ch;
        (sh / den, 1.0 / den)
    } else {
        // Divided through by e^y / 2, which cannot overflow for thick layers.
        let e = (-2.0 * y).exp();
        let den = ap * (1.0 - e) + b * (1.0 + e);
        ((1.0 - e) / den, 2.0 * b * (-y).exp() / den)
    };
    (r as f32, t as f32)
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

    /// The two-flux equations `di/dx = -(K + S) i + S j`, `dj/dx = (K + S) j - S i` (down
    /// and up fluxes) on `[0, X]` with `i(0) = 1`, `j(X) = 0`, integrated numerically
    /// (RK4 from `x = X` back to 0 with `(i, j) = (1, 0)`, then scaled: the equations are
    /// linear): `R = j(0) / i(0)`, `T = 1 / i(0)`.
    fn two_flux(k: f64, s: f64, x: f64) -> (f64, f64) {
        let n = 20_000;
        let h = -x / n as f64;
        let f = |i: f64, j: f64| (-(k + s) * i + s * j, (k + s) * j - s * i);
        let (mut i, mut j) = (1.0f64, 0.0f64);
        for _ in 0..n {
            let (a1, b1) = f(i, j);
            let (a2, b2) = f(i + 0.5 * h * a1, j + 0.5 * h * b1);
            let (a3, b3) = f(i + 0.5 * h * a2, j + 0.5 * h * b2);
            let (a4, b4) = f(i + h * a3, j + h * b3);
            i += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
            j += h / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4);
        }
        (j / i, 1.0 / i)
    }

    /// The closed form against the two-flux equations it solves (absorbing and not, thin
    /// and thick, either side of the series branch), and its limits: a thick layer reflects
    /// `a` and transmits nothing, an empty one transmits everything, no absorption
    /// conserves energy, and `R + T <= 1`.
    #[test]
    fn slab_split_solves_the_two_flux_equations() {
        for a in [0.05f32, 0.3, 0.8, 0.95, 0.999_99, 1.0] {
            let ks = (1.0 - a as f64).powi(2) / (2.0 * a as f64);
            for sx in [1e-4f32, 0.01, 0.3, 1.0, 4.0, 20.0] {
                let (r, t) = slab_reflectance_transmittance(a, sx);
                let (rw, tw) = two_flux(ks, 1.0, sx as f64);
                let what = format!("a {a} sx {sx}: ({r}, {t}) vs ({rw}, {tw})");
                assert!((r as f64 - rw).abs() < 1e-5, "{what}");
                assert!((t as f64 - tw).abs() < 1e-5, "{what}");
                assert!(r + t <= 1.0 + 1e-6, "{what}");
                if a == 1.0 {
                    assert!((r + t - 1.0).abs() < 1e-6, "{what}");
                }
            }
            let (r, t) = slab_reflectance_transmittance(a, 1e7);
            assert!((r - a).abs() < 1e-5 && t < 1e-5, "thick a {a}: ({r}, {t})");
            assert_eq!(slab_reflectance_transmittance(a, 0.0), (0.0, 1.0));
        }
    }
}
