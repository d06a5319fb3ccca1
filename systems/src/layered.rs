//! pbrt-v4's layered BxDF (Pharr, Jakob and Humphreys, *Physically Based Rendering*, 4th
//! ed., sec. 14.3 "Layered BxDFs"; after Guo, Hasan and Zhao 2018, "Position-free Monte
//! Carlo simulation for arbitrary layered BSDFs"): a dielectric coat ([`Coat`]) over an
//! opaque base ([`Base`]: diffuse or conductor), with an optional homogeneous slab of unit
//! extinction, thickness `thickness`, single-scattering albedo `albedo` and
//! Henyey-Greenstein `g` between them. Light that refracts into the slab is followed by a
//! random walk between the two interfaces; evaluation, sampling and the density are all
//! *stochastic* estimates, so each takes a random number generator.
//!
//! What is copied is the behaviour of pbrt-v4's `LayeredBxDF<_, _, twoSided = true>` (the
//! coated diffuse and coated conductor are both two-sided): a `wo` below the surface is
//! mirrored above (and `wi` with it); the base never transmits, so the Bxdf only reflects.
//! - [`Layered::eval`]: `n_samples` walks from `wo` with next-event estimation towards a
//!   refracted copy of `wi` at every base bounce and every medium scattering event, each
//!   weighted by the power heuristic against the walk's own sampling (pbrt-v4
//!   `LayeredBxDF::f`), plus the coat's own reflection.
//!   One deliberate difference: when a walk's own bounce (at the base or in the slab)
//!   reaches the light through the coat, its power-heuristic weight uses the density with
//!   which the other strategy (the coat sampled from `wi`) produces that inside direction,
//!   `p_coat(wi -> -w)`; pbrt-v4 uses the coat's density the other way, `p_coat(-w -> wi)`,
//!   a density over a different variable, so its two weights do not sum to one. Measured
//!   with pbrt's weights: `f(wo, wi)` and `f(wi, wo)` differ by 4% (13 standard errors) for
//!   a coat of roughness 0.3 over a diffuse base, and the sampler's weights miss the
//!   evaluation by 15% in a grazing bin; with these both agree within noise (the tests).
//!   Likewise the sampler keeps the ratio `f / pdf` of its walk rather than the two
//!   products, which underflow after about fifty scattering events.
//! - [`Layered::sample`]: one walk from `wo` until it leaves through the coat; its weight
//!   is the walk's throughput (an unbiased estimate of `f cos / pdf` for the path taken), and
//!   its density, which only multiple importance sampling uses, is [`Layered::pdf`]
//!   (pbrt-v4's `pdfIsProportional` samples).
//! - [`Layered::pdf`]: pbrt-v4's approximation: the coat's reflection plus the
//!   transmission-reflection-transmission paths of one base bounce (MIS of two estimates),
//!   mixed with the uniform density `1 / 4pi` at 10% so it is positive everywhere.
//!
//! The walk's transmittance through the slab along `w` over a height `dz` is
//! `exp(-|dz| / |w.z|)` (unit extinction: `thickness` is the optical depth at normal
//! incidence), so with `albedo = 0` the slab still absorbs (pbrt-v4's `Tr`). After depth 3
//! a walk whose throughput falls below 0.25 plays Russian roulette.
//!
//! There is no energy compensation (pbrt-v4 has none: the walk already counts the
//! interreflections a single-scattering model loses).

pub mod interfaces;

pub use interfaces::{Base, Coat, InterfaceSample, SMOOTH_ALPHA};

use crate::bxdf::BxdfSample;
use crate::lights::power_heuristic;
use crate::microfacet::positive;
use crate::phase::{hg_eval, hg_sample};
use crate::rough_dielectric::Lobes;
use crate::sampler::SplitMix64;
use risotto_components::{LobeSampled, Rgb, Vec2, Vec3};
use std::f32::consts::PI;

/// A layered Bxdf's parameters (the base is given per call: its reflectance may vary per
/// point).
#[derive(Clone, Debug, PartialEq)]
pub struct Layered {
    /// The dielectric coat on top.
    pub coat: Coat,
    /// Optical thickness of the slab between coat and base (> 0).
    pub thickness: f32,
    /// Single-scattering albedo of the slab, per channel in [0, 1]; black: the slab only
    /// absorbs.
    pub albedo: Rgb,
    /// Henyey-Greenstein asymmetry of the slab's scattering, in (-1, 1).
    pub g: f32,
    /// Longest walk, in interface or medium events.
    pub max_depth: u32,
    /// Walks per evaluation (and per density estimate).
    pub n_samples: u32,
}

/// One draw in `[0, 1)` (pbrt-v4 clamps to `OneMinusEpsilon`; [`SplitMix64::f32`] never
/// reaches 1).
#[inline]
fn draw(rng: &mut SplitMix64) -> f32 {
    rng.f32()
}

/// Transmittance of the unit-extinction slab over height `dz` along `w` (pbrt-v4's
/// `LayeredBxDF::Tr`).
#[inline]
fn tr(dz: f32, w: Vec3) -> f32 {
    if dz.abs() <= f32::MIN_POSITIVE {
        return 1.0;
    }
    (-(dz / w.z).abs()).exp()
}

/// An exponential distance of unit extinction along `w`, as a height: `-ln(1 - u) |w.z|`.
#[inline]
fn sample_height(u: f32, w: Vec3) -> f32 {
    -(1.0 - u).ln() * w.z.abs()
}

/// The density with which next-event estimation (the coat sampled from the light's side
/// `wi`, transmission only) produces the inside direction `w` (travelling up towards the
/// coat): the other strategy's density in the power heuristic of a walk's own bounce.
#[inline]
fn nee_pdf(coat: &Coat, wi: Vec3, w: Vec3) -> f32 {
    coat.pdf(wi, -w, Lobes::Transmission)
}

impl Layered {
    /// The slab is a medium that scatters (non-black albedo).
    #[inline]
    fn scatters(&self) -> bool {
        !self.albedo.is_black()
    }

    /// Lobes the Bxdf can produce over `base`: always a reflection; a density (`DIFFUSE`)
    /// unless coat, base and slab are all specular; `SPECULAR` when the coat is smooth.
    pub fn lobes(&self, base: &Base<'_>) -> LobeSampled {
        let mut lobes = LobeSampled::REFLECT;
        if self.coat.is_specular() {
            lobes |= LobeSampled::SPECULAR;
        }
        if !(self.coat.is_specular() && base.is_specular() && !self.scatters()) {
            lobes |= LobeSampled::DIFFUSE;
        }
        lobes
    }

    /// `f(wo, wi) |cos theta_i|`, estimated with `n_samples` walks drawing from `rng`
    /// (pbrt-v4's `LayeredBxDF::f`, two-sided). Black for a transmission (`wo` and `wi` on
    /// opposite sides).
    pub fn eval(&self, base: &Base<'_>, wo: Vec3, wi: Vec3, rng: &mut SplitMix64) -> Rgb {
        let (wo, wi) = if wo.z < 0.0 { (-wo, -wi) } else { (wo, wi) };
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return Rgb::BLACK;
        }
        let n = self.n_samples.max(1);
        // The coat's own reflection, counted `n` times to be averaged with the walks.
        let mut f = self.coat.f(wo, wi) * n as f32;
        for _ in 0..n {
            f += self.eval_walk(base, wo, wi, rng);
        }
        f * (wi.z / n as f32)
    }

    /// One walk of [`Layered::eval`] (`wo`, `wi` above): the light arriving along `wi` is
    /// reached by next-event estimation through a refracted copy of `wi` (`wis`), the
    /// walk's own bounces reach it through the coat's `f`, and the two are weighted by the
    /// power heuristic when both exist (pbrt-v4's inner loop with the entrance at the top,
    /// the exit at the top, the base as the non-exit interface).
    fn eval_walk(&self, base: &Base<'_>, wo: Vec3, wi: Vec3, rng: &mut SplitMix64) -> Rgb {
        let coat = &self.coat;
        let mut f = Rgb::BLACK;
        let uc = draw(rng);
        let u = Vec2::new(draw(rng), draw(rng));
        let Some(wos) = coat.sample(wo, uc, u, Lobes::Transmission, false) else {
            return f;
        };
        let uc = draw(rng);
        let u = Vec2::new(draw(rng), draw(rng));
        // The light's side is sampled as importance (pbrt-v4's `!mode`).
        let Some(wis) = coat.sample(wi, uc, u, Lobes::Transmission, true) else {
            return f;
        };
        let exit_z = self.thickness;
        let mut beta = wos.weight();
        let mut z = self.thickness;
        let mut w = wos.wi;
        // f / pdf of the light's refraction, without its cosine (pbrt-v4's wis->f / wis->pdf).
        let wis_f = wis.f * (1.0 / wis.pdf);
        for depth in 0..self.max_depth {
            if depth > 3 && beta.max_channel() < 0.25 {
                let q = (1.0 - beta.max_channel()).max(0.0);
                if draw(rng) < q {
                    break;
                }
                beta *= 1.0 / (1.0 - q);
            }
            if !self.scatters() {
                z = if z == self.thickness {
                    0.0
                } else {
                    self.thickness
                };
                beta *= tr(self.thickness, w);
            } else {
                let dz = sample_height(draw(rng), w);
                let zp = if w.z > 0.0 { z + dz } else { z - dz };
                if 0.0 < zp && zp < self.thickness {
                    // A scattering event: next-event estimation through `wis`...
                    let p_wis = hg_eval(self.g, -w, -wis.wi);
                    let wt = if coat.is_specular() {
                        1.0
                    } else {
                        power_heuristic(wis.pdf, p_wis)
                    };
                    f += beta * self.albedo * wis_f * (p_wis * wt * tr(zp - exit_z, wis.wi));
                    // ...then the phase function's sample, which may leave through the coat.
                    let u = Vec2::new(draw(rng), draw(rng));
                    let (wp, pdf_p) = hg_sample(self.g, -w, u);
                    if !positive(pdf_p) || wp.z == 0.0 {
                        continue;
                    }
                    // HG is sampled exactly: p / pdf = 1.
                    beta *= self.albedo;
                    w = wp;
                    z = zp;
                    if w.z > 0.0 && !coat.is_specular() {
                        let f_exit = coat.f(-w, wi);
                        if !f_exit.is_black() {
                            let wt = power_heuristic(pdf_p, nee_pdf(coat, wi, w));
                            f += beta * f_exit * (tr(zp - exit_z, w) * wt);
                        }
                    }
                    continue;
                }
                z = zp.clamp(0.0, self.thickness);
            }
            if z == exit_z {
                // Back at the coat from inside: the walk continues only by reflecting.
                let uc = draw(rng);
                let u = Vec2::new(draw(rng), draw(rng));
                let Some(bs) = coat.sample(-w, uc, u, Lobes::Reflection, false) else {
                    break;
                };
                beta *= bs.weight();
                w = bs.wi;
            } else {
                // At the base: next-event estimation through `wis`...
                if !base.is_specular() {
                    let wt = if coat.is_specular() {
                        1.0
                    } else {
                        power_heuristic(wis.pdf, base.pdf(-w, -wis.wi))
                    };
                    let f_base = base.f(-w, -wis.wi);
                    f += beta * f_base * wis_f * (wis.wi.z.abs() * wt * tr(self.thickness, wis.wi));
                }
                // ...then the base's sample, towards the coat and through it to `wi`.
                let uc = draw(rng);
                let u = Vec2::new(draw(rng), draw(rng));
                let Some(bs) = base.sample(-w, uc, u) else {
                    break;
                };
                beta *= bs.weight();
                w = bs.wi;
                if !coat.is_specular() {
                    let f_exit = coat.f(-w, wi);
                    if !f_exit.is_black() {
                        let wt = if base.is_specular() {
                            1.0
                        } else {
                            power_heuristic(bs.pdf, nee_pdf(coat, wi, w))
                        };
                        f += beta * f_exit * (tr(self.thickness, bs.wi) * wt);
                    }
                }
            }
        }
        f
    }

    /// Samples a direction from `wo` (pbrt-v4's `LayeredBxDF::Sample_f`, two-sided): the
    /// coat's lobes with `uc` and `u`; a refraction starts a walk drawing from a generator
    /// seeded by `seed` until it leaves through the coat (`None` if it is absorbed, rouletted
    /// or runs past `max_depth`). The weight is the walk's `f cos / pdf`; `pdf` is the
    /// walk's density for a Dirac path (its discrete probability), otherwise
    /// [`Layered::pdf`] estimated with a generator seeded from both directions.
    pub fn sample(
        &self,
        base: &Base<'_>,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        seed: u64,
    ) -> Option<BxdfSample> {
        let flip = if wo.z < 0.0 { -1.0 } else { 1.0 };
        let wo_given = wo;
        let wo = wo * flip;
        if !positive(wo.z) {
            return None;
        }
        let (beta, wi, path_pdf, specular) = self.sample_walk(base, wo, uc, u, seed)?;
        let wi = wi * flip;
        let weight = beta * wi.z.abs();
        if !weight.is_finite() {
            return None;
        }
        let pdf = if specular {
            path_pdf
        } else {
            // The stream an evaluation's density at (wo, wi) draws (`evaluation_rng(wi, wo)`
            // of the engine's contract), so both report the same number.
            let (a, b) = (wi, wo_given);
            let mut rng = SplitMix64(crate::sampler::seed_from(&[a.x, a.y, a.z, b.x, b.y, b.z]));
            self.pdf(base, wo_given, wi, &mut rng)
        };
        let kind = if specular {
            LobeSampled::SPECULAR
        } else {
            LobeSampled::DIFFUSE
        };
        Some(BxdfSample {
            wi,
            weight,
            pdf,
            lobe: LobeSampled::REFLECT | kind,
            eta: 1.0,
        })
    }

    /// The walk of [`Layered::sample`] from `wo` above: `(beta, wi, pdf, specular)` with
    /// `beta` the walk's `f / pdf` without the last cosine (pbrt-v4 keeps the products `f`
    /// and `pdf` apart; their ratio is kept here instead, since after some fifty scattering
    /// events in the slab both underflow an `f32` and the walk would be lost) and `pdf` the
    /// product of the discrete probabilities of a Dirac path.
    fn sample_walk(
        &self,
        base: &Base<'_>,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        seed: u64,
    ) -> Option<(Rgb, Vec3, f32, bool)> {
        let bs = self.coat.sample(wo, uc, u, Lobes::Both, false)?;
        if bs.reflect {
            return Some((bs.f * (1.0 / bs.pdf), bs.wi, bs.pdf, bs.specular));
        }
        let mut rng = SplitMix64(seed);
        let mut w = bs.wi;
        let mut specular = bs.specular;
        let mut beta = bs.weight();
        let mut pdf = bs.pdf;
        let mut z = self.thickness;
        for depth in 0..self.max_depth {
            let rr_beta = beta.max_channel();
            if depth > 3 && rr_beta < 0.25 {
                let q = (1.0 - rr_beta).max(0.0);
                if draw(&mut rng) < q {
                    return None;
                }
                beta *= 1.0 / (1.0 - q);
                pdf *= 1.0 - q;
            }
            if w.z == 0.0 {
                return None;
            }
            if self.scatters() {
                let dz = sample_height(draw(&mut rng), w);
                let zp = if w.z > 0.0 { z + dz } else { z - dz };
                if zp == z {
                    return None;
                }
                if 0.0 < zp && zp < self.thickness {
                    let u = Vec2::new(draw(&mut rng), draw(&mut rng));
                    let (wp, pdf_p) = hg_sample(self.g, -w, u);
                    if !positive(pdf_p) || wp.z == 0.0 {
                        return None;
                    }
                    // HG is sampled exactly: p / pdf = 1.
                    beta *= self.albedo;
                    specular = false;
                    w = wp;
                    z = zp;
                    continue;
                }
                z = zp.clamp(0.0, self.thickness);
            } else {
                z = if z == self.thickness {
                    0.0
                } else {
                    self.thickness
                };
                beta *= tr(self.thickness, w);
            }
            let uc = draw(&mut rng);
            let u = Vec2::new(draw(&mut rng), draw(&mut rng));
            let bs = if z == 0.0 {
                base.sample(-w, uc, u)?
            } else {
                self.coat.sample(-w, uc, u, Lobes::Both, false)?
            };
            pdf *= bs.pdf;
            specular &= bs.specular;
            w = bs.wi;
            if !bs.reflect {
                // Out through the coat.
                return Some((beta * bs.f * (1.0 / bs.pdf), w, pdf, specular));
            }
            beta *= bs.weight();
        }
        None
    }

    /// pbrt-v4's density estimate for `wo`, `wi` (`LayeredBxDF::PDF`, two-sided, the
    /// reflection case; 0 for a transmission): the coat's reflection density plus, per
    /// sample, the transmission-reflection-transmission paths through one base bounce (two
    /// estimates combined by the power heuristic when coat and base both have densities),
    /// mixed as `0.1 / 4pi + 0.9 * estimate`. An approximation of the sampler's density
    /// (it ignores longer walks and the refraction's Jacobians), used for MIS only.
    pub fn pdf(&self, base: &Base<'_>, wo: Vec3, wi: Vec3, rng: &mut SplitMix64) -> f32 {
        let (wo, wi) = if wo.z < 0.0 { (-wo, -wi) } else { (wo, wi) };
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return 0.0;
        }
        let coat = &self.coat;
        let n = self.n_samples.max(1);
        let mut sum = n as f32 * coat.pdf(wo, wi, Lobes::Reflection);
        for _ in 0..n {
            let (uc, u) = (draw(rng), Vec2::new(draw(rng), draw(rng)));
            let wos = coat.sample(wo, uc, u, Lobes::Transmission, false);
            let (uc, u) = (draw(rng), Vec2::new(draw(rng), draw(rng)));
            let wis = coat.sample(wi, uc, u, Lobes::Transmission, true);
            let (Some(wos), Some(wis)) = (wos, wis) else {
                continue;
            };
            if coat.is_specular() {
                sum += base.pdf(-wos.wi, -wis.wi);
                continue;
            }
            let (uc, u) = (draw(rng), Vec2::new(draw(rng), draw(rng)));
            let Some(rs) = base.sample(-wos.wi, uc, u) else {
                continue;
            };
            if base.is_specular() {
                sum += coat.pdf(-rs.wi, wi, Lobes::Both);
            } else {
                let r_pdf = base.pdf(-wos.wi, -wis.wi);
                sum += power_heuristic(wis.pdf, r_pdf) * r_pdf;
                let t_pdf = coat.pdf(-rs.wi, wi, Lobes::Both);
                sum += power_heuristic(rs.pdf, t_pdf) * t_pdf;
            }
        }
        0.1 / (4.0 * PI) + 0.9 * sum / n as f32
    }
}

#[cfg(test)]
mod tests;
