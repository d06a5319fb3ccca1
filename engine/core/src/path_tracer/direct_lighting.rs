//! Direct-lighting stage (next-event estimation): light samples at a group's points, the
//! Bxdf's response, and shadow rays into the [`ShadowRayQueue`](super::queues::ShadowRayQueue).
//!
//! One implementation serves two callers:
//! - the shade stage, for the surface and volume points the path tracer shades: the path
//!   continues there with a Bxdf (or phase-function) sample, so light samples are weighted by
//!   the power heuristic against it ([`LightingTechnique::Mis`]; `NeeOnly` gives weight 1
//!   and the emitters those samples hit count 0);
//! - the [`LightingDelegate`] handed to volume integrators ([`DirectLighting`]): they light
//!   in-volume points whose paths do *not* continue with a phase-function sample (single
//!   scattering), so nothing else estimates that light path and the weight is 1 whatever the
//!   technique. Weighting it against a phase sample nobody takes would lose about half the
//!   light (the power heuristic's share of the phase technique).
//!
//! Both honour `max_depth` (a light sample at a vertex of a ray of depth `d` closes a path of
//! `d + 2` segments) and give shadow rays the vertex's sampler dimension (a sequence of their
//! own, fresh per bounce).

use super::non_finite_case;
use super::queues::{scratch, GroupScratch, LightBuffers};
use super::shading_normals::discard_light_directions;
use crate::integrator::LightingTechnique;
use crate::plugin::{Bxdf, LightingDelegate, ShadingContext};
use crate::scene::CompiledScene;
use crate::stats::{Stage, System, SystemStats, VolumeEvent};
use glam::Vec3;
use risotto_components::{Paths, Rays, Rgb, ShadowRayColumns, ShadowRays};
use risotto_systems::direct_lighting::{
    non_finite_rows, spawn_shadow_rays, LightColumns, LightMis,
};
use risotto_systems::lights::{LightSampleColumns, LightSet};
use risotto_systems::path::Vertices;
use risotto_systems::sampler::PathSampler;

/// What one call of [`sample_lights`] lights.
pub(super) struct LitGroup<'a, 'b> {
    /// The group's points and the rays that arrived there.
    pub vertices: Vertices<'a>,
    /// An extra factor per point (the delegate's caller's weights), or `None`.
    pub weight: Option<&'b [Rgb]>,
    /// The vertex's first four sampler dimensions per point (indices 0..3 are used here).
    pub u4: &'b [[f32; 4]],
    /// Whether each point's light path fits in `max_depth`.
    pub active: &'b [bool],
    /// MIS against the Bxdf sample the path continues with, or none.
    pub mis: LightMis,
}

/// Samples one light per point of the group, evaluates `bxdf` (the points' Bxdf, a phase
/// function for volume points, bound to `ctx`) towards it and writes the
/// shadow rays of the non-black samples to `out` from row `start` on (lights from `lights`:
/// the path tracer's set for its technique, or every light for the delegate); returns the number of
/// rows written. `dimension[r]` is the first sampler dimension of the shadow rays of points
/// that ray `r` arrived at; `paths` (the batch's) names the camera samples of non-finite
/// cases.
#[allow(
    clippy::too_many_arguments,
    reason = "the columns it reads and writes, named"
)]
pub(super) fn sample_lights(
    scene: &CompiledScene,
    lights: &LightSet,
    group: LitGroup<'_, '_>,
    bxdf: &mut dyn Bxdf,
    ctx: &ShadingContext<'_>,
    paths: &Paths,
    dimension: &[u32],
    buffers: &mut LightBuffers,
    out: &mut ShadowRayColumns<'_>,
    start: usize,
    stats: &mut SystemStats,
) -> usize {
    let LitGroup {
        vertices,
        weight,
        u4,
        active,
        mis,
    } = group;
    let m = vertices.range.len();
    let lstart = std::time::Instant::now();
    // The light samples' directions are where the Bxdf evaluates (`Vec3::Z` where there is
    // no sample).
    let mut light = LightSampleColumns {
        wi: scratch(&mut buffers.wi, m, Vec3::Z),
        distance: scratch(&mut buffers.distance, m, 0.0),
        radiance: scratch(&mut buffers.radiance, m, Rgb::BLACK),
        pdf: scratch(&mut buffers.pdf, m, 0.0),
        delta: scratch(&mut buffers.delta, m, false),
        margin: scratch(&mut buffers.margin, m, 0.0),
    };
    let range = vertices.range.clone();
    lights.sample_column(
        &scene.geometry,
        &vertices.points.p[range][..m],
        u4,
        active,
        &mut light,
    );
    stats.record(System::Lights, m, lstart.elapsed().as_secs_f64());
    if scene.features.emissive_volume_lights {
        let volume = (0..m)
            .filter(|&k| light.pdf[k] > 0.0 && lights.selects_volume(u4[k][2]))
            .count();
        stats.volume_event(VolumeEvent::LightSample, volume);
    }
    let (value, pdf) = (
        scratch(&mut buffers.value, m, Rgb::BLACK),
        scratch(&mut buffers.eval_pdf, m, 0.0),
    );
    bxdf.evaluate_samples(ctx, light.wi, value, pdf);
    if scene.discards_disagreeing_directions() && vertices.on_surface {
        let range = vertices.range.clone();
        let lifted = vertices.terminator_lift;
        discard_light_directions(vertices.points, range, lifted, light.wi, value);
    }
    // NaN provenance: the Bxdf's evaluations and the light samples of the active points.
    let bxdf_bad = |k: usize| active[k] & !(value[k].is_finite() & pdf[k].is_finite());
    let light_bad =
        |k: usize| active[k] & !(light.radiance[k].is_finite() & light.pdf[k].is_finite());
    let bad_bxdf = non_finite_rows(active, value, pdf);
    let bad_light = non_finite_rows(active, light.radiance, light.pdf);
    let stage = if vertices.on_surface {
        Stage::Bxdf
    } else {
        Stage::Phase
    };
    stats.non_finite(stage, bad_bxdf);
    stats.non_finite(Stage::Lighting, bad_light);
    if bad_bxdf + bad_light > 0 {
        let (pts, start) = (vertices.points, vertices.range.start);
        for k in 0..m {
            let r = pts.ray_id[start + k] as usize;
            let (path, depth) = (vertices.incoming.path[r], vertices.incoming.depth[r]);
            let material = Some(pts.material[start + k]);
            if bxdf_bad(k) {
                non_finite_case(stats, paths, path, depth, stage, material);
            }
            if light_bad(k) {
                non_finite_case(stats, paths, path, depth, Stage::Lighting, material);
            }
        }
    }
    let features = scene.features;
    let stacks = features.volumes || features.transmissive || !scene.camera_stack.is_empty();
    let light = LightColumns {
        samples: light,
        value,
        pdf,
        points: scratch(&mut buffers.points, m, 0),
    };
    spawn_shadow_rays(
        vertices,
        weight,
        dimension,
        light,
        mis,
        stacks.then(|| scene.boundaries()),
        out,
        start,
    )
}

/// The lighting delegate the path tracer hands to volume integrators
/// (RIS `IntegratorDelegate::PerformDirectLighting`): the same light sampling as the shade
/// stage, without MIS (see the module docs), its shadow rays traced with all others in the
/// bounce's transmission stage.
pub struct DirectLighting<'a> {
    scene: &'a CompiledScene,
    paths: &'a Paths,
    shadow: &'a mut ShadowRays,
    group: &'a mut GroupScratch,
    /// Rows of `shadow` written by this delegate's calls, and light-sample count.
    lit: usize,
    seconds: f64,
    /// What the calls' light sampling counted (its non-finite values are the render's; its
    /// `lights` time is recorded once, as `lit` and `seconds`).
    stats: SystemStats,
}

impl<'a> DirectLighting<'a> {
    /// A delegate queuing its shadow rays in `shadow` (`technique` decides only whether the
    /// path tracer offers a delegate at all: `BxdfOnly` does not); `paths` are the batch's.
    pub(super) fn new(
        scene: &'a CompiledScene,
        technique: LightingTechnique,
        paths: &'a Paths,
        shadow: &'a mut ShadowRays,
        group: &'a mut GroupScratch,
    ) -> Self {
        debug_assert!(technique != LightingTechnique::BxdfOnly || !scene.lights.can_sample());
        let _ = technique;
        DirectLighting {
            scene,
            paths,
            shadow,
            group,
            lit: 0,
            seconds: 0.0,
            stats: SystemStats::default(),
        }
    }

    /// Records the delegate's work in `stats`: its light samples and their time, and the
    /// non-finite values its calls found (NaN provenance of the delegate's light samples and
    /// phase evaluations).
    pub(super) fn finish(self, stats: &mut SystemStats) {
        if self.lit > 0 {
            stats.record(System::Lights, self.lit, self.seconds);
        }
        for (a, b) in stats.non_finite.iter_mut().zip(&self.stats.non_finite) {
            *a += b;
        }
        for &e in &self.stats.non_finite_events {
            stats.non_finite_event(e);
        }
    }
}

impl LightingDelegate for DirectLighting<'_> {
    fn perform_direct_lighting(
        &mut self,
        ctx: &ShadingContext<'_>,
        bxdf: &mut dyn Bxdf,
        rays: &Rays,
        samplers: &mut [PathSampler],
        weight: &[Rgb],
    ) {
        let start = std::time::Instant::now();
        let m = ctx.num_points();
        let scene = self.scene;
        let GroupScratch {
            u4,
            active,
            ray_dimension,
            light,
            ..
        } = &mut *self.group;
        let ray_id = ctx.ray_id();
        // The vertex's four light dimensions, drawn point by point from each point's ray
        // (several points may share a ray: each takes the ray's next dimensions); the shadow
        // ray's own sequence starts at the ray's dimension before the draw.
        let u4 = scratch(u4, m, [0.0; 4]);
        let active = scratch(active, m, false);
        let dimension = scratch(ray_dimension, rays.len(), 0);
        dimension.copy_from_slice(&rays.dimension);
        for k in 0..m {
            let r = ray_id[k] as usize;
            let s = &mut samplers[r];
            dimension[r] = s.dimension;
            u4[k] = s.next_4d();
            // A light sample at a point on a ray of depth `d` closes a path of `d + 2`
            // segments.
            active[k] = rays.depth[r] as u32 + 2 <= scene.settings.max_depth;
        }
        let (points, range) = ctx.rows();
        let vertices = Vertices {
            points,
            range,
            on_surface: false,
            terminator_lift: false,
            incoming: rays,
        };
        let start_row = self.shadow.len();
        let mut out = self.shadow.append_default(m);
        let group = LitGroup {
            vertices,
            weight: Some(weight),
            u4,
            active,
            mis: LightMis::None,
        };
        let written = sample_lights(
            scene,
            &scene.lights,
            group,
            bxdf,
            ctx,
            self.paths,
            dimension,
            light,
            &mut out,
            0,
            &mut self.stats,
        );
        self.shadow.truncate(start_row + written);
        self.lit += m;
        self.seconds += start.elapsed().as_secs_f64();
    }
}
