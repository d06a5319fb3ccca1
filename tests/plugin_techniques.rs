//! A technique declared by a material written outside the engine (issue 31, point 3): the
//! contract names no plug-in, so `risotto techniques`, `render --technique` and `converge`
//! must treat a user's declaration exactly as the built-ins' (`scattering`, `tracking`,
//! `subsurface`).
//!
//! The material `Smoke` is an index-matched ball whose interior absorbs like Beer's law,
//! and declares the technique `absorption` with the values `scene` (its own coefficient,
//! the default) and `double` (twice it, an approximation that does not converge to the
//! scene). Its interior reads the choice through the integrator context, on path rays
//! (`nearest_hits`) and shadow rays (`transmission`) alike.

mod common;

use bumpalo::Bump;
use common::{camera, environment, settings};
use glam::Vec3;
use risotto::builtins::builtin::BeerInterior;
use risotto::components::{LobeSampled, Rays, Rgb};
use risotto::engine::plugin::*;
use risotto::engine::render::{render, RenderOptions};
use risotto::engine::scene::{CompiledScene, Scene, ShapeGeometry};
use risotto::engine::technique::{listing, TechniqueRegistry, Techniques};
use risotto::systems::geometry::Sphere;
use risotto::systems::sampler::PathSampler;
use risotto::tools::converge::{
    run, AdaptivePlan, ConvergeOptions, Progress, Reference, SppPlan, Variant,
};

/// The declaration, as data.
static ABSORPTION: Technique = Technique {
    name: "absorption",
    summary: "how strongly the smoke absorbs",
    values: &[
        TechniqueValue {
            name: "scene",
            summary: "the material's own sigma_a",
            converges: always,
        },
        TechniqueValue {
            name: "double",
            summary: "twice it (an approximation)",
            converges: never,
        },
    ],
    default: "scene",
    applies_to: "scenes with smoke",
};

static SMOKE_TECHNIQUES: [&Technique; 1] = [&ABSORPTION];

/// Absorption coefficient of the smoke, per unit length.
const SIGMA_A: f32 = 0.5;

struct Smoke;

/// The interior's coefficient under the render's choice of `absorption`.
fn sigma_a(ictx: &dyn IntegratorContext) -> f32 {
    match ictx.technique(ABSORPTION.name) {
        Some("double") => 2.0 * SIGMA_A,
        _ => SIGMA_A,
    }
}

/// Beer-Lambert absorption (the built-in `beer` interior) with the coefficient the render's
/// choice of `absorption` gives, read through the context on every call.
struct SmokeInterior;

impl VolumeIntegrator for SmokeInterior {
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        samplers: &mut [PathSampler],
        lobes_wanted: LobeSampled,
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
        let sigma_a = Rgb::splat(sigma_a(services.ictx));
        BeerInterior { sigma_a }.nearest_hits(rays, samplers, lobes_wanted, services, out);
    }
    fn transmission(
        &self,
        segments: &Segments,
        samplers: &mut [PathSampler],
        ictx: &dyn IntegratorContext,
        trans: &mut [Rgb],
        emission: &mut [Rgb],
    ) {
        let sigma_a = Rgb::splat(sigma_a(ictx));
        BeerInterior { sigma_a }.transmission(segments, samplers, ictx, trans, emission);
    }
}

impl BxdfFactory for Smoke {
    fn instance_hints(&self) -> InstanceHints {
        InstanceHints::INDEX_MATCHED
            | InstanceHints::TRANSMISSION_SHADOWS
            | InstanceHints::TRANSMITS
            | InstanceHints::COMPUTES_INTERIOR
            | InstanceHints::INTERIOR_TRANSMISSION
    }
    fn begin_scatter<'a>(
        &'a self,
        _ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a) {
        arena.alloc(NullBxdf)
    }
    fn begin_interior<'a>(
        &'a self,
        _ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> Option<&'a mut (dyn VolumeIntegrator + 'a)> {
        Some(arena.alloc(SmokeInterior))
    }
    fn shadow_transmittance(&self) -> Rgb {
        Rgb::WHITE
    }
    fn techniques(&self) -> &'static [&'static Technique] {
        &SMOKE_TECHNIQUES
    }
}

/// A ball of smoke of radius 1 at the origin against a white sky, seen from z = 4.
fn smoke_scene(size: u32, spp: u32) -> CompiledScene {
    let mut scene = Scene::new(camera(30.0, 4.0, size, size), settings(size, size, spp, 8));
    let m = scene.add_material("smoke", 0, Box::new(Smoke));
    scene.add_shape(
        "ball",
        ShapeGeometry::Sphere(Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        }),
        m,
        None,
    );
    environment(&mut scene, Rgb::WHITE);
    scene.compile().unwrap()
}

#[test]
fn a_declared_technique_is_listed_parsed_and_swept_like_a_built_in_one() {
    let scene = smoke_scene(8, 1);
    let registry = TechniqueRegistry::for_scene(&scene);
    let names: Vec<_> = registry.applicable().map(|t| t.name).collect();
    assert_eq!(names, ["integrator", "lighting", "sampler", "absorption"]);
    let text = listing(&registry);
    assert!(
        text.contains("absorption: how strongly the smoke absorbs (applies to scenes with smoke)")
            && text.contains("* absorption=scene")
            && text.contains("absorption=double"),
        "{text}"
    );
    let double = Techniques::parse(&registry, "absorption=double").unwrap();
    assert_eq!(double.plugins.get("absorption"), Some("double"));
    assert!(double.check_applicable(&registry).is_ok());
    assert!(!double.converges(&registry), "declared as an approximation");
    let labels: Vec<_> = Techniques::variants(&registry)
        .iter()
        .map(|t| t.label())
        .collect();
    assert!(
        labels.contains(&"absorption=double".to_string()),
        "{labels:?}"
    );
    // A value the declaration does not have is named in the error.
    let e = Techniques::parse(&registry, "absorption=triple").unwrap_err();
    assert!(e.to_string().contains("scene, double"), "{e}");
}

#[test]
fn the_plug_in_reads_the_chosen_value_through_the_context() {
    let scene = smoke_scene(9, 4);
    let registry = TechniqueRegistry::for_scene(&scene);
    let centre = |spec: &str| {
        let t = Techniques::parse(&registry, spec).unwrap();
        let out = render(&scene, &t.render_options(RenderOptions::default()), &|_| {}).unwrap();
        out.beauty.get(4, 4).g
    };
    // The centre pixel's ray crosses the ball along (nearly) its diameter: 2 units.
    let scene_value = centre("absorption=scene");
    let doubled = centre("absorption=double");
    let expect = |s: f32| (-2.0 * s).exp();
    assert!(
        (scene_value / expect(SIGMA_A) - 1.0).abs() < 0.02,
        "{scene_value} against {}",
        expect(SIGMA_A)
    );
    assert!(
        (doubled / expect(2.0 * SIGMA_A) - 1.0).abs() < 0.02,
        "{doubled} against {}",
        expect(2.0 * SIGMA_A)
    );
}

#[test]
fn converge_sweeps_a_declared_technique_and_keeps_it_out_of_the_reference() {
    let mut scene = smoke_scene(8, 1);
    let registry = TechniqueRegistry::for_scene(&scene);
    let options = ConvergeOptions {
        variants: Techniques::variants(&registry)
            .into_iter()
            .filter(|t| {
                matches!(
                    t.label().as_str(),
                    "lighting=mis+sampler=sobol" | "absorption=double"
                )
            })
            .map(Variant::from)
            .collect(),
        plan: SppPlan::List(vec![1, 2]),
        adaptive: AdaptivePlan::default(),
        repeats: 1,
        reference: Reference::Render {
            spp: Some(8),
            techniques: None,
        },
        render: RenderOptions::default(),
        metric: Default::default(),
    };
    assert_eq!(options.variants.len(), 2);
    let progress = Progress {
        stage: &|_| {},
        samples: &|_| {},
    };
    let sweep = run(&mut scene, &options, &progress).unwrap();
    let labels: Vec<_> = sweep.curves.iter().map(|c| c.label.as_str()).collect();
    assert_eq!(labels, ["lighting=mis+sampler=sobol", "absorption=double"]);
    // Each curve names every applicable technique's value, the declared one included.
    let doubled = &sweep.curves[1];
    assert_eq!(
        doubled.techniques.get("absorption").map(String::as_str),
        Some("double")
    );
    // The reference is rendered with a variant that converges: not `double`.
    assert_eq!(
        sweep.reference.techniques.as_deref(),
        Some("lighting=mis+sampler=sobol")
    );
    // The doubled smoke is darker than the reference: its error does not vanish.
    assert!(doubled.points.iter().all(|p| p.mse > 0.0));
}
