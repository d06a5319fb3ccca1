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

//!
//! # Files
//! `parse.rs` reads the scene table, `interior.rs` is the volume integrator (free flights,
//! transmittance, emission); this file holds the medium's parameters.

mod interior;
mod parse;

pub use interior::HeterogeneousInterior;
pub(crate) use parse::parse;

use crate::media::PhaseBxdf;
use risotto_components::Rgb;
use risotto_systems::grid::{DensityGrid, MajorantGrid};
use risotto_systems::phase::PhaseFunction;
use std::sync::Arc;
#[cfg(doc)]
use {
    crate::plugin::{ShadingMode, VolumeIntegrator, VolumeTechniques},
    crate::stats::VolumeEvent,
    risotto_systems::tracking::{delta_tracking_emitting, ratio_tracking_emitting},
};

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
