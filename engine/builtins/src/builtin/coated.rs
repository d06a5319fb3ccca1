//! pbrt-v4's coated materials, `coated_diffuse` and `coated_conductor`: the layered Bxdf of
//! [`risotto_systems::layered`] (a dielectric coat over a diffuse or conductor base, a slab
//! between them) as a closure. Two-sided, as pbrt-v4's (`TwoSided = true`): seen from
//! behind the shading normal the layers are mirrored. Its value and density are stochastic;
//! the evaluation draws from [`evaluation_rng`] (per point and direction pair, so
//! reproducible), the sampler from a generator seeded by its own sample.

use super::bxdfs::Reflectance;
use super::rough::{evaluate, generate};
use glam::Vec3;
use risotto_components::{LobeSampled, Rgb};
use risotto_engine::plugin::*;
use risotto_systems::layered::{Base, Layered};
use risotto_systems::rough_conductor::RoughConductor;
use risotto_systems::sampler::{seed_from, PathSampler};

/// The base of a coated material, as the material holds it.
#[derive(Clone, Debug, PartialEq)]
pub enum CoatedBase {
    /// Lambertian (pbrt-v4's `coateddiffuse`); its reflectance is given per closure.
    Diffuse,
    /// A smooth conductor (`coatedconductor` with conductor roughness 0): complex index
    /// relative to the coat.
    SmoothConductor {
        /// Real part per channel.
        eta: Rgb,
        /// Imaginary part per channel.
        k: Rgb,
    },
    /// A GGX conductor, its index relative to the coat (no energy compensation).
    RoughConductor(RoughConductor),
}

/// The coated closure over `layered` and `base`; `reflectance` is the diffuse base's
/// reflectance (one colour or a pattern's column; unused by a conductor base).
#[derive(Clone, Copy, Debug)]
pub struct CoatedBxdf<'a, R = Rgb> {
    /// Coat, slab and walk parameters.
    pub layered: &'a Layered,
    /// The base.
    pub base: &'a CoatedBase,
    /// The diffuse base's reflectance, in [0, 1].
    pub reflectance: R,
}

impl<R: Reflectance> CoatedBxdf<'_, R> {
    /// The base at point `i`.
    #[inline]
    fn base_at(&self, i: usize) -> Base<'_> {
        match self.base {
            CoatedBase::Diffuse => Base::Diffuse(self.reflectance.at(i)),
            &CoatedBase::SmoothConductor { eta, k } => Base::SmoothConductor { eta, k },
            CoatedBase::RoughConductor(c) => Base::RoughConductor(c),
        }
    }
}

impl<R: Reflectance> Bxdf for CoatedBxdf<'_, R> {
    fn lobes(&self) -> LobeSampled {
        // The lobes do not depend on the reflectance's value.
        self.layered.lobes(&self.base_at_any())
    }
    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    ) {
        generate(ctx, samplers, out, |i, wo, u, uc| {
            // The walk's generator is seeded by this sample (pbrt-v4: `Hash(wo)`,
            // `Hash(uc, u)`), so its numbers follow the sampler's.
            let seed = seed_from(&[wo.x, wo.y, wo.z, uc, u.x, u.y]);
            self.layered.sample(&self.base_at(i), wo, uc, u, seed)
        });
    }
    fn evaluate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        wi: &[Vec3],
        value: &mut [Rgb],
        pdf: &mut [f32],
    ) {
        evaluate(ctx, wi, value, pdf, |i, wo, wi| {
            let base = self.base_at(i);
            let f = self
                .layered
                .eval(&base, wo, wi, &mut evaluation_rng(wo, wi));
            // The density's stream: the pair swapped, what `Layered::sample` uses too, so a
            // sample's pdf and this one agree exactly.
            let p = self.layered.pdf(&base, wo, wi, &mut evaluation_rng(wi, wo));
            (f, p)
        });
    }
    fn albedo(&self, _ctx: &ShadingContext<'_>, out: &mut [Rgb]) {
        for (i, a) in out.iter_mut().enumerate() {
            *a = match self.base {
                CoatedBase::Diffuse => self.reflectance.at(i),
                CoatedBase::SmoothConductor { eta, k } => {
                    risotto_systems::conductor::fresnel_conductor_rgb(1.0, *eta, *k)
                }
                CoatedBase::RoughConductor(c) => c.normal_reflectance(),
            };
        }
    }
}

impl<R: Reflectance> CoatedBxdf<'_, R> {
    /// A base of the right kind for [`Bxdf::lobes`] (grey for the diffuse one).
    fn base_at_any(&self) -> Base<'_> {
        match self.base {
            CoatedBase::Diffuse => Base::Diffuse(Rgb::splat(0.5)),
            _ => self.base_at(0),
        }
    }
}
