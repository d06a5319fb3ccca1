//! The `risotto` driver: `risotto render SCENE.toml [options]`, `risotto compare`,
//! `risotto techniques SCENE.toml` and `risotto converge SCENE.toml [options]`.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use risotto::engine::compare::compare;
use risotto::engine::converge::{self, ConvergeOptions, Reference, SppPlan};
use risotto::engine::load::{compile_scene, load_scene_file, MaterialRegistry};
use risotto::engine::output::{read_exr_rgb, write_exr, write_png, FilmOutput};
use risotto::engine::render::{render, RenderOptions};
use risotto::engine::scene::CompiledScene;
use risotto::engine::technique::{self, Techniques};
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
    /// List the techniques (estimator choices that trade time for error) that apply to a
    /// scene, with their values; `*` marks the default.
    Techniques {
        /// The scene file.
        scene: PathBuf,
    },
    /// Render each technique at increasing spp and measure error against a reference and
    /// render time: writes DIR/converge.csv, .json, .png and .svg and prints a table of
    /// equal-time error and equal-error time relative to the best technique.
    Converge(ConvergeArgs),
}

#[derive(clap::Args)]
struct ConvergeArgs {
    /// The scene file.
    scene: PathBuf,
    /// Reference image (EXR of the scene's size), taken as exact. Without it the reference
    /// is rendered (see --reference-spp).
    #[arg(long, conflicts_with = "reference_spp")]
    reference: Option<PathBuf>,
    /// Samples per pixel of the rendered reference, as two independent halves whose
    /// difference estimates its noise, subtracted from every MSE. Defaults to 16 times the
    /// largest spp of the sweep (at most 65536).
    #[arg(long)]
    reference_spp: Option<u32>,
    /// Techniques of the rendered reference: NAME=VALUE[+NAME=VALUE...]; defaults to every
    /// technique's default.
    #[arg(long)]
    reference_technique: Option<String>,
    /// The variants to sweep, comma-separated, each NAME=VALUE[+NAME=VALUE...] on top of the
    /// defaults; `all`: the defaults and every other value of every technique that applies
    /// to the scene, one at a time.
    #[arg(long, default_value = "all")]
    techniques: String,
    /// Samples per pixel of the sweep, comma-separated.
    #[arg(long, default_value = "1,2,4,8,16,32,64", conflicts_with = "budget")]
    spp: String,
    /// Instead of --spp: each variant renders 1, 2, 4, ... spp until one render takes at
    /// least this many seconds.
    #[arg(long)]
    budget: Option<f64>,
    /// Renders per point, with different seeds (min/max error bars).
    #[arg(long, default_value_t = 1)]
    repeats: u32,
    /// Output directory.
    #[arg(long, default_value = "converge")]
    out: PathBuf,
    /// Worker threads (defaults to all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Paths per batch.
    #[arg(long, default_value_t = 4096)]
    batch_size: usize,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
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
    /// Direct-lighting technique: mis (the default), nee, bxdf. An alias of
    /// `--technique lighting=VALUE`.
    #[arg(long)]
    lighting: Option<String>,
    /// A technique, NAME=VALUE (repeatable); `risotto techniques SCENE` lists them.
    #[arg(long = "technique", value_name = "NAME=VALUE")]
    techniques: Vec<String>,
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
        Command::Techniques { scene } => techniques_command(&scene),
        Command::Converge(args) => converge_command(args),
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
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| default_output(&args.scene));
    check_outputs(&args.scene, &out, args.stats.as_deref())?;
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
    let compiled = compile_scene(scene, &args.scene)?;
    let techniques = render_techniques(&args, &compiled)?;
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
    let options = techniques.render_options(RenderOptions {
        threads: args.threads,
        batch_size: args.batch_size,
        ..RenderOptions::default()
    });
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

/// The techniques of `risotto render`: `--lighting` (an alias) and every `--technique`,
/// which must apply to the scene and may not contradict each other.
fn render_techniques(args: &RenderArgs, scene: &CompiledScene) -> Result<Techniques> {
    // (the flag as given, its assignment)
    let mut assignments: Vec<(String, String)> = args
        .techniques
        .iter()
        .map(|a| (format!("--technique {a}"), a.clone()))
        .collect();
    if let Some(l) = &args.lighting {
        assignments.insert(0, (format!("--lighting {l}"), format!("lighting={l}")));
    }
    let mut t = Techniques::default();
    let mut given: Vec<(&str, String)> = Vec::new();
    for (flag, a) in &assignments {
        let tech = t.assign(a).with_context(|| flag.clone())?;
        let value = t.get(tech.name)?.to_string();
        if let Some((_, v)) = given.iter().find(|(n, v)| *n == tech.name && *v != value) {
            anyhow::bail!(
                "{flag}: {} was already set to {v} (by --lighting or another --technique)",
                tech.name
            );
        }
        given.push((tech.name, value));
        if !(tech.applies)(&scene.features) {
            anyhow::bail!(
                "{flag}: technique {a} does not apply to {} ({} applies to {})",
                args.scene.display(),
                tech.name,
                tech.applies_to
            );
        }
    }
    Ok(t)
}

fn techniques_command(scene_path: &Path) -> Result<()> {
    let registry = MaterialRegistry::with_builtins();
    let scene = load_scene_file(scene_path, &registry)?;
    let compiled = compile_scene(scene, scene_path)?;
    print!("{}", technique::listing(&compiled.features));
    Ok(())
}

/// Parses `--spp 1,2,4`.
fn parse_spp_list(s: &str) -> Result<Vec<u32>> {
    let mut v = Vec::new();
    for item in s.split(',') {
        let n: u32 = item
            .trim()
            .parse()
            .with_context(|| format!("--spp {s}: \"{item}\" is not a whole number"))?;
        anyhow::ensure!(
            (1..=risotto::systems::sampler::MAX_SPP).contains(&n),
            "--spp {s}: {n} is not between 1 and {}",
            risotto::systems::sampler::MAX_SPP
        );
        v.push(n);
    }
    v.sort_unstable();
    v.dedup();
    Ok(v)
}

fn converge_command(args: ConvergeArgs) -> Result<()> {
    let registry = MaterialRegistry::with_builtins();
    let scene = load_scene_file(&args.scene, &registry)?;
    let mut compiled = compile_scene(scene, &args.scene)?;
    let variants = if args.techniques.trim() == "all" {
        Techniques::variants(&compiled.features)
    } else {
        let mut v = Vec::new();
        for spec in args.techniques.split(',') {
            let t = Techniques::parse(spec.trim())
                .with_context(|| format!("--techniques {}", args.techniques))?;
            t.check_applicable(&compiled.features)
                .with_context(|| format!("--techniques {spec} on {}", args.scene.display()))?;
            if !v.contains(&t) {
                v.push(t);
            }
        }
        v
    };
    let plan = match args.budget {
        Some(b) => SppPlan::Budget(b),
        None => SppPlan::List(parse_spp_list(&args.spp)?),
    };
    let reference = match &args.reference {
        Some(path) => {
            let image =
                read_exr_rgb(path).with_context(|| format!("--reference {}", path.display()))?;
            Reference::Image {
                image,
                path: path.display().to_string(),
            }
        }
        None => {
            if let Some(n) = args.reference_spp {
                anyhow::ensure!(
                    (2..=risotto::systems::sampler::MAX_SPP).contains(&n),
                    "--reference-spp {n}: must be between 2 and {} (two halves)",
                    risotto::systems::sampler::MAX_SPP
                );
            }
            let techniques = match &args.reference_technique {
                Some(spec) => Techniques::parse(spec)
                    .with_context(|| format!("--reference-technique {spec}"))?,
                None => Techniques::default(),
            };
            Reference::Render {
                spp: args.reference_spp,
                techniques,
            }
        }
    };
    if let Some(0) = args.threads {
        anyhow::bail!("--threads 0: need at least one thread");
    }
    anyhow::ensure!(
        args.batch_size > 0,
        "--batch-size 0: need at least one path per batch"
    );
    let options = ConvergeOptions {
        variants,
        plan,
        repeats: args.repeats,
        reference,
        render: RenderOptions {
            threads: args.threads,
            batch_size: args.batch_size,
            ..RenderOptions::default()
        },
    };
    let pixels = compiled.camera.width as u64 * compiled.camera.height as u64;
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        let (bar, template) = match converge::total_samples(&options, pixels) {
            Some(total) => (
                ProgressBar::new(total),
                "{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% {eta} left  {msg}",
            ),
            None => (
                ProgressBar::new_spinner(),
                "{spinner} [{elapsed_precise}] {human_pos} samples  {msg}",
            ),
        };
        bar.set_style(ProgressStyle::with_template(template).expect("static template is valid"));
        bar
    };
    let stage = |s: &str| bar.set_message(s.to_string());
    let samples = |n: u64| bar.inc(n);
    let sweep = converge::run(
        &mut compiled,
        &options,
        &converge::Progress {
            stage: &stage,
            samples: &samples,
        },
    )?;
    bar.finish_and_clear();
    sweep.write_all(&args.out)?;
    print!("{}", sweep.table());
    if let (Reference::Render { techniques, .. }, Some(best)) =
        (&options.reference, sweep.most_efficient())
    {
        if best.label != techniques.label() {
            println!(
                "note: {} was more efficient than the reference's technique ({}); \
                 --reference-technique {} renders the reference with it",
                best.label,
                techniques.label(),
                best.label
            );
        }
    }
    if !args.quiet {
        eprintln!("wrote {}/converge.{{csv,json,png,svg}}", args.out.display());
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

/// Checks the outputs of `risotto render` before anything is rendered: `out` is an EXR, the
/// PNG preview beside it and the stats file are distinct from it, from each other and from
/// the scene, and each can be written (its directory exists, it is not a directory, and it can
/// be opened for writing). Nothing is created or truncated here.
fn check_outputs(scene: &Path, out: &Path, stats: Option<&Path>) -> Result<()> {
    let is_exr = out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    anyhow::ensure!(
        is_exr,
        "--out {}: the output must be an EXR file (extension .exr); the PNG preview is \
         written beside it",
        out.display()
    );
    let png = out.with_extension("png");
    let mut named = vec![
        ("the scene", scene.to_path_buf()),
        ("--out", out.to_path_buf()),
        ("the PNG preview", png.clone()),
    ];
    if let Some(stats) = stats {
        named.push(("--stats", stats.to_path_buf()));
    }
    for (i, (a, pa)) in named.iter().enumerate() {
        for (b, pb) in &named[..i] {
            anyhow::ensure!(
                !same_file(pa, pb),
                "{a} {} is the same file as {b} {}: one would overwrite the other",
                pa.display(),
                pb.display()
            );
        }
    }
    for (what, path) in named.iter().skip(1) {
        check_writable(path).with_context(|| format!("{what} {}", path.display()))?;
    }
    Ok(())
}

/// Whether `a` and `b` name the same file: equal after making them absolute and resolving
/// `.`, `..` and symbolic links of the parts that exist.
fn same_file(a: &Path, b: &Path) -> bool {
    fn resolved(p: &Path) -> PathBuf {
        if let Ok(c) = std::fs::canonicalize(p) {
            return c;
        }
        let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
        match (abs.parent(), abs.file_name()) {
            (Some(dir), Some(name)) => std::fs::canonicalize(dir)
                .map(|d| d.join(name))
                .unwrap_or(abs.clone()),
            _ => abs,
        }
    }
    resolved(a) == resolved(b)
}

/// Whether `path` can be written, without creating or truncating it: an existing file is
/// opened for writing; otherwise its directory must exist, and a probe file is created there
/// and removed.
fn check_writable(path: &Path) -> Result<()> {
    if path.is_dir() {
        anyhow::bail!("is a directory");
    }
    if path.exists() {
        std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .context("cannot be written")?;
        return Ok(());
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    anyhow::ensure!(
        dir.is_dir(),
        "cannot be written: directory {} does not exist",
        dir.display()
    );
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(path)
        .context("cannot be written")?;
    std::fs::remove_file(path).context("cannot be written")?;
    Ok(())
}

fn default_output(scene: &Path) -> PathBuf {
    let stem = scene
        .file_stem()
        .map_or_else(|| "render".into(), |s| s.to_os_string());
    PathBuf::from(stem).with_extension("exr")
}
