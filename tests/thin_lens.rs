//! The thin-lens camera in images: an edge in focus stays sharp, out of focus it is blurred
//! by the circle of confusion thin-lens optics predicts, and `aperture_radius = 0` renders
//! the pinhole camera's image bit for bit.

mod common;

use common::*;
use glam::Vec3;
use risotto::builtins::builtin::Surface;
use risotto::engine::render::{render, RenderOptions, RenderOutput};
use risotto::engine::scene::Scene;
use risotto::loader::load::{compile_scene, scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::parse_scene;
use risotto::systems::camera::{Camera, Projection};
use risotto_components::Rgb;
use std::path::PathBuf;

/// Image of the edge scene: wide, a few rows (averaged into one profile).
const W: u32 = 128;
const H: u32 = 4;
const FOV: f32 = 40.0;
/// The camera sits at z = DEPTH looking down -z; the emitter is in the plane z = 0.
const DEPTH: f32 = 5.0;

/// The horizontal profile (row average of the red channel) of an emitting half-plane
/// `x < 0` at depth [`DEPTH`], radiance 1, nothing else in the scene, seen by a thin-lens
/// camera with `aperture_radius` and `focus_distance`. `max_depth = 1`: a pixel's value is
/// exactly the fraction of its film-and-lens samples whose ray hits the emitter.
fn edge_profile(aperture_radius: f32, focus_distance: f32) -> Vec<f64> {
    let camera = Camera::look_at(
        Projection::ThinLens {
            fov_deg: FOV,
            aperture_radius,
            focus_distance,
        },
        Vec3::new(0.0, 0.0, DEPTH),
        Vec3::ZERO,
        Vec3::Y,
        W,
        H,
    )
    .unwrap();
    let mut scene = Scene::new(camera, settings(W, H, 1024, 1));
    let black = scene.add_material(
        "black",
        0,
        mat(Surface::Diffuse {
            reflectance: Rgb::BLACK,
        }),
    );
    // Facing +z (towards the camera): e1 x e2 = X x Y = +z.
    let half_plane = quad(
        Vec3::new(-50.0, -50.0, 0.0),
        Vec3::X * 50.0,
        Vec3::Y * 100.0,
    );
    scene.add_shape("emitter", half_plane, black, Some(Rgb::WHITE));
    let out = render_default(&scene.compile().unwrap());
    (0..W as usize)
        .map(|x| {
            (0..H as usize)
                .map(|y| out.beauty.pixels[y * W as usize + x].r as f64)
                .sum::<f64>()
                / H as f64
        })
        .collect()
}

/// The 10-90 % width in pixels of a falling edge profile (value per pixel, centres at
/// `i + 0.5`), the crossings found by linear interpolation between pixel centres.
fn width_10_90(profile: &[f64]) -> f64 {
    let crossing = |level: f64| {
        let i = profile
            .windows(2)
            .position(|w| w[0] >= level && w[1] < level)
            .unwrap_or_else(|| panic!("no crossing of {level}: {profile:?}"));
        let (a, b) = (profile[i], profile[i + 1]);
        i as f64 + 0.5 + (a - level) / (a - b)
    };
    crossing(0.1) - crossing(0.9)
}

/// Fraction of a disk of radius 1 whose centre is at `s` (radii) left of a straight edge,
/// lying left of the edge: the circular segment `1/2 + (s sqrt(1 - s^2) + asin s) / pi`.
fn disk_fraction_left(s: f64) -> f64 {
    let s = s.clamp(-1.0, 1.0);
    0.5 + (s * (1.0 - s * s).sqrt() + s.asin()) / std::f64::consts::PI
}

/// The predicted profile: a point of the emitter at depth `d` seen through a lens of radius
/// `A` focused at depth `f` is spread on the focal plane over a disk of radius
/// `c = A |d - f| / d` (the rays from the lens disk through the point cross the focal plane
/// at `P f / d + l (1 - f / d)`, `l` on the lens disk), centred on the pinhole image of the
/// point. The focal plane shows `2 f tan(fov / 2)` world units across `W` pixels, so the
/// circle of confusion has radius `c W / (2 f tan(fov / 2))` pixels. A pixel's value is the
/// box filter (its own square) of the disk-blurred step at the image centre.
fn predicted_profile(aperture_radius: f64, focus: f64) -> (Vec<f64>, f64) {
    let d = DEPTH as f64;
    let c_world = aperture_radius * (d - focus).abs() / d;
    let half_width = focus * (0.5 * FOV as f64).to_radians().tan();
    let r_px = c_world * W as f64 / (2.0 * half_width);
    let centre = W as f64 / 2.0;
    let profile = (0..W)
        .map(|i| {
            let n = 400;
            (0..n)
                .map(|k| {
                    let x = i as f64 + (k as f64 + 0.5) / n as f64;
                    disk_fraction_left((centre - x) / r_px)
                })
                .sum::<f64>()
                / n as f64
        })
        .collect();
    (profile, r_px)
}

#[test]
fn edge_in_focus_is_sharp_and_out_of_focus_is_blurred_by_the_circle_of_confusion() {
    let aperture = 0.3;
    // In focus: the step between pixels 63 and 64 stays one pixel wide (0.8 by the
    // interpolation between centres for a step on a pixel boundary).
    let sharp = edge_profile(aperture, DEPTH);
    let w = width_10_90(&sharp);
    assert!(w <= 1.0, "in-focus edge width {w} px: {sharp:?}");
    assert!(sharp[..62].iter().all(|&v| v == 1.0) && sharp[66..].iter().all(|&v| v == 0.0));
    // Out of focus, focused in front of and behind the emitter.
    for focus in [3.0f32, 8.0] {
        let got = edge_profile(aperture, focus);
        let (want, r_px) = predicted_profile(aperture as f64, focus as f64);
        let (w_got, w_want) = (width_10_90(&got), width_10_90(&want));
        println!("focus {focus}: CoC radius {r_px:.3} px, 10-90 width {w_got:.3} px, predicted {w_want:.3} px");
        assert!(
            (w_got / w_want - 1.0).abs() < 0.03,
            "focus {focus}: width {w_got} px, predicted {w_want} px (CoC radius {r_px} px)"
        );
        // The whole profile, not only its width.
        let worst = got
            .iter()
            .zip(&want)
            .map(|(g, w)| (g - w).abs())
            .fold(0.0, f64::max);
        assert!(worst < 0.02, "focus {focus}: profile off by {worst}");
    }
}

/// The shipped depth-of-field scene with `aperture_radius = 0` and the same scene with
/// `projection = "perspective"` render the same bits.
#[test]
fn thin_lens_of_radius_zero_renders_the_pinhole_image_bit_for_bit() {
    let file = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/depth_of_field.toml");
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.contains("aperture_radius = 0.12"));
    let zero = text.replace("aperture_radius = 0.12", "aperture_radius = 0");
    let pinhole = text
        .replace("projection = \"thin_lens\"", "projection = \"perspective\"")
        .replace("aperture_radius = 0.12", "");
    let lens = text.clone();
    let render_text = |text: &str| -> RenderOutput {
        let desc = parse_scene(text, &file).unwrap_or_else(|e| panic!("{e}"));
        let mut scene = scene_from_desc(desc, &MaterialRegistry::with_builtins()).unwrap();
        // Small and quick: 48 x 36, 4 samples per pixel.
        (
            scene.settings.width,
            scene.settings.height,
            scene.settings.spp,
        ) = (48, 36, 4);
        (scene.camera.width, scene.camera.height) = (48, 36);
        let compiled = compile_scene(scene).unwrap();
        render(&compiled, &RenderOptions::default(), &|_| {}).unwrap()
    };
    let bits = |out: &RenderOutput| -> Vec<[u32; 3]> {
        out.beauty
            .pixels
            .iter()
            .map(|p| [p.r.to_bits(), p.g.to_bits(), p.b.to_bits()])
            .collect()
    };
    let (zero, pinhole, lens) = (
        render_text(&zero),
        render_text(&pinhole),
        render_text(&lens),
    );
    assert_eq!(bits(&zero), bits(&pinhole));
    assert_eq!(zero.variance.pixels, pinhole.variance.pixels);
    // The check can fail: a lens changes the image.
    assert_ne!(bits(&lens), bits(&pinhole));
}
