//! `risotto converge SCENE.toml [options]`: every applicable technique at increasing spp
//! against a reference, written as CSV, JSON and a plot (the engine's [`converge`] does the
//! work; this is its command line).

use crate::check_threads;
use crate::scene_input::SceneInput;
use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use risotto::engine::output::read_exr_rgb;
use risotto::engine::render::RenderOptions;
use risotto::engine::technique::{TechniqueRegistry, Techniques};
use risotto::loader::load::{compile_scene, MaterialRegistry};
use risotto::tools::converge::{
    self, AdaptivePlan, ConvergeOptions, ErrorMetric, Reference, SppPlan, Variant,
};
use std::path::PathBuf;

#[derive(clap::Args)]
pub(crate) struct ConvergeArgs {
    /// The scene file, or `-` to read it from standard input.
    scene: PathBuf,
    /// Override a scene value by its TOML path (repeatable), as for `render`.
    #[arg(short = 'D', long = "define", value_name = "KEY.PATH=VALUE")]
    defines: Vec<String>,
    /// Reference image (EXR of the scene's size), taken as exact. Without it the reference
    /// is rendered (see --reference-spp).
    #[arg(long, conflicts_with = "reference_spp")]
    reference: Option<PathBuf>,
    /// Samples per pixel of the rendered reference, as two independent halves whose
    /// difference estimates its noise, subtracted from every MSE. Defaults to 16 times the
    /// largest spp of the sweep (at most 65536).
    #[arg(long)]
    reference_spp: Option<u32>,
    /// Techniques of the rendered reference: NAME=VALUE[+NAME=VALUE...]; by default the
    /// sweep's most efficient technique that converges to the exact image, judged from two
    /// seeds of its largest spp.
    #[arg(long)]
    reference_technique: Option<String>,
    /// The variants to sweep, comma-separated, each NAME=VALUE[+NAME=VALUE...] on top of the
    /// defaults, `adaptive=on` among them (adaptive sampling, points at --noise-targets);
    /// `all`: the defaults, every other value of every technique that applies to the scene
    /// one at a time, and adaptive=on where the scene's integrator is the path tracer.
    #[arg(long, default_value = "all")]
    techniques: String,
    /// Samples per pixel of the sweep, comma-separated.
    #[arg(long, default_value = "1,2,4,8,16,32,64", conflicts_with = "budget")]
    spp: String,
    /// Instead of --spp: each variant renders 1, 2, 4, ... spp until one render takes at
    /// least this many seconds.
    #[arg(long)]
    budget: Option<f64>,
    /// The noise targets (relative errors, descending) of the adaptive=on curves, one point
    /// each, at most the sweep's largest spp per pixel. With --budget the first is halved
    /// until a render takes the budget.
    #[arg(long, default_value = "0.4,0.2,0.1,0.05,0.025,0.0125,0.00625")]
    noise_targets: String,
    /// The samples every pixel of an adaptive=on point takes before any stops.
    #[arg(long, default_value_t = converge::DEFAULT_MIN_SPP)]
    min_spp: u32,
    /// Renders per point, with different seeds (min/max error bars).
    #[arg(long, default_value_t = 1)]
    repeats: u32,
    /// Output directory.
    #[arg(long, default_value = "converge")]
    out: PathBuf,
    /// Worker threads (defaults to all cores), for every phase: reading the scene, building it
    /// and rendering
    #[arg(long)]
    threads: Option<usize>,
    /// Paths per batch.
    #[arg(long, default_value_t = 4096)]
    batch_size: usize,
    /// The error the techniques are compared by (efficiency, fits, equal-time and
    /// equal-error ratios, plot): `mse`, or `relmse` (each pixel's squared error over its
    /// squared reference value plus 0.01), which a few very bright pixels do not dominate.
    /// Both are in the CSV and JSON either way.
    #[arg(long, default_value = "mse", value_parser = parse_metric)]
    metric: ErrorMetric,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

/// Parses `--metric mse|relmse`.
fn parse_metric(s: &str) -> std::result::Result<ErrorMetric, String> {
    ErrorMetric::from_name(s).ok_or_else(|| format!("\"{s}\" is not mse or relmse"))
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

/// Parses `--noise-targets 0.4,0.2`: positive, descending.
fn parse_noise_targets(s: &str) -> Result<Vec<f64>> {
    let mut v = Vec::new();
    for item in s.split(',') {
        let x: f64 = item
            .trim()
            .parse()
            .with_context(|| format!("--noise-targets {s}: \"{item}\" is not a number"))?;
        anyhow::ensure!(
            x.is_finite() && x > 0.0,
            "--noise-targets {s}: {x} is not a positive relative error (e.g. 0.1)"
        );
        v.push(x);
    }
    v.sort_unstable_by(|a, b| b.total_cmp(a));
    v.dedup();
    Ok(v)
}

pub(crate) fn converge_command(args: ConvergeArgs) -> Result<()> {
    // First: it sizes rayon's global pool, which loading and compiling start.
    check_threads(args.threads)?;
    let registry = MaterialRegistry::with_builtins();
    let input = SceneInput::read(&args.scene, &args.defines, None)?;
    let mut compiled = compile_scene(input.load(&registry)?)?;
    let registry = TechniqueRegistry::for_scene(&compiled);
    let variants = if args.techniques.trim() == "all" {
        Variant::all(&compiled)
    } else {
        let mut v = Vec::new();
        for spec in args.techniques.split(',') {
            let t = Variant::parse(&compiled, spec.trim()).with_context(|| {
                format!(
                    "--techniques {} on {}",
                    args.techniques,
                    args.scene.display()
                )
            })?;
            if !v.contains(&t) {
                v.push(t);
            }
        }
        v
    };
    anyhow::ensure!(
        args.min_spp >= 1,
        "--min-spp {}: must be at least 1",
        args.min_spp
    );
    let adaptive = AdaptivePlan {
        noise_targets: parse_noise_targets(&args.noise_targets)?,
        min_spp: args.min_spp,
    };
    let plan = match args.budget {
        Some(b) => SppPlan::Budget(b),
        None => SppPlan::List(parse_spp_list(&args.spp)?),
    };
    let mut variants = variants;
    if let (true, SppPlan::List(spps)) = (args.techniques.trim() == "all", &plan) {
        // `all` asks for adaptive=on only where it can show something; asked for by name
        // with too small a cap it is an error (converge::run).
        let cap = spps.iter().copied().max().unwrap_or(1);
        if variants.iter().any(|v| v.adaptive.is_some()) && !adaptive.can_stop_below(cap) {
            variants.retain(|v| v.adaptive.is_none());
            eprintln!(
                "note: adaptive=on left out: with --spp up to {cap} no pixel can stop before \
                 the cap (a pixel stops at 2 x --min-spp {} samples at the earliest)",
                adaptive.min_spp
            );
        }
    }
    let reference = match &args.reference {
        Some(path) => {
            let image = read_exr_rgb(path).context("--reference")?;
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
                Some(spec)
                    if Variant::parse(&compiled, spec).is_ok_and(|v| v.adaptive.is_some()) =>
                {
                    anyhow::bail!(
                        "--reference-technique {spec}: a reference is rendered uniformly \
                         (adaptive sampling's stopping rule is biased)"
                    )
                }
                Some(spec) => Some(
                    Techniques::parse(&registry, spec)
                        .with_context(|| format!("--reference-technique {spec}"))?,
                ),
                None => None,
            };
            Reference::Render {
                spp: args.reference_spp,
                techniques,
            }
        }
    };
    anyhow::ensure!(
        args.batch_size > 0,
        "--batch-size 0: need at least one path per batch"
    );
    let options = ConvergeOptions {
        variants,
        plan,
        adaptive,
        repeats: args.repeats,
        reference,
        render: RenderOptions {
            threads: args.threads,
            batch_size: args.batch_size,
            // A curve reads the beauty and the sample counts alone.
            aovs: false,
            ..RenderOptions::default()
        },
        metric: args.metric,
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
    if let (
        Reference::Render {
            techniques: Some(techniques),
            ..
        },
        Some(best),
    ) = (&options.reference, sweep.most_efficient())
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
