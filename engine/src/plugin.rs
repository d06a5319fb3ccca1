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
//! use risotto_engine::builtin::{DiffuseBxdf, BeerInterior};
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

use crate::context::IntegratorContext;
use bumpalo::Bump;
use glam::Vec3;
use risotto_components::{LobeSampled, Rays, Rgb, ShadingPointRow, ShadingPoints, VolumeEntry};
use risotto_systems::bxdf::{BxdfSample, Frame};
use risotto_systems::sampler::PathSampler;
use std::any::Any;
use std::ops::Range;

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
    /// The interior emits light.
    pub const INTERIOR_EMITS: InstanceHints = InstanceHints(512);

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

/// Why a closure is being built (RIS `RixSCShadingMode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ShadingMode {
    /// Shading a surface hit.
    Scatter,
    /// Shading a point inside a volume (`k_RixSCVolumeScatterQuery`): the factory returns a
    /// phase function.
    VolumeScatter,
    /// Building an interior for a ray that travels through the volume.
    Interior,
}

/// Another volume overlapping the innermost one, with its own integrator (built by the
/// renderer through its factory's `begin_interior`).
pub struct OverlappingVolume<'a> {
    /// Which volume.
    pub entry: VolumeEntry,
    /// Its factory.
    pub factory: &'a dyn BxdfFactory,
    /// Its integrator (None when its factory computes no interior).
    pub integrator: Option<&'a (dyn VolumeIntegrator + 'a)>,
}

/// A group of shading points that share a material, with the RIS builtins as columns
/// (`P`, `Ng`, `Nn`, `Vn`, `VLen`, `u`, `v`, `w`, `transmission`, ray id).
pub struct ShadingContext<'a> {
    points: &'a ShadingPoints,
    range: Range<usize>,
    mode: ShadingMode,
    material: u32,
    overlapping: &'a [OverlappingVolume<'a>],
}

impl<'a> ShadingContext<'a> {
    /// A context over rows `range` of `points`.
    pub fn new(
        points: &'a ShadingPoints,
        range: Range<usize>,
        mode: ShadingMode,
        material: u32,
        overlapping: &'a [OverlappingVolume<'a>],
    ) -> Self {
        ShadingContext {
            points,
            range,
            mode,
            material,
            overlapping,
        }
    }
    /// Number of points (RIS `numPts`).
    pub fn num_points(&self) -> usize {
        self.range.len()
    }
    /// Why this context exists.
    pub fn mode(&self) -> ShadingMode {
        self.mode
    }
    /// Material (factory) index of every point.
    pub fn material(&self) -> u32 {
        self.material
    }
    /// Positions `P`.
    pub fn p(&self) -> &'a [Vec3] {
        &self.points.p[self.range.clone()]
    }
    /// Geometric normals `Ng`.
    pub fn ng(&self) -> &'a [Vec3] {
        &self.points.ng[self.range.clone()]
    }
    /// Shading normals `Nn`.
    pub fn nn(&self) -> &'a [Vec3] {
        &self.points.nn[self.range.clone()]
    }
    /// Directions towards the viewer `Vn`.
    pub fn vn(&self) -> &'a [Vec3] {
        &self.points.vn[self.range.clone()]
    }
    /// Incident segment lengths `VLen`.
    pub fn vlen(&self) -> &'a [f32] {
        &self.points.vlen[self.range.clone()]
    }
    /// Parameters `u`.
    pub fn u(&self) -> &'a [f32] {
        &self.points.u[self.range.clone()]
    }
    /// Parameters `v`.
    pub fn v(&self) -> &'a [f32] {
        &self.points.v[self.range.clone()]
    }
    /// Parameters `w`.
    pub fn w(&self) -> &'a [f32] {
        &self.points.w[self.range.clone()]
    }
    /// Transmission over each point's incident segment.
    pub fn transmission(&self) -> &'a [Rgb] {
        &self.points.transmission[self.range.clone()]
    }
    /// Index of the ray that produced each point.
    pub fn ray_id(&self) -> &'a [u32] {
        &self.points.ray_id[self.range.clone()]
    }
    /// Whether each ray arrived on the front face.
    pub fn front_face(&self) -> &'a [bool] {
        &self.points.front_face[self.range.clone()]
    }
    /// IOR of the medium outside each point's shape (see [`ShadingPointRow::ior_outside`]).
    pub fn ior_outside(&self) -> &'a [f32] {
        &self.points.ior_outside[self.range.clone()]
    }
    /// Shape index of each point (`u32::MAX` inside volumes).
    pub fn shape(&self) -> &'a [u32] {
        &self.points.shape[self.range.clone()]
    }
    /// The other volumes that overlap this context's volume (RIS `GetOverlappingVolumes`).
    pub fn overlapping_volumes(&self) -> &'a [OverlappingVolume<'a>] {
        self.overlapping
    }
}

/// Output columns of [`Bxdf::generate_samples`], one row per point of the context.
#[derive(Clone, Debug, Default)]
pub struct BxdfSamples {
    /// Sampled incident direction (world space, unit). Ignored where `pdf == 0`.
    pub wi: Vec<Vec3>,
    /// `f * |cos| / pdf` (for specular lobes: the lobe weight).
    pub weight: Vec<Rgb>,
    /// Solid-angle pdf of `wi`; for specular lobes the discrete lobe probability. 0 = no sample
    /// (the path ends, counted as absorbed).
    pub pdf: Vec<f32>,
    /// Lobe bits of each sample (`TRANSMIT` marks a crossing into the opposite volume).
    pub lobe: Vec<LobeSampled>,
    /// Relative index of refraction crossed (1 when none).
    pub eta: Vec<f32>,
}

impl BxdfSamples {
    /// Writes the sample `s` drawn in the local frame `frame` as row `i` (direction turned to
    /// world space).
    #[inline]
    pub fn set_local(&mut self, i: usize, frame: &Frame, s: BxdfSample) {
        self.wi[i] = frame.to_world(s.wi);
        self.weight[i] = s.weight;
        self.pdf[i] = s.pdf;
        self.lobe[i] = s.lobe;
        self.eta[i] = s.eta;
    }

    /// Resizes every column to `n` rows of "no sample".
    pub fn reset(&mut self, n: usize) {
        self.wi.clear();
        self.wi.resize(n, Vec3::Z);
        self.weight.clear();
        self.weight.resize(n, Rgb::BLACK);
        self.pdf.clear();
        self.pdf.resize(n, 0.0);
        self.lobe.clear();
        self.lobe.resize(n, LobeSampled::NONE);
        self.eta.clear();
        self.eta.resize(n, 1.0);
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

/// Where a volume integrator's results go: shading points grouped by material, plus rays that
/// escaped to the environment.
#[derive(Default, Debug)]
pub struct ShadeGroups {
    /// All points of all groups; each group is a contiguous range.
    pub points: ShadingPoints,
    /// The groups.
    pub groups: Vec<ShadeGroup>,
    /// Rays (ids in the table passed to `nearest_hits`) that left the scene.
    pub misses: Vec<u32>,
    /// Transmission applied to each escaped ray (parallel to `misses`).
    pub miss_transmission: Vec<Rgb>,
}

/// One group of a [`ShadeGroups`].
#[derive(Clone, Debug, PartialEq)]
pub struct ShadeGroup {
    /// Material (factory) index of the group's points.
    pub material: u32,
    /// Surface hits ([`ShadingMode::Scatter`]) or points inside a volume
    /// ([`ShadingMode::VolumeScatter`]).
    pub mode: ShadingMode,
    /// Rows of [`ShadeGroups::points`].
    pub range: Range<usize>,
}

impl ShadeGroups {
    /// Removes everything, keeping allocations.
    pub fn clear(&mut self) {
        self.points.clear();
        self.groups.clear();
        self.misses.clear();
        self.miss_transmission.clear();
    }
    /// Appends a group made of `rows` (RIS `EndVolumeSampling` with a membership mask: pass the
    /// retained points only). Empty groups are not added.
    pub fn push_group(
        &mut self,
        material: u32,
        mode: ShadingMode,
        rows: impl IntoIterator<Item = ShadingPointRow>,
    ) {
        let start = self.points.len();
        for r in rows {
            self.points.push(r);
        }
        let end = self.points.len();
        if end > start {
            self.groups.push(ShadeGroup {
                material,
                mode,
                range: start..end,
            });
        }
    }
    /// Multiplies the transmission of every point by `transmittance(VLen)` and of every
    /// escaped ray by `transmittance(tmax)` of its ray in `rays` (the table this was answered
    /// for): what a homogeneous, non-scattering interior does to the hits `nearest_hits`
    /// returns.
    pub fn attenuate_segments(&mut self, rays: &Rays, transmittance: impl Fn(f32) -> Rgb) {
        for (tr, &vlen) in self.points.transmission.iter_mut().zip(&self.points.vlen) {
            *tr *= transmittance(vlen);
        }
        for (tr, &ray) in self.miss_transmission.iter_mut().zip(&self.misses) {
            *tr *= transmittance(rays.tmax[ray as usize]);
        }
    }
    /// Records an escaped ray.
    pub fn push_miss(&mut self, ray_id: u32, transmission: Rgb) {
        self.misses.push(ray_id);
        self.miss_transmission.push(transmission);
    }
    /// Transmission column of group `g`, for a volume integrator to write.
    pub fn transmission_mut(&mut self, g: usize) -> &mut [Rgb] {
        let r = self.groups[g].range.clone();
        &mut self.points.transmission[r]
    }
    /// Segment lengths `VLen` of group `g`.
    pub fn vlen(&self, g: usize) -> &[f32] {
        &self.points.vlen[self.groups[g].range.clone()]
    }
    /// Ray ids of group `g`.
    pub fn ray_id(&self, g: usize) -> &[u32] {
        &self.points.ray_id[self.groups[g].range.clone()]
    }
    /// Total number of points.
    pub fn num_points(&self) -> usize {
        self.points.len()
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

/// A volume integrator bound to one volumetric domain (RIS `RixVolumeIntegrator`).
pub trait VolumeIntegrator {
    /// Finds the next shading points for rays travelling in this volume (called instead of
    /// [`IntegratorContext::nearest_hits`]). Usually calls `ictx.nearest_hits` itself; may
    /// write `transmission` onto the points it returns, splat in-scattered light through
    /// `lighting`, or return different points altogether (points inside the volume as a
    /// [`ShadingMode::VolumeScatter`] group; rays it returns nothing for are absorbed).
    /// `samplers[i]` is ray `i`'s sample source.
    #[allow(
        clippy::too_many_arguments,
        reason = "mirrors the RIS GetNearestHits contract"
    )]
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        samplers: &mut [PathSampler],
        lobes_wanted: LobeSampled,
        ictx: &mut IntegratorContext<'_>,
        lighting: Option<&mut dyn LightingDelegate>,
        out: &mut ShadeGroups,
    );

    /// Transmission (and emission reaching the segment start) along each segment, which lies
    /// entirely inside this volume (RIS `GetTransmission`).
    fn transmission(
        &self,
        segments: &Segments,
        samplers: &mut [PathSampler],
        ictx: &IntegratorContext<'_>,
        trans: &mut [Rgb],
        emission: &mut [Rgb],
    );

    /// Lets an overlapping volume's integrator be inspected (downcast) by the innermost one.
    fn as_any(&self) -> Option<&dyn Any> {
        None
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

    /// Index of refraction of the interior, used as the *outside* IOR of shapes nested in it.
    /// Defaults to 1.
    fn ior(&self) -> f32 {
        1.0
    }
}
