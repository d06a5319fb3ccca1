//! The smooth plastic closure: a Lambertian base under a smooth dielectric coat
//! (`risotto_systems::bxdf::plastic` has the model and its equations).

use super::bxdfs::{for_sample_chunks, frame, Reflectance};
use glam::Vec3;
use risotto_components::{LobeSampled, Rgb};
use risotto_engine::plugin::*;
use risotto_systems::bxdf::{self, PlasticCoat};
use risotto_systems::sampler::PathSampler;

/// Smooth plastic (one-sided: black seen from behind). The base reflectance is one colour
/// (`R = Rgb`, the default) or one per point (`R = &[Rgb]`, a pattern's column), as
/// [`super::DiffuseBxdf`]'s.
#[derive(Clone, Copy, Debug)]
pub struct PlasticBxdf<R = Rgb> {
    /// The coat: relative index, specular colour, internal-scattering model.
    pub coat: PlasticCoat,
    /// The base's (diffuse) reflectance, in [0, 1].
    pub diffuse: R,
}

impl<R: Reflectance> Bxdf for PlasticBxdf<R> {
    fn lobes(&self) -> LobeSampled {
        // The diffuse lobe gets light sampling and MIS; the coat's reflection is Dirac.
        LobeSampled::REFLECT | LobeSampled::DIFFUSE | LobeSampled::SPECULAR
    }
    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    ) {
        let (nn, vn) = (ctx.nn(), ctx.vn());
        for_sample_chunks(samplers, |i, u| {
            let f = frame(nn[i]);
            let wo = f.to_local(vn[i]);
            if let Some(s) = bxdf::plastic_sample(&self.coat, self.diffuse.at(i), wo, u) {
                out.set_local(i, &f, s);
            }
        });
    }
    fn evaluate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        wi: &[Vec3],
        value: &mut [Rgb],
        pdf: &mut [f32],
    ) {
        let (nn, vn) = (ctx.nn(), ctx.vn());
        for i in 0..ctx.num_points() {
            let (cos_o, cos_i) = (nn[i].dot(vn[i]), nn[i].dot(wi[i]));
            (value[i], pdf[i]) = bxdf::plastic_eval(&self.coat, self.diffuse.at(i), cos_o, cos_i);
        }
    }
    fn albedo(&self, ctx: &ShadingContext<'_>, out: &mut [Rgb]) {
        let (nn, vn) = (ctx.nn(), ctx.vn());
        for (i, a) in out.iter_mut().enumerate() {
            *a = bxdf::plastic_albedo(&self.coat, self.diffuse.at(i), nn[i].dot(vn[i]));
        }
    }
}
