//! The Beckmann distribution against integrals computed in slope space, where it is a
//! Gaussian: the projected area of the facets is 1, and `G1` normalises the visible
//! normals, `int D(m) max(0, wo . m) G1(wo) dm = cos theta_o` (Heitz 2014 eq. 17/43: the
//! white-furnace identity of the masking function).

use super::*;

/// `int g(m) D(m) dm` over the normals by the midpoint rule in the stretched slopes
/// `(s, t) = (slope_x / au, slope_y / av)` on `[-6, 6]^2` (the Gaussian is below `e^-36`
/// outside): `m = normalize(-au s, -av t, 1)`, `dm = cos^3 theta_m au av ds dt`.
fn slope_integral(b: &Beckmann, g: impl Fn(Vec3) -> f64) -> f64 {
    const N: usize = 800;
    let h = 12.0 / N as f64;
    let mut sum = 0.0;
    for i in 0..N {
        let s = -6.0 + (i as f64 + 0.5) * h;
        for j in 0..N {
            let t = -6.0 + (j as f64 + 0.5) * h;
            let m = Vec3::new(
                (-b.alpha_u as f64 * s) as f32,
                (-b.alpha_v as f64 * t) as f32,
                1.0,
            )
            .normalize();
            let jac = (m.z as f64).powi(3) * b.alpha_u as f64 * b.alpha_v as f64;
            sum += g(m) * b.d(m) as f64 * jac;
        }
    }
    sum * h * h
}

fn distributions() -> [Beckmann; 5] {
    [
        Beckmann::isotropic(0.05),
        Beckmann::isotropic(0.3),
        Beckmann::isotropic(1.0),
        Beckmann::new(0.2, 0.7),
        Beckmann::new(0.9, 0.1),
    ]
}

fn view(cos: f32, phi: f32) -> Vec3 {
    let s = (1.0 - cos * cos).sqrt();
    Vec3::new(s * phi.cos(), s * phi.sin(), cos)
}

#[test]
fn projected_area_of_the_facets_is_one() {
    for b in distributions() {
        let area = slope_integral(&b, |m| m.z as f64);
        assert!((area - 1.0).abs() < 1e-4, "{b:?}: {area}");
    }
}

#[test]
fn g1_normalises_the_visible_normals() {
    for b in distributions() {
        for wo in [
            view(1.0, 0.0),
            view(0.7, 0.4),
            view(0.3, 2.0),
            view(0.05, 1.1),
        ] {
            let visible = slope_integral(&b, |m| wo.dot(m).max(0.0) as f64);
            let ratio = visible * b.g1(wo) as f64 / wo.z as f64;
            assert!((ratio - 1.0).abs() < 2e-3, "{b:?} wo {wo}: {ratio}");
        }
    }
}

/// The identity is sharp: `Lambda` halved (or GGX's `Lambda` used with Beckmann's `D`)
/// breaks it at grazing incidence by far more than the tolerance above.
#[test]
fn the_normalisation_check_can_fail() {
    let b = Beckmann::isotropic(0.5);
    let wo = view(0.1, 0.3);
    let visible = slope_integral(&b, |m| wo.dot(m).max(0.0) as f64);
    let halved = visible / (1.0 + 0.5 * b.lambda(wo) as f64) / wo.z as f64;
    assert!((halved - 1.0).abs() > 0.05, "{halved}");
    let ggx = super::super::Ggx::isotropic(0.5);
    let wrong = visible * ggx.g1(wo) as f64 / wo.z as f64;
    assert!((wrong - 1.0).abs() > 0.01, "{wrong}");
}

#[test]
fn lambda_limits() {
    let b = Beckmann::isotropic(0.3);
    assert_eq!(b.lambda(Vec3::Z), 0.0);
    assert_eq!(b.lambda(Vec3::X), f32::INFINITY);
    // Lambda is even in w (transmission sees the same masking from below).
    let w = view(0.4, 1.0);
    assert_eq!(b.lambda(w), b.lambda(-w));
}

#[test]
fn sampled_normals_face_the_viewer_and_are_unit() {
    for b in distributions() {
        for wo in [view(1.0, 0.0), view(0.5, 0.5), view(0.01, 2.0)] {
            for i in 0..64 {
                for j in 0..64 {
                    let u = Vec2::new((i as f32 + 0.5) / 64.0, (j as f32 + 0.5) / 64.0);
                    let m = b.sample_visible(wo, u);
                    assert!((m.length() - 1.0).abs() < 1e-4, "{b:?} {wo} {u}: {m}");
                    assert!(m.z > 0.0, "{b:?} {wo} {u}: {m}");
                }
            }
        }
    }
}
