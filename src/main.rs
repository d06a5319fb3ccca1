//! The `risotto` driver: `risotto render SCENE.toml [options]`.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use risotto::engine::compare::compare;
use risotto::engine::integrator::LightingTechnique;
use risotto::engine::load::{compile_scene, load_scene_file, MaterialRegistry};
use risotto::engine::output::{read_exr_rgb, write_exr, write_png, FilmOutput};
use risotto::engine::render::{render, RenderOptions};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "risotto",
    version,
    about = "A physically based CPU renderer with first-class volumes"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene file to an EXR (beauty, variance, sampleCount) and a PNG preview.
    Render(RenderArgs),
    /// Compare an image with a reference (RMSE, relMSE, MAE, per-channel means), as the
    /// Mitsuba harness's rmse.py does.
    Compare {
        /// The image to test (EXR).
        test: PathBuf,
        /// The reference (EXR).
        reference: PathBuf,
    },
}

#[derive(clap::Args)]
struct RenderArgs {
    /// The scene file (TOML, see docs/scene-format.md).
    scene: PathBuf,
    /// Samples per pixel (overrides the scene).
    #[arg(long)]
    spp: Option<u32>,
    /// Output EXR; the PNG preview is written beside it. Defaults to SCENE_STEM.exr in the
    /// current directory.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write render statistics as JSON to this file.
    #[arg(long)]
    stats: Option<PathBuf>,
    /// Worker threads (defaults to all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Sampler seed (overrides the scene).
    #[arg(long)]
    seed: Option<u64>,
    /// Maximum path segments (overrides the scene; -1 = unbounded).
    #[arg(long, allow_negative_numbers = true)]
    max_depth: Option<i64>,
    /// Exposure of the PNG preview in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
    /// Also write albedo, normal and depth AOVs into the EXR.
    #[arg(long)]
    aovs: bool,
    /// Direct-lighting technique: mis, nee, bxdf.
    #[arg(long, default_value = "mis")]
    lighting: String,
    /// Paths per batch (1 to 16777216: a batch's tables are allocated whole).
    #[arg(long, default_value_t = 4096)]
    batch_size: usize,
    /// No progress bar and no summary.
    #[arg(long)]
    quiet: bool,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render_command(args),
        Command::Compare { test, reference } => compare_command(&test, &reference),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn render_command(args: RenderArgs) -> Result<()> {
    let registry = MaterialRegistry::with_builtins();
    let mut scene = load_scene_file(&args.scene, &registry)?;
    if let Some(spp) = args.spp {
        anyhow::ensure!(
            (1..=risotto::systems::sampler::MAX_SPP).contains(&spp),
            "--spp {spp}: must be between 1 and {}",
            risotto::systems::sampler::MAX_SPP
        );
        scene.settings.spp = spp;
    }
    if let Some(seed) = args.seed {
        scene.settings.seed = seed;
    }
    if let Some(d) = args.max_depth {
        scene.settings.max_depth = match d {
            -1 => u32::MAX,
            d if d >= 1 && d <= u32::MAX as i64 => d as u32,
            d => anyhow::bail!("--max-depth {d}: must be -1 (unbounded) or at least 1"),
        };
    }
    if let Some(0) = args.threads {
        anyhow::bail!("--threads 0: need at least one thread");
    }
    anyhow::ensure!(
        args.batch_size > 0,
        "--batch-size 0: need at least one path per batch"
    );
    const MAX_BATCH_SIZE: usize = 1 << 24;
    anyhow::ensure!(
        args.batch_size <= MAX_BATCH_SIZE,
        "--batch-size {}: must be at most {MAX_BATCH_SIZE} paths",
        args.batch_size
    );
    let technique = match args.lighting.as_str() {
        "mis" => LightingTechnique::Mis,
        "nee" => LightingTechnique::NeeOnly,
        "bxdf" => LightingTechnique::BxdfOnly,
        other => anyhow::bail!("--lighting {other}: expected mis, nee or bxdf"),
    };
    let compiled = compile_scene(scene, &args.scene)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| default_output(&args.scene));
    let total =
        compiled.settings.spp as u64 * compiled.camera.width as u64 * compiled.camera.height as u64;
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(total);
        b.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% {per_sec} samples, {eta} left",
            )
            .expect("static template is valid"),
        );
        b
    };
    let options = RenderOptions {
        threads: args.threads,
        batch_size: args.batch_size,
        technique,
        ..RenderOptions::default()
    };
    let result = render(&compiled, &options, &|n| bar.inc(n))?;
    bar.finish_and_clear();

    let film = FilmOutput {
        beauty: &result.beauty,
        variance: &result.variance,
        sample_count: &result.sample_count,
        albedo: args.aovs.then_some(&result.albedo),
        normal: args.aovs.then_some(&result.normal),
        depth: args.aovs.then_some(result.depth.as_slice()),
    };
    write_exr(&out, &film)?;
    let png = out.with_extension("png");
    write_png(&png, &result.beauty, args.exposure)?;
    if let Some(path) = &args.stats {
        result
            .stats
            .write_json(path)
            .with_context(|| format!("cannot write stats to {}", path.display()))?;
    }
    if !args.quiet {
        eprintln!("{}", result.stats);
        eprintln!("wrote {} and {}", out.display(), png.display());
    }
    Ok(())
}

fn compare_command(test: &Path, reference: &Path) -> Result<()> {
    let t = read_exr_rgb(test)?;
    let r = read_exr_rgb(reference)?;
    let m = compare(&t, &r)?;
    println!("{m}");
    Ok(())
}

fn default_output(scene: &Path) -> PathBuf {
    let stem = scene
        .file_stem()
        .map_or_else(|| "render".into(), |s| s.to_os_string());
    PathBuf::from(stem).with_extension("exr")
}
