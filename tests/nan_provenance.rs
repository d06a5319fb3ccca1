//! NaN provenance (issue 14): a plug-in that produces NaN is named in the render's stats by
//! the stage whose output it poisoned, and the film stays finite.

mod common;
use bumpalo::Bump;
use common::*;
use glam::Vec3;
use risotto::builtins::builtin::{DielectricBxdf, DiffuseBxdf, Surface};
use risotto::builtins::phase::PhaseBxdf;
use risotto::components::{LobeSampled, Rays, Rgb};
use risotto::engine::path_tracer::VertexEvent;
use risotto::engine::plugin::IntegratorContext;
use risotto::engine::plugin::{
    Bxdf, BxdfFactory, InstanceHints, Segments, ShadeGroups, ShadingContext, ShadingMode,
    VolumeIntegrator, VolumeServices,
};
use risotto::engine::render::{render, RenderOptions, RenderOutput};
use risotto::engine::replay::replay;
use risotto::engine::scene::{CompiledScene, LightComponent, Scene, ShapeGeometry};
use risotto::engine::stats::{NonFiniteCase, Stage, MAX_NON_FINITE_CASES};
use risotto::systems::bxdf_samples::BxdfSamples;
use risotto::systems::geometry::Sphere;
use risotto::systems::phase::PhaseFunction;
use risotto::systems::sampler::PathSampler;

/// A white diffuse surface whose sampled weights (`false`) or evaluations towards light
/// samples (`true`) are NaN at points with `x > 0`.
struct PoisonedDiffuse(bool);

struct PoisonedDiffuseBxdf(DiffuseBxdf, bool);

/// Whether point `i` of `ctx` is poisoned.
fn poisoned(ctx: &ShadingContext<'_>, i: usize) -> bool {
    ctx.p()[i].x > 0.0
}

impl Bxdf for PoisonedDiffuseBxdf {
    fn lobes(&self) -> LobeSampled {
        self.0.lobes()
    }
    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    ) {
        self.0.generate_samples(ctx, samplers, out);
        for i in (0..samplers.len()).filter(|&i| !self.1 && poisoned(ctx, i)) {
            out.weight[i] = Rgb::splat(f32::NAN);
        }
    }
    fn evaluate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        wi: &[Vec3],
        value: &mut [Rgb],
        pdf: &mut [f32],
    ) {
        self.0.evaluate_samples(ctx, wi, value, pdf);
        for i in (0..wi.len()).filter(|&i| self.1 && poisoned(ctx, i)) {
            value[i] = Rgb::splat(f32::NAN);
        }
    }
}

impl BxdfFactory for PoisonedDiffuse {
    fn instance_hints(&self) -> InstanceHints {
        InstanceHints::NONE
    }
    fn begin_scatter<'a>(
        &'a self,
        _ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a) {
        let diffuse = DiffuseBxdf {
            reflectance: Rgb::WHITE,
        };
        arena.alloc(PoisonedDiffuseBxdf(diffuse, self.0))
    }
}

/// Glass (index 1, so rays go straight through) whose interior's integrator writes NaN
/// transmissions: for the hits it returns and, on shadow rays, in `transmission`.
struct PoisonedGlass;

#[derive(Clone, Copy)]
struct NanInterior;

impl BxdfFactory for PoisonedGlass {
    fn instance_hints(&self) -> InstanceHints {
        InstanceHints::TRANSMITS
            | InstanceHints::COMPUTES_INTERIOR
            | InstanceHints::INTERIOR_TRANSMISSION
            | InstanceHints::TRANSMISSION_SHADOWS
    }
    fn begin_scatter<'a>(
        &'a self,
        _ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a) {
        arena.alloc(DielectricBxdf {
            ior: 1.0,
            tint: Rgb::WHITE,
        })
    }
    fn begin_interior<'a>(
        &'a self,
        _ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> Option<&'a mut (dyn VolumeIntegrator + 'a)> {
        Some(arena.alloc(NanInterior))
    }
    fn shadow_transmittance(&self) -> Rgb {
        Rgb::WHITE
    }
}

impl VolumeIntegrator for NanInterior {
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        _samplers: &mut [PathSampler],
        _lobes_wanted: LobeSampled,
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
        services.ictx.nearest_hits(rays, out);
        out.attenuate_segments(rays, |_| Rgb::splat(f32::NAN));
    }
    fn transmission(
        &self,
        segments: &Segments,
        _samplers: &mut [PathSampler],
        _ictx: &dyn IntegratorContext,
        trans: &mut [Rgb],
        emission: &mut [Rgb],
    ) {
        trans[..segments.len()].fill(Rgb::splat(f32::NAN));
        emission.fill(Rgb::BLACK);
    }
}

/// Glass (index 1) around a volume whose integrator lights the rays' origins through the
/// path tracer's lighting delegate with a phase function that evaluates to NaN (and then
/// lets the rays through unattenuated).
struct DelegateNanGlass;

struct DelegateNanInterior<'a> {
    ctx: &'a ShadingContext<'a>,
}

/// An isotropic phase function whose evaluations towards light samples are NaN.
struct NanPhase(PhaseBxdf<'static>);

impl Bxdf for NanPhase {
    fn lobes(&self) -> LobeSampled {
        self.0.lobes()
    }
    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    ) {
        self.0.generate_samples(ctx, samplers, out);
    }
    fn evaluate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        wi: &[Vec3],
        value: &mut [Rgb],
        pdf: &mut [f32],
    ) {
        self.0.evaluate_samples(ctx, wi, value, pdf);
        value.fill(Rgb::splat(f32::NAN));
    }
}

impl BxdfFactory for DelegateNanGlass {
    fn instance_hints(&self) -> InstanceHints {
        InstanceHints::TRANSMITS
            | InstanceHints::COMPUTES_INTERIOR
            | InstanceHints::INTERIOR_TRANSMISSION
            | InstanceHints::TRANSMISSION_SHADOWS
    }
    fn begin_scatter<'a>(
        &'a self,
        _ctx: &'a ShadingContext<'a>,
        mode: ShadingMode,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a) {
        let phase = PhaseBxdf::weighted(PhaseFunction::Isotropic, Rgb::WHITE);
        match mode {
            ShadingMode::VolumeScatter => arena.alloc(NanPhase(phase)),
            _ => arena.alloc(DielectricBxdf {
                ior: 1.0,
                tint: Rgb::WHITE,
            }),
        }
    }
    fn begin_interior<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> Option<&'a mut (dyn VolumeIntegrator + 'a)> {
        Some(arena.alloc(DelegateNanInterior { ctx }))
    }
    fn shadow_transmittance(&self) -> Rgb {
        Rgb::WHITE
    }
}

impl VolumeIntegrator for DelegateNanInterior<'_> {
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        samplers: &mut [PathSampler],
        _lobes_wanted: LobeSampled,
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
        if let Some(lighting) = services.lighting {
            let vs = self.ctx.begin_volume_sampling();
            let vctx = vs.context();
            let phase =
                services
                    .factory
                    .begin_scatter(&vctx, ShadingMode::VolumeScatter, services.arena);
            let weight = vec![Rgb::WHITE; rays.len()];
            lighting.perform_direct_lighting(&vctx, phase, rays, samplers, &weight);
        }
        services.ictx.nearest_hits(rays, out);
    }
    fn transmission(
        &self,
        segments: &Segments,
        _samplers: &mut [PathSampler],
        _ictx: &dyn IntegratorContext,
        trans: &mut [Rgb],
        emission: &mut [Rgb],
    ) {
        trans[..segments.len()].fill(Rgb::WHITE);
        emission.fill(Rgb::BLACK);
    }
}

/// Renders [`sphere_scene`] with default options.
fn render_sphere(factory: Box<dyn BxdfFactory>) -> RenderOutput {
    render_default(&sphere_scene(factory))
}

/// A unit sphere of `factory` (material "ball") above a grey floor (y = -1), lit by a point
/// light above and a dim sky, seen from the front by a 16x16 camera at x = 0, so world
/// `x > 0` is the right half of the image.
fn sphere_scene(factory: Box<dyn BxdfFactory>) -> CompiledScene {
    let (w, h) = (16, 16);
    let cam = perspective(Vec3::new(0.0, 0.5, 5.0), Vec3::ZERO, 45.0, w, h);
    let mut scene = Scene::new(cam, settings(w, h, 4, 6));
    let ball = scene.add_material("ball", 1, factory);
    let floor = scene.add_material(
        "floor",
        0,
        mat(Surface::Diffuse {
            reflectance: Rgb::splat(0.5),
        }),
    );
    scene.add_shape(
        "ball",
        ShapeGeometry::Sphere(Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        }),
        ball,
        None,
    );
    let s = 10.0;
    scene.add_shape(
        "floor",
        quad(
            Vec3::new(-s, -1.0, s),
            Vec3::new(2.0 * s, 0.0, 0.0),
            Vec3::new(0.0, 0.0, -2.0 * s),
        ),
        floor,
        None,
    );
    scene.add_light(
        "lamp",
        LightComponent::Point {
            position: Vec3::new(0.0, 4.0, 0.0),
            intensity: Rgb::splat(10.0),
        },
    );
    environment(&mut scene, Rgb::splat(0.2));
    scene.compile().unwrap()
}

fn assert_film_finite(out: &RenderOutput) {
    for (i, p) in out.beauty.pixels.iter().enumerate() {
        assert!(p.is_finite(), "pixel {i} is {p:?}");
    }
}

/// The stats' non-finite count of `stage`, checked against the JSON and the summary.
fn reported(out: &RenderOutput, stage: Stage) -> u64 {
    let n = out.stats.counters.non_finite[stage as usize];
    let json: serde_json::Value = serde_json::from_str(&out.stats.to_json()).unwrap();
    let summary = out.stats.to_string();
    if n > 0 {
        assert_eq!(json["non_finite"][stage.name()], n, "{json}");
        assert!(
            summary.contains(&format!(" {} {n}", stage.name())),
            "{summary}"
        );
    } else {
        assert!(json["non_finite"].get(stage.name()).is_none(), "{json}");
    }
    n
}

#[test]
fn a_bxdf_writing_nan_weights_is_named_and_the_film_stays_finite() {
    for evaluations in [false, true] {
        let out = render_sphere(Box::new(PoisonedDiffuse(evaluations)));
        assert_film_finite(&out);
        assert!(reported(&out, Stage::Bxdf) > 0, "{}", out.stats);
        for stage in Stage::ALL.into_iter().filter(|&s| s != Stage::Bxdf) {
            assert_eq!(reported(&out, stage), 0, "{}: {}", stage.name(), out.stats);
        }
        if !evaluations {
            // A NaN sample weight ends its path (counted as absorbed): nothing reached the
            // film.
            assert_eq!(out.stats.counters.nan_dropped, 0);
        }
    }
}

#[test]
fn a_volume_integrator_writing_nan_transmission_is_named_and_the_film_stays_finite() {
    let out = render_sphere(Box::new(PoisonedGlass));
    assert_film_finite(&out);
    // Rays inside the ball get NaN transmissions from `nearest_hits`; shadow rays from the
    // floor to the lamp cross it and get NaN from `transmission`.
    assert!(reported(&out, Stage::Volume) > 0, "{}", out.stats);
    assert!(reported(&out, Stage::Transmission) > 0, "{}", out.stats);
    // Later stages fed a poisoned throughput do not count it again.
    for stage in Stage::ALL {
        if ![Stage::Volume, Stage::Transmission].contains(&stage) {
            assert_eq!(reported(&out, stage), 0, "{}: {}", stage.name(), out.stats);
        }
    }
    // The poisoned samples were dropped at the film, not written.
    assert!(out.stats.counters.nan_dropped > 0, "{}", out.stats);
}

/// The render's non-finite cases, checked against the JSON and the summary.
fn cases(out: &RenderOutput) -> Vec<NonFiniteCase> {
    let cases = out.stats.non_finite_cases.clone();
    let json: serde_json::Value = serde_json::from_str(&out.stats.to_json()).unwrap();
    let summary = out.stats.to_string();
    if cases.is_empty() {
        assert!(json.get("non_finite_cases").is_none(), "{json}");
        assert!(!summary.contains("non-finite sample"), "{summary}");
        return cases;
    }
    let listed = json["non_finite_cases"].as_array().unwrap();
    assert_eq!(listed.len(), cases.len(), "{json}");
    for (c, j) in cases.iter().zip(listed) {
        assert_eq!(j["x"], c.x, "{j}");
        assert_eq!(j["y"], c.y, "{j}");
        assert_eq!(j["sample"], c.sample, "{j}");
        assert_eq!(j["depth"], c.depth, "{j}");
        assert_eq!(j["stage"], c.stage.name(), "{j}");
        assert_eq!(j["material"].as_str(), c.material.as_deref(), "{j}");
        let replay = format!("--replay {},{},{}", c.x, c.y, c.sample);
        assert!(j["replay"].as_str().unwrap().ends_with(&replay), "{j}");
        let line = format!(
            "non-finite sample: pixel ({}, {}) sample {} depth {} stage {}",
            c.x,
            c.y,
            c.sample,
            c.depth,
            c.stage.name()
        );
        let line = summary
            .lines()
            .find(|l| l.starts_with(&line))
            .unwrap_or_else(|| panic!("no {line:?} in {summary}"));
        assert!(
            line.ends_with(&format!("risotto render SCENE {replay}")),
            "{line}"
        );
    }
    cases
}

#[test]
fn non_finite_cases_name_pixel_sample_depth_stage_and_material() {
    let scene = sphere_scene(Box::new(PoisonedDiffuse(false)));
    let seed = scene.settings.seed;
    let out = render_default(&scene);
    let cases = cases(&out);
    assert_eq!(cases.len(), MAX_NON_FINITE_CASES, "{}", out.stats);
    // Sorted by (pixel index, sample), one per camera sample.
    let key = |c: &NonFiniteCase| (c.y * 16 + c.x, c.sample);
    assert!(
        cases.windows(2).all(|w| key(&w[0]) < key(&w[1])),
        "{cases:?}"
    );
    for c in &cases {
        assert_eq!(c.stage, Stage::Bxdf, "{c:?}");
        assert_eq!(c.material.as_deref(), Some("ball"), "{c:?}");
        assert_eq!(c.seed, seed);
        assert!(c.x < 16 && c.y < 16 && c.sample < 4, "{c:?}");
        // Seen directly, a poisoned point (world x > 0) is in the image's right half: the
        // camera sits at x = 0 and pixel columns 0..8 lie wholly left of the centre line.
        if c.depth == 0 {
            assert!(c.x >= 8, "{c:?}");
        }
    }
    assert!(cases.iter().any(|c| c.depth == 0), "{cases:?}");
    // The kept cases are the smallest keys: no pixel-sample before the first kept one, in
    // the rows above it, can have met the ball's right half directly (they see the sky).
    assert!(cases[0].y >= 2, "{cases:?}");
}

/// Replays every case of a render of `factory`'s ball and checks that the path meets a
/// non-finite value from `stage` at the recorded depth, first there, on the ball's poisoned
/// half (world x > 0), and that the replay's own stats name the same case.
fn replay_reproduces_the_cases(factory: Box<dyn BxdfFactory>, stage: Stage) {
    let scene = sphere_scene(factory);
    let out = render_default(&scene);
    let cases = cases(&out);
    assert_eq!(cases.len(), MAX_NON_FINITE_CASES, "{}", out.stats);
    for c in &cases {
        let r = replay(&scene, &RenderOptions::default(), c.x, c.y, c.sample).unwrap();
        let v = r
            .first_non_finite()
            .unwrap_or_else(|| panic!("{c:?}: the replay met no non-finite value\n{r}"));
        assert_eq!(v.depth, c.depth, "{c:?}\n{r}");
        assert!(v.non_finite.contains(&stage), "{c:?}\n{r}");
        match &v.event {
            VertexEvent::Surface {
                material, position, ..
            } => {
                assert_eq!(material, "ball", "{c:?}\n{r}");
                assert!(position.x > 0.0, "{c:?}: unpoisoned point {position}\n{r}");
            }
            e => panic!("{c:?}: non-finite at {e:?}\n{r}"),
        }
        // Every vertex before it was clean.
        let before = r.trace.vertices.iter().take_while(|w| w.depth < c.depth);
        assert!(before.clone().all(|w| w.non_finite.is_empty()), "{r}");
        assert_eq!(r.stats.non_finite_cases.len(), 1, "{}", r.stats);
        assert_eq!(r.stats.non_finite_cases[0], *c);
        let shown = r.to_string();
        assert!(shown.contains("<-- became non-finite here"), "{shown}");
        assert!(
            shown.contains(&format!("depth {}: surface of material \"ball\"", c.depth)),
            "{shown}"
        );
    }
}

#[test]
fn replaying_a_case_meets_the_nan_of_a_bxdf_sample_at_the_recorded_depth() {
    replay_reproduces_the_cases(Box::new(PoisonedDiffuse(false)), Stage::Bxdf);
}

#[test]
fn replaying_a_case_meets_the_nan_of_a_bxdf_evaluation_at_the_recorded_depth() {
    // Here the NaN reaches the path's radiance through the shadow ray: the film drops it.
    let scene = sphere_scene(Box::new(PoisonedDiffuse(true)));
    let out = render_default(&scene);
    let c = &cases(&out)[0];
    let r = replay(&scene, &RenderOptions::default(), c.x, c.y, c.sample).unwrap();
    assert!(!r.radiance().is_finite(), "{r}");
    assert!(r.to_string().ends_with("(dropped at the film)"), "{r}");
    assert_eq!(r.stats.counters.nan_dropped, 1);
    replay_reproduces_the_cases(Box::new(PoisonedDiffuse(true)), Stage::Bxdf);
}

#[test]
fn non_finite_cases_do_not_depend_on_threads_batches_or_tiles() {
    let scene = sphere_scene(Box::new(PoisonedDiffuse(true)));
    let run = |threads: usize, batch_size: usize, tile_size: u32| {
        let options = RenderOptions {
            threads: Some(threads),
            batch_size,
            tile_size,
            ..RenderOptions::default()
        };
        let out = render(&scene, &options, &|_| {}).unwrap();
        cases(&out)
    };
    let one = run(1, 4096, 16);
    assert_eq!(one.len(), MAX_NON_FINITE_CASES);
    assert_eq!(run(2, 4096, 16), one);
    assert_eq!(run(2, 7, 4), one);
}

#[test]
fn a_volume_integrators_cases_name_its_material() {
    let out = render_sphere(Box::new(PoisonedGlass));
    let cases = cases(&out);
    assert!(!cases.is_empty(), "{}", out.stats);
    for c in &cases {
        match c.stage {
            Stage::Volume => assert_eq!(c.material.as_deref(), Some("ball"), "{c:?}"),
            Stage::Transmission => assert_eq!(c.material, None, "{c:?}"),
            s => panic!("stage {} in {c:?}", s.name()),
        }
    }
    // Camera rays refract into the ball at its surface (the depth-0 vertex, a Bxdf of its
    // own); the interior answers the refracted rays, of depth 1, with NaN.
    assert!(
        cases
            .iter()
            .any(|c| c.stage == Stage::Volume && c.depth == 1),
        "{cases:?}"
    );
    assert!(cases.iter().all(|c| c.depth >= 1), "{cases:?}");
}

#[test]
fn the_lighting_delegates_non_finite_values_are_counted() {
    // The delegate's light sampling used to count into a throw-away accumulator.
    let out = render_sphere(Box::new(DelegateNanGlass));
    assert_film_finite(&out);
    assert!(reported(&out, Stage::Phase) > 0, "{}", out.stats);
    for stage in Stage::ALL.into_iter().filter(|&s| s != Stage::Phase) {
        assert_eq!(reported(&out, stage), 0, "{}: {}", stage.name(), out.stats);
    }
    assert!(out.stats.counters.nan_dropped > 0, "{}", out.stats);
    let cases = cases(&out);
    assert!(!cases.is_empty());
    for c in &cases {
        assert_eq!(c.stage, Stage::Phase, "{c:?}");
        assert_eq!(c.material.as_deref(), Some("ball"), "{c:?}");
        // Lit at the origins of the rays inside the ball (refracted at depth 0).
        assert!(c.depth >= 1, "{c:?}");
    }
}

#[test]
fn a_clean_render_reports_no_non_finite_stage() {
    let out = render_sphere(mat(Surface::Diffuse {
        reflectance: Rgb::splat(0.8),
    }));
    assert_film_finite(&out);
    for stage in Stage::ALL {
        assert_eq!(reported(&out, stage), 0, "{}: {}", stage.name(), out.stats);
    }
    let json: serde_json::Value = serde_json::from_str(&out.stats.to_json()).unwrap();
    assert!(json.get("non_finite").is_none(), "{json}");
    assert!(cases(&out).is_empty());
}
