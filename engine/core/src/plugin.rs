//! The plug-in contract: Bxdf factories, Bxdf closures, volume integrators and the shading
//! context they see. This is the seed's RIS interface (`RixBxdfFactory`, `RixBxdf`,
//! `RixVolumeIntegrator`, `RixShadingContext`) in Rust and batch-shaped: every call handles a
//! whole shading context (a contiguous group of points that share a material).
//!
//! Closures (Bxdfs and volume integrators) are allocated in the worker's per-batch arena (a
//! [`bumpalo::Bump`], the seed's `AllocForVolume`) and live for the batch; the arena is reset
//! after each batch, so a closure must not own heap memory that needs `Drop` (bumpalo never runs
//! destructors) -- keep plain data, or slices allocated in the same arena.
//!
//! # Example: a factory with an absorbing interior
//!
//! ```
//! use bumpalo::Bump;
//! use risotto_engine::plugin::*;
//! use risotto_builtins::builtin::{DiffuseBxdf, BeerInterior};
//! use risotto_components::Rgb;
//!
//! /// A grey diffuse surface whose interior absorbs like tinted glass.
//! struct Murky { sigma_a: Rgb }
//!
//! impl BxdfFactory for Murky {
//!     fn instance_hints(&self) -> InstanceHints {
//!         InstanceHints::COMPUTES_INTERIOR | InstanceHints::INTERIOR_TRANSMISSION
//!     }
//!     fn begin_scatter<'a>(&'a self, _ctx: &'a ShadingContext<'a>, _mode: ShadingMode,
//!                          arena: &'a Bump) -> &'a mut (dyn Bxdf + 'a) {
//!         arena.alloc(DiffuseBxdf { reflectance: Rgb::splat(0.5) })
//!     }
//!     fn begin_interior<'a>(&'a self, _ctx: &'a ShadingContext<'a>, _mode: ShadingMode,
//!                           arena: &'a Bump) -> Option<&'a mut (dyn VolumeIntegrator + 'a)> {
//!         Some(arena.alloc(BeerInterior { sigma_a: self.sigma_a }))
//!     }
//! }
//! # let _ = Murky { sigma_a: Rgb::splat(1.0) };
//! ```

pub mod context;
pub mod exits;
pub mod param_cache;
pub mod shading_context;
pub mod technique;
pub mod volume_light;
pub mod volume_space;

pub use crate::shade_groups::{EmittedRadiance, ShadeGroup, ShadeGroups, ShadingMode, WalkedRays};
pub use crate::stats::VolumeEvent;
use bumpalo::Bump;
pub use context::IntegratorContext;
pub use exits::{answer_exits, Exits};
use glam::Vec3;
use risotto_components::{LobeSampled, Rays, Rgb};
pub use risotto_systems::bxdf_samples::BxdfSamples;
pub use risotto_systems::sampler::SplitMix64;
use risotto_systems::sampler::{seed_from, PathSampler};
pub use shading_context::{
    Builtin, OverlappingVolume, ParamCache, ParamValue, PatternCounters, ShadingContext,
    VolumeSampling, VolumeSpace, MAX_COMPONENTS,
};
use std::any::Any;
pub use technique::{always, never, PluginTechniques, Technique, TechniqueError, TechniqueValue};
pub use volume_light::{EmissionStrategies, EmitterSupport, VolumeEmitter, VolumeLightMis};

/// What a factory tells the renderer without being asked to build anything (RIS
/// `GetInstanceHints`). The scene's feature set, and so the scheduler's stage list, is derived
/// from these.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct InstanceHints(pub u32);

impl InstanceHints {
    /// No hints: an opaque surface without interior.
    pub const NONE: InstanceHints = InstanceHints(0);
    /// `begin_interior` returns a volume integrator for the shape's interior.
    pub const COMPUTES_INTERIOR: InstanceHints = InstanceHints(1);
    /// The interior's integrator answers `transmission` (shadow rays may cross it).
    pub const INTERIOR_TRANSMISSION: InstanceHints = InstanceHints(2);
    /// The interior may overlap other volumes and wants to see them
    /// ([`ShadingContext::overlapping_volumes`]).
    pub const INTERIOR_OVERLAPPING: InstanceHints = InstanceHints(4);
    /// The surface is an index-matched boundary: rays pass unchanged (never shaded) and the
    /// crossing does not count as a scattering bounce.
    pub const INDEX_MATCHED: InstanceHints = InstanceHints(8);
    /// Shadow rays pass the surface, attenuated by [`BxdfFactory::shadow_transmittance`]
    /// (the seed's cheap, non-refracting glass shadows).
    pub const TRANSMISSION_SHADOWS: InstanceHints = InstanceHints(16);
    /// The Bxdf can produce rays with the transmit bit (the scene needs partitioning).
    pub const TRANSMITS: InstanceHints = InstanceHints(32);
    /// The interior scatters light (its integrator returns volume points or splats).
    pub const INTERIOR_SCATTERS: InstanceHints = InstanceHints(64);
    /// The interior's coefficients vary in space.
    pub const INTERIOR_HETEROGENEOUS: InstanceHints = InstanceHints(128);
    /// The interior is a subsurface integrator.
    pub const INTERIOR_SUBSURFACE: InstanceHints = InstanceHints(256);
    /// The interior emits light: the scene gets the `emissive_media` feature, without which
    /// no emission is gathered anywhere. The emission its integrator's
    /// [`VolumeIntegrator::transmission`] returns is added to shadow rays through it
    /// (weighted like the light sample's radiance), unless the material also says
    /// [`INTERIOR_EMITS_ALONG_PATHS`](Self::INTERIOR_EMITS_ALONG_PATHS).
    pub const INTERIOR_EMITS: InstanceHints = InstanceHints(512);
    /// The material reads the surface parameters `u`, `v` of its shading points
    /// ([`ShadingContext::u`], [`ShadingContext::v`]). Sphere hits get theirs (`phi / 2pi`,
    /// `theta / pi`: two `atan2` per hit) only in scenes with such a material; elsewhere
    /// their `u = v = 0`. Triangle hits always carry their barycentrics.
    pub const READS_SURFACE_UV: InstanceHints = InstanceHints(1024);
    /// With [`INTERIOR_EMITS`](Self::INTERIOR_EMITS): the interior's `nearest_hits` reports
    /// what it emits along the path rays it answers ([`ShadeGroups::emitted`]), every
    /// direction from every vertex. The path tracer then counts the interior's emission
    /// there only, and not also along shadow rays (the `emission` output of `transmission`,
    /// which such an interior still fills for integrators that want it): a shadow ray's
    /// direction is one a path ray can take too, so adding both would count the emission
    /// seen towards light samples twice. The built-in emissive media set both hints.
    pub const INTERIOR_EMITS_ALONG_PATHS: InstanceHints = InstanceHints(2048);
    /// The surface is partly present (the seed's opacity shaders): the factory answers
    /// [`BxdfFactory::opacity`] with the surface's opacity `a` in [0, 1] at each hit (by
    /// default its [`BxdfFactory::param`]`("opacity")`, a constant or a pattern whose
    /// channels are averaged; a factory may compute it from the hit's direction too, as a
    /// thin pane's Fresnel reflectance does). Path rays pass the surface
    /// unchanged with probability `1 - a` and scatter with probability `a`; shadow rays
    /// are attenuated by `1 - a` at each crossing, in addition to the volumes'
    /// `transmission`. The scene gets the `opacity` feature, without which no opacity stage
    /// runs. The surface's emission is not masked (Mitsuba's `mask` does the same: the
    /// emitter is not part of the Bxdf).
    pub const OPACITY: InstanceHints = InstanceHints(4096);

    /// True when every bit of `other` is set.
    pub const fn contains(self, other: InstanceHints) -> bool {
        self.0 & other.0 == other.0
    }
}

impl std::ops::BitOr for InstanceHints {
    type Output = InstanceHints;
    fn bitor(self, o: InstanceHints) -> InstanceHints {
        InstanceHints(self.0 | o.0)
    }
}

/// A scattering closure bound to one shading context (RIS `RixBxdf`): a surface Bxdf, or a
/// phase function for [`ShadingMode::VolumeScatter`] contexts.
pub trait Bxdf {
    /// Lobes this closure can produce. When it has no `DIFFUSE` (non-Dirac) lobe, the
    /// renderer skips light sampling and MIS for it.
    fn lobes(&self) -> LobeSampled;

    /// Samples one incident direction per point (RIS `GenerateSamples`). `samplers[i]` is
    /// point `i`'s sample source.
    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    );

    /// Evaluates `f * |cos|` and the solid-angle pdf of sampling `wi[i]` at point `i`
    /// (RIS `EvaluateSamples`). Dirac lobes evaluate to zero.
    ///
    /// A stochastic Bxdf (one whose value is itself a Monte Carlo estimate, as pbrt-v4's
    /// layered BxDF) draws the random numbers it needs here from
    /// [`evaluation_rng`]`(wo, wi)` for point `i`'s directions: the same pair always gets
    /// the same numbers, so a value and its pdf are reproducible, renders are deterministic
    /// for any thread count, and no sampler dimensions are consumed.
    fn evaluate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        wi: &[Vec3],
        value: &mut [Rgb],
        pdf: &mut [f32],
    );

    /// Directional albedo estimate per point for the `albedo` AOV. Defaults to black.
    fn albedo(&self, ctx: &ShadingContext<'_>, out: &mut [Rgb]) {
        let _ = ctx;
        out.fill(Rgb::BLACK);
    }
}

/// The random numbers a stochastic Bxdf's evaluation draws for the direction pair `(a, b)`
/// (see [`Bxdf::evaluate_samples`]): a [`SplitMix64`] seeded by hashing the six coordinates'
/// bits, as pbrt-v4 seeds its layered BxDF's generator from `Hash(wo)` and `Hash(wi)`. Any
/// frame, as long as the Bxdf uses one consistently; swapping the arguments gives an
/// unrelated stream (what a density estimate drawn beside the value wants).
pub fn evaluation_rng(a: Vec3, b: Vec3) -> SplitMix64 {
    SplitMix64(seed_from(&[a.x, a.y, a.z, b.x, b.y, b.z]))
}

/// A Bxdf that never scatters: what a factory's `begin_scatter` returns where it has
/// nothing to scatter (an index-matched boundary, which is never shaded; a point it is never
/// asked to shade), since it must always return one.
#[derive(Clone, Copy, Debug)]
pub struct NullBxdf;

impl Bxdf for NullBxdf {
    fn lobes(&self) -> LobeSampled {
        LobeSampled::NONE
    }
    fn generate_samples(
        &mut self,
        _ctx: &ShadingContext<'_>,
        _samplers: &mut [PathSampler],
        _out: &mut BxdfSamples,
    ) {
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
}

/// Direct-lighting services a global integrator may offer to volume integrators
/// (RIS `IntegratorDelegate::PerformDirectLighting`). The path tracer offers it; an integrator
/// that cannot (e.g. a light tracer) passes `None`.
pub trait LightingDelegate {
    /// Estimates direct lighting at every point of `ctx` (a [`ShadingMode::VolumeScatter`]
    /// context) scattered by `bxdf` towards `ctx.vn()`, multiplies it by `weight[i]` and the
    /// path throughput of the ray `rays[ctx.ray_id()[i]]`, and adds it to that ray's path.
    fn perform_direct_lighting(
        &mut self,
        ctx: &ShadingContext<'_>,
        bxdf: &mut dyn Bxdf,
        rays: &Rays,
        samplers: &mut [PathSampler],
        weight: &[Rgb],
    );
}

/// Straight segments on which [`VolumeIntegrator::transmission`] runs, chosen by the renderer.
#[derive(Clone, Debug, Default)]
pub struct Segments {
    /// Segment start.
    pub origin: Vec<Vec3>,
    /// Unit direction.
    pub direction: Vec<Vec3>,
    /// Segment length (RIS `maxDist`).
    pub length: Vec<f32>,
}

impl Segments {
    /// Number of segments.
    pub fn len(&self) -> usize {
        self.origin.len()
    }
    /// True when there are no segments.
    pub fn is_empty(&self) -> bool {
        self.origin.is_empty()
    }
    /// Removes every segment.
    pub fn clear(&mut self) {
        self.origin.clear();
        self.direction.clear();
        self.length.clear();
    }
    /// Appends a segment.
    pub fn push(&mut self, origin: Vec3, direction: Vec3, length: f32) {
        self.origin.push(origin);
        self.direction.push(direction);
        self.length.push(length);
    }
}

/// What the renderer lends a volume integrator's [`VolumeIntegrator::nearest_hits`] (the
/// seed's `ictx`, `lcb` and allocator, plus the factory that built the integrator, to build
/// phase functions with `begin_scatter(.., ShadingMode::VolumeScatter, ..)`).
pub struct VolumeServices<'a, 's> {
    /// The renderer's ray-tracing services.
    pub ictx: &'a mut (dyn IntegratorContext + 's),
    /// Direct lighting at in-volume points, when the global integrator offers it.
    pub lighting: Option<&'a mut dyn LightingDelegate>,
    /// The factory whose `begin_interior` built the integrator.
    pub factory: &'a dyn BxdfFactory,
    /// The worker's per-batch arena (plain data only: it runs no destructors).
    pub arena: &'a Bump,
    /// When the volume's emitter ([`BxdfFactory::volume_emitter`]) is light-sampled: how
    /// to weight the emission gathered along the rays against those light samples
    /// ([`crate::plugin::volume_light`]). `None`: weight 1.
    pub volume_light: Option<VolumeLightMis<'a>>,
    /// The rays start at the lights (the seed's `isLightPath`): a bidirectional integrator's
    /// light subpaths, which carry importance rather than radiance. A volume integrator
    /// answers them as it answers camera rays (transmittance and scattering points are the
    /// same); what it may skip is radiance it would gather for the rays (emission along
    /// them, which the global integrator ignores on light paths), and a lighting delegate is
    /// never offered with them.
    pub light_path: bool,
}

/// A volume integrator bound to one volumetric domain (RIS `RixVolumeIntegrator`).
pub trait VolumeIntegrator {
    /// Finds the next shading points for rays travelling in this volume (called instead of
    /// [`IntegratorContext::nearest_hits`]). Usually calls `services.ictx.nearest_hits`
    /// itself; may write `transmission` onto the points it returns, light in-volume points
    /// through `services.lighting` (single scattering; `None` when the global integrator
    /// offers no delegate), or return different points altogether: points inside the volume
    /// as a [`ShadingMode::VolumeScatter`] group (multiple scattering, through
    /// [`ShadingContext::begin_volume_sampling`] and
    /// [`VolumeSampling::end_volume_sampling`]). Rays it returns nothing for are absorbed.
    /// An emissive medium also reports the radiance it emitted along each ray's travel
    /// before the point it returns (or before the ray was absorbed) in
    /// [`ShadeGroups::emitted`], weighted by everything that happened inside the volume
    /// but not by the ray's throughput, which the global integrator applies (and says so
    /// with [`InstanceHints::INTERIOR_EMITS_ALONG_PATHS`]).
    /// `samplers[i]` is ray `i`'s sample source.
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        samplers: &mut [PathSampler],
        lobes_wanted: LobeSampled,
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    );

    /// Transmission (and emission reaching the segment start) along each segment, which lies
    /// entirely inside this volume (RIS `GetTransmission`). `emission[i]` is the radiance
    /// the volume emits along segment `i` that arrives at its start, attenuated within the
    /// segment (`int_0^L T(s) j(s) ds` for an emission coefficient `j`); black for a volume
    /// that does not emit. Where [`IntegratorContext::emission_wanted`] is false the caller
    /// drops `emission`, and the integrator may skip gathering it (leave it black).
    fn transmission(
        &self,
        segments: &Segments,
        samplers: &mut [PathSampler],
        ictx: &dyn IntegratorContext,
        trans: &mut [Rgb],
        emission: &mut [Rgb],
    );

    /// Lets an overlapping volume's integrator be inspected (downcast) by the innermost one.
    fn as_any(&self) -> Option<&dyn Any> {
        None
    }
}

/// The scalar opacity of a parameter value: the mean of its channels (a grey pattern, such
/// as an image's alpha channel, gives its value), clamped to [0, 1] against rounding.
#[inline]
pub fn opacity_of(value: Rgb) -> f32 {
    value.average().clamp(0.0, 1.0)
}

/// The `opacity` parameter of `ctx`'s material at each of its points, through the
/// context's cache (a colour's channels averaged, [`opacity_of`]), written to `out`; 1 (opaque)
/// without one. What [`BxdfFactory::opacity`] answers by
/// default, for a factory that overrides it for some surfaces only.
pub fn opacity_parameter(ctx: &ShadingContext<'_>, out: &mut [f32]) {
    match ctx.eval_param("opacity") {
        Some(column) => {
            for (a, &c) in out.iter_mut().zip(column) {
                *a = opacity_of(c);
            }
        }
        None => out.fill(1.0),
    }
}

/// Creates closures for one material (RIS `RixBxdfFactory`).
pub trait BxdfFactory: Send + Sync {
    /// What the renderer may know without building closures.
    fn instance_hints(&self) -> InstanceHints;

    /// Builds the Bxdf for a shading context (RIS `BeginScatter`).
    fn begin_scatter<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        mode: ShadingMode,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a);

    /// Builds the interior's volume integrator (RIS `BeginInterior`). Defaults to none.
    fn begin_interior<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        mode: ShadingMode,
        arena: &'a Bump,
    ) -> Option<&'a mut (dyn VolumeIntegrator + 'a)> {
        let _ = (ctx, mode, arena);
        None
    }

    /// Per-channel transmittance of the surface for shadow rays when
    /// [`InstanceHints::TRANSMISSION_SHADOWS`] is set. Defaults to opaque.
    fn shadow_transmittance(&self) -> Rgb {
        Rgb::BLACK
    }

    /// The surface's opacity `a` in [0, 1] at every point of `ctx` (with
    /// [`InstanceHints::OPACITY`]), written to `out` (one per point): the probability that a
    /// ray meeting the surface there finds it present. Path rays pass with probability
    /// `1 - a`, shadow rays are attenuated by `(1 - a) + a T` for the
    /// [`shadow_transmittance`](Self::shadow_transmittance) `T` (`crate::opacity`). The
    /// context's points are hits as the trace stage writes them, with `vn` the reverse of
    /// the ray's direction (a shadow ray's, towards its light, at a shadow ray's crossing),
    /// so `a` may depend on the direction; it must not depend on which way a ray crosses
    /// (`vn` or `-vn`), since a shadow ray and a path ray cross the same surface in opposite
    /// directions for the same light path.
    ///
    /// Defaults to [`param`](Self::param)`("opacity")` evaluated through the context's
    /// cache (a colour's channels averaged, clamped to [0, 1]); opaque without one.
    fn opacity(&self, ctx: &ShadingContext<'_>, out: &mut [f32]) {
        opacity_parameter(ctx, out)
    }

    /// The value of material parameter `name` (RIS: a parameter's connection), what
    /// [`ShadingContext::eval_param`] evaluates and caches. Defaults to none.
    fn param(&self, name: &str) -> Option<ParamValue<'_>> {
        let _ = name;
        None
    }

    /// The interior's emission as a light, for a shape with bounds `bounds` where the
    /// interior is `support` (next-event estimation towards emissive media,
    /// [`crate::plugin::volume_light`]). A factory that returns one promises that its integrator
    /// weights the emission it gathers along path rays by
    /// [`VolumeServices::volume_light`] and that shadow rays cross its boundary as its path
    /// rays do. Asked once per emissive shape at scene compilation. Defaults to none.
    fn volume_emitter(
        &self,
        bounds: (Vec3, Vec3),
        support: EmitterSupport,
    ) -> Option<VolumeEmitter> {
        let _ = (bounds, support);
        None
    }

    /// The techniques this material's closures offer (estimator choices a render may make
    /// over what the material says), as data: `risotto techniques` lists them for every
    /// scene with this material, `risotto render --technique NAME=VALUE` and `risotto
    /// converge` set and sweep them, and the closures read the chosen value through
    /// [`IntegratorContext::technique`]. Defaults to none.
    fn techniques(&self) -> &'static [&'static Technique] {
        &[]
    }

    /// Index of refraction of the interior, used as the *outside* IOR of shapes nested in it.
    /// Defaults to 1.
    fn ior(&self) -> f32 {
        1.0
    }
}
