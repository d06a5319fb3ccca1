//! Emissive media (issue 11) against results that are not the renderer itself.
//!
//! Convention: `emission` is the **emission coefficient** `j`, radiance per unit length, the
//! source term of `dL/ds = -sigma_t L + j + sigma_s (phase x L_in)`. So:
//!
//! - a uniform emissive, absorbing slab of thickness `d` (`sigma_s = 0`) seen straight on
//!   shows `L = j / sigma_a (1 - exp(-sigma_a d))` (solve `dL/ds = -sigma_a L + j` from 0);
//! - a medium with `j = sigma_a L0` inside an index-matched boundary, in a constant
//!   environment `L0`, is in **equilibrium**: `L = L0` solves the transfer equation
//!   (`-sigma_t L0 + sigma_a L0 + sigma_s L0 = 0`, the phase function being normalised), for
//!   any albedo, phase function and shape -- every pixel of such a sphere is `L0`, which
//!   tests every order of scattering of the emitted light, for the walk and for bounces;
//! - a diffuse floor under a wide emissive absorbing slab receives from the slab the
//!   radiance `j / sigma_a (1 - exp(-sigma_a d / mu))` from each direction `mu = cos theta`
//!   above, i.e. the irradiance `2 pi j / sigma_a (1/2 - E_3(sigma_a d))`
//!   (`int_0^1 mu e^{-tau / mu} dmu = E_3(tau)`, the exponential integral).

mod common;
use common::scratch_dir;
use common::*;
use glam::Vec3;
use risotto::builtins::heterogeneous::{HeterogeneousInterior, HeterogeneousMedium, Tracking};
use risotto::builtins::media::{HomogeneousInterior, HomogeneousMedium, Scattering};
use risotto::engine::context::RenderContext;
use risotto::engine::integrator::LightingTechnique;
use risotto::engine::plugin::{
    InstanceHints, Segments, ShadingContext, ShadingMode, VolumeIntegrator,
};
use risotto::engine::render::{render, RenderOptions, RenderOutput};
use risotto::engine::scene::CompiledScene;
use risotto::engine::stats::VolumeEvent;
use risotto::loader::load::{scene_from_desc, LoadError, MaterialRegistry};
use risotto::loader::scene_file::parse_scene;
use risotto::systems::grid::DensityGrid;
use risotto::systems::phase::PhaseFunction;
use risotto::systems::sampler::PathSampler;
use risotto_components::{Rgb, ShadingPoints};
use std::path::Path;

/// Writes a Mitsuba `.vol` grid (version 3, float32, one channel).
fn write_vol(path: &Path, dims: [usize; 3], data: &[f32]) {
    let mut b = b"VOL".to_vec();
    b.push(3);
    for v in [1i32, dims[0] as i32, dims[1] as i32, dims[2] as i32, 1] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0].iter().chain(data) {
        b.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(path, b).unwrap();
}

/// An `n^3` grid ramped along x: `lo + (hi - lo) (ix + 0.5) / n`.
fn ramp(n: usize, lo: f32, hi: f32) -> Vec<f32> {
    let mut data = Vec::with_capacity(n * n * n);
    for _z in 0..n {
        for _y in 0..n {
            for x in 0..n {
                data.push(lo + (hi - lo) * (x as f32 + 0.5) / n as f32);
            }
        }
    }
    data
}

fn load(dir: &Path, text: &str) -> Result<CompiledScene, LoadError> {
    let desc = parse_scene(text, &dir.join("scene.toml"))?;
    Ok(scene_from_desc(desc, &MaterialRegistry::with_builtins())?
        .compile()
        .unwrap())
}

fn render_text(dir: &Path, text: &str, technique: LightingTechnique) -> RenderOutput {
    let scene = load(dir, text).unwrap_or_else(|e| panic!("{e}"));
    let options = RenderOptions {
        technique,
        ..RenderOptions::default()
    };
    let out = render(&scene, &options, &|_| {}).unwrap();
    assert_eq!(out.stats.counters.nan_dropped, 0, "NaN samples");
    assert_finite("render", &out);
    out
}

/// A wide slab `y in [-d, 0]` of `interior` (index-matched), seen straight down by an
/// orthographic camera; nothing else in the scene.
fn slab_scene(interior: &str, d: f32, spp: u32) -> String {
    format!(
        r#"
[render]
width = 8
height = 8
spp = {spp}
max_depth = -1

[camera]
projection = "orthographic"
width = 0.5
from = [0, 5, 0]
to = [0, 0, 0]
up = [0, 0, 1]

[materials.glow]
type = "interface"
interior = {interior}

[[shapes]]
name = "slab"
type = "box"
material = "glow"
min = [-40, -{d}, -40]
max = [40, 0, 40]
"#
    )
}

/// `j / sigma_a (1 - exp(-sigma_a d))`: what a uniform emissive absorbing slab shows.
fn slab_radiance(j: f64, sigma_a: f64, d: f64) -> f64 {
    if sigma_a == 0.0 {
        j * d
    } else {
        j / sigma_a * (1.0 - (-sigma_a * d).exp())
    }
}

/// Asserts `got` (a mean with standard error `se`) is `want` to 1 % or 3 standard errors.
fn assert_close(what: &str, got: Rgb, se: Rgb, want: f64) {
    for (c, (g, s)) in [(got.r, se.r), (got.g, se.g), (got.b, se.b)]
        .into_iter()
        .enumerate()
    {
        let (g, s) = (g as f64, s as f64);
        let ok = (g - want).abs() <= (0.01 * want).max(3.0 * s);
        assert!(ok, "{what}, channel {c}: {g} +- {s} vs {want}");
    }
}

#[test]
fn an_emissive_absorbing_slab_shows_j_over_sigma_a_times_one_minus_t() {
    let (j, sigma_a, d) = (3.0, 2.0, 0.5);
    let want = slab_radiance(j, sigma_a, d);
    // The check discriminates: emission not attenuated would give j d, attenuated twice
    // (or by the full thickness) something else.
    assert!((j * d - want).abs() > 0.5 * want);
    assert!((j * d * (-sigma_a * d).exp() - want).abs() > 0.1 * want);
    let dir = scratch_dir("emit", "slab");
    // Homogeneous: the exact segment integral, whatever the scattering technique
    // (deterministic: every pixel is the closed form to float precision).
    for scattering in ["multiple", "walk", "bounce", "single"] {
        let interior = format!(
            r#"{{ type = "homogeneous", sigma_a = {sigma_a}, emission = {j}, scattering = "{scattering}" }}"#
        );
        for technique in [
            LightingTechnique::Mis,
            LightingTechnique::NeeOnly,
            LightingTechnique::BxdfOnly,
        ] {
            let out = render_text(&dir, &slab_scene(&interior, d as f32, 4), technique);
            for p in &out.beauty.pixels {
                for c in p.to_array() {
                    let rel = (c as f64 - want).abs() / want;
                    assert!(
                        rel < 1e-4,
                        "{scattering} {technique:?}: pixel {c} vs {want}"
                    );
                }
            }
            let events = out.stats.counters.volume_events[VolumeEvent::Emission as usize];
            assert!(events > 0, "{scattering}: the emission code ran");
        }
    }
    // A chromatic slab: each channel its own closed form.
    let interior = r#"{ type = "homogeneous", sigma_a = [0.5, 2, 8], emission = [1, 3, 0.5] }"#;
    let out = render_text(
        &dir,
        &slab_scene(interior, d as f32, 4),
        LightingTechnique::Mis,
    );
    let (mean, _) = image_mean(&out);
    for (got, (j, s)) in mean
        .to_array()
        .into_iter()
        .zip([(1.0, 0.5), (3.0, 2.0), (0.5, 8.0)])
    {
        let want = slab_radiance(j, s, d);
        assert!((got as f64 - want).abs() < 1e-4 * want, "{got} vs {want}");
    }
    // Heterogeneous, constant density: both emission forms and every tracking (shadow rays
    // play no part here: the free flights' emission estimator, j / majorant at every
    // tentative collision, with noise).
    let grid = dir.join("ones.vol");
    write_vol(&grid, [2, 2, 2], &[1.0; 8]);
    for emission in [
        format!("{j}"),
        format!(r#"{{ grid = "ones.vol", scale = {j} }}"#),
    ] {
        for tracking in ["ratio", "residual", "delta"] {
            let interior = format!(
                r#"{{ type = "heterogeneous", density = {{ constant = 1 }}, scale = {sigma_a}, albedo = 0, emission = {emission}, tracking = "{tracking}" }}"#
            );
            let out = render_text(
                &dir,
                &slab_scene(&interior, d as f32, 256),
                LightingTechnique::Mis,
            );
            let (mean, se) = image_mean(&out);
            assert_close(
                &format!("heterogeneous {emission} {tracking}"),
                mean,
                se,
                want,
            );
        }
    }
    // An emission grid where the density vanishes: no extinction, `L = j d`. Found only
    // because the tracking majorant of emitting cells is raised above zero.
    let interior = r#"{ type = "heterogeneous", density = { constant = 0 }, emission = { grid = "ones.vol", scale = 3 } }"#;
    let out = render_text(
        &dir,
        &slab_scene(interior, d as f32, 256),
        LightingTechnique::Mis,
    );
    let (mean, se) = image_mean(&out);
    assert_close(
        "emission without density",
        mean,
        se,
        slab_radiance(3.0, 0.0, d),
    );
}

/// A unit sphere of `interior` (index-matched) in a constant environment of radiance 1, seen
/// whole by a 12 x 12 camera.
fn equilibrium_scene(interior: &str, spp: u32) -> String {
    format!(
        r#"
[render]
width = 12
height = 12
spp = {spp}
max_depth = -1

[camera]
fov = 40
from = [0, 0, 4]
to = [0, 0, 0]

[materials.medium]
type = "interface"
interior = {interior}

[[shapes]]
name = "ball"
type = "sphere"
material = "medium"
center = [0, 0, 0]
radius = 1

[[lights]]
type = "environment"
radiance = 1
"#
    )
}

/// Asserts the equilibrium: every channel's image mean is 1 within 3 standard errors (and
/// the estimate is precise enough for that to mean something), no pixel far off.
fn assert_equilibrium(what: &str, out: &RenderOutput) {
    let (mean, se) = image_mean(out);
    for (m, s) in mean.to_array().into_iter().zip(se.to_array()) {
        assert!(s < 0.01, "{what}: standard error {s}");
        assert!(
            (m - 1.0).abs() <= 3.0 * s + 1e-4,
            "{what}: {mean:?} +- {se:?}"
        );
    }
    for p in &out.beauty.pixels {
        assert!(
            p.max_channel() < 1.5 && p.min_channel() > 0.5,
            "{what}: pixel {p:?}"
        );
    }
    let c = &out.stats.counters;
    assert!(
        c.volume_events[VolumeEvent::Scatter as usize] > 0,
        "{what}: scattered"
    );
    assert!(
        c.volume_events[VolumeEvent::Emission as usize] > 0,
        "{what}: emitted"
    );
}

const TECHNIQUES: [LightingTechnique; 3] = [
    LightingTechnique::Mis,
    LightingTechnique::NeeOnly,
    LightingTechnique::BxdfOnly,
];

#[test]
fn an_emissive_scattering_sphere_with_j_sigma_a_l0_is_in_equilibrium() {
    let dir = scratch_dir("emit", "equilibrium");
    // Every order of scattering, walked and bounced, any albedo and phase function, every
    // lighting technique: under `nee` the environment is light-sampled, so shadow rays cross
    // the emissive sphere -- emission gathered along them as well as along the paths would
    // push the pixels above 1.
    for (sigma_t, albedo) in [(2.0f32, 0.3f32), (3.0, 0.9)] {
        let j = sigma_t * (1.0 - albedo);
        for phase in [r#"{ type = "isotropic" }"#, r#"{ type = "hg", g = 0.7 }"#] {
            for scattering in ["walk", "bounce"] {
                let interior = format!(
                    r#"{{ type = "homogeneous", sigma_t = {sigma_t}, albedo = {albedo}, emission = {j}, phase = {phase}, scattering = "{scattering}" }}"#
                );
                for technique in TECHNIQUES {
                    let out = render_text(&dir, &equilibrium_scene(&interior, 64), technique);
                    let what = format!("albedo {albedo} {phase} {scattering} {technique:?}");
                    assert_equilibrium(&what, &out);
                }
            }
        }
    }
    // A chromatic medium (spectral MIS over channels of different extinction): j = sigma_a
    // per channel.
    for scattering in ["walk", "bounce"] {
        let interior = format!(
            r#"{{ type = "homogeneous", sigma_a = [0.8, 1.0, 0.8], sigma_s = [0.2, 1.0, 3.2], emission = [0.8, 1.0, 0.8], scattering = "{scattering}" }}"#
        );
        let out = render_text(
            &dir,
            &equilibrium_scene(&interior, 64),
            LightingTechnique::Mis,
        );
        assert_equilibrium(&format!("chromatic {scattering}"), &out);
    }
    // Without emission the same sphere is darker than the environment: the test sees the
    // emission.
    let interior = r#"{ type = "homogeneous", sigma_t = 2, albedo = 0.3 }"#;
    let out = render_text(
        &dir,
        &equilibrium_scene(interior, 16),
        LightingTechnique::Mis,
    );
    assert!(image_mean(&out).0.g < 0.8);
}

#[test]
fn an_emissive_heterogeneous_sphere_with_j_sigma_a_l0_is_in_equilibrium() {
    let dir = scratch_dir("emit", "hetero-equilibrium");
    // Density ramped 0.2 .. 2 along x, sigma_t = 2 density, albedo 0.6: j(p) = sigma_a(p) =
    // 0.8 density(p), given as a colour (emission follows the density) or as the same grid
    // with scale 0.8.
    write_vol(&dir.join("ramp.vol"), [8, 8, 8], &ramp(8, 0.2, 2.0));
    for emission in ["0.8", r#"{ grid = "ramp.vol", scale = 0.8 }"#] {
        for tracking in ["ratio", "residual", "delta"] {
            let interior = format!(
                r#"{{ type = "heterogeneous", density = {{ grid = "ramp.vol" }}, scale = 2, albedo = 0.6, emission = {emission}, tracking = "{tracking}", majorant_grid = 4 }}"#
            );
            for technique in [LightingTechnique::Mis, LightingTechnique::NeeOnly] {
                let out = render_text(&dir, &equilibrium_scene(&interior, 64), technique);
                assert_equilibrium(&format!("{emission} {tracking} {technique:?}"), &out);
            }
        }
    }
}

/// A diffuse floor (albedo 0.5) seen from above through a wide emissive absorbing slab
/// (`y in [0.5, 1.5]`, `interior`), a point light of intensity 4 at height 2 above it;
/// max_depth 2.
fn floor_scene(interior: &str, spp: u32) -> String {
    format!(
        r#"
[render]
width = 4
height = 4
spp = {spp}
max_depth = 2

[camera]
projection = "orthographic"
width = 0.02
from = [0, 1.9, 0]
to = [0, 0, 0]
up = [0, 0, 1]

[materials.floor]
type = "diffuse"
reflectance = 0.5

[materials.glow]
type = "interface"
interior = {interior}

[[shapes]]
type = "quad"
material = "floor"
corner = [-1000, 0, -1000]
edge1 = [0, 0, 2000]
edge2 = [2000, 0, 0]

[[shapes]]
name = "slab"
type = "box"
material = "glow"
min = [-1000, 0.5, -1000]
max = [1000, 1.5, 1000]

[[lights]]
type = "point"
position = [0, 2, 0]
intensity = 4
"#
    )
}

/// `E_3(tau) = int_0^1 mu e^{-tau / mu} dmu` (Simpson in f64).
fn e3(tau: f64) -> f64 {
    let f = |mu: f64| {
        if mu == 0.0 {
            0.0
        } else {
            mu * (-tau / mu).exp()
        }
    };
    let n = 20_000;
    let h = 1.0 / n as f64;
    let mut s = f(0.0) + f(1.0);
    for k in 1..n {
        s += f(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}

#[test]
fn an_emissive_slab_lights_the_floor_below_it_and_counts_once() {
    // The camera ray crosses the slab (thickness 1): E = j / sigma_a (1 - T), then sees the
    // floor through T = exp(-sigma_a). The floor point under the light gets the light through
    // the slab, T I / r^2 (r = 2, cos = 1), and the slab's own radiance from the upper
    // hemisphere, 2 pi j / sigma_a (1/2 - E_3(sigma_a)); it reflects rho / pi of both.
    let (j, sigma_a, rho) = (0.5f64, 0.7f64, 0.5f64);
    let t = (-sigma_a).exp();
    let seen_from_floor = 2.0 * std::f64::consts::PI * j / sigma_a * (0.5 - e3(sigma_a));
    let floor = rho / std::f64::consts::PI * (t * 4.0 / 4.0 + seen_from_floor);
    let want = slab_radiance(j, sigma_a, 1.0) + t * floor;
    let dir = scratch_dir("emit", "floor");
    // Homogeneous under every scattering technique (`single` runs the lighting delegate on
    // the camera ray's segment: with sigma_s = 0 it adds nothing, and the emission along
    // the segment must still be there, exactly once), and heterogeneous.
    let mut interiors: Vec<String> = ["multiple", "bounce", "walk", "single"]
        .iter()
        .map(|s| {
            format!(
                r#"{{ type = "homogeneous", sigma_a = {sigma_a}, emission = {j}, scattering = "{s}" }}"#
            )
        })
        .collect();
    interiors.push(
        format!(
            r#"{{ type = "heterogeneous", density = {{ constant = 1 }}, scale = {sigma_a}, albedo = 0, emission = {j} }}"#
        ),
    );
    for interior in &interiors {
        // The point light needs light sampling: MIS and light sampling alone. Neither may
        // add the slab's emission along the shadow ray too (that direction is one the Bxdf
        // samples as well).
        for technique in [LightingTechnique::Mis, LightingTechnique::NeeOnly] {
            let out = render_text(&dir, &floor_scene(interior, 1024), technique);
            let (mean, se) = image_mean(&out);
            assert_close(&format!("{interior} {technique:?}"), mean, se, want);
        }
    }
    // Light from the slab is a good part of what the floor gets: without it (or with it
    // twice) the check fails.
    assert!(rho / std::f64::consts::PI * seen_from_floor * t > 0.05 * want);
}

/// Segments from `origin` along `direction` of `length`, `n` copies, with independent
/// samplers.
fn segments(n: usize, origin: Vec3, direction: Vec3, length: f32) -> (Segments, Vec<PathSampler>) {
    let mut s = Segments::default();
    let mut samplers = Vec::with_capacity(n);
    for k in 0..n {
        s.push(origin, direction, length);
        samplers.push(PathSampler {
            seed: 0x9e37_79b9,
            sample: k as u32,
            dimension: 0,
        });
    }
    (s, samplers)
}

/// A compiled scene to lend integrators an `IntegratorContext` (it plays no part).
fn some_scene() -> CompiledScene {
    load(
        &scratch_dir("emit", "ctx"),
        &slab_scene(r#"{ type = "null" }"#, 1.0, 1),
    )
    .unwrap()
}

#[test]
fn transmission_returns_the_emission_reaching_the_segment_start() {
    let scene = some_scene();
    let mut stats = risotto::engine::stats::SystemStats::default();
    let ictx = RenderContext::new(&scene, &mut stats);
    let (origin, direction, length) = (Vec3::new(-1.0, 0.0, 0.0), Vec3::X, 1.5);
    // Homogeneous: exact, per channel.
    let medium = HomogeneousMedium {
        sigma_t: Rgb::new(0.5, 2.0, 0.0),
        sigma_s: Rgb::new(0.25, 1.0, 0.0),
        phase: PhaseFunction::Isotropic,
        scattering: Scattering::Multiple,
        emission: Rgb::new(1.0, 2.0, 3.0),
        albedo_pattern: None,
        g_pattern: None,
    };
    let (segs, mut samplers) = segments(4, origin, direction, length);
    let mut pts = ShadingPoints::with_capacity(4);
    pts.extend_in_volume(&segs.origin, &segs.direction, 0);
    let ctx = ShadingContext::new(&pts, 0..4, ShadingMode::Interior, 0, &[]);
    let homogeneous = HomogeneousInterior {
        medium: &medium,
        ctx: &ctx,
        boundary_blocks_shadows: false,
    };
    let (mut trans, mut emission) = (vec![Rgb::BLACK; 4], vec![Rgb::BLACK; 4]);
    homogeneous.transmission(&segs, &mut samplers, &ictx, &mut trans, &mut emission);
    for e in &emission {
        let want = [(1.0, 0.5), (2.0, 2.0), (3.0, 0.0)].map(|(j, s)| slab_radiance(j, s, 1.5));
        for (got, want) in e.to_array().into_iter().zip(want) {
            assert!((got as f64 - want).abs() < 1e-5 * want, "{got} vs {want}");
        }
    }
    // Heterogeneous, over the box [-1, 1]^3 (a segment through its middle): the tracking
    // estimates' mean is the closed form, for every tracking and both forms; and the
    // transmittance estimate is what it was.
    let n = 20_000;
    let (segs, _) = segments(n, origin, direction, length);
    let mut pts = ShadingPoints::with_capacity(n);
    pts.extend_in_volume(&segs.origin, &segs.direction, 0);
    let ctx = ShadingContext::new(&pts, 0..n, ShadingMode::Interior, 0, &[])
        .with_volume_bounds(Vec3::splat(-1.0), Vec3::splat(1.0));
    let (density, scale) = (0.5f32, 1.2f32);
    let grid = || DensityGrid::constant([4, 4, 4], density).unwrap();
    let cases = [
        // j = colour * density.
        (
            "follows density",
            HeterogeneousMedium::new(
                grid(),
                4,
                scale,
                Rgb::splat(0.5),
                PhaseFunction::Isotropic,
                Tracking::Ratio,
            )
            .with_emission_following_density(Rgb::new(2.0, 4.0, 6.0)),
            Rgb::new(1.0, 2.0, 3.0),
            scale * density,
        ),
        // j = scale * grid, with no extinction at all (the raised majorant finds it).
        (
            "grid, no density",
            HeterogeneousMedium::new(
                DensityGrid::constant([4, 4, 4], 0.0).unwrap(),
                4,
                scale,
                Rgb::splat(0.5),
                PhaseFunction::Isotropic,
                Tracking::Ratio,
            )
            .with_emission_grid(grid(), Rgb::new(2.0, 4.0, 6.0)),
            Rgb::new(1.0, 2.0, 3.0),
            0.0,
        ),
    ];
    for (what, medium, j, sigma_t) in cases {
        for tracking in [Tracking::Ratio, Tracking::Residual, Tracking::Delta] {
            let medium = HeterogeneousMedium {
                tracking,
                ..medium.clone()
            };
            let integrator = HeterogeneousInterior {
                medium: &medium,
                ctx: &ctx,
            };
            let (_, mut samplers) = segments(n, origin, direction, length);
            let (mut trans, mut emission) = (vec![Rgb::BLACK; n], vec![Rgb::BLACK; n]);
            integrator.transmission(&segs, &mut samplers, &ictx, &mut trans, &mut emission);
            let (mut sum, mut sum2, mut tsum) = ([0.0f64; 3], [0.0f64; 3], 0.0f64);
            for (e, t) in emission.iter().zip(&trans) {
                for (c, v) in e.to_array().into_iter().enumerate() {
                    sum[c] += v as f64;
                    sum2[c] += (v as f64).powi(2);
                }
                tsum += t.g as f64;
            }
            for c in 0..3 {
                let mean = sum[c] / n as f64;
                let se = ((sum2[c] / n as f64 - mean * mean) / n as f64).sqrt();
                let want = slab_radiance(j.to_array()[c] as f64, sigma_t as f64, length as f64);
                assert!(
                    (mean - want).abs() <= (4.0 * se).max(1e-6 * want),
                    "{what} {tracking:?} channel {c}: {mean} +- {se} vs {want}"
                );
            }
            let t_want = (-(sigma_t * length) as f64).exp();
            let t_mean = tsum / n as f64;
            assert!(
                (t_mean - t_want).abs() < 0.02,
                "{what} {tracking:?}: transmittance {t_mean} vs {t_want}"
            );
        }
    }
}

#[test]
fn scenes_without_emission_run_no_emission_code() {
    let dir = scratch_dir("emit", "gating");
    let grid = dir.join("ramp.vol");
    write_vol(&grid, [8, 8, 8], &ramp(8, 0.2, 2.0));
    let plain = [
        r#"{ type = "homogeneous", sigma_t = 2, albedo = 0.8 }"#,
        r#"{ type = "homogeneous", sigma_t = 2, albedo = 0.8, scattering = "walk" }"#,
        r#"{ type = "heterogeneous", density = { grid = "ramp.vol" }, scale = 2 }"#,
        // An all-zero emission is none.
        r#"{ type = "homogeneous", sigma_t = 2, albedo = 0.8, emission = 0 }"#,
    ];
    for interior in plain {
        let scene = load(&dir, &equilibrium_scene(interior, 4)).unwrap();
        assert!(!scene.features.emissive_media, "{interior}");
        for info in &scene.material_info {
            assert!(!info.hints.contains(InstanceHints::INTERIOR_EMITS));
        }
        let out = render(&scene, &RenderOptions::default(), &|_| {}).unwrap();
        assert_eq!(
            out.stats.counters.volume_events[VolumeEvent::Emission as usize],
            0,
            "{interior}"
        );
        assert!(!out.stats.features.iter().any(|f| f == "emissive_media"));
    }
    let emissive = [
        r#"{ type = "homogeneous", sigma_t = 2, albedo = 0.8, emission = 0.4 }"#,
        r#"{ type = "homogeneous", sigma_t = 2, albedo = 0.8, emission = 0.4, scattering = "walk" }"#,
        r#"{ type = "heterogeneous", density = { grid = "ramp.vol" }, scale = 2, emission = 0.4 }"#,
        r#"{ type = "heterogeneous", density = { grid = "ramp.vol" }, emission = { grid = "ramp.vol" } }"#,
    ];
    for interior in emissive {
        let scene = load(&dir, &equilibrium_scene(interior, 4)).unwrap();
        assert!(scene.features.emissive_media, "{interior}");
        let hints = scene.material_info[0].hints;
        assert!(hints
            .contains(InstanceHints::INTERIOR_EMITS | InstanceHints::INTERIOR_EMITS_ALONG_PATHS));
        let out = render(&scene, &RenderOptions::default(), &|_| {}).unwrap();
        assert!(out.stats.counters.volume_events[VolumeEvent::Emission as usize] > 0);
        assert!(out.stats.features.iter().any(|f| f == "emissive_media"));
        assert!(out.stats.to_json().contains("\"emission\""));
    }
}

#[test]
fn extreme_emission_and_extinction_stay_finite() {
    let dir = scratch_dir("emit", "extreme");
    let d = 0.5f32;
    for sigma_a in [1e-6f32, 1e6] {
        let want = slab_radiance(1e30, sigma_a as f64, d as f64);
        for scattering in ["bounce", "walk", "single"] {
            let interior = format!(
                r#"{{ type = "homogeneous", sigma_a = {sigma_a:e}, sigma_s = {sigma_a:e}, emission = 1e30, scattering = "{scattering}" }}"#
            );
            let out = render_text(&dir, &slab_scene(&interior, d, 4), LightingTechnique::Mis);
            let (mean, _) = image_mean(&out);
            // With albedo 1/2 the slab shows at least its emission attenuated by the full
            // extinction (the light scattered back is extra) and at most the emission
            // attenuated by absorption alone (its limits: j d thin, j / sigma_a thick).
            let lo = slab_radiance(1e30, 2.0 * sigma_a as f64, d as f64);
            let g = mean.g as f64;
            assert!(
                g >= 0.99 * lo && g <= 1.01 * want,
                "{scattering} sigma {sigma_a}: {mean:?} vs [{lo}, {want}]"
            );
        }
        let interior = format!(
            r#"{{ type = "heterogeneous", density = {{ constant = 1 }}, scale = {sigma_a:e}, albedo = 0, emission = 1e30 }}"#
        );
        let out = render_text(&dir, &slab_scene(&interior, d, 16), LightingTechnique::Mis);
        let (mean, se) = image_mean(&out);
        assert_close(&format!("heterogeneous sigma {sigma_a}"), mean, se, want);
    }
}

#[test]
fn bad_emission_values_are_located_errors() {
    let d = scratch_dir("emit", "errors");
    write_vol(&d.join("ones.vol"), [2, 2, 2], &[1.0; 8]);
    let mut neg = vec![1.0f32; 8];
    neg[3] = -2.5;
    write_vol(&d.join("neg.vol"), [2, 2, 2], &neg);
    let hetero = r#"type = "heterogeneous", density = { constant = 1 }"#;
    let cases: Vec<(String, Vec<&str>)> = vec![
        (
            r#"{ type = "homogeneous", sigma_t = 1, emission = -1 }"#.into(),
            vec![
                "scene.toml:",
                "materials.glow.interior",
                "emission",
                "-1",
                ">= 0",
            ],
        ),
        (
            r#"{ type = "homogeneous", sigma_t = 1, emission = [1, nan, 1] }"#.into(),
            vec!["materials.glow.interior", "emission", "nan"],
        ),
        (
            format!(r#"{{ {hetero}, emission = [1, -2, 0] }}"#),
            vec!["scene.toml:", "materials.glow.interior", "emission", "-2"],
        ),
        (
            format!(r#"{{ {hetero}, emission = {{ grid = "none.vol" }} }}"#),
            vec![
                "materials.glow.interior.emission",
                "none.vol",
                "cannot read",
            ],
        ),
        (
            format!(r#"{{ {hetero}, emission = {{ grid = "neg.vol" }} }}"#),
            vec![
                "materials.glow.interior.emission",
                "neg.vol",
                "voxel (1, 1, 0)",
                "-2.5",
            ],
        ),
        (
            format!(r#"{{ {hetero}, emission = {{ scale = 2 }} }}"#),
            vec!["materials.glow.interior.emission", "grid"],
        ),
        (
            format!(r#"{{ {hetero}, emission = {{ grid = "ones.vol", scale = -3 }} }}"#),
            vec!["materials.glow.interior.emission", "scale", "-3"],
        ),
        (
            format!(r#"{{ {hetero}, emission = {{ grid = "ones.vol", colour = 1 }} }}"#),
            vec!["materials.glow.interior.emission", "colour"],
        ),
        (
            r#"{ type = "heterogeneous", density = { constant = 10 }, emission = 3e38 }"#.into(),
            vec!["emission", "1e30"],
        ),
        (
            r#"{ type = "beer", sigma_a = 1, emission = 1 }"#.into(),
            vec!["materials.glow.interior", "emission"],
        ),
    ];
    for (interior, needles) in cases {
        let e = match load(&d, &slab_scene(&interior, 1.0, 1)) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("{interior}: accepted"),
        };
        for n in needles {
            assert!(e.contains(n), "{interior}: {e:?} lacks {n:?}");
        }
    }
    // A subsurface material has no interior key, emission included.
    let text = slab_scene(r#"{ type = "null" }"#, 1.0, 1).replace(
        "[materials.glow]\ntype = \"interface\"\ninterior = { type = \"null\" }",
        "[materials.glow]\ntype = \"subsurface\"\nemission = 1",
    );
    let e = load(&d, &text)
        .err()
        .expect("subsurface emission rejected")
        .to_string();
    assert!(e.contains("emission"), "{e}");
}
