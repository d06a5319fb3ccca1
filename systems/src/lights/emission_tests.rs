//! Tests of `emission.rs`: each light kind's emission densities against `emission_pdf`,
//! the emitted power against its analytic value, the sampled directions against their pdf
//! (the flux lights at infinity carry through the scene), and the selection; the
//! chi-square tests of the sampled directions are in `emission_direction_tests.rs`.

use super::*;
use crate::distribution::tests::{chi_square, chi_square_limit};
use crate::geometry::Sphere;
use crate::pattern::Texture;
use crate::sampler::SplitMix64 as Rng;
use crate::volume_lights::tests::gradient_emitter;
use crate::volume_lights::{EmissionField, EmitterSupport, VolumeEmitter};
use std::f64::consts::PI as PI64;

/// The scene box of every test: its bounding sphere has centre `(0, 0.5, 0)` and radius
/// `sqrt(2^2 + 3^2 + 2^2) / 2`.
pub(super) const BOUNDS: (Vec3, Vec3) = (Vec3::new(-1.0, -1.0, -1.0), Vec3::new(1.0, 2.0, 1.0));
const CENTER: Vec3 = Vec3::new(0.0, 0.5, 0.0);

pub(super) fn scene_radius() -> f32 {
    17.0f32.sqrt() * 0.5
}

/// One triangle (prim 0, area 0.6, in the plane `y = 1`) and one sphere (prim 1).
pub(super) fn geometry() -> SceneGeometry {
    let tri = [
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, 1.0, 1.0),
        Vec3::new(1.2, 1.0, 0.0),
    ];
    let sphere = Sphere {
        center: Vec3::new(-0.5, 0.0, 0.2),
        radius: 0.3,
    };
    SceneGeometry::build(vec![tri], vec![sphere])
}

/// A Nearest-filtered 16 x 8 map: a brighter upper half, a sun, some black texels.
pub(super) fn sky_map() -> EnvironmentMap {
    let (w, h) = (16, 8);
    let mut rng = Rng(42);
    let px = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let sky = if y < h / 2 { 1.0 } else { 0.2 };
            let mut p = Rgb::new(sky * 0.6, sky * 0.8, sky) * (0.5 + rng.f32());
            if (x, y) == (5, 2) {
                p = Rgb::new(60.0, 45.0, 24.0);
            }
            if i % 11 == 0 {
                p = Rgb::BLACK;
            }
            p
        })
        .collect();
    EnvironmentMap::new(px, w, h)
}

/// `j = 3` inside the unit ball in `[-1, 1]^3` (eight cells): `int j dV = 4 pi`.
fn ball_emitter() -> VolumeEmitter {
    let grid = crate::grid::DensityGrid::constant([2, 2, 2], 1.0).unwrap();
    let field = EmissionField::Grid {
        grid: Arc::new(grid),
        scale: Rgb::splat(3.0),
    };
    let ball = EmitterSupport::Ball {
        center: Vec3::ZERO,
        radius: 1.0,
    };
    let b = (Vec3::splat(-1.0), Vec3::splat(1.0));
    VolumeEmitter::new(
        b,
        [2, 2, 2],
        &[Rgb::splat(3.0); 8],
        vec![1.0; 8],
        field,
        ball,
    )
    .unwrap()
}

pub(super) fn spot(cutoff: f32, beam: f32, texture: Option<Arc<SpotTexture>>) -> Light {
    Light::Spot {
        position: Vec3::new(0.2, 1.5, -0.3),
        direction: Vec3::new(0.3, -1.0, 0.2).normalize(),
        intensity: Rgb::new(4.0, 2.0, 1.0),
        falloff: SpotFalloff::from_degrees(cutoff, beam),
        texture,
    }
}

/// A constant projection texture of `(0.5, 0.25, 1)`.
fn constant_texture() -> Arc<SpotTexture> {
    let axis = Vec3::new(0.3, -1.0, 0.2).normalize();
    let t = Texture::new(2, 2, vec![Rgb::new(0.5, 0.25, 1.0); 4]).unwrap();
    Arc::new(SpotTexture::new(t, axis, Vec3::X, 40f32.to_radians()).unwrap())
}

/// Every light kind, each with a name and its analytic emitted power per channel.
fn lights_and_powers() -> Vec<(&'static str, Light, [f64; 3])> {
    let r2 = (scene_radius() as f64).powi(2);
    let le = Rgb::new(1.0, 2.0, 3.0);
    let per = |c: Rgb, k: f64| c.to_array().map(|v| v as f64 * k);
    let spot_power =
        |cutoff: f32, beam: f32| SpotFalloff::from_degrees(cutoff, beam).solid_angle() as f64;
    let sky_integral = sky_map().integral();
    vec![
        // Triangle area 0.5 |(0, 0, 1) x (1.2, 0, 0)| = 0.6: L A pi.
        (
            "triangle",
            Light::Area {
                prim: 0,
                radiance: le,
            },
            per(le, 0.6 * PI64),
        ),
        (
            "sphere",
            Light::Area {
                prim: 1,
                radiance: le,
            },
            per(le, 4.0 * PI64 * 0.09 * PI64),
        ),
        (
            "point",
            Light::Point {
                position: Vec3::new(0.1, 0.2, 0.3),
                intensity: le,
            },
            per(le, 4.0 * PI64),
        ),
        (
            "spot",
            spot(40.0, 25.0, None),
            per(Rgb::new(4.0, 2.0, 1.0), spot_power(40.0, 25.0)),
        ),
        // A hard edge: I 2 pi (1 - cos c), independent of `solid_angle`.
        (
            "hard spot",
            spot(30.0, 30.0, None),
            per(
                Rgb::new(4.0, 2.0, 1.0),
                2.0 * PI64 * (1.0 - (PI64 / 6.0).cos()),
            ),
        ),
        (
            "textured spot",
            spot(40.0, 25.0, Some(constant_texture())),
            per(Rgb::new(2.0, 0.5, 1.0), spot_power(40.0, 25.0)),
        ),
        (
            "distant",
            Light::Distant {
                direction: Vec3::new(0.2, -1.0, 0.4).normalize(),
                irradiance: le,
            },
            per(le, PI64 * r2),
        ),
        (
            "constant environment",
            Light::Environment {
                radiance: le,
                map: None,
            },
            per(le, 4.0 * PI64 * PI64 * r2),
        ),
        (
            "environment map",
            Light::Environment {
                radiance: Rgb::new(1.0, 0.5, 2.0),
                map: Some(Box::new(sky_map())),
            },
            per(Rgb::new(1.0, 0.5, 2.0) * sky_integral, PI64 * r2),
        ),
        (
            "volume gradient",
            Light::Volume {
                emitter: Arc::new(gradient_emitter()),
            },
            per(Rgb::new(12.0, 6.0, 3.0), 4.0 * PI64),
        ),
        (
            "volume ball",
            Light::Volume {
                emitter: Arc::new(ball_emitter()),
            },
            per(Rgb::splat(4.0 * std::f32::consts::PI), 4.0 * PI64),
        ),
    ]
}

pub(super) fn random_sample(
    set: &LightSet,
    g: &SceneGeometry,
    rng: &mut Rng,
) -> Option<EmissionSample> {
    set.sample_emission(g, BOUNDS, rng.f32(), rng.vec2(), rng.vec2())
}

pub(super) fn close(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs())
}

#[test]
fn emission_pdf_of_a_sample_is_its_own_pdfs_and_the_fields_follow_the_conventions() {
    let g = geometry();
    let mut rng = Rng(3);
    let r = scene_radius();
    for (name, light, _) in lights_and_powers() {
        let kind = std::mem::discriminant(&light);
        let set = LightSet::new(vec![light], &g, r);
        let mut found = 0;
        for _ in 0..4000 {
            let Some(s) = random_sample(&set, &g, &mut rng) else {
                continue;
            };
            found += 1;
            let (pos, dir) = set.emission_pdf(s.light, s.p, s.n, s.direction, BOUNDS);
            assert!(
                close(pos, s.pdf_position, 1e-4) && close(dir, s.pdf_direction, 1e-4),
                "{name}: emission_pdf ({pos}, {dir}) vs sample ({}, {})",
                s.pdf_position,
                s.pdf_direction
            );
            assert!((s.direction.length() - 1.0).abs() < 1e-5, "{name}");
            assert!(s
                .radiance
                .to_array()
                .iter()
                .all(|&c| c >= 0.0 && c.is_finite()));
            match &set.lights()[0] {
                Light::Area { prim, .. } => {
                    assert!((s.n.length() - 1.0).abs() < 1e-5, "{name}");
                    assert!(close(s.cos_at_light, s.n.dot(s.direction), 1e-5), "{name}");
                    assert!(s.n.dot(s.direction) > 0.0, "{name}: one-sided");
                    // On the primitive: its normal at the point is the sample's.
                    let (on_prim, _) = g.sample_prim(*prim, Vec2::ZERO);
                    if *prim == 0 {
                        assert!((s.p - on_prim).dot(s.n).abs() < 1e-5, "{name}: off plane");
                    } else {
                        let c = Vec3::new(-0.5, 0.0, 0.2);
                        assert!(((s.p - c).length() - 0.3).abs() < 1e-5, "{name}");
                        assert!((s.n - (s.p - c) / 0.3).length() < 1e-4, "{name}");
                    }
                    assert!(!s.delta_position && !s.delta_direction && !s.at_infinity);
                }
                Light::Point { position, .. } | Light::Spot { position, .. } => {
                    assert_eq!((s.p, s.n, s.cos_at_light), (*position, Vec3::ZERO, 1.0));
                    assert!(s.delta_position && !s.delta_direction && !s.at_infinity);
                }
                Light::Distant { .. } | Light::Environment { .. } => {
                    if let Light::Distant { direction, .. } = &set.lights()[0] {
                        assert_eq!(s.direction, *direction, "{name}");
                    }
                    // On the disk R behind the centre, perpendicular to the direction.
                    let d = s.p - CENTER;
                    assert!((d.dot(s.direction) + r).abs() < 1e-4 * r, "{name}");
                    assert!((d + r * s.direction).length() <= r * (1.0 + 1e-5), "{name}");
                    assert_eq!(s.n, s.direction);
                    assert_eq!(s.cos_at_light, 1.0);
                    let distant = matches!(set.lights()[0], Light::Distant { .. });
                    assert!(s.at_infinity && !s.delta_position);
                    assert_eq!(s.delta_direction, distant);
                }
                Light::Volume { emitter } => {
                    assert_eq!(s.radiance, emitter.emission(s.p), "{name}");
                    assert_eq!((s.n, s.cos_at_light), (Vec3::ZERO, 1.0));
                    assert!(!s.delta_position && !s.delta_direction && !s.at_infinity);
                }
            }
        }
        assert!(found > 2000, "{name}: only {found} samples");
        assert_eq!(std::mem::discriminant(&set.lights()[0]), kind);
    }
}

#[test]
fn emission_pdf_is_zero_where_sampling_never_goes() {
    let g = geometry();
    let r = scene_radius();
    let set = LightSet::new(
        vec![Light::Area {
            prim: 0,
            radiance: Rgb::WHITE,
        }],
        &g,
        r,
    );
    let n = g.sample_prim(0, Vec2::ZERO).1;
    // Behind a one-sided emitter.
    assert_eq!(set.emission_pdf(0, Vec3::ZERO, n, -n, BOUNDS).1, 0.0);
    // Outside the spot's cone, and outside a volume emitter's box.
    let set = LightSet::new(vec![spot(30.0, 20.0, None)], &g, r);
    let Light::Spot {
        direction: axis, ..
    } = set.lights()[0]
    else {
        unreachable!()
    };
    assert_eq!(
        set.emission_pdf(0, Vec3::ZERO, Vec3::ZERO, -axis, BOUNDS).1,
        0.0
    );
    let out = Frame::from_normal(axis).to_world(Vec3::new(0.6, 0.0, 0.8));
    assert_eq!(
        set.emission_pdf(0, Vec3::ZERO, Vec3::ZERO, out, BOUNDS).1,
        0.0
    );
    let set = LightSet::new(
        vec![Light::Volume {
            emitter: Arc::new(gradient_emitter()),
        }],
        &g,
        r,
    );
    assert_eq!(
        set.emission_pdf(0, Vec3::splat(5.0), Vec3::ZERO, Vec3::Y, BOUNDS)
            .0,
        0.0
    );
    // An unknown light.
    assert_eq!(
        set.emission_pdf(7, Vec3::ZERO, Vec3::ZERO, Vec3::Y, BOUNDS),
        (0.0, 0.0)
    );
}

/// `E[radiance cos_at_light / (pdf_position pdf_direction)]` per channel over `n` samples
/// (counting only the rays `keep` keeps: the power they carry), with its standard error.
fn power_estimate(
    set: &LightSet,
    g: &SceneGeometry,
    n: usize,
    seed: u64,
    keep: impl Fn(&EmissionSample) -> bool,
) -> [(f64, f64); 3] {
    let mut rng = Rng(seed);
    let (mut sum, mut sum2) = ([0.0f64; 3], [0.0f64; 3]);
    for _ in 0..n {
        let Some(s) = random_sample(set, g, &mut rng).filter(&keep) else {
            continue;
        };
        let w = s.cos_at_light as f64 / (s.pdf_position as f64 * s.pdf_direction as f64);
        for (c, v) in s.radiance.to_array().into_iter().enumerate() {
            let x = v as f64 * w;
            sum[c] += x;
            sum2[c] += x * x;
        }
    }
    std::array::from_fn(|c| {
        let mean = sum[c] / n as f64;
        let var = (sum2[c] / n as f64 - mean * mean).max(0.0);
        (mean, (var / n as f64).sqrt())
    })
}

/// `got` is `want` per channel within four standard errors (and a relative `1e-4` for
/// zero-variance estimates).
fn assert_within_noise(got: [(f64, f64); 3], want: [f64; 3], what: &str) {
    for c in 0..3 {
        let (mean, se) = got[c];
        assert!(
            (mean - want[c]).abs() <= 4.0 * se + 1e-4 * want[c],
            "{what}, channel {c}: {mean} +- {se} vs {}",
            want[c]
        );
    }
}

#[test]
fn the_estimated_emitted_power_is_each_lights_analytic_power() {
    let g = geometry();
    for (k, (name, light, want)) in lights_and_powers().into_iter().enumerate() {
        let set = LightSet::new(vec![light], &g, scene_radius());
        let got = power_estimate(&set, &g, 200_000, 11 + k as u64, |_| true);
        assert_within_noise(got, want, name);
    }
}

/// The flux lights at infinity carry into a sphere of radius `rho` inside the scene (off
/// its centre): the rays that hit it, weighted as in [`power_estimate`]. Analytic: a
/// distant light's `E pi rho^2`; a constant environment's `L pi 4 pi rho^2` (irradiance
/// `pi L` on every surface element). Fails if the disk is misplaced, too small, or not
/// uniform.
#[test]
fn lights_at_infinity_carry_their_flux_into_the_scene() {
    let g = geometry();
    let (c, rho) = (Vec3::new(0.6, 1.2, -0.5), 0.4f32);
    let hits = |p: Vec3, d: Vec3| {
        // |p + t d - c|^2 = rho^2 with t > 0.
        let o = p - c;
        let b = o.dot(d);
        let disc = b * b - (o.length_squared() - rho * rho);
        disc >= 0.0 && -b - disc.sqrt() > 0.0
    };
    let le = Rgb::new(1.0, 2.0, 3.0);
    let area = PI64 * (rho as f64).powi(2);
    let cases = [
        (
            Light::Distant {
                direction: Vec3::new(0.2, -1.0, 0.4).normalize(),
                irradiance: le,
            },
            area,
        ),
        (
            Light::Environment {
                radiance: le,
                map: None,
            },
            PI64 * 4.0 * area,
        ),
    ];
    for (light, k) in cases {
        let set = LightSet::new(vec![light], &g, scene_radius());
        let got = power_estimate(&set, &g, 400_000, 5, |s| hits(s.p, s.direction));
        let want = le.to_array().map(|l| k * l as f64);
        assert_within_noise(got, want, &format!("{:?}", set.lights()[0]));
    }
}

#[test]
fn selection_follows_selection_pmf_and_picks_what_sample_picks() {
    let g = geometry();
    let (a, b) = (Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, -1.0, 0.0));
    let lights = vec![
        Light::Point {
            position: a,
            intensity: Rgb::splat(1.0),
        },
        Light::Point {
            position: b,
            intensity: Rgb::splat(3.0),
        },
    ];
    let set = LightSet::new(lights, &g, 1.0);
    // Selection in proportion to power (4 pi I): 1 : 3.
    assert!(close(set.selection_pmf(0), 0.25, 1e-6) && close(set.selection_pmf(1), 0.75, 1e-6));
    let mut rng = Rng(17);
    let n = 100_000u64;
    let mut counts = [0u64; 2];
    for _ in 0..n {
        let u = rng.f32();
        let s = set
            .sample_emission(&g, BOUNDS, u, rng.vec2(), rng.vec2())
            .expect("point lights always emit");
        assert_eq!(Some(s.light), set.selected_light(u));
        // Next-event estimation from the origin picks the same light for the same u.
        let nee = set.sample(&g, Vec3::ZERO, u, Vec2::splat(0.5)).unwrap();
        assert_eq!(nee.wi, if s.light == 0 { Vec3::Y } else { Vec3::NEG_Y });
        // pdf_position of a Dirac position is the selection probability.
        assert_eq!(s.pdf_position, set.selection_pmf(s.light));
        counts[s.light as usize] += 1;
    }
    let probs = [set.selection_pmf(0) as f64, set.selection_pmf(1) as f64];
    let (stat, df) = chi_square(&counts, &probs, n);
    assert!(
        stat < chi_square_limit(df),
        "chi2 {stat}, counts {counts:?}"
    );
    // Nothing to select.
    let empty = LightSet::new(Vec::new(), &g, 1.0);
    assert_eq!(empty.selected_light(0.5), None);
    assert!(empty
        .sample_emission(&g, BOUNDS, 0.5, Vec2::ZERO, Vec2::ZERO)
        .is_none());
    assert_eq!(empty.environment_light(), None);
}

#[test]
fn a_volume_light_beside_another_light_samples_its_cells_from_the_rescaled_selection() {
    // The volume light takes the middle of the selection interval: the power estimate
    // over the set is the sum of the three lights' powers only if the volume light's cell
    // sample is `u_select` rescaled to [0, 1) within its interval (it would otherwise
    // reach only some of the cells, at the wrong rates).
    let g = geometry();
    let lights = vec![
        Light::Point {
            position: Vec3::new(0.0, 3.0, 0.0),
            intensity: Rgb::splat(2.0),
        },
        Light::Volume {
            emitter: Arc::new(gradient_emitter()),
        },
        Light::Environment {
            radiance: Rgb::splat(0.01),
            map: None,
        },
    ];
    let set = LightSet::new(lights, &g, scene_radius());
    assert_eq!(set.environment_light(), Some(2));
    let got = power_estimate(&set, &g, 400_000, 29, |_| true);
    let r2 = (scene_radius() as f64).powi(2);
    // 4 pi I + 4 pi int j dV + L 4 pi pi R^2.
    let want = [12.0, 6.0, 3.0]
        .map(|j: f64| 4.0 * PI64 * 2.0 + 4.0 * PI64 * j + 0.01 * 4.0 * PI64 * PI64 * r2);
    assert_within_noise(got, want, "point, volume and environment");
}
