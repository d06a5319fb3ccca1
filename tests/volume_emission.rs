//! The seed's `GetTransmission` returns `trans` and `emission`: what a volume emits along a
//! shadow ray is added to its contribution (attenuated by what lies before it on the ray,
//! weighted like the light's radiance), and only in scenes whose materials say their
//! interiors emit (`InstanceHints::INTERIOR_EMITS`).

mod common;
use bumpalo::Bump;
use common::*;
use glam::Vec3;
use risotto::builtins::builtin::{NullBxdf, Surface};
use risotto::engine::plugin::IntegratorContext;
use risotto::engine::plugin::*;
use risotto::engine::scene::{LightComponent, Scene};
use risotto::systems::sampler::PathSampler;
use risotto_components::{LobeSampled, Rays, Rgb};

/// An index-matched volume, transparent, that emits `emission` (radiance reaching the start
/// of any segment through it) along shadow rays, with or without the hint that says so.
struct Glowing {
    emission: Rgb,
    transmittance: Rgb,
    hinted: bool,
}

struct GlowingInterior {
    emission: Rgb,
    transmittance: Rgb,
}

impl BxdfFactory for Glowing {
    fn instance_hints(&self) -> InstanceHints {
        let h = InstanceHints::INDEX_MATCHED
            | InstanceHints::TRANSMISSION_SHADOWS
            | InstanceHints::TRANSMITS
            | InstanceHints::COMPUTES_INTERIOR
            | InstanceHints::INTERIOR_TRANSMISSION;
        if self.hinted {
            h | InstanceHints::INTERIOR_EMITS
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
        arena.alloc(NullBxdf)
    }
    fn begin_interior<'a>(
        &'a self,
        _ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> Option<&'a mut (dyn VolumeIntegrator + 'a)> {
        Some(arena.alloc(GlowingInterior {
            emission: self.emission,
            transmittance: self.transmittance,
        }))
    }
    fn shadow_transmittance(&self) -> Rgb {
        Rgb::WHITE
    }
}

impl VolumeIntegrator for GlowingInterior {
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        _samplers: &mut [PathSampler],
        _lobes_wanted: LobeSampled,
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
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
        trans[..segments.len()].fill(self.transmittance);
        emission[..segments.len()].fill(self.emission);
    }
}

/// A diffuse floor (albedo 0.5) seen from above, a point light of intensity 4 at height 2
/// above it, and between them (y in [0.5, 1.5]) a wide glowing slab; max_depth 2 (direct
/// light only). Every floor point sees the light straight above it through the slab, so the
/// radiance is `rho / pi * cos * (T * I / r^2 + E)` with `cos = 1` at the centre.
fn floor_radiance(glow: Glowing) -> Rgb {
    let cam = ortho_camera(Vec3::new(0.0, 1.9, 0.0), Vec3::ZERO, Vec3::Z, 0.02, 4, 4);
    let mut scene = Scene::new(cam, settings(4, 4, 4, 2));
    let floor = scene.add_material(
        "floor",
        0,
        mat(Surface::Diffuse {
            reflectance: Rgb::splat(0.5),
        }),
    );
    scene.add_shape(
        "floor",
        quad(Vec3::new(-5.0, 0.0, -5.0), Vec3::Z * 10.0, Vec3::X * 10.0),
        floor,
        None,
    );
    let m = scene.add_material("glow", 0, Box::new(glow));
    add_box(
        &mut scene,
        "slab",
        Vec3::new(-5.0, 0.5, -5.0),
        Vec3::new(5.0, 1.5, 5.0),
        m,
    );
    scene.add_light(
        "lamp",
        LightComponent::Point {
            position: Vec3::new(0.0, 2.0, 0.0),
            intensity: Rgb::splat(4.0),
        },
    );
    let out = render_default(&scene.compile().unwrap());
    assert_eq!(out.stats.counters.nan_dropped, 0);
    image_mean(&out).0
}

#[test]
fn volume_emission_along_shadow_rays_reaches_the_path() {
    let rho_over_pi = 0.5 / std::f32::consts::PI;
    let (i_over_r2, t) = (4.0 / 4.0, 0.5);
    let e = Rgb::new(0.25, 0.5, 1.0);
    let lit = floor_radiance(Glowing {
        emission: e,
        transmittance: Rgb::splat(t),
        hinted: true,
    });
    // The camera sees a tiny patch around the centre: cos ~ 1, r ~ 2.
    let want = (Rgb::splat(t * i_over_r2) + e) * rho_over_pi;
    for (got, want) in [(lit.r, want.r), (lit.g, want.g), (lit.b, want.b)] {
        assert!((got - want).abs() < 1e-3 * want, "{lit:?} vs {want:?}");
    }
    // Without the hint the scene has no emissive media and the emission is not gathered.
    let dark = floor_radiance(Glowing {
        emission: e,
        transmittance: Rgb::splat(t),
        hinted: false,
    });
    let want = t * i_over_r2 * rho_over_pi;
    assert!((dark.g - want).abs() < 1e-3 * want, "{dark:?} vs {want}");
}
