//! The built-in interiors: which volume integrator a built-in material's inside gets
//! ([`Interior`]), and the two that live here, `null` (pass-through) and `beer`
//! (Beer-Lambert absorption). The scattering ones are in [`crate::media`],
//! [`crate::heterogeneous`] and [`crate::subsurface`].

use crate::heterogeneous::{HeterogeneousInterior, HeterogeneousMedium};
use crate::media::{HomogeneousInterior, HomogeneousMedium};
use bumpalo::Bump;
use risotto_components::{LobeSampled, Rays, Rgb};
use risotto_engine::plugin::IntegratorContext;
use risotto_engine::plugin::*;
use risotto_systems::sampler::PathSampler;
use std::sync::Arc;

/// The seed's `NullInterior`: passes hits through, transmission 1.
#[derive(Clone, Copy, Debug, Default)]
pub struct NullInterior;

impl VolumeIntegrator for NullInterior {
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        _samplers: &mut [PathSampler],
        _lobes_wanted: LobeSampled,
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
        services.ictx.nearest_hits(rays, out);
    }
    fn transmission(
        &self,
        _segments: &Segments,
        _samplers: &mut [PathSampler],
        _ictx: &dyn IntegratorContext,
        trans: &mut [Rgb],
        emission: &mut [Rgb],
    ) {
        trans.fill(Rgb::WHITE);
        emission.fill(Rgb::BLACK);
    }
}

/// The seed's `GlassInterior`: Beer-Lambert absorption, `T = exp(-sigma_a * d)` per channel,
/// on the hits it returns and on shadow segments. No scattering.
#[derive(Clone, Copy, Debug)]
pub struct BeerInterior {
    /// Absorption coefficient per channel (per world unit), >= 0.
    pub sigma_a: Rgb,
}

impl BeerInterior {
    /// Transmittance over a distance.
    #[inline]
    pub fn transmittance(&self, distance: f32) -> Rgb {
        beer(self.sigma_a, distance)
    }
}

/// `exp(-sigma * d)` per channel; an infinite distance through a non-absorbing channel gives 1
/// (not NaN: `0 * inf` is defined as 0 here).
#[inline]
pub fn beer(sigma: Rgb, distance: f32) -> Rgb {
    sigma.map(|s| if s == 0.0 { 1.0 } else { (-s * distance).exp() })
}

impl VolumeIntegrator for BeerInterior {
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        _samplers: &mut [PathSampler],
        _lobes_wanted: LobeSampled,
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
        services.ictx.nearest_hits(rays, out);
        out.attenuate_segments(rays, |length| self.transmittance(length));
    }
    fn transmission(
        &self,
        segments: &Segments,
        _samplers: &mut [PathSampler],
        _ictx: &dyn IntegratorContext,
        trans: &mut [Rgb],
        emission: &mut [Rgb],
    ) {
        for i in 0..segments.len() {
            trans[i] = self.transmittance(segments.length[i]);
        }
        emission.fill(Rgb::BLACK);
    }
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

/// Which built-in interior a material has.
#[derive(Clone, Debug, PartialEq)]
pub enum Interior {
    /// No volume inside.
    None,
    /// Pass-through volume (transmission 1).
    Null,
    /// Beer-Lambert absorber.
    Beer {
        /// Absorption coefficient per channel.
        sigma_a: Rgb,
    },
    /// Homogeneous scattering medium.
    Homogeneous(HomogeneousMedium),
    /// Heterogeneous scattering medium (a density grid; shared, not copied).
    Heterogeneous(Arc<HeterogeneousMedium>),
    /// The `subsurface` material's interior ([`crate::subsurface`]): the walked medium and
    /// the diffusion profile made from the artist's parameters, and the mode to use.
    Subsurface(crate::subsurface::SubsurfaceInteriorParams),
}

impl Interior {
    /// What the engine may assume of a material with this interior (its part of
    /// [`BxdfFactory::instance_hints`]).
    pub(super) fn hints(&self) -> InstanceHints {
        let volume = InstanceHints::COMPUTES_INTERIOR | InstanceHints::INTERIOR_TRANSMISSION;
        // The built-in emissive media report their emission along path rays (and fill
        // `transmission`'s emission output too).
        let emits = InstanceHints::INTERIOR_EMITS | InstanceHints::INTERIOR_EMITS_ALONG_PATHS;
        match self {
            Interior::None => InstanceHints::NONE,
            Interior::Null | Interior::Beer { .. } => volume,
            Interior::Homogeneous(m) if m.emits() => {
                volume | InstanceHints::INTERIOR_SCATTERS | emits
            }
            Interior::Heterogeneous(m) if m.emits() => {
                volume
                    | InstanceHints::INTERIOR_SCATTERS
                    | InstanceHints::INTERIOR_HETEROGENEOUS
                    | emits
            }
            Interior::Homogeneous(_) => volume | InstanceHints::INTERIOR_SCATTERS,
            Interior::Subsurface(_) => {
                volume | InstanceHints::INTERIOR_SCATTERS | InstanceHints::INTERIOR_SUBSURFACE
            }
            Interior::Heterogeneous(_) => {
                volume | InstanceHints::INTERIOR_SCATTERS | InstanceHints::INTERIOR_HETEROGENEOUS
            }
        }
    }
    /// The volume integrator of this interior over `ctx`'s points, in the arena (`None`
    /// without an interior). `boundary_blocks_shadows`: the surface around it lets no shadow
    /// ray through.
    pub(super) fn begin<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        arena: &'a Bump,
        boundary_blocks_shadows: bool,
    ) -> Option<&'a mut (dyn VolumeIntegrator + 'a)> {
        match self {
            Interior::None => None,
            Interior::Null => Some(arena.alloc(NullInterior)),
            Interior::Beer { sigma_a } => Some(arena.alloc(BeerInterior { sigma_a: *sigma_a })),
            Interior::Subsurface(params) => {
                Some(arena.alloc(crate::subsurface::SubsurfaceInterior {
                    walk: HomogeneousInterior {
                        medium: &params.walk,
                        ctx,
                        boundary_blocks_shadows,
                    },
                    diffusion: crate::diffusion::DiffusionInterior {
                        medium: params.diffusion,
                    },
                    mode: params.mode,
                    patterned: params.patterned.as_deref(),
                }))
            }
            Interior::Homogeneous(medium) => Some(arena.alloc(HomogeneousInterior {
                medium,
                ctx,
                boundary_blocks_shadows,
            })),
            Interior::Heterogeneous(medium) => {
                Some(arena.alloc(HeterogeneousInterior { medium, ctx }))
            }
        }
    }
}

/// The `subsurface` material as a built-in material (here, beside the interior it builds:
/// the subsurface module itself knows nothing of the built-in material).
impl crate::subsurface::SubsurfaceParams {
    /// The material: a smooth dielectric (shadow rays blocked, as a real boundary does)
    /// over the walked medium.
    pub fn material(&self) -> super::BuiltinMaterial {
        self.material_with(crate::subsurface::SubsurfacePatterns::default())
    }

    /// [`Self::material`] with `albedo` and `mean_free_path` from `patterns` where they
    /// are given (read at each ray's entry point, see the module docs).
    pub fn material_with(
        &self,
        patterns: crate::subsurface::SubsurfacePatterns,
    ) -> super::BuiltinMaterial {
        let patterned = (!patterns.is_empty()).then(|| {
            Arc::new(crate::subsurface::PatternedSubsurface {
                params: *self,
                patterns,
            })
        });
        super::BuiltinMaterial {
            surface: super::Surface::Dielectric {
                ior: self.ior,
                tint: Rgb::WHITE,
                cheap_shadows: false,
            },
            interior: Interior::Subsurface(crate::subsurface::SubsurfaceInteriorParams {
                walk: self.medium(),
                diffusion: self.diffusion(),
                mode: self.mode,
                patterned,
            }),
        }
    }
}
