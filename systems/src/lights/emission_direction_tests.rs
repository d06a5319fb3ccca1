//! Chi-square tests of `emission.rs`'s sampled directions against `emission_pdf`: area
//! lights (cosine about the normal), spot lights (uniform in the cutoff cone) and an
//! environment map (its importance sampling, light travelling away from the map).

use super::tests::{close, geometry, random_sample, sky_map, spot, BOUNDS};
use super::*;
use crate::distribution::tests::{chi_square, chi_square_limit};
use crate::environment_map::{dir_to_uv, uv_to_dir};
use crate::sampler::SplitMix64 as Rng;
use std::f64::consts::PI as PI64;

/// Chi-square of directions in `(cos theta, phi)` about `axis`, `cos theta` in `[z_lo, 1]`
/// cut in `NT` equal bins (equal solid angle), against `pdf` integrated over each bin by a
/// sub-grid. Directions outside the band fall in a bin of probability 0.
fn chi_square_about_axis(dirs: &[Vec3], axis: Vec3, z_lo: f32, pdf: impl Fn(Vec3) -> f32) {
    const NT: usize = 12;
    const NP: usize = 16;
    const SUB: usize = 8;
    let frame = Frame::from_normal(axis);
    let dz = (1.0 - z_lo as f64) / NT as f64;
    let dphi = 2.0 * PI64 / NP as f64;
    let mut probs = vec![0.0f64; NT * NP + 1];
    for i in 0..NT {
        for j in 0..NP {
            let mut p = 0.0;
            for a in 0..SUB {
                for b in 0..SUB {
                    let z = z_lo as f64 + (i as f64 + (a as f64 + 0.5) / SUB as f64) * dz;
                    let phi = (j as f64 + (b as f64 + 0.5) / SUB as f64) * dphi;
                    let s = (1.0 - z * z).max(0.0).sqrt();
                    let local = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32);
                    p += pdf(frame.to_world(local)) as f64;
                }
            }
            probs[i * NP + j] = p * dz * dphi / (SUB * SUB) as f64;
        }
    }
    let total: f64 = probs.iter().sum();
    assert!((total - 1.0).abs() < 2e-3, "the pdf integrates to {total}");
    let mut counts = vec![0u64; probs.len()];
    for d in dirs {
        let l = frame.to_local(*d);
        let bin = if l.z < z_lo {
            NT * NP
        } else {
            let i = (((l.z - z_lo) as f64 / dz) as usize).min(NT - 1);
            let phi = (l.y as f64).atan2(l.x as f64).rem_euclid(2.0 * PI64);
            i * NP + ((phi / dphi) as usize).min(NP - 1)
        };
        counts[bin] += 1;
    }
    let (stat, df) = chi_square(&counts, &probs, dirs.len() as u64);
    assert!(stat < chi_square_limit(df), "chi2 {stat} with {df} dof");
}

fn sampled_directions(
    set: &LightSet,
    g: &SceneGeometry,
    n: usize,
    seed: u64,
) -> Vec<EmissionSample> {
    let mut rng = Rng(seed);
    (0..n)
        .filter_map(|_| random_sample(set, g, &mut rng))
        .collect()
}

#[test]
fn area_light_directions_are_cosine_distributed_chi_square() {
    let g = geometry();
    let set = LightSet::new(
        vec![Light::Area {
            prim: 0,
            radiance: Rgb::WHITE,
        }],
        &g,
        1.0,
    );
    let samples = sampled_directions(&set, &g, 200_000, 21);
    let n = samples[0].n;
    let dirs: Vec<Vec3> = samples.iter().map(|s| s.direction).collect();
    // The whole sphere (z_lo = -1): nothing may go behind the emitter.
    chi_square_about_axis(&dirs, n, -1.0, |d| {
        set.emission_pdf(0, Vec3::ZERO, n, d, BOUNDS).1
    });
    // The pdf itself is cos / pi (an independent value, not the code's).
    let d = Frame::from_normal(n).to_world(Vec3::new(0.6, 0.0, 0.8));
    let pdf = set.emission_pdf(0, Vec3::ZERO, n, d, BOUNDS).1;
    assert!(close(pdf, 0.8 / std::f32::consts::PI, 1e-5), "{pdf}");
}

#[test]
fn spot_light_directions_are_uniform_in_the_cutoff_cone_chi_square() {
    let g = geometry();
    let set = LightSet::new(vec![spot(35.0, 10.0, None)], &g, 1.0);
    let Light::Spot {
        direction: axis, ..
    } = set.lights()[0]
    else {
        unreachable!()
    };
    let dirs: Vec<Vec3> = sampled_directions(&set, &g, 200_000, 22)
        .iter()
        .map(|s| s.direction)
        .collect();
    let z_lo = 35f32.to_radians().cos();
    chi_square_about_axis(&dirs, axis, z_lo, |d| {
        set.emission_pdf(0, Vec3::ZERO, Vec3::ZERO, d, BOUNDS).1
    });
    let want = 1.0 / (2.0 * PI64 * (1.0 - z_lo as f64));
    assert!(close(
        set.emission_pdf(0, Vec3::ZERO, Vec3::ZERO, axis, BOUNDS).1,
        want as f32,
        1e-4
    ));
}

/// Directions of a non-uniform environment map, binned by the map texel (four quadrants
/// each) of the direction they come *from* (`-direction`), against `emission_pdf` at the
/// texel centre times its `(u, v)` Jacobian `2 pi^2 sin theta` (the Nearest map's density
/// is constant in `(u, v)` per texel). A sampler that forgot the light travels away from
/// the map, or a pdf read at the wrong direction, fails.
#[test]
fn environment_directions_follow_the_maps_pdf_chi_square() {
    let g = geometry();
    let map = sky_map();
    let (w, h) = (map.width(), map.height());
    let light = Light::Environment {
        radiance: Rgb::WHITE,
        map: Some(Box::new(map)),
    };
    let set = LightSet::new(vec![light], &g, 1.0);
    let mut probs = vec![0.0f64; 4 * w * h];
    for j in 0..h {
        for i in 0..w {
            let uv = Vec2::new((i as f32 + 0.5) / w as f32, (j as f32 + 0.5) / h as f32);
            let towards = uv_to_dir(uv);
            let sin_theta = (1.0 - towards.y as f64 * towards.y as f64).sqrt();
            let pdf = set
                .emission_pdf(0, Vec3::ZERO, Vec3::ZERO, -towards, BOUNDS)
                .1;
            let cell = pdf as f64 * 2.0 * PI64 * PI64 * sin_theta / (w * h) as f64;
            for q in 0..4 {
                probs[4 * (j * w + i) + q] = cell / 4.0;
            }
        }
    }
    let total: f64 = probs.iter().sum();
    assert!((total - 1.0).abs() < 1e-4, "{total}");
    let samples = sampled_directions(&set, &g, 300_000, 23);
    let mut counts = vec![0u64; probs.len()];
    for s in &samples {
        let uv = dir_to_uv(-s.direction);
        let (x, y) = (uv.x * w as f32, uv.y * h as f32);
        let (i, j) = ((x as usize).min(w - 1), (y as usize).min(h - 1));
        let q = usize::from(x - i as f32 >= 0.5) + 2 * usize::from(y - j as f32 >= 0.5);
        counts[4 * (j * w + i) + q] += 1;
    }
    let (stat, df) = chi_square(&counts, &probs, samples.len() as u64);
    assert!(stat < chi_square_limit(df), "chi2 {stat} with {df} dof");
}
