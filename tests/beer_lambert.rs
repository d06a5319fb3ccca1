//! Beer-Lambert checks of the volume-integrator contract, all deterministic and compared with
//! the closed form `T = exp(-sigma_a d)` per channel:
//!
//! * camera rays through an index-matched absorbing box (pass-throughs + `nearest_hits`);
//! * shadow rays through an absorbing slab (the transmission system + `transmission`);
//! * nested volumes (the innermost volume's integrator runs in the inner cube);
//! * overlapping volumes, with a custom integrator that sums the coefficients of every volume
//!   it overlaps through `ShadingContext::overlapping_volumes` and `as_any` downcasting, for
//!   camera rays and for shadow rays;
//! * a camera inside a volume (stack probed, and given explicitly).
//!
//! Every path here is deterministic: orthographic cameras (all rays of an image are parallel,
//! so every one crosses the same thickness), index-matched boundaries, emission seen directly
//! (`max_depth` 1) or a Dirac distant light (light sampling only, MIS weight 1).

mod common;
use bumpalo::Bump;
use common::*;
use glam::Vec3;
use risotto::builtins::builtin::{beer, Interior, NullBxdf, Surface};
use risotto::engine::output::Image;
use risotto::engine::plugin::IntegratorContext;
use risotto::engine::plugin::*;
use risotto::engine::scene::{CompileError, RenderSettings, Scene, ShapeGeometry};
use risotto::systems::camera::{Camera, Projection};
use risotto::systems::sampler::PathSampler;
use risotto_components::{LobeSampled, Rays, Rgb};

/// Radiance of the emitter behind the volumes.
const L: Rgb = Rgb::new(2.0, 3.0, 5.0);

/// Image size of every test (pixel edges fall on multiples of `view / RES`).
const RES: u32 = 16;

/// An orthographic camera at `from` looking at `to`, `view` world units wide, RES x RES.
fn ortho(from: Vec3, to: Vec3, up: Vec3, view: f32) -> Camera {
    Camera::look_at(
        Projection::Orthographic { width: view },
        from,
        to,
        up,
        RES,
        RES,
    )
    .unwrap()
}

fn settings_depth(max_depth: u32) -> RenderSettings {
    settings(RES, RES, 4, max_depth)
}

/// An `interface` boundary with a Beer interior.
fn beer_boundary(scene: &mut Scene, name: &str, sigma_a: Rgb) -> u32 {
    scene.add_material(
        name,
        0,
        mat_in(Surface::Interface, Interior::Beer { sigma_a }),
    )
}

/// A 10 x 10 emitter in the plane `z = z`, facing +z (towards cameras on the +z side).
fn emitter_at(scene: &mut Scene, z: f32) {
    let black = scene.add_material(
        "black",
        0,
        mat(Surface::Diffuse {
            reflectance: Rgb::BLACK,
        }),
    );
    scene.add_shape(
        "emitter",
        ShapeGeometry::Triangles(quad_tris(
            Vec3::new(-5.0, -5.0, z),
            Vec3::X * 10.0,
            Vec3::Y * 10.0,
        )),
        black,
        Some(L),
    );
}

/// Renders and checks every pixel against `expected(x, y)` (pixel indices) to relative error
/// 1e-4 per channel; pixels where `expected` returns `None` are not checked.
fn render_and_check(scene: Scene, expected: impl Fn(u32, u32) -> Option<Rgb>) -> Image {
    let out = render_default(&scene.compile().unwrap());
    assert_eq!(out.stats.counters.nan_dropped, 0);
    let mut checked = 0;
    for y in 0..RES {
        for x in 0..RES {
            let Some(e) = expected(x, y) else { continue };
            let v = out.beauty.get(x as usize, y as usize);
            for (c, (v, e)) in v.to_array().iter().zip(e.to_array()).enumerate() {
                let rel = (v - e).abs() / e.abs().max(1e-30);
                assert!(
                    rel < 1e-4,
                    "pixel ({x}, {y}) channel {c}: got {v}, expected {e} (rel. error {rel})"
                );
            }
            checked += 1;
        }
    }
    assert!(checked > 0, "no pixel checked");
    out.beauty
}

/// World-space x (or y, by symmetry of the square view) range of pixel column `i` for a view
/// of width `view` centred on 0.
fn pixel_span(i: u32, view: f32) -> (f32, f32) {
    let s = view / RES as f32;
    (-0.5 * view + s * i as f32, -0.5 * view + s * (i + 1) as f32)
}

#[test]
fn camera_rays_through_an_index_matched_absorber() {
    let sigma = Rgb::new(0.5, 1.0, 2.0);
    let d = 0.7;
    let mut scene = Scene::new(
        ortho(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 2.0),
        settings_depth(1),
    );
    let m = beer_boundary(&mut scene, "absorber", sigma);
    add_box(
        &mut scene,
        "slab",
        Vec3::new(-3.0, -3.0, -0.5 * d),
        Vec3::new(3.0, 3.0, 0.5 * d),
        m,
    );
    emitter_at(&mut scene, -2.0);
    let expected = L * beer(sigma, d);
    render_and_check(scene, |_, _| Some(expected));
}

/// A diffuse floor `y = 0` lit by a distant light at `theta` from the zenith through the slab
/// `y in [0.5, 0.5 + d]`; the camera looks straight down from `camera_y`.
fn shadow_scene(sigma: Rgb, d: f32, theta: f32, camera_y: f32) -> (Scene, Rgb, f32) {
    let mut scene = Scene::new(
        ortho(Vec3::new(0.0, camera_y, 0.0), Vec3::ZERO, Vec3::Z, 1.0),
        settings_depth(2),
    );
    let albedo = Rgb::new(0.8, 0.6, 0.4);
    add_floor(&mut scene, Vec3::ZERO, albedo);
    let m = beer_boundary(&mut scene, "absorber", sigma);
    add_box(
        &mut scene,
        "slab",
        Vec3::new(-20.0, 0.5, -20.0),
        Vec3::new(20.0, 0.5 + d, 20.0),
        m,
    );
    let e = Rgb::new(3.0, 2.0, 1.5);
    add_sun(&mut scene, theta, e);
    // Lambert: L = albedo / pi * E * cos(theta), before the slab's transmittance.
    (
        scene,
        albedo * e * (theta.cos() / std::f32::consts::PI),
        theta.cos(),
    )
}

#[test]
fn shadow_rays_through_an_index_matched_absorber() {
    let sigma = Rgb::new(0.5, 1.0, 2.0);
    let d = 1.0;
    let theta = 50f32.to_radians();
    // Camera below the slab: only the shadow ray crosses it, on a chord d / cos(theta).
    let (scene, unlit, cos) = shadow_scene(sigma, d, theta, 0.3);
    let expected = unlit * beer(sigma, d / cos);
    render_and_check(scene, |_, _| Some(expected));
    // Camera above the slab: the camera ray crosses it too (vertically, thickness d).
    let (scene, unlit, cos) = shadow_scene(sigma, d, theta, 3.0);
    let expected = unlit * beer(sigma, d / cos) * beer(sigma, d);
    render_and_check(scene, |_, _| Some(expected));
}

#[test]
fn nested_volumes_run_the_innermost_integrator() {
    let (so, si) = (Rgb::new(0.2, 0.4, 0.6), Rgb::new(1.5, 0.5, 3.0));
    let view = 2.0;
    let mut scene = Scene::new(
        ortho(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, view),
        settings_depth(1),
    );
    let outer = beer_boundary(&mut scene, "outer", so);
    let inner = beer_boundary(&mut scene, "inner", si);
    // The outer cube is wider than the view (its side faces are never hit); the inner one
    // covers pixels 4..12 exactly.
    add_box(
        &mut scene,
        "outer",
        Vec3::new(-1.5, -1.5, -1.0),
        Vec3::new(1.5, 1.5, 1.0),
        outer,
    );
    add_box(
        &mut scene,
        "inner",
        Vec3::new(-0.5, -0.5, -0.4),
        Vec3::new(0.5, 0.5, 0.4),
        inner,
    );
    emitter_at(&mut scene, -3.0);
    let (d_outer, d_inner) = (2.0, 0.8);
    let through_both = L * beer(so, d_outer - d_inner) * beer(si, d_inner);
    let outer_only = L * beer(so, d_outer);
    let inside = |i: u32| {
        let (a, b) = pixel_span(i, view);
        a >= -0.5 && b <= 0.5
    };
    let img = render_and_check(scene, |x, y| {
        Some(if inside(x) && inside(y) {
            through_both
        } else {
            outer_only
        })
    });
    // Both regions are really in the image.
    assert_ne!(img.get(0, 0), img.get(8, 8));
}

// ---------------------------------------------------------------------------------------
// Overlapping volumes with a user-defined integrator.

/// An index-matched boundary whose interior absorbs with `sigma_a`; in regions where several
/// such volumes overlap, the one integrator the renderer runs (the innermost) adds the
/// coefficients of all of them (found with `overlapping_volumes` and `as_any`).
struct SummingAbsorber {
    sigma_a: Rgb,
}

/// The closure: `own` is this volume's coefficient (what other volumes read), `total` the
/// sum over this volume and every volume overlapping it where it is the innermost.
struct SummingInterior {
    own: Rgb,
    total: Rgb,
}

impl BxdfFactory for SummingAbsorber {
    fn instance_hints(&self) -> InstanceHints {
        InstanceHints::INDEX_MATCHED
            | InstanceHints::TRANSMISSION_SHADOWS
            | InstanceHints::TRANSMITS
            | InstanceHints::COMPUTES_INTERIOR
            | InstanceHints::INTERIOR_TRANSMISSION
            | InstanceHints::INTERIOR_OVERLAPPING
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
        ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> Option<&'a mut (dyn VolumeIntegrator + 'a)> {
        let mut total = self.sigma_a;
        for v in ctx.overlapping_volumes() {
            let other = v
                .integrator
                .and_then(|i| i.as_any())
                .and_then(|a| a.downcast_ref::<SummingInterior>());
            if let Some(o) = other {
                total += o.own;
            }
        }
        Some(arena.alloc(SummingInterior {
            own: self.sigma_a,
            total,
        }))
    }
    fn shadow_transmittance(&self) -> Rgb {
        Rgb::WHITE
    }
}

impl VolumeIntegrator for SummingInterior {
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        _samplers: &mut [PathSampler],
        _lobes_wanted: LobeSampled,
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
        services.ictx.nearest_hits(rays, out);
        out.attenuate_segments(rays, |length| beer(self.total, length));
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
            trans[i] = beer(self.total, segments.length[i]);
        }
        emission.fill(Rgb::BLACK);
    }
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

#[test]
fn overlapping_volumes_are_visible_to_the_innermost_integrator() {
    let (s1, s2) = (Rgb::new(0.3, 0.6, 0.9), Rgb::new(1.0, 0.2, 0.5));
    let view = 2.0;
    let mut scene = Scene::new(
        ortho(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, view),
        settings_depth(1),
    );
    let m1 = scene.add_material("a", 0, Box::new(SummingAbsorber { sigma_a: s1 }));
    let m2 = scene.add_material("b", 0, Box::new(SummingAbsorber { sigma_a: s2 }));
    // Along -z: box b alone on z in [0.4, 1], both on [-0.2, 0.4], box a alone on [-1, -0.2].
    // Box b only covers x > 0 (pixel columns 8..16).
    add_box(
        &mut scene,
        "a",
        Vec3::new(-1.5, -1.5, -1.0),
        Vec3::new(1.5, 1.5, 0.4),
        m1,
    );
    add_box(
        &mut scene,
        "b",
        Vec3::new(0.0, -1.6, -0.2),
        Vec3::new(1.6, 1.6, 1.0),
        m2,
    );
    emitter_at(&mut scene, -3.0);
    let (only2, overlap, only1) = (0.6, 0.6, 0.8);
    let both = L * beer(s1 + s2, overlap) * beer(s2, only2) * beer(s1, only1);
    let a_alone = L * beer(s1, 1.4);
    let img = render_and_check(scene, |x, _| {
        Some(if pixel_span(x, view).0 >= 0.0 {
            both
        } else {
            a_alone
        })
    });
    assert_ne!(img.get(0, 0), img.get(15, 0));
}

#[test]
fn overlapping_volumes_are_visible_to_shadow_rays() {
    // The floor of `shadow_scene`, lit through two overlapping slabs: a on y in [0.5, 1.5],
    // b on y in [1.0, 2.2]. A shadow ray at theta crosses 0.5 of a alone, 0.5 of both and
    // 0.7 of b alone (vertical thicknesses, times 1 / cos(theta)).
    let (s1, s2) = (Rgb::new(0.3, 0.6, 0.9), Rgb::new(1.0, 0.2, 0.5));
    let theta = 35f32.to_radians();
    let (mut scene, unlit, cos) = shadow_scene(Rgb::BLACK, 1e-3, theta, 0.3);
    // Replace the helper's (transparent) slab by the two summing absorbers.
    let slab = scene
        .world
        .query::<&risotto::engine::scene::Name>()
        .iter()
        .find(|(_, n)| n.0 == "slab")
        .map(|(e, _)| e)
        .unwrap();
    scene.world.despawn(slab).unwrap();
    let m1 = scene.add_material("a", 0, Box::new(SummingAbsorber { sigma_a: s1 }));
    let m2 = scene.add_material("b", 0, Box::new(SummingAbsorber { sigma_a: s2 }));
    add_box(
        &mut scene,
        "a",
        Vec3::new(-20.0, 0.5, -20.0),
        Vec3::new(20.0, 1.5, 20.0),
        m1,
    );
    add_box(
        &mut scene,
        "b",
        Vec3::new(-21.0, 1.0, -21.0),
        Vec3::new(21.0, 2.2, 21.0),
        m2,
    );
    let expected = unlit * beer(s1, 0.5 / cos) * beer(s1 + s2, 0.5 / cos) * beer(s2, 0.7 / cos);
    render_and_check(scene, |_, _| Some(expected));
}

// ---------------------------------------------------------------------------------------
// The camera inside volumes.

/// Camera at the origin looking down -z at the emitter (z = -3) from inside `fog`
/// (z in [-1, 1]), optionally also inside `mist` (z in [-0.6, 0.5]).
fn camera_inside(with_mist: bool, camera_volume: Option<Vec<String>>) -> Scene {
    let mut scene = Scene::new(
        ortho(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), Vec3::Y, 1.0),
        settings_depth(1),
    );
    scene.camera_volume = camera_volume;
    let fog = beer_boundary(&mut scene, "fog", Rgb::new(0.4, 0.8, 1.6));
    add_box(
        &mut scene,
        "fog",
        Vec3::new(-3.0, -3.0, -1.0),
        Vec3::new(3.0, 3.0, 1.0),
        fog,
    );
    if with_mist {
        let mist = beer_boundary(&mut scene, "mist", Rgb::new(2.0, 1.0, 0.1));
        add_box(
            &mut scene,
            "mist",
            Vec3::new(-2.0, -2.0, -0.6),
            Vec3::new(2.0, 2.0, 0.5),
            mist,
        );
    }
    emitter_at(&mut scene, -3.0);
    scene
}

#[test]
fn camera_inside_a_volume_is_attenuated() {
    let fog = Rgb::new(0.4, 0.8, 1.6);
    let mist = Rgb::new(2.0, 1.0, 0.1);
    let one = L * beer(fog, 1.0);
    // Probed.
    let scene = camera_inside(false, None);
    let compiled_stack = {
        let s = camera_inside(false, None).compile().unwrap();
        s.camera_stack
            .entries()
            .iter()
            .map(|e| e.shape)
            .collect::<Vec<_>>()
    };
    assert_eq!(compiled_stack.len(), 1);
    render_and_check(scene, |_, _| Some(one));
    // Given explicitly.
    render_and_check(camera_inside(false, Some(vec!["fog".into()])), |_, _| {
        Some(one)
    });
    // A stated stack that is wrong is an error naming what the camera is really in (it used
    // to override probing: every camera ray left the fog through a back face it was never
    // recorded inside, nothing absorbed it, and the image was silently unattenuated).
    for wrong in [vec![], vec!["fog".to_string(), "fog2".to_string()]] {
        let mut scene = camera_inside(false, Some(wrong.clone()));
        if wrong.len() == 2 {
            let m = beer_boundary(&mut scene, "fog2", Rgb::splat(1.0));
            add_box(&mut scene, "fog2", Vec3::splat(5.0), Vec3::splat(6.0), m);
        }
        let e = scene
            .compile()
            .err()
            .unwrap_or_else(|| panic!("{wrong:?} accepted"));
        let msg = e.to_string();
        assert!(
            matches!(e, CompileError::CameraVolume(_)) && msg.contains("is inside [\"fog\"]"),
            "{wrong:?}: {msg}"
        );
    }
    // Listing both volumes innermost first is wrong too (the stack's order is its meaning).
    let e = camera_inside(true, Some(vec!["mist".into(), "fog".into()]))
        .compile()
        .err()
        .expect("innermost-first order accepted");
    assert!(
        e.to_string().contains("is inside [\"fog\", \"mist\"]"),
        "{e}"
    );

    // Two nested volumes around the camera: mist (innermost) for 0.6, then fog for 0.4.
    let two = L * beer(mist, 0.6) * beer(fog, 0.4);
    let s = camera_inside(true, None).compile().unwrap();
    let names: Vec<&str> = s
        .camera_stack
        .entries()
        .iter()
        .map(|e| s.shapes[e.shape as usize].name.as_str())
        .collect();
    assert_eq!(names, ["fog", "mist"], "outermost first");
    render_and_check(camera_inside(true, None), |_, _| Some(two));
    render_and_check(
        camera_inside(true, Some(vec!["fog".into(), "mist".into()])),
        |_, _| Some(two),
    );
}
