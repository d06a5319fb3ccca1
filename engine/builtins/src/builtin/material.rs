//! The built-in material factory: a [`Surface`] and an [`Interior`], building the surface's
//! Bxdf closure at surface points, the phase closure at volume points, and the interior's
//! volume integrator.

use super::bxdfs::*;
use super::coated::{CoatedBase, CoatedBxdf};
use super::interiors::*;
use super::plastic::PlasticBxdf;
use super::rough::*;
use super::rough_patterns::{VaryingConductor, VaryingDielectric, VaryingPlastic};
use super::thin_dielectric::ThinDielectricBxdf;
use super::two_sided::{facing_normals, TwoSidedBxdf};
use crate::phase::{phase_bxdf, PhaseBxdf};
use crate::scatter_patterns::eval_uncached;
use bumpalo::Bump;
use risotto_components::Rgb;
use risotto_engine::plugin::*;
use risotto_systems::bxdf::PlasticCoat;
use risotto_systems::layered::Layered;
use risotto_systems::pattern::PatternGraph;
use risotto_systems::rough_conductor::RoughConductor;
use risotto_systems::rough_dielectric::RoughDielectric;
use risotto_systems::rough_plastic::RoughPlastic;
use std::sync::Arc;

/// The surface part of a built-in material.
#[derive(Clone, Debug, PartialEq)]
pub enum Surface {
    /// Lambertian.
    Diffuse {
        /// Reflectance.
        reflectance: Rgb,
    },
    /// Lambertian with a reflectance pattern (every value in [0, 1] by the graph's bounds,
    /// which the scene loader checks), evaluated per point through the context's cache
    /// (parameter `reflectance`).
    DiffusePattern {
        /// The reflectance graph.
        reflectance: Arc<PatternGraph>,
    },
    /// Smooth dielectric.
    Dielectric {
        /// Interior IOR.
        ior: f32,
        /// Refraction tint.
        tint: Rgb,
        /// Shadow rays pass (attenuated by `tint`) instead of being blocked: the seed's cheap
        /// non-refracting glass shadows.
        cheap_shadows: bool,
    },
    /// Smooth dielectric with a tint pattern (every value in [0, 1] by the graph's bounds,
    /// checked by the scene loader), evaluated per hit through the context's cache
    /// (parameter `tint`). Shadow rays are blocked (cheap shadows attenuate by one colour).
    DielectricPattern {
        /// Interior IOR.
        ior: f32,
        /// The tint graph.
        tint: Arc<PatternGraph>,
    },
    /// Perfect mirror / smooth conductor.
    Mirror {
        /// Reflectance.
        reflectance: Rgb,
    },
    /// Perfect mirror with a reflectance pattern (every value in [0, 1] by the graph's
    /// bounds, checked by the scene loader), evaluated per point through the context's cache
    /// (parameter `reflectance`), as [`Surface::DiffusePattern`].
    MirrorPattern {
        /// The reflectance graph.
        reflectance: Arc<PatternGraph>,
    },
    /// Rough conductor, GGX or Beckmann (complex index, Fresnel tint, optional energy compensation),
    /// its tables integrated when the material was built.
    RoughConductor(RoughConductor),
    /// Rough dielectric, GGX or Beckmann; its `eta` is the material's index (against vacuum).
    RoughDielectric(RoughDielectric),
    /// Rough conductor whose roughness or complex index is a pattern
    /// ([`super::rough_patterns`]); parameters `alpha` / `alpha_u` / `alpha_v`, `eta`, `k`.
    RoughConductorPattern(Box<VaryingConductor>),
    /// Rough dielectric whose roughness is a pattern ([`super::rough_patterns`]).
    RoughDielectricPattern(Box<VaryingDielectric>),
    /// Index-matched boundary: rays pass unchanged.
    Interface,
    /// Smooth plastic: a Lambertian base under a smooth dielectric coat
    /// ([`risotto_systems::bxdf::plastic`]). One-sided.
    Plastic {
        /// The coat.
        coat: PlasticCoat,
        /// The base's reflectance.
        diffuse: Rgb,
    },
    /// Smooth plastic with a base-reflectance pattern (every value in [0, 1] by the graph's
    /// bounds, checked by the scene loader), evaluated per point through the context's cache
    /// (parameter `diffuse_reflectance`).
    PlasticPattern {
        /// The coat.
        coat: PlasticCoat,
        /// The base-reflectance graph.
        diffuse: Arc<PatternGraph>,
    },
    /// Rough plastic: a Lambertian base under a rough dielectric coat
    /// ([`risotto_systems::rough_plastic`], its tables integrated when the material was
    /// built). One-sided.
    RoughPlastic {
        /// The coat.
        lobe: RoughPlastic,
        /// The base's reflectance.
        diffuse: Rgb,
    },
    /// Rough plastic with a base-reflectance pattern (every value in [0, 1] by the graph's
    /// bounds, checked by the scene loader), evaluated per point through the context's cache
    /// (parameter `diffuse_reflectance`).
    RoughPlasticPattern {
        /// The coat.
        lobe: RoughPlastic,
        /// The base-reflectance graph.
        diffuse: Arc<PatternGraph>,
    },
    /// Rough plastic whose roughness is a pattern ([`super::rough_patterns`]); its base
    /// reflectance a colour or a pattern.
    RoughPlasticVarying(Box<VaryingPlastic>),
    /// A thin pane of glass ([`risotto_systems::bxdf::thin_dielectric`]): no refraction
    /// offset; shadow rays blocked unless its transmission is a null event.
    ThinDielectric {
        /// The pane's index of refraction.
        ior: f32,
        /// Transmission is a null event, not a bounce ([`ThinDielectricBxdf::null_transmission`]):
        /// the pane is a surface with opacity `R'` (its reflectance) and a mirror Bxdf.
        null_transmission: bool,
    },
    /// pbrt-v4's `coateddiffuse` / `coatedconductor`: a dielectric coat over a base with a
    /// slab between ([`risotto_systems::layered`]). Two-sided.
    Coated(Box<CoatedSurface>),
    /// A one-sided reflecting surface (`Diffuse`, `Plastic`, their pattern forms) shaded on
    /// whichever side the viewer is (Mitsuba 3's `twosided`). The scene loader wraps only
    /// surfaces that do not transmit.
    TwoSided(Box<Surface>),
}

/// The parameters of a [`Surface::Coated`].
#[derive(Clone, Debug, PartialEq)]
pub struct CoatedSurface {
    /// Coat, slab and walk.
    pub layered: Layered,
    /// The base.
    pub base: CoatedBase,
    /// A diffuse base's reflectance: a colour, or a pattern (every value in [0, 1] by the
    /// graph's bounds, checked by the scene loader) evaluated per point through the
    /// context's cache (parameter `reflectance`). Ignored by a conductor base.
    pub reflectance: CoatedReflectance,
}

/// A diffuse base's reflectance.
#[derive(Clone, Debug, PartialEq)]
pub enum CoatedReflectance {
    /// One colour.
    Color(Rgb),
    /// A pattern.
    Pattern(Arc<PatternGraph>),
}

impl Surface {
    /// The surface's share of the material's instance hints.
    fn hints(&self) -> InstanceHints {
        match self {
            Surface::Diffuse { .. }
            | Surface::Mirror { .. }
            | Surface::Plastic { .. }
            | Surface::RoughPlastic { .. }
            | Surface::RoughConductor(_) => InstanceHints::NONE,
            Surface::Coated(c) => match &c.reflectance {
                CoatedReflectance::Pattern(g) if g.reads_uv() => InstanceHints::READS_SURFACE_UV,
                _ => InstanceHints::NONE,
            },
            Surface::RoughDielectric(_) => InstanceHints::TRANSMITS,
            Surface::RoughConductorPattern(c) => c.hints(),
            Surface::RoughPlasticVarying(p) => p.hints(),
            Surface::RoughDielectricPattern(d) => d.hints(),
            Surface::DiffusePattern { reflectance } | Surface::MirrorPattern { reflectance }
                if reflectance.reads_uv() =>
            {
                InstanceHints::READS_SURFACE_UV
            }
            Surface::PlasticPattern { diffuse, .. }
            | Surface::RoughPlasticPattern { diffuse, .. }
                if diffuse.reads_uv() =>
            {
                InstanceHints::READS_SURFACE_UV
            }
            Surface::DiffusePattern { .. }
            | Surface::MirrorPattern { .. }
            | Surface::PlasticPattern { .. }
            | Surface::RoughPlasticPattern { .. } => InstanceHints::NONE,
            Surface::DielectricPattern { tint, .. } if tint.reads_uv() => {
                InstanceHints::TRANSMITS | InstanceHints::READS_SURFACE_UV
            }
            Surface::DielectricPattern { .. } => InstanceHints::TRANSMITS,
            &Surface::Dielectric { cheap_shadows, .. } => {
                let h = InstanceHints::TRANSMITS;
                if cheap_shadows {
                    h | InstanceHints::TRANSMISSION_SHADOWS
                } else {
                    h
                }
            }
            Surface::Interface => {
                InstanceHints::INDEX_MATCHED
                    | InstanceHints::TRANSMISSION_SHADOWS
                    | InstanceHints::TRANSMITS
            }
            // A pane alone passes rays without their entering anything: not `TRANSMITS`
            // (which would track the shape on the volume stack as a closed boundary; with an
            // interior it is one, `instance_hints`). A null transmission is a pass of the
            // opacity machinery (`BuiltinMaterial::opacity`).
            Surface::ThinDielectric {
                null_transmission, ..
            } => match null_transmission {
                true => InstanceHints::OPACITY,
                false => InstanceHints::NONE,
            },
            Surface::TwoSided(inner) => inner.hints(),
        }
    }

    /// The surface's closure at the points of `ctx`.
    fn scatter<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a) {
        match *self {
            Surface::Diffuse { reflectance } => arena.alloc(DiffuseBxdf { reflectance }),
            // Patterns go through the context's cache ([`pattern_column`]).
            Surface::DiffusePattern { ref reflectance } => arena.alloc(DiffuseBxdf {
                reflectance: pattern_column(ctx, "reflectance", reflectance, arena),
            }),
            Surface::Dielectric { ior, tint, .. } => arena.alloc(DielectricBxdf { ior, tint }),
            Surface::DielectricPattern { ior, ref tint } => arena.alloc(DielectricBxdf {
                ior,
                tint: pattern_column(ctx, "tint", tint, arena),
            }),
            Surface::Mirror { reflectance } => arena.alloc(MirrorBxdf { reflectance }),
            Surface::MirrorPattern { ref reflectance } => arena.alloc(MirrorBxdf {
                reflectance: pattern_column(ctx, "reflectance", reflectance, arena),
            }),
            Surface::RoughConductor(ref lobe) => arena.alloc(RoughConductorBxdf { lobe }),
            Surface::RoughDielectric(ref lobe) => arena.alloc(RoughDielectricBxdf { lobe }),
            Surface::RoughConductorPattern(ref c) => c.scatter(ctx, arena),
            Surface::RoughPlasticVarying(ref p) => p.scatter(ctx, arena),
            Surface::RoughDielectricPattern(ref d) => d.scatter(ctx, arena),
            Surface::Interface => arena.alloc(NullBxdf),
            Surface::Plastic { coat, diffuse } => arena.alloc(PlasticBxdf { coat, diffuse }),
            Surface::PlasticPattern { coat, ref diffuse } => arena.alloc(PlasticBxdf {
                coat,
                diffuse: pattern_column(ctx, "diffuse_reflectance", diffuse, arena),
            }),
            Surface::RoughPlastic { ref lobe, diffuse } => {
                arena.alloc(RoughPlasticBxdf { lobe, diffuse })
            }
            Surface::RoughPlasticPattern {
                ref lobe,
                ref diffuse,
            } => arena.alloc(RoughPlasticBxdf {
                lobe,
                diffuse: pattern_column(ctx, "diffuse_reflectance", diffuse, arena),
            }),
            Surface::ThinDielectric {
                ior,
                null_transmission,
            } => arena.alloc(ThinDielectricBxdf {
                ior,
                null_transmission,
            }),
            Surface::Coated(ref c) => match c.reflectance {
                CoatedReflectance::Color(reflectance) => arena.alloc(CoatedBxdf {
                    layered: &c.layered,
                    base: &c.base,
                    reflectance,
                }),
                CoatedReflectance::Pattern(ref graph) => arena.alloc(CoatedBxdf {
                    layered: &c.layered,
                    base: &c.base,
                    reflectance: pattern_column(ctx, "reflectance", graph, arena),
                }),
            },
            Surface::TwoSided(ref inner) => {
                let nn = facing_normals(ctx, arena);
                let facing = arena.alloc(ctx.with_shading_normals(nn));
                let inner = inner.scatter(facing, arena);
                arena.alloc(TwoSidedBxdf { inner, nn })
            }
        }
    }

    /// The surface's parameter `name`, for [`BxdfFactory::param`].
    fn param(&self, name: &str) -> Option<ParamValue<'_>> {
        match (self, name) {
            (Surface::Diffuse { reflectance } | Surface::Mirror { reflectance }, "reflectance") => {
                Some(ParamValue::Color(*reflectance))
            }
            (
                Surface::DiffusePattern { reflectance } | Surface::MirrorPattern { reflectance },
                "reflectance",
            ) => Some(ParamValue::Pattern(reflectance)),
            (Surface::Dielectric { ior, .. } | Surface::DielectricPattern { ior, .. }, "ior") => {
                Some(ParamValue::Float(*ior))
            }
            (Surface::DielectricPattern { tint, .. }, "tint") => Some(ParamValue::Pattern(tint)),
            (Surface::Dielectric { tint, .. }, "tint") => Some(ParamValue::Color(*tint)),
            (
                Surface::Plastic { diffuse, .. } | Surface::RoughPlastic { diffuse, .. },
                "diffuse_reflectance",
            ) => Some(ParamValue::Color(*diffuse)),
            (
                Surface::PlasticPattern { diffuse, .. }
                | Surface::RoughPlasticPattern { diffuse, .. },
                "diffuse_reflectance",
            ) => Some(ParamValue::Pattern(diffuse)),
            (Surface::ThinDielectric { ior, .. }, "ior") => Some(ParamValue::Float(*ior)),
            (Surface::RoughDielectric(lobe), "ior") => Some(ParamValue::Float(lobe.eta)),
            (Surface::RoughDielectric(lobe), "tint") => Some(ParamValue::Color(lobe.tint)),
            (Surface::RoughConductor(lobe), "specular_reflectance") => {
                Some(ParamValue::Color(lobe.tint))
            }
            (Surface::RoughConductorPattern(c), "specular_reflectance") => {
                Some(ParamValue::Color(c.tint))
            }
            (Surface::RoughConductorPattern(c), _) => c.param(name),
            (Surface::RoughPlasticVarying(p), _) => p.param(name),
            (Surface::RoughDielectricPattern(d), "ior") => Some(ParamValue::Float(d.eta)),
            (Surface::RoughDielectricPattern(d), "tint") => Some(ParamValue::Color(d.tint)),
            (Surface::RoughDielectricPattern(d), _) => d.param(name),
            (Surface::Coated(c), "reflectance") => match &c.reflectance {
                CoatedReflectance::Color(r) => Some(ParamValue::Color(*r)),
                CoatedReflectance::Pattern(g) => Some(ParamValue::Pattern(g)),
            },
            (Surface::TwoSided(inner), _) => inner.param(name),
            _ => None,
        }
    }
}

/// A built-in material: a surface and an optional interior.
#[derive(Clone, Debug, PartialEq)]
pub struct BuiltinMaterial {
    /// Surface scattering.
    pub surface: Surface,
    /// Interior volume.
    pub interior: Interior,
}

impl BxdfFactory for BuiltinMaterial {
    fn instance_hints(&self) -> InstanceHints {
        let surface = match (&self.surface, &self.interior) {
            // A pane around an interior (Mitsuba's thindielectric bounding a medium): the
            // rays it passes cross into the volume, a boundary like any transmitting one.
            (surface @ Surface::ThinDielectric { .. }, interior)
                if !matches!(interior, Interior::None) =>
            {
                InstanceHints::TRANSMITS | surface.hints()
            }
            (surface, _) => surface.hints(),
        };
        surface | self.interior.hints()
    }

    fn begin_scatter<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        mode: ShadingMode,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a) {
        match mode {
            // A point inside the interior: its phase function (an interior that does not
            // scatter never returns such points; isotropic and black if asked anyway).
            ShadingMode::VolumeScatter => {
                return match &self.interior {
                    Interior::Subsurface(params) => {
                        arena.alloc(PhaseBxdf::new(params.walk.phase, params.walk.albedo()))
                    }
                    // A `g` pattern is read through the context's cache.
                    Interior::Homogeneous(m) => {
                        phase_bxdf(ctx, m.phase, m.g_pattern.as_deref(), m.albedo(), arena)
                    }
                    Interior::Heterogeneous(m) => {
                        phase_bxdf(ctx, m.phase, m.g_pattern.as_deref(), m.albedo, arena)
                    }
                    _ => arena.alloc(NullBxdf),
                };
            }
            // Interiors are built by `begin_interior`; a surface closure is never needed for
            // them.
            ShadingMode::Interior => return arena.alloc(NullBxdf),
            ShadingMode::Scatter => {}
        }
        self.surface.scatter(ctx, arena)
    }

    fn begin_interior<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> Option<&'a mut (dyn VolumeIntegrator + 'a)> {
        // A surface with opacity lets shadow rays through where it is absent.
        let blocks = self.surface != Surface::Interface
            && self.shadow_transmittance().is_black()
            && !self.surface.hints().contains(InstanceHints::OPACITY);
        self.interior.begin(ctx, arena, blocks)
    }

    fn shadow_transmittance(&self) -> Rgb {
        match self.surface {
            Surface::Interface => Rgb::WHITE,
            Surface::Dielectric {
                tint,
                cheap_shadows: true,
                ..
            } => tint,
            _ => Rgb::BLACK,
        }
    }

    /// A pane whose transmission is a null event (Mitsuba 3's `thindielectric` under its
    /// volumetric path tracers) is present with probability `R'(cos)`, its reflectance with
    /// the internal bounces summed, at the hit's angle to the shading normal: a path ray
    /// passes it straight with probability `T' = 1 - R'` without a bounce, and a shadow ray
    /// through it is attenuated by `T'`, Mitsuba's `eval_null_transmission`. Symmetric in
    /// the direction, as the contract asks. Other surfaces: their `opacity` parameter.
    fn opacity(&self, ctx: &ShadingContext<'_>, out: &mut [f32]) {
        match self.surface {
            Surface::ThinDielectric {
                ior,
                null_transmission: true,
            } => {
                let (nn, vn, ior_out) = (ctx.nn(), ctx.vn(), ctx.ior_outside());
                for (i, a) in out.iter_mut().enumerate() {
                    let eta = ior / ior_out[i].max(1e-6);
                    *a = risotto_systems::bxdf::thin_dielectric_reflectance(nn[i].dot(vn[i]), eta);
                }
            }
            _ => risotto_engine::opacity::opacity_parameter(ctx, out),
        }
    }

    fn param(&self, name: &str) -> Option<ParamValue<'_>> {
        match (&self.surface, name) {
            (_, crate::scatter_patterns::G_PARAM) => match &self.interior {
                Interior::Homogeneous(m) => m.g_pattern.as_deref().map(ParamValue::Pattern),
                Interior::Heterogeneous(m) => m.g_pattern.as_deref().map(ParamValue::Pattern),
                _ => None,
            },
            (surface, _) => surface.param(name),
        }
    }

    fn techniques(&self) -> &'static [&'static Technique] {
        use crate::heterogeneous::TRACKING;
        use crate::media::SCATTERING;
        use crate::subsurface::SUBSURFACE;
        static HOMOGENEOUS: [&Technique; 1] = [&SCATTERING];
        static SUBSURFACE_WALK: [&Technique; 2] = [&SCATTERING, &SUBSURFACE];
        static HETEROGENEOUS: [&Technique; 1] = [&TRACKING];
        match &self.interior {
            Interior::Homogeneous(_) => &HOMOGENEOUS,
            Interior::Subsurface(_) => &SUBSURFACE_WALK,
            Interior::Heterogeneous(_) => &HETEROGENEOUS,
            Interior::None | Interior::Null | Interior::Beer { .. } => &[],
        }
    }

    fn ior(&self) -> f32 {
        match self.surface {
            Surface::Dielectric { ior, .. } | Surface::DielectricPattern { ior, .. } => ior,
            Surface::RoughDielectric(ref lobe) => lobe.eta,
            Surface::RoughDielectricPattern(ref d) => d.eta,
            _ => 1.0,
        }
    }

    /// A heterogeneous emissive interior behind an index-matched `interface` is a light
    /// (behind other surfaces path rays do not keep their pdf, `risotto_engine::plugin::volume_light`).
    fn volume_emitter(
        &self,
        bounds: (glam::Vec3, glam::Vec3),
        support: risotto_engine::plugin::EmitterSupport,
    ) -> Option<risotto_engine::plugin::VolumeEmitter> {
        match (&self.surface, &self.interior) {
            (Surface::Interface, Interior::Heterogeneous(m)) => m.volume_emitter(bounds, support),
            (Surface::Interface, Interior::Homogeneous(m)) => m.volume_emitter(bounds, support),
            _ => None,
        }
    }
}

/// The column of pattern parameter `name` (the material's `graph`) over `ctx`'s points:
/// through the context's cache, or, for a context without one (a plug-in's own), evaluated
/// here.
pub(super) fn pattern_column<'a>(
    ctx: &ShadingContext<'a>,
    name: &str,
    graph: &PatternGraph,
    arena: &'a Bump,
) -> &'a [Rgb] {
    ctx.eval_param(name)
        .unwrap_or_else(|| eval_uncached(graph, ctx, arena))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use risotto_components::{ShadingPointRow, ShadingPoints};

    #[test]
    fn a_pattern_parameter_is_evaluated_at_p_once_per_context() {
        use risotto_systems::pattern::{Axis, Node, PatternGraph};
        use std::sync::Arc;
        // reflectance = gradient along x from 0 at x = 0 to 1 at x = 4.
        let graph = PatternGraph::new(vec![Node::Gradient {
            axis: Axis::X,
            from: 0.0,
            to: 4.0,
            a: Rgb::BLACK,
            b: Rgb::WHITE,
        }])
        .unwrap();
        let material = BuiltinMaterial {
            surface: Surface::DiffusePattern {
                reflectance: Arc::new(graph),
            },
            interior: Interior::None,
        };
        let mut t = ShadingPoints::default();
        for i in 0..3 {
            let p = Vec3::new(i as f32, 0.0, 0.0);
            t.push(ShadingPointRow::in_volume(p, Vec3::X, i, 0));
        }
        let (arena, counters) = (Bump::new(), PatternCounters::default());
        let cache = ParamCache::new(&arena, &counters);
        let ctx = ShadingContext::new(&t, 0..3, ShadingMode::Scatter, 0, &[])
            .with_factory(&material)
            .with_cache(&cache);
        let bxdf = material.begin_scatter(&ctx, ShadingMode::Scatter, &arena);
        let mut albedo = [Rgb::BLACK; 3];
        bxdf.albedo(&ctx, &mut albedo);
        assert_eq!(albedo, [0.0, 0.25, 0.5].map(Rgb::splat));
        // The Bxdf pulled the column once; another pull on the context is a cache hit.
        assert_eq!((counters.hits.get(), counters.evals.get()), (0, 1));
        assert_eq!(ctx.eval_param("reflectance").unwrap(), &albedo[..]);
        assert_eq!((counters.hits.get(), counters.evals.get()), (1, 1));
        // Without a cache the Bxdf evaluates the graph itself, to the same values.
        let bare = ShadingContext::new(&t, 1..3, ShadingMode::Scatter, 0, &[]);
        let bxdf = material.begin_scatter(&bare, ShadingMode::Scatter, &arena);
        let mut two = [Rgb::BLACK; 2];
        bxdf.albedo(&bare, &mut two);
        assert_eq!(two, albedo[1..]);
    }
}
