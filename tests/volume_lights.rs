//! Emissive volumes as lights (issue 11): next-event estimation towards emissive media, MIS
//! against the collision estimator, checked against a brute-force integral and against
//! unidirectional estimation alone.
//!
//! A diffuse floor (reflectance `rho`) lit only by a uniform emissive, absorbing box above it
//! has radiance `rho / pi * E(q)`, with the irradiance
//! `E(q) = int_box j exp(-sigma_a l(x, q)) cos(theta_q) / |x - q|^2 dV`
//! (`l` the length of the segment from `x` towards `q` inside the box), computed here by
//! the midpoint rule. `lighting = mis` (light sampling of the box, MIS-weighted against the
//! medium's collision estimator), `nee` and `bxdf` (the collision estimator alone) must all
//! agree with it.

mod common;
use common::scratch_dir;
use common::*;
use risotto::engine::features::Features;
use risotto::engine::integrator::{GlobalIntegrator, LightingTechnique};
use risotto::engine::render::{render, render_with, RenderOptions, RenderOutput};
use risotto::engine::scene::CompiledScene;
use risotto::engine::stats::VolumeEvent;
use risotto::loader::load::{scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::parse_scene;
use risotto_components::Rgb;
use std::path::Path;

fn compile(dir: &Path, text: &str) -> CompiledScene {
    let desc = parse_scene(text, &dir.join("scene.toml")).unwrap_or_else(|e| panic!("{e}"));
    scene_from_desc(desc, &MaterialRegistry::with_builtins())
        .unwrap()
        .compile()
        .unwrap()
}

fn render_with_technique(scene: &CompiledScene, technique: LightingTechnique) -> RenderOutput {
    let options = RenderOptions {
        technique,
        ..RenderOptions::default()
    };
    let out = render(scene, &options, &|_| {}).unwrap();
    assert_eq!(out.stats.counters.nan_dropped, 0, "NaN samples");
    assert_finite("render", &out);
    out
}

const TECHNIQUES: [LightingTechnique; 3] = [
    LightingTechnique::Mis,
    LightingTechnique::NeeOnly,
    LightingTechnique::BxdfOnly,
];

/// The box of medium.
const LO: [f64; 3] = [-0.5, 0.5, -0.5];
const HI: [f64; 3] = [0.5, 1.5, 0.5];
/// The floor patch the camera sees: `x in [-X, X]`, `z in [-Z, Z]` (an orthographic view
/// of width 0.02 from `(2, 0.3, 0)` towards the origin).
const X: f64 = 0.01 * 2.022_374_842_3 / 0.3;
const Z: f64 = 0.01;

/// A floor of reflectance 0.5 seen at a grazing angle (the camera rays pass under the box),
/// lit by the box `LO..HI` of `interior` behind an index-matched boundary; direct light only.
fn floor_scene(interior: &str, spp: u32) -> String {
    format!(
        r#"
[render]
width = 8
height = 8
spp = {spp}
max_depth = 2

[camera]
projection = "orthographic"
width = 0.02
from = [2, 0.3, 0]
to = [0, 0, 0]
up = [0, 1, 0]

[materials.floor]
type = "diffuse"
reflectance = 0.5

[materials.glow]
type = "interface"
interior = {interior}

[[shapes]]
name = "floor"
type = "quad"
material = "floor"
corner = [-5, 0, -5]
edge1 = [0, 0, 10]
edge2 = [10, 0, 0]

[[shapes]]
name = "glow"
type = "box"
material = "glow"
min = {LO:?}
max = {HI:?}
"#
    )
}

/// Distance from `x` (inside the box) along unit `d` to where it leaves the box.
fn exit_distance(x: [f64; 3], d: [f64; 3]) -> f64 {
    (0..3)
        .map(|a| {
            if d[a] > 0.0 {
                (HI[a] - x[a]) / d[a]
            } else if d[a] < 0.0 {
                (LO[a] - x[a]) / d[a]
            } else {
                f64::INFINITY
            }
        })
        .fold(f64::INFINITY, f64::min)
}

/// `E(q)` of the uniform box (`j`, `sigma_a`) at floor point `q`, midpoint rule on `n^3`
/// points.
fn irradiance(q: [f64; 3], j: f64, sigma_a: f64, n: usize) -> f64 {
    let h = [0, 1, 2].map(|a| (HI[a] - LO[a]) / n as f64);
    let dv = h[0] * h[1] * h[2];
    let mut e = 0.0;
    for k in 0..n {
        for jy in 0..n {
            for i in 0..n {
                let x = [
                    LO[0] + (i as f64 + 0.5) * h[0],
                    LO[1] + (jy as f64 + 0.5) * h[1],
                    LO[2] + (k as f64 + 0.5) * h[2],
                ];
                let v = [q[0] - x[0], q[1] - x[1], q[2] - x[2]];
                let s2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
                let s = s2.sqrt();
                let d = v.map(|c| c / s);
                let l = exit_distance(x, d);
                // cos at the floor: the direction towards x is -d, the normal +y.
                e += j * (-sigma_a * l).exp() * (-d[1]) / s2 * dv;
            }
        }
    }
    e
}

/// The floor radiance averaged over the patch the camera sees.
fn expected_floor_radiance(j: f64, sigma_a: f64) -> f64 {
    let m = 3;
    let mut sum = 0.0;
    for a in 0..m {
        for b in 0..m {
            let x = -X + (2.0 * a as f64 + 1.0) * X / m as f64;
            let z = -Z + (2.0 * b as f64 + 1.0) * Z / m as f64;
            sum += irradiance([x, 0.0, z], j, sigma_a, 48);
        }
    }
    0.5 / std::f64::consts::PI * sum / (m * m) as f64
}

/// Asserts an image mean (with its standard error) is the brute-force integral `want` in
/// every channel: within 3 standard errors plus 0.3 % for the quadrature, at a useful
/// precision (a standard error below 2 %).
fn assert_brute_force(what: &str, (mean, se): (Rgb, Rgb), want: f64) {
    for (c, (g, s)) in [(mean.r, se.r), (mean.g, se.g), (mean.b, se.b)]
        .into_iter()
        .enumerate()
    {
        let (g, s) = (g as f64, s as f64);
        assert!(s < 0.02 * want, "{what}: se {s} of {want}");
        assert!(
            (g - want).abs() <= 3.0 * s + 0.003 * want,
            "{what} channel {c}: {g} +- {s} vs {want}"
        );
    }
}

/// The floor under the uniform box `interior` (emission `j`, absorption `sigma_a`, no
/// scattering) under each lighting technique: light-sampled under MIS only, each image
/// mean the brute-force integral within 3 standard errors (plus the quadrature's 0.3 %),
/// and MIS the most precise at equal spp: its standard error below `ratio` times the
/// unidirectional one's.
fn assert_box_lights_floor(d: &Path, interior: &str, j: f64, sigma_a: f64, ratio: f32) {
    let scene = compile(d, &floor_scene(interior, 512));
    assert!(
        scene.features.emissive_volume_lights,
        "{interior}: the box is light-sampled"
    );
    let want = expected_floor_radiance(j, sigma_a);
    let mut errors = Vec::new();
    for technique in TECHNIQUES {
        let out = render_with_technique(&scene, technique);
        let (mean, se) = image_mean(&out);
        errors.push(se.r);
        let samples = out.stats.counters.volume_events[VolumeEvent::LightSample as usize];
        assert_eq!(
            samples > 0,
            technique == LightingTechnique::Mis,
            "{interior} {technique:?}: {samples} volume-light samples"
        );
        assert_brute_force(&format!("{interior} {technique:?}"), (mean, se), want);
    }
    // MIS light-samples the box (`nee` and `bxdf` do not, crate docs of
    // risotto_engine::plugin::volume_light): at equal spp it is the more precise.
    assert!(
        errors[0] < ratio * errors[2],
        "{interior}: se mis {} vs bxdf {}",
        errors[0],
        errors[2]
    );
}

#[test]
fn a_uniform_emissive_box_lights_a_floor_as_the_brute_force_integral_says() {
    let d = scratch_dir("vlights", "box");
    constant_vol(&d.join("one.vol"), [2, 2, 2], 1.0);
    let (j, sigma_a) = (2.0, 1.5);
    let interior = format!(
        "{{ type = \"heterogeneous\", density = {{ grid = \"one.vol\" }}, scale = {sigma_a}, \
         albedo = 0, emission = {j}, majorant_grid = 2 }}"
    );
    assert_box_lights_floor(&d, &interior, j, sigma_a, 0.7);
}

/// The same box with its density or its emission given by patterns, in every form that
/// reaches the emitter: a pattern density the emission follows, an emission pattern over a
/// grid density, and a homogeneous interior with an emission pattern (built heterogeneous).
#[test]
fn pattern_emitters_light_a_floor_as_the_brute_force_integral_says() {
    let d = scratch_dir("vlights", "pattern-box");
    constant_vol(&d.join("one.vol"), [2, 2, 2], 1.0);
    let (j, sigma_a) = (2.0, 1.5);
    for interior in [
        format!(
            r#"{{ type = "heterogeneous", density = {{ pattern = "constant", value = 1 }}, scale = {sigma_a}, albedo = 0, emission = {j}, majorant_grid = 2 }}"#
        ),
        format!(
            r#"{{ type = "heterogeneous", density = {{ grid = "one.vol" }}, scale = {sigma_a}, albedo = 0, emission = {{ pattern = "constant", value = {j} }}, majorant_grid = 2 }}"#
        ),
        format!(
            r#"{{ type = "homogeneous", sigma_t = {sigma_a}, albedo = 0, emission = {{ pattern = "constant", value = {j} }} }}"#
        ),
    ] {
        assert_box_lights_floor(&d, &interior, j, sigma_a, 0.7);
    }
}

/// A homogeneous emissive box (constant coefficients) is a light too: its path rays that
/// compete with light samples gather the point estimator of the weighted emission
/// (`engine/builtins/src/media/emission.rs`), camera rays the exact integral. Its
/// unidirectional estimate is exact along each segment, so MIS's margin is smaller than
/// for the heterogeneous media's collision estimator (0.66 of its error here).
#[test]
fn a_homogeneous_emissive_box_lights_a_floor_as_the_brute_force_integral_says() {
    let d = scratch_dir("vlights", "homogeneous-box");
    let (j, sigma_a) = (2.0, 1.5);
    for scattering in ["bounce", "walk"] {
        let interior = format!(
            r#"{{ type = "homogeneous", sigma_t = {sigma_a}, albedo = 0, emission = {j}, scattering = "{scattering}" }}"#
        );
        assert_box_lights_floor(&d, &interior, j, sigma_a, 0.75);
    }
}

/// A scattering, chromatic homogeneous emitter: MIS, NEE alone and unidirectional
/// estimation agree, when its points bounce back to the path tracer (which light-samples
/// the medium from inside it) and when it walks (only each walk's first step is weighed).
#[test]
fn a_scattering_homogeneous_emitter_under_mis_equals_unidirectional_estimation() {
    let d = scratch_dir("vlights", "homogeneous-scatter");
    for scattering in ["bounce", "walk"] {
        let interior = format!(
            r#"{{ type = "homogeneous", sigma_t = [1, 2, 4], albedo = 0.7, emission = [3, 1.5, 0.5], phase = {{ type = "hg", g = 0.4 }}, scattering = "{scattering}" }}"#
        );
        let text = floor_scene(&interior, 1024).replace("max_depth = 2", "max_depth = 6");
        let scene = compile(&d, &text);
        assert!(scene.features.emissive_volume_lights, "{scattering}");
        let out = render_with_technique(&scene, LightingTechnique::Mis);
        assert!(out.stats.counters.volume_events[VolumeEvent::LightSample as usize] > 0);
        let mis = image_mean(&out);
        let uni = image_mean(&render_with_technique(&scene, LightingTechnique::BxdfOnly));
        let nee = image_mean(&render_with_technique(&scene, LightingTechnique::NeeOnly));
        assert_agree(&format!("{scattering}: mis vs bxdf"), mis, uni);
        assert_agree(&format!("{scattering}: nee vs bxdf"), nee, uni);
    }
}

/// A scattering medium whose emission is a spatially varying pattern (a hot layer along y,
/// coloured): MIS with light samples of the pattern emitter equals unidirectional
/// estimation, and so does NEE alone.
#[test]
fn a_scattering_pattern_emitter_under_mis_equals_unidirectional_estimation() {
    let d = scratch_dir("vlights", "pattern-grid");
    let interior = r#"{ type = "heterogeneous", density = { pattern = "gradient", axis = "y", from = 0.5, to = 1.5, a = 2, b = 0.5 }, scale = 2, albedo = 0.6, emission = { pattern = "multiply", a = { pattern = "gradient", axis = "y", from = 0.6, to = 1.2, a = 4, b = 0 }, b = [1.5, 0.75, 0.25] }, majorant_grid = 4 }"#;
    let text = floor_scene(interior, 1024).replace("max_depth = 2", "max_depth = 6");
    let scene = compile(&d, &text);
    assert!(scene.features.emissive_volume_lights);
    let out = render_with_technique(&scene, LightingTechnique::Mis);
    assert!(out.stats.counters.volume_events[VolumeEvent::LightSample as usize] > 0);
    assert_eq!(out.stats.counters.majorant_violations, 0);
    let mis = image_mean(&out);
    let uni = image_mean(&render_with_technique(&scene, LightingTechnique::BxdfOnly));
    let nee = image_mean(&render_with_technique(&scene, LightingTechnique::NeeOnly));
    assert_agree("mis vs bxdf", mis, uni);
    assert_agree("nee vs bxdf", nee, uni);
}

/// Writes a Mitsuba `.vol` grid of `n^3` voxels `f(x, y, z)` (voxel centres in the unit cube).
fn write_vol(path: &Path, n: usize, f: impl Fn(f32, f32, f32) -> f32) {
    let mut b = b"VOL\x03".to_vec();
    for v in [1i32, n as i32, n as i32, n as i32, 1] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    let c = |i: usize| (i as f32 + 0.5) / n as f32;
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                b.extend_from_slice(&f(c(x), c(y), c(z)).to_le_bytes());
            }
        }
    }
    std::fs::write(path, b).unwrap();
}

/// Asserts two renders' image means agree within 3 combined standard errors per channel.
fn assert_agree(what: &str, a: (Rgb, Rgb), b: (Rgb, Rgb)) {
    let ((ma, sa), (mb, sb)) = (a, b);
    for (c, (x, y, s)) in [
        (ma.r, mb.r, (sa.r.powi(2) + sb.r.powi(2)).sqrt()),
        (ma.g, mb.g, (sa.g.powi(2) + sb.g.powi(2)).sqrt()),
        (ma.b, mb.b, (sa.b.powi(2) + sb.b.powi(2)).sqrt()),
    ]
    .into_iter()
    .enumerate()
    {
        assert!(
            s < 0.03 * x.abs().max(y.abs()),
            "{what} channel {c}: se {s} of {x}"
        );
        assert!(
            (x - y).abs() <= 3.0 * s,
            "{what} channel {c}: {x} vs {y} (se {s})"
        );
    }
}

#[test]
fn a_scattering_grid_emitter_under_mis_equals_unidirectional_estimation() {
    let d = scratch_dir("vlights", "grid");
    // A density falling off along y and a hot spot of emission near one corner; the medium
    // scatters (albedo 0.6), so volume-scatter vertices light-sample it too.
    write_vol(&d.join("density.vol"), 8, |_, y, _| 0.5 + 1.5 * (1.0 - y));
    write_vol(&d.join("heat.vol"), 8, |x, y, z| {
        let r2 = (x - 0.3).powi(2) + (y - 0.3).powi(2) + (z - 0.6).powi(2);
        (-r2 / 0.05).exp()
    });
    let interior = "{ type = \"heterogeneous\", density = { grid = \"density.vol\" }, \
                    scale = 2, albedo = 0.6, emission = { grid = \"heat.vol\", scale = [6, 3, 1] }, \
                    majorant_grid = 4 }";
    let mut text = floor_scene(interior, 1024);
    text = text.replace("max_depth = 2", "max_depth = 6");
    let scene = compile(&d, &text);
    assert!(scene.features.emissive_volume_lights);
    let mis = image_mean(&render_with_technique(&scene, LightingTechnique::Mis));
    let uni = image_mean(&render_with_technique(&scene, LightingTechnique::BxdfOnly));
    let nee = image_mean(&render_with_technique(&scene, LightingTechnique::NeeOnly));
    assert_agree("mis vs bxdf", mis, uni);
    assert_agree("nee vs bxdf", nee, uni);
}

#[test]
fn a_scene_without_emissive_media_has_no_volume_lights() {
    let d = scratch_dir("vlights", "none");
    constant_vol(&d.join("one.vol"), [2, 2, 2], 1.0);
    let interior = "{ type = \"heterogeneous\", density = { grid = \"one.vol\" }, scale = 1, \
                    albedo = 0.5 }";
    let scene = compile(&d, &floor_scene(interior, 1));
    assert!(!scene.features.emissive_volume_lights);
    assert!(!scene
        .features
        .names()
        .iter()
        .any(|n| n == "emissive_volume_lights"));
    assert!(scene.volume_light.iter().all(|&l| l == u32::MAX));
}

/// Behind a dielectric, path rays refract (a Dirac event) and shadow rays cannot pass
/// straight through, so an emissive medium there is no light (module docs of
/// `risotto_engine::plugin::volume_light`): the scene has no volume light, MIS draws no volume
/// light sample, and its image agrees with unidirectional estimation.
#[test]
fn an_emissive_medium_behind_a_dielectric_is_no_light() {
    let d = scratch_dir("vlights", "dielectric");
    for interior in [
        r#"{ type = "homogeneous", sigma_t = 1.5, albedo = 0.5, emission = 2 }"#,
        r#"{ type = "heterogeneous", density = { constant = 1 }, scale = 1.5, albedo = 0.5, emission = 2 }"#,
    ] {
        let text = floor_scene(interior, 256)
            .replace("type = \"interface\"", "type = \"dielectric\"\nior = 1.5")
            .replace("max_depth = 2", "max_depth = 8");
        assert!(text.contains("ior = 1.5"));
        let scene = compile(&d, &text);
        assert!(!scene.features.emissive_volume_lights, "{interior}");
        assert!(scene.volume_light.iter().all(|&l| l == u32::MAX));
        // No light subpath can start in it: light tracing alone does not converge.
        assert!(scene.features.emissive_media_without_lights);
        let features = Features {
            transmissive: false,
            ..scene.features
        };
        assert!(!light_tracing_converges(&features));
        let out = render_with_technique(&scene, LightingTechnique::Mis);
        assert_eq!(
            out.stats.counters.volume_events[VolumeEvent::LightSample as usize],
            0
        );
        let mis = image_mean(&out);
        let uni = image_mean(&render_with_technique(&scene, LightingTechnique::BxdfOnly));
        assert_agree(&format!("{interior}: mis vs bxdf"), mis, uni);
    }
}

/// The homogeneous emitter's point estimator at extreme densities: a box of extinction
/// 1e-3 (about one comb point per crossing, from the rate's floor) and 1e3 (thousands of
/// mean free paths across; the sum stops where the transmittance falls below 1e-12), with
/// `j = 2 sigma_t` so that the box glows with about `2 (1 - T)`. No sample is dropped as
/// NaN, and MIS, `bdpt` and `vcm` agree with unidirectional estimation.
#[test]
fn homogeneous_emitters_stay_finite_and_unbiased_at_extreme_densities() {
    let d = scratch_dir("vlights", "homogeneous-extreme");
    for sigma in [1e-3f32, 1e3] {
        let j = 2.0 * sigma;
        let interior = format!(
            r#"{{ type = "homogeneous", sigma_t = {sigma}, albedo = 0.5, emission = {j} }}"#
        );
        let scene = compile(&d, &floor_scene(&interior, 1024));
        assert!(scene.features.emissive_volume_lights, "sigma_t {sigma}");
        let mis_out = render_with_technique(&scene, LightingTechnique::Mis);
        let uni_out = render_with_technique(&scene, LightingTechnique::BxdfOnly);
        for out in [&mis_out, &uni_out] {
            assert_eq!(out.stats.counters.nan_dropped, 0, "sigma_t {sigma}");
        }
        assert_agree(
            &format!("sigma_t {sigma}: mis vs bxdf"),
            image_mean(&mis_out),
            image_mean(&uni_out),
        );
        // The bidirectional integrators, whose light subpaths start in the medium and whose
        // weights take its majorant for a cosine: finite at both extremes, and unbiased.
        for integrator in [GlobalIntegrator::Bdpt, GlobalIntegrator::Vcm] {
            let out = render_with_integrator(&scene, integrator);
            assert_agree(
                &format!("sigma_t {sigma}: {integrator:?} vs bxdf"),
                image_mean(&out),
                image_mean(&uni_out),
            );
        }
    }
}

fn render_with_integrator(scene: &CompiledScene, integrator: GlobalIntegrator) -> RenderOutput {
    let options = RenderOptions {
        integrator: Some(integrator),
        ..RenderOptions::default()
    };
    let out = render(scene, &options, &|_| {}).unwrap();
    let c = &out.stats.counters;
    assert_eq!(c.nan_dropped, 0, "{integrator:?}: NaN samples");
    assert!(
        c.non_finite.iter().all(|&n| n == 0),
        "{integrator:?}: non-finite values by stage {:?}",
        c.non_finite
    );
    assert_finite("render", &out);
    out
}

/// The bidirectional integrators sample an emissive medium as a light too (issue 34):
/// light subpaths start in it, camera vertices light-sample it and connect to those
/// subpaths, and what the camera subpaths' rays gather in it is weighed against them all
/// (`engine/core/src/bidir/volume_emission.rs`). On the floor under the uniform box, `bdpt`
/// and `vcm` give the brute-force integral, and at equal spp `bdpt` is more precise than
/// the collision estimator alone (which is all it had while media were no lights to it:
/// then the ratio was 1).
#[test]
fn bidirectional_integrators_light_a_floor_from_an_emissive_box() {
    let d = scratch_dir("vlights", "bidir-box");
    constant_vol(&d.join("one.vol"), [2, 2, 2], 1.0);
    let (j, sigma_a) = (2.0, 1.5);
    let want = expected_floor_radiance(j, sigma_a);
    for interior in [
        format!(
            "{{ type = \"heterogeneous\", density = {{ grid = \"one.vol\" }}, scale = {sigma_a}, \
             albedo = 0, emission = {j}, majorant_grid = 2 }}"
        ),
        format!(
            r#"{{ type = "homogeneous", sigma_t = {sigma_a}, albedo = 0, emission = {j}, scattering = "bounce" }}"#
        ),
        format!(
            r#"{{ type = "homogeneous", sigma_t = {sigma_a}, albedo = 0, emission = {j}, scattering = "walk" }}"#
        ),
    ] {
        let scene = compile(&d, &floor_scene(&interior, 512));
        let collision = image_mean(&render_with_technique(&scene, LightingTechnique::BxdfOnly)).1;
        for integrator in [GlobalIntegrator::Bdpt, GlobalIntegrator::Vcm] {
            let out = render_with_integrator(&scene, integrator);
            let (mean, se) = image_mean(&out);
            assert_brute_force(&format!("{interior} {integrator:?}"), (mean, se), want);
            if integrator == GlobalIntegrator::Bdpt {
                assert!(
                    se.r < 0.8 * collision.r,
                    "{interior}: se bdpt {} vs the collision estimator's {}",
                    se.r,
                    collision.r
                );
            }
        }
    }
}

/// The box seen from above and beside (a pinhole camera sees it and the floor around it),
/// for light tracing, which splats wherever its subpaths land.
fn overview_scene(interior: &str, spp: u32, max_depth: u32) -> String {
    floor_scene(interior, spp)
        .replace("max_depth = 2", &format!("max_depth = {max_depth}"))
        .replace(
            r#"projection = "orthographic"
width = 0.02
from = [2, 0.3, 0]
to = [0, 0, 0]
up = [0, 1, 0]"#,
            r#"projection = "perspective"
fov = 50
from = [0, 3.5, 3]
to = [0, 0.3, 0]
up = [0, 1, 0]"#,
        )
}

/// Every integrator renders the floor and the glow of an emissive medium alike: light
/// tracing (whose floor was black before emissive media were lights to it: nothing
/// started in them), `bdpt` and `vcm` against the path tracer, for an absorbing box and a
/// scattering, chromatic one, whose points bounce back to the integrator or walk (light
/// subpaths whose first segment walked are the camera subpaths' alone, `volume_emission.rs`).
#[test]
fn every_integrator_agrees_on_the_light_of_an_emissive_medium() {
    let d = scratch_dir("vlights", "bidir-overview");
    let cases = [
        (
            r#"{ type = "homogeneous", sigma_t = 1.5, albedo = 0, emission = 2, scattering = "bounce" }"#,
            2,
        ),
        (
            r#"{ type = "homogeneous", sigma_t = [1, 2, 4], albedo = 0.7, emission = [3, 1.5, 0.5], phase = { type = "hg", g = 0.4 }, scattering = "bounce" }"#,
            5,
        ),
        (
            r#"{ type = "homogeneous", sigma_t = [1, 2, 4], albedo = 0.7, emission = [3, 1.5, 0.5], phase = { type = "hg", g = 0.4 }, scattering = "walk" }"#,
            5,
        ),
    ];
    for (interior, max_depth) in cases {
        let scene = compile(&d, &overview_scene(interior, 1024, max_depth));
        assert!(scene.features.emissive_volume_lights);
        assert!(!scene.features.emissive_media_without_lights);
        // `risotto techniques` lists `light` as converging here but for the box's
        // boundary (any surface rays cross counts as one a light vertex may not see the
        // camera through).
        let features = Features {
            transmissive: false,
            ..scene.features
        };
        assert!(light_tracing_converges(&features));
        let path = image_mean(&render_with_technique(&scene, LightingTechnique::Mis));
        for integrator in [
            GlobalIntegrator::Light,
            GlobalIntegrator::Bdpt,
            GlobalIntegrator::Vcm,
        ] {
            let out = render_with_integrator(&scene, integrator);
            assert_agree(
                &format!("{interior} {integrator:?}"),
                image_mean(&out),
                path,
            );
        }
    }
}

/// Whether `risotto techniques` lists `integrator = light` as converging on a scene with
/// `features`.
fn light_tracing_converges(features: &Features) -> bool {
    let light = risotto::engine::technique::INTEGRATOR
        .values
        .iter()
        .find(|v| v.name == "light")
        .unwrap();
    (light.converges)(features)
}

/// Each strategy alone (`Bidirectional::alone`) makes the paths through an emissive medium
/// that the path tracer does: on the floor beside the absorbing box, the paths of two
/// segments (camera, floor, a point of the medium) by the camera subpath gathering the
/// emission along its second ray `(0, 3)`, by next-event estimation of the volume light
/// `(1, 2)` and by light tracing from a point of the medium `(2, 1)`, each unweighted,
/// against the path tracer's `max_depth = 2` image minus its `max_depth = 1` image.
#[test]
fn each_strategy_alone_lights_the_floor_from_the_medium() {
    use risotto::engine::bidir::{Bidirectional, Strategy, StrategyAlone};
    let d = scratch_dir("vlights", "bidir-alone");
    let interior = r#"{ type = "homogeneous", sigma_t = 1.5, albedo = 0, emission = 2, scattering = "bounce" }"#;
    let scene_at = |max_depth, seed: u32| {
        let text = overview_scene(interior, 1024, max_depth)
            .replace("spp = 1024", &format!("spp = 1024\nseed = {seed}"));
        compile(&d, &text)
    };
    let two = image_mean(&render_with_technique(
        &scene_at(2, 1),
        LightingTechnique::Mis,
    ));
    let one = image_mean(&render_with_technique(
        &scene_at(1, 2),
        LightingTechnique::Mis,
    ));
    let want = (
        two.0 - one.0,
        (two.1 * two.1 + one.1 * one.1).map(f32::sqrt),
    );
    let scene = scene_at(2, 3);
    for (s, t) in [(0, 3), (1, 2), (2, 1)] {
        let mut bd = Bidirectional::new(&scene, Strategy::Bdpt, Default::default(), 64).unwrap();
        bd.alone = Some(StrategyAlone {
            light_vertices: s,
            camera_vertices: t,
        });
        let out = render_with(&bd, &scene, &RenderOptions::default(), &|_| {}).unwrap();
        assert_eq!(out.stats.counters.nan_dropped, 0);
        assert_agree(&format!("({s}, {t})"), image_mean(&out), want);
    }
}
