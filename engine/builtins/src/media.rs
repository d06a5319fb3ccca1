//! Built-in scattering media: phase functions as Bxdfs and the homogeneous volume integrator
//! (the seed's "Shading in a Volume", "Single Scattering" and "Multiple Scattering").
//!
//! # Conventions
//! Coefficients are per world unit, per RGB channel: `sigma_t = sigma_a + sigma_s` and
//! `albedo = sigma_s / sigma_t`. A phase function is normalised over the sphere; its Bxdf's
//! sample weight is `p / pdf = 1` and its value `p`: the single-scattering albedo (`sigma_s`)
//! is part of the free-flight weight the volume integrator writes into the point's
//! transmission ([`risotto_systems::medium::FreeFlight::weight`]), never of the phase
//! function.
//!
//! # Multiple scattering
//! [`HomogeneousInterior::nearest_hits`] traces the bundle's rays to the volume's boundary
//! (or whatever surface lies inside), samples one free flight per ray with one-sample
//! spectral MIS over the RGB channels (Miller, Georgiev and Jarosz 2019; Mitsuba 3's
//! `volpathmis`; channel probabilities in proportion to the ray's throughput), and returns the
//! rays that stop inside as a [`ShadingMode::VolumeScatter`] group (the path tracer then lights
//! and scatters them like surface points, with the phase function as Bxdf) and the others'
//! hits with the pass-through weight.
//!
//! # Single scattering
//! With a lighting delegate, each ray's in-scattered light on its segment `[0, tmax]` is
//! estimated at two points, one per technique: a free-flight distance and, where the scene has
//! point or spot lights, an equiangular sample towards one of them (Kulla and Fajardo 2012), each
//! weighted by the balance heuristic over both (Veach 1997, eq. 9.10 with one sample per
//! technique: `f(t) / (pdf_distance(t) + pdf_equiangular(t))`). The delegate lights them; the
//! ray goes on to its hit with the exact transmittance. Without a delegate (an integrator
//! that offers none, like PxrVCM, or `--lighting bxdf`) the medium scatters as in multiple
//! scattering: the seed's "the only way to perform volume scattering for integrators that do
//! not provide a lighting delegate".
//!
//! # Emission
//! A medium with an `emission` coefficient `j` (radiance per unit length, the source term of
//! `dL/ds = -sigma_t L + j + sigma_s (phase x L_in)`) reports, for every ray it answers,
//! the exact integral of its emission over the ray's segment to the surface ahead,
//! `j (1 - exp(-sigma_t t)) / sigma_t` per channel
//! ([`emitted_radiance`]), in
//! [`ShadeGroups::emitted`]; the random walk adds the same integral for each of its steps
//! ([`crate::media::random_walk`]). The segment's radiance is that emission plus what the free flight
//! estimates (the in-scattered light at the event, or the radiance beyond the segment),
//! so adding the exact part is unbiased, costs no variance and needs no change to the
//! spectral-MIS weights of the flight. Shadow segments get the same integral from
//! [`HomogeneousInterior::transmission`]. In single scattering the emission along the ray
//! is exact too; the light the medium emits is not scattered again there (single
//! scattering is of the scene's lights).
//!
//! # Files
//! This file holds the phase Bxdfs, the medium's parameters and the multiple-scattering
//! integrator; `media/single.rs` the single-scattering estimator.

pub mod emission;
pub mod random_walk;
mod single;

use crate::scatter_patterns::scale_by_albedo;
use bumpalo::Bump;
use emission::emission_along;
use glam::Vec3;
use risotto_components::{LobeSampled, Rays, Rgb, ShadingPoints};
use risotto_engine::plugin::*;
use risotto_engine::technique;
use risotto_systems::lights::Light;
use risotto_systems::medium::{
    channel_pdf, emitted_radiance, equiangular_pdf, equiangular_sample, flights_frozen,
    flights_may_freeze, free_flight_pdf, sample_free_flight, transmittance,
};
use risotto_systems::pattern::PatternGraph;
use risotto_systems::phase::PhaseFunction;
use risotto_systems::ray::{before_hit, coordinate_epsilon};
use risotto_systems::sampler::{next_4d_column, PathSampler};
use std::sync::Arc;

/// How a homogeneous medium scatters (scene files:
/// `scattering = "multiple" | "walk" | "bounce" | "single"`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Scattering {
    /// Every order of scattering, by whichever of [`Walk`](Self::Walk) and
    /// [`Bounce`](Self::Bounce) suits the volume: the walk where light sampling at the
    /// medium's events cannot succeed (the boundary blocks shadow rays and no point light
    /// lies inside the volume's bounds), else bounces.
    #[default]
    Multiple,
    /// Every order, walked inside the volume integrator ([`crate::media::random_walk`]): only the
    /// walks' exits go back to the global integrator; no light sampling at the events.
    Walk,
    /// Every order: each scattering point goes back to the global integrator, which lights
    /// and scatters it like a surface point (one global bounce per event).
    Bounce,
    /// Single scattering through the lighting delegate (multiple without one).
    Single,
}

impl Scattering {
    /// Every value, in the order of the [`SCATTERING`] technique's values.
    pub const ALL: [Scattering; 4] = [
        Scattering::Multiple,
        Scattering::Walk,
        Scattering::Bounce,
        Scattering::Single,
    ];

    /// The name the scene file and the [`SCATTERING`] technique use.
    pub fn name(self) -> &'static str {
        match self {
            Scattering::Multiple => "multiple",
            Scattering::Walk => "walk",
            Scattering::Bounce => "bounce",
            Scattering::Single => "single",
        }
    }

    /// The value named `name`.
    pub fn from_name(name: &str) -> Option<Scattering> {
        Scattering::ALL.into_iter().find(|s| s.name() == name)
    }
}

/// The `scattering` technique every scattering medium built on [`HomogeneousInterior`]
/// declares (homogeneous media and the subsurface walk): the render's choice over what each
/// medium's `scattering` says.
pub static SCATTERING: Technique = Technique {
    name: "scattering",
    summary: "single or multiple scattering in scattering media",
    values: &[
        TechniqueValue {
            name: "scene",
            summary: "as each medium's `scattering` says",
            converges: technique::always,
        },
        TechniqueValue {
            name: "multiple",
            summary: "every order: walk where light sampling cannot help, else bounce",
            converges: technique::always,
        },
        TechniqueValue {
            name: "walk",
            summary: "every order, walked inside the volume integrator (exits only)",
            converges: technique::always,
        },
        TechniqueValue {
            name: "bounce",
            summary: "every order: each scattering point goes back to the path tracer",
            converges: technique::always,
        },
        TechniqueValue {
            name: "single",
            summary: "single scattering through the lighting delegate (biased: no higher orders)",
            converges: technique::never,
        },
    ],
    default: "scene",
    applies_to: "scenes with homogeneous scattering media or subsurface materials",
};

/// A homogeneous scattering medium's parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct HomogeneousMedium {
    /// Extinction coefficient per channel (per world unit), >= 0.
    pub sigma_t: Rgb,
    /// Scattering coefficient per channel, `0 <= sigma_s <= sigma_t`.
    pub sigma_s: Rgb,
    /// Phase function.
    pub phase: PhaseFunction,
    /// Multiple or single scattering.
    pub scattering: Scattering,
    /// Emission coefficient `j` per channel: radiance emitted per unit length (the source
    /// term of `dL/ds = -sigma_t L + j + sigma_s (phase x L_in)`), >= 0. Black: the medium
    /// does not emit. A medium with `j = sigma_a L0` inside an environment of radiance `L0`
    /// is in equilibrium: it looks like `L0` from everywhere.
    pub emission: Rgb,
    /// The albedo as a pattern of the world position (`albedo = { pattern = .. }`, every
    /// channel in `[0, 1]` by its interval bounds), read at each scattering point
    /// ([`crate::scatter_patterns`]); `sigma_s` is then `sigma_t` (albedo 1) and the
    /// pattern scales each collision's weight. `None`: `sigma_s` alone.
    pub albedo_pattern: Option<Arc<PatternGraph>>,
    /// The Henyey-Greenstein `g` as a grey pattern of the world position (within `(-1, 1)`
    /// by its interval bounds), read at each scattering point; `phase` is then HG (its own
    /// `g` unused). `None`: `phase` alone.
    pub g_pattern: Option<Arc<PatternGraph>>,
}

impl HomogeneousMedium {
    /// Whether the medium emits (some channel of `emission` is positive).
    pub fn emits(&self) -> bool {
        !self.emission.is_black()
    }

    /// Single-scattering albedo `sigma_s / sigma_t` per channel (0 where `sigma_t` is 0).
    pub fn albedo(&self) -> Rgb {
        albedo_of(self.sigma_s, self.sigma_t)
    }
}

/// `sigma_s / sigma_t` per channel (0 where `sigma_t` is 0).
pub fn albedo_of(sigma_s: Rgb, sigma_t: Rgb) -> Rgb {
    let ratio = |a: f32, b: f32| if b > 0.0 { a / b } else { 0.0 };
    Rgb::new(
        ratio(sigma_s.r, sigma_t.r),
        ratio(sigma_s.g, sigma_t.g),
        ratio(sigma_s.b, sigma_t.b),
    )
}

/// The homogeneous medium's volume integrator, bound to the bundle's shading context (one
/// point per ray, at its origin, as the renderer binds it).
pub struct HomogeneousInterior<'a> {
    /// The medium.
    pub medium: &'a HomogeneousMedium,
    /// The context `begin_interior` bound.
    pub ctx: &'a ShadingContext<'a>,
    /// The volume's boundary blocks shadow rays (neither index-matched nor letting shadows
    /// through): light sampling from inside can then reach only lights inside it, which
    /// decides [`Scattering::Multiple`] for the walk.
    pub boundary_blocks_shadows: bool,
}

/// Sampler dimensions the integrator draws per ray: channel, distance, light choice and
/// equiangular distance (four, so that the vertex after it stays aligned to the sampler's
/// four-dimensional sets).
const DIMS_PER_SEGMENT: usize = 4;

impl HomogeneousInterior<'_> {
    /// [`Scattering::Multiple`]'s choice: walk when light sampling at the medium's events
    /// cannot find a light (the boundary blocks shadow rays and no point or spot light lies in the
    /// volume's bounds; area lights inside are found by the walk's own rays).
    fn walks(&self, ictx: &dyn risotto_engine::plugin::IntegratorContext) -> bool {
        if !self.boundary_blocks_shadows {
            return false;
        }
        let bounds = self.ctx.volume_space().map(|s| s.world_bounds);
        !ictx.lights().lights().iter().any(|l| match (l, bounds) {
            (Light::Point { position, .. } | Light::Spot { position, .. }, Some((lo, hi))) => {
                position.cmpge(lo).all() && position.cmple(hi).all()
            }
            (Light::Point { .. } | Light::Spot { .. }, None) => true,
            _ => false,
        })
    }

    /// Draws the four dimensions of every ray's segment, into the batch arena (plain data).
    fn draw<'b>(samplers: &mut [PathSampler], arena: &'b Bump) -> &'b [[f32; DIMS_PER_SEGMENT]] {
        let u = arena.alloc_slice_fill_copy(samplers.len(), [0.0; DIMS_PER_SEGMENT]);
        next_4d_column(samplers, u);
        u
    }

    /// Shading points at the rays' origins (the bound context's, when it has one per ray).
    fn origins(&self, rays: &Rays) -> Option<ShadingPoints> {
        if self.ctx.num_points() == rays.len() {
            return None;
        }
        let mut pts = ShadingPoints::with_capacity(rays.len());
        pts.extend_in_volume(&rays.origin, &rays.direction, self.ctx.material());
        Some(pts)
    }

    /// Multiple scattering (see the module docs): traces the rays, samples a free flight on
    /// each ray's segment to its hit (or unbounded), and shades only the hits of the rays that
    /// pass; the others become the scattering points.
    fn scatter_inside(
        &self,
        rays: &Rays,
        u: &[[f32; DIMS_PER_SEGMENT]],
        samplers: &[PathSampler],
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
        let (light, ictx, arena) = (
            services.volume_light.as_ref(),
            services.ictx,
            services.arena,
        );
        let m = &self.medium;
        let n = rays.len();
        let m0 = out.misses.len();
        // The per-ray columns of this call: plain data in the batch arena.
        let tmax = arena.alloc_slice_copy(&rays.tmax);
        for (tmax, &hit) in tmax.iter_mut().zip(ictx.trace(rays)) {
            *tmax = tmax.min(hit);
        }
        self.emit_along(rays, tmax, samplers, light, ictx, out);
        // Only media whose mean free path is below the float spacing of their coordinates
        // can freeze a walk (`flights_frozen`): the others skip the test per event.
        let may_freeze = self
            .ctx
            .volume_space()
            .is_none_or(|s| flights_may_freeze(m.sigma_t, s.world_bounds.0, s.world_bounds.1));
        let mut frozen = 0;
        let scattered = arena.alloc_slice_fill_copy(n, false);
        let passes = arena.alloc_slice_fill_copy(n, true);
        let t = arena.alloc_slice_fill_copy(n, 0.0f32);
        let weight = arena.alloc_slice_fill_copy(n, Rgb::BLACK);
        for i in 0..n {
            if tmax[i] == f32::INFINITY {
                // Nothing ahead: the ray has already left the medium's closed boundary, which
                // it crossed within its `tmin` (a grazing entry, whose chord is shorter than
                // the spawn offset measured along the ray). A free flight on the unbounded
                // segment would scatter it in empty space forever (an albedo-1 path never
                // ends); it escapes instead, as it physically does after a chord of at most a
                // few offsets, and the escaped stage counts it as `escaped_inside`.
                weight[i] = Rgb::WHITE;
                continue;
            }
            let f = sample_free_flight(
                m.sigma_t,
                m.sigma_s,
                channel_pdf(rays.throughput[i]),
                u[i][0],
                u[i][1],
                tmax[i],
            );
            scattered[i] = f.scattered;
            passes[i] = !f.scattered;
            weight[i] = f.weight;
            t[i] = f.t;
            if !f.scattered {
                continue;
            }
            t[i] = event_inside(ictx, rays, i, f.t, tmax[i]);
            let (o, d) = (rays.origin[i], rays.direction[i]);
            if may_freeze && flights_frozen(m.sigma_t, o + d * t[i]) {
                // Its walk could not move from here, nor gather anything: it ends.
                (scattered[i], passes[i]) = (false, false);
                frozen += 1;
            }
        }
        let events = scattered.iter().filter(|&&s| s).count();
        if let Some(graph) = &m.albedo_pattern {
            // The flights ran at albedo 1: each collision's weight times the albedo there.
            let evals = scale_by_albedo(graph, rays, t, scattered, weight);
            self.ctx.count_pattern_evals(evals);
        }
        // The scattering points (a volume-sampling context at P = o + t d) before the hits
        // of the rays that pass: those hits are mostly the medium's index-matched boundary,
        // which the pass-through stage then removes from the end of the hit queue without
        // moving the scattering points.
        if events > 0 {
            let own = self.origins(rays);
            let parent = own.as_ref().map(|pts| {
                ShadingContext::new(pts, 0..n, ShadingMode::Interior, self.ctx.material(), &[])
            });
            let parent = parent.as_ref().unwrap_or(self.ctx);
            let mut v = parent.begin_volume_sampling();
            v.set_along_rays(rays, t);
            v.set_transmission(weight);
            v.end_volume_sampling(scattered, out);
        }
        // Rays that pass keep their hit (or miss), attenuated by the pass weight.
        let p0 = out.points.len();
        ictx.shade_traced(rays, Some(passes), out);
        for k in p0..out.points.len() {
            out.points.transmission[k] *= weight[out.points.ray_id[k] as usize];
        }
        for k in m0..out.misses.len() {
            out.miss_transmission[k] *= weight[out.misses[k] as usize];
        }
        ictx.count_volume_events(risotto_engine::stats::VolumeEvent::Scatter, events);
        ictx.count_volume_events(
            risotto_engine::stats::VolumeEvent::Pass,
            n - events - frozen,
        );
        ictx.count_volume_events(risotto_engine::stats::VolumeEvent::Frozen, frozen);
    }

    /// Reports the medium's emission along each ray's segment `[0, tmax[i]]` in
    /// `out.emitted`: the exact integral [`emitted_radiance`] (deterministic: no variance,
    /// and independent of the free flight sampled on the segment, which estimates the
    /// other terms of the segment's radiance), or, for a ray weighed against light samples
    /// of the medium (`light`), the point estimator of the weighted integral
    /// ([`crate::media::emission`]). Segments with nothing ahead (`tmax = inf`, a ray
    /// that has already left the medium) emit nothing. No-op for a medium that does not
    /// emit.
    fn emit_along(
        &self,
        rays: &Rays,
        tmax: &[f32],
        samplers: &[PathSampler],
        light: Option<&risotto_engine::plugin::VolumeLightMis<'_>>,
        ictx: &mut dyn IntegratorContext,
        out: &mut ShadeGroups,
    ) {
        let m = &self.medium;
        if !m.emits() {
            return;
        }
        for (i, &t) in tmax.iter().enumerate() {
            let e = emission_along(m, rays, i, t, light, &samplers[i]);
            out.emitted.push(i as u32, e);
        }
        ictx.count_volume_events(risotto_engine::stats::VolumeEvent::Emission, tmax.len());
    }
}

/// Where a scattering event sampled at `t` on ray `i`'s segment `[tmin, tmax]` inside a
/// volume is kept (`tmax`: the ray's hit in the last [`IntegratorContext::trace`] of `rays`,
/// or its own `tmax` where it hit nothing).
///
/// A scattering point within the spawn offset of a boundary could round to its far side: of
/// the segment's start (a ray past a pass-through starts on the boundary and skips it with
/// `tmin`) or of its end. The next ray from it (spawned without an offset) would then cross
/// that boundary again, and the volume stack would never see the ray leave (an albedo-1
/// furnace then walks forever outside). Such points move to `[tmin, scatter_max]`, a shift of
/// ~1e-6 relative, far below any noise; `scatter_max` is the hit less the hit's error offset
/// and the point's own rounding along the ray (`before_hit`, the cosine clamped at 1e-3),
/// needed (and the hit's surface computed) only for points near the hit (the origin, for a
/// ray from an earlier event whose segment is shorter than that). The gate has no
/// surface bound yet: it allows 2000 `coordinate_epsilon`s of `|o| + |t d|` (which bound
/// the point's rounding).
#[inline]
pub fn event_inside(
    ictx: &dyn risotto_engine::plugin::IntegratorContext,
    rays: &Rays,
    i: usize,
    t: f32,
    tmax: f32,
) -> f32 {
    let (o, d, tmin) = (rays.origin[i], rays.direction[i], rays.tmin[i]);
    let near_hit =
        tmax < rays.tmax[i] && t > tmax - 2000.0 * coordinate_epsilon(o.abs() + (d * tmax).abs());
    let scatter_max = match near_hit.then(|| ictx.traced_surface(rays, i)).flatten() {
        Some(surf) => {
            let s = before_hit(tmax, surf.offset(), surf.ng, o, d);
            if s >= tmin {
                s
            } else if tmin == 0.0 {
                // The ray leaves from its origin (an earlier event, itself kept clear of the
                // boundary) through less than the boundary's error: no point of the segment
                // is surely inside but the origin. Halfway to the boundary instead, each such
                // event would halve the clearance, and a walk along the boundary would creep
                // across it.
                0.0
            } else {
                0.5 * (tmin + tmax)
            }
        }
        None => tmax,
    };
    t.min(scatter_max).max(tmin.min(0.5 * tmax))
}

/// Keeps the points `p0 + i` of `out` with `keep[i]` (the rows this bundle appended),
/// fixing the ranges of the groups from `g0` on (which all lie in those rows).
pub(crate) fn retain_points(out: &mut ShadeGroups, p0: usize, keep: &[bool], g0: usize) {
    // before[i] = the rows kept among the tail's first i.
    let mut before = Vec::with_capacity(keep.len() + 1);
    let mut kept = 0usize;
    before.push(0);
    for &k in keep {
        kept += k as usize;
        before.push(kept);
    }
    out.points.retain_rows_from(p0, keep);
    let mut j = g0;
    for k in g0..out.groups.len() {
        let g = out.groups[k].clone();
        let range = p0 + before[g.range.start - p0]..p0 + before[g.range.end - p0];
        if !range.is_empty() {
            out.groups[j] = ShadeGroup { range, ..g };
            j += 1;
        }
    }
    out.groups.truncate(j);
}

impl VolumeIntegrator for HomogeneousInterior<'_> {
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        samplers: &mut [PathSampler],
        _lobes_wanted: LobeSampled,
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
        let scattering = services
            .ictx
            .technique(SCATTERING.name)
            .and_then(Scattering::from_name)
            .unwrap_or(self.medium.scattering);
        let walk = match scattering {
            Scattering::Walk => true,
            Scattering::Multiple => self.walks(services.ictx),
            Scattering::Bounce => false,
            // Single scattering needs the delegate; without one it scatters as Multiple.
            Scattering::Single => services.lighting.is_none() && self.walks(services.ictx),
        };
        if walk {
            let light = services.volume_light.as_ref();
            random_walk::walk_bundle(self.medium, light, rays, samplers, services.ictx, out);
            return;
        }
        let u = Self::draw(samplers, services.arena);
        if scattering == Scattering::Single && services.lighting.is_some() {
            let start = (out.points.len(), out.groups.len(), out.misses.len());
            services.ictx.nearest_hits(rays, out);
            // Each ray's segment in the medium: to its hit, or unbounded.
            let mut tmax = rays.tmax.clone();
            for k in start.0..out.points.len() {
                let r = out.points.ray_id[k] as usize;
                tmax[r] = tmax[r].min(out.points.vlen[k]);
            }
            let light = services.volume_light.as_ref();
            self.emit_along(rays, &tmax, samplers, light, services.ictx, out);
            self.single_scatter(rays, samplers, u, &tmax, start, services, out);
        } else {
            self.scatter_inside(rays, u, samplers, services, out);
        }
    }

    fn transmission(
        &self,
        segments: &Segments,
        _samplers: &mut [PathSampler],
        _ictx: &dyn risotto_engine::plugin::IntegratorContext,
        trans: &mut [Rgb],
        emission: &mut [Rgb],
    ) {
        let m = &self.medium;
        for i in 0..segments.len() {
            trans[i] = transmittance(m.sigma_t, segments.length[i]);
            emission[i] = emitted_radiance(m.sigma_t, m.emission, segments.length[i]);
        }
    }
}
