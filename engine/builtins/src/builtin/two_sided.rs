//! The two-sided wrapper (Mitsuba 3's `twosided`): a one-sided reflection closure shaded on
//! whichever side the viewer is.

use glam::Vec3;
use risotto_components::{LobeSampled, Rgb};
use risotto_engine::plugin::*;
use risotto_systems::sampler::PathSampler;

/// The shading normals of `ctx`'s points turned to the viewer's side: `-nn` where
/// `nn . vn < 0`. Seen from behind, a one-sided lobe with these normals is the lobe of the
/// front mirrored through the surface (the same tangents, the normal flipped), which is what
/// Mitsuba 3's `twosided` does by negating the local `z` of both directions.
pub fn facing_normals<'a>(ctx: &ShadingContext<'_>, arena: &'a bumpalo::Bump) -> &'a [Vec3] {
    let (nn, vn) = (ctx.nn(), ctx.vn());
    arena.alloc_slice_fill_iter(
        nn.iter()
            .zip(vn)
            .map(|(&n, &v)| if n.dot(v) < 0.0 { -n } else { n }),
    )
}

/// A one-sided reflection closure made two-sided: every call hands `inner` the context with
/// the shading normals `nn` ([`facing_normals`] of the same points).
pub struct TwoSidedBxdf<'a> {
    /// The one-sided closure, built on the facing view of the context.
    pub inner: &'a mut (dyn Bxdf + 'a),
    /// The viewer-facing shading normals, one per point of the context.
    pub nn: &'a [Vec3],
}

impl Bxdf for TwoSidedBxdf<'_> {
    fn lobes(&self) -> LobeSampled {
        self.inner.lobes()
    }
    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    ) {
        let facing = ctx.with_shading_normals(self.nn);
        self.inner.generate_samples(&facing, samplers, out);
    }
    fn evaluate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        wi: &[Vec3],
        value: &mut [Rgb],
        pdf: &mut [f32],
    ) {
        let facing = ctx.with_shading_normals(self.nn);
        self.inner.evaluate_samples(&facing, wi, value, pdf);
    }
    fn albedo(&self, ctx: &ShadingContext<'_>, out: &mut [Rgb]) {
        let facing = ctx.with_shading_normals(self.nn);
        self.inner.albedo(&facing, out);
    }
}
