//! Adaptive sampling (`RenderOptions::noise_target`, `render --noise-target`; issue 36) on a
//! scene of very uneven noise: a glass ball of smoke (noisy: light reaches its inside
//! through refraction and scattering) beside diffuse walls lit by a lamp (smooth). Against
//! a long uniform reference:
//! - at equal samples (the adaptive bookkeeping is one pass over the film per pass, so
//!   equal samples is equal time up to that; `--nocapture` prints both times), the
//!   adaptive image's MSE is lower than uniform sampling's;
//! - the pixels it stops are at the target: their measured relative error, RMS over them,
//!   is at most 1.5 times the target (the window rule's is about half of it: a pixel stops
//!   when the worst of its 3 x 3 window is at the target);
//! - the stopping rule's bias stays below 2 % (it is measurable here: see the test);
//! - the unbiased rule's mean agrees with the reference within noise, it too stops pixels
//!   at the target, within a factor of 1.5 either way, and its MSE is about uniform
//!   sampling's at equal samples (no unbiased rule can do much better here: README, and
//!   `examples/adaptive_bound.rs`).

use risotto::engine::render::{
    render, NoiseTarget, RenderOptions, RenderOutput, StoppingRule, Window,
};
use risotto::loader::load::{scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::parse_scene_with;

const SCENE: &str = r#"
[render]
width = 32
height = 24
spp = 64
max_depth = 12

[camera]
from = [0, 1, 4]
to = [0, 0.8, 0]
fov = 45

[materials.wall]
type = "diffuse"
reflectance = 0.6

[materials.lamp]
type = "diffuse"
reflectance = 0

[materials.smoky_glass]
type = "dielectric"
ior = 1.5
interior = { type = "homogeneous", sigma_t = 4, albedo = 0.95 }

[[shapes]]
name = "floor"
type = "quad"
material = "wall"
corner = [-3, 0, -3]
edge1 = [0, 0, 6]
edge2 = [6, 0, 0]

[[shapes]]
name = "back"
type = "quad"
material = "wall"
corner = [-3, 0, -1.5]
edge1 = [6, 0, 0]
edge2 = [0, 4, 0]

[[shapes]]
name = "lamp"
type = "quad"
material = "lamp"
emission = 12
corner = [-0.4, 2.5, -0.4]
edge1 = [0.8, 0, 0]
edge2 = [0, 0, 0.8]

[[shapes]]
name = "ball"
type = "sphere"
material = "smoky_glass"
center = [0.6, 0.6, 0.3]
radius = 0.5
"#;

fn render_with(spp: u32, target: Option<NoiseTarget>) -> (RenderOutput, f64) {
    render_window(spp, target, None)
}

fn render_window(
    spp: u32,
    target: Option<NoiseTarget>,
    crop: Option<Window>,
) -> (RenderOutput, f64) {
    render_interruptible(spp, target, crop, None, &|_| {})
}

fn render_interruptible(
    spp: u32,
    target: Option<NoiseTarget>,
    crop: Option<Window>,
    interrupt: Option<&'static std::sync::atomic::AtomicBool>,
    progress: &(dyn Fn(u64) + Sync),
) -> (RenderOutput, f64) {
    let desc = parse_scene_with(
        SCENE,
        std::path::Path::new("adaptive.toml"),
        &[format!("render.spp={spp}")],
    )
    .unwrap();
    let scene = scene_from_desc(desc, &MaterialRegistry::with_builtins())
        .unwrap()
        .compile()
        .unwrap();
    let options = RenderOptions {
        threads: Some(2),
        noise_target: target,
        crop,
        interrupt,
        ..RenderOptions::default()
    };
    let t = std::time::Instant::now();
    let out = render(&scene, &options, progress).unwrap();
    (out, t.elapsed().as_secs_f64())
}

/// The 4096-spp uniform reference, rendered once for the tests that compare with it.
fn reference() -> &'static RenderOutput {
    static REFERENCE: std::sync::OnceLock<RenderOutput> = std::sync::OnceLock::new();
    REFERENCE.get_or_init(|| render_with(4096, None).0)
}

fn luminance(p: [f32; 3]) -> f64 {
    (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) as f64
}

fn mse(a: &RenderOutput, reference: &RenderOutput) -> f64 {
    let n = a.beauty.pixels.len();
    a.beauty
        .pixels
        .iter()
        .zip(&reference.beauty.pixels)
        .map(|(p, r)| {
            let (p, r) = (p.to_array(), r.to_array());
            (0..3).map(|c| ((p[c] - r[c]) as f64).powi(2)).sum::<f64>() / 3.0
        })
        .sum::<f64>()
        / n as f64
}

#[test]
fn adaptive_sampling_beats_uniform_at_equal_samples_and_reaches_its_target() {
    let target = NoiseTarget {
        relative_error: 0.08,
        min_spp: 16,
        rule: StoppingRule::Window,
    };
    let reference = reference();
    let (adaptive, adaptive_seconds) = render_with(2048, Some(target));
    let pixels = adaptive.sample_count.len() as f64;
    let total: f64 = adaptive.sample_count.iter().map(|&c| c as f64).sum();
    let equal_spp = (total / pixels).round() as u32;
    let (uniform, uniform_seconds) = render_with(equal_spp, None);

    let summary = adaptive.stats.adaptive.clone().unwrap();
    let (mse_a, mse_u) = (mse(&adaptive, reference), mse(&uniform, reference));
    println!(
        "adaptive: {summary:?}, {adaptive_seconds:.2} s, MSE {mse_a:.3e}; uniform at {equal_spp} \
         spp: {uniform_seconds:.2} s, MSE {mse_u:.3e}"
    );
    // The samples went unevenly (the test would say nothing if they had not); no pixel
    // stops before twice the minimum.
    assert!(
        summary.spp_min == 32 && summary.spp_max > 16 * 32,
        "{summary:?}"
    );
    assert!(
        mse_a < 0.8 * mse_u,
        "adaptive MSE {mse_a:e} vs uniform {mse_u:e}"
    );

    // Pixels that stopped: measured relative error against the reference (with the
    // renderer's floor of 1 % of the image mean), RMS over them, within 1.5 x the target.
    let achieved = achieved_error(&adaptive, reference, 2048, target, 0.5, 0.0);

    // The stopping rule's bias. Measured here: -1.4 % (adaptive 0.1173, reference 0.1189,
    // 6.5 standard errors): the walls' light includes rare caustic paths through the ball,
    // and a pixel that has not yet drawn one shows a low mean *and* a low variance, so a
    // rule that reads the samples it stops on stops it low (Kirk and Arvo 1991). The window
    // and the earliest stop at twice the minimum bound it. Passes sized to each pixel's
    // need, which stop pixels with a third fewer samples than doubling passes did, raised
    // it from 1.1 % (-1.4 % against -1.1 % over six seeds); the assertion keeps it below
    // 2 % so a worse rule fails.
    let (ma, mr) = (image_mean(&adaptive), image_mean(reference));
    println!("uniform mean {:.5}", image_mean(&uniform));
    println!(
        "image mean: adaptive {ma:.5}, reference {mr:.5}, sigma {:.5}; achieved error {achieved:.4}",
        image_mean_sigma(&adaptive)
    );
    assert!((ma - mr).abs() < 0.02 * mr, "{ma} vs {mr}");
}

/// The unbiased rule ([`StoppingRule::Unbiased`]) on the same scene: its image mean agrees
/// with the reference's within three standard errors (of both), where the window rule's is
/// 6.5 standard errors low; its samples still go unevenly, the pixels it stops are at the
/// target, and its MSE at equal samples is at most 1.25x uniform sampling's. Measured here
/// 0.75x (0.80x with doubling passes); over ten seeds at target 0.1, 1.00x, where a rule that knew every pixel's
/// variance would reach 0.90x (`examples/adaptive_bound.rs`). The rule before its
/// estimates were pooled had 1.45x here (1.9x over ten seeds): a wall pixel's own few
/// samples, and its 3 x 3 neighbours', mostly miss the rare caustic paths that make its
/// variance.
#[test]
fn the_unbiased_rule_stops_at_the_target_with_an_unbiased_mean() {
    let target = NoiseTarget {
        relative_error: 0.08,
        min_spp: 16,
        rule: StoppingRule::Unbiased,
    };
    let reference = reference();
    let (adaptive, seconds) = render_with(2048, Some(target));
    let summary = adaptive.stats.adaptive.clone().unwrap();
    let equal_spp = summary.spp_mean.round() as u32;
    let (uniform, uniform_seconds) = render_with(equal_spp, None);
    let (mse_a, mse_u) = (mse(&adaptive, reference), mse(&uniform, reference));
    println!(
        "unbiased rule: {summary:?}, {seconds:.2} s, MSE {mse_a:.3e}; uniform at {equal_spp} \
         spp: {uniform_seconds:.2} s, MSE {mse_u:.3e}"
    );
    assert_eq!(summary.pilot_spp, 16, "{summary:?}");
    assert!(
        summary.spp_min >= 32 && summary.spp_max >= 8 * summary.spp_min,
        "{summary:?}"
    );
    assert!(
        mse_a < 1.25 * mse_u,
        "unbiased rule's MSE {mse_a:e} vs uniform {mse_u:e}"
    );
    // Fewer stop than under the window rule: the pooled estimates are more cautious than a
    // pixel's own. Those that stop are within a factor of 1.5 of the target either way: the
    // passes are sized to each pixel's need (doubling passes that stopped a pixel after two
    // looks at its target left them at 0.66x here).
    let achieved = achieved_error(&adaptive, reference, 2048, target, 1.0 / 3.0, 1.0 / 1.5);
    let (ma, mr) = (image_mean(&adaptive), image_mean(reference));
    let sigma = image_mean_sigma(&adaptive).hypot(image_mean_sigma(reference));
    println!(
        "image mean: unbiased rule {ma:.5}, reference {mr:.5}, sigma {sigma:.5} ({:+.2} sigma); \
         achieved error {achieved:.4}",
        (ma - mr) / sigma
    );
    assert!((ma - mr).abs() < 3.0 * sigma, "{ma} vs {mr}, sigma {sigma}");
}

/// The mean luminance of an image's pixels.
fn image_mean(img: &RenderOutput) -> f64 {
    let pixels = img.beauty.pixels.len() as f64;
    img.beauty
        .pixels
        .iter()
        .map(|p| luminance(p.to_array()))
        .sum::<f64>()
        / pixels
}

/// The standard error of [`image_mean`], from the film's variances of the pixel means.
fn image_mean_sigma(img: &RenderOutput) -> f64 {
    let pixels = img.beauty.pixels.len() as f64;
    let variance: f64 = img
        .variance
        .pixels
        .iter()
        .map(|v| {
            let v = v.to_array();
            0.2126f64.powi(2) * v[0] as f64
                + 0.7152f64.powi(2) * v[1] as f64
                + 0.0722f64.powi(2) * v[2] as f64
        })
        .sum::<f64>()
        / (pixels * pixels);
    variance.sqrt()
}

/// The relative error against `reference` (the renderer's floor: 1 % of the image mean),
/// RMS over the pixels that stopped before `cap` samples, after asserting that more than
/// `min_stopped` of them (a fraction) did and that it is between `lower` and 1.5 times the
/// target.
fn achieved_error(
    adaptive: &RenderOutput,
    reference: &RenderOutput,
    cap: u32,
    target: NoiseTarget,
    min_stopped: f64,
    lower: f64,
) -> f64 {
    let floor = 0.01 * image_mean(reference);
    let (mut sum_sq, mut stopped) = (0.0, 0usize);
    for (i, (p, r)) in adaptive
        .beauty
        .pixels
        .iter()
        .zip(&reference.beauty.pixels)
        .enumerate()
    {
        if adaptive.sample_count[i] < cap as f32 {
            let (p, r) = (luminance(p.to_array()), luminance(r.to_array()));
            sum_sq += ((p - r) / r.max(floor)).powi(2);
            stopped += 1;
        }
    }
    let pixels = adaptive.sample_count.len();
    assert!(
        stopped as f64 > min_stopped * pixels as f64,
        "only {stopped} of {pixels} pixels stopped"
    );
    let achieved = (sum_sq / stopped as f64).sqrt();
    let target = target.relative_error as f64;
    assert!(
        (lower * target..1.5 * target).contains(&achieved),
        "achieved {achieved} over {stopped} stopped pixels, target {target}"
    );
    achieved
}

/// With a target no pixel can miss, every pixel stops at its second look, after twice the
/// minimum: the render is the uniform render of `2 min_spp` samples, bit for bit (stopped
/// pixels take nothing more, the others the same sample indices as a uniform render).
#[test]
fn a_target_every_pixel_meets_stops_all_after_the_minimum() {
    let (adaptive, _) = render_with(
        256,
        Some(NoiseTarget {
            relative_error: 1e30,
            min_spp: 8,
            rule: StoppingRule::Window,
        }),
    );
    let (uniform, _) = render_with(16, None);
    assert!(adaptive.sample_count.iter().all(|&c| c == 16.0));
    // Two passes: `min_spp`, then the rest of the earliest stop's.
    assert_eq!(adaptive.stats.adaptive.as_ref().map(|a| a.passes), Some(2));
    assert_eq!(adaptive.beauty, uniform.beauty);
}

/// Each pass gives each pixel its own range of samples, sized from its estimate; a pixel's
/// samples are still the first indices of its sequence, added in order: its value and
/// variance are the bits of a one-pixel render (`crop`) of as many samples. Pixels of
/// every count the render gave are checked (the test would say nothing if the counts were
/// few).
#[test]
fn each_pixel_holds_the_first_samples_of_its_own_sequence() {
    let target = NoiseTarget {
        relative_error: 0.15,
        min_spp: 8,
        rule: StoppingRule::Window,
    };
    let (adaptive, _) = render_with(512, Some(target));
    let counts = assert_pixels_hold_their_first_samples(&adaptive);
    assert!(counts.len() >= 6, "counts {counts:?}");
    // Sized passes give counts that are not the doublings of 8.
    assert!(
        counts.iter().any(|c| !c.is_power_of_two()),
        "counts {counts:?}"
    );
}

/// Asserts that one pixel of each sample count of `out` has the value and variance of a
/// one-pixel render (`crop`) of that count; returns the counts.
fn assert_pixels_hold_their_first_samples(out: &RenderOutput) -> Vec<u32> {
    let width = 32;
    let mut by_count = std::collections::BTreeMap::new();
    for (i, &count) in out.sample_count.iter().enumerate() {
        by_count.entry(count as u32).or_insert(i as u32);
    }
    for (&count, &i) in &by_count {
        let (x, y) = (i % width, i / width);
        let crop = Window {
            x0: x,
            y0: y,
            x1: x + 1,
            y1: y + 1,
        };
        let (one, _) = render_window(count, None, Some(crop));
        let i = i as usize;
        assert_eq!(
            (one.beauty.pixels[0], one.variance.pixels[0]),
            (out.beauty.pixels[i], out.variance.pixels[i]),
            "pixel ({x}, {y}), {count} samples"
        );
    }
    by_count.into_keys().collect()
}

/// Interrupted mid-render (the flag set once a fifth of the uninterrupted render's samples
/// are in), an adaptive render ends after the pass in flight with what it has: fewer
/// samples than the whole render, and each pixel still holding the first samples of its
/// sequence (the bits of a one-pixel render of its count).
#[test]
fn an_interrupted_adaptive_render_keeps_each_pixels_first_samples() {
    use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
    static STOP: AtomicBool = AtomicBool::new(false);
    let target = NoiseTarget {
        relative_error: 0.05,
        min_spp: 8,
        rule: StoppingRule::Window,
    };
    let (whole, _) = render_with(1024, Some(target));
    let total = |o: &RenderOutput| o.sample_count.iter().map(|&c| c as f64).sum::<f64>();
    let done = AtomicU64::new(0);
    let fifth = (total(&whole) / 5.0) as u64;
    let progress = |n: u64| {
        if done.fetch_add(n, Ordering::Relaxed) + n >= fifth {
            STOP.store(true, Ordering::Relaxed);
        }
    };
    let (cut, _) = render_interruptible(1024, Some(target), None, Some(&STOP), &progress);
    assert!(STOP.load(Ordering::Relaxed));
    println!("interrupted: {} of {} samples", total(&cut), total(&whole));
    assert!(
        total(&cut) < 0.9 * total(&whole),
        "{} of {} samples",
        total(&cut),
        total(&whole)
    );
    assert_pixels_hold_their_first_samples(&cut);
}

/// The driver: `--noise-target` writes the adaptive stats, and refuses what it cannot do.
#[test]
fn the_driver_reports_adaptive_stats_and_refuses_splitting() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("adaptive-cli");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let (out, stats) = (dir.join("a.exr"), dir.join("a.json"));
    let run = |extra: &[&str]| {
        let mut args = vec!["render", scene.to_str().unwrap(), "--no-preview", "-o"];
        args.push(out.to_str().unwrap());
        args.extend_from_slice(extra);
        std::process::Command::new(env!("CARGO_BIN_EXE_risotto"))
            .args(&args)
            .output()
            .unwrap()
    };
    // The adaptive stats of a render at target 0.2, at least 4 spp, with `rule`.
    let adaptive_stats = |rule: &str| -> serde_json::Value {
        let o = run(&[
            "--noise-target",
            "0.2",
            "--min-spp",
            "4",
            "--stopping-rule",
            rule,
            "--stats",
            stats.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        json["adaptive"].clone()
    };
    let a = adaptive_stats("window");
    assert_eq!(a["target"].as_f64(), Some(0.2f32 as f64));
    assert!(a["spp_max"].as_u64().unwrap() <= 64);
    assert!(a["spp_min"].as_u64().unwrap() >= 8);
    assert_eq!(a["pilot_spp"].as_u64(), Some(0));
    // The passes (at least the first and the one to the earliest stop) and what deciding
    // between them cost.
    assert!(a["passes"].as_u64().unwrap() >= 2, "{a}");
    assert!(a["plan_seconds"].as_f64().unwrap() >= 0.0, "{a}");
    // The unbiased rule renders its pilot of --min-spp samples a pixel and says so.
    assert_eq!(adaptive_stats("unbiased")["pilot_spp"].as_u64(), Some(4));
    // A minimum that leaves no pixel a chance to stop before the cap is warned about, and
    // one that does is not.
    let warnings = |min_spp: &str| {
        let o = run(&["--noise-target", "0.2", "--min-spp", min_spp, "--quiet"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let err = warnings("32");
    assert!(
        err.contains("warning: --min-spp 32: no pixel can stop before 64 samples"),
        "{err}"
    );
    assert!(!warnings("31").contains("warning"));
    for (args, needle) in [
        (
            &["--noise-target", "0"][..],
            "must be a positive relative error",
        ),
        (
            &["--noise-target", "0.1", "--checkpoint", "5"][..],
            "cannot be used with",
        ),
        (&["--min-spp", "4"][..], "--noise-target"),
        (&["--stopping-rule", "unbiased"][..], "--noise-target"),
        (
            &["--noise-target", "0.1", "--stopping-rule", "own"][..],
            "invalid value 'own'",
        ),
    ] {
        let o = run(args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && stderr.contains(needle),
            "{args:?}: {stderr}"
        );
    }
}
