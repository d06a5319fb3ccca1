//! What any stopping rule of `render --noise-target` could gain on a scene, at best: the
//! MSE of the sample counts a rule would choose if it **knew** every pixel's variance,
//! against uniform sampling's at the same mean samples per pixel (issue 36).
//!
//! ```text
//! cargo run --release --example adaptive_bound -- SCENE.toml [SPP]
//! ```
//!
//! It renders `SCENE.toml` uniformly at `SPP` samples a pixel (default 16384) and takes each
//! pixel's per-sample variance `var_c` (the film's variance of the mean times `SPP`) and
//! value `v_c` as the truth. A rule that knows them and stops a pixel at the requested
//! relative error `t` (the renderer's measure: the worst channel's `sqrt(var_c / n) /
//! max(v_c, floor_c)`, the floor 1 % of the image's mean) gives it
//! `n = max_c var_c / (t max(v_c, floor_c))^2` samples, clamped to `[32, 2048]` (the first
//! count at which the renderer's rules can stop a pixel at the default `--min-spp 16`, and
//! the cap the README's measurements use). Its expected MSE is `mean over pixels of
//! mean_c var_c / n`; uniform sampling's at the same mean count `N` is `mean var / N`.
//! Without the clamps the ratio is the same at every target, printed last: what the
//! relative-error allocation itself gives, before the clamps bound it.
//!
//! Such a rule is unbiased (its counts depend on no pixel's samples), so the ratio bounds
//! what an unbiased stopping rule that estimates the variances can reach; the Neyman
//! allocation (`n` proportional to the pixel's standard deviation, the counts that minimise
//! the MSE for their total; Neyman 1934) is what an MSE-optimal allocation would reach,
//! which no relative-error target asks for. README, "Renders that stop at a requested
//! accuracy", has it measured on `scenes/adaptive-smoke-ball.toml`.

use risotto::engine::render::{render, RenderOptions, NOISE_FLOOR_FRACTION};
use risotto::loader::load::{scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::parse_scene_with;
use risotto::systems::adaptive::{error_floor, pooled_relative_error, Neighbourhood};

/// The targets the README's table sweeps.
const TARGETS: [f64; 4] = [0.4, 0.2, 0.1, 0.05];
/// The counts a pixel may get: the earliest stop (two looks after `--min-spp 16`) and the
/// cap.
const COUNTS: (f64, f64) = (32.0, 2048.0);

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (path, spp) = match args.as_slice() {
        [path] => (path, 16384u32),
        [path, spp] => (
            path,
            spp.parse()
                .map_err(|_| format!("SPP must be a whole number, not `{spp}`"))?,
        ),
        _ => return Err("usage: adaptive_bound SCENE.toml [SPP]".into()),
    };
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    let desc = parse_scene_with(
        &text,
        std::path::Path::new(path),
        &[format!("render.spp={spp}")],
    )
    .map_err(|e| e.to_string())?;
    let scene = scene_from_desc(desc, &MaterialRegistry::with_builtins())
        .map_err(|e| e.to_string())?
        .compile()
        .map_err(|e| e.to_string())?;
    let out = render(&scene, &RenderOptions::default(), &|_| {}).map_err(|e| e.to_string())?;

    let value: Vec<[f32; 3]> = out.beauty.pixels.iter().map(|p| p.to_array()).collect();
    let variance: Vec<[f32; 3]> = (out.variance.pixels.iter())
        .map(|v| v.to_array().map(|v| v * spp as f32))
        .collect();
    let pixels = value.len() as f64;
    // Each pixel's per-sample relative error (the worst channel), by the renderer's own
    // measure and floor: a neighbourhood of the pixel alone.
    let floor = error_floor(&value, NOISE_FLOOR_FRACTION);
    let mut relative = vec![0.0f32; value.len()];
    pooled_relative_error(
        out.window.width() as usize,
        out.window.height() as usize,
        &value,
        &variance,
        Neighbourhood::Square(0),
        floor,
        &mut relative,
    );
    let mean_variance: Vec<f64> = variance
        .iter()
        .map(|s| s.iter().map(|&s| s as f64).sum::<f64>() / 3.0)
        .collect();
    let sigma_mean = mean_variance.iter().map(|s| s.sqrt()).sum::<f64>() / pixels;

    println!("{path}: {} pixels, truth from {spp} spp", value.len());
    println!(
        "target  mean spp  known-variance rule / uniform  Neyman / uniform  (MSE at equal samples)"
    );
    for target in TARGETS {
        let counts: Vec<f64> = relative
            .iter()
            .map(|&e| (e as f64 / target).powi(2).clamp(COUNTS.0, COUNTS.1))
            .collect();
        let mean_count = counts.iter().sum::<f64>() / pixels;
        let mse_rule = (mean_variance.iter().zip(&counts))
            .map(|(s, n)| s / n)
            .sum::<f64>()
            / pixels;
        let mse_uniform = mean_variance.iter().sum::<f64>() / pixels / mean_count;
        // Neyman: n_i = N sigma_i / mean sigma, so sigma_i^2 / n_i = sigma_i mean sigma / N.
        let mse_neyman = sigma_mean * sigma_mean / mean_count;
        println!(
            "{target:<6}  {mean_count:>8.0}  {:>29.2}  {:>16.2}",
            mse_rule / mse_uniform,
            mse_neyman / mse_uniform
        );
    }
    // Without the clamps the counts `(e / t)^2` scale with `1 / t^2` alone, so the ratio is
    // the same at every target: `mean(s / e^2) mean(e^2) / mean(s)`, with `s` a pixel's
    // variance and `e` its relative error. For one channel and no floor that is `mean(v^2)
    // mean(e^2) / mean(v^2 e^2)` (`v` the pixel's value): below 1 only where the brighter
    // pixels are the relatively noisier ones. A pixel without variance takes no samples
    // and adds nothing.
    let (mut per_count, mut count_sum) = (0.0f64, 0.0f64);
    for (s, &e) in mean_variance.iter().zip(&relative) {
        let n = (e as f64).powi(2);
        if n > 0.0 {
            per_count += s / n;
            count_sum += n;
        }
    }
    let mean_variance_all = mean_variance.iter().sum::<f64>() / pixels;
    println!(
        "without the [{}, {}] clamps, at every target: known-variance rule / uniform {:.2}",
        COUNTS.0,
        COUNTS.1,
        (per_count / pixels) * (count_sum / pixels) / mean_variance_all
    );
    Ok(())
}
