//! Tests of `lights.rs`.

use super::*;
use crate::geometry::Sphere;
use crate::sampler::SplitMix64 as Rng;

/// The scalar reference of [`LightSet::sample_column`], point by point.
fn sample_column_scalar(
    set: &LightSet,
    geometry: &SceneGeometry,
    p: &[Vec3],
    u: &[[f32; 4]],
    active: &[bool],
) -> Vec<Option<LightSample>> {
    (0..p.len())
        .map(|i| {
            active[i]
                .then(|| set.sample(geometry, p[i], u[i][2], Vec2::new(u[i][0], u[i][1])))
                .flatten()
        })
        .collect()
}

/// A scene of `n_tri` small triangles (area lights of varied power, some facing away
/// from the origin region) plus one sphere; returns the geometry and the triangle lights.
fn triangle_scene(n_tri: usize, rng: &mut Rng) -> (SceneGeometry, Vec<Light>) {
    let mut tris = Vec::new();
    let mut lights = Vec::new();
    for i in 0..n_tri {
        let c = Vec3::new(
            rng.f32() * 4.0 - 2.0,
            1.0 + rng.f32(),
            rng.f32() * 4.0 - 2.0,
        );
        let e1 = Vec3::new(rng.f32(), 0.1 * rng.f32(), rng.f32() - 0.5);
        let e2 = Vec3::new(rng.f32() - 0.5, 0.1 * rng.f32(), rng.f32());
        tris.push(if i % 2 == 0 {
            [c, c + e1, c + e2]
        } else {
            [c, c + e2, c + e1]
        });
        lights.push(Light::Area {
            prim: i as u32,
            radiance: Rgb::new(1.0 + i as f32, 2.0, 0.5 * rng.f32()),
        });
    }
    let sphere = Sphere {
        center: Vec3::new(0.0, 3.0, 0.0),
        radius: 0.5,
    };
    (SceneGeometry::build(tris, vec![sphere]), lights)
}

/// `set.sample_column` into fresh columns (filled with junk first, so that rows the
/// sampler fails to write show), read back as rows.
fn sample_column_rows(
    backend: Backend,
    set: &LightSet,
    geometry: &SceneGeometry,
    p: &[Vec3],
    u: &[[f32; 4]],
    active: &[bool],
) -> Vec<Option<LightSample>> {
    let n = p.len();
    let (mut wi, mut distance, mut radiance) =
        (vec![Vec3::NAN; n], vec![-1.0; n], vec![Rgb::splat(-1.0); n]);
    let (mut pdf, mut delta, mut margin) = (vec![-1.0; n], vec![true; n], vec![-1.0; n]);
    let mut cols = LightSampleColumns {
        wi: &mut wi,
        distance: &mut distance,
        radiance: &mut radiance,
        pdf: &mut pdf,
        delta: &mut delta,
        margin: &mut margin,
    };
    set.sample_column_on(backend, geometry, p, u, active, &mut cols);
    for i in 0..n {
        if cols.pdf[i] == 0.0 {
            assert_eq!(cols.wi[i], Vec3::Z, "rows without a sample have wi = +z");
        }
    }
    (0..n).map(|i| cols.get(i)).collect()
}

/// `sample_column` must return exactly `sample`'s results point by point.
fn check_column(set: &LightSet, geometry: &SceneGeometry, rng: &mut Rng) {
    for len in [0usize, 1, 3, 4, 5, 8, 11, 64] {
        let p: Vec<Vec3> = (0..len)
            .map(|i| match i % 7 {
                // A point on a light's plane corner and far away points: degenerate
                // and grazing samples.
                0 => geometry.triangle(0)[0],
                1 => Vec3::splat(1e30),
                _ => Vec3::new(
                    rng.f32() * 2.0 - 1.0,
                    rng.f32() - 1.0,
                    rng.f32() * 2.0 - 1.0,
                ),
            })
            .collect();
        let u: Vec<[f32; 4]> = (0..len)
            .map(|i| match i % 5 {
                0 => [0.0, 0.0, 0.0, 0.5],
                1 => [0.5, 0.5, 1.0 - f32::EPSILON / 2.0, 0.5],
                _ => [rng.f32(), rng.f32(), rng.f32(), rng.f32()],
            })
            .collect();
        let active: Vec<bool> = (0..len).map(|i| i % 6 != 3).collect();
        let want = sample_column_scalar(set, geometry, &p, &u, &active);
        for backend in Backend::all() {
            let out = sample_column_rows(backend, set, geometry, &p, &u, &active);
            check_rows(&out, &want, &format!("{backend:?}, len {len}"));
        }
    }
}

/// Rows `got` and `want` hold the same bits.
fn check_rows(got: &[Option<LightSample>], want: &[Option<LightSample>], what: &str) {
    for i in 0..want.len() {
        {
            let bits = |s: Option<LightSample>| {
                s.map(|s| {
                    (
                        s.wi.to_array().map(f32::to_bits),
                        s.distance.to_bits(),
                        s.radiance.to_array().map(f32::to_bits),
                        s.pdf.to_bits(),
                        s.delta,
                        s.margin.to_bits(),
                    )
                })
            };
            assert_eq!(bits(got[i]), bits(want[i]), "{what}, point {i}");
        }
    }
}

#[test]
fn power_heuristic_weights_and_edge_cases() {
    // Veach's w = a^2 / (a^2 + b^2), and the conventions for degenerate pdfs.
    assert_eq!(power_heuristic(1.0, 1.0), 0.5);
    assert_eq!(power_heuristic(3.0, 4.0), 9.0 / 25.0);
    assert_eq!(power_heuristic(0.0, 2.0), 0.0, "a = 0");
    assert_eq!(power_heuristic(0.0, 0.0), 0.0, "a = b = 0");
    assert_eq!(power_heuristic(f32::INFINITY, 1.0), 1.0, "a infinite");
    assert_eq!(power_heuristic(1e20, 1.0), 1.0, "a^2 overflows");
    assert_eq!(power_heuristic(f32::NAN, 1.0), 1.0, "a NaN");
    assert_eq!(power_heuristic(1.0, f32::INFINITY), 0.0, "b infinite");
    assert_eq!(power_heuristic(1.0, f32::NAN), 1.0, "w NaN");
    assert_eq!(power_heuristic(1e19, 1e19), 0.5, "a^2 + b^2 finite");
}

#[test]
fn column_sampling_equals_per_point_sampling() {
    let mut rng = Rng(5);
    // Triangle lights only (every group takes the four-lane path), with few lights
    // (selection by counting) and many (binary search in the distribution).
    for n in [1usize, 2, 5, 16, 40] {
        let (geometry, lights) = triangle_scene(n, &mut rng);
        let set = LightSet::new(lights, &geometry, 10.0);
        check_column(&set, &geometry, &mut rng);
    }
    // Mixed kinds: groups that select a sphere, point, distant or environment light
    // fall back to per-point sampling; a zero-power triangle light is never selected.
    let (geometry, mut lights) = triangle_scene(4, &mut rng);
    lights.push(Light::Area {
        prim: 4,
        radiance: Rgb::splat(3.0),
    });
    lights.push(Light::Point {
        position: Vec3::new(0.0, 2.0, 0.0),
        intensity: Rgb::splat(5.0),
    });
    lights.push(Light::Distant {
        direction: -Vec3::Y,
        irradiance: Rgb::splat(0.5),
    });
    lights.push(Light::Spot {
        position: Vec3::new(0.3, 2.0, 0.1),
        direction: -Vec3::Y,
        intensity: Rgb::splat(8.0),
        falloff: SpotFalloff::from_degrees(60.0, 40.0),
        texture: None,
    });
    lights.push(Light::Environment {
        radiance: Rgb::splat(0.1),
        map: None,
    });
    lights.push(Light::Area {
        prim: 3,
        radiance: Rgb::BLACK,
    });
    let set = LightSet::new(lights, &geometry, 10.0);
    check_column(&set, &geometry, &mut rng);
    // At most eight lights of mixed kinds (the eight-lane path, whose lanes of other
    // kinds go through `sample`).
    let (geometry, mut lights) = triangle_scene(3, &mut rng);
    lights.push(Light::Area {
        prim: 3,
        radiance: Rgb::splat(3.0),
    });
    lights.push(Light::Point {
        position: Vec3::new(0.0, 2.0, 0.0),
        intensity: Rgb::splat(5.0),
    });
    lights.push(Light::Area {
        prim: 2,
        radiance: Rgb::BLACK,
    });
    let set = LightSet::new(lights, &geometry, 10.0);
    check_column(&set, &geometry, &mut rng);
    // No lights at all.
    let set = LightSet::new(Vec::new(), &geometry, 10.0);
    check_column(&set, &geometry, &mut rng);
}

#[test]
fn triangle_light_samples_match_area_pdf_and_emitter() {
    // Independent of the sampling code path: every sample's pdf is the solid-angle pdf
    // area_pdf computes from the hit point, and the point lies on the sampled emitter's
    // plane at the reported distance.
    let mut rng = Rng(9);
    let (geometry, lights) = triangle_scene(6, &mut rng);
    let set = LightSet::new(lights, &geometry, 10.0);
    let n = 4096;
    let p: Vec<Vec3> = (0..n)
        .map(|_| Vec3::new(rng.f32(), -1.0, rng.f32()))
        .collect();
    let u: Vec<[f32; 4]> = (0..n)
        .map(|_| [rng.f32(), rng.f32(), rng.f32(), 0.0])
        .collect();
    let out = sample_column_rows(Backend::best(), &set, &geometry, &p, &u, &vec![true; n]);
    let mut found = 0;
    for (i, s) in out.iter().enumerate() {
        let Some(s) = s else { continue };
        found += 1;
        let q = p[i] + s.wi * s.distance;
        let prim = (0..6)
            .find(|&t| {
                let [a, b, c] = geometry.triangle(t);
                let nrm = (b - a).cross(c - a).normalize();
                (q - a).dot(nrm).abs() < 1e-4
            })
            .expect("sample lies on some emitter") as u32;
        let ng = geometry.sample_prim(prim, Vec2::ZERO).1;
        let want = set.area_pdf(prim, p[i], q, ng);
        assert!((s.pdf - want).abs() <= 1e-3 * want, "{} vs {want}", s.pdf);
    }
    assert!(found > n / 4, "only {found} samples");
}

/// `2 pi int_0^pi f(theta) sin theta dtheta` by the midpoint rule in f64 on `f.eval`.
fn integrate_falloff(f: &SpotFalloff) -> f64 {
    let n = 200_000;
    let h = std::f64::consts::PI / n as f64;
    let sum: f64 = (0..n)
        .map(|k| {
            let t = (k as f64 + 0.5) * h;
            f.eval(t.cos() as f32) as f64 * t.sin()
        })
        .sum();
    2.0 * std::f64::consts::PI * sum * h
}

#[test]
fn spot_falloff_is_mitsubas_linear_ramp_in_angle() {
    let f = SpotFalloff::from_degrees(20.0, 15.0);
    let at = |deg: f32| f.eval(deg.to_radians().cos());
    assert_eq!(at(0.0), 1.0);
    assert_eq!(at(14.9), 1.0);
    // Linear in the angle: (20 - theta) / (20 - 15).
    for deg in [15.5f32, 16.0, 17.5, 19.0, 19.9] {
        let want = (20.0 - deg) / 5.0;
        assert!(
            (at(deg) - want).abs() < 2e-3,
            "{deg}: {} vs {want}",
            at(deg)
        );
    }
    assert_eq!(at(20.1), 0.0);
    assert_eq!(at(90.0), 0.0);
    assert_eq!(at(180.0), 0.0);
    // beam = cutoff: a hard edge.
    let hard = SpotFalloff::from_degrees(30.0, 30.0);
    assert_eq!(hard.eval(29.9f32.to_radians().cos()), 1.0);
    assert_eq!(hard.eval(30.1f32.to_radians().cos()), 0.0);
}

#[test]
fn spot_power_is_the_integrated_falloff() {
    for (c, b) in [
        (20.0, 15.0),
        (90.0, 67.5),
        (90.0, 1.0),
        (45.0, 45.0),
        (30.0, 29.999),
        (5.0, 0.5),
    ] {
        let f = SpotFalloff::from_degrees(c, b);
        let num = integrate_falloff(&f);
        let closed = f.solid_angle() as f64;
        assert!(
            (closed - num).abs() <= 1e-4 * num,
            "cutoff {c} beam {b}: closed {closed} vs integrated {num}"
        );
    }
    // The selection power uses it: a spot and a point light of equal intensity are
    // selected in the ratio of the solid angle to 4 pi.
    let geometry = SceneGeometry::build(Vec::new(), Vec::new());
    let f = SpotFalloff::from_degrees(40.0, 30.0);
    let lights = vec![
        Light::Spot {
            position: Vec3::ZERO,
            direction: Vec3::Y,
            intensity: Rgb::new(1.0, 2.0, 3.0),
            falloff: f,
            texture: None,
        },
        Light::Point {
            position: Vec3::ZERO,
            intensity: Rgb::new(1.0, 2.0, 3.0),
        },
    ];
    let set = LightSet::new(lights, &geometry, 1.0);
    let ratio = set.selection_pmf(0) / set.selection_pmf(1);
    let want = integrate_falloff(&f) / (4.0 * std::f64::consts::PI);
    assert!(
        (ratio as f64 - want).abs() < 1e-4 * want,
        "{ratio} vs {want}"
    );
}

#[test]
fn spot_sample_is_intensity_falloff_over_distance_squared() {
    let geometry = SceneGeometry::build(Vec::new(), Vec::new());
    let f = SpotFalloff::from_degrees(30.0, 20.0);
    let set = LightSet::new(
        vec![Light::Spot {
            position: Vec3::new(0.0, 2.0, 0.0),
            direction: Vec3::NEG_Y,
            intensity: Rgb::new(4.0, 2.0, 1.0),
            falloff: f,
            texture: None,
        }],
        &geometry,
        1.0,
    );
    for x in [0.0f32, 0.5, 0.8, 1.0, 1.1, 1.5] {
        let p = Vec3::new(x, 0.0, 0.0);
        let theta = (x / 2.0).atan().to_degrees();
        let want = if theta <= 20.0 {
            1.0
        } else if theta < 30.0 {
            (30.0 - theta) / 10.0
        } else {
            0.0
        };
        let s = set.sample(&geometry, p, 0.5, Vec2::splat(0.5));
        match s {
            None => assert_eq!(want, 0.0, "x {x}"),
            Some(s) => {
                let d2 = 4.0 + x * x;
                let got = s.radiance.r * d2 / 4.0;
                assert!((got - want).abs() < 1e-3, "x {x}: {got} vs {want}");
                assert!(s.delta && s.pdf == 1.0);
                assert!((s.distance - d2.sqrt()).abs() < 1e-5);
            }
        }
    }
}

#[test]
fn a_light_set_samples_a_volume_light_at_its_volume_pdf_and_caps_its_share() {
    use crate::geometry::SceneGeometry;
    use glam::Vec2;
    let geometry = SceneGeometry::build(Vec::new(), Vec::new());
    let e = Arc::new(crate::volume_lights::tests::emitter());
    let point = Light::Point {
        position: Vec3::splat(5.0),
        intensity: Rgb::splat(1e-3),
    };
    let volume = Light::Volume { emitter: e.clone() };
    let set = LightSet::new(vec![point, volume], &geometry, 10.0);
    // The volume light's power (216) is far above the point light's (0.013): capped
    // at one half.
    assert!((set.selection_pmf(1) - 0.5).abs() < 1e-6);
    let p = Vec3::new(0.0, -1.0, 0.0);
    let mut r = crate::volume_lights::tests::rng(3);
    let mut volume_samples = 0;
    for _ in 0..2000 {
        let u = [r(), r(), r()];
        let s = set.sample(&geometry, p, u[2], Vec2::new(u[0], u[1]));
        assert_eq!(
            s.is_some_and(|s| !s.delta),
            set.selects_volume(u[2]),
            "a non-Dirac sample is the volume light's"
        );
        let Some(s) = s.filter(|s| !s.delta) else {
            continue;
        };
        volume_samples += 1;
        let x = p + s.wi * s.distance;
        let maj = e.mis_majorant(x);
        // pdf = P(light) p_V s^2 / majorant, radiance = j / majorant.
        let want = set.volume_pdf(1, x) * s.distance * s.distance / maj;
        assert!((s.pdf - want).abs() <= 1e-3 * want, "{} vs {want}", s.pdf);
        let j = e.emission(x) * (1.0 / maj);
        assert!((s.radiance.r - j.r).abs() <= 1e-5 * j.r);
    }
    assert!((800..1200).contains(&volume_samples), "{volume_samples}");
}
