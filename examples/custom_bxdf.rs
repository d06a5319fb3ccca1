//! A surface Bxdf written outside the engine, registered as a scene-file material type.
//!
//! Run with `cargo run --release --example custom_bxdf`; it renders a small image of a glossy
//! ball on a glossy floor and writes `custom_bxdf.exr` and `.png` to the system's temporary
//! directory.
//!
//! The closure is the energy-normalised modified Phong lobe (Lafortune and Willems 1994,
//! "Using the modified Phong reflectance model for physically based rendering"), in the
//! shading frame (`z` = shading normal, `wo` towards the viewer, `r` = `wo` mirrored about
//! the normal, `alpha` = the angle between `wi` and `r`):
//!
//! - `f(wo, wi) = ks (n + 2) / (2 pi) cos^n alpha` for `wi` above the surface;
//! - sampling: `cos alpha = u1^(1 / (n + 1))`, `phi = 2 pi u2` around `r`, so the solid-angle
//!   pdf is `(n + 1) / (2 pi) cos^n alpha`. A sample below the surface is no sample (the path
//!   ends), so the pdf of a direction above it is still that density: what MIS needs;
//! - the weight `f cos(theta_i) / pdf = ks (n + 2) / (n + 1) cos(theta_i)`;
//! - at normal incidence the directional albedo is exactly `ks` (`E[cos alpha] = (n + 1) /
//!   (n + 2)`), below it elsewhere: the lobe never creates energy for `ks <= 1`.
//!
//! | RIS | risotto |
//! |---|---|
//! | `RixBxdfFactory` | [`BxdfFactory`] ([`Glossy`]) |
//! | `BeginScatter` -> `RixBxdf` | [`BxdfFactory::begin_scatter`] -> [`GlossyBxdf`] in the per-batch arena |
//! | `RixBxdf::GenerateSample` | [`Bxdf::generate_samples`]: one direction per point of the context, columns in, columns out |
//! | `RixBxdf::EvaluateSample` | [`Bxdf::evaluate_samples`]: `f cos` and pdf towards light samples (for MIS) |
//! | `GetInstanceHints` | [`BxdfFactory::instance_hints`]: none (opaque, no interior) |
//! | registering the plug-in | [`MaterialRegistry::register`]: scene files then say `type = "glossy"` |
//!
//! The lobe is a `DIFFUSE` (non-Dirac) lobe in [`LobeSampled`]'s sense, so the path tracer
//! samples lights at its points and weights them against the Bxdf's own samples by the
//! power heuristic. The math is in the plain functions [`phong_sample`] and [`phong_eval`];
//! `tests/custom_bxdf.rs` checks them against their pdf and the albedo's closed form.
//!
//! ```toml
//! [materials.gloss]
//! type = "glossy"
//! color = [0.9, 0.6, 0.3]   # ks per channel, in [0, 1]; default 0.8
//! exponent = 40             # n > 0, larger is sharper; default 20
//! ```

use risotto::bumpalo::Bump;
use risotto::components::{LobeSampled, Rgb};
use risotto::engine::output::{write_exr, write_png};
use risotto::engine::plugin::{
    Bxdf, BxdfFactory, BxdfSamples, InstanceHints, ShadingContext, ShadingMode,
};
use risotto::engine::render::{render, RenderOptions, RenderOutput};
use risotto::glam::{Vec2, Vec3};
use risotto::loader::load::{scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::{parse_scene, MaterialParams, SceneError};
use risotto::systems::bxdf::Frame;
use risotto::systems::sampler::PathSampler;
use std::f32::consts::PI;
use std::path::Path;

/// The lobe bits of a sample: a non-Dirac reflection.
const GLOSSY_REFLECT: LobeSampled = LobeSampled(LobeSampled::REFLECT.0 | LobeSampled::DIFFUSE.0);

/// A sample of the lobe: direction (shading frame), weight `f cos / pdf` and pdf.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhongSample {
    /// Incident direction, unit, above the surface.
    pub wi: Vec3,
    /// `f cos(theta_i) / pdf`.
    pub weight: Rgb,
    /// Solid-angle pdf.
    pub pdf: f32,
}

/// `wo` mirrored about the normal (shading frame).
fn mirror(wo: Vec3) -> Vec3 {
    Vec3::new(-wo.x, -wo.y, wo.z)
}

/// Samples the lobe of colour `ks` and exponent `n` for the viewer direction `wo` (shading
/// frame, unit) with `u` in `[0, 1)^2`; `None` when `wo` is below the surface or the sampled
/// direction is (the path ends there).
pub fn phong_sample(ks: Rgb, n: f32, wo: Vec3, u: Vec2) -> Option<PhongSample> {
    if wo.z <= 0.0 {
        return None;
    }
    let cos_alpha = u.x.powf(1.0 / (n + 1.0));
    let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    let around_r = Vec3::new(sin_alpha * phi.cos(), sin_alpha * phi.sin(), cos_alpha);
    let wi = Frame::from_normal(mirror(wo)).to_world(around_r);
    if wi.z <= 0.0 {
        return None;
    }
    let pdf = (n + 1.0) / (2.0 * PI) * cos_alpha.powf(n);
    (pdf > 0.0).then(|| PhongSample {
        wi,
        weight: ks * ((n + 2.0) / (n + 1.0) * wi.z),
        pdf,
    })
}

/// `f cos(theta_i)` and the pdf of [`phong_sample`] choosing `wi`, for `wo` (shading frame,
/// unit vectors). Zero below the surface on either side.
pub fn phong_eval(ks: Rgb, n: f32, wo: Vec3, wi: Vec3) -> (Rgb, f32) {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return (Rgb::BLACK, 0.0);
    }
    let cos_n = wi.dot(mirror(wo)).max(0.0).powf(n);
    let f = ks * ((n + 2.0) / (2.0 * PI) * cos_n);
    (f * wi.z, (n + 1.0) / (2.0 * PI) * cos_n)
}

/// The factory of the `glossy` material type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Glossy {
    /// `ks` per channel, in [0, 1].
    pub color: Rgb,
    /// Phong exponent `n > 0`.
    pub exponent: f32,
}

impl Glossy {
    /// The factory for a material table of a scene file (keys in the module docs).
    pub fn from_params(p: &MaterialParams) -> Result<Self, SceneError> {
        p.deny_unknown(&["color", "exponent"])?;
        let color = p.rgb_where(
            "color",
            Some(Rgb::splat(0.8)),
            "every channel in [0, 1]",
            |c| c.min_channel() >= 0.0 && c.max_channel() <= 1.0,
        )?;
        let exponent = p.f32_where("exponent", Some(20.0), "> 0 and at most 1e4", |v| {
            v > 0.0 && v <= 1e4
        })?;
        Ok(Glossy { color, exponent })
    }
}

impl BxdfFactory for Glossy {
    fn instance_hints(&self) -> InstanceHints {
        InstanceHints::NONE
    }
    fn begin_scatter<'a>(
        &'a self,
        _ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a) {
        // Plain data: the arena runs no destructors.
        arena.alloc(GlossyBxdf {
            ks: self.color,
            n: self.exponent,
        })
    }
}

/// The closure: [`phong_sample`] and [`phong_eval`] over the context's points, each in its
/// own shading frame.
#[derive(Clone, Copy, Debug)]
pub struct GlossyBxdf {
    /// `ks` per channel.
    pub ks: Rgb,
    /// Phong exponent.
    pub n: f32,
}

impl Bxdf for GlossyBxdf {
    fn lobes(&self) -> LobeSampled {
        GLOSSY_REFLECT
    }
    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    ) {
        // `out` arrives reset: no sample (pdf 0) unless one is written.
        let (nn, vn) = (ctx.nn(), ctx.vn());
        for (i, sampler) in samplers.iter_mut().enumerate() {
            let frame = Frame::from_normal(nn[i]);
            let u = sampler.next_2d();
            if let Some(s) = phong_sample(self.ks, self.n, frame.to_local(vn[i]), u) {
                out.wi[i] = frame.to_world(s.wi);
                out.weight[i] = s.weight;
                out.pdf[i] = s.pdf;
                out.lobe[i] = GLOSSY_REFLECT;
            }
        }
    }
    fn evaluate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        wi: &[Vec3],
        value: &mut [Rgb],
        pdf: &mut [f32],
    ) {
        let (nn, vn) = (ctx.nn(), ctx.vn());
        for i in 0..ctx.num_points() {
            let frame = Frame::from_normal(nn[i]);
            let (wo, w) = (frame.to_local(vn[i]), frame.to_local(wi[i]));
            (value[i], pdf[i]) = phong_eval(self.ks, self.n, wo, w);
        }
    }
    fn albedo(&self, _ctx: &ShadingContext<'_>, out: &mut [Rgb]) {
        // The normal-incidence albedo (module docs).
        out.fill(self.ks);
    }
}

/// The built-in materials plus `glossy`.
pub fn registry() -> MaterialRegistry {
    let mut registry = MaterialRegistry::with_builtins();
    registry.register("glossy", |p| Ok(Box::new(Glossy::from_params(p)?)));
    registry
}

/// The example scene: a glossy copper ball on a broad glossy grey disc of floor, lit by a
/// small spherical lamp and a dim sky.
pub const SCENE: &str = r#"
[render]
width = 160
height = 120
spp = 32
max_depth = 8

[camera]
fov = 30
from = [3, 2.5, 5]
to = [0, 0.7, 0]

[materials.floor]
type = "glossy"
color = 0.6
exponent = 8

[materials.copper]
type = "glossy"
color = [0.95, 0.64, 0.54]
exponent = 200

[materials.lamp]
type = "diffuse"
reflectance = 0

[[shapes]]
name = "ground"
type = "rectangle"
material = "floor"
transform = [{ scale = 12 }, { look_at = { from = [0, 0, 0], to = [0, 1, 0], up = [0, 0, 1] } }]

[[shapes]]
name = "copper ball"
type = "sphere"
material = "copper"
center = [0, 0.8, 0]
radius = 0.8

[[shapes]]
name = "bulb"
type = "sphere"
material = "lamp"
center = [-2, 4, 1.5]
radius = 0.4
emission = 30

[[lights]]
type = "environment"
radiance = [0.2, 0.25, 0.3]
"#;

/// Parses `text` (reported as `name` in messages), builds it with [`registry`] and renders it.
pub fn render_text(text: &str, name: &str) -> Result<RenderOutput, Box<dyn std::error::Error>> {
    let desc = parse_scene(text, Path::new(name))?;
    let scene = scene_from_desc(desc, &registry())?;
    let compiled = scene.compile()?;
    Ok(render(&compiled, &RenderOptions::default(), &|_| {})?)
}

#[allow(
    dead_code,
    reason = "the test that includes this file calls the other items"
)]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = render_text(SCENE, "custom_bxdf.toml")?;
    let dir = std::env::temp_dir();
    let exr = dir.join("custom_bxdf.exr");
    let png = dir.join("custom_bxdf.png");
    write_exr(&exr, &out.film_output(false))?;
    write_png(&png, &out.beauty, 0.0)?;
    let m = out.beauty.mean();
    println!(
        "wrote {} and {} (mean radiance {:.4} {:.4} {:.4})",
        exr.display(),
        png.display(),
        m[0],
        m[1],
        m[2]
    );
    Ok(())
}
