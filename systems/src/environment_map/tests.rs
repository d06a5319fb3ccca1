//! Tests of the environment map: convention, sampling against its pdf, filters, rotation.

use super::*;
use crate::distribution::tests::{chi_square, chi_square_limit};
use crate::sampler::SplitMix64 as Rng;

#[test]
fn direction_convention() {
    // Documented anchors of the scene-format convention.
    let uv = dir_to_uv(Vec3::NEG_Z);
    assert!((uv - Vec2::new(0.5, 0.5)).length() < 1e-6);
    let uv = dir_to_uv(Vec3::X);
    assert!((uv - Vec2::new(0.75, 0.5)).length() < 1e-6);
    let uv = dir_to_uv(Vec3::NEG_X);
    assert!((uv - Vec2::new(0.25, 0.5)).length() < 1e-6);
    assert_eq!(dir_to_uv(Vec3::Z).x, 0.0);
    assert_eq!(dir_to_uv(Vec3::Y).y, 0.0);
    assert_eq!(dir_to_uv(Vec3::NEG_Y).y, 1.0);
    let mut rng = Rng(8);
    for _ in 0..1000 {
        let uv = rng.vec2();
        let d = uv_to_dir(uv);
        assert!((d.length() - 1.0).abs() < 1e-5);
        let back = dir_to_uv(d);
        assert!((back.y - uv.y).abs() < 1e-3, "{uv} {back}");
        let du = (back.x - uv.x).abs();
        assert!(du < 1e-4 || (1.0 - du) < 1e-4 || uv.y < 1e-3 || uv.y > 0.999);
    }
    // eval picks the texel the convention names: 4x2 map, texel (3, 0) is u in
    // [0.75, 1) (between +x and +z), upper hemisphere.
    let mut px = vec![Rgb::BLACK; 8];
    px[3] = Rgb::new(1.0, 2.0, 3.0);
    px[4] = Rgb::new(4.0, 0.0, 0.0); // (0, 1): u in [0, 0.25), lower half: +z, down
    let map = EnvironmentMap::new(px, 4, 2);
    assert_eq!(
        map.eval(Vec3::new(1.0, 0.3, 0.1).normalize()),
        Rgb::new(1.0, 2.0, 3.0)
    );
    assert_eq!(
        map.eval(Vec3::new(-0.1, -0.3, 1.0).normalize()),
        Rgb::new(4.0, 0.0, 0.0)
    );
    assert_eq!(map.eval(Vec3::new(0.0, 0.3, -1.0).normalize()), Rgb::BLACK);
}

fn test_map(w: usize, h: usize) -> Vec<Rgb> {
    let mut rng = Rng(42);
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let sky = if y < h / 2 { 1.0 } else { 0.2 };
            let mut p = Rgb::new(sky * 0.6, sky * 0.8, sky) * (0.5 + rng.f32());
            if (x, y) == (5, 3) {
                p = Rgb::new(200.0, 150.0, 80.0); // a sun
            }
            if i % 11 == 0 {
                p = Rgb::BLACK;
            }
            p
        })
        .collect()
}

/// `∫ L dω` by direct quadrature: a fine (θ, φ) midpoint grid aligned with the texels,
/// 8x8 cells per texel, each weighted by its exact solid angle.
fn quadrature(map: &EnvironmentMap, f: impl Fn(Vec3) -> [f64; 3]) -> [f64; 3] {
    let (nu, nv) = (map.width() * 8, map.height() * 8);
    let mut s = [0.0f64; 3];
    for j in 0..nv {
        let t0 = std::f64::consts::PI * j as f64 / nv as f64;
        let t1 = std::f64::consts::PI * (j + 1) as f64 / nv as f64;
        let omega = 2.0 * std::f64::consts::PI / nu as f64 * (t0.cos() - t1.cos());
        for i in 0..nu {
            let uv = Vec2::new((i as f32 + 0.5) / nu as f32, (j as f32 + 0.5) / nv as f32);
            let v = f(uv_to_dir(uv));
            for c in 0..3 {
                s[c] += v[c] * omega;
            }
        }
    }
    s
}

/// A rotation that moves every axis (so a wrong or missing inverse shows).
fn tilt() -> Mat3 {
    Mat3::from_axis_angle(Vec3::new(0.3, 1.0, -0.5).normalize(), 1.1)
}

/// The maps the sampling tests run on: nearest (the original), bilinear, bilinear rotated.
fn maps(w: usize, h: usize) -> [(&'static str, EnvironmentMap); 3] {
    let px = test_map(w, h);
    [
        ("nearest", EnvironmentMap::new(px.clone(), w, h)),
        (
            "bilinear",
            EnvironmentMap::with_filter(px.clone(), w, h, EnvFilter::Bilinear, Mat3::IDENTITY),
        ),
        (
            "bilinear rotated",
            EnvironmentMap::with_filter(px, w, h, EnvFilter::Bilinear, tilt()),
        ),
    ]
}

/// `∫ f dω` by a midpoint rule on `sub` x `sub` cells per density cell of `map` (in its
/// frame, so no quadrature cell straddles a step of the pdf), each weighted by its exact
/// solid angle; `f` gets the map-frame direction.
fn cell_quadrature(map: &EnvironmentMap, sub: usize, f: impl Fn(Vec3) -> f64) -> f64 {
    let (cw, ch, offset) = cells(map);
    let (nu, nv) = (cw * sub, ch * sub);
    let mut s = 0.0f64;
    for j in 0..nv {
        let t0 = std::f64::consts::PI * j as f64 / nv as f64;
        let t1 = std::f64::consts::PI * (j + 1) as f64 / nv as f64;
        let omega = 2.0 * std::f64::consts::PI / nu as f64 * (t0.cos() - t1.cos());
        for i in 0..nu {
            let u = (i as f32 + 0.5) / nu as f32 + offset;
            let uv = Vec2::new(u, (j as f32 + 0.5) / nv as f32);
            s += f(uv_to_dir(uv)) * omega;
        }
    }
    s
}

/// The solid-angle pdf integrates to 1 over the sphere, for the rotated map through world
/// directions `R d` (a rotation preserves solid angle).
#[test]
fn env_pdf_integrates_to_one_over_the_sphere() {
    for (name, map) in maps(32, 16) {
        let r = if name.contains("rotated") {
            tilt()
        } else {
            Mat3::IDENTITY
        };
        let s = cell_quadrature(&map, 8, |d| f64::from(map.pdf(r * d)));
        assert!((s - 1.0).abs() < 1e-4, "{name}: ∫ pdf dω = {s}");
    }
}

#[test]
fn env_importance_sampling_matches_quadrature() {
    let (w, h) = (32, 16);
    for (name, map) in maps(w, h) {
        let exact = quadrature(&map, |d| map.eval(d).to_array().map(f64::from));
        // Exact for nearest; for bilinear the cells' mean radiance times solid angle.
        let closed_tol = if map.filter() == EnvFilter::Nearest {
            1e-4
        } else {
            1e-2
        };
        let closed = map.integral();
        for (cl, ex) in closed.to_array().into_iter().zip(exact) {
            let rel = (f64::from(cl) - ex).abs() / ex;
            assert!(rel < closed_tol, "{name}: closed form vs quadrature: {rel}");
        }
        let mut rng = Rng(2024);
        let n = 200_000;
        let (mut sum, mut sum2) = ([0.0f64; 3], [0.0f64; 3]);
        for _ in 0..n {
            let (dir, l, pdf) = map.sample(rng.vec2());
            assert!((dir.length() - 1.0).abs() < 1e-5);
            assert_eq!(l, map.eval(dir));
            assert_eq!(pdf, map.pdf(dir));
            if pdf == 0.0 {
                continue;
            }
            for (c, lc) in l.to_array().into_iter().enumerate() {
                let x = f64::from(lc) / f64::from(pdf);
                sum[c] += x;
                sum2[c] += x * x;
            }
        }
        for c in 0..3 {
            let mean = sum[c] / n as f64;
            let sigma = ((sum2[c] / n as f64 - mean * mean) / n as f64).sqrt();
            let err = (mean - exact[c]).abs();
            assert!(
                err < 5.0 * sigma + 1e-6 && err < 5e-3 * exact[c],
                "{name} channel {c}: MC {mean} vs quadrature {} (sigma {sigma})",
                exact[c]
            );
        }
    }
}

/// The cells the sampling density is constant on, in the map's frame: texels for nearest,
/// the bilinear lattice's cells (from column centre to column centre, from row centre to
/// row centre) for bilinear. `(columns, rows, u offset)`.
fn cells(map: &EnvironmentMap) -> (usize, usize, f32) {
    match map.filter() {
        EnvFilter::Nearest => (map.width(), map.height(), 0.0),
        EnvFilter::Bilinear => (map.width(), map.height() - 1, 0.5 / map.width() as f32),
    }
}

/// Chi-square of sampled directions against the pdf, over the density's cells split in
/// 2x2 sub-cells (in the map's frame, reached through the test's own inverse of the
/// rotation). A cell's probability is exactly `p(u, v) / (columns rows)` with
/// `p(u, v) = pdf(ω) 2π² sin θ` at its centre (the density is constant over a cell in
/// `(u, v)`), and each sub-cell takes a quarter. A sampler whose density is not its
/// `pdf` (cells shifted by half a texel, a rotation applied one way and inverted the
/// same way, a non-uniform position within the cell) fails.
#[test]
fn env_sampling_chi_square_against_pdf() {
    for (name, map) in maps(24, 12) {
        let to_world = if name.contains("rotated") {
            tilt()
        } else {
            Mat3::IDENTITY
        };
        let to_local = to_world.transpose();
        let (cw, ch, offset) = cells(&map);
        let mut probs = vec![0.0f64; 4 * cw * ch];
        for j in 0..ch {
            for i in 0..cw {
                let uv = Vec2::new(
                    (i as f32 + 0.5) / cw as f32 + offset,
                    (j as f32 + 0.5) / ch as f32,
                );
                let local = uv_to_dir(uv);
                let sin_theta = f64::from((1.0 - local.y * local.y).sqrt());
                let p_uv = f64::from(map.pdf(to_world * local))
                    * 2.0
                    * std::f64::consts::PI.powi(2)
                    * sin_theta;
                let cell = p_uv / (cw * ch) as f64;
                for q in 0..4 {
                    probs[4 * (j * cw + i) + q] = cell / 4.0;
                }
            }
        }
        let total: f64 = probs.iter().sum();
        assert!(
            (total - 1.0).abs() < 1e-4,
            "{name}: Σ probabilities {total}"
        );
        let mut counts = vec![0u64; probs.len()];
        let mut rng = Rng(31);
        let n = 300_000u64;
        for _ in 0..n {
            let (d, _, _) = map.sample(rng.vec2());
            let uv = dir_to_uv((to_local * d).normalize());
            let x = (uv.x - offset).rem_euclid(1.0) * cw as f32;
            let y = uv.y * ch as f32;
            let (i, j) = ((x as usize).min(cw - 1), (y as usize).min(ch - 1));
            let q = usize::from(x - i as f32 >= 0.5) + 2 * usize::from(y - j as f32 >= 0.5);
            counts[4 * (j * cw + i) + q] += 1;
        }
        let (stat, df) = chi_square(&counts, &probs, n);
        assert!(
            stat < chi_square_limit(df),
            "{name}: chi2 {stat} with {df} dof"
        );
    }
}

/// A map (the test map, its own non-symmetric layout) with the filter and rotation.
fn bilinear(px: &[Rgb], w: usize, h: usize, to_world: Mat3) -> EnvironmentMap {
    EnvironmentMap::with_filter(px.to_vec(), w, h, EnvFilter::Bilinear, to_world)
}

#[test]
fn bilinear_hits_texel_centres_and_is_continuous_across_borders_and_the_seam() {
    let (w, h) = (8, 5);
    let px = test_map(w, h);
    let map = bilinear(&px, w, h, Mat3::IDENTITY);
    // At the lattice points (Mitsuba's: u = (i + 1/2) / w, v = j / (h - 1)) the texels.
    for j in 0..h {
        for i in 0..w {
            let uv = Vec2::new((i as f32 + 0.5) / w as f32, j as f32 / (h - 1) as f32);
            let got = map.bilinear_uv(uv);
            let want = px[j * w + i];
            assert!(
                (got - want).max_channel().abs() < 1e-5,
                "({i}, {j}): {got:?} vs {want:?}"
            );
        }
    }
    // Either side of every nearest-texel border and of the seam: the values meet, where
    // nearest lookup jumps (the test map's neighbours differ).
    let eps = 1e-6f32;
    let jump = |a: Rgb, b: Rgb| {
        (a - b)
            .to_array()
            .iter()
            .fold(0.0f32, |m, c| m.max(c.abs()))
    };
    let mut nearest_jumps = 0;
    for j in 0..20 {
        let v = (j as f32 + 0.5) / 20.0;
        for i in 0..=w {
            let u = i as f32 / w as f32;
            let (lo, hi) = if i == 0 || i == w {
                (Vec2::new(1.0 - eps, v), Vec2::new(eps, v))
            } else {
                (Vec2::new(u - eps, v), Vec2::new(u + eps, v))
            };
            assert!(
                jump(map.bilinear_uv(lo), map.bilinear_uv(hi)) < 1e-2,
                "u = {u}, v = {v}"
            );
            nearest_jumps += usize::from(jump(map.lookup_uv(lo), map.lookup_uv(hi)) > 1e-2);
        }
        for i in 1..h {
            let v = i as f32 / h as f32;
            let u = (j as f32 + 0.5) / 20.0;
            let (lo, hi) = (Vec2::new(u, v - eps), Vec2::new(u, v + eps));
            assert!(
                jump(map.bilinear_uv(lo), map.bilinear_uv(hi)) < 1e-2,
                "u = {u}, v = {v}"
            );
        }
    }
    assert!(
        nearest_jumps > 20,
        "the borders tested are real jumps for nearest lookup"
    );
    // Across the seam in direction space too: just either side of +z (u = 0).
    let a = map.eval(Vec3::new(-1e-4, 0.2, 1.0).normalize());
    let b = map.eval(Vec3::new(1e-4, 0.2, 1.0).normalize());
    assert!(jump(a, b) < 1e-2, "{a:?} vs {b:?}");
}

#[test]
fn rotated_map_in_the_rotated_direction_equals_the_map_in_the_direction() {
    let (w, h) = (24, 12);
    let px = test_map(w, h);
    let r = tilt();
    let plain = bilinear(&px, w, h, Mat3::IDENTITY);
    let rotated = bilinear(&px, w, h, r);
    let mut rng = Rng(12);
    for k in 0..2000 {
        // Cell centres (far from pdf steps) and random points.
        let uv = if k % 2 == 0 {
            let (i, j) = (k % w, (k / w) % (h - 1));
            Vec2::new(
                (i as f32 + 1.0) / w as f32,
                (j as f32 + 0.5) / (h - 1) as f32,
            )
        } else {
            rng.vec2()
        };
        let d = uv_to_dir(uv);
        let (a, b) = (rotated.eval(r * d), plain.eval(d));
        assert!(
            (a - b).max_channel().abs() < 2e-3 * (1.0 + b.max_channel()),
            "{a:?} vs {b:?}"
        );
        if k % 2 == 0 {
            let (p, q) = (rotated.pdf(r * d), plain.pdf(d));
            assert!((p - q).abs() <= 1e-3 * q, "pdf {p} vs {q}");
        }
    }
    // And the rotation is not the identity: somewhere the two maps differ a lot.
    let differ = (0..1000)
        .map(|_| {
            let d = uv_to_dir(rng.vec2());
            (rotated.eval(d) - plain.eval(d)).max_channel().abs()
        })
        .fold(0.0f32, f32::max);
    assert!(differ > 1.0, "{differ}");
}

#[test]
fn bilinear_density_is_positive_wherever_radiance_is() {
    // One lit texel among black ones: the interpolated radiance reaches half way to the
    // neighbouring centres, and sampling must reach all of it (or the MC mean falls short).
    let (w, h) = (16, 9);
    let mut px = vec![Rgb::BLACK; w * h];
    px[4 * w + 7] = Rgb::new(3.0, 2.0, 1.0);
    let map = bilinear(&px, w, h, tilt());
    let mut rng = Rng(5);
    for _ in 0..100_000 {
        let d = uv_to_dir(rng.vec2());
        if !map.eval(d).is_black() {
            assert!(map.pdf(d) > 0.0, "radiance without density at {d}");
        }
    }
}

#[test]
fn one_bright_texel_takes_almost_all_samples() {
    let (w, h) = (64, 32);
    let mut px = vec![Rgb::splat(1e-3); w * h];
    let bright = Rgb::new(1e4, 5e3, 2e3);
    px[20 * w + 10] = bright;
    let map = EnvironmentMap::new(px, w, h);
    let mut rng = Rng(77);
    let n = 100_000;
    let hits = (0..n)
        .filter(|_| map.sample(rng.vec2()).1 == bright)
        .count();
    // Expected share: 5667 sin θ_20 / (5667 sin θ_20 + 1e-3 Σ sin θ) ≈ 0.9998.
    assert!(hits as f64 > 0.999 * n as f64, "{hits} of {n}");
}

#[test]
fn zero_and_garbage_maps_do_not_nan() {
    let mut rng = Rng(4);
    let garbage = vec![
        Rgb::new(f32::NAN, -1.0, 0.0),
        Rgb::new(f32::INFINITY, 0.0, 0.0),
        Rgb::BLACK,
        Rgb::new(-5.0, -5.0, -5.0),
    ];
    for (px, w, h) in [(vec![Rgb::BLACK; 32], 8, 4), (garbage, 2, 2)] {
        let map = EnvironmentMap::new(px, w, h);
        for _ in 0..10_000 {
            let (dir, _, pdf) = map.sample(rng.vec2());
            assert!(dir.is_finite() && pdf.is_finite() && pdf >= 0.0);
            let q = map.pdf(uv_to_dir(rng.vec2()));
            assert!(q.is_finite() && q >= 0.0);
        }
        // Poles: sin θ = 0 gives pdf 0, not infinity.
        assert_eq!(map.pdf(Vec3::Y), 0.0);
        assert_eq!(map.pdf(Vec3::NEG_Y), 0.0);
    }
    // The all-black map samples uniformly in (u, v): pdf = 1 / (2π² sin θ).
    let map = EnvironmentMap::new(vec![Rgb::BLACK; 32], 8, 4);
    let d = Vec3::new(1.0, 0.0, 0.0);
    assert!((map.pdf(d) - 1.0 / (2.0 * PI * PI)).abs() < 1e-6);
}

/// Equal-area maps: the test map laid out as pbrt's octahedral square, unrotated and tilted.
fn equal_area_maps(n: usize) -> [(&'static str, Mat3, EnvironmentMap); 2] {
    let px = test_map(n, n);
    let map = |r: Mat3| {
        EnvironmentMap::with_projection(
            px.clone(),
            n,
            n,
            EnvProjection::EqualArea,
            EnvFilter::Nearest,
            r,
        )
    };
    [
        ("equal-area", Mat3::IDENTITY, map(Mat3::IDENTITY)),
        ("equal-area rotated", tilt(), map(tilt())),
    ]
}

/// `∫ f dω` over the sphere by the midpoint rule on `sub` x `sub` cells per texel of an
/// `n` x `n` equal-area square, every cell of solid angle `4π / cells` exactly (the mapping
/// preserves area; no cell straddles a texel); `f` gets the map-frame direction.
fn equal_area_quadrature(n: usize, sub: usize, f: impl Fn(Vec3) -> [f64; 3]) -> [f64; 3] {
    let m = n * sub;
    let omega = 4.0 * std::f64::consts::PI / (m * m) as f64;
    let mut s = [0.0f64; 3];
    for j in 0..m {
        for i in 0..m {
            let p = Vec2::new((i as f32 + 0.5) / m as f32, (j as f32 + 0.5) / m as f32);
            let v = f(equal_area::square_to_sphere(p));
            for c in 0..3 {
                s[c] += v[c] * omega;
            }
        }
    }
    s
}

/// pbrt's layout: texel `(i, j)` (row `j` from the top) is the direction of its centre on
/// the octahedral square, through the rotation; the pdf integrates to 1; the closed-form
/// integral is the quadrature's; importance sampling returns what `eval` and `pdf` say and
/// estimates the integral.
#[test]
fn equal_area_maps_read_pbrts_layout_and_integrate() {
    let n = 16;
    let px = test_map(n, n);
    for (name, r, map) in equal_area_maps(n) {
        assert_eq!(map.projection(), EnvProjection::EqualArea);
        for (i, j) in [(5, 3), (0, 0), (8, 8), (15, 2), (3, 12)] {
            let centre = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            let dir = r * equal_area::square_to_sphere(centre);
            assert_eq!(map.eval(dir), px[j * n + i], "{name}: texel ({i}, {j})");
        }
        let pdf = equal_area_quadrature(n, 4, |d| [f64::from(map.pdf(r * d)); 3])[0];
        assert!((pdf - 1.0).abs() < 1e-4, "{name}: ∫ pdf dω = {pdf}");
        let exact = equal_area_quadrature(n, 4, |d| map.eval(r * d).to_array().map(f64::from));
        for (cl, ex) in map.integral().to_array().into_iter().zip(exact) {
            assert!(
                (f64::from(cl) - ex).abs() < 1e-4 * ex,
                "{name}: {cl} vs {ex}"
            );
        }
        let mut rng = Rng(77);
        let count = 200_000;
        let mut sum = [0.0f64; 3];
        for _ in 0..count {
            let (dir, l, pdf) = map.sample(rng.vec2());
            assert!((dir.length() - 1.0).abs() < 1e-5);
            assert_eq!((l, pdf), (map.eval(dir), map.pdf(dir)), "{name}");
            assert!(pdf > 0.0, "{name}: a sampled direction of density 0");
            for (c, lc) in l.to_array().into_iter().enumerate() {
                sum[c] += f64::from(lc) / f64::from(pdf);
            }
        }
        for c in 0..3 {
            let mean = sum[c] / count as f64;
            // Sampling in proportion to the texel average: the estimate is exact up to
            // the channels' ratios, which vary little in the test map.
            assert!(
                (mean - exact[c]).abs() < 5e-3 * exact[c],
                "{name} channel {c}: {mean} vs {}",
                exact[c]
            );
        }
    }
}

/// Chi-square of sampled directions, mapped back to the square through the test's own
/// inverse rotation, against the pdf over each texel's 2x2 sub-squares: a texel's
/// probability is `pdf(ω) 4π / (w h)` (every texel covers the same solid angle). A sampler
/// whose density differs from its `pdf` (a `sin θ` weight left in, a mapping that is not
/// area-preserving, the rotation applied the wrong way) fails.
#[test]
fn equal_area_sampling_chi_square_against_pdf() {
    let n = 12;
    for (name, r, map) in equal_area_maps(n) {
        let mut probs = vec![0.0f64; 4 * n * n];
        for j in 0..n {
            for i in 0..n {
                let centre = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let pdf = f64::from(map.pdf(r * equal_area::square_to_sphere(centre)));
                let texel = pdf * 4.0 * std::f64::consts::PI / (n * n) as f64;
                for q in 0..4 {
                    probs[4 * (j * n + i) + q] = texel / 4.0;
                }
            }
        }
        let total: f64 = probs.iter().sum();
        assert!(
            (total - 1.0).abs() < 1e-4,
            "{name}: Σ probabilities {total}"
        );
        let mut counts = vec![0u64; probs.len()];
        let mut rng = Rng(5);
        let samples = 300_000u64;
        for _ in 0..samples {
            let (d, _, _) = map.sample(rng.vec2());
            let p = equal_area::sphere_to_square((r.transpose() * d).normalize()) * n as f32;
            let (i, j) = ((p.x as usize).min(n - 1), (p.y as usize).min(n - 1));
            let q = usize::from(p.x - i as f32 >= 0.5) + 2 * usize::from(p.y - j as f32 >= 0.5);
            counts[4 * (j * n + i) + q] += 1;
        }
        let (stat, df) = chi_square(&counts, &probs, samples);
        assert!(
            stat < chi_square_limit(df),
            "{name}: chi2 {stat} with {df} dof"
        );
    }
}
