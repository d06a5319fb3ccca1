//! Opacity on any material (Mitsuba 3's `mask` BSDF, the seed's opacity shaders): a factory
//! that wraps another, adds [`InstanceHints::OPACITY`] and answers the `opacity` parameter,
//! and hands everything else to the wrapped factory. The renderer does the rest through the
//! public contract (`risotto_engine::opacity`): path rays pass the surface with probability
//! `1 - opacity`, shadow rays are attenuated by it. A user's plug-in may instead set the
//! hint and answer `param("opacity")` itself.

use bumpalo::Bump;
use glam::Vec3;
use risotto_components::Rgb;
use risotto_engine::plugin::*;
use risotto_systems::pattern::PatternGraph;
use std::sync::Arc;

/// A surface's opacity: the fraction of it that is present.
#[derive(Clone, Debug, PartialEq)]
pub enum Opacity {
    /// One value in [0, 1] everywhere.
    Constant(f32),
    /// A pattern (every channel in [0, 1] by the graph's bounds, which the scene loader
    /// checks; the channels' mean is the opacity), evaluated per hit through the context's
    /// cache: an image's alpha channel, a checker of holes.
    Pattern(Arc<PatternGraph>),
}

/// A material with opacity: `inner` where present, nothing where not.
pub struct OpacityMask {
    /// The material of the present part.
    pub inner: Box<dyn BxdfFactory>,
    /// How much of the surface is present.
    pub opacity: Opacity,
}

impl BxdfFactory for OpacityMask {
    fn instance_hints(&self) -> InstanceHints {
        let uv = match &self.opacity {
            Opacity::Pattern(graph) if graph.reads_uv() => InstanceHints::READS_SURFACE_UV,
            _ => InstanceHints::NONE,
        };
        self.inner.instance_hints() | InstanceHints::OPACITY | uv
    }

    fn begin_scatter<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        mode: ShadingMode,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a) {
        self.inner.begin_scatter(ctx, mode, arena)
    }

    fn begin_interior<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        mode: ShadingMode,
        arena: &'a Bump,
    ) -> Option<&'a mut (dyn VolumeIntegrator + 'a)> {
        self.inner.begin_interior(ctx, mode, arena)
    }

    fn shadow_transmittance(&self) -> Rgb {
        self.inner.shadow_transmittance()
    }

    /// The mask's own opacity times the wrapped material's, when that has one too (a
    /// pane whose transmission is a null event): the surface is present where both are.
    fn opacity(&self, ctx: &ShadingContext<'_>, out: &mut [f32]) {
        if self.inner.instance_hints().contains(InstanceHints::OPACITY) {
            self.inner.opacity(ctx, out);
        } else {
            out.fill(1.0);
        }
        match &self.opacity {
            Opacity::Constant(a) => out.iter_mut().for_each(|o| *o *= a),
            Opacity::Pattern(_) => {
                if let Some(column) = ctx.eval_param("opacity") {
                    for (o, &c) in out.iter_mut().zip(column) {
                        *o *= risotto_engine::opacity::opacity_of(c);
                    }
                }
            }
        }
    }

    fn param(&self, name: &str) -> Option<ParamValue<'_>> {
        match (name, &self.opacity) {
            ("opacity", Opacity::Constant(a)) => Some(ParamValue::Float(*a)),
            ("opacity", Opacity::Pattern(graph)) => Some(ParamValue::Pattern(graph)),
            _ => self.inner.param(name),
        }
    }

    fn volume_emitter(
        &self,
        bounds: (Vec3, Vec3),
        support: EmitterSupport,
    ) -> Option<VolumeEmitter> {
        self.inner.volume_emitter(bounds, support)
    }

    fn techniques(&self) -> &'static [&'static Technique] {
        self.inner.techniques()
    }

    fn ior(&self) -> f32 {
        self.inner.ior()
    }
}
