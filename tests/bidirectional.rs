//! The bidirectional global integrators (`integrator = light | bdpt | vcm`,
//! `engine/core/src/bidir/`)
//! against things that are not themselves: the Mitsuba 3 references of
//! `tests/mitsuba_reference.rs` (its scenes, at 64x64) and the path tracer.
//!
//! Noise: the splats of light subpaths are not in the film's variance layer (render.rs,
//! `add_splats`), so every estimate here is two renders with different seeds, and its noise
//! is measured from their difference: the variance of the pair's mean in a pixel is
//! `(a - b)^2 / 4` (one degree of freedom per pixel; 64 per 8x8 block). The pooled channel
//! mean takes the larger of the per-pixel sum and the sum over 8x8 blocks of the blocks'
//! differences (which also counts pixels correlated by one light subpath's splats).
//!
//! A match is: every channel's image mean within `4 sigma` of the reference's (sigma from
//! both sides' noise), with a floor of 0.3 % (the path tracer's own agreement with these
//! references) and never looser than 2 % (a render whose noise would allow more fails as
//! too noisy); and every 8x8 block's z-score below 4.5 (64 blocks x 3 channels: ~1e-3
//! chance of a false failure per image under pure noise).
//!
//! Cost (release, 2 cores, measured when written): the whole file runs in 6.5 to 7.6 s of
//! wall time (the tests two at a time, each render on every core); the Mitsuba comparisons
//! are most of it (`bdpt_matches_mitsuba` about 6 s: 12 scenes, two renders each at
//! 64x64 and 8 to 128 spp per render, `smoke_homog`, `hg_sphere` and `spot` the dearest).

mod common;

use risotto::engine::integrator::GlobalIntegrator;
use risotto::engine::output::{read_exr_rgb, Image};
use risotto::engine::render::{render, NoiseTarget, RenderOptions, RenderOutput, StoppingRule};
use risotto::engine::scene::CompiledScene;
use risotto::loader::load::{scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::load_scene;
use std::path::Path;

/// The root of the repository.
fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// `scenes/mitsuba-suite/NAME.toml` at `size x size`, `spp`, `seed` and (when given)
/// `max_depth`.
fn suite_scene(
    name: &str,
    size: u32,
    spp: u32,
    seed: u64,
    max_depth: Option<u32>,
) -> CompiledScene {
    scene_at(
        &format!("scenes/mitsuba-suite/{name}.toml"),
        size,
        spp,
        seed,
        max_depth,
    )
}

/// The scene file `path` (from the repository's root) at `size x size`, `spp`, `seed` and
/// (when given) `max_depth`.
fn scene_at(path: &str, size: u32, spp: u32, seed: u64, max_depth: Option<u32>) -> CompiledScene {
    let mut desc = load_scene(&root().join(path)).unwrap();
    desc.render.width = size;
    desc.render.height = size;
    desc.render.spp = spp;
    desc.render.seed = seed;
    if let Some(d) = max_depth {
        desc.render.max_depth = d;
    }
    scene_from_desc(desc, &MaterialRegistry::with_builtins())
        .unwrap()
        .compile()
        .unwrap()
}

/// Renders `scene` with `integrator` on `threads` (all cores when `None`).
fn run(
    scene: &CompiledScene,
    integrator: GlobalIntegrator,
    threads: Option<usize>,
) -> RenderOutput {
    let options = RenderOptions {
        integrator: Some(integrator),
        threads,
        ..RenderOptions::default()
    };
    render(scene, &options, &|_| {}).unwrap()
}

/// Asserts that nothing non-finite reached the film or was dropped on the way.
fn assert_no_nan(what: &str, out: &RenderOutput) {
    let c = &out.stats.counters;
    assert_eq!(c.nan_dropped, 0, "{what}: NaN samples dropped");
    assert!(
        c.non_finite.iter().all(|&n| n == 0),
        "{what}: non-finite values by stage {:?}",
        c.non_finite
    );
    common::assert_finite(what, out);
}

/// An image estimate with its noise: per-pixel means and variances of the means, and the
/// variance of each channel's image mean.
struct Estimate {
    width: usize,
    height: usize,
    mean: Vec<[f64; 3]>,
    var: Vec<[f64; 3]>,
    mean_var: [f64; 3],
}

impl Estimate {
    /// The mean of two independent renders, its noise measured from their difference.
    fn pair(a: &RenderOutput, b: &RenderOutput) -> Estimate {
        let (width, height) = (a.beauty.width, a.beauty.height);
        let px = |o: &RenderOutput, k: usize| o.beauty.pixels[k].to_array().map(|v| v as f64);
        let mut mean = Vec::with_capacity(width * height);
        let mut var = Vec::with_capacity(width * height);
        for k in 0..width * height {
            let (pa, pb) = (px(a, k), px(b, k));
            mean.push([0, 1, 2].map(|c| 0.5 * (pa[c] + pb[c])));
            var.push([0, 1, 2].map(|c| 0.25 * (pa[c] - pb[c]).powi(2)));
        }
        // Variance of the image sum: per pixel, and per 8x8 block of differences.
        let n = (width * height) as f64;
        let mut per_pixel = [0.0f64; 3];
        for v in &var {
            (0..3).for_each(|c| per_pixel[c] += v[c]);
        }
        let mut per_block = [0.0f64; 3];
        for_blocks(width, height, |pixels| {
            let mut d = [0.0f64; 3];
            for k in pixels {
                let (pa, pb) = (px(a, k), px(b, k));
                (0..3).for_each(|c| d[c] += pa[c] - pb[c]);
            }
            (0..3).for_each(|c| per_block[c] += 0.25 * d[c] * d[c]);
        });
        let mean_var = [0, 1, 2].map(|c| per_pixel[c].max(per_block[c]) / (n * n));
        Estimate {
            width,
            height,
            mean,
            var,
            mean_var,
        }
    }

    /// A reference image whose pixels have the noise `noise` (standard deviation).
    fn reference(image: &Image, noise: f64) -> Estimate {
        let n = image.pixels.len();
        Estimate {
            width: image.width,
            height: image.height,
            mean: image
                .pixels
                .iter()
                .map(|p| p.to_array().map(|v| v as f64))
                .collect(),
            var: vec![[noise * noise; 3]; n],
            mean_var: [noise * noise / n as f64; 3],
        }
    }

    /// Each channel's image mean.
    fn channel_means(&self) -> [f64; 3] {
        let n = self.mean.len() as f64;
        [0, 1, 2].map(|c| self.mean.iter().map(|p| p[c]).sum::<f64>() / n)
    }
}

/// Calls `f` with the pixel indices of each 8x8 block of a `width x height` image.
fn for_blocks(width: usize, height: usize, mut f: impl FnMut(Vec<usize>)) {
    for by in (0..height).step_by(8) {
        for bx in (0..width).step_by(8) {
            let pixels = (by..(by + 8).min(height))
                .flat_map(|y| (bx..(bx + 8).min(width)).map(move |x| y * width + x))
                .collect();
            f(pixels);
        }
    }
}

/// The least standard deviation of an 8x8 block's difference, relative to the block's
/// reference value: where our renders are nearly noiseless (an environment seen directly,
/// a lit wall of a thin medium) the path tracer itself differs from the Mitsuba references
/// by up to 0.7 % per block (envmap_rotated's sky: the maps' bilinear lattices; hetero_grid
/// 0.2 %, glass_beer 0.08 %), far above its noise (block |z| 6 to 21 with the path tracer
/// through this same check, measured when written).
const BLOCK_FLOOR_RELATIVE: f64 = 0.005;

/// The least standard deviation of an 8x8 block's mean difference, absolute: a block whose
/// reference is a trace of light (5e-7 in `hg_sphere`'s corner) where both our renders
/// are exactly 0.
const BLOCK_FLOOR_ABSOLUTE: f64 = 1e-5;

/// How far apart two estimates are, in their noise.
#[derive(Debug)]
struct Verdict {
    /// Relative difference of each channel's image mean.
    mean_rel: [f64; 3],
    /// The allowed relative difference: 4 sigma, at least 0.3 %.
    tolerance: [f64; 3],
    /// The largest |z| over 8x8 blocks and channels.
    max_block_z: f64,
}

impl Verdict {
    fn of(test: &Estimate, reference: &Estimate) -> Verdict {
        assert_eq!(
            (test.width, test.height),
            (reference.width, reference.height)
        );
        let (mt, mr) = (test.channel_means(), reference.channel_means());
        let mean_rel = [0, 1, 2].map(|c| (mt[c] - mr[c]) / mr[c]);
        let tolerance = [0, 1, 2]
            .map(|c| (4.0 * (test.mean_var[c] + reference.mean_var[c]).sqrt() / mr[c]).max(0.003));
        let mut max_block_z = 0.0f64;
        for_blocks(test.width, test.height, |pixels| {
            for c in 0..3 {
                let (mut d, mut v, mut m) = (0.0, 0.0, 0.0);
                for &k in &pixels {
                    d += test.mean[k][c] - reference.mean[k][c];
                    v += test.var[k][c] + reference.var[k][c];
                    m += reference.mean[k][c];
                }
                v += (BLOCK_FLOOR_RELATIVE * m).powi(2)
                    + (BLOCK_FLOOR_ABSOLUTE * pixels.len() as f64).powi(2);
                let z = if v > 0.0 {
                    d / v.sqrt()
                } else if d.abs() < 1e-9 {
                    0.0
                } else {
                    f64::INFINITY
                };
                max_block_z = max_block_z.max(z.abs());
            }
        });
        Verdict {
            mean_rel,
            tolerance,
            max_block_z,
        }
    }

    /// Whether the noise allows a check at 2 %.
    fn tight_enough(&self) -> bool {
        self.tolerance.iter().all(|&t| t <= 0.02)
    }

    /// Whether the two estimates agree within noise.
    fn matches(&self) -> bool {
        (0..3).all(|c| self.mean_rel[c].abs() <= self.tolerance[c]) && self.max_block_z < 4.5
    }
}

/// Two renders (seeds 1 and 2) of suite scene `name` with `integrator`, both checked for
/// non-finite values.
fn estimate(
    name: &str,
    integrator: GlobalIntegrator,
    size: u32,
    spp: u32,
    max_depth: Option<u32>,
) -> (Estimate, RenderOutput) {
    let a = run(
        &suite_scene(name, size, spp, 1, max_depth),
        integrator,
        None,
    );
    let b = run(
        &suite_scene(name, size, spp, 2, max_depth),
        integrator,
        None,
    );
    let what = format!("{name} ({})", integrator.name());
    assert_no_nan(&what, &a);
    assert_no_nan(&what, &b);
    (Estimate::pair(&a, &b), a)
}

/// The Mitsuba reference of suite scene `name` (64x64), its per-pixel noise `noise`.
fn mitsuba(name: &str, noise: f64) -> Estimate {
    let image = read_exr_rgb(&root().join(format!("tests/data/{name}-mitsuba-64.exr"))).unwrap();
    Estimate::reference(&image, noise)
}

/// Checks `integrator` at `spp` (two renders of half each) on suite scene `name` against
/// its Mitsuba reference (per-pixel noise `ref_noise`); `Err` says how it fails.
fn check_mitsuba(
    name: &str,
    integrator: GlobalIntegrator,
    spp: u32,
    ref_noise: f64,
) -> Result<(), String> {
    let t = std::time::Instant::now();
    let (est, out) = estimate(name, integrator, 64, spp / 2, None);
    if !out.stats.warnings.is_empty() {
        return Err(format!("{name}: warnings {:?}", out.stats.warnings));
    }
    let v = Verdict::of(&est, &mitsuba(name, ref_noise));
    eprintln!(
        "{name} {} {spp} spp: {v:?} ({:.2} s)",
        integrator.name(),
        t.elapsed().as_secs_f64()
    );
    if !v.tight_enough() {
        return Err(format!("{name}: too noisy to check at 2 %: {v:?}"));
    }
    if !v.matches() {
        return Err(format!(
            "{name}: {} differs from Mitsuba: {v:?}",
            integrator.name()
        ));
    }
    Ok(())
}

/// Checks every `(scene, spp, reference noise)` of `cases` with `integrator`; fails with
/// every mismatch.
fn check_all(integrator: GlobalIntegrator, cases: &[(&str, u32, f64)]) {
    let failures: Vec<String> = cases
        .iter()
        .filter_map(|&(name, spp, noise)| check_mitsuba(name, integrator, spp, noise).err())
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The reference noise of `subsurface_like` per 64x64 pixel (896 spp reference: see
/// `tests/mitsuba_reference.rs`); the other references' noise is negligible here.
const SUBSURFACE_REF_NOISE: f64 = 0.0054;

/// The reference noise of `furnace` per 64x64 pixel (every pixel is exactly 1 in
/// expectation; the reference deviates by 0.00098: `tests/mitsuba_reference.rs`).
const FURNACE_REF_NOISE: f64 = 0.001;

/// The seven scenes of the Mitsuba harness and the lights and surfaces the bidirectional
/// integrators treat specially: a spot (a Dirac position), a distant light with vertex
/// normals (`uv_sphere`), a rotated environment map, a thin pane and rough glass.
#[test]
fn bdpt_matches_mitsuba() {
    check_all(
        GlobalIntegrator::Bdpt,
        &[
            ("cornell", 32, 0.0),
            ("furnace", 16, FURNACE_REF_NOISE),
            ("glass_beer", 32, 0.0),
            ("hetero_grid", 32, 0.0),
            ("hg_sphere", 160, 0.0),
            ("smoke_homog", 16, 0.0),
            ("subsurface_like", 32, SUBSURFACE_REF_NOISE),
            ("spot", 256, 0.0),
            ("uv_sphere", 32, 0.0),
            ("envmap_rotated", 32, 0.0),
            ("thin_pane", 32, 0.0),
            ("rough_glass", 64, 0.0),
        ],
    );
}

/// Vertex connection and merging: bdpt plus merging, which must not move the mean beyond
/// noise (at these spp the merge radius is still at its first iterations' size, so this
/// also bounds its bias here).
#[test]
fn vcm_matches_mitsuba() {
    check_all(
        GlobalIntegrator::Vcm,
        &[
            ("cornell", 32, 0.0),
            ("glass_beer", 32, 0.0),
            ("hetero_grid", 32, 0.0),
            ("smoke_homog", 16, 0.0),
            ("spot", 256, 0.0),
            ("uv_sphere", 32, 0.0),
            ("rough_glass", 64, 0.0),
        ],
    );
}

/// Light tracing alone reaches the camera only from vertices with a non-Dirac lobe: it
/// cannot render what the camera sees through smooth glass or in a mirror (`glass_beer`,
/// `subsurface_like`'s dielectric sphere, `envmap_rotated`'s mirror sphere, `thin_pane`),
/// so those are checked to fail (below). The rest must match.
#[test]
fn light_tracing_matches_mitsuba() {
    check_all(
        GlobalIntegrator::Light,
        &[
            ("cornell", 32, 0.0),
            ("furnace", 16, FURNACE_REF_NOISE),
            ("hetero_grid", 160, 0.0),
            ("smoke_homog", 16, 0.0),
            ("spot", 256, 0.0),
            ("uv_sphere", 32, 0.0),
        ],
    );
}

/// The check can fail: light tracing misses the camera's view through a smooth pane (the
/// walls behind `thin_pane`'s pane), by far more than the noise.
#[test]
fn light_tracing_through_a_smooth_pane_does_not_match() {
    let (est, _) = estimate("thin_pane", GlobalIntegrator::Light, 64, 8, None);
    let v = Verdict::of(&est, &mitsuba("thin_pane", 0.0));
    eprintln!("thin_pane light: {v:?}");
    assert!(!v.matches(), "{v:?}");
    assert!(v.mean_rel.iter().all(|&d| d < -0.1), "{v:?}");
}

/// Light tracing alone against the path tracer on a diffuse scene lit by an area light,
/// where light subpaths reach every camera vertex: direct lighting only (`max_depth` 2) and
/// up to 7 bounces (8).
#[test]
fn light_tracing_matches_the_path_tracer_on_cornell() {
    for depth in [2, 8] {
        let (light, _) = estimate("cornell", GlobalIntegrator::Light, 32, 64, Some(depth));
        let (path, _) = estimate("cornell", GlobalIntegrator::Path, 32, 64, Some(depth));
        let v = Verdict::of(&light, &path);
        eprintln!("cornell max_depth {depth}, light vs path: {v:?}");
        assert!(v.tight_enough(), "max_depth {depth}: {v:?}");
        assert!(v.matches(), "max_depth {depth}: {v:?}");
    }
    // The check can fail: depth 2 against depth 8 (the indirect light, about a third of
    // the cornell box's) is told apart.
    let (direct, _) = estimate("cornell", GlobalIntegrator::Light, 32, 32, Some(2));
    let (all, _) = estimate("cornell", GlobalIntegrator::Path, 32, 32, Some(8));
    assert!(!Verdict::of(&direct, &all).matches());
}

/// The splat film sums in fixed point, so the order in which threads add their light
/// subpaths does not change a bit.
#[test]
fn bdpt_renders_the_same_bits_on_one_and_two_threads() {
    for name in ["cornell", "smoke_homog"] {
        let scene = suite_scene(name, 32, 4, 0, None);
        let one = run(&scene, GlobalIntegrator::Bdpt, Some(1));
        let two = run(&scene, GlobalIntegrator::Bdpt, Some(2));
        assert!(
            beauty_bits(&one) == beauty_bits(&two),
            "{name}: 1 and 2 threads differ"
        );
    }
}

/// The beauty's bits.
fn beauty_bits(o: &RenderOutput) -> Vec<[u32; 3]> {
    o.beauty
        .pixels
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

/// `vcm` merges at every camera vertex the light vertices of its whole iteration (one light
/// subpath per camera sample of the iteration, traced by a light pass before any camera
/// subpath), not only those of its own batch: so how the iteration is cut into batches,
/// tiles and threads changes no bit. (With merging per batch, the batch size set how many
/// light subpaths a merge saw, `N_L` of its kernel and weights, and so the image.) And
/// merging does something: the image differs from `bdpt`'s.
#[test]
fn vcm_merges_the_light_vertices_of_the_whole_iteration() {
    let scene = suite_scene("cornell", 32, 4, 0, None);
    let render_cut = |integrator, batch_size, tile_size, threads| {
        let options = RenderOptions {
            integrator: Some(integrator),
            threads: Some(threads),
            batch_size,
            tile_size,
            ..RenderOptions::default()
        };
        render(&scene, &options, &|_| {}).unwrap()
    };
    let whole = render_cut(GlobalIntegrator::Vcm, 4096, 32, 1);
    assert_no_nan("vcm", &whole);
    for (batch_size, tile_size, threads) in [(16, 32, 1), (64, 8, 2), (4096, 16, 2)] {
        let cut = render_cut(GlobalIntegrator::Vcm, batch_size, tile_size, threads);
        assert!(
            beauty_bits(&cut) == beauty_bits(&whole),
            "batches of {batch_size}, tiles of {tile_size}, {threads} threads"
        );
    }
    let bdpt = render_cut(GlobalIntegrator::Bdpt, 4096, 32, 1);
    assert!(
        beauty_bits(&bdpt) != beauty_bits(&whole),
        "vcm merged nothing"
    );
}

/// `subsurface_like`'s dielectric sphere of dense medium: the bidirectional integrators
/// render it themselves, without a warning (checked in [`bdpt_matches_mitsuba`], which
/// fails on any warning), and bdpt matches Mitsuba. The medium's default
/// `scattering = "multiple"` walks inside the sphere (its boundary blocks shadow rays), and
/// the walk's exits come out through a smooth dielectric, a Dirac boundary no connection
/// uses anyway (compare [`walked_media_render_correctly_or_fall_back`]). The fallback to the path
/// tracer is for subsurface interiors (`type = "subsurface"`, which walk inside the surface
/// in one call, `scenes/subsurface-thin.toml`): it is taken, and said in the stats' warnings.
#[test]
fn subsurface_interiors_fall_back_to_the_path_tracer_with_a_warning() {
    let scene = scene_at("scenes/subsurface-thin.toml", 32, 2, 0, None);
    assert!(
        scene.features.subsurface,
        "the scene has no subsurface interior"
    );
    let small = |integrator| run(&scene, integrator, None);
    let bdpt = small(GlobalIntegrator::Bdpt);
    let path = small(GlobalIntegrator::Path);
    assert!(
        bdpt.stats
            .warnings
            .iter()
            .any(|w| w.contains("integrator bdpt cannot render this scene")
                && w.contains("path tracer rendered it")),
        "{:?}",
        bdpt.stats.warnings
    );
    assert!(
        path.beauty.pixels == bdpt.beauty.pixels,
        "the fallback is not the path tracer's image"
    );
}

/// Adaptive sampling stops pixels, but light subpaths splat onto every pixel: the two do
/// not go together, and asking for both is an error, not a silently wrong image.
#[test]
fn bdpt_with_a_noise_target_is_an_error() {
    let scene = suite_scene("cornell", 16, 4, 0, None);
    for integrator in [GlobalIntegrator::Bdpt, GlobalIntegrator::Light] {
        let options = RenderOptions {
            integrator: Some(integrator),
            noise_target: Some(NoiseTarget {
                relative_error: 0.05,
                min_spp: 2,
                rule: StoppingRule::Window,
            }),
            ..RenderOptions::default()
        };
        let err = render(&scene, &options, &|_| {})
            .err()
            .unwrap_or_else(|| panic!("{} with a noise target rendered", integrator.name()))
            .to_string();
        assert!(
            err.contains("noise target") && err.contains(integrator.name()),
            "{err}"
        );
    }
}

/// `integrator = "bdpt"` in a scene file's `[render]` renders with bdpt: the same bits as
/// asking for it in the options, and not the path tracer's.
#[test]
fn the_scene_files_integrator_is_used() {
    let dir = common::scratch_dir("bidirectional", "scene_file_integrator");
    let text = std::fs::read_to_string(root().join("scenes/mitsuba-suite/cornell.toml"))
        .unwrap()
        .replacen("[render]\n", "[render]\nintegrator = \"bdpt\"\n", 1);
    assert!(text.contains("integrator = \"bdpt\""));
    let from_file = common::load_scene_text(&dir, &text).unwrap();
    assert_eq!(from_file.settings.integrator, GlobalIntegrator::Bdpt);
    let options = |integrator| RenderOptions {
        integrator,
        ..RenderOptions::default()
    };
    let mut small =
        risotto::loader::scene_file::parse_scene(&text, &dir.join("scene.toml")).unwrap();
    small.render.width = 32;
    small.render.height = 32;
    small.render.spp = 4;
    let small = scene_from_desc(small, &MaterialRegistry::with_builtins())
        .unwrap()
        .compile()
        .unwrap();
    let by_file = render(&small, &options(None), &|_| {}).unwrap();
    let by_option = render(&small, &options(Some(GlobalIntegrator::Bdpt)), &|_| {}).unwrap();
    let by_path = render(&small, &options(Some(GlobalIntegrator::Path)), &|_| {}).unwrap();
    assert!(by_file.beauty.pixels == by_option.beauty.pixels);
    assert!(by_file.beauty.pixels != by_path.beauty.pixels);
}

/// A medium whose volume integrator walks every event inside one call
/// (`scattering = "walk"`) returns only the walk's exits: no strategy can connect to its
/// inner scattering points. `bdpt` and `vcm` weight such a walk as a chain of Dirac vertices
/// and must still match Mitsuba; `light`, which sees a medium only through light vertices
/// inside it, must say in its warnings that its rays were walked (and count them).
/// `smoke_homog` with its smoke walked (the path tracer renders it within 0.5 % of
/// Mitsuba: the walk itself is right).
#[test]
fn walked_media_render_correctly_or_say_so() {
    let path = root().join("scenes/mitsuba-suite/smoke_homog.toml");
    let text = std::fs::read_to_string(&path).unwrap().replacen(
        "phase = { type = \"isotropic\" } }",
        "phase = { type = \"isotropic\" }, scattering = \"walk\" }",
        1,
    );
    assert!(text.contains("scattering = \"walk\""));
    let scene = |seed, spp| {
        let mut desc = risotto::loader::scene_file::parse_scene(&text, &path).unwrap();
        desc.render.width = 64;
        desc.render.height = 64;
        desc.render.spp = spp;
        desc.render.seed = seed;
        scene_from_desc(desc, &MaterialRegistry::with_builtins())
            .unwrap()
            .compile()
            .unwrap()
    };
    // The walked smoke is noisier than the bounced one: 40 spp per render for a 2 % check.
    for integrator in [GlobalIntegrator::Bdpt, GlobalIntegrator::Vcm] {
        let outs: Vec<RenderOutput> = [1, 2]
            .map(|seed| run(&scene(seed, 40), integrator, None))
            .into();
        assert!(
            outs[0].stats.counters.walked_subpath_rays > 0,
            "the smoke walked"
        );
        let v = Verdict::of(
            &Estimate::pair(&outs[0], &outs[1]),
            &mitsuba("smoke_homog", 0.0),
        );
        eprintln!("smoke_homog walked, {}: {v:?}", integrator.name());
        assert!(
            v.tight_enough() && v.matches(),
            "{}: {v:?}",
            integrator.name()
        );
    }
    let light = run(&scene(1, 4), GlobalIntegrator::Light, None);
    let walked = light.stats.counters.walked_subpath_rays;
    assert!(walked > 0, "light subpaths walked the smoke");
    assert!(
        light
            .stats
            .warnings
            .iter()
            .any(|w| w.contains(&format!("{walked} rays of light subpaths were walked"))),
        "{:?}",
        light.stats.warnings
    );
}

/// Stages a render does not need never run, and the stats show it: the path tracer runs no
/// `emit`, `connect` or `merge`; `light` and `bdpt` no `merge`; `vcm` all three.
#[test]
fn the_stats_show_which_integrator_stages_ran() {
    use risotto::engine::stats::System;
    let scene = suite_scene("cornell", 16, 4, 1, None);
    let calls = |out: &RenderOutput, s: System| out.stats.counters.systems[s as usize].calls;
    for (integrator, emit, merge) in [
        (GlobalIntegrator::Path, false, false),
        (GlobalIntegrator::Light, true, false),
        (GlobalIntegrator::Bdpt, true, false),
        (GlobalIntegrator::Vcm, true, true),
    ] {
        let out = run(&scene, integrator, Some(1));
        let name = integrator.name();
        assert_eq!(calls(&out, System::Emit) > 0, emit, "{name}: emit");
        assert_eq!(calls(&out, System::Connect) > 0, emit, "{name}: connect");
        assert_eq!(calls(&out, System::Merge) > 0, merge, "{name}: merge");
    }
}

/// `--replay` records the path tracer's paths: with a bidirectional integrator it is an
/// error that says so, and with the path tracer it works.
#[test]
fn replay_says_it_records_the_path_tracer_only() {
    use risotto::engine::replay::replay;
    let scene = suite_scene("cornell", 16, 4, 1, None);
    for integrator in [
        GlobalIntegrator::Light,
        GlobalIntegrator::Bdpt,
        GlobalIntegrator::Vcm,
    ] {
        let options = RenderOptions {
            integrator: Some(integrator),
            ..RenderOptions::default()
        };
        let Err(e) = replay(&scene, &options, 8, 8, 0) else {
            panic!("{}: replay did not refuse", integrator.name());
        };
        let text = e.to_string();
        assert!(
            text.contains("records the path tracer's paths") && text.contains(integrator.name()),
            "{text}"
        );
    }
    let path = RenderOptions {
        integrator: Some(GlobalIntegrator::Path),
        ..RenderOptions::default()
    };
    assert!(replay(&scene, &path, 8, 8, 0).is_ok());
}

/// The variance layer of a bidirectional render holds the light-traced image's noise too
/// (`render/splats.rs`): on cornell at 16 x 16 and 8 spp with independent samples, the
/// variance of each pixel across 8 seeds, pooled over the image but the lamp, is within a
/// quarter of the mean reported variance, for the path tracer, light tracing (nearly all of
/// whose image is splats) and bdpt. Before, the splats' mean was
/// added to the sums alone: light tracing reported about nothing (the camera samples are
/// black but for the lamp), and bdpt less than its camera subpaths' own variance.
#[test]
fn the_variance_layer_measures_the_splats_noise() {
    for integrator in [
        GlobalIntegrator::Path,
        GlobalIntegrator::Light,
        GlobalIntegrator::Bdpt,
    ] {
        // The independent sampler: the variance layer is the iid estimate (stratified
        // samples have less variance than it says).
        let options = RenderOptions {
            integrator: Some(integrator),
            sampler: risotto::systems::independent_sampler::SamplerKind::Independent,
            ..RenderOptions::default()
        };
        let runs: Vec<RenderOutput> = (1..=8)
            .map(|seed| {
                let scene = suite_scene("cornell", 16, 8, seed, None);
                render(&scene, &options, &|_| {}).unwrap()
            })
            .collect();
        let n = runs.len() as f64;
        let (mut measured, mut reported) = (0.0f64, 0.0f64);
        for k in 0..runs[0].beauty.pixels.len() {
            for c in 0..3 {
                let v: Vec<f64> = runs
                    .iter()
                    .map(|o| o.beauty.pixels[k].to_array()[c] as f64)
                    .collect();
                let mean = v.iter().sum::<f64>() / n;
                // Not the lamp (radiance about 17), whose edge pixels' variance would
                // outweigh the rest of the image.
                if mean > 2.0 {
                    continue;
                }
                measured += v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
                reported += runs
                    .iter()
                    .map(|o| o.variance.pixels[k].to_array()[c] as f64)
                    .sum::<f64>()
                    / n;
            }
        }
        let ratio = measured / reported;
        eprintln!(
            "{}: measured / reported variance {ratio:.3} ({measured:.4e} / {reported:.4e})",
            integrator.name()
        );
        assert!(
            (0.75..1.33).contains(&ratio),
            "{}: {ratio}",
            integrator.name()
        );
    }
}

/// Each connection strategy alone and unweighted (`Bidirectional::alone`, the issue's "each
/// strategy alone, MIS off") is an unbiased estimator of the paths it can make. On cornell
/// (diffuse surfaces, one area light, a pinhole camera) every strategy makes every path, so
/// the image of strategy `(s, t)` alone is the path tracer's image of the paths of `s + t -
/// 1` segments: its render at that `max_depth` minus its render at one less (independent
/// seeds). Checked for every strategy of paths of 2 and 3 segments: the camera subpath
/// hitting the light, next-event estimation, the connections and light tracing. A factor
/// wrong in one strategy (an adjoint's cosine, a pdf's measure) shows here, where the MIS
/// sum, which other strategies dominate, can hide it.
#[test]
fn each_strategy_alone_renders_the_paths_of_its_length() {
    use risotto::engine::bidir::{Bidirectional, Strategy, StrategyAlone};
    let cornell = "scenes/mitsuba-suite/cornell.toml";
    let (size, spp) = (32, 1024);
    for k in 2u32..=3 {
        let longer = run(
            &scene_at(cornell, size, spp, 1, Some(k)),
            GlobalIntegrator::Path,
            None,
        );
        let shorter = run(
            &scene_at(cornell, size, spp, 2, Some(k - 1)),
            GlobalIntegrator::Path,
            None,
        );
        let ((ml, sl), (ms, ss)) = (common::image_mean(&longer), common::image_mean(&shorter));
        let scene = scene_at(cornell, size, spp, 3, Some(k));
        for s in 0..=k {
            let t = k + 1 - s;
            let mut bd = Bidirectional::new(
                &scene,
                Strategy::Bdpt,
                Default::default(),
                (size * size) as usize,
            )
            .unwrap();
            bd.alone = Some(StrategyAlone {
                light_vertices: s,
                camera_vertices: t,
            });
            let options = RenderOptions::default();
            let out = risotto::engine::render::render_with(&bd, &scene, &options, &|_| {}).unwrap();
            assert_no_nan(&format!("({s}, {t})"), &out);
            let (m, se) = common::image_mean(&out);
            for (c, (got, e, want, e_want)) in [
                (m.r, se.r, ml.r - ms.r, sl.r.hypot(ss.r)),
                (m.g, se.g, ml.g - ms.g, sl.g.hypot(ss.g)),
                (m.b, se.b, ml.b - ms.b, sl.b.hypot(ss.b)),
            ]
            .into_iter()
            .enumerate()
            {
                let sigma = e.hypot(e_want);
                eprintln!("k {k} ({s}, {t}) channel {c}: {got} +- {e} vs {want} +- {e_want}");
                assert!(
                    sigma < 0.04 * want,
                    "k {k} ({s}, {t}) channel {c}: se {sigma} of {want}"
                );
                assert!(
                    (got - want).abs() <= 4.0 * sigma,
                    "k {k} ({s}, {t}) channel {c}: {got} vs {want} (se {sigma})"
                );
            }
        }
    }
}
