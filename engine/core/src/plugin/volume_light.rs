//! Emissive volumes as lights (issue 11): the contract's part. A factory offers its
//! interior's emission as a light ([`BxdfFactory::volume_emitter`](super::BxdfFactory::volume_emitter)(super::BxdfFactory::volume_emitter)),
//! and its volume integrator weighs what it gathers along path rays against the light samples
//! of that emitter ([`VolumeLightMis`]). The emitter itself is
//! [`risotto_systems::volume_lights`]'s; the scene's glue is in `scene/volume_lights.rs`.
//!
//! At scene compilation every shape whose material's interior emits is offered to its
//! factory ([`BxdfFactory::volume_emitter`](super::BxdfFactory::volume_emitter)); the emitters returned join the MIS light set
//! (`CompiledScene::mis_lights`) as `Light::Volume`,
//! selected by power with the other lights (their share capped at one half, see
//! `LightSet`), so under `lighting = mis` every shading vertex (surfaces and volume-scatter
//! points) samples them in its next-event estimation. Scenes with such an emitter have the
//! `emissive_volume_lights` feature; others never reach any of this.
//!
//! The unidirectional side of the MIS pair is the medium's collision estimator: its volume
//! integrator multiplies what it gathers at each tentative collision `x` of ray `r` by
//! [`VolumeLightMis::unidirectional_weight`], `w_U = p_U^2 / (p_U^2 + p_V^2)` with `p_U =
//! pdf(r) majorant(x) / |x - prev_p(r)|^2` and `p_V` the light-sampling density in volume
//! measure (the derivation is in [`risotto_systems::volume_lights`]). Camera rays and rays
//! with a Dirac lobe or no pdf keep weight 1 (no light sample was weighed against them).
//! A homogeneous medium, whose path rays gather their emission exactly, switches the rays
//! that are weighed to a point estimator of that density (a randomly offset comb of
//! `majorant` points per unit length along the segment, the built-ins' `homogeneous_emission`).
//! Shadow rays end at the sampled point inside the medium, so their transmittance covers the
//! emitter's own medium up to it; the emitter's emission along them is not added (the
//! built-in media report emission along path rays,
//! [`InstanceHints::INTERIOR_EMITS_ALONG_PATHS`](super::InstanceHints::INTERIOR_EMITS_ALONG_PATHS)).
//!
//! A global integrator with more strategies than light sampling at the ray's last vertex
//! (the bidirectional ones, whose light subpaths also start in the medium) gives its own
//! weights through [`VolumeLightMis::strategies`] ([`EmissionStrategies`]); a volume
//! integrator calls the same [`VolumeLightMis::unidirectional_weight`] and
//! [`VolumeLightMis::weighs`] either way.
//!
//! Light sampling alone (`lighting = nee`, and the lighting delegate) does not sample volume
//! lights: the collision estimator keeps weight 1 there. Next-event estimation alone is no
//! usable estimator of a volume's emission: from a vertex inside the emitter its variance is
//! infinite (the contribution `f T j / (p_V s^2)` has second moment `int ds / s^2` near the
//! vertex, which diverges; MIS removes it, as `w_V -> 0` there), and a wide emitter's cells
//! near a vertex are almost never chosen (a floor under an emissive slab 2000 units wide,
//! in `tests/emissive_media.rs`, got 23 % too little light at 1024 spp). `lighting = bxdf`
//! samples no light.
//!
//! Only boundaries that shadow rays cross as the path rays do can carry an emitter: the
//! built-in media offer one behind an index-matched `interface`, whose path rays keep their
//! direction and pdf. (Behind a dielectric, path rays are refracted, a Dirac event, and keep
//! weight 1, so an emitter there would count the light twice through cheap shadows or
//! never through opaque ones.)

use glam::Vec3;
use risotto_components::Rays;
use risotto_systems::lights::power_heuristic;
pub use risotto_systems::volume_lights::{EmitterSupport, VolumeEmitter};

/// What a volume integrator needs to weight its collision estimator against light sampling
/// of its own emitter ([`VolumeServices::volume_light`](crate::plugin::VolumeServices)).
#[derive(Clone, Copy)]
pub struct VolumeLightMis<'a> {
    /// The emitter (the medium's cells and tracking bounds).
    pub emitter: &'a VolumeEmitter,
    /// Its selection probability in the light set the global integrator samples.
    pub selection: f32,
    /// The global integrator's own weights, when strategies other than light sampling at
    /// the ray's last vertex also make the paths the collision estimator ends (a
    /// bidirectional integrator's: light subpaths that start in the medium, connections to
    /// them); `None`: the path tracer's pair of light sampling and the collision estimator
    /// (the [module docs](self)). Either way a volume integrator calls the same two methods.
    pub strategies: Option<&'a dyn EmissionStrategies>,
}

impl std::fmt::Debug for VolumeLightMis<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VolumeLightMis")
            .field("emitter", self.emitter)
            .field("selection", &self.selection)
            .field("strategies", &self.strategies.is_some())
            .finish()
    }
}

/// A global integrator's weights for the emission a medium's collision estimator gathers
/// along its rays, when more strategies than light sampling at the ray's last vertex make
/// those paths ([`VolumeLightMis::strategies`]). Whatever the strategies, the weights of
/// one path must sum to one over them (Veach 1997, sec. 9.2), so only the global
/// integrator, which knows all of them, can give this one's.
pub trait EmissionStrategies: Sync {
    /// The weight of what the collision estimator gathers at world point `x` on ray `r` of
    /// `rays` (tentative collisions at the rate `light.emitter.mis_majorant(x)`, the density
    /// `pdf(r) majorant(x) / |x - prev_p(r)|^2` in volume measure, as in the
    /// [module docs](self)).
    fn weight(&self, light: &VolumeLightMis<'_>, rays: &Rays, r: usize, x: Vec3) -> f32;

    /// Whether ray `r`'s emission is weighed at all (the weight is 1 where it is not, and a
    /// volume integrator may gather it exactly).
    fn weighs(&self, rays: &Rays, r: usize) -> bool;
}

impl VolumeLightMis<'_> {
    /// The weight `w_U` of what the collision estimator gathers at world point `x` on ray `r`
    /// of `rays` (see the [module docs](self)).
    #[inline]
    pub fn unidirectional_weight(&self, rays: &Rays, r: usize, x: Vec3) -> f32 {
        if let Some(s) = self.strategies {
            return s.weight(self, rays, r, x);
        }
        if !self.weighs(rays, r) {
            return 1.0;
        }
        let s2 = (x - rays.prev_p[r]).length_squared();
        let p_v = self.selection * self.emitter.pdf(x);
        let p_u = rays.pdf[r] * self.emitter.mis_majorant(x) / s2;
        power_heuristic(p_u, p_v)
    }

    /// Whether ray `r`'s emission is weighed against other strategies at all; under the
    /// path tracer not for camera rays, rays with a Dirac lobe or no pdf
    /// ([`Self::unidirectional_weight`] is 1 on those). (Under `nee` and `bxdf`, which sample
    /// no volume light, an integrator gets no `VolumeLightMis` at all.)
    #[inline]
    pub fn weighs(&self, rays: &Rays, r: usize) -> bool {
        if let Some(s) = self.strategies {
            return s.weighs(rays, r);
        }
        let pdf = rays.pdf[r];
        let plain = rays.depth[r] == 0 || rays.lobe[r].is_specular() || pdf.is_nan() || pdf <= 0.0;
        !plain
    }
}
