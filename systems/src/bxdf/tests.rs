//! Tests of `bxdf.rs`.

use super::*;

use crate::sampler::SplitMix64 as Rng;
fn dir(theta: f32, phi: f32) -> Vec3 {
    Vec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

/// Fresnel reflectance from the angle forms (Born & Wolf eq. 1.5.(21)):
/// `R_s = sin^2(ti - tt) / sin^2(ti + tt)`, `R_p = tan^2(ti - tt) / tan^2(ti + tt)`,
/// in f64 -- a different formula than the one under test.
fn fresnel_angles(theta_i: f64, eta: f64) -> (f64, f64) {
    if theta_i == 0.0 {
        let r0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
        return (r0, r0);
    }
    let sin_t = theta_i.sin() / eta;
    if sin_t >= 1.0 {
        return (1.0, 1.0);
    }
    let theta_t = sin_t.asin();
    let rs = ((theta_i - theta_t).sin() / (theta_i + theta_t).sin()).powi(2);
    let rp = ((theta_i - theta_t).tan() / (theta_i + theta_t).tan()).powi(2);
    (rs, rp)
}

#[test]
fn frame_is_orthonormal_right_handed_and_inverts() {
    let mut rng = Rng(1);
    let mut normals: Vec<Vec3> = (0..2000)
        .map(|_| sample_uniform_sphere(rng.vec2()))
        .collect();
    normals.extend([
        Vec3::Z,
        -Vec3::Z,
        Vec3::X,
        Vec3::new(0.0, -0.0, -1.0),
        Vec3::new(1e-4, 0.0, -1.0).normalize(),
        Vec3::new(0.0, 1e-7, -1.0).normalize(),
        Vec3::new(1.0, 0.0, -0.0),
        Vec3::new(1.0, 0.0, 1e-7).normalize(),
    ]);
    for n in normals {
        let f = Frame::from_normal(n);
        for (a, b) in [(f.s, f.t), (f.t, f.n), (f.s, f.n)] {
            assert!(a.dot(b).abs() < 1e-5, "not orthogonal for n = {n}");
        }
        for v in [f.s, f.t, f.n] {
            assert!((v.length() - 1.0).abs() < 1e-5, "not unit for n = {n}");
        }
        assert!(
            (f.s.cross(f.t) - f.n).length() < 1e-5,
            "not right-handed for {n}"
        );
        assert!((f.to_local(n) - Vec3::Z).length() < 1e-5);
        let v = Vec3::new(0.3, -0.5, 0.81).normalize();
        assert!((f.to_local(f.to_world(v)) - v).length() < 1e-5);
    }
}

#[test]
fn quarter_pi_sin_cos_matches_libm() {
    // Against the f64 functions over the whole interval, including its ends.
    let n = 100_000;
    for i in 0..=n {
        let x = (i as f32 / n as f32 * 2.0 - 1.0) * FRAC_PI_4;
        let (s, c) = sin_cos_quarter_pi(x);
        let (s64, c64) = (x as f64).sin_cos();
        assert!(
            (s as f64 - s64).abs() <= 1.2e-7 * s64.abs().max(1e-30) + 1e-9,
            "sin {x}"
        );
        assert!((c as f64 - c64).abs() <= 1.2e-7, "cos {x}");
    }
}

#[test]
fn concentric_disk_stays_in_disk_and_covers_it() {
    let mut rng = Rng(2);
    let mut quadrants = [0usize; 4];
    for _ in 0..10_000 {
        let d = sample_concentric_disk(rng.vec2());
        assert!(d.length() <= 1.0 + 1e-6);
        quadrants[(d.x >= 0.0) as usize * 2 + (d.y >= 0.0) as usize] += 1;
    }
    for q in quadrants {
        assert!((q as f64 - 2500.0).abs() < 5.0 * 43.3, "{quadrants:?}");
    }
    // Corners of the square go to the circle's diagonals.
    let c = sample_concentric_disk(Vec2::new(1.0, 1.0));
    assert!((c - Vec2::splat(std::f32::consts::FRAC_1_SQRT_2)).length() < 1e-6);
}

#[test]
fn triangle_samples_are_uniform_barycentrics() {
    // Inside the triangle, and the mean of uniform barycentrics is the centroid
    // (1/3, 1/3) with per-coordinate variance 1/18.
    let mut rng = Rng(3);
    let n = 200_000;
    let mut sum = [0.0f64; 2];
    let mut below_half = 0usize;
    for _ in 0..n {
        let b = sample_uniform_triangle(rng.vec2());
        assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
        sum[0] += b.x as f64;
        sum[1] += b.y as f64;
        // Area of {b0 + b1 < 1/2} is a quarter of the triangle's.
        below_half += (b.x + b.y < 0.5) as usize;
    }
    let tol = 5.0 * (1.0f64 / 18.0 / n as f64).sqrt();
    for s in sum {
        assert!((s / n as f64 - 1.0 / 3.0).abs() < tol, "{sum:?}");
    }
    let p = below_half as f64 / n as f64;
    assert!(
        (p - 0.25).abs() < 5.0 * (0.25 * 0.75 / n as f64).sqrt(),
        "{p}"
    );
}

#[test]
fn fresnel_known_values() {
    for eta in [1.0f32, 1.33, 1.5, 2.4, 0.5] {
        let r0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
        assert!(
            (fresnel_dielectric(1.0, eta) - r0).abs() < 1e-6,
            "eta {eta}"
        );
        // Normal incidence from inside sees the same reflectance.
        assert!(
            (fresnel_dielectric(-1.0, eta) - r0).abs() < 1e-6,
            "eta {eta}"
        );
    }
    // Glass: 4% at normal incidence, 1 at grazing.
    assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
    assert_eq!(fresnel_dielectric(0.0, 1.5), 1.0);
    // Index matched: no reflection at all, even at grazing incidence.
    for c in [1.0, 0.5, 1e-7, 0.0, -0.3] {
        assert_eq!(fresnel_dielectric(c, 1.0), 0.0);
    }
    // Against the angle form of the Fresnel equations over the whole range.
    for eta in [1.33f64, 1.5, 2.4, 1.0 / 1.5] {
        for k in 1..90 {
            let theta = (k as f64).to_radians();
            let (rs, rp) = fresnel_angles(theta, eta);
            let (s, p) = fresnel_dielectric_polarized(theta.cos() as f32, eta as f32);
            assert!(
                (s as f64 - rs).abs() < 2e-5,
                "Rs eta {eta} theta {k}: {s} {rs}"
            );
            assert!(
                (p as f64 - rp).abs() < 2e-5,
                "Rp eta {eta} theta {k}: {p} {rp}"
            );
        }
    }
}

#[test]
fn fresnel_total_internal_reflection_above_critical_angle() {
    let eta = 1.5f32;
    let critical = (1.0 / eta).asin();
    for k in 1..50 {
        let theta = critical + (std::f32::consts::FRAC_PI_2 - critical) * k as f32 / 50.0;
        // From inside (cos < 0): TIR.
        assert_eq!(fresnel_dielectric(-theta.cos(), eta), 1.0, "theta {theta}");
        // The same angle from outside never totally reflects.
        assert!(fresnel_dielectric(theta.cos(), eta) < 1.0);
    }
    // Just below the critical angle light still gets through.
    let below = critical - 1e-3;
    assert!(fresnel_dielectric(-below.cos(), eta) < 1.0);
    assert!(refract_local(-dir(critical + 1e-3, 0.3), eta).is_none());
}

#[test]
fn fresnel_brewster_angle_zeroes_parallel_reflectance() {
    for eta in [1.33f32, 1.5, 2.4, 1.0 / 1.5] {
        // tan(theta_B) = n_t / n_i.
        let theta_b = eta.atan();
        let (rs, rp) = fresnel_dielectric_polarized(theta_b.cos(), eta);
        assert!(rp < 1e-6, "eta {eta}: Rp = {rp}");
        assert!(rs > 1e-3, "eta {eta}: Rs = {rs}");
        // And R_p is not small away from it.
        let (_, rp_off) = fresnel_dielectric_polarized((theta_b + 0.2).cos(), eta);
        assert!(rp_off > 1e-3);
    }
}

#[test]
fn fresnel_reciprocity_and_energy_conservation() {
    for eta in [1.33f32, 1.5, 2.4] {
        for k in 1..=100 {
            let cos_i = k as f32 / 100.0;
            let r = fresnel_dielectric(cos_i, eta);
            // Stokes relations: reflectance is the same for the reversed path
            // (from inside at the refracted angle, relative index 1/eta).
            let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
            let cos_t = (1.0 - sin2_t).sqrt();
            // Going back from inside near the critical angle is ill-conditioned
            // (cos_i = sqrt(1 - eta^2 sin_t^2) cancels), so the f32 tolerance grows as
            // 1 / cos_i towards grazing incidence.
            let tol = 2e-6 / cos_i.max(0.01);
            let back = fresnel_dielectric(cos_t, 1.0 / eta);
            assert!(
                (back - r).abs() < tol,
                "eta {eta} cos {cos_i}: {r} vs {back}"
            );
            assert!((fresnel_dielectric(-cos_t, eta) - r).abs() < tol);
            // A negative cosine is the same as flipping eta.
            assert_eq!(
                fresnel_dielectric(-cos_i, eta),
                fresnel_dielectric(cos_i, 1.0 / eta)
            );
            // Energy: T from the *transmission* amplitude coefficients
            // t_s = 2 cos_i / (cos_i + eta cos_t), t_p = 2 cos_i / (eta cos_i + cos_t),
            // with the beam cross-section/impedance factor eta cos_t / cos_i,
            // must complement R.
            let (ci, ct, e) = (cos_i as f64, cos_t as f64, eta as f64);
            let ts = 2.0 * ci / (ci + e * ct);
            let tp = 2.0 * ci / (e * ci + ct);
            let t = e * ct / ci * 0.5 * (ts * ts + tp * tp);
            assert!((r as f64 + t - 1.0).abs() < 1e-5, "eta {eta} cos {cos_i}");
        }
    }
}

#[test]
fn refraction_obeys_snell_and_is_reciprocal() {
    let mut rng = Rng(4);
    for eta in [1.33f32, 1.5, 2.4, 0.7] {
        for _ in 0..2000 {
            let mut wo = sample_uniform_sphere(rng.vec2());
            if wo.z.abs() < 1e-3 {
                wo.z = 0.5;
                wo = wo.normalize();
            }
            let Some((wi, eta_rel)) = refract_local(wo, eta) else {
                // Only total internal reflection may refuse to refract.
                let n_ratio = if wo.z > 0.0 { eta } else { 1.0 / eta };
                let sin_o = (1.0 - wo.z * wo.z).sqrt();
                assert!(sin_o > n_ratio * (1.0 - 1e-5), "refused at sin {sin_o}");
                continue;
            };
            let (n_i, n_t) = if wo.z > 0.0 { (1.0, eta) } else { (eta, 1.0) };
            assert!((eta_rel - n_t / n_i).abs() < 1e-6);
            assert!((wi.length() - 1.0).abs() < 1e-5);
            assert!(wi.z * wo.z < 0.0, "must cross the interface");
            // Snell: n_i sin_i = n_t sin_t.
            let sin_i = wo.truncate().length();
            let sin_t = wi.truncate().length();
            assert!((n_i * sin_i - n_t * sin_t).abs() < 1e-5);
            // Plane of incidence: the tangential parts are antiparallel.
            assert!(wo.truncate().perp_dot(wi.truncate()).abs() < 1e-5);
            assert!(wo.truncate().dot(wi.truncate()) <= 1e-6);
            // Reciprocity: reversing the light path refracts back to wo, with 1/eta.
            let (back, eta_back) = refract_local(wi, eta).expect("reverse path exists");
            assert!((back - wo).length() < 1e-4, "{back} vs {wo}");
            assert!((eta_back * eta_rel - 1.0).abs() < 1e-5);
            // The sampler's transmitted lobe is exactly this direction.
            let s = dielectric_sample(eta, Rgb::WHITE, wo, Vec2::new(1.0 - 1e-7, 0.5))
                .expect("valid wo");
            assert!(s.lobe.is_transmit() && s.lobe.is_specular());
            assert_eq!(s.wi, wi);
            assert_eq!(s.eta, eta_rel);
        }
    }
}

#[test]
fn mirror_reflection_is_exact() {
    let mut rng = Rng(5);
    for _ in 0..1000 {
        let n = sample_uniform_sphere(rng.vec2());
        let frame = Frame::from_normal(n);
        let mut w = sample_uniform_sphere(rng.vec2());
        if w.dot(n) < 0.0 {
            w = -w;
        }
        let wo = frame.to_local(w);
        let Some(s) = mirror_sample(Rgb::new(0.9, 0.5, 0.1), wo) else {
            assert!(wo.z <= 0.0);
            continue;
        };
        // r = 2 (n.w) n - w in world space.
        let expected = 2.0 * n.dot(w) * n - w;
        assert!((frame.to_world(s.wi) - expected).length() < 1e-5);
        assert_eq!(s.wi, reflect_local(wo));
        assert_eq!(s.weight, Rgb::new(0.9, 0.5, 0.1));
        assert_eq!(s.lobe, SPECULAR_REFLECT);
        // The dielectric's reflected lobe is the same direction.
        let d = dielectric_sample(1.5, Rgb::WHITE, wo, Vec2::ZERO).expect("reflects");
        assert_eq!(d.wi, s.wi);
    }
    assert!(mirror_sample(Rgb::WHITE, Vec3::new(0.0, 0.6, -0.8)).is_none());
}

#[test]
fn dielectric_reflection_probability_and_mean_weight() {
    // Monte Carlo over u.x must reproduce P(reflect) = R and E[weight] =
    // R + T tint / eta_rel^2, at several angles and from both sides.
    let tint = Rgb::new(1.0, 0.8, 0.3);
    let n = 200_000;
    for eta in [1.5f32, 1.33] {
        for theta_deg in [0.0f32, 30.0, 60.0, 80.0, 89.0] {
            for side in [1.0f32, -1.0] {
                let mut wo = dir(theta_deg.to_radians(), 1.1);
                wo.z *= side;
                let mut rng = Rng(6 + theta_deg as u64);
                let mut reflected = 0usize;
                let mut sum = [0.0f64; 3];
                for _ in 0..n {
                    let s = dielectric_sample(eta, tint, wo, rng.vec2()).expect("valid");
                    reflected += s.lobe.contains(LobeSampled::REFLECT) as usize;
                    for (acc, w) in sum.iter_mut().zip(s.weight.to_array()) {
                        *acc += w as f64;
                    }
                }
                // Reference from the independent angle-form Fresnel, in f64.
                let eta_rel = if side > 0.0 {
                    eta as f64
                } else {
                    1.0 / eta as f64
                };
                let (rs, rp) = fresnel_angles(theta_deg.to_radians() as f64, eta_rel);
                let r = 0.5 * (rs + rp);
                let t = 1.0 - r;
                let p = reflected as f64 / n as f64;
                let sigma = (r * t / n as f64).sqrt().max(1e-9);
                assert!((p - r).abs() < 5.0 * sigma + 1e-5, "P(R) {p} vs {r}");
                for (c, acc) in tint.to_array().iter().zip(sum) {
                    let expect = r + t * *c as f64 / (eta_rel * eta_rel);
                    let mean = acc / n as f64;
                    // Two-valued weight: std = |1 - c/eta^2| sqrt(R T).
                    let spread = (1.0 - *c as f64 / (eta_rel * eta_rel)).abs();
                    assert!(
                        (mean - expect).abs() < 5.0 * spread * sigma + 1e-5,
                        "E[w] {mean} vs {expect}"
                    );
                }
            }
        }
    }
}

#[test]
fn diffuse_column_equals_per_point_sampling_bit_for_bit() {
    // diffuse_sample_world is a rearrangement of Frame + diffuse_sample + to_world; it
    // must produce the same bits, including at the concentric map's centre and wedge
    // diagonals, the square's edges, normals at +-z (and -0 z), grazing and below-surface
    // viewers, and for every length (full blocks of eight and a remainder), on every
    // backend this CPU runs.
    let mut rng = Rng(21);
    let edge_u = [0.0, 0.25, 0.5, 0.75, 1.0 - f32::EPSILON / 2.0];
    let special_n = [
        Vec3::Z,
        -Vec3::Z,
        Vec3::new(1.0, 0.0, -0.0),
        Vec3::Y,
        Vec3::new(0.6, 0.0, -0.8),
    ];
    for len in [0usize, 1, 2, 3, 4, 5, 7, 8, 9, 15, 64, 203] {
        let mut n = Vec::new();
        let mut vn = Vec::new();
        let mut u = Vec::new();
        for i in 0..len {
            let ni = if i % 3 == 0 {
                special_n[i % special_n.len()]
            } else {
                sample_uniform_sphere(rng.vec2())
            };
            let ui = if i % 4 == 1 {
                Vec2::new(edge_u[i % 5], edge_u[(i / 5) % 5])
            } else {
                rng.vec2()
            };
            let vi = match i % 5 {
                0 => -ni,
                1 => Frame::from_normal(ni).to_world(Vec3::X),
                _ => sample_uniform_sphere(rng.vec2()),
            };
            n.push(ni);
            vn.push(vi);
            u.push(ui);
        }
        let (mut want_wi, mut want_pdf) = (vec![Vec3::splat(7.0); len], vec![7.0; len]);
        diffuse_sample_world_scalar(&n, &vn, &u, &mut want_wi, &mut want_pdf);
        for backend in Backend::all() {
            let mut wi = vec![Vec3::splat(7.0); len];
            let mut pdf = vec![7.0; len];
            diffuse_sample_world_on(backend, &n, &vn, &u, &mut wi, &mut pdf);
            for i in 0..len {
                assert_eq!(
                    (wi[i].to_array().map(f32::to_bits), pdf[i].to_bits()),
                    (
                        want_wi[i].to_array().map(f32::to_bits),
                        want_pdf[i].to_bits()
                    ),
                    "{backend:?}, len {len}, point {i}: n {:?} vn {:?} u {:?}",
                    n[i],
                    vn[i],
                    u[i]
                );
            }
        }
    }
}

#[test]
fn diffuse_weight_is_albedo_and_eval_matches_sample() {
    let albedo = Rgb::new(0.8, 0.5, 0.2);
    let mut rng = Rng(7);
    let wo = dir(0.7, 2.0);
    let n = 100_000;
    let mut sum = [0.0f64; 3];
    for _ in 0..n {
        let s = diffuse_sample(albedo, wo, rng.vec2()).expect("wo is above");
        let (f_cos, pdf) = diffuse_eval(albedo, wo, s.wi);
        assert!((pdf - s.pdf).abs() <= 1e-6 * pdf);
        // weight = f |cos| / pdf, consistently with eval.
        let w = f_cos / pdf;
        assert!((w.r - s.weight.r).abs() < 1e-5 && (w.b - s.weight.b).abs() < 1e-5);
        for (acc, w) in sum.iter_mut().zip(s.weight.to_array()) {
            *acc += w as f64;
        }
    }
    for (acc, a) in sum.iter().zip(albedo.to_array()) {
        assert!((acc / n as f64 - a as f64).abs() < 1e-6);
    }
    // Independently: the albedo is the hemispherical integral of eval's f |cos|,
    // estimated with uniform sphere sampling (density 1/(4 pi)).
    let mut est = 0.0f64;
    for _ in 0..n {
        let wi = sample_uniform_sphere(rng.vec2());
        est += diffuse_eval(albedo, wo, wi).0.g as f64 / INV_4PI as f64;
    }
    let est = est / n as f64;
    // The estimator is X = 4 a cos on the upper hemisphere, 0 below:
    // E[X^2] = 8 a^2 / 3, so Var X = 5 a^2 / 3.
    let a = albedo.g as f64;
    assert!(
        (est - a).abs() < 5.0 * a * (5.0 / 3.0 / n as f64).sqrt(),
        "{est}"
    );
    // One-sided: nothing from below.
    assert!(diffuse_sample(albedo, Vec3::new(0.0, 0.6, -0.8), Vec2::splat(0.3)).is_none());
    assert_eq!(diffuse_eval(albedo, wo, -Vec3::Z), (Rgb::BLACK, 0.0));
}

#[test]
fn no_nan_at_grazing_angles_extreme_g_and_u_edges() {
    let one_minus = 1.0 - f32::EPSILON / 2.0;
    let us = [0.0f32, 1e-7, 0.5, one_minus];
    let mut uvs = Vec::new();
    for &a in &us {
        for &b in &us {
            uvs.push(Vec2::new(a, b));
        }
    }
    let mut wos = Vec::new();
    for z in [1e-7f32, 0.0, -0.0, -1e-7, 1.0, -1.0] {
        let r = (1.0 - z * z).sqrt();
        wos.push(Vec3::new(r, 0.0, z));
        wos.push(Vec3::new(0.6 * r, -0.8 * r, z));
    }
    let finite = |s: &BxdfSample| {
        s.wi.is_finite() && s.weight.is_finite() && s.pdf.is_finite() && s.eta.is_finite()
    };
    for &wo in &wos {
        for &u in &uvs {
            if let Some(s) = diffuse_sample(Rgb::WHITE, wo, u) {
                assert!(finite(&s) && s.pdf > 0.0 && s.wi.z > 0.0, "{wo} {u} {s:?}");
                let (f, p) = diffuse_eval(Rgb::WHITE, wo, s.wi);
                assert!(f.is_finite() && p.is_finite());
            }
            for eta in [1.5f32, 1.0 / 1.5, 1.0, 1.0001] {
                if let Some(s) = dielectric_sample(eta, Rgb::WHITE, wo, u) {
                    assert!(finite(&s) && s.pdf > 0.0, "eta {eta} wo {wo} u {u}: {s:?}");
                    assert!((s.wi.length() - 1.0).abs() < 1e-4);
                } else {
                    assert_eq!(wo.z, 0.0);
                }
            }
            if let Some(s) = mirror_sample(Rgb::WHITE, wo) {
                assert!(finite(&s));
            }
            for g in [-0.9999f32, -0.999, 0.0, 0.999, 0.9999, 1.0, -1.0, 2.0] {
                let (wi, pdf) = hg_sample(g, wo, u);
                assert!(wi.is_finite() && pdf.is_finite() && pdf > 0.0, "g {g}");
                assert!(
                    (wi.length() - 1.0).abs() < 1e-4,
                    "g {g} |wi| {}",
                    wi.length()
                );
                let e = hg_eval(g, wo, wi);
                assert!(e.is_finite() && e > 0.0);
                let e = hg_eval(g, wo, wo);
                assert!(e.is_finite() && e > 0.0);
                let e = hg_eval(g, wo, -wo);
                assert!(e.is_finite() && e > 0.0);
            }
        }
        for c in [wo.z, 1.0, -1.0, 0.0, -0.0, 1.0000001, -1.0000001] {
            for eta in [1.5f32, 1.0 / 1.5, 1.0] {
                let r = fresnel_dielectric(c, eta);
                assert!((0.0..=1.0).contains(&r), "c {c} eta {eta}: {r}");
            }
        }
    }
    // Samplers at the square's edges stay on their domain.
    for &u in &uvs {
        assert!(sample_uniform_sphere(u).is_finite());
        assert!((sample_uniform_sphere(u).length() - 1.0).abs() < 1e-5);
        assert!(sample_cosine_hemisphere(u).z >= 0.0);
        let c = sample_uniform_cone(u, 0.9999);
        assert!(c.is_finite() && c.z >= 0.9999 - 1e-6);
    }
}
