//! A scattering medium written outside the engine with only the public API, as the seed's
//! "Multiple Scattering" section does it: the volume integrator samples free-flight distances
//! and returns the rays that stop inside the volume to the global integrator as a
//! `VolumeScatter` group, which the path tracer then lights and scatters again like any other
//! shading points (so the medium gets multiple scattering for free, and works with global
//! integrators that offer no lighting delegate).
//!
//! Run with `cargo run --release --example scattering_medium`; it renders a small image of a
//! lit smoke ball and writes `scattering_medium.exr` and `.png` to the temporary directory.
//!
//! | seed (RIS) | here |
//! |---|---|
//! | `GetInstanceHints`: interior computes, transmits, scatters | [`Smoke::instance_hints`] |
//! | `BeginInterior` -> `RixVolumeIntegrator` | [`Smoke::begin_interior`] -> [`SmokeInterior`] |
//! | `GetNearestHits` with `maxDist = -log(1 - xi) / density` | [`SmokeInterior`]'s `nearest_hits`: `sample_free_flight` per ray |
//! | `BeginVolumeSampling` / `SetBuiltinVar` / `EndVolumeSampling(membership)` | `begin_volume_sampling`, `set_builtin(P / Vn)`, `set_transmission`, `end_volume_sampling` |
//! | `BeginScatter(.., k_RixSCVolumeScatterQuery)` -> `PxrDoubleHenyeyGreenstein` | [`Smoke::begin_scatter`] in `VolumeScatter` mode -> an HG phase function |
//! | `GetTransmission` | exact transmittance `exp(-sigma_t d)` |
//!
//! **Weights.** [`sample_free_flight`]'s weight at a scattering event is
//! `sigma_s T(t) / pdf(t)`: it already contains `sigma_s`, so the phase function's own weight
//! (`p / pdf = 1` for exact HG sampling) must not multiply by the albedo again: the phase
//! Bxdf here has albedo 1.

use risotto::builtins::builtin::{DiffuseBxdf, NullBxdf};
use risotto::builtins::phase::PhaseBxdf;
use risotto::bumpalo::Bump;
use risotto::components::{LobeSampled, Rays, Rgb};
use risotto::engine::output::{write_exr, write_png};
use risotto::engine::plugin::IntegratorContext;
use risotto::engine::plugin::{
    Builtin, Bxdf, BxdfFactory, InstanceHints, Segments, ShadeGroups, ShadingContext, ShadingMode,
    VolumeIntegrator, VolumeServices,
};
use risotto::engine::render::{render, RenderOptions, RenderOutput};
use risotto::engine::scene::{CompiledScene, LightComponent, RenderSettings, Scene, ShapeGeometry};
use risotto::glam::Vec3;
use risotto::systems::camera::{Camera, Projection};
use risotto::systems::geometry::Sphere;
use risotto::systems::medium::{channel_pdf, sample_free_flight, transmittance};
use risotto::systems::phase::PhaseFunction;
use risotto::systems::sampler::PathSampler;

/// A homogeneous scattering medium behind an index-matched boundary.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Smoke {
    /// Extinction coefficient per channel (per world unit).
    pub sigma_t: Rgb,
    /// Scattering coefficient per channel, `<= sigma_t`.
    pub sigma_s: Rgb,
    /// Henyey-Greenstein mean cosine.
    pub g: f32,
}

impl BxdfFactory for Smoke {
    fn instance_hints(&self) -> InstanceHints {
        // The boundary: rays and shadow rays pass unchanged (index-matched). The interior:
        // an integrator that answers nearest hits and transmission, and scatters.
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
            // Points inside the volume: the phase function. Albedo 1: the free flight's
            // weight already holds sigma_s (see the module docs).
            ShadingMode::VolumeScatter => arena.alloc(PhaseBxdf::weighted(
                PhaseFunction::HenyeyGreenstein { g: self.g },
                Rgb::WHITE,
            )),
            // The index-matched surface is never shaded.
            ShadingMode::Scatter | ShadingMode::Interior => arena.alloc(NullBxdf),
        }
    }

    fn begin_interior<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> Option<&'a mut (dyn VolumeIntegrator + 'a)> {
        Some(arena.alloc(SmokeInterior { medium: *self, ctx }))
    }

    fn shadow_transmittance(&self) -> Rgb {
        Rgb::WHITE
    }
}

/// The interior closure: plain data and a borrowed context (closures live in the arena, which
/// runs no destructors).
pub struct SmokeInterior<'a> {
    /// The medium.
    pub medium: Smoke,
    /// The renderer's context at the rays' origins (point `i` for ray `i`).
    pub ctx: &'a ShadingContext<'a>,
}

impl VolumeIntegrator for SmokeInterior<'_> {
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        samplers: &mut [PathSampler],
        _lobes_wanted: LobeSampled,
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
        let n = rays.len();
        let Smoke {
            sigma_t, sigma_s, ..
        } = self.medium;
        // Where each ray would leave the volume (or the surface inside it it would hit).
        let mut hits = ShadeGroups::default();
        services.ictx.nearest_hits(rays, &mut hits);
        let mut length = vec![f32::INFINITY; n];
        for (k, &r) in hits.points.ray_id.iter().enumerate() {
            length[r as usize] = hits.points.vlen[k];
        }
        // One free flight per ray (spectral MIS over the channels the path carries).
        let mut vs = self.ctx.begin_volume_sampling();
        let mut member = vec![false; n];
        let (mut p, mut vn) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
        let mut weight = vec![Rgb::WHITE; n];
        let mut pass = vec![Rgb::WHITE; n];
        for i in 0..n {
            let (u_channel, u_distance) = (samplers[i].next_1d(), samplers[i].next_1d());
            let flight = sample_free_flight(
                sigma_t,
                sigma_s,
                channel_pdf(rays.throughput[i]),
                u_channel,
                u_distance,
                length[i],
            );
            p[i] = rays.origin[i];
            vn[i] = -rays.direction[i];
            if flight.scattered {
                member[i] = true;
                p[i] += rays.direction[i] * flight.t;
                weight[i] = flight.weight;
            } else {
                pass[i] = flight.weight;
            }
        }
        // The points that stay in the volume: a VolumeScatter group for the global
        // integrator, with the flight's weight as the segment's transmission.
        vs.set_builtin(Builtin::P, &p);
        vs.set_builtin(Builtin::Vn, &vn);
        vs.set_transmission(&weight);
        // The others keep their hit, weighted by the pass estimate.
        for g in &hits.groups {
            let start = out.points.len();
            for k in g.range.clone() {
                let r = hits.points.ray_id[k] as usize;
                if !member[r] {
                    out.points.push_from(&hits.points, k);
                    let last = out.points.len() - 1;
                    out.points.transmission[last] *= pass[r];
                }
            }
            out.close_group(g.material, g.mode, start);
        }
        vs.end_volume_sampling(&member, out);
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
            trans[i] = transmittance(self.medium.sigma_t, segments.length[i]);
        }
        emission.fill(Rgb::BLACK);
    }
}

/// A grey diffuse floor.
struct Floor;

impl BxdfFactory for Floor {
    fn instance_hints(&self) -> InstanceHints {
        InstanceHints::NONE
    }
    fn begin_scatter<'a>(
        &'a self,
        _ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a) {
        arena.alloc(DiffuseBxdf {
            reflectance: Rgb::splat(0.5),
        })
    }
}

/// The example scene: a smoke ball (radius 1) of `smoke` on a floor, lit by a point light and
/// a dim sky, `width x height` pixels at `spp` samples.
pub fn smoke_scene(smoke: Smoke, width: u32, height: u32, spp: u32) -> CompiledScene {
    let camera = Camera::look_at(
        Projection::Perspective { fov_deg: 35.0 },
        Vec3::new(0.0, 2.0, 6.0),
        Vec3::new(0.0, 0.9, 0.0),
        Vec3::Y,
        width,
        height,
    )
    .expect("a valid camera");
    let settings = RenderSettings {
        width,
        height,
        spp,
        max_depth: 64,
        ..RenderSettings::default()
    };
    let mut scene = Scene::new(camera, settings);
    let floor = scene.add_material("floor", 0, Box::new(Floor));
    let (a, b, c, d) = (
        Vec3::new(-10.0, 0.0, -10.0),
        Vec3::new(-10.0, 0.0, 10.0),
        Vec3::new(10.0, 0.0, 10.0),
        Vec3::new(10.0, 0.0, -10.0),
    );
    scene.add_shape(
        "floor",
        ShapeGeometry::Triangles(vec![[a, b, c], [a, c, d]]),
        floor,
        None,
    );
    let smoke = scene.add_material("smoke", 0, Box::new(smoke));
    scene.add_shape(
        "ball",
        ShapeGeometry::Sphere(Sphere {
            center: Vec3::new(0.0, 1.0, 0.0),
            radius: 1.0,
        }),
        smoke,
        None,
    );
    scene.add_light(
        "lamp",
        LightComponent::Point {
            position: Vec3::new(-3.0, 5.0, 3.0),
            intensity: Rgb::splat(40.0),
        },
    );
    scene.add_light(
        "sky",
        LightComponent::Environment {
            radiance: Rgb::new(0.1, 0.12, 0.16),
            map: None,
        },
    );
    scene.compile().expect("the example scene compiles")
}

/// Renders `scene` with the path tracer and default options.
pub fn render_scene(scene: &CompiledScene) -> RenderOutput {
    render(scene, &RenderOptions::default(), &|_| {}).expect("render")
}

/// Bluish smoke: scatters blue a little more than red.
pub const SMOKE: Smoke = Smoke {
    sigma_t: Rgb::new(2.0, 2.2, 2.5),
    sigma_s: Rgb::new(1.6, 1.9, 2.3),
    g: 0.3,
};

#[allow(
    dead_code,
    reason = "the test that includes this file calls the other items"
)]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = render_scene(&smoke_scene(SMOKE, 160, 120, 32));
    let dir = std::env::temp_dir();
    let exr = dir.join("scattering_medium.exr");
    let png = dir.join("scattering_medium.png");
    write_exr(&exr, &out.film_output(false))?;
    write_png(&png, &out.beauty, 0.0)?;
    let m = out.beauty.mean();
    println!(
        "smoke ball: {}x{} px, mean RGB ({:.4}, {:.4}, {:.4}), {:.2} s",
        out.beauty.width, out.beauty.height, m[0], m[1], m[2], out.stats.wall_seconds
    );
    println!("wrote {} and {}", exr.display(), png.display());
    Ok(())
}
