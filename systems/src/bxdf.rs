//! Scattering math for surfaces, one sample at a time (phase functions live in
//! [`crate::phase`]; the Henyey-Greenstein functions are re-exported here for existing callers).
//!
//! The engine wraps these in batch-shaped Bxdf closures; here live the per-sample formulas.
//!
//! # Conventions
//! - Surface functions work in a **local shading frame** whose shading normal is `+z`
//!   ([`Frame`] maps world directions in and out). `+z` is the *outside* of a dielectric.
//! - `wo` points from the shading point back towards where the ray came from (`wo = -d`,
//!   the same as a shading point's `vn`); `wi` is the sampled direction the path continues
//!   along. Both are unit vectors.
//! - A [`BxdfSample::weight`] is `f * |cos theta_i| / pdf`, per channel, dimensionless.
//! - Dirac (specular) lobes report as `pdf` the *discrete probability* of choosing that lobe,
//!   and their weight already includes the lobe's `f * |cos| / pdf`. Evaluating a Dirac lobe
//!   at an arbitrary direction gives zero, so there are no eval functions for them.
//! - Degenerate inputs (grazing `wo` exactly in the surface plane, samples that land on the
//!   horizon) produce `None`, never NaN.

use crate::simd8::{Backend, Kernel8, Lanes8, Row8, Simd};
use risotto_components::{LobeSampled, Rgb, Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4};

// The engine's volume Bxdfs and the chi-square tests reach HG through this module; one
// definition, in `phase`, serves both paths.
pub use crate::phase::{hg_eval, hg_sample, HG_G_MAX};
// The frame and the warps live in `crate::warp`, below both this module and `phase`; these
// are their public paths.
pub use crate::warp::{
    sample_concentric_disk, sample_cosine_hemisphere, sample_uniform_cone, sample_uniform_sphere,
    sample_uniform_triangle, sin_cos_quarter_pi, uniform_cone_pdf, Frame, INV_4PI,
};
use crate::warp::{sin_cos_quarter_pi_with, SIN_COS_POLY};

/// One sampled scattering direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BxdfSample {
    /// Sampled direction, local frame, unit length.
    pub wi: Vec3,
    /// `f * |cos theta_i| / pdf` per channel.
    pub weight: Rgb,
    /// Solid-angle density of `wi`; for a Dirac lobe the discrete probability of having
    /// chosen that lobe.
    pub pdf: f32,
    /// `REFLECT` or `TRANSMIT`, plus `DIFFUSE` or `SPECULAR`.
    pub lobe: LobeSampled,
    /// Relative index of refraction crossed, `eta_transmitted / eta_incident`; 1 when the
    /// sample did not cross an interface.
    pub eta: f32,
}

// ---------------------------------------------------------------------------------------
// Lambertian
// ---------------------------------------------------------------------------------------

const DIFFUSE_REFLECT: LobeSampled = LobeSampled(LobeSampled::REFLECT.0 | LobeSampled::DIFFUSE.0);
const SPECULAR_REFLECT: LobeSampled = LobeSampled(LobeSampled::REFLECT.0 | LobeSampled::SPECULAR.0);
const SPECULAR_TRANSMIT: LobeSampled =
    LobeSampled(LobeSampled::TRANSMIT.0 | LobeSampled::SPECULAR.0);

/// Strictly above the surface (`cos > 0`); false for NaN, so NaN input yields no sample.
#[inline]
fn above(cos: f32) -> bool {
    cos > 0.0
}

/// A usable relative index of refraction: positive and finite (false for NaN).
#[inline]
fn valid_eta(eta: f32) -> bool {
    eta > 0.0 && eta.is_finite()
}

/// Samples the one-sided Lambertian lobe `f = reflectance / pi` by cosine-weighted
/// hemisphere sampling, so `weight = reflectance` exactly. `None` when `wo` is at or below
/// the surface (the lobe is zero there) or the sample lands on the horizon.
#[inline]
pub fn diffuse_sample(reflectance: Rgb, wo: Vec3, u: Vec2) -> Option<BxdfSample> {
    if !above(wo.z) {
        return None;
    }
    let wi = sample_cosine_hemisphere(u);
    if !above(wi.z) {
        return None;
    }
    Some(BxdfSample {
        wi,
        weight: reflectance,
        pdf: wi.z * FRAC_1_PI,
        lobe: DIFFUSE_REFLECT,
        eta: 1.0,
    })
}

/// [`diffuse_sample`] for a column of points, with the directions turned to world space:
/// for point `i` with unit shading normal `n[i]`, unit direction towards the viewer
/// `vn[i]` and sample `u[i]`, writes `wi[i]` and `pdf[i]` (0 where `diffuse_sample` returns
/// `None`; `wi[i]` is then `+z`). The weight of every sample is the reflectance.
///
/// Bit for bit `Frame::from_normal(n).to_world(diffuse_sample(_, frame.to_local(vn), u).wi)`
/// and its pdf (tested): the same float operations in the same order, evaluated for eight
/// points at once (`simd8` lanes), with the concentric map's two wedges as selects
/// (so both share one division and one polynomial) and no branch per point.
///
/// # Panics
/// When the columns differ in length.
pub fn diffuse_sample_world(n: &[Vec3], vn: &[Vec3], u: &[Vec2], wi: &mut [Vec3], pdf: &mut [f32]) {
    diffuse_sample_world_on(Backend::best(), n, vn, u, wi, pdf);
}

/// [`diffuse_sample_world`] on the lanes of `backend`.
fn diffuse_sample_world_on(
    backend: Backend,
    n: &[Vec3],
    vn: &[Vec3],
    u: &[Vec2],
    wi: &mut [Vec3],
    pdf: &mut [f32],
) {
    let len = n.len();
    assert!(
        vn.len() == len && u.len() == len && wi.len() == len && pdf.len() == len,
        "diffuse_sample_world: column lengths"
    );
    backend.run(DiffuseWorld { n, vn, u, wi, pdf });
}

/// The scalar reference of [`diffuse_sample_world`], point by point.
#[cfg(test)]
fn diffuse_sample_world_scalar(
    n: &[Vec3],
    vn: &[Vec3],
    u: &[Vec2],
    wi: &mut [Vec3],
    pdf: &mut [f32],
) {
    for i in 0..n.len() {
        let f = Frame::from_normal(n[i]);
        (wi[i], pdf[i]) = match diffuse_sample(Rgb::WHITE, f.to_local(vn[i]), u[i]) {
            Some(s) => (f.to_world(s.wi), s.pdf),
            None => (Vec3::Z, 0.0),
        };
    }
}

/// The columns of [`diffuse_sample_world`] (equally long), as a [`Kernel8`].
struct DiffuseWorld<'a> {
    n: &'a [Vec3],
    vn: &'a [Vec3],
    u: &'a [Vec2],
    wi: &'a mut [Vec3],
    pdf: &'a mut [f32],
}

impl Kernel8 for DiffuseWorld<'_> {
    type Output = ();
    #[inline(always)]
    fn run<S: Simd>(self, s: S) {
        let (n8, n_rest) = self.n.as_chunks::<8>();
        let (vn8, vn_rest) = self.vn.as_chunks::<8>();
        let (u8, u_rest) = self.u.as_chunks::<8>();
        let (wi8, wi_rest) = self.wi.as_chunks_mut::<8>();
        let (pdf8, pdf_rest) = self.pdf.as_chunks_mut::<8>();
        for ((((n, vn), u), wi), pdf) in n8.iter().zip(vn8).zip(u8).zip(wi8).zip(pdf8) {
            diffuse_sample_eight(s, n, vn, u, wi, pdf);
        }
        if !n_rest.is_empty() {
            // The last partial block, padded with a point that has no sample (seen from
            // below). Element loops rather than `copy_from_slice`: a `memcpy` call of a
            // varying small length mispredicts inside.
            let (mut n, mut vn, mut u) = ([Vec3::Z; 8], [Vec3::NEG_Z; 8], [Vec2::ZERO; 8]);
            for (j, ((&nr, &vr), &ur)) in n_rest.iter().zip(vn_rest).zip(u_rest).enumerate() {
                (n[j], vn[j], u[j]) = (nr, vr, ur);
            }
            let (mut wi, mut pdf) = ([Vec3::Z; 8], [0.0; 8]);
            diffuse_sample_eight(s, &n, &vn, &u, &mut wi, &mut pdf);
            for (j, (w, p)) in wi_rest.iter_mut().zip(pdf_rest).enumerate() {
                (*w, *p) = (wi[j], pdf[j]);
            }
        }
    }
}

/// Eight points of [`diffuse_sample_world`] on the lanes of `s`: operation for operation
/// [`Frame::from_normal`], [`diffuse_sample`] (the wedge and centre tests as selects) and
/// [`Frame::to_world`], no fused multiply-add, so the bits of the scalar code.
#[inline(always)]
fn diffuse_sample_eight<S: Simd>(
    s: S,
    n: &[Vec3; 8],
    vn: &[Vec3; 8],
    u: &[Vec2; 8],
    wi: &mut [Vec3; 8],
    pdf: &mut [f32; 8],
) {
    let [nx, ny, nz] = s.load_xyz(n);
    let [vx, vy, vz] = s.load_xyz(vn);
    // Frame::to_local(vn).z, the only local coordinate of wo the lobe needs (Vec3::dot:
    // (x x' + y y') + z z').
    let cos_o = vx * nx + vy * ny + vz * nz;
    let ux = s.load(&Row8(u.map(|u| u.x)));
    let uy = s.load(&Row8(u.map(|u| u.y)));
    let (zero, one, two) = (s.splat(0.0), s.splat(1.0), s.splat(2.0));
    // sample_concentric_disk, the wedge test as a select.
    let px = two * ux - one;
    let py = two * uy - one;
    let wedge_x = px.abs().gt(py.abs());
    let big = S::F::select(wedge_x, px, py);
    let small = S::F::select(wedge_x, py, px);
    // The coefficients splatted one by one: no closure, whose body would be compiled
    // without the kernel's target features.
    let k = SIN_COS_POLY;
    let k = [
        s.splat(k[0]),
        s.splat(k[1]),
        s.splat(k[2]),
        s.splat(k[3]),
        s.splat(k[4]),
        s.splat(k[5]),
        s.splat(k[6]),
        s.splat(k[7]),
    ];
    let (sin, cos) = sin_cos_quarter_pi_with(s.splat(FRAC_PI_4) * (small / big), k);
    let centre = px.eq(zero) & py.eq(zero);
    let dx = S::F::select(centre, zero, big * S::F::select(wedge_x, cos, sin));
    let dy = S::F::select(centre, zero, big * S::F::select(wedge_x, sin, cos));
    // sample_cosine_hemisphere: 1 - |d|^2 is never -0 or NaN here, so a compare-select is
    // the same value as f32::max(0).
    let r2 = one - (dx * dx + dy * dy);
    let lz = S::F::select(r2.gt(zero), r2, zero).sqrt();
    // Frame::from_normal and Frame::to_world, term for term.
    let sign = one.copysign(nz);
    let a = s.splat(-1.0) / (sign + nz);
    let b = nx * ny * a;
    let (sx, sy, sz) = (one + sign * nx * nx * a, sign * b, sign.neg() * nx);
    let (tx, ty, tz) = (b, sign + ny * ny * a, ny.neg());
    let ok = cos_o.gt(zero) & lz.gt(zero);
    let x = S::F::select(ok, sx * dx + tx * dy + nx * lz, zero).to_array();
    let y = S::F::select(ok, sy * dx + ty * dy + ny * lz, zero).to_array();
    let z = S::F::select(ok, sz * dx + tz * dy + nz * lz, one).to_array();
    *pdf = S::F::select(ok, lz * s.splat(FRAC_1_PI), zero).to_array();
    for j in 0..8 {
        wi[j] = Vec3::new(x[j], y[j], z[j]);
    }
}

/// Evaluates the one-sided Lambertian lobe: `(f * |cos theta_i|, pdf)` with
/// `f = reflectance / pi` and the cosine-hemisphere pdf; zero when either direction is at
/// or below the surface.
pub fn diffuse_eval(reflectance: Rgb, wo: Vec3, wi: Vec3) -> (Rgb, f32) {
    diffuse_eval_cos(reflectance, wo.z, wi.z)
}

/// [`diffuse_eval`] from the cosines alone (`cos_o = n . wo`, `cos_i = n . wi`): the
/// Lambertian lobe needs no tangent frame, so callers with world-space directions can skip
/// building one.
#[inline]
pub fn diffuse_eval_cos(reflectance: Rgb, cos_o: f32, cos_i: f32) -> (Rgb, f32) {
    if !(above(cos_o) && above(cos_i)) {
        return (Rgb::BLACK, 0.0);
    }
    let pdf = cos_i * FRAC_1_PI;
    (reflectance * pdf, pdf)
}

// ---------------------------------------------------------------------------------------
// Fresnel and the smooth dielectric
// ---------------------------------------------------------------------------------------

/// Result of solving Snell's law plus the Fresnel equations at one interface.
struct FresnelTerms {
    /// `R_s` (perpendicular) reflectance.
    rs: f32,
    /// `R_p` (parallel) reflectance.
    rp: f32,
    /// `cos theta_t >= 0` (0 under total internal reflection).
    cos_t: f32,
    /// `eta_t / eta_i` for the side the light arrives from.
    eta_rel: f32,
    /// Total internal reflection: no transmitted direction exists.
    tir: bool,
}

/// Fresnel equations for a dielectric interface (Born & Wolf, "Principles of Optics",
/// sec. 1.5.2). `cos_i < 0` means arriving from the inside: the ratio flips to `1/eta`.
fn fresnel_terms(cos_i: f32, eta: f32) -> FresnelTerms {
    let cos_i = cos_i.clamp(-1.0, 1.0);
    let (cos_i, eta) = if cos_i < 0.0 {
        (-cos_i, 1.0 / eta)
    } else {
        (cos_i, eta)
    };
    if eta == 1.0 {
        // Index matched: no interface at all (and the general formulas are 0/0 at grazing).
        return FresnelTerms {
            rs: 0.0,
            rp: 0.0,
            cos_t: cos_i,
            eta_rel: 1.0,
            tir: false,
        };
    }
    // Snell: sin_t = sin_i / eta. (1 - c)(1 + c) keeps precision at normal incidence.
    let sin2_t = (1.0 - cos_i) * (1.0 + cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return FresnelTerms {
            rs: 1.0,
            rp: 1.0,
            cos_t: 0.0,
            eta_rel: eta,
            tir: true,
        };
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    // Amplitude coefficients with eta = n_t / n_i (divide the textbook forms by n_i):
    // r_s = (n_i cos_i - n_t cos_t) / (n_i cos_i + n_t cos_t),
    // r_p = (n_t cos_i - n_i cos_t) / (n_t cos_i + n_i cos_t).
    // A denominator is zero only when cos_i = cos_t = 0, i.e. eta = 1 at exactly grazing
    // incidence; an index-matched interface does not reflect, so report 0 there.
    let ds = cos_i + eta * cos_t;
    let dp = eta * cos_i + cos_t;
    let rs_amp = if ds > 0.0 {
        (cos_i - eta * cos_t) / ds
    } else {
        0.0
    };
    let rp_amp = if dp > 0.0 {
        (eta * cos_i - cos_t) / dp
    } else {
        0.0
    };
    FresnelTerms {
        rs: (rs_amp * rs_amp).min(1.0),
        rp: (rp_amp * rp_amp).min(1.0),
        cos_t,
        eta_rel: eta,
        tir: false,
    }
}

/// Unpolarized Fresnel reflectance `(R_s + R_p) / 2` of a smooth dielectric interface.
///
/// `cos_theta_i` is the cosine between the incident direction (pointing away from the
/// surface) and the normal; `eta = n_inside / n_outside`. A negative cosine means the light
/// arrives from the inside and the ratio becomes `1 / eta`. Returns 1 under total internal
/// reflection. The transmittance is `1 - R` (energy conservation of the interface).
pub fn fresnel_dielectric(cos_theta_i: f32, eta: f32) -> f32 {
    let f = fresnel_terms(cos_theta_i, eta);
    0.5 * (f.rs + f.rp)
}

/// The two polarized Fresnel reflectances `(R_s, R_p)` (perpendicular, parallel) with the
/// same conventions as [`fresnel_dielectric`]. `R_p` vanishes at Brewster's angle.
pub fn fresnel_dielectric_polarized(cos_theta_i: f32, eta: f32) -> (f32, f32) {
    let f = fresnel_terms(cos_theta_i, eta);
    (f.rs, f.rp)
}

/// Mirror reflection of a local direction about `+z`.
#[inline]
pub fn reflect_local(wo: Vec3) -> Vec3 {
    Vec3::new(-wo.x, -wo.y, wo.z)
}

/// Refraction of a local direction through the `z = 0` interface with
/// `eta = n_inside / n_outside` (`+z` is outside). `wo` may be on either side; the result
/// is on the other side. Returns `(wi, eta_rel)` with `eta_rel = n_t / n_i` for this
/// crossing, or `None` under total internal reflection or for `wo` in the plane.
pub fn refract_local(wo: Vec3, eta: f32) -> Option<(Vec3, f32)> {
    if wo.z == 0.0 || !valid_eta(eta) {
        return None;
    }
    let f = fresnel_terms(wo.z, eta);
    if f.tir {
        return None;
    }
    Some((refract_with(wo, f.cos_t, f.eta_rel), f.eta_rel))
}

/// Snell's law in vector form (pbrt-v4 sec. 9.3.2): the tangential part scales by
/// `1/eta_rel`, the normal part is `cos_t` on the far side of the interface.
#[inline]
fn refract_with(wo: Vec3, cos_t: f32, eta_rel: f32) -> Vec3 {
    let z = if wo.z > 0.0 { -cos_t } else { cos_t };
    Vec3::new(-wo.x / eta_rel, -wo.y / eta_rel, z)
}

/// Samples a smooth dielectric interface (`eta = n_inside / n_outside`, `+z` outside).
///
/// Chooses reflection with probability `R` (exact unpolarized Fresnel, `u.x < R`) and
/// refraction otherwise, so each Dirac lobe's weight is `f |cos| / pdf`:
/// - reflection: `pdf = R`, weight 1;
/// - refraction: `pdf = T = 1 - R`, weight `tint / eta_rel^2`. The `1/eta_rel^2` is the
///   radiance (not importance) transport factor: radiance is compressed by `(n_t/n_i)^2`
///   crossing into a denser medium (pbrt-v4 sec. 9.5.2, Veach thesis sec. 5.2).
///
/// So `E[weight] = R + T * tint / eta_rel^2`. `wo` may be on either side; under total
/// internal reflection `R = 1`. `None` for `wo` in the surface plane or an invalid `eta`.
pub fn dielectric_sample(eta: f32, tint: Rgb, wo: Vec3, u: Vec2) -> Option<BxdfSample> {
    if wo.z == 0.0 || !wo.z.is_finite() || !valid_eta(eta) {
        return None;
    }
    let f = fresnel_terms(wo.z, eta);
    let r = 0.5 * (f.rs + f.rp);
    // `f.tir` also covers u.x = 1 (outside [0, 1)) under total internal reflection.
    if u.x < r || f.tir {
        Some(BxdfSample {
            wi: reflect_local(wo),
            weight: Rgb::WHITE,
            pdf: r,
            lobe: SPECULAR_REFLECT,
            eta: 1.0,
        })
    } else {
        let inv_eta = 1.0 / f.eta_rel;
        Some(BxdfSample {
            wi: refract_with(wo, f.cos_t, f.eta_rel),
            weight: tint * (inv_eta * inv_eta),
            pdf: 1.0 - r,
            lobe: SPECULAR_TRANSMIT,
            eta: f.eta_rel,
        })
    }
}

/// Perfect specular reflection weighted by `reflectance` (a mirror or a smooth conductor
/// whose colour the caller already computed). One-sided like [`diffuse_sample`]: `None`
/// when `wo` is at or below the surface.
pub fn mirror_sample(reflectance: Rgb, wo: Vec3) -> Option<BxdfSample> {
    if !above(wo.z) {
        return None;
    }
    Some(BxdfSample {
        wi: reflect_local(wo),
        weight: reflectance,
        pdf: 1.0,
        lobe: SPECULAR_REFLECT,
        eta: 1.0,
    })
}

pub mod plastic;
pub mod thin_dielectric;
pub use plastic::{
    fresnel_diffuse_reflectance, plastic_albedo, plastic_eval, plastic_sample, PlasticCoat,
};
pub use thin_dielectric::{thin_dielectric_reflectance, thin_dielectric_sample};

#[cfg(test)]
mod tests;
