//! The thin dielectric closure: a pane of glass with both faces in one surface
//! (`risotto_systems::bxdf::thin_dielectric` has the model).
//!
//! A pane alone bounds no volume: its material computes no interior and does not hint
//! `TRANSMITS`, so the renderer does not track it on the volume stack, and a ray that passes
//! stays in the volumes it was in (the sample's `TRANSMIT` bit says which side it left by;
//! its `eta` is 1). With an interior (Mitsuba's thindielectric around a medium) the closed
//! shape is a boundary like a dielectric's, of index 1: a ray the pane passes enters or
//! leaves the volume, and the pane's own index applies at both faces. Shadow rays are blocked, as by the smooth dielectric and as Mitsuba 3's
//! path tracer does (its emitter samples test occlusion): light through a pane arrives by
//! the straight transmission lobe only.

use super::bxdfs::{for_sample_chunks, frame};
use glam::Vec3;
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
    /// Transmission is a null event (its sample carries [`LobeSampled::PASS`]): the path
    /// goes on straight through without counting a bounce towards `max_depth`, as Mitsuba
    /// 3's volumetric path tracers treat their `thindielectric` (its transmission component
    /// is flagged `Null`). Off, the transmission is a specular bounce like the reflection.
    pub null_transmission: bool,
}

impl Bxdf for ThinDielectricBxdf {
    fn lobes(&self) -> LobeSampled {
        LobeSampled::REFLECT | LobeSampled::TRANSMIT | LobeSampled::SPECULAR
    }
    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    ) {
        let (nn, vn, ior_out) = (ctx.nn(), ctx.vn(), ctx.ior_outside());
        for_sample_chunks(samplers, |i, u| {
            // The pane is symmetric: either side of the shading normal.
            let f = frame(nn[i]);
            let eta = self.ior / ior_out[i].max(1e-6);
            let null_transmission = self.null_transmission;
            if let Some(s) = bxdf::thin_dielectric_sample(eta, f.to_local(vn[i]), u) {
                out.set_local(i, &f, s);
                if null_transmission && s.lobe.is_transmit() {
                    out.lobe[i] = LobeSampled(s.lobe.0 | LobeSampled::PASS.0);
                }
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
