//! The seed's shared pattern cache (issue 31, point 5a): "when the renderer executes the
//! upstream pattern graphs for the RixBxdf and the RixVolumeIntegrator via EvalParam(), both
//! plugins will share the same renderer built-in pattern cache. If they pull on the same
//! pattern subgraph, the shared subgraph will only need to be executed once."
//!
//! A glass ball whose material's Bxdf and interior can both pull the parameter `sigma` (a
//! pattern of `P`): the interior reads its absorption coefficient from it at
//! `begin_interior`, as the seed's closures do. Three variants of the material, rendered
//! with the same paths: both pull (`Both`), only the Bxdf (`BxdfOnly`), only the interior
//! (`InteriorOnly`). With sharing, the interior's pulls in `Both` evaluate nothing: every
//! one is answered from the Bxdf's column, and the images agree bit for bit.

mod common;

use bumpalo::Bump;
use common::{camera, environment, settings};
use glam::Vec3;
use risotto::builtins::builtin::{BeerInterior, DielectricBxdf};
use risotto::components::Rgb;
use risotto::engine::plugin::*;
use risotto::engine::render::{render, RenderOptions, RenderOutput};
use risotto::engine::scene::{Scene, ShapeGeometry};
use risotto::systems::geometry::Sphere;
use risotto::systems::pattern::{Axis, Node, PatternGraph};

/// Which closures pull `sigma`.
#[derive(Clone, Copy, PartialEq)]
enum Pulls {
    Both,
    BxdfOnly,
    InteriorOnly,
}

struct Glass {
    sigma: PatternGraph,
    pulls: Pulls,
}

/// The absorption coefficient every point of the pattern has.
const SIGMA: f32 = 0.7;

impl BxdfFactory for Glass {
    fn instance_hints(&self) -> InstanceHints {
        InstanceHints::TRANSMITS
            | InstanceHints::COMPUTES_INTERIOR
            | InstanceHints::INTERIOR_TRANSMISSION
    }
    fn begin_scatter<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        mode: ShadingMode,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a) {
        if mode == ShadingMode::Scatter && self.pulls != Pulls::InteriorOnly {
            // Pulled, as a Bxdf reading its inputs would; the glass itself is clear.
            assert!(ctx.eval_param("sigma").is_some());
        }
        arena.alloc(DielectricBxdf {
            ior: 1.5,
            tint: Rgb::WHITE,
        })
    }
    fn begin_interior<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> Option<&'a mut (dyn VolumeIntegrator + 'a)> {
        let sigma = match self.pulls {
            Pulls::BxdfOnly => SIGMA,
            _ => ctx.eval_param("sigma").map_or(SIGMA, |column| column[0].g),
        };
        Some(arena.alloc(BeerInterior {
            sigma_a: Rgb::splat(sigma),
        }))
    }
    fn param(&self, name: &str) -> Option<ParamValue<'_>> {
        (name == "sigma").then_some(ParamValue::Pattern(&self.sigma))
    }
    fn ior(&self) -> f32 {
        1.5
    }
}

/// The ball against a grey sky, rendered.
fn render_ball(pulls: Pulls) -> RenderOutput {
    // A gradient whose two ends are equal: a real pattern graph (evaluated per point) with
    // the same value everywhere, so the points it is evaluated at do not matter.
    let sigma = PatternGraph::new(vec![Node::Gradient {
        axis: Axis::X,
        from: -1.0,
        to: 1.0,
        a: Rgb::splat(SIGMA),
        b: Rgb::splat(SIGMA),
    }])
    .unwrap();
    let mut scene = Scene::new(camera(30.0, 4.0, 24, 24), settings(24, 24, 4, 6));
    let m = scene.add_material("glass", 0, Box::new(Glass { sigma, pulls }));
    scene.add_shape(
        "ball",
        ShapeGeometry::Sphere(Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        }),
        m,
        None,
    );
    environment(&mut scene, Rgb::splat(0.8));
    let compiled = scene.compile().unwrap();
    let options = RenderOptions {
        threads: Some(1),
        ..RenderOptions::default()
    };
    render(&compiled, &options, &|_| {}).unwrap()
}

#[test]
fn the_interior_takes_the_bxdf_s_column_instead_of_evaluating_it_again() {
    let both = render_ball(Pulls::Both);
    let bxdf_only = render_ball(Pulls::BxdfOnly);
    let interior_only = render_ball(Pulls::InteriorOnly);
    let (b, x, i) = (
        &both.stats.counters,
        &bxdf_only.stats.counters,
        &interior_only.stats.counters,
    );
    // The interior's own evaluations, when nothing is shared: one per binding.
    assert!(i.pattern_evals > 0, "the interior never pulled");
    assert_eq!(i.pattern_cache_shared, 0, "no Bxdf column to share");
    assert_eq!(
        x.pattern_cache_shared, 0,
        "nothing asked the Bxdf's columns"
    );
    // Both pull: the interior's pulls are all answered by the Bxdf's columns.
    assert_eq!(
        b.pattern_evals, x.pattern_evals,
        "the interior evaluated again"
    );
    assert_eq!(b.pattern_cache_shared, i.pattern_evals);
    // The same paths and the same coefficient: the same image, bit for bit.
    assert_eq!(both.beauty.pixels, interior_only.beauty.pixels);
    assert_eq!(both.beauty.pixels, bxdf_only.beauty.pixels);
    // The interior absorbed (the ball is darker than the sky behind it).
    let centre = both.beauty.get(12, 12).g;
    assert!(centre < 0.8 * 0.9, "centre {centre}");
}
