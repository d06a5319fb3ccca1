//! The heterogeneous scattering medium: extinction `sigma_t(p) = scale * density(p)` (per
//! channel: `scale` may be a colour) from a density grid placed in the shape's bounds, a
//! constant single-scattering albedo and a phase function (scene files: `interior = { type = "heterogeneous", ... }`,
//! `docs/scene-format.md`).
//!
//! # Pattern coefficients
//! `density` and `emission` may be pattern graphs ([`PatternField`], `field.rs`) of the
//! **world-space position `P`** (the `P` surface patterns see; `u`, `v` are refused inside a
//! medium). A density pattern is grey (one density) or a colour graph (a density per
//! channel, see Per-channel density), bounded in `[0, inf)` with a finite upper bound,
//! checked with the graph's interval bounds at load time. It is evaluated one point per
//! tentative collision (the trackers ask for one point at a time) and counted in the
//! stats' `pattern_evals`. Its majorant grid holds, per cell, the graph's interval bounds
//! over the cell's world box ([`risotto_systems::pattern::bounds`]; Lipschitz bounds for
//! `noise`): built per shape on first use, since the shape's bounds are known only after
//! the scene is compiled.
//!
//! # Estimators
//! - **Free flights** ([`HeterogeneousInterior::nearest_hits`]): delta tracking (Woodcock)
//!   against the **majorant grid** ([`MajorantGrid`], `majorant_grid` cells per axis, 16 by
//!   default; 1 = one global majorant as in Mitsuba), traversed with a 3D DDA so that each
//!   tentative collision is sampled from its own cell's bound (spectral tracking for a
//!   chromatic scale, see Spectral handling). A real collision scatters
//!   with weight `albedo` (`sigma_s / sigma_t`, the same convention as the homogeneous
//!   medium's [`FreeFlight`](risotto_systems::medium::FreeFlight) weight); the points go to
//!   the global integrator as a [`ShadingMode::VolumeScatter`] group (multiple scattering;
//!   with or without a lighting delegate). Null collisions are counted as
//!   [`VolumeEvent::Null`].
//! - **Transmittance** ([`HeterogeneousInterior::transmission`]): `tracking` chooses ratio
//!   tracking (default), residual ratio tracking (the majorant grid's per-cell minimum as the
//!   control), delta tracking (0 or 1), fixed-step ray marching or the unbiased ray-marching
//!   estimator ([`risotto_systems::ray_marching`]); `ray_marching` also marches the free
//!   flights. The render's [`TRACKING`] technique overrides the medium's choice.
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
//! The albedo may be a colour, and so may the density `scale`.
//! - **Grey scale** (one `sigma_t` for R, G and B): every channel shares the free-flight
//!   distribution, so the estimators' weights are `albedo` at a collision and 1 on passing:
//!   bounded, and no colour noise.
//! - **Chromatic scale** (`scale = [r, g, b]`): `sigma_t,c = k_c * max(scale) * density`,
//!   `k = scale / max(scale)`, and every estimator tracks against one **grey majorant**,
//!   the largest channel of the scale times the majorant grid's cell bound
//!   ([`risotto_systems::spectral_tracking`]). Free flights use **spectral tracking with
//!   one-sample spectral MIS** (Miller, Georgiev and Jarosz 2019, sec. 5; Mitsuba 3's
//!   `volpathmis`): channel probabilities in proportion to the ray's throughput (as the
//!   homogeneous medium's [`channel_pdf`](risotto_systems::medium::channel_pdf)), each
//!   tentative collision real with the channel-weighted probability, and the flight's
//!   per-channel weight `f_c / p` (at most `1 / p_c`) multiplies the passing ray's hit or the
//!   scattering point's `albedo`. Emission is gathered at that running weight. Ray-marched
//!   free flights are grey only: with `tracking = "ray_marching"` a chromatic medium still
//!   tracks its free flights (and marches its shadow rays). Shadow rays: ratio and residual
//!   ratio tracking with one sequence of tentative collisions and three running products,
//!   delta tracking as a spectral-MIS flight's pass weight (equal channel probabilities:
//!   each channel unbiased, at most 3), and the marching estimators on one shared march per
//!   channel. A grey scale keeps exactly the grey estimators (the same random numbers and
//!   images).
//!
//! # Per-channel density
//! A 3-channel density grid ([`DensityChannels`], `density_channels`) gives
//! `sigma_t,c(p) = scale_c density_c(p)`: the channels' ratios vary in space, so the medium
//! is tracked as chromatic whatever its scale, by the same spectral estimators written
//! against a per-point split ([`risotto_systems::spectral_tracking::PerChannel`]:
//! `sigma = max_c sigma_t,c`, `k(t) = sigma_t(t) / sigma`). The existing trackers expect
//! one grey majorant per segment, so the majorant grid holds, per cell, the largest
//! channel's **extinction** bound (scale included; [`DensityChannels::majorants`]) and the
//! smallest channel's lower bound, which is then every channel's residual-tracking control
//! (a per-channel majorant would need three sequences of tentative collisions, and lose
//! the shared one spectral MIS is built on). A medium with one density channel never enters
//! these paths.
//!
//! A **colour density pattern** is the same per point (`sigma_t,c = scale_c P_c(P)`, the
//! graph's channels): the same estimators, its majorant cells from the graph's interval
//! bounds weighted per channel by `scale / max(scale)` ([`PatternField`]), so that they are
//! the largest channel's extinction bound over `max(scale)` and the smallest channel's low
//! end, as a 3-channel grid's. Its emission cannot follow the density (there is no one
//! density to follow): an emission pattern says what it is.
//!
//! # Files
//! `interior.rs` is the volume integrator (free flights, transmittance, emission), `field.rs`
//! the density and emission fields, `emitter.rs` the medium as a light; this file holds the
//! medium's parameters. The scene loader reads them from a scene table
//! (`risotto-loader`'s `media_params::heterogeneous`).

mod emitter;
mod field;
mod interior;

pub use field::PatternField;
pub use interior::HeterogeneousInterior;

use crate::phase::PhaseBxdf;
use risotto_components::Rgb;
use risotto_engine::plugin::{Technique, TechniqueValue};
use risotto_systems::grid::{DensityChannels, DensityGrid, MajorantGrid};
use risotto_systems::phase::PhaseFunction;
use std::sync::Arc;
#[cfg(doc)]
use {
    risotto_engine::plugin::{ShadingMode, VolumeIntegrator},
    risotto_engine::stats::VolumeEvent,
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

/// The `tracking` technique every heterogeneous medium declares: the free-flight and
/// transmittance estimators, over what each medium's `tracking` says.
pub static TRACKING: Technique = Technique {
    name: "tracking",
    summary: "free-flight and transmittance estimators in heterogeneous media",
    values: &[
        TechniqueValue {
            name: "scene",
            summary: "as each heterogeneous medium's `tracking` says",
            converges: risotto_engine::technique::always,
        },
        TechniqueValue {
            name: "ratio",
            summary: "ratio tracking for shadow rays (Novak et al. 2014); delta-tracked flights",
            converges: risotto_engine::technique::always,
        },
        TechniqueValue {
            name: "residual",
            summary: "residual ratio tracking, each majorant cell's minimum as control",
            converges: risotto_engine::technique::always,
        },
        TechniqueValue {
            name: "delta",
            summary: "delta tracking for shadow rays too (0 or 1)",
            converges: risotto_engine::technique::always,
        },
        TechniqueValue {
            name: "ray_marching",
            summary: "fixed-step ray marching of flights and shadow rays (biased)",
            converges: risotto_engine::technique::never,
        },
        TechniqueValue {
            name: "unbiased_ray_marching",
            summary: "power series around a marched pivot for shadow rays (Kettunen et al. 2021)",
            converges: risotto_engine::technique::always,
        },
    ],
    default: "scene",
    applies_to: "scenes with heterogeneous media",
};

/// Default majorant-grid cells per axis.
pub const DEFAULT_MAJORANT_CELLS: usize = 16;

/// A heterogeneous medium's parameters (shared by every integrator built for it).
#[derive(Clone, Debug, PartialEq)]
pub struct HeterogeneousMedium {
    /// The density field over the unit cube of the shape's bounds (for a pattern density, a
    /// one-voxel grid holding the pattern's global upper bound).
    pub density: Arc<DensityGrid>,
    /// Bounds of `density` over coarse cells (density units); for a pattern density, one
    /// global cell (the per-shape grids are the pattern's, [`PatternField::majorants`]).
    pub majorants: Arc<MajorantGrid>,
    /// A density per channel (a 3-channel grid, `density = { grid = "rgb.vol" }`):
    /// `sigma_t,c = scale_c density_c`, tracked by the per-channel spectral estimators
    /// against one grey majorant (module docs, Per-channel density). `density` then holds
    /// the per-voxel largest channel and `majorants` the **extinction** bounds over the
    /// channels ([`DensityChannels::majorants`], already scaled: [`Self::majorant_scale`]
    /// is 1). `None` (the default): one density.
    pub density_channels: Option<Arc<DensityChannels>>,
    /// A density given by a pattern of the world position instead of `density`'s grid
    /// (`density = { pattern = .. }`): grey, or a colour graph, one density per channel
    /// (module docs, Per-channel density); `None` (the default): the grid.
    pub density_pattern: Option<Arc<PatternField>>,
    /// `sigma_t = scale * density` per channel, per world unit, >= 0 (grey: the same in
    /// every channel; chromatic: spectral tracking, see the module docs).
    pub scale: Rgb,
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
    /// A diagnostic, not a scene key: `Some(c)` makes a chromatic medium's free flights
    /// track channel `c` alone (channel probabilities one-hot) instead of spectral MIS over
    /// the throughput. Unbiased when the tracked channel's null-collision probability is
    /// positive wherever another channel's is (e.g. it is the thinnest channel), but the
    /// other channels' weights grow without bound (`(k_c / k_hero)^n` after `n` scattering
    /// events): the fireflies spectral MIS removes, for tests that compare the two. `None`
    /// (the default): spectral MIS.
    pub single_channel: Option<usize>,
    /// The albedo as a pattern of the world position (`albedo = { pattern = .. }`, every
    /// channel in `[0, 1]` by its interval bounds), evaluated at each scattering point; the
    /// constant `albedo` is then unused (1) except by the albedo AOV. `None`: `albedo`.
    pub albedo_pattern: Option<Arc<risotto_systems::pattern::PatternGraph>>,
    /// The Henyey-Greenstein `g` as a grey pattern of the world position (within `(-1, 1)`),
    /// read by the phase Bxdf at each scattering point through the context's cache
    /// ([`crate::scatter_patterns`]); `phase` is then HG. `None`: `phase` alone.
    pub g_pattern: Option<Arc<risotto_systems::pattern::PatternGraph>>,
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
    /// `j(p) = pattern(P)`: a pattern of the world position (colour-valued, >= 0), with
    /// majorant grids of the density's resolution from its interval bounds, which say where
    /// the medium emits.
    Pattern(Arc<PatternField>),
}

pub use crate::media::emission::{emission_floor, EMISSION_COLLISIONS_PER_CELL};

impl HeterogeneousMedium {
    /// A medium over `density` (moved in, or an `Arc` shared with other media naming the
    /// same file) with a majorant grid of `majorant_cells` per axis (clamped to
    /// `[1, voxels]` per axis) and a grey `scale` ([`HeterogeneousMedium::with_scale`] makes
    /// it chromatic).
    pub fn new(
        density: impl Into<Arc<DensityGrid>>,
        majorant_cells: usize,
        scale: f32,
        albedo: Rgb,
        phase: PhaseFunction,
        tracking: Tracking,
    ) -> Self {
        let density = density.into();
        let res = density.dims().map(|n| majorant_cells.clamp(1, n));
        let majorants = MajorantGrid::new(&density, res);
        HeterogeneousMedium {
            density,
            majorants: Arc::new(majorants),
            scale: Rgb::splat(scale),
            albedo,
            phase,
            tracking,
            march_step: None,
            emission: None,
            single_channel: None,
            density_channels: None,
            density_pattern: None,
            albedo_pattern: None,
            g_pattern: None,
        }
    }

    /// The medium with the pattern `graph` of the world position as its density (replacing
    /// the grid; a colour graph is a density per channel, module docs), with majorant grids
    /// of `majorant_cells` per axis (at least 1) from the graph's interval bounds. `graph`
    /// must be bounded in `[0, inf)` in every channel with a finite upper bound (the scene
    /// reader checks both with located errors).
    pub fn with_density_pattern(
        self,
        graph: risotto_systems::pattern::PatternGraph,
        majorant_cells: usize,
    ) -> Self {
        // A colour graph is a density per channel (module docs, Per-channel density).
        let weights = (!graph.is_grey()).then(|| self.pattern_channel_weights());
        let field =
            PatternField::new(graph, [majorant_cells.max(1); 3]).with_channel_weights(weights);
        self.with_pattern_field(field)
    }

    /// The medium over the density pattern `field` (its one-voxel `density` grid and global
    /// majorant cell holding the field's global upper bound).
    fn with_pattern_field(self, field: PatternField) -> Self {
        let max = field.global_bounds().1.max(0.0);
        let grid = DensityGrid::constant([1, 1, 1], if max.is_finite() { max } else { 0.0 })
            .expect("a finite, non-negative constant");
        let majorants = MajorantGrid::global(&grid);
        HeterogeneousMedium {
            density: Arc::new(grid),
            majorants: Arc::new(majorants),
            density_pattern: Some(Arc::new(field)),
            ..self
        }
    }

    /// The medium over the per-channel density `channels` (replacing the grid:
    /// `sigma_t,c = scale_c density_c`), with a majorant grid of `majorant_cells` per axis
    /// (clamped to `[1, voxels]`) bounding the largest channel's extinction from above and
    /// the smallest's from below. [`Self::with_scale`] rebuilds it for a new scale.
    pub fn with_density_channels(self, channels: DensityChannels, majorant_cells: usize) -> Self {
        let dims = channels.dims();
        let n: usize = dims.iter().product();
        let max: Vec<f32> = (0..n)
            .map(|i| {
                (0..3)
                    .map(|c| {
                        let [x, y, z] = risotto_systems::grid::voxel_of(dims, i);
                        channels.channel(c).voxel(x, y, z)
                    })
                    .fold(0.0, f32::max)
            })
            .collect();
        let res = dims.map(|n| majorant_cells.clamp(1, n));
        let majorants = channels.majorants(self.scale, res);
        HeterogeneousMedium {
            density: Arc::new(DensityGrid::new(dims, max).expect("the channels' own dims")),
            majorants: Arc::new(majorants),
            density_channels: Some(Arc::new(channels)),
            density_pattern: None,
            ..self
        }
    }

    /// The weights of a per-channel density pattern's bounds: `scale / max(scale)` (white for
    /// a black scale), so that `max(scale)` times a weighted bound bounds every channel's
    /// extinction ([`PatternField::with_channel_weights`]).
    fn pattern_channel_weights(&self) -> Rgb {
        let s = self.max_scale();
        if s > 0.0 {
            self.scale * (1.0 / s)
        } else {
            Rgb::WHITE
        }
    }

    /// Whether the density is one per channel, a 3-channel grid or a colour pattern: the
    /// medium is then tracked by the per-channel spectral estimators (module docs).
    pub fn per_channel_density(&self) -> bool {
        self.density_channels.is_some()
            || self
                .density_pattern
                .as_ref()
                .is_some_and(|p| p.channel_weights.is_some())
    }

    /// The factor from the majorant grid's bounds to extinction bounds: the densest
    /// channel's scale for one density, 1 for a per-channel density (whose majorant grid
    /// is already in extinction units).
    pub fn majorant_scale(&self) -> f32 {
        if self.density_channels.is_some() {
            1.0
        } else {
            self.max_scale()
        }
    }

    /// The majorant cells per axis of the medium's density (the grid's or the pattern's).
    pub fn majorant_res(&self) -> [usize; 3] {
        match &self.density_pattern {
            Some(p) => p.res,
            None => self.majorants.res(),
        }
    }

    /// The medium emitting the pattern `graph` of the world position as its emission
    /// coefficient (`graph` bounded in `[0, inf)` per channel; checked by the reader).
    pub fn with_emission_pattern(mut self, graph: risotto_systems::pattern::PatternGraph) -> Self {
        let field = PatternField::new(graph, self.majorant_res());
        let emits = field.global_bounds().1 > 0.0;
        self.emission = emits.then(|| HeterogeneousEmission::Pattern(Arc::new(field)));
        self
    }

    /// The medium with the density scale `scale` per channel (`sigma_t,c = scale_c *
    /// density`).
    pub fn with_scale(mut self, scale: Rgb) -> Self {
        self.scale = scale;
        if let Some(c) = &self.density_channels {
            self.majorants = Arc::new(c.majorants(scale, self.majorants.res()));
        }
        if let Some(p) = self.density_pattern.clone() {
            if p.channel_weights.is_some() {
                let weights = Some(self.pattern_channel_weights());
                let field =
                    PatternField::shared(p.graph.clone(), p.res).with_channel_weights(weights);
                return self.with_pattern_field(field);
            }
        }
        self
    }

    /// The extinction scale of the densest channel: the grey majorant is this times the
    /// majorant grid's density bound (for a grey scale, the scale itself).
    pub fn max_scale(&self) -> f32 {
        self.scale.max_channel()
    }

    /// `k = scale / max_scale` (every channel in `[0, 1]`, `(1, 1, 1)` for a grey or zero
    /// scale): `sigma_t,c = k_c * max_scale * density`
    /// ([`risotto_systems::spectral_tracking`]'s convention).
    pub fn channel_ratios(&self) -> Rgb {
        let s = self.max_scale();
        if self.is_chromatic() {
            self.scale * (1.0 / s)
        } else {
            Rgb::WHITE
        }
    }

    /// Whether the channels' scales differ (spectral tracking), rather than one grey scale.
    pub fn is_chromatic(&self) -> bool {
        let c = self.scale;
        !(c.r == c.g && c.g == c.b) && c.max_channel() > 0.0
    }

    /// The medium emitting `j(p) = colour * density(p)` (black: no emission).
    pub fn with_emission_following_density(mut self, colour: Rgb) -> Self {
        self.emission =
            (!colour.is_black()).then_some(HeterogeneousEmission::FollowsDensity(colour));
        self
    }

    /// The medium emitting `j(p) = scale * grid(p)`, `grid` placed like the density (a
    /// black `scale` or an all-zero grid: no emission).
    pub fn with_emission_grid(mut self, grid: impl Into<Arc<DensityGrid>>, scale: Rgb) -> Self {
        let grid = grid.into();
        self.emission = (!scale.is_black() && grid.max() > 0.0).then(|| {
            let majorants = MajorantGrid::new(&grid, self.majorant_res());
            HeterogeneousEmission::Grid {
                grid,
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
    pub fn phase_bxdf(&self) -> PhaseBxdf<'static> {
        PhaseBxdf::new(self.phase, self.albedo)
    }
}
