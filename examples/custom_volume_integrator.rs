//! A volume integrator written outside the engine, registered as a scene-file material type.
//!
//! Run with `cargo run --release --example custom_volume_integrator`; it renders a small image
//! of a "smoky glass" sphere and writes `custom_volume_integrator.exr` and `.png` to the
//! system's temporary directory.
//!
//! # How this maps onto the RIS volume-integrator contract
//!
//! The seed document ("Writing Volume Integrators") describes RenderMan's RIS interface; risotto
//! has the same shape, batch-oriented and in Rust (`risotto::engine::plugin`):
//!
//! | RIS | risotto |
//! |---|---|
//! | `RixBxdfFactory` | [`BxdfFactory`] ([`SmokyGlass`] here) |
//! | `GetInstanceHints`: `k_ComputesInterior \| k_InteriorTransmission` | [`BxdfFactory::instance_hints`]: `COMPUTES_INTERIOR \| INTERIOR_TRANSMISSION` (plus `TRANSMITS`: the surface refracts) |
//! | `BeginScatter` -> `RixBxdf` | [`BxdfFactory::begin_scatter`] -> a [`Bxdf`] (the engine's own `DielectricBxdf` here) |
//! | `BeginInterior` -> `RixVolumeIntegrator` | [`BxdfFactory::begin_interior`] -> a [`VolumeIntegrator`] ([`SmokyInterior`]) |
//! | `pool.AllocForVolume<T>()` + placement new | `arena.alloc(T)`: closures live in the worker's per-batch arena |
//! | `GetNearestHits(..., ictx, ...)` | [`VolumeIntegrator::nearest_hits`]: calls `ictx.nearest_hits` (the renderer's `IntegratorContext::GetNearestHits`) and writes each returned point's `transmission` from its `VLen` |
//! | `GetTransmission(rays[i].maxDist)` | [`VolumeIntegrator::transmission`] on renderer-chosen straight [`Segments`] (`length` = `maxDist`) |
//! | `GetOverlappingVolumes` | `ShadingContext::overlapping_volumes` + `VolumeIntegrator::as_any` |
//! | registering the plug-in | [`MaterialRegistry::register`]: scene files then say `type = "smoky_glass"` |
//!
//! The global integrator (the path tracer) does the rest, exactly as in the seed's pseudo code:
//! rays the Bxdf refracts carry the `TRANSMIT` lobe bit, the renderer keeps the per-ray volume
//! stack (entering on front faces, leaving on back faces), and rays travelling inside the
//! sphere are handed to this integrator's `nearest_hits` instead of plain nearest hits. Shadow
//! rays are never bent: with `cheap_shadows = true` the glass surface lets them through and
//! the renderer calls `transmission` on the part of the shadow ray inside the sphere (the
//! seed's "cheap, non-physically based shadows" of a blue glass sphere).
//!
//! # The material
//!
//! `smoky_glass` is a smooth dielectric whose interior absorbs like the seed's
//! `GlassInterior` (Beer's law, `T = exp(-sigma_a d)`), but parametrised the way artists
//! usually set tinted glass: by the colour white light has after travelling `distance` world
//! units inside, so `sigma_a = -ln(color) / distance` per channel.
//!
//! ```toml
//! [materials.smoke]
//! type = "smoky_glass"
//! ior = 1.5                 # default 1.5
//! color = [0.9, 0.6, 0.3]   # transmittance after `distance`, each channel in (0, 1]
//! distance = 0.5            # world units, default 1
//! cheap_shadows = true      # shadow rays pass (attenuated by the interior); default false
//! ```

use risotto::builtins::builtin::DielectricBxdf;
use risotto::bumpalo::Bump;
use risotto::components::{LobeSampled, Rays, Rgb};
use risotto::engine::output::{write_exr, write_png};
use risotto::engine::plugin::IntegratorContext;
use risotto::engine::plugin::{
    Bxdf, BxdfFactory, InstanceHints, Segments, ShadeGroups, ShadingContext, ShadingMode,
    VolumeIntegrator, VolumeServices,
};
use risotto::engine::render::{render, RenderOptions, RenderOutput};
use risotto::loader::load::{scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::{parse_scene, SceneError};
use risotto::systems::sampler::PathSampler;
use std::path::Path;

/// The factory of the `smoky_glass` material type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmokyGlass {
    /// Index of refraction of the glass.
    pub ior: f32,
    /// Absorption coefficient per channel (per world unit).
    pub sigma_a: Rgb,
    /// Whether shadow rays may pass the surface (then attenuated by the interior only).
    pub cheap_shadows: bool,
}

impl SmokyGlass {
    /// `sigma_a` such that white light keeps `color` after `distance` world units:
    /// `exp(-sigma_a * distance) = color`.
    pub fn sigma_a_for(color: Rgb, distance: f32) -> Rgb {
        color.map(|c| -c.ln() / distance)
    }

    /// The factory for a material table of a scene file (see the module docs for the keys).
    pub fn from_params(
        p: &risotto::loader::scene_file::MaterialParams,
    ) -> Result<Self, SceneError> {
        p.deny_unknown(&["ior", "color", "distance", "cheap_shadows"])?;
        let ior = p.f32_where("ior", Some(1.5), "> 0", |v| v > 0.0)?;
        let color = p.rgb_where(
            "color",
            Some(Rgb::splat(0.5)),
            "every channel in (0, 1]",
            |c| c.min_channel() > 0.0 && c.max_channel() <= 1.0,
        )?;
        let distance = p.f32_where("distance", Some(1.0), "> 0 and finite", |v| {
            v > 0.0 && v.is_finite()
        })?;
        let cheap_shadows = p.bool("cheap_shadows", Some(false))?;
        Ok(SmokyGlass {
            ior,
            sigma_a: Self::sigma_a_for(color, distance),
            cheap_shadows,
        })
    }
}

/// The interior closure (the seed's `GlassInterior`): Beer-Lambert absorption, no scattering.
/// Plain data, as closures in the arena must be (their destructors never run).
#[derive(Clone, Copy, Debug)]
pub struct SmokyInterior {
    /// Absorption coefficient per channel.
    pub sigma_a: Rgb,
}

impl SmokyInterior {
    /// `exp(-sigma_a d)` per channel; an infinite distance in a clear channel stays 1.
    fn transmittance(&self, d: f32) -> Rgb {
        self.sigma_a
            .map(|s| if s == 0.0 { 1.0 } else { (-s * d).exp() })
    }
}

impl BxdfFactory for SmokyGlass {
    fn instance_hints(&self) -> InstanceHints {
        let h = InstanceHints::TRANSMITS
            | InstanceHints::COMPUTES_INTERIOR
            | InstanceHints::INTERIOR_TRANSMISSION;
        if self.cheap_shadows {
            h | InstanceHints::TRANSMISSION_SHADOWS
        } else {
            h
        }
    }

    fn begin_scatter<'a>(
        &'a self,
        _ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a) {
        // The surface is the engine's smooth dielectric; it reads the IOR outside each point
        // from the volume stack (`ShadingContext::ior_outside`).
        arena.alloc(DielectricBxdf {
            ior: self.ior,
            tint: Rgb::WHITE,
        })
    }

    fn begin_interior<'a>(
        &'a self,
        _ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> Option<&'a mut (dyn VolumeIntegrator + 'a)> {
        Some(arena.alloc(SmokyInterior {
            sigma_a: self.sigma_a,
        }))
    }

    fn shadow_transmittance(&self) -> Rgb {
        // The surface itself lets cheap shadows through unattenuated; the interior's
        // `transmission` does the absorbing.
        if self.cheap_shadows {
            Rgb::WHITE
        } else {
            Rgb::BLACK
        }
    }

    fn ior(&self) -> f32 {
        self.ior
    }
}

impl VolumeIntegrator for SmokyInterior {
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        _samplers: &mut [PathSampler],
        _lobes_wanted: LobeSampled,
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
        // Nothing scatters inside: the next hits are the ordinary nearest hits ...
        services.ictx.nearest_hits(rays, out);
        // ... attenuated by Beer's law over each point's incident segment (RIS `k_VLen`); a
        // ray escaping from inside (an open mesh) travelled its whole, unbounded, tmax.
        out.attenuate_segments(rays, |length| self.transmittance(length));
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

    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

/// The built-in material types plus `smoky_glass`.
pub fn registry() -> MaterialRegistry {
    let mut registry = MaterialRegistry::with_builtins();
    registry.register("smoky_glass", |p| Ok(Box::new(SmokyGlass::from_params(p)?)));
    registry
}

/// The example scene: a smoky glass sphere on a floor under an area light and a grey sky.
pub const SCENE: &str = r#"
[render]
width = 160
height = 120
spp = 32
max_depth = -1
rr_depth = 5

[camera]
fov = 35
from = [0, 2, 6]
to = [0, 0.8, 0]

[materials.floor]
type = "diffuse"
reflectance = 0.5

[materials.smoke]
type = "smoky_glass"
ior = 1.5
color = [0.9, 0.6, 0.3]
distance = 0.5
cheap_shadows = true

[materials.black]
type = "diffuse"
reflectance = 0

[[shapes]]
name = "floor"
type = "quad"
material = "floor"
corner = [-10, 0, -10]
edge1 = [0, 0, 20]
edge2 = [20, 0, 0]

[[shapes]]
name = "ball"
type = "sphere"
material = "smoke"
center = [0, 1, 0]
radius = 1

[[shapes]]
name = "lamp"
type = "rectangle"
material = "black"
emission = 8
transform = [{ scale = 2 }, { look_at = { from = [-3, 6, 3], to = [0, 0, 0] } }]

[[lights]]
type = "environment"
radiance = 0.5
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
    let out = render_text(SCENE, "custom_volume_integrator.toml")?;
    let dir = std::env::temp_dir();
    let exr = dir.join("custom_volume_integrator.exr");
    let png = dir.join("custom_volume_integrator.png");
    write_exr(&exr, &out.film_output(false))?;
    write_png(&png, &out.beauty, 0.0)?;
    let m = out.beauty.mean();
    println!(
        "smoky_glass: {}x{} px, mean RGB ({:.4}, {:.4}, {:.4}), {:.2} s",
        out.beauty.width, out.beauty.height, m[0], m[1], m[2], out.stats.wall_seconds
    );
    println!("wrote {} and {}", exr.display(), png.display());
    Ok(())
}
