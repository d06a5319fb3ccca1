//! The heterogeneous scattering medium: extinction `sigma_t(p) = scale * density(p)` from a
//! density grid placed in the shape's bounds, a constant single-scattering albedo and a
//! phase function (scene files: `interior = { type = "heterogeneous", ... }`,
//! `docs/scene-format.md`).
//!
//! # Estimators
//! - **Free flights** ([`HeterogeneousInterior::nearest_hits`]): delta tracking (Woodcock)
//!   against the **majorant grid** ([`MajorantGrid`], `majorant_grid` cells per axis, 16 by
//!   default; 1 = one global majorant as in Mitsuba), traversed with a 3D DDA so that each
//!   tentative collision is sampled from its own cell's bound. A real collision scatters
//!   with weight `albedo` (`sigma_s / sigma_t`, the same convention as the homogeneous
//!   medium's [`FreeFlight`](risotto_systems::medium::FreeFlight) weight); the points go to
//!   the global integrator as a [`ShadingMode::VolumeScatter`] group (multiple scattering;
//!   with or without a lighting delegate). Null collisions are counted as
//!   [`VolumeEvent::Null`].
//! - **Transmittance** ([`HeterogeneousInterior::transmission`]): `tracking` chooses ratio
//!   tracking (default), residual ratio tracking (the majorant grid's per-cell minimum as the
//!   control), delta tracking (0 or 1), fixed-step ray marching or the unbiased ray-marching
//!   estimator ([`risotto_systems::ray_marching`]); `ray_marching` also marches the free
//!   flights. The render's [`VolumeTechniques::tracking`] overrides the medium's choice.
//!
//! Both draw their random numbers from the samplers they are given, a variable number per
//! ray (two per tentative collision for delta tracking, one for ratio tracking), rounded up
//! to a multiple of four dimensions so that the vertices after them stay aligned to the
//! sampler's four-dimensional sets.
//!
//! # Emission
//! `emission` gives the **emission coefficient** `j(p)` (radiance per unit length,
//! [`HeterogeneousEmission`]): a colour times the density (`emission = colour`) or a
//! colour times a grid of its own (`emission = { grid, scale }`). The estimator is
//! pbrt-v4's (`VolPathIntegrator`, where the emission term is `sigma_a Le`): at **every**
//! tentative collision of delta tracking, null or real, the free flight adds `j(p) /
//! majorant` at the path's weight (1 along a delta-tracking flight), including the collision
//! that turns out real ([`delta_tracking_emitting`]); its expectation is
//! `int_0^t T(s) j(s) ds` over the ray's segment. Shadow segments
//! ([`HeterogeneousInterior::transmission`]) add `T_k j / bound` at each tentative
//! collision of ratio or residual tracking, `T_k` the running transmittance estimate
//! ([`ratio_tracking_emitting`]), or pbrt's sum under delta tracking.
//!
//! Both need a positive tentative-collision rate wherever `j > 0`, which a density bound of
//! 0 (emission where the density vanishes, or `scale = 0`) or a residual control equal to
//! the bound (a constant cell) would not give. So in every majorant cell where the medium
//! emits (the density's bound is positive, for the colour form; the emission grid's, for
//! the grid form) the tracking bound is raised to at least `minorant + f`, with
//! `f =` [`EMISSION_COLLISIONS_PER_CELL`] per width of the widest cell side: any bound
//! above the extinction keeps delta and ratio tracking unbiased, and this one gives emitting
//! cells about one collision per cell crossed (at most one per widest side, so a flat box
//! costs no more collisions than a cube of its largest side). Media that do not emit track exactly as
//! before (the same bounds, the same random numbers).
//!
//! # Spectral handling
//! The density scale is grey (one `sigma_t` for R, G and B); the albedo may be a colour.
//! With a grey extinction every channel shares the free-flight distribution, so the
//! estimator's weights are `albedo` at a collision and 1 on passing: bounded, and no colour
//! noise. A chromatic scale (spectral tracking) is not implemented yet.

use crate::grid_file::{is_vdb, read_grid_named};
use crate::load::phase_function;
use crate::media::{retain_points, PhaseBxdf};
use crate::plugin::*;
use crate::scene_file::{MaterialParams, SceneError};
use crate::stats::VolumeEvent;
use glam::Vec3;
use risotto_components::{LobeSampled, Rays, Rgb, ShadingPointRow, ShadingPoints};
use risotto_systems::grid::{Dda, DensityGrid, MajorantGrid, MajorantSegment};
use risotto_systems::phase::PhaseFunction;
use risotto_systems::ray_marching::{
    ray_marching_free_flight, ray_marching_transmittance, unbiased_ray_marching,
};
use risotto_systems::sampler::PathSampler;
use risotto_systems::tracking::{
    delta_tracking, delta_tracking_emitting, delta_tracking_transmittance, ratio_tracking,
    ratio_tracking_emitting, residual_ratio_tracking, Transmittance,
};
use std::sync::Arc;

/// How [`HeterogeneousInterior::transmission`] estimates transmittance, and whether free
/// flights are ray-marched (scene files: `tracking = "ratio" | "residual" | "delta" |
/// "ray_marching" | "unbiased_ray_marching"`; `risotto render --technique tracking=..`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Tracking {
    /// Ratio tracking: the product of null-collision probabilities.
    #[default]
    Ratio,
    /// Residual ratio tracking with each majorant cell's minimum as the control.
    Residual,
    /// Delta tracking: 1 if a free flight passes, else 0.
    Delta,
    /// Fixed-step ray marching of the optical depth, for shadow rays and free flights
    /// (biased, consistent as the step shrinks; [`risotto_systems::ray_marching`]).
    RayMarching,
    /// The unbiased ray-marching transmittance estimator (a power series around a marched
    /// pivot) for shadow rays; free flights by delta tracking.
    UnbiasedRayMarching,
}

/// Every [`Tracking`], in the order the docs list them.
pub const TRACKINGS: [Tracking; 5] = [
    Tracking::Ratio,
    Tracking::Residual,
    Tracking::Delta,
    Tracking::RayMarching,
    Tracking::UnbiasedRayMarching,
];

impl Tracking {
    /// The scene-file name.
    pub fn name(self) -> &'static str {
        match self {
            Tracking::Ratio => "ratio",
            Tracking::Residual => "residual",
            Tracking::Delta => "delta",
            Tracking::RayMarching => "ray_marching",
            Tracking::UnbiasedRayMarching => "unbiased_ray_marching",
        }
    }
    /// The tracking of a scene-file name.
    pub fn from_name(name: &str) -> Option<Tracking> {
        TRACKINGS.into_iter().find(|t| t.name() == name)
    }
}

/// Default majorant-grid cells per axis.
pub const DEFAULT_MAJORANT_CELLS: usize = 16;

/// A heterogeneous medium's parameters (shared by every integrator built for it).
#[derive(Clone, Debug, PartialEq)]
pub struct HeterogeneousMedium {
    /// The density field over the unit cube of the shape's bounds.
    pub density: Arc<DensityGrid>,
    /// Bounds of `density` over coarse cells (density units).
    pub majorants: Arc<MajorantGrid>,
    /// `sigma_t = scale * density`, per world unit, >= 0.
    pub scale: f32,
    /// Single-scattering albedo `sigma_s / sigma_t` per channel, in [0, 1].
    pub albedo: Rgb,
    /// Phase function.
    pub phase: PhaseFunction,
    /// Transmittance estimator.
    pub tracking: Tracking,
    /// Ray-marching step in world units (`None`: the smallest voxel extent of the grid in
    /// the shape's bounds).
    pub march_step: Option<f32>,
    /// What the medium emits; `None` (the default): nothing.
    pub emission: Option<HeterogeneousEmission>,
}

/// What a heterogeneous medium emits: its **emission coefficient** `j(p)`, radiance per
/// unit length (the source term of `dL/ds = -sigma_t L + j + ...`), per channel (scene
/// files: `emission = colour` or `emission = { grid = "file.vol", scale = colour }`).
#[derive(Clone, Debug, PartialEq)]
pub enum HeterogeneousEmission {
    /// `j(p) = colour * density(p)` (the density grid's own values, before the density
    /// `scale`): the emission follows the density, as in a flame made of one grid.
    FollowsDensity(Rgb),
    /// `j(p) = scale * grid(p)`: an independent grid (a temperature field), placed in the
    /// shape's bounds like the density grid.
    Grid {
        /// The emission grid (placed like the density).
        grid: Arc<DensityGrid>,
        /// `j = scale * grid` per channel, >= 0.
        scale: Rgb,
        /// Bounds of `grid` over the density's majorant cells (same resolution), which
        /// say where the medium emits.
        majorants: Arc<MajorantGrid>,
    },
}

/// Tentative collisions per majorant-cell width that a ray gets at least in a cell where
/// the medium emits (see [`HeterogeneousInterior`]'s emission estimators).
pub const EMISSION_COLLISIONS_PER_CELL: f32 = 1.0;

impl HeterogeneousMedium {
    /// A medium over `density` with a majorant grid of `majorant_cells` per axis (clamped to
    /// `[1, voxels]` per axis).
    pub fn new(
        density: DensityGrid,
        majorant_cells: usize,
        scale: f32,
        albedo: Rgb,
        phase: PhaseFunction,
        tracking: Tracking,
    ) -> Self {
        let res = density.dims().map(|n| majorant_cells.clamp(1, n));
        let majorants = MajorantGrid::new(&density, res);
        HeterogeneousMedium {
            density: Arc::new(density),
            majorants: Arc::new(majorants),
            scale,
            albedo,
            phase,
            tracking,
            march_step: None,
            emission: None,
        }
    }

    /// The medium emitting `j(p) = colour * density(p)` (black: no emission).
    pub fn with_emission_following_density(mut self, colour: Rgb) -> Self {
        self.emission =
            (!colour.is_black()).then_some(HeterogeneousEmission::FollowsDensity(colour));
        self
    }

    /// The medium emitting `j(p) = scale * grid(p)`, `grid` placed like the density (a
    /// black `scale` or an all-zero grid: no emission).
    pub fn with_emission_grid(mut self, grid: DensityGrid, scale: Rgb) -> Self {
        self.emission = (!scale.is_black() && grid.max() > 0.0).then(|| {
            let majorants = MajorantGrid::new(&grid, self.majorants.res());
            HeterogeneousEmission::Grid {
                grid: Arc::new(grid),
                scale,
                majorants: Arc::new(majorants),
            }
        });
        self
    }

    /// Whether the medium emits.
    pub fn emits(&self) -> bool {
        self.emission.is_some()
    }

    /// The phase function as the Bxdf of the medium's scattering points.
    pub fn phase_bxdf(&self) -> PhaseBxdf {
        PhaseBxdf {
            phase: self.phase,
            albedo: self.albedo,
        }
    }
}

/// Reads `interior = { type = "heterogeneous", ... }` (see `docs/scene-format.md`).
pub(crate) fn parse(t: &MaterialParams) -> Result<HeterogeneousMedium, SceneError> {
    t.deny_unknown(&[
        "type",
        "density",
        "scale",
        "albedo",
        "phase",
        "tracking",
        "march_step",
        "majorant_grid",
        "emission",
    ])?;
    let d = t
        .table("density")?
        .ok_or_else(|| t.error(None, "a heterogeneous interior needs `density = { grid = \"file.vol\" }` (or `{ constant = .. }`)"))?;
    d.deny_unknown(&["grid", "header", "name", "constant"])?;
    let density = match (d.path("grid")?, d.has("constant")) {
        (Some(path), false) => {
            let header = d.path("header")?;
            let name = if d.has("name") {
                Some(d.string("name", None)?)
            } else {
                None
            };
            grid_file(&d, &path, header, name)?
        }
        (None, true) => {
            if d.has("header") {
                return Err(d.error(Some("header"), "`header` belongs to a raw `grid` file"));
            }
            let c = d.f32_where("constant", None, "must be >= 0", |v| v >= 0.0)?;
            DensityGrid::constant([1, 1, 1], c)
                .map_err(|e| d.error(Some("constant"), e.to_string()))?
        }
        (Some(_), true) => {
            return Err(d.error(
                Some("constant"),
                "give either `grid` or `constant`, not both",
            ))
        }
        (None, false) => {
            return Err(d.error(
                None,
                "`density` needs `grid = \"file\"` or `constant = number`",
            ))
        }
    };
    let scale = t.f32_where("scale", Some(1.0), "must be >= 0", |v| v >= 0.0)?;
    if !(scale * density.max()).is_finite() {
        return Err(t.error(
            Some("scale"),
            format!(
                "scale {scale} times the grid's max {} overflows",
                density.max()
            ),
        ));
    }
    let albedo = t.rgb_where("albedo", Some(Rgb::WHITE), "every channel in [0, 1]", |c| {
        c.min_channel() >= 0.0 && c.max_channel() <= 1.0
    })?;
    let phase = match t.table("phase")? {
        None => PhaseFunction::Isotropic,
        Some(p) => phase_function(&p)?,
    };
    let name = t.string("tracking", Some("ratio"))?;
    let tracking = Tracking::from_name(&name).ok_or_else(|| {
        t.error(
            Some("tracking"),
            format!(
                "unknown tracking \"{name}\" (known: {})",
                TRACKINGS.map(Tracking::name).join(", ")
            ),
        )
    })?;
    let march_step = if t.has("march_step") {
        Some(t.f32_where("march_step", None, "must be > 0 (world units)", |v| v > 0.0)?)
    } else {
        None
    };
    let cells = t.u32("majorant_grid", Some(DEFAULT_MAJORANT_CELLS as u32))?;
    if cells == 0 || cells > 256 {
        return Err(t.error(
            Some("majorant_grid"),
            format!("must be in [1, 256] cells per axis, got {cells}"),
        ));
    }
    let medium = HeterogeneousMedium {
        march_step,
        ..HeterogeneousMedium::new(density, cells as usize, scale, albedo, phase, tracking)
    };
    Ok(match parse_emission(t)? {
        None => medium,
        Some(EmissionKey::Colour(c)) => {
            let max = medium.density.max();
            if !(c * max).is_finite() {
                return Err(t.error(
                    Some("emission"),
                    format!("emission {c:?} times the density grid's max {max} overflows"),
                ));
            }
            medium.with_emission_following_density(c)
        }
        Some(EmissionKey::Grid(grid, scale)) => medium.with_emission_grid(grid, scale),
    })
}

/// Reads the grid file of a `{ grid = .., header = .., name = .. }` table `t` (density or
/// emission): `header` only for raw files, `name` only for `.vdb` ones.
fn grid_file(
    t: &MaterialParams,
    path: &std::path::Path,
    header: Option<std::path::PathBuf>,
    name: Option<String>,
) -> Result<DensityGrid, SceneError> {
    if is_vdb(path) && header.is_some() {
        return Err(t.error(
            Some("header"),
            "`header` belongs to a raw `grid` file, not a .vdb",
        ));
    }
    if !is_vdb(path) && name.is_some() {
        return Err(t.error(Some("name"), "`name` picks a grid of a .vdb file"));
    }
    let vol = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("vol"));
    if header.is_none() && !vol && !is_vdb(path) {
        // A raw grid's header beside it is read too.
        t.note_file(&path.with_extension("json"));
    }
    read_grid_named(path, header.as_deref(), name.as_deref())
        .map_err(|e| t.error(Some("grid"), e.to_string()))
}

/// The two forms of a heterogeneous interior's `emission` key.
enum EmissionKey {
    /// `emission = colour`.
    Colour(Rgb),
    /// `emission = { grid = "file", scale = colour }`.
    Grid(DensityGrid, Rgb),
}

/// Reads `emission` (absent: none): a colour (`j = colour * density`) or a table
/// `{ grid = "file.vol" | "file.raw", header = "file.json", scale = colour }`
/// (`j = scale * grid`).
fn parse_emission(t: &MaterialParams) -> Result<Option<EmissionKey>, SceneError> {
    let coefficient = "every channel in [0, 1e30] (radiance per unit length; MAX_RADIANCE)";
    let ok = |c: Rgb| {
        c.min_channel() >= 0.0
            && c.is_finite()
            && c.max_channel() <= crate::scene_file::MAX_RADIANCE
    };
    if !t.has("emission") {
        return Ok(None);
    }
    if !t.is_table("emission") {
        return Ok(Some(EmissionKey::Colour(t.rgb_where(
            "emission",
            None,
            coefficient,
            ok,
        )?)));
    }
    let e = t.table("emission")?.expect("checked: a table");
    e.deny_unknown(&["grid", "header", "name", "scale"])?;
    let Some(path) = e.path("grid")? else {
        return Err(e.error(
            None,
            "an emission table needs `grid = \"file.vol\"` (or give `emission` as a colour: \
             j = colour * density)",
        ));
    };
    let header = e.path("header")?;
    let name = if e.has("name") {
        Some(e.string("name", None)?)
    } else {
        None
    };
    let grid = grid_file(&e, &path, header, name)?;
    let scale = e.rgb_where("scale", Some(Rgb::WHITE), coefficient, ok)?;
    if !(scale * grid.max()).is_finite() {
        return Err(e.error(
            Some("scale"),
            format!(
                "scale {scale:?} times the emission grid's max {} overflows",
                grid.max()
            ),
        ));
    }
    Ok(Some(EmissionKey::Grid(grid, scale)))
}

/// The heterogeneous medium's volume integrator, bound to the bundle's shading context (which
/// carries the shape's bounds, where the grid is placed).
pub struct HeterogeneousInterior<'a> {
    /// The medium.
    pub medium: &'a HeterogeneousMedium,
    /// The context `begin_interior` bound.
    pub ctx: &'a ShadingContext<'a>,
}

/// Sampler dimensions are consumed in multiples of this (see the module docs).
const DIMENSION_SET: u32 = 4;

/// Rounds the dimensions `s` consumed since `start` up to whole sets (at least one).
fn align(s: &mut PathSampler, start: u32) {
    let used = s.dimension.wrapping_sub(start).max(1);
    s.dimension = start.wrapping_add(used.next_multiple_of(DIMENSION_SET));
}

/// The majorant segments a ray crosses in an emissive medium: the density's, scaled to
/// extinction, with the bound of every cell where the medium emits raised to at least
/// `minorant + floor` (see [`HeterogeneousInterior`]'s emission docs). The emission grid's
/// cells are traversed in lockstep with the density's (same resolution, same ray: the same
/// segments).
struct EmissiveSegments<'g> {
    density: Dda<'g>,
    emission: Option<Dda<'g>>,
    scale: f32,
    floor: f32,
}

impl Iterator for EmissiveSegments<'_> {
    type Item = MajorantSegment;
    #[inline]
    fn next(&mut self) -> Option<MajorantSegment> {
        let g = self.density.next()?;
        let emits = match &mut self.emission {
            Some(e) => e.next().is_some_and(|e| e.majorant > 0.0),
            None => g.majorant > 0.0,
        };
        let mut s = g.scaled(self.scale);
        if emits {
            s.majorant = s.majorant.max(s.minorant + self.floor);
        }
        Some(s)
    }
}

impl HeterogeneousInterior<'_> {
    /// The majorant segments of the grid-space ray `(o, d)` on `[0, tmax]`, for an emissive
    /// medium ([`EmissiveSegments`]).
    fn emissive_segments(&self, o: Vec3, d: Vec3, tmax: f32) -> EmissiveSegments<'_> {
        let m = self.medium;
        let res = m.majorants.res();
        let (lo, hi) = self.ctx.volume_bounds().unwrap_or((Vec3::ZERO, Vec3::ONE));
        let extent = (hi - lo).to_array();
        // The widest side of a cell in world units; the floor is so many collisions per
        // width. (The widest, not the narrowest: a flat box would otherwise get a rate that
        // a ray travelling along it could not get through.)
        let width = (0..3)
            .map(|a| extent[a] / res[a] as f32)
            .filter(|w| *w > 0.0 && w.is_finite())
            .fold(0.0f32, f32::max);
        let floor = if width > 0.0 {
            (EMISSION_COLLISIONS_PER_CELL / width).min(f32::MAX)
        } else {
            0.0
        };
        let emission = match &m.emission {
            Some(HeterogeneousEmission::Grid { majorants, .. }) => {
                Some(majorants.traverse(o, d, 0.0, tmax))
            }
            _ => None,
        };
        EmissiveSegments {
            density: m.majorants.traverse(o, d, 0.0, tmax),
            emission,
            scale: m.scale,
            floor,
        }
    }

    /// The emission coefficient at grid point `uvw`, where the extinction is `sigma_t`.
    #[inline]
    fn emission_at(&self, uvw: Vec3, sigma_t: f32) -> Rgb {
        let m = self.medium;
        match &m.emission {
            None => Rgb::BLACK,
            Some(HeterogeneousEmission::FollowsDensity(c)) => {
                let density = if m.scale > 0.0 {
                    sigma_t / m.scale
                } else {
                    m.density.lookup(uvw)
                };
                *c * density
            }
            Some(HeterogeneousEmission::Grid { grid, scale, .. }) => *scale * grid.lookup(uvw),
        }
    }

    /// Transmittance of one world-space segment with the medium's `tracking`, and the
    /// emission reaching its start, for an emissive medium.
    fn segment_emission(
        &self,
        o: Vec3,
        d: Vec3,
        length: f32,
        tracking: Tracking,
        s: &mut PathSampler,
    ) -> (Transmittance, Rgb) {
        let m = self.medium;
        let (o, d) = self.to_grid(o, d);
        let segs = self.emissive_segments(o, d, length);
        let sigma = |t: f32| m.scale * m.density.lookup(o + d * t);
        let emission = |t: f32, sigma_t: f32| self.emission_at(o + d * t, sigma_t);
        let start = s.dimension;
        let rand = || s.next_1d();
        // The ray-marching estimators gather no emission: emissive media ratio-track.
        let r = match tracking {
            Tracking::Ratio | Tracking::RayMarching | Tracking::UnbiasedRayMarching => {
                ratio_tracking_emitting(segs, sigma, emission, rand, false)
            }
            Tracking::Residual => ratio_tracking_emitting(segs, sigma, emission, rand, true),
            Tracking::Delta => {
                let (f, e) = delta_tracking_emitting(segs, sigma, emission, rand);
                let t = Transmittance {
                    value: if f.collided { 0.0 } else { 1.0 },
                    nulls: f.nulls + f.collided as u32,
                    violations: f.violations,
                };
                (t, e)
            }
        };
        align(s, start);
        r
    }

    /// `(origin, direction)` of a world-space ray in the grid's unit cube (the same `t`).
    fn to_grid(&self, o: Vec3, d: Vec3) -> (Vec3, Vec3) {
        let (lo, hi) = self.ctx.volume_bounds().unwrap_or((Vec3::ZERO, Vec3::ONE));
        let inv = 1.0 / (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
        ((o - lo) * inv, d * inv)
    }

    /// The ray-marching step in world units: the medium's `march_step`, or the smallest
    /// voxel extent in the shape's bounds.
    fn march_step(&self) -> f32 {
        self.medium.march_step.unwrap_or_else(|| {
            let (lo, hi) = self.ctx.volume_bounds().unwrap_or((Vec3::ZERO, Vec3::ONE));
            let dims = self.medium.density.dims();
            let voxel = (hi - lo) / Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32);
            let v = voxel.min_element();
            // A flat box (zero extent on an axis) marches by its other voxels.
            if v > 0.0 {
                v
            } else {
                voxel.max_element().max(f32::MIN_POSITIVE)
            }
        })
    }

    /// Transmittance of one world-space segment with `tracking`.
    fn segment_transmittance(
        &self,
        o: Vec3,
        d: Vec3,
        length: f32,
        tracking: Tracking,
        s: &mut PathSampler,
    ) -> Transmittance {
        let m = self.medium;
        let (o, d) = self.to_grid(o, d);
        let segs = || {
            m.majorants
                .traverse(o, d, 0.0, length)
                .map(|g| g.scaled(m.scale))
        };
        let sigma = |t: f32| m.scale * m.density.lookup(o + d * t);
        let start = s.dimension;
        let rand = || s.next_1d();
        let r = match tracking {
            Tracking::Ratio => ratio_tracking(segs(), sigma, rand),
            Tracking::Residual => residual_ratio_tracking(segs(), sigma, rand),
            Tracking::Delta => delta_tracking_transmittance(segs(), sigma, rand),
            Tracking::RayMarching => {
                ray_marching_transmittance(segs(), sigma, rand, self.march_step())
            }
            Tracking::UnbiasedRayMarching => {
                unbiased_ray_marching(segs, sigma, rand, self.march_step())
            }
        };
        align(s, start);
        r
    }
}

impl VolumeIntegrator for HeterogeneousInterior<'_> {
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        samplers: &mut [PathSampler],
        _lobes_wanted: LobeSampled,
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
        let m = self.medium;
        let n = rays.len();
        let (p0, g0, m0) = (out.points.len(), out.groups.len(), out.misses.len());
        services.ictx.nearest_hits(rays, out);
        // Each ray's segment in the medium: to its hit, or to where it leaves the grid.
        let mut tmax = rays.tmax.clone();
        for k in p0..out.points.len() {
            let r = out.points.ray_id[k] as usize;
            tmax[r] = tmax[r].min(out.points.vlen[k]);
        }
        let mut scattered = vec![false; n];
        let mut t = vec![0.0f32; n];
        let (mut nulls, mut violations) = (0u64, 0u64);
        let tracking = services.techniques.tracking.unwrap_or(m.tracking);
        let step = self.march_step();
        let emits = m.emits();
        for i in 0..n {
            let (o, d) = self.to_grid(rays.origin[i], rays.direction[i]);
            let s = &mut samplers[i];
            let start = s.dimension;
            let sigma = |t: f32| m.scale * m.density.lookup(o + d * t);
            let f = if emits {
                // pbrt-v4's estimator: j / majorant at every tentative collision (module
                // docs), at the path's weight, which delta tracking keeps at 1.
                let (f, e) = delta_tracking_emitting(
                    self.emissive_segments(o, d, tmax[i]),
                    sigma,
                    |t, sigma_t| self.emission_at(o + d * t, sigma_t),
                    || s.next_1d(),
                );
                out.emitted.push(i as u32, e);
                f
            } else {
                let segs = m
                    .majorants
                    .traverse(o, d, 0.0, tmax[i])
                    .map(|g| g.scaled(m.scale));
                if tracking == Tracking::RayMarching {
                    ray_marching_free_flight(segs, sigma, || s.next_1d(), step)
                } else {
                    delta_tracking(segs, sigma, || s.next_1d())
                }
            };
            align(s, start);
            nulls += f.nulls as u64;
            violations += f.violations as u64;
            scattered[i] = f.collided;
            t[i] = f.t;
        }
        let stats = &mut *services.ictx.stats;
        stats.majorant_violations += violations;
        if emits {
            stats.volume_event(VolumeEvent::Emission, n);
        }
        let events = scattered.iter().filter(|&&s| s).count();
        stats.volume_event(VolumeEvent::Scatter, events);
        stats.volume_event(VolumeEvent::Pass, n - events);
        stats.volume_event(VolumeEvent::Null, nulls as usize);
        if events == 0 {
            return;
        }
        // Passing rays keep their hits (weight 1); the hits and misses of rays that scatter
        // leave.
        let keep: Vec<bool> = (p0..out.points.len())
            .map(|k| !scattered[out.points.ray_id[k] as usize])
            .collect();
        retain_points(out, p0, &keep, g0);
        let mut j = m0;
        for k in m0..out.misses.len() {
            if !scattered[out.misses[k] as usize] {
                out.misses[j] = out.misses[k];
                out.miss_transmission[j] = out.miss_transmission[k];
                j += 1;
            }
        }
        out.misses.truncate(j);
        out.miss_transmission.truncate(j);
        // The scattering points: a volume-sampling context at P = o + t d, weight albedo.
        let own = (self.ctx.num_points() != n).then(|| {
            let mut pts = ShadingPoints::with_capacity(n);
            for i in 0..n {
                let (o, d) = (rays.origin[i], rays.direction[i]);
                pts.push(ShadingPointRow::in_volume(
                    o,
                    d,
                    i as u32,
                    self.ctx.material(),
                ));
            }
            pts
        });
        let own_ctx = own.as_ref().map(|pts| {
            let c = ShadingContext::new(pts, 0..n, ShadingMode::Interior, self.ctx.material(), &[]);
            match self.ctx.volume_bounds() {
                Some((lo, hi)) => c.with_volume_bounds(lo, hi),
                None => c,
            }
        });
        let parent = own_ctx.as_ref().unwrap_or(self.ctx);
        let mut v = parent.begin_volume_sampling();
        let p: Vec<Vec3> = (0..n)
            .map(|i| rays.origin[i] + rays.direction[i] * t[i])
            .collect();
        v.set_builtin(Builtin::P, &p);
        v.set_vlen(&t);
        v.set_transmission(&vec![m.albedo; n]);
        v.end_volume_sampling(&scattered, out);
    }

    fn transmission(
        &self,
        segments: &Segments,
        samplers: &mut [PathSampler],
        ictx: &crate::context::IntegratorContext<'_>,
        trans: &mut [Rgb],
        emission: &mut [Rgb],
    ) {
        let tracking = ictx
            .volume_techniques()
            .tracking
            .unwrap_or(self.medium.tracking);
        if self.medium.emits() {
            for i in 0..segments.len() {
                let (r, e) = self.segment_emission(
                    segments.origin[i],
                    segments.direction[i],
                    segments.length[i],
                    tracking,
                    &mut samplers[i],
                );
                trans[i] = Rgb::splat(r.value);
                ictx.count_majorant_violations(r.violations as u64);
                emission[i] = e;
            }
            return;
        }
        for i in 0..segments.len() {
            let r = self.segment_transmittance(
                segments.origin[i],
                segments.direction[i],
                segments.length[i],
                tracking,
                &mut samplers[i],
            );
            trans[i] = Rgb::splat(r.value);
            ictx.count_majorant_violations(r.violations as u64);
        }
        emission.fill(Rgb::BLACK);
    }
}
