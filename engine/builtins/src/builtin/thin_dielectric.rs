//! The thin dielectric closure: a pane of glass with both faces in one surface
//! (`risotto_systems::bxdf::thin_dielectric` has the model).
//!
//! A pane alone bounds no volume: its material computes no interior and does not hint
//! `TRANSMITS`, so the renderer does not track it on the volume stack, and a ray that passes
//! stays in the volumes it was in (the sample's `TRANSMIT` bit says which side it left by;
//! its `eta` is 1). With an interior (Mitsuba's thindielectric around a medium) the closed
//! shape is a boundary like a dielectric's, of index 1: a ray the pane passes enters or
//! leaves the volume, and the pane's own index applies at both faces.
//!
//! Shadow rays are blocked, as by the smooth dielectric and as Mitsuba 3's path tracer does
//! (its emitter samples test occlusion): light through a pane arrives by the straight
//! transmission lobe only. Unless the transmission is a **null event** (Mitsuba 3's
//! volumetric path tracers: its `thindielectric` flags the transmission `Null`, and their
//! shadow rays pass it attenuated by `eval_null_transmission = 1 - R'`): the material is
//! then a surface with opacity `R'(cos)` (`BuiltinMaterial::opacity`) whose Bxdf only
//! reflects, so the renderer's opacity machinery passes path rays with probability `T'`
//! without a bounce, keeping the last vertex's pdf for MIS with light samples, and
//! attenuates shadow rays by `T'`.

use super::bxdfs::{for_sample_chunks, frame};
use glam::{Vec2, Vec3};
use risotto_components::{LobeSampled, Rgb};
use risotto_engine::plugin::*;
use risotto_systems::bxdf;
use risotto_systems::sampler::PathSampler;

/// A thin pane of relative index `ior / ior_outside`: Fresnel reflection with the internal
/// bounces summed, or straight transmission.
#[derive(Clone, Copy, Debug)]
pub struct ThinDielectricBxdf {
    /// Index of refraction of the pane's material.
    pub ior: f32,
    /// Transmission is a null event, decided before shading by the pane's opacity `R'`
    /// (module docs): the path goes on straight through without counting a bounce towards
    /// `max_depth`, as Mitsuba 3's volumetric path tracers treat their `thindielectric`.
    /// A ray that meets the pane then always reflects (weight 1: the choice's probability
    /// `R'` cancels the reflectance). Off, the transmission is a specular bounce like the
    /// reflection.
    pub null_transmission: bool,
}

impl Bxdf for ThinDielectricBxdf {
    fn lobes(&self) -> LobeSampled {
        match self.null_transmission {
            true => LobeSampled::REFLECT | LobeSampled::SPECULAR,
            false => LobeSampled::REFLECT | LobeSampled::TRANSMIT | LobeSampled::SPECULAR,
        }
    }
    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    ) {
        let (nn, vn, ior_out) = (ctx.nn(), ctx.vn(), ctx.ior_outside());
        let null_transmission = self.null_transmission;
        for_sample_chunks(samplers, |i, u| {
            // The pane is symmetric: either side of the shading normal.
            let f = frame(nn[i]);
            let eta = self.ior / ior_out[i].max(1e-6);
            // The opacity choice took the transmission: what meets the pane reflects
            // (`u.x = 0 < R'` picks the reflection, unless R' is 0, when no ray meets it).
            let u = if null_transmission {
                Vec2::new(0.0, u.y)
            } else {
                u
            };
            if let Some(s) = bxdf::thin_dielectric_sample(eta, f.to_local(vn[i]), u) {
                out.set_local(i, &f, s);
            }
        });
    }
    fn evaluate_samples(
        &mut self,
        _ctx: &ShadingContext<'_>,
        _wi: &[Vec3],
        value: &mut [Rgb],
        pdf: &mut [f32],
    ) {
        value.fill(Rgb::BLACK);
        pdf.fill(0.0);
    }
    fn albedo(&self, _ctx: &ShadingContext<'_>, out: &mut [Rgb]) {
        out.fill(Rgb::WHITE);
    }
}
