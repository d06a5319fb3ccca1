//! A second global integrator and volume integrators written outside the engine, with only the
//! public API (issue 9, items 3 and 4).
//!
//! * [`DirectOnly`] is a global integrator (RIS `RixIntegrator`) that estimates direct lighting
//!   only: camera ray, first hit, one light sample, one shadow ray. Like PxrVCM it offers
//!   volume integrators **no** lighting delegate. On a diffuse scene it estimates what the
//!   path tracer estimates with `max_depth = 2`; the two must agree block by block.
//! * [`SlabMedium`] is a factory whose interior ([`SlabInterior`]) does single scattering in a
//!   homogeneous medium: given the path tracer's lighting delegate it samples one distance per
//!   ray, lights the point there through `perform_direct_lighting` and returns the hits behind
//!   with their transmission; without a delegate (under [`DirectOnly`]) it falls back to
//!   returning the in-volume points as a `VolumeScatter` group, which the global integrator
//!   lights itself. Under both integrators the single-scattered radiance of a slab must match
//!   the closed forms below.
//!
//! # The slab's single scattering
//!
//! A slab `-d <= z <= 0` of extinction `sigma_t`, albedo `omega` and an isotropic phase
//! function, bounded by an index-matched surface, lies on a black plane and is seen by an
//! orthographic camera at normal incidence (`mu = 1`). Nothing else is visible, so the pixel
//! radiance is the single-scattered radiance (zero scattering reaches the black plane, and
//! the interiors here never scatter twice). With `tau = sigma_t d`:
//!
//! * **point light** of intensity `I` at height `h` above the camera ray's entry point: a
//!   point at depth `t` is lit along the vertical, `L_i = I e^{-sigma_t t} / (h + t)^2`, and
//!   is seen through `e^{-sigma_t t}`:
//!   `L = sigma_s I / (4 pi) int_0^d e^{-2 sigma_t t} / (h + t)^2 dt`;
//! * **constant environment** `L` over the upper hemisphere (the black plane hides the lower
//!   one): Chandrasekhar's single-scattering reflection of a finite plane-parallel slab for a
//!   collimated beam, `I(mu, mu0) = (F / 4) omega p mu0 / (mu + mu0) (1 - e^{-tau (1/mu +
//!   1/mu0)})` (S. Chandrasekhar, *Radiative Transfer*, 1950 / Dover 1960, ch. I; the
//!   first-order term of the reflection function), integrated over a diffuse incidence of
//!   radiance `L` (`pi F = L dOmega_0`, `p = 1` isotropic) and taken at `mu = 1`:
//!   `L_ss = (omega L / 2) int_0^1 mu0 / (1 + mu0) (1 - e^{-tau (1 + 1/mu0)}) dmu0`.
//!
//! Both integrals are evaluated with Simpson's rule in `f64` (error far below 1e-6).

mod common;
use bumpalo::Bump;
use common::*;
use glam::Vec3;
use risotto::builtins::builtin::{NullBxdf, Surface};
use risotto::builtins::phase::PhaseBxdf;
use risotto::engine::context::RenderContext;
use risotto::engine::integrator::{Integrator, PathBatch};
use risotto::engine::plugin::IntegratorContext;
use risotto::engine::plugin::{
    Builtin, Bxdf, BxdfFactory, InstanceHints, ParamCache, PatternCounters, Segments, ShadeGroups,
    ShadingContext, ShadingMode, VolumeIntegrator, VolumeServices,
};
use risotto::engine::render::{render, render_with, RenderOptions, RenderOutput};
use risotto::engine::scene::{CompiledScene, LightComponent, Scene, ShapeGeometry};
use risotto::engine::stats::SystemStats;
use risotto::engine::transmission::trace_shadow_rays;
use risotto::systems::camera::push_camera_rays;
use risotto::systems::lights::LightSampleColumns;
use risotto::systems::phase::PhaseFunction;
use risotto::systems::ray::{shadow_ray, skip_tmin, spawn_origin};
use risotto::systems::sampler::PathSampler;
use risotto_components::{
    LobeSampled, Rays, Rgb, ShadingPointRow, ShadingPoints, ShadowRayRow, ShadowRays, VolumeEntry,
    VolumeStack,
};

// ---------------------------------------------------------------------------------------
// The direct-lighting-only global integrator.
// ---------------------------------------------------------------------------------------

/// Direct lighting only: emission seen by camera rays, the environment behind them, and one
/// light sample at the first scattering point (surface or volume). Index-matched boundaries
/// are passed (volume stacks kept up to date); volumes are handed to their integrators
/// **without** a lighting delegate.
struct DirectOnly {
    /// Added to the rays' sampler dimension for the light samples, so that the estimate is
    /// not correlated with the path tracer's (which draws its light samples there).
    dimension_offset: u32,
}

/// What a worker keeps across batches.
#[derive(Default)]
struct DirectWorker {
    shadow: ShadowRays,
    contribution: Vec<Rgb>,
}

impl Integrator for DirectOnly {
    type Worker = DirectWorker;

    fn run_batch(
        &self,
        scene: &CompiledScene,
        batch: &mut PathBatch,
        worker: &mut DirectWorker,
        stats: &mut SystemStats,
        arena: &Bump,
    ) {
        let mut rays = Rays::default();
        push_camera_rays(
            &scene.camera,
            &batch.paths.pixel,
            &batch.paths.sample,
            &batch.seeds,
            &scene.camera_stack,
            &mut rays,
        );
        worker.shadow.clear();
        let mut rounds = 0;
        while !rays.is_empty() && rounds <= scene.settings.max_passes {
            rounds += 1;
            let mut next = Rays::default();
            // Bundles of rays travelling in the same volumes.
            let mut bundles: Vec<(VolumeStack, Vec<u32>)> = Vec::new();
            for i in 0..rays.len() {
                let s = &rays.volume_stack[i];
                match bundles.iter_mut().find(|(k, _)| k == s) {
                    Some((_, ids)) => ids.push(i as u32),
                    None => bundles.push((s.clone(), vec![i as u32])),
                }
            }
            for (stack, ids) in bundles {
                let mut bundle = Rays::default();
                bundle.extend_gather(&rays, &ids);
                let mut groups = ShadeGroups::default();
                let interior = stack.innermost().filter(|e| {
                    scene.material_info[e.material as usize]
                        .hints
                        .contains(InstanceHints::COMPUTES_INTERIOR)
                });
                match interior {
                    None => RenderContext::new(scene, stats).nearest_hits(&bundle, &mut groups),
                    Some(e) => volume_hits(scene, batch, &mut bundle, e, stats, arena, &mut groups),
                }
                self.shade(
                    scene,
                    batch,
                    &bundle,
                    &groups,
                    &mut next,
                    &mut worker.shadow,
                    arena,
                );
            }
            rays = next;
        }
        worker.contribution.clear();
        worker
            .contribution
            .extend_from_slice(&worker.shadow.contribution);
        trace_shadow_rays(
            scene,
            &worker.shadow,
            batch,
            Default::default(),
            &mut worker.contribution,
            stats,
            arena,
        );
        for (&path, &c) in worker.shadow.path.iter().zip(&worker.contribution) {
            batch.paths.radiance[path as usize] += c;
        }
    }
}

/// Hands `bundle` (rays in the volume `entry`) to that volume's integrator, as the renderer's
/// trace stage does, but with no lighting delegate.
fn volume_hits(
    scene: &CompiledScene,
    batch: &PathBatch,
    bundle: &mut Rays,
    entry: VolumeEntry,
    stats: &mut SystemStats,
    arena: &Bump,
    out: &mut ShadeGroups,
) {
    let m = bundle.len();
    let mut points = ShadingPoints::default();
    for k in 0..m {
        bundle.shading_ctx_index[k] = k as u32;
        points.push(ShadingPointRow::in_volume(
            bundle.origin[k],
            bundle.direction[k],
            k as u32,
            entry.material,
        ));
    }
    let counters = PatternCounters::default();
    let cache = ParamCache::new(arena, &counters);
    let factory = scene.materials[entry.material as usize].factory.as_ref();
    let (lo, hi) = scene.shape_bounds[entry.shape as usize];
    let ctx = ShadingContext::new(&points, 0..m, ShadingMode::Interior, entry.material, &[])
        .with_factory(factory)
        .with_cache(&cache)
        .with_volume_bounds(lo, hi);
    let integrator = factory
        .begin_interior(&ctx, ShadingMode::Interior, arena)
        .expect("COMPUTES_INTERIOR promised an interior");
    let mut samplers: Vec<PathSampler> = (0..m)
        .map(|k| {
            let path = bundle.path[k] as usize;
            PathSampler {
                seed: batch.seeds[path],
                sample: batch.paths.sample[path],
                dimension: bundle.dimension[k],
            }
        })
        .collect();
    let mut ictx = RenderContext::new(scene, stats);
    integrator.nearest_hits(
        bundle,
        &mut samplers,
        LobeSampled(0xff),
        VolumeServices {
            ictx: &mut ictx,
            lighting: None,
            factory,
            arena,
            volume_light: None,
            light_path: false,
        },
        out,
    );
    for (k, s) in samplers.iter().enumerate() {
        bundle.dimension[k] = s.dimension;
    }
}

impl DirectOnly {
    /// Environment for the misses, pass-throughs into `next`, emission and one light sample
    /// (a shadow ray into `shadow`) at every other point of `groups`, the answer for `rays`.
    #[allow(clippy::too_many_arguments, reason = "the tables it reads and writes")]
    fn shade(
        &self,
        scene: &CompiledScene,
        batch: &mut PathBatch,
        rays: &Rays,
        groups: &ShadeGroups,
        next: &mut Rays,
        shadow: &mut ShadowRays,
        arena: &Bump,
    ) {
        let paths = &mut batch.paths;
        for (k, &r) in groups.misses.iter().enumerate() {
            let r = r as usize;
            let le = scene.lights.environment_radiance(rays.direction[r]);
            paths.radiance[rays.path[r] as usize] +=
                rays.throughput[r] * groups.miss_transmission[k] * le;
        }
        let pts = &groups.points;
        for g in &groups.groups {
            let hints = scene.material_info[g.material as usize].hints;
            if g.mode == ShadingMode::Scatter && hints.contains(InstanceHints::INDEX_MATCHED) {
                for i in g.range.clone() {
                    let mut row = rays.row(pts.ray_id[i] as usize);
                    let p = pts.p[i];
                    row.throughput *= pts.transmission[i];
                    row.origin = p;
                    row.tmin = skip_tmin(pts.p[i], pts.p_offset[i], pts.ng[i], row.direction);
                    row.tmax = f32::INFINITY;
                    row.passes += 1;
                    let shape = pts.shape[i];
                    if scene.tracks_interior(shape) {
                        row.volume_stack
                            .cross(scene.volume_entry(shape), pts.front_face[i]);
                    }
                    next.push(row);
                }
                continue;
            }
            let factory = scene.materials[g.material as usize].factory.as_ref();
            let counters = PatternCounters::default();
            let cache = ParamCache::new(arena, &counters);
            let ctx = ShadingContext::new(pts, g.range.clone(), g.mode, g.material, &[])
                .with_factory(factory)
                .with_cache(&cache);
            let bxdf = factory.begin_scatter(&ctx, g.mode, arena);
            let m = g.range.len();
            let on_surface = g.mode == ShadingMode::Scatter;
            let ray_id = ctx.ray_id();
            let throughput: Vec<Rgb> = (0..m)
                .map(|k| rays.throughput[ray_id[k] as usize] * ctx.transmission()[k])
                .collect();
            if on_surface {
                for k in 0..m {
                    let le = scene.shapes[ctx.shape()[k] as usize].emission;
                    if let (Some(le), true) = (le, ctx.front_face()[k]) {
                        paths.radiance[rays.path[ray_id[k] as usize] as usize] +=
                            throughput[k] * le;
                    }
                }
            }
            let u4: Vec<[f32; 4]> = (0..m)
                .map(|k| {
                    let r = ray_id[k] as usize;
                    let path = rays.path[r] as usize;
                    PathSampler {
                        seed: batch.seeds[path],
                        sample: paths.sample[path],
                        dimension: rays.dimension[r] + self.dimension_offset,
                    }
                    .next_4d()
                })
                .collect();
            let (mut wi, mut distance) = (vec![Vec3::Z; m], vec![0.0; m]);
            let (mut radiance, mut pdf, mut delta) =
                (vec![Rgb::BLACK; m], vec![0.0; m], vec![false; m]);
            let mut margin = vec![0.0; m];
            scene.lights.sample_column(
                &scene.geometry,
                ctx.p(),
                &u4,
                &vec![true; m],
                &mut LightSampleColumns {
                    wi: &mut wi,
                    distance: &mut distance,
                    radiance: &mut radiance,
                    pdf: &mut pdf,
                    delta: &mut delta,
                    margin: &mut margin,
                },
            );
            let (mut value, mut bxdf_pdf) = (vec![Rgb::BLACK; m], vec![0.0; m]);
            bxdf.evaluate_samples(&ctx, &wi, &mut value, &mut bxdf_pdf);
            for k in 0..m {
                if pdf[k] <= 0.0 {
                    continue;
                }
                let r = ray_id[k] as usize;
                let weight = throughput[k] * value[k] * (1.0 / pdf[k]);
                let contribution = weight * radiance[k];
                if contribution.is_black() {
                    continue;
                }
                let p = ctx.p()[k];
                let origin = spawn_origin(p, ctx.ng()[k], ctx.p_offset()[k], wi[k], on_surface);
                let (direction, tmax) = shadow_ray(p, origin, wi[k], distance[k], margin[k]);
                shadow.push(ShadowRayRow {
                    origin,
                    direction,
                    tmax,
                    contribution,
                    weight,
                    path: rays.path[r],
                    dimension: rays.dimension[r] + self.dimension_offset + 4,
                    volume_stack: rays.volume_stack[r].clone(),
                });
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// The single-scattering medium.
// ---------------------------------------------------------------------------------------

/// An index-matched boundary around a homogeneous, isotropically scattering medium.
#[derive(Clone, Copy, Debug)]
struct SlabMedium {
    sigma_t: f32,
    albedo: f32,
}

impl BxdfFactory for SlabMedium {
    fn instance_hints(&self) -> InstanceHints {
        InstanceHints::INDEX_MATCHED
            | InstanceHints::TRANSMISSION_SHADOWS
            | InstanceHints::TRANSMITS
            | InstanceHints::COMPUTES_INTERIOR
            | InstanceHints::INTERIOR_TRANSMISSION
            | InstanceHints::INTERIOR_SCATTERS
    }
    fn begin_scatter<'a>(
        &'a self,
        _ctx: &'a ShadingContext<'a>,
        mode: ShadingMode,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a) {
        match mode {
            // The phase function of the interior: isotropic, weighted by the albedo.
            ShadingMode::VolumeScatter => arena.alloc(PhaseBxdf::weighted(
                PhaseFunction::Isotropic,
                Rgb::splat(self.albedo),
            )),
            // The surface is never shaded (index-matched).
            ShadingMode::Scatter | ShadingMode::Interior => arena.alloc(NullBxdf),
        }
    }
    fn begin_interior<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> Option<&'a mut (dyn VolumeIntegrator + 'a)> {
        Some(arena.alloc(SlabInterior {
            ctx,
            sigma_t: self.sigma_t,
        }))
    }
    fn shadow_transmittance(&self) -> Rgb {
        Rgb::WHITE
    }
}

/// Single scattering through the lighting delegate, or in-volume points without one.
struct SlabInterior<'a> {
    /// The context at the rays' origins (one point per ray, in ray order).
    ctx: &'a ShadingContext<'a>,
    sigma_t: f32,
}

impl SlabInterior<'_> {
    fn transmittance(&self, d: f32) -> Rgb {
        Rgb::splat((-self.sigma_t * d).exp())
    }
}

impl VolumeIntegrator for SlabInterior<'_> {
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        samplers: &mut [PathSampler],
        _lobes_wanted: LobeSampled,
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
        let n = rays.len();
        let s = self.sigma_t;
        let mut hits = ShadeGroups::default();
        services.ictx.nearest_hits(rays, &mut hits);
        // The length of each ray's segment in the volume (unbounded when it escapes).
        let mut length = vec![f32::INFINITY; n];
        for (k, &r) in hits.points.ray_id.iter().enumerate() {
            length[r as usize] = hits.points.vlen[k];
        }
        let mut vs = self.ctx.begin_volume_sampling();
        let (mut p, mut vn, mut t) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n], vec![0.0; n]);
        match services.lighting {
            Some(lighting) => {
                // Single scattering: one distance per ray from the exponential truncated to
                // the segment, pdf sigma_t e^{-sigma_t t} / c with c = 1 - e^{-sigma_t len}, so
                // sigma_t T(t) / pdf = c (the phase function's weight carries the albedo).
                let mut weight = vec![Rgb::BLACK; n];
                for i in 0..n {
                    let u = samplers[i].next_1d();
                    let len = length[i];
                    p[i] = rays.origin[i];
                    vn[i] = -rays.direction[i];
                    if len.is_finite() {
                        let c = -(-s * len).exp_m1();
                        t[i] = -(-u * c).ln_1p() / s;
                        p[i] += rays.direction[i] * t[i];
                        weight[i] = Rgb::splat(c);
                    }
                }
                vs.set_builtin(Builtin::P, &p);
                vs.set_builtin(Builtin::Vn, &vn);
                vs.set_vlen(&t);
                let vctx = vs.context();
                let phase = services.factory.begin_scatter(
                    &vctx,
                    ShadingMode::VolumeScatter,
                    services.arena,
                );
                lighting.perform_direct_lighting(&vctx, phase, rays, samplers, &weight);
                // The hits behind, attenuated over their segments.
                hits.attenuate_segments(rays, |d| self.transmittance(d));
                out.append_offset(&hits, 0);
            }
            None => {
                // No delegate: a free flight per ray (pdf sigma_t e^{-sigma_t t}); the rays
                // that stop inside become a VolumeScatter group for the global integrator
                // (transmission sigma_t T / pdf = 1, the phase function's weight carries the
                // albedo), the others keep their hit (T(len) / P(pass) = 1).
                let mut member = vec![false; n];
                for i in 0..n {
                    let u = samplers[i].next_1d();
                    let d = -(-u).ln_1p() / s;
                    p[i] = rays.origin[i];
                    vn[i] = -rays.direction[i];
                    if d < length[i] {
                        member[i] = true;
                        t[i] = d;
                        p[i] += rays.direction[i] * d;
                    }
                }
                vs.set_builtin(Builtin::P, &p);
                vs.set_builtin(Builtin::Vn, &vn);
                vs.set_vlen(&t);
                vs.set_transmission(&vec![Rgb::WHITE; n]);
                for g in &hits.groups {
                    let start = out.points.len();
                    for k in g.range.clone() {
                        if !member[hits.points.ray_id[k] as usize] {
                            out.points.push_from(&hits.points, k);
                        }
                    }
                    out.close_group(g.material, g.mode, start);
                }
                vs.end_volume_sampling(&member, out);
            }
        }
    }

    fn transmission(
        &self,
        segments: &Segments,
        _samplers: &mut [PathSampler],
        _ictx: &dyn IntegratorContext,
        trans: &mut [Rgb],
        emission: &mut [Rgb],
    ) {
        for i in 0..segments.len() {
            trans[i] = self.transmittance(segments.length[i]);
        }
        emission.fill(Rgb::BLACK);
    }
}

// ---------------------------------------------------------------------------------------
// Scenes and closed forms.
// ---------------------------------------------------------------------------------------

/// Simpson's rule for `f` on `[a, b]` with `n` (even) intervals.
fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let h = (b - a) / n as f64;
    let mut sum = f(a) + f(b);
    for k in 1..n {
        sum += f(a + k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    sum * h / 3.0
}

const SIGMA_T: f32 = 1.0;
const ALBEDO: f32 = 0.8;
const THICKNESS: f32 = 1.0;
/// Height of the point light above the slab.
const LAMP_HEIGHT: f32 = 0.5;

/// Single-scattered radiance under a point light of intensity 1 (module docs).
fn expected_point_light() -> f64 {
    let (s, h) = (SIGMA_T as f64, LAMP_HEIGHT as f64);
    let integral = simpson(
        |t| (-2.0 * s * t).exp() / (h + t).powi(2),
        0.0,
        THICKNESS as f64,
        20_000,
    );
    (ALBEDO as f64 * s) / (4.0 * std::f64::consts::PI) * integral
}

/// Single-scattered radiance under a constant environment of radiance 1 (module docs).
fn expected_environment() -> f64 {
    let tau = (SIGMA_T * THICKNESS) as f64;
    let integral = simpson(
        |mu| {
            if mu == 0.0 {
                0.0
            } else {
                mu / (1.0 + mu) * (1.0 - (-tau * (1.0 + 1.0 / mu)).exp())
            }
        },
        0.0,
        1.0,
        20_000,
    );
    ALBEDO as f64 / 2.0 * integral
}

enum Lighting {
    Point,
    Environment,
}

/// The slab `-d <= z <= 0` (100 x 100 wide) on a black plane, seen at normal incidence by an
/// orthographic camera 0.004 wide (so the whole image is the point below the lamp).
fn slab_scene(lighting: Lighting, spp: u32) -> CompiledScene {
    let (w, h) = (32, 32);
    let mut scene = Scene::new(
        ortho_camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 0.004, w, h),
        settings(w, h, spp, 64),
    );
    let medium = scene.add_material(
        "medium",
        0,
        Box::new(SlabMedium {
            sigma_t: SIGMA_T,
            albedo: ALBEDO,
        }),
    );
    add_box(
        &mut scene,
        "slab",
        Vec3::new(-50.0, -50.0, -THICKNESS),
        Vec3::new(50.0, 50.0, 0.0),
        medium,
    );
    let black = scene.add_material(
        "black",
        0,
        mat(Surface::Diffuse {
            reflectance: Rgb::BLACK,
        }),
    );
    scene.add_shape(
        "ground",
        quad(
            Vec3::new(-500.0, -500.0, -THICKNESS - 0.5),
            Vec3::X * 1000.0,
            Vec3::Y * 1000.0,
        ),
        black,
        None,
    );
    match lighting {
        Lighting::Point => {
            scene.add_light(
                "lamp",
                LightComponent::Point {
                    position: Vec3::new(0.0, 0.0, LAMP_HEIGHT),
                    intensity: Rgb::WHITE,
                },
            );
        }
        Lighting::Environment => environment(&mut scene, Rgb::WHITE),
    }
    scene.compile().unwrap()
}

/// Asserts that `out`'s image mean is `expected` within 3 standard errors, and that 3
/// standard errors are under 1% (so the comparison can fail).
fn assert_matches(out: &RenderOutput, expected: f64, what: &str) {
    assert_eq!(out.stats.counters.nan_dropped, 0, "{what}: NaN samples");
    assert!(out.beauty.pixels.iter().all(|p| p.is_finite()), "{what}");
    let (mean, se) = image_mean(out);
    let e = expected as f32;
    for c in 0..3 {
        let (m, s) = (mean.to_array()[c], se.to_array()[c]);
        eprintln!(
            "{what}: channel {c}: {m:.6} +- {s:.6}, closed form {e:.6}, ratio {:.4}",
            m / e
        );
        assert!(
            3.0 * s < 0.01 * e,
            "{what}: standard error {s} too large for 1%"
        );
        assert!(
            (m - e).abs() <= 3.0 * s,
            "{what}: channel {c}: {m} +- {s}, closed form {e} (ratio {})",
            m / e
        );
    }
}

fn direct_only(scene: &CompiledScene) -> RenderOutput {
    let integrator = DirectOnly {
        dimension_offset: 64,
    };
    render_with(&integrator, scene, &RenderOptions::default(), &|_| {}).unwrap()
}

// ---------------------------------------------------------------------------------------
// Tests.
// ---------------------------------------------------------------------------------------

/// A diffuse room (floor, block, an area lamp, a point light, an environment) with the
/// render seed `seed`.
fn diffuse_room(seed: u64) -> CompiledScene {
    let (w, h) = (32, 32);
    let mut settings = settings(w, h, 64, 2);
    settings.seed = seed;
    let mut scene = Scene::new(
        perspective(
            Vec3::new(0.0, 1.5, 4.0),
            Vec3::new(0.0, 0.5, 0.0),
            60.0,
            w,
            h,
        ),
        settings,
    );
    let grey = scene.add_material(
        "grey",
        0,
        mat(Surface::Diffuse {
            reflectance: Rgb::new(0.7, 0.5, 0.3),
        }),
    );
    scene.add_shape(
        "floor",
        quad(Vec3::new(-3.0, 0.0, -3.0), Vec3::Z * 6.0, Vec3::X * 6.0),
        grey,
        None,
    );
    add_box(
        &mut scene,
        "block",
        Vec3::new(-0.4, 0.0, -0.6),
        Vec3::new(0.6, 1.0, 0.4),
        grey,
    );
    // A 1 x 1 lamp at y = 2.5 facing down, visible to the camera.
    scene.add_shape(
        "lamp",
        ShapeGeometry::Triangles(quad_tris(Vec3::new(-1.5, 2.5, -1.5), Vec3::X, Vec3::Z)),
        grey,
        Some(Rgb::splat(4.0)),
    );
    scene.add_light(
        "bulb",
        LightComponent::Point {
            position: Vec3::new(1.5, 1.5, 1.0),
            intensity: Rgb::splat(2.0),
        },
    );
    environment(&mut scene, Rgb::new(0.2, 0.3, 0.4));
    scene.compile().unwrap()
}

#[test]
fn direct_only_integrator_matches_the_path_tracer_at_max_depth_2() {
    // Different seeds: the two estimates are independent.
    let pt = render(&diffuse_room(1), &RenderOptions::default(), &|_| {}).unwrap();
    let direct = direct_only(&diffuse_room(2));
    for out in [&pt, &direct] {
        assert_eq!(out.stats.counters.nan_dropped, 0);
    }
    // 4 x 4 blocks of 8 x 8 pixels, each channel within 3 sigma of the difference.
    let mut worst: f32 = 0.0;
    for by in 0..4 {
        for bx in 0..4 {
            let (xs, ys) = (bx * 8..bx * 8 + 8, by * 8..by * 8 + 8);
            let (a, sa) = crop_mean(&pt, xs.clone(), ys.clone());
            let (b, sb) = crop_mean(&direct, xs, ys);
            for c in 0..3 {
                let (a, b) = (a.to_array()[c], b.to_array()[c]);
                let s = (sa.to_array()[c].powi(2) + sb.to_array()[c].powi(2)).sqrt();
                let z = (a - b).abs() / s.max(1e-9);
                worst = worst.max(z);
                assert!(
                    z <= 3.0,
                    "block ({bx}, {by}) channel {c}: path tracer {a}, direct only {b}, sigma {s}"
                );
                // The test can fail: the noise is far below the signal.
                assert!(s < 0.05 * a.max(b), "block ({bx}, {by}): sigma {s} vs {a}");
            }
        }
    }
    eprintln!("worst block difference: {worst:.2} sigma");
}

#[test]
fn delegate_single_scattering_under_a_point_light_matches_the_closed_form() {
    let out = render(
        &slab_scene(Lighting::Point, 128),
        &RenderOptions::default(),
        &|_| {},
    )
    .unwrap();
    assert_matches(&out, expected_point_light(), "point light, delegate");
}

#[test]
fn delegate_single_scattering_under_an_environment_matches_chandrasekhar() {
    let out = render(
        &slab_scene(Lighting::Environment, 512),
        &RenderOptions::default(),
        &|_| {},
    )
    .unwrap();
    assert_matches(&out, expected_environment(), "environment, delegate");
}

#[test]
fn without_a_delegate_the_medium_returns_volume_points_and_still_matches() {
    // Under the direct-only integrator (no delegate) the interior returns its in-volume points
    // as a VolumeScatter group; the integrator lights them once: single scattering again.
    // (A free flight stops in the slab with probability 1 - e^{-tau}: more samples.)
    let out = direct_only(&slab_scene(Lighting::Point, 256));
    assert_matches(&out, expected_point_light(), "point light, no delegate");
    let out = direct_only(&slab_scene(Lighting::Environment, 1024));
    assert_matches(&out, expected_environment(), "environment, no delegate");
}

#[test]
fn closed_forms_are_what_the_limits_say() {
    // Thick slab under the environment: omega / 2 (1 - ln 2); the numbers above are below it.
    let e = expected_environment();
    let thick = ALBEDO as f64 / 2.0 * (1.0 - std::f64::consts::LN_2);
    assert!(e < thick && e > 0.5 * thick, "{e} vs {thick}");
    let p = expected_point_light();
    assert!(p > 0.0 && p < ALBEDO as f64 / (4.0 * std::f64::consts::PI) / 0.25);
}

/// A user's integrator that renders in iterations (`Integrator::iteration_paths`), as the
/// built-in `vcm` does: it logs every call, and a batch's radiance is the number of light
/// passes its iteration ran before it.
struct IterationProbe {
    max_paths: usize,
    log: std::sync::Mutex<Vec<Call>>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Call {
    Begin {
        sample: u32,
        camera_samples: usize,
    },
    Light {
        pixel: u32,
        sample: u32,
        paths: usize,
    },
    End,
    Camera {
        pixel: u32,
        sample: u32,
        paths: usize,
    },
}

impl IterationProbe {
    fn push(&self, c: Call) {
        self.log.lock().unwrap().push(c);
    }
}

impl Integrator for IterationProbe {
    type Worker = ();

    fn run_batch(
        &self,
        _: &CompiledScene,
        batch: &mut PathBatch,
        _: &mut (),
        _: &mut SystemStats,
        _: &Bump,
    ) {
        let p = &batch.paths;
        self.push(Call::Camera {
            pixel: p.pixel[0],
            sample: p.sample[0],
            paths: p.len(),
        });
        let log = self.log.lock().unwrap();
        let begin = log
            .iter()
            .rposition(|c| matches!(c, Call::Begin { .. }))
            .unwrap();
        let lights = log[begin..]
            .iter()
            .filter(|c| matches!(c, Call::Light { .. }))
            .count();
        batch.paths.radiance.fill(Rgb::splat(lights as f32));
    }

    fn iteration_paths(&self) -> Option<usize> {
        Some(self.max_paths)
    }

    fn begin_iteration(&self, sample: u32, camera_samples: usize) {
        self.push(Call::Begin {
            sample,
            camera_samples,
        });
    }

    fn light_pass(
        &self,
        _: &CompiledScene,
        batch: &PathBatch,
        _: &mut (),
        _: &mut SystemStats,
        _: &Bump,
    ) {
        let p = &batch.paths;
        self.push(Call::Light {
            pixel: p.pixel[0],
            sample: p.sample[0],
            paths: p.len(),
        });
    }

    fn end_light_pass(&self, _: &mut SystemStats) {
        self.push(Call::End);
    }
}

/// The iteration contract, from a plug-in's side: a user's integrator gets one iteration per
/// sample index and group of tiles (at most its `iteration_paths` pixels a group, at least
/// one tile), every batch of the iteration first in its light pass and then, after
/// `end_light_pass`, in its camera pass, the same batches in both, each pixel and sample
/// once; and the image is what its camera passes made.
#[test]
fn a_user_integrator_renders_in_iterations() {
    let (w, h, spp) = (32u32, 24u32, 3u32);
    let scene = Scene::new(
        perspective(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 40.0, w, h),
        settings(w, h, spp, 4),
    )
    .compile()
    .unwrap();
    // 16 x 16 tiles, row by row: 256, 256, 128 and 128 pixels; at most 600 a group takes
    // two tiles (600 / 256), so groups of 512 and 256 pixels. A tile's batch is its pixels
    // at one sample index (a batch never cuts a pixel's run of samples).
    let probe = IterationProbe {
        max_paths: 600,
        log: Default::default(),
    };
    let options = RenderOptions {
        threads: Some(2),
        tile_size: 16,
        batch_size: 64,
        ..RenderOptions::default()
    };
    let out = render_with(&probe, &scene, &options, &|_| {}).unwrap();
    let log = probe.log.into_inner().unwrap();
    let mut seen = std::collections::HashSet::new();
    let mut iterations = 0;
    for it in log.split(|c| matches!(c, Call::Begin { .. })).skip(1) {
        iterations += 1;
        let end = it.iter().position(|c| *c == Call::End).expect("an end");
        let key = |c: &Call| match *c {
            Call::Light {
                pixel,
                sample,
                paths,
            }
            | Call::Camera {
                pixel,
                sample,
                paths,
            } => (pixel, sample, paths),
            _ => panic!("{c:?} inside an iteration's pass"),
        };
        let mut light: Vec<_> = it[..end].iter().map(key).collect();
        let mut camera: Vec<_> = it[end + 1..].iter().map(key).collect();
        assert!(!light.is_empty(), "an iteration without batches");
        light.sort_unstable();
        camera.sort_unstable();
        assert_eq!(light, camera, "the two passes' batches differ");
        let paths: usize = camera.iter().map(|b| b.2).sum();
        assert!(paths <= 600, "an iteration of {paths} pixels");
        for b in camera {
            assert!(seen.insert((b.0, b.1)), "batch {b:?} rendered twice");
        }
    }
    let begins: Vec<(u32, usize)> = log
        .iter()
        .filter_map(|c| match *c {
            Call::Begin {
                sample,
                camera_samples,
            } => Some((sample, camera_samples)),
            _ => None,
        })
        .collect();
    // Two groups of two tiles for each of 3 sample indices, in sample order; every pixel
    // and sample rendered.
    assert_eq!(iterations, 6);
    let sizes: Vec<usize> = begins.iter().map(|b| b.1).collect();
    assert_eq!(sizes, [512, 256].repeat(3));
    assert!(begins.windows(2).all(|b| b[0].0 <= b[1].0));
    assert_eq!(seen.len(), 4 * 3);
    // Every camera batch came after both light passes of its iteration.
    assert!(
        out.beauty.pixels.iter().all(|p| p.to_array() == [2.0; 3]),
        "a camera pass ran before its iteration's light passes were done"
    );
}
