//! Direct lighting of a Lambertian plane against closed-form irradiance.
//!
//! With `max_depth = 2` (Mitsuba's convention: camera segment + one light segment) the image
//! of a diffuse plane of albedo `rho` is its outgoing radiance `L = rho / pi * E`, where `E`
//! is the irradiance at the point seen. `E` is known in closed form for a distant light, a
//! point light and a parallel emitting rectangle.

mod common;
use common::*;
use glam::Vec3;
use risotto::builtins::builtin::Surface;
use risotto::engine::integrator::LightingTechnique;
use risotto::engine::scene::{LightComponent, Scene};
use risotto_components::Rgb;
use std::f64::consts::PI;

/// Half the side of the (large) plane z = 0, normal +z.
const PLANE: f32 = 50.0;

fn plane_scene(camera: risotto::systems::camera::Camera, spp: u32, rho: Rgb) -> Scene {
    let (w, h) = (camera.width, camera.height);
    let mut scene = Scene::new(camera, settings(w, h, spp, 2));
    let m = scene.add_material("plane", 0, mat(Surface::Diffuse { reflectance: rho }));
    // e1 x e2 = x x y = +z.
    scene.add_shape(
        "plane",
        quad(
            Vec3::new(-PLANE, -PLANE, 0.0),
            Vec3::new(2.0 * PLANE, 0.0, 0.0),
            Vec3::new(0.0, 2.0 * PLANE, 0.0),
        ),
        m,
        None,
    );
    scene
}

fn close(got: f32, want: f64, rel: f64) -> bool {
    (got as f64 - want).abs() <= rel * want.abs() + 1e-7
}

#[test]
fn distant_light_gives_rho_e_cos_over_pi_everywhere() {
    let rho = Rgb::new(0.8, 0.5, 0.25);
    let e = Rgb::new(2.0, 3.0, 4.0);
    let theta = 35f32.to_radians();
    let (w, h) = (16, 12);
    let cam = ortho_camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 4.0, w, h);
    let mut scene = plane_scene(cam, 4, rho);
    scene.add_light(
        "sun",
        LightComponent::Distant {
            // Travels towards the plane, at `theta` from its normal.
            direction: -Vec3::new(theta.sin(), 0.0, theta.cos()),
            irradiance: e,
        },
    );
    let out = render_default(&scene.compile().unwrap());
    let cos = (theta as f64).cos();
    let want: Vec<f64> = (0..3)
        .map(|c| rho.to_array()[c] as f64 * e.to_array()[c] as f64 * cos / PI)
        .collect();
    // A Dirac light and a plane: every sample has the same value; only float rounding differs.
    for (i, p) in out.beauty.pixels.iter().enumerate() {
        for (c, (got, want)) in p.to_array().into_iter().zip(&want).enumerate() {
            assert!(
                close(got, *want, 1e-5),
                "pixel {i} channel {c}: {got} vs {want}"
            );
        }
    }
}

/// `E(r) = I h / (h^2 + r^2)^(3/2)`: inverse-square falloff times the cosine `h / d` at the
/// plane, for a point light at height `h` above the point at distance `r` from the foot.
fn point_irradiance(intensity: f64, h: f64, r: f64) -> f64 {
    intensity * h / (h * h + r * r).powf(1.5)
}

#[test]
fn point_light_above_plane_follows_inverse_square_cosine_law() {
    let rho = Rgb::new(0.9, 0.6, 0.3);
    let intensity = Rgb::new(5.0, 6.0, 7.0);
    let height = 2.0f32;
    let (n, view) = (9u32, 0.09f32);
    // Looking straight down through the (geometry-less) light at the foot point.
    let cam = ortho_camera(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, Vec3::Y, view, n, n);
    let mut scene = plane_scene(cam, 16, rho);
    scene.add_light(
        "bulb",
        LightComponent::Point {
            position: Vec3::new(0.0, 0.0, height),
            intensity,
        },
    );
    let out = render_default(&scene.compile().unwrap());
    // Pixel (x, y) sees the square [x0, x0 + s] x [y0, y0 + s] of the plane (the image is
    // symmetric about the foot point, so orientation does not matter). E decreases with r,
    // so the pixel mean lies between E at the farthest and at the nearest point of the square.
    let s = view as f64 / n as f64;
    let half = view as f64 / 2.0;
    for y in 0..n as usize {
        for x in 0..n as usize {
            let (x0, y0) = (-half + x as f64 * s, -half + y as f64 * s);
            // Nearest and farthest |coordinate| on [a, a + s].
            let near = |a: f64| {
                if a <= 0.0 && a + s >= 0.0 {
                    0.0
                } else {
                    a.abs().min((a + s).abs())
                }
            };
            let far = |a: f64| a.abs().max((a + s).abs());
            let r_min = near(x0).hypot(near(y0));
            let r_max = far(x0).hypot(far(y0));
            let got = out.beauty.get(x, y).to_array();
            let channels = rho.to_array().into_iter().zip(intensity.to_array());
            for (c, (g, (r, i))) in got.into_iter().zip(channels).enumerate() {
                let k = r as f64 / PI;
                let lo = k * point_irradiance(i as f64, height as f64, r_max);
                let hi = k * point_irradiance(i as f64, height as f64, r_min);
                let g = g as f64;
                assert!(
                    g >= lo * (1.0 - 1e-5) && g <= hi * (1.0 + 1e-5),
                    "pixel ({x}, {y}) channel {c}: {g} not in [{lo}, {hi}]"
                );
            }
        }
    }
    // The centre pixel's range is tight (r <= 0.007): the value is rho/pi * I / h^2.
    let centre = out.beauty.get(4, 4).to_array();
    let channels = rho.to_array().into_iter().zip(intensity.to_array());
    for (got, (r, i)) in centre.into_iter().zip(channels) {
        let want = r as f64 / PI * i as f64 / (height as f64 * height as f64);
        assert!(close(got, want, 2e-5), "{got} vs {want}");
    }
}

/// Form factor from a differential area to a parallel rectangle of sides `a`, `b` at distance
/// `c`, one corner of which lies on the area's normal (Howell, *A Catalog of Radiation Heat
/// Transfer Configuration Factors*, B-3; also Siegel & Howell, Thermal Radiation Heat
/// Transfer, appendix C):
/// `F = 1/(2 pi) [A/sqrt(1+A^2) atan(B/sqrt(1+A^2)) + B/sqrt(1+B^2) atan(A/sqrt(1+B^2))]`
/// with `A = a/c`, `B = b/c`. The expression is odd in `a` and in `b`, so signed extents
/// combine rectangles by inclusion-exclusion.
fn corner_form_factor(a: f64, b: f64, c: f64) -> f64 {
    let (a, b) = (a / c, b / c);
    let sa = (1.0 + a * a).sqrt();
    let sb = (1.0 + b * b).sqrt();
    (a / sa * (b / sa).atan() + b / sb * (a / sb).atan()) / (2.0 * PI)
}

/// Irradiance at `(px, py, 0)` (normal +z) from the rectangle `[x0, x1] x [y0, y1]` at height
/// `h` emitting radiance `le` downwards: `E = pi * Le * F` (a Lambertian emitter's exitance
/// is `pi Le`, reciprocity), with `F` assembled from four corner rectangles.
fn rect_irradiance(le: f64, h: f64, [x0, x1, y0, y1]: [f64; 4], px: f64, py: f64) -> f64 {
    let f = |x: f64, y: f64| corner_form_factor(x - px, y - py, h);
    PI * le * (f(x1, y1) - f(x0, y1) - f(x1, y0) + f(x0, y0))
}

/// Brute-force `E = Le * integral of cos(theta) cos(theta') / d^2 dA = Le * h^2 / d^4 dA` by
/// the midpoint rule, to check the closed form above.
fn rect_irradiance_quadrature(
    le: f64,
    h: f64,
    [x0, x1, y0, y1]: [f64; 4],
    px: f64,
    py: f64,
) -> f64 {
    let n = 600;
    let (dx, dy) = ((x1 - x0) / n as f64, (y1 - y0) / n as f64);
    let mut sum = 0.0;
    for j in 0..n {
        for i in 0..n {
            let x = x0 + (i as f64 + 0.5) * dx - px;
            let y = y0 + (j as f64 + 0.5) * dy - py;
            let d2 = x * x + y * y + h * h;
            sum += h * h / (d2 * d2);
        }
    }
    le * sum * dx * dy
}

#[test]
fn rectangle_form_factor_matches_quadrature() {
    let rect = [-0.5, 0.5, -0.5, 0.5];
    for (px, py) in [(0.0, 0.0), (0.3, -0.2), (1.5, 0.7)] {
        let closed = rect_irradiance(1.0, 1.0, rect, px, py);
        let brute = rect_irradiance_quadrature(1.0, 1.0, rect, px, py);
        assert!(
            (closed - brute).abs() < 1e-5 * closed,
            "{closed} vs {brute}"
        );
    }
    // Centred square, half side X h: E = 4 Le X/sqrt(1+X^2) atan(X/sqrt(1+X^2)) -> pi Le as
    // the square covers the hemisphere.
    let big = rect_irradiance(1.0, 1.0, [-1e4, 1e4, -1e4, 1e4], 0.0, 0.0);
    assert!((big - PI).abs() < 1e-3, "{big}");
}

#[test]
fn square_area_light_over_plane_matches_form_factor() {
    let rho = Rgb::new(0.7, 0.5, 0.3);
    let le = Rgb::new(10.0, 8.0, 6.0);
    let (half_side, height) = (0.5f32, 1.0f32);
    // An oblique orthographic view (60 degrees from the normal) so the camera ray to the foot
    // point passes beside the emitter: at height h it is tan(60) h = 1.73 > 0.5 away.
    let tilt = 60f32.to_radians();
    let (n, view) = (9u32, 0.09f32);
    let from = 10.0 * Vec3::new(0.0, -tilt.sin(), tilt.cos());
    let cam = ortho_camera(from, Vec3::ZERO, Vec3::Z, view, n, n);
    let mut scene = plane_scene(cam, 4096, rho);
    let black = scene.add_material(
        "emitter",
        0,
        mat(Surface::Diffuse {
            reflectance: Rgb::BLACK,
        }),
    );
    // e1 x e2 = y x x = -z: the emitting side faces the plane.
    let s = 2.0 * half_side;
    scene.add_shape(
        "lamp",
        quad(
            Vec3::new(-half_side, -half_side, height),
            Vec3::new(0.0, s, 0.0),
            Vec3::new(s, 0.0, 0.0),
        ),
        black,
        Some(le),
    );
    let compiled = scene.compile().unwrap();
    let rect = [-0.5, 0.5, -0.5, 0.5].map(|v: f64| v * s as f64);

    // The central 3x3 pixels see, on the plane, x in [-1.5, 1.5] px and y stretched by
    // 1/cos(tilt) (camera right = +x, image up = (0, cos, sin) projects to +y / cos).
    let px = view as f64 / n as f64;
    let (xr, yr) = (1.5 * px, 1.5 * px / (tilt as f64).cos());
    let m = 40;
    let mut e_avg = 0.0;
    for j in 0..m {
        for i in 0..m {
            let x = -xr + (i as f64 + 0.5) * 2.0 * xr / m as f64;
            let y = -yr + (j as f64 + 0.5) * 2.0 * yr / m as f64;
            e_avg += rect_irradiance(1.0, height as f64, rect, x, y);
        }
    }
    e_avg /= (m * m) as f64;

    for technique in [
        LightingTechnique::Mis,
        LightingTechnique::NeeOnly,
        LightingTechnique::BxdfOnly,
    ] {
        let out = render_with(&compiled, technique, None);
        let (mean, se) = crop_mean(&out, 3..6, 3..6);
        for c in 0..3 {
            let want = rho.to_array()[c] as f64 / PI * le.to_array()[c] as f64 * e_avg;
            let (got, sigma) = (mean.to_array()[c] as f64, se.to_array()[c] as f64);
            assert!(
                sigma < 0.02 * want,
                "{technique:?}: too noisy to test, se {sigma}"
            );
            assert!(
                (got - want).abs() <= 3.0 * sigma + 1e-3 * want,
                "{technique:?} channel {c}: {got} vs {want} (se {sigma})"
            );
        }
    }
}

/// Mitsuba 3's spot falloff (`src/emitters/spot.cpp`, `falloff_curve`), written
/// independently of the renderer's: 1 within `beam`, linear in the angle to 0 at `cutoff`.
fn spot_falloff(theta: f64, cutoff: f64, beam: f64) -> f64 {
    if theta <= beam {
        1.0
    } else if theta < cutoff {
        (cutoff - theta) / (cutoff - beam)
    } else {
        0.0
    }
}

#[test]
fn spot_light_above_plane_follows_its_falloff() {
    // A spot at height h pointing straight down: the point at distance r from the foot is
    // at theta = atan(r / h) from the axis and receives E = I f(theta) cos(theta) / d^2.
    let rho = Rgb::new(0.9, 0.6, 0.3);
    let intensity = Rgb::new(5.0, 6.0, 7.0);
    let (h, cutoff_deg, beam_deg) = (2.0f64, 30.0f64, 20.0f64);
    let (cutoff, beam) = (cutoff_deg.to_radians(), beam_deg.to_radians());
    let e = |i: f64, r: f64| {
        let d2 = h * h + r * r;
        i * spot_falloff((r / h).atan(), cutoff, beam) * (h / d2.sqrt()) / d2
    };
    // One row of 150 pixels of 0.01 x 0.01 covering x in [0, 1.5] on the line y = 0:
    // inside the beam (r < h tan 20 = 0.728), the ramp (to h tan 30 = 1.155) and beyond.
    let (n, view) = (150u32, 1.5f32);
    let cam = ortho_camera(
        Vec3::new(0.75, 0.0, 10.0),
        Vec3::new(0.75, 0.0, 0.0),
        Vec3::Y,
        view,
        n,
        1,
    );
    let mut scene = plane_scene(cam, 16, rho);
    scene.add_light(
        "spot",
        LightComponent::Spot {
            position: Vec3::new(0.0, 0.0, h as f32),
            direction: Vec3::NEG_Z,
            intensity,
            cutoff_angle: cutoff_deg as f32,
            beam_width: beam_deg as f32,
            texture: None,
        },
    );
    let out = render_default(&scene.compile().unwrap());
    // E decreases with r (every factor does), so a pixel's mean lies between E at the
    // farthest and at the nearest point of its square, whatever its samples.
    let s = view as f64 / n as f64;
    let (mut inside, mut ramp, mut dark) = (0, 0, 0);
    for x in 0..n as usize {
        let x0 = x as f64 * s;
        let r_min = x0;
        let r_max = (x0 + s).hypot(s / 2.0);
        let got = out.beauty.get(x, 0).to_array();
        let channels = rho.to_array().into_iter().zip(intensity.to_array());
        for (c, (g, (r, i))) in got.into_iter().zip(channels).enumerate() {
            let k = r as f64 / PI;
            let (lo, hi) = (k * e(i as f64, r_max), k * e(i as f64, r_min));
            let g = g as f64;
            assert!(
                g >= lo * (1.0 - 1e-5) && g <= hi * (1.0 + 1e-5) + 1e-9,
                "pixel {x} (r in [{r_min:.3}, {r_max:.3}]) channel {c}: {g} not in [{lo}, {hi}]"
            );
        }
        let theta = (r_max / h).atan();
        if theta < beam {
            inside += 1;
        } else if (r_min / h).atan() > cutoff {
            dark += 1;
            assert_eq!(got, [0.0; 3], "pixel {x} is outside the cone");
        } else if (r_min / h).atan() > beam && theta < cutoff {
            ramp += 1;
        }
    }
    assert!(
        inside > 50 && ramp > 30 && dark > 20,
        "{inside} {ramp} {dark}"
    );
    // Mid-ramp, the linear ramp in angle and a smoothstep on the cosines differ by far
    // more than the pixel's bounds: theta = 25 deg (r = h tan 25 = 0.9326) has f = 1/2.
    let x = (h * 25f64.to_radians().tan() / s) as usize;
    let got = out.beauty.get(x, 0).r as f64;
    let want = rho.r as f64 / PI * e(intensity.r as f64, (x as f64 + 0.5) * s);
    assert!((got - want).abs() < 0.02 * want, "{got} vs {want}");
}
