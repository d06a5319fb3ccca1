//! The built-in `subsurface` material: a smooth dielectric boundary over a scattering
//! interior given the way artists give it -- the surface colour (`albedo`, the
//! multiple-scattering albedo) and how far light travels (`mean_free_path`, per
//! `unit_length` world units) -- turned into the coefficients of a homogeneous medium that
//! the random walk ([`crate::media::random_walk`]) runs in (`mode = "random_walk"`), or into the
//! normalized diffusion profile of [`crate::diffusion`] (`mode = "diffusion"`).
//!
//! # From albedo to single-scattering albedo
//! The artist's `albedo` `A` is the fraction of uniform diffuse light that a thick slab of
//! the material reflects: the spherical albedo of a semi-infinite medium. The walk needs the
//! single-scattering albedo `alpha = sigma_s / sigma_t`. They are related through van de
//! Hulst's similarity parameter `s = sqrt((1 - alpha) / (1 - g alpha))` by his asymptotic
//! formula for the spherical albedo of a semi-infinite medium
//! (H. C. van de Hulst, *Multiple Light Scattering*, 1980, vol. 2):
//!
//! `A = (1 - s)(1 - 0.139 s) / (1 + 1.17 s)`,
//!
//! which is a quadratic in `s` with the root in `[0, 1]`
//! `s = (b - sqrt(b^2 - 0.556 (1 - A))) / 0.278`, `b = 1.139 + 1.17 A`; then
//! `alpha = (1 - s^2) / (1 - g s^2)`. It is exact at `A = 0` (`alpha = 0`) and `A = 1`
//! (`alpha = 1`: an albedo-1 material is a white furnace) and, against Chandrasekhar's exact
//! spherical albedo of an index-matched isotropic half-space
//! (`1 - 2 sqrt(1 - alpha) int_0^1 H(mu) mu dmu`, with his H-function), within 0.2 % for
//! `A >= 0.5`, 1 % at `A = 0.2` and 2.4 % at `A = 0.05` (`tests/subsurface.rs` checks this).
//! The same role is played in production by Christensen and Burley's fits (2015) for the
//! diffusion profile and Chiang, Kutz and Burley's (2016, eq. 4) for random walks; the
//! latter is not exact at `A = 1` (it gives `alpha = 0.9989`, and a white material comes out
//! at 0.92), which is why the closed form above is used.
//!
//! # Mean free path
//! `mean_free_path` is the literal mean free path `1 / sigma_t` per channel, in units of
//! `unit_length` world units: `sigma_t = 1 / (mean_free_path * unit_length)`. So
//! `unit_length = 0.01` says "the mean free paths are in centimetres of a scene in metres".
//!
//! # Patterns
//! `albedo` and `mean_free_path` may be pattern graphs of the world position `P`
//! ([`SubsurfacePatterns`]), read at each ray's **entry point** (the start of its segment
//! inside the boundary, where the bundle's shading context sits): every ray then walks in,
//! or diffuses with the profile of, the homogeneous medium of its entry point's values, as
//! if the material were that constant there. Light entering a region of another colour
//! keeps its entry colour until it leaves (or reflects back in off the boundary, where it
//! reads the values again): the usual treatment of textured subsurface albedo (the seed's
//! SSDiffusion evaluates its parameters at the entry point's context too). Medium patterns
//! see `P` only (`u`, `v` belong to surfaces).

use crate::media::{HomogeneousMedium, Scattering};
use glam::Vec3;
use risotto_components::Rgb;
use risotto_engine::plugin::{Technique, TechniqueValue};
use risotto_systems::pattern::{self, PatternGraph};
use risotto_systems::phase::PhaseFunction;
use std::sync::Arc;

/// How the `subsurface` material's interior is integrated (scene files:
/// `mode = "random_walk" | "diffusion"`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SubsurfaceMode {
    /// A path-traced walk inside the boundary ([`crate::media::random_walk`]).
    #[default]
    RandomWalk,
    /// Christensen-Burley normalized diffusion with probe rays ([`crate::diffusion`]).
    Diffusion,
}

impl SubsurfaceMode {
    /// The name the scene file (`mode`) and the [`SUBSURFACE`] technique use.
    pub fn name(self) -> &'static str {
        match self {
            SubsurfaceMode::RandomWalk => "random_walk",
            SubsurfaceMode::Diffusion => "diffusion",
        }
    }

    /// The mode named `name`.
    pub fn from_name(name: &str) -> Option<SubsurfaceMode> {
        [SubsurfaceMode::RandomWalk, SubsurfaceMode::Diffusion]
            .into_iter()
            .find(|m| m.name() == name)
    }
}

/// The `subsurface` technique the `subsurface` material declares: random walk or diffusion
/// for every subsurface material, over what each one's `mode` says.
pub static SUBSURFACE: Technique = Technique {
    name: "subsurface",
    summary: "random walk or diffusion in subsurface materials",
    values: &[
        TechniqueValue {
            name: "scene",
            summary: "as each subsurface material's `mode` says",
            converges: risotto_engine::technique::always,
        },
        TechniqueValue {
            name: "random_walk",
            summary: "walk every path inside the boundary (exact)",
            converges: risotto_engine::technique::always,
        },
        TechniqueValue {
            name: "diffusion",
            summary: "normalized diffusion with probe rays (fast, approximate)",
            converges: risotto_engine::technique::never,
        },
    ],
    default: "scene",
    applies_to: "scenes with subsurface materials",
};

/// The `subsurface` material's parameters, as the scene file gives them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SubsurfaceParams {
    /// Index of refraction of the interior relative to the outside.
    pub ior: f32,
    /// Multiple-scattering albedo (the surface colour), per channel in [0, 1].
    pub albedo: Rgb,
    /// Mean free path `1 / sigma_t` per channel, in `unit_length` units, > 0.
    pub mean_free_path: Rgb,
    /// World units per unit of `mean_free_path`, > 0.
    pub unit_length: f32,
    /// Henyey-Greenstein mean cosine, in (-1, 1).
    pub g: f32,
    /// Integration mode.
    pub mode: SubsurfaceMode,
}

/// The single-scattering albedo whose semi-infinite medium has spherical albedo `a`
/// (van de Hulst's relation inverted, see the module docs), for HG mean cosine `g`.
pub fn single_scattering_albedo(a: f32, g: f32) -> f32 {
    let a = a.clamp(0.0, 1.0) as f64;
    let g = g as f64;
    let b = 1.139 + 1.17 * a;
    let disc = (b * b - 0.556 * (1.0 - a)).max(0.0);
    let s = ((b - disc.sqrt()) / 0.278).clamp(0.0, 1.0);
    let s2 = s * s;
    ((1.0 - s2) / (1.0 - g * s2)).clamp(0.0, 1.0) as f32
}

/// Van de Hulst's spherical albedo of a semi-infinite medium of single-scattering albedo
/// `alpha` and HG mean cosine `g`: `(1 - s)(1 - 0.139 s) / (1 + 1.17 s)`,
/// `s = sqrt((1 - alpha) / (1 - g alpha))` (the forward relation of
/// [`single_scattering_albedo`]).
pub fn spherical_albedo(alpha: f32, g: f32) -> f32 {
    let (alpha, g) = (alpha.clamp(0.0, 1.0) as f64, g as f64);
    let s = ((1.0 - alpha) / (1.0 - g * alpha)).max(0.0).sqrt();
    ((1.0 - s) * (1.0 - 0.139 * s) / (1.0 + 1.17 * s)) as f32
}

impl SubsurfaceParams {
    /// The homogeneous medium of these parameters: `sigma_t = 1 / (mean_free_path *
    /// unit_length)`, `sigma_s = alpha sigma_t` with `alpha` from
    /// [`single_scattering_albedo`], HG phase with `g`, walked.
    pub fn medium(&self) -> HomogeneousMedium {
        let sigma_t = self.mean_free_path.map(|l| 1.0 / (l * self.unit_length));
        let alpha = self.albedo.map(|a| single_scattering_albedo(a, self.g));
        let phase = if self.g == 0.0 {
            PhaseFunction::Isotropic
        } else {
            PhaseFunction::HenyeyGreenstein { g: self.g }
        };
        HomogeneousMedium {
            sigma_t,
            sigma_s: sigma_t * alpha,
            phase,
            scattering: Scattering::Walk,
            emission: Rgb::BLACK,
            albedo_pattern: None,
            g_pattern: None,
        }
    }

    /// The diffusion mode's medium: the albedo as given and Burley's shape
    /// `d = mean_free_path * unit_length / s(A)` ([`risotto_systems::bssrdf::scaling`]).
    pub fn diffusion(&self) -> crate::diffusion::DiffusionMedium {
        let l = self.mean_free_path * self.unit_length;
        crate::diffusion::DiffusionMedium {
            albedo: self.albedo,
            d: Rgb::new(
                l.r / risotto_systems::bssrdf::scaling(self.albedo.r),
                l.g / risotto_systems::bssrdf::scaling(self.albedo.g),
                l.b / risotto_systems::bssrdf::scaling(self.albedo.b),
            ),
            slab_scattering: self.slab_scattering(),
            sigma_t: l.map(|l| 1.0 / l),
            exact_counts: true,
        }
    }

    /// The two-flux scattering coefficient of the diffusion mode's thin-layer split, per
    /// world unit: `S = (3/4) sigma_s (1 - g)`, three quarters of the reduced scattering
    /// coefficient of the walked medium ([`Self::medium`]), the diffusion-theory value of
    /// Kubelka-Munk's `S` (W. M. Star, J. P. A. Marijnissen and M. J. C. van Gemert, "Light
    /// dosimetry in optical phantoms and in tissues: I. Multiple flux and transport theory",
    /// Phys. Med. Biol. 33, 1988: `S = (3/4) sigma_s' - (1/4) sigma_a`, whose absorption
    /// part is left to `R_inf = A` here).
    pub fn slab_scattering(&self) -> Rgb {
        let walk = self.medium();
        walk.sigma_s * (0.75 * (1.0 - self.g))
    }
}

/// What a `subsurface` material's interior is built from: both modes' media (the render's
/// `subsurface` technique may pick either) and the material's mode.
#[derive(Clone, Debug, PartialEq)]
pub struct SubsurfaceInteriorParams {
    /// The walked medium (`mode = "random_walk"`).
    pub walk: HomogeneousMedium,
    /// The diffusion profile (`mode = "diffusion"`).
    pub diffusion: crate::diffusion::DiffusionMedium,
    /// The material's mode.
    pub mode: SubsurfaceMode,
    /// The parameters with their patterns, when `albedo` or `mean_free_path` is one (the
    /// media above are then those of the constant parameters, used by no ray).
    pub patterned: Option<Arc<PatternedSubsurface>>,
}

/// A `subsurface` material's pattern parameters, each a pattern graph of the world
/// position read at the entry points (see the module docs); `None`: the constant.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SubsurfacePatterns {
    /// Multiple-scattering albedo, every channel in `[0, 1]` by the graph's bounds.
    pub albedo: Option<Arc<PatternGraph>>,
    /// Mean free path in `unit_length` units, every channel > 0 by the graph's bounds.
    pub mean_free_path: Option<Arc<PatternGraph>>,
}

impl SubsurfacePatterns {
    /// Whether neither parameter is a pattern.
    pub fn is_empty(&self) -> bool {
        self.albedo.is_none() && self.mean_free_path.is_none()
    }
}

/// A `subsurface` material's constant parameters and its patterns.
#[derive(Clone, Debug, PartialEq)]
pub struct PatternedSubsurface {
    /// The constants (`albedo` and `mean_free_path` where no pattern gives them).
    pub params: SubsurfaceParams,
    /// The patterns.
    pub patterns: SubsurfacePatterns,
}

impl PatternedSubsurface {
    /// The constant parameters at each world point of `p`, and the pattern evaluations made
    /// (one per point and pattern).
    pub fn at(&self, p: &[Vec3]) -> (Vec<SubsurfaceParams>, u64) {
        let n = p.len();
        let zeros = vec![0.0f32; n];
        let mut evals = 0u64;
        let mut column = |graph: Option<&Arc<PatternGraph>>, constant: Rgb| -> Vec<Rgb> {
            let mut out = vec![constant; n];
            if let Some(g) = graph {
                pattern::eval(g, p, &zeros, &zeros, &mut out);
                evals += n as u64;
            }
            out
        };
        let albedo = column(self.patterns.albedo.as_ref(), self.params.albedo);
        let mfp = column(
            self.patterns.mean_free_path.as_ref(),
            self.params.mean_free_path,
        );
        let params = (0..n)
            .map(|i| SubsurfaceParams {
                // Within the load-time bounds up to rounding.
                albedo: albedo[i].map(|a| a.clamp(0.0, 1.0)),
                mean_free_path: mfp[i].map(|l| l.max(f32::MIN_POSITIVE)),
                ..self.params
            })
            .collect();
        (params, evals)
    }
}

/// The `subsurface` material's volume integrator: the walk or diffusion, as the render's
/// `subsurface` technique or else the material says.
pub struct SubsurfaceInterior<'a> {
    /// The walk (a homogeneous interior that walks).
    pub walk: crate::media::HomogeneousInterior<'a>,
    /// Diffusion.
    pub diffusion: crate::diffusion::DiffusionInterior,
    /// The material's mode.
    pub mode: SubsurfaceMode,
    /// The patterned parameters, if any ([`SubsurfaceInteriorParams::patterned`]).
    pub patterned: Option<&'a PatternedSubsurface>,
}

impl risotto_engine::plugin::VolumeIntegrator for SubsurfaceInterior<'_> {
    fn nearest_hits(
        &mut self,
        rays: &risotto_components::Rays,
        samplers: &mut [risotto_systems::sampler::PathSampler],
        lobes_wanted: risotto_components::LobeSampled,
        services: risotto_engine::plugin::VolumeServices<'_, '_>,
        out: &mut risotto_engine::plugin::ShadeGroups,
    ) {
        let mode = services
            .ictx
            .technique(SUBSURFACE.name)
            .and_then(SubsurfaceMode::from_name)
            .unwrap_or(self.mode);
        if let Some(patterned) = self.patterned {
            // Every ray in the medium of its entry point's values (module docs).
            let (params, evals) = patterned.at(&rays.origin);
            self.walk.ctx.count_pattern_evals(evals);
            match mode {
                SubsurfaceMode::RandomWalk => {
                    let per_ray: Vec<(Rgb, Rgb)> = params
                        .iter()
                        .map(|p| {
                            let m = p.medium();
                            (m.sigma_t, m.sigma_s)
                        })
                        .collect();
                    crate::media::random_walk::walk_bundle_per_ray(
                        self.walk.medium,
                        &per_ray,
                        rays,
                        samplers,
                        services.ictx,
                        out,
                    );
                }
                SubsurfaceMode::Diffusion => {
                    let per_ray: Vec<_> = params.iter().map(|p| p.diffusion()).collect();
                    self.diffusion
                        .diffuse(Some(&per_ray), rays, samplers, services.ictx, out);
                }
            }
            return;
        }
        match mode {
            SubsurfaceMode::RandomWalk => {
                self.walk
                    .nearest_hits(rays, samplers, lobes_wanted, services, out)
            }
            SubsurfaceMode::Diffusion => {
                self.diffusion
                    .nearest_hits(rays, samplers, lobes_wanted, services, out)
            }
        }
    }

    fn transmission(
        &self,
        segments: &risotto_engine::plugin::Segments,
        samplers: &mut [risotto_systems::sampler::PathSampler],
        ictx: &dyn risotto_engine::plugin::IntegratorContext,
        trans: &mut [Rgb],
        emission: &mut [Rgb],
    ) {
        if let Some(patterned) = self.patterned {
            // The extinction of each segment's start (a dielectric boundary lets no shadow
            // ray in; this serves integrators that trace their own segments inside).
            let (params, evals) = patterned.at(&segments.origin);
            self.walk.ctx.count_pattern_evals(evals);
            for (i, p) in params.iter().enumerate() {
                let sigma_t = p.medium().sigma_t;
                trans[i] = risotto_systems::medium::transmittance(sigma_t, segments.length[i]);
            }
            emission.fill(Rgb::BLACK);
            return;
        }
        self.walk
            .transmission(segments, samplers, ictx, trans, emission)
    }
}
