//! The integrator context (RIS `RixIntegratorContext`): everything a volume integrator (and
//! a global integrator) gets from the renderer, as an interface. The renderer's own
//! implementation over a compiled scene is `crate::context::RenderContext`; the built-in
//! plug-ins see exactly this trait, as a user's plug-in does.

use super::technique::PluginTechniques;
use crate::shade_groups::ShadeGroups;
use crate::stats::VolumeEvent;
use glam::Vec3;
use risotto_components::{Hits, Rays, VolumeStack};
use risotto_systems::geometry::SurfaceSample;
use risotto_systems::lights::LightSet;

/// The renderer's ray-tracing services, bound to one compiled scene and one worker (RIS
/// `RixIntegratorContext`).
pub trait IntegratorContext {
    /// Records `n` sampled extinctions above their majorant's bound
    /// ([`SystemStats::majorant_violations`](crate::stats::SystemStats::majorant_violations)); callable from a volume's `transmission`,
    /// which sees the context shared. They reach the render's stats when the context ends.
    fn count_majorant_violations(&self, n: u64);

    /// Records `segments` majorant segments too dense to track that a volume integrated
    /// exactly instead, with `lookups` density lookups
    /// ([`SystemStats::dense_segments`](crate::stats::SystemStats::dense_segments),
    /// `risotto_systems::tracking::dense`); callable from a volume's `transmission`, as
    /// [`Self::count_majorant_violations`].
    fn count_dense_segments(&self, segments: u64, lookups: u64);

    /// Records `n` tentative collisions (lookups) a volume's `transmission` took to estimate
    /// shadow rays' transmittance
    /// ([`SystemStats::shadow_collisions`](crate::stats::SystemStats::shadow_collisions)).
    fn count_shadow_collisions(&self, n: u64);

    /// Counts `n` volume events of kind `event` (the stats' `volume_events`).
    fn count_volume_events(&mut self, event: VolumeEvent, n: usize);

    /// Counts `n` pattern evaluations a volume made point by point (medium coefficients):
    /// they add to the stats' `pattern_evals` and, of those, `volume_pattern_evals`.
    fn count_volume_pattern_evals(&mut self, n: u64);

    /// The scene's axis-aligned bounds `(min, max)` over every primitive.
    fn scene_bounds(&self) -> (Vec3, Vec3);

    /// The render's `max_depth`: the most path segments a path may have
    /// ([`RenderSettings::max_depth`](crate::scene::RenderSettings::max_depth); `u32::MAX`
    /// for unbounded). A volume integrator that walks many events per call stops its walks
    /// there, as the global integrator would.
    fn max_depth(&self) -> u32;

    /// Every light of the scene, as light sampling without MIS sees them (for in-volume
    /// light sampling, e.g. equiangular sampling towards point lights).
    fn lights(&self) -> &LightSet;

    /// The closest surface hit of each bare ray (`origin`, `direction`, `tmin..tmax`),
    /// without shading points: for volume integrators that trace their own rays (random
    /// walks, probe rays). `out` is resized to the rays; a miss has `prim == NO_HIT`. Read
    /// a hit's surface with [`Self::surface_at`] and its shape with [`Self::shape_of`].
    /// Counted as closest-hit intersection in the stats.
    fn closest_hits(
        &mut self,
        origin: &[Vec3],
        direction: &[Vec3],
        tmin: &[f32],
        tmax: &[f32],
        out: &mut Hits,
    );

    /// The surface at a hit of [`Self::closest_hits`] (primitive `prim` at distance `t`
    /// along `origin + t direction`, barycentrics `b1`, `b2`): point, geometric normal,
    /// error bound.
    fn surface_at(
        &self,
        prim: u32,
        origin: Vec3,
        direction: Vec3,
        t: f32,
        b1: f32,
        b2: f32,
    ) -> SurfaceSample;

    /// The shape primitive `prim` belongs to (what [`ShadingContext::shape`] says of a
    /// shading point; a volume stack entry's `shape`).
    ///
    /// [`ShadingContext::shape`]: crate::plugin::shading_context::ShadingContext::shape
    fn shape_of(&self, prim: u32) -> u32;

    /// The distance from `p` to the nearest surface of the scene, at most `cap` (an empty
    /// ball around `p`: a walk may take any step shorter than it without tracing a ray).
    fn clearance(&self, p: Vec3, cap: f32) -> f32;

    /// Whether the caller of [`VolumeIntegrator::transmission`](crate::plugin::VolumeIntegrator::transmission)
    /// uses its `emission` output. Where it does not (the path tracer adds a built-in
    /// medium's emission along its path rays, so it drops what shadow rays gather), an
    /// integrator may leave `emission` black and run a cheaper transmittance estimator.
    fn emission_wanted(&self) -> bool;

    /// The value this render chose for the plug-in technique `name` (one a material
    /// declares, [`BxdfFactory::techniques`](crate::plugin::BxdfFactory::techniques));
    /// `None`: its default, usually "as the material says".
    fn technique(&self, name: &str) -> Option<&'static str>;

    /// Every plug-in technique choice of this render.
    fn techniques(&self) -> PluginTechniques;

    /// IOR outside `shape` for a ray travelling with `stack`: the IOR of the innermost volume
    /// that is not `shape`'s own interior (1 in vacuum).
    fn ior_outside(&self, stack: &VolumeStack, shape: u32) -> f32;

    /// Traces `rays` to their nearest surface hits and appends the hits to `out`, grouped by
    /// material (each group contiguous), as [`ShadingMode::Scatter`](crate::shade_groups::ShadingMode::Scatter) groups; rays that escape
    /// are appended to `out.misses`. Points carry `ray_id` = index into `rays` and
    /// transmission 1.
    fn nearest_hits(&mut self, rays: &Rays, out: &mut ShadeGroups);

    /// The first half of [`nearest_hits`](Self::nearest_hits): traces `rays` to their
    /// nearest surface hits and returns each ray's hit distance (`f32::INFINITY` for a
    /// miss), without building shading points. A volume integrator that decides from the
    /// distances which rays stop inside (free-flight sampling) then shades only the others
    /// with [`shade_traced`](Self::shade_traced), instead of building every point and
    /// dropping most of them.
    fn trace(&mut self, rays: &Rays) -> &[f32];

    /// Where ray `i` of the last [`trace`](Self::trace) (of `rays`) hits: the point, the
    /// surface's geometric normal and the point's error bound; `None` for a miss.
    fn traced_surface(&self, rays: &Rays, i: usize) -> Option<SurfaceSample>;

    /// The second half of [`nearest_hits`](Self::nearest_hits), for the rays of the last
    /// [`trace`](Self::trace) (which must have been of `rays`): appends the hits and misses
    /// of the rays `i` with `keep[i]` (every ray for `None`) to `out`, exactly as
    /// `nearest_hits` would have appended them, in the same order, less the others.
    ///
    /// # Panics
    /// When `keep` or the last trace is not as long as `rays`.
    fn shade_traced(&mut self, rays: &Rays, keep: Option<&[bool]>, out: &mut ShadeGroups);
}
