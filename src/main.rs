//! The `risotto` driver: `risotto render SCENE.toml [options]`, `risotto compare`,
//! `risotto techniques SCENE.toml`, `risotto converge SCENE.toml [options]`,
//! `risotto merge PART.exr... --out FULL.exr` and `risotto info PART.exr`.

mod converge_command;
mod display;
mod interrupt;
mod progress;
mod render_args;
mod replay_args;
mod run_info;
mod scene_input;
mod split;
use converge_command::{converge_command, ConvergeArgs};
use render_args::{ProgressMode, RenderArgs};
use replay_args::{parse_replay, replay_base_command};
use scene_input::{SceneInput, STDIN_NAME};
use split::{grid_tile, info_command, merge_command, parse_crop, sample_chunk};

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use indicatif::ProgressBar;
use risotto::engine::output::{
    read_exr_rgb, rgb_part, write_exr, write_exr_placed, write_png, Image,
};
use risotto::engine::render::{
    checked_extent, render, render_checkpointed, Checkpoints, NoiseTarget, RenderError,
    RenderOptions, RenderOutput,
};
use risotto::engine::replay::replay;
use risotto::engine::scene::CompiledScene;
use risotto::engine::technique::{self, TechniqueRegistry, Techniques};
use risotto::loader::load::{compile_scene, MaterialRegistry};
use risotto::tools::compare::compare;
use risotto::tools::merge::{parse_sample_range, write_partial, Partial};
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
    Render(Box<RenderArgs>),
    /// Compare an image with a reference (RMSE, relMSE, MAE, per-channel means), as the
    /// Mitsuba harness's rmse.py does.
    Compare {
        /// The image to test (EXR).
        test: PathBuf,
        /// The reference (EXR).
        reference: PathBuf,
    },
    /// List the techniques (estimator choices that trade time for error) that apply to a
    /// scene, with their values; `*` marks the default. `adaptive` (converge's adaptive
    /// sampling) follows them where the scene's integrator is the path tracer.
    Techniques {
        /// The scene file, or `-` to read it from standard input.
        scene: PathBuf,
        /// Override a scene value by its TOML path (repeatable), as for `render`.
        #[arg(short = 'D', long = "define", value_name = "KEY.PATH=VALUE")]
        defines: Vec<String>,
    },
    /// Render each technique at increasing spp and measure error against a reference and
    /// render time: writes DIR/converge.csv, .json, .png and .svg and prints a table of
    /// equal-time error and equal-error time relative to the best technique.
    Converge(ConvergeArgs),
    /// Merge partial renders (tiles from --crop, sample passes from --samples, checkpoints)
    /// into the whole render: writes the EXR (with the AOV layers when the parts carry them),
    /// its PNG preview and merged stats JSON.
    Merge(MergeArgs),
    /// Convert a Mitsuba 3 XML or pbrt-v4 scene into risotto's TOML scene format (relative
    /// paths rewritten for OUT's directory). Rendering OUT gives the same image as rendering
    /// the original.
    Convert {
        /// The scene (`.xml` or `.pbrt`), or `-` to read it from standard input.
        scene: PathBuf,
        /// The TOML scene to write.
        out: PathBuf,
        /// Set a scene parameter (Mitsuba's `<default>` / `$name`), repeatable.
        #[arg(short = 'D', long = "define", value_name = "NAME=VALUE")]
        defines: Vec<String>,
    },
    /// Print a partial render's header as JSON: resolution, window, sample range, spp,
    /// seed, scene hash, whether it carries AOVs.
    Info {
        /// The partial EXR.
        part: PathBuf,
    },
}

#[derive(clap::Args)]
struct MergeArgs {
    /// The partial EXRs.
    #[arg(required = true)]
    parts: Vec<PathBuf>,
    /// The merged EXR; the PNG preview is written beside it.
    #[arg(long)]
    out: PathBuf,
    /// The merged stats JSON. Defaults to OUT with the extension .stats.json.
    #[arg(long)]
    stats: Option<PathBuf>,
    /// Exposure of the PNG preview in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render_command(*args),
        Command::Compare { test, reference } => compare_command(&test, &reference),
        Command::Techniques { scene, defines } => techniques_command(&scene, &defines),
        Command::Converge(args) => converge_command(args),
        Command::Merge(args) => merge_command(args),
        Command::Info { part } => info_command(&part),
        Command::Convert {
            scene,
            out,
            defines,
        } => convert_command(&scene, &out, &defines),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // 128 + SIGINT, the shell's status for a command ended by Ctrl-C.
        Err(e) if e.is::<interrupt::Interrupted>() => {
            eprintln!("{}", printable(&format!("{e:#}")));
            ExitCode::from(130)
        }
        Err(e) => {
            eprintln!("error: {}", printable(&format!("{e:#}")));
            ExitCode::FAILURE
        }
    }
}

/// Longest line of an error message printed, in characters.
const MAX_MESSAGE_LINE: usize = 1000;

/// An error message as printed: control characters escaped (a file name can carry terminal
/// escape sequences) and every line cut at [`MAX_MESSAGE_LINE`] characters, saying how much
/// was left out (a message can quote a hostile file's megabyte-long line).
fn printable(message: &str) -> String {
    message
        .lines()
        .map(|line| {
            let line = risotto::engine::diagnostics::terminal_safe(line);
            match line.char_indices().nth(MAX_MESSAGE_LINE) {
                Some((cut, _)) => {
                    let rest = line[cut..].chars().count();
                    format!("{} ... ({rest} more characters)", &line[..cut])
                }
                None => line,
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// How often `--display` updates the viewer.
const DISPLAY_EVERY: std::time::Duration = std::time::Duration::from_secs(1);

fn render_command(args: RenderArgs) -> Result<()> {
    check_exposure(args.exposure)?;
    check_threads(args.threads)?;
    anyhow::ensure!(
        !args.denoise || cfg!(feature = "denoise"),
        "--denoise: this risotto was built without the `denoise` feature (Intel Open Image \
         Denoise); README, \"Denoising\", says how to build it"
    );
    let input = SceneInput::read(&args.scene, &args.defines, args.size.as_deref())?;
    let out = args.out.clone().unwrap_or_else(|| input.default_output());
    if args.replay.is_none() {
        let scene_file: &[(&str, &Path)] = if input.path == Path::new(STDIN_NAME) {
            &[]
        } else {
            &[("the scene", &args.scene)]
        };
        check_outputs(scene_file, &out, args.stats.as_deref(), !args.no_preview)?;
    }
    let registry = MaterialRegistry::with_builtins();
    let load_start = std::time::Instant::now();
    let mut scene = input.load(&registry)?;
    let load_seconds = load_start.elapsed().as_secs_f64();
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
    let build_start = std::time::Instant::now();
    let compiled = compile_scene(scene)?;
    let build_seconds = build_start.elapsed().as_secs_f64();
    let techniques = render_techniques(&args, &compiled)?;
    if let Some(spec) = &args.replay {
        let (x, y, sample) = parse_replay(spec)?;
        let options = techniques.render_options(RenderOptions::default());
        let r = replay(&compiled, &options, x, y, sample).map_err(|e| match e {
            RenderError::Replay { reason, .. } => anyhow::anyhow!("--replay {spec}: {reason}"),
            e => e.into(),
        })?;
        // A reader that stops early (`| head`) is not an error.
        use std::io::Write;
        return match writeln!(std::io::stdout().lock(), "{r}") {
            Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
                Err(e).context("cannot write the replay to stdout")
            }
            _ => Ok(()),
        };
    }
    let (width, height) = (compiled.camera.width, compiled.camera.height);
    let crop = match (&args.crop, &args.grid, &args.tile) {
        (Some(c), _, _) => Some(parse_crop(c)?),
        (None, Some(grid), Some(tile)) => Some(grid_tile(grid, tile, width, height)?),
        _ => None,
    };
    let samples = match (&args.samples, args.chunks, args.chunk) {
        (Some(s), _, _) => {
            Some(parse_sample_range(s).map_err(|e| anyhow::anyhow!("--samples {e}"))?)
        }
        (None, Some(n), Some(j)) => Some(sample_chunk(n, j, compiled.settings.spp)?),
        _ => None,
    };
    // `try_from`: an interval past `Duration`'s range (about 5.8e11 years) is an error, not
    // the panic `from_secs_f64` gives.
    let checkpoint = match args.checkpoint {
        Some(t) if t.is_finite() && t > 0.0 => match std::time::Duration::try_from_secs_f64(t) {
            Ok(d) => Some(d),
            Err(_) => anyhow::bail!(
                "--checkpoint {t:e}: too long (at most {:e} seconds)",
                u64::MAX as f64
            ),
        },
        Some(t) => anyhow::bail!("--checkpoint {t}: must be a positive number of seconds"),
        None => None,
    };
    let partial = args.partial || crop.is_some() || samples.is_some() || checkpoint.is_some();
    let noise_target = match args.noise_target {
        Some(x) if x.is_finite() && x > 0.0 => {
            anyhow::ensure!(args.min_spp >= 1, "--min-spp 0: must be at least 1");
            Some(NoiseTarget {
                relative_error: x,
                min_spp: args.min_spp,
                rule: args.stopping_rule.into(),
            })
        }
        Some(x) => {
            anyhow::bail!("--noise-target {x}: must be a positive relative error (e.g. 0.02)")
        }
        None => None,
    };
    if let Some(target) = &noise_target {
        // A pixel may stop from `2 min_spp` samples on and takes at most the scene's spp:
        // when the first is not below the second, no pixel stops early.
        let (earliest, cap) = (target.min_spp.saturating_mul(2), compiled.settings.spp);
        if earliest >= cap {
            eprintln!(
                "warning: --min-spp {}: no pixel can stop before {earliest} samples, and a \
                 pixel takes at most {cap} (the scene's spp or --spp): every pixel takes all \
                 {cap}, as without --noise-target",
                target.min_spp
            );
        }
    }
    let options = techniques.render_options(RenderOptions {
        threads: args.threads,
        batch_size: args.batch_size,
        crop,
        samples,
        interrupt: Some(interrupt::install()?),
        noise_target,
        // The first-hit AOVs cost 140 bytes a pixel (`AOV_BYTES_PER_PIXEL`): kept only for
        // the layers `--aovs` writes and the guides `--denoise` reads.
        aovs: args.aovs || args.denoise,
        ..RenderOptions::default()
    });
    let (window, range) = checked_extent(&compiled, &options).map_err(|e| match e {
        // pbrt users type x0,x1,y0,y1: say which order this is.
        RenderError::Crop { window, reason } => anyhow::anyhow!(
            "--crop {window}: {reason}; --crop takes X0,Y0,X1,Y1 (columns X0..X1, rows \
             Y0..Y1, half-open, of the {width}x{height} image), not pbrt's x0,x1,y0,y1"
        ),
        RenderError::Samples { samples, reason } => {
            anyhow::anyhow!("--samples {samples}: {reason}")
        }
        e => e.into(),
    })?;
    let total = range.len() as u64 * window.pixels() as u64;
    // An adaptive render's total is the most it can take: it stops at the noise target.
    let adaptive = options.noise_target.is_some();
    let json = (args.progress == ProgressMode::Json)
        .then(|| progress::JsonProgress::new(total, adaptive, std::time::Duration::from_secs(1)));
    let bar = if args.quiet || args.progress != ProgressMode::Bar {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(total);
        b.set_style(match adaptive {
            true => progress::adaptive_bar_style(),
            false => progress::bar_style(),
        });
        b
    };
    let settings = &compiled.settings;
    let resolution = (compiled.camera.width, compiled.camera.height);
    let hash = if partial {
        split::partial_scene_hash(&input, &compiled, &techniques)?
    } else {
        String::new()
    };
    let (spp, seed) = (settings.spp, settings.seed);
    let to_partial =
        |r: &RenderOutput| Partial::of_render(r, resolution, spp, seed, hash.clone(), args.aovs);
    let announced = std::sync::atomic::AtomicBool::new(false);
    let tick = |n: u64| {
        if interrupt::requested() && !announced.swap(true, std::sync::atomic::Ordering::Relaxed) {
            bar.suspend(|| {
                eprintln!(
                    "interrupted: finishing the samples in flight, then writing what is done \
                     (interrupt again to quit at once)"
                )
            });
        }
        bar.inc(n);
        if let Some(j) = &json {
            j.inc(n);
        }
    };
    // A checkpoint that cannot be written (a full disk, a vanished directory) costs only the
    // protection it would have given: the render goes on, and the failure is a warning.
    let mut failed_checkpoints = 0u32;
    let mut display = args.display.as_deref().and_then(|address| {
        let name = out.file_name().map_or_else(
            || "risotto".to_owned(),
            |n| n.to_string_lossy().into_owned(),
        );
        display::TevDisplay::connect(address, &name, width, height)
            .map_err(|e| bar.suspend(|| eprintln!("warning: {}; rendering on", printable(&e))))
            .ok()
    });
    let mut result = if checkpoint.is_none() && display.is_none() {
        render(&compiled, &options, &tick)?
    } else {
        // Passes: a checkpoint after those that end its interval, the display after each.
        let every = match (checkpoint, &display) {
            (Some(c), Some(_)) => c.min(DISPLAY_EVERY),
            (Some(c), None) => c,
            (None, _) => DISPLAY_EVERY,
        };
        // Without a display every pass ends a checkpoint interval (as before); with one, the
        // passes are the display's and a checkpoint follows those that end about its interval
        // (passes are sized to take `every`, give or take).
        let checkpoint_every_pass = display.is_none();
        let mut last_checkpoint = std::time::Instant::now();
        let mut write = |r: &RenderOutput| {
            if let Some(d) = display.as_mut() {
                if let Err(e) = d.show(&r.beauty, r.window) {
                    bar.suspend(|| eprintln!("warning: --display stopped: {e}"));
                    display = None;
                }
            }
            if checkpoint.is_some_and(|c| {
                checkpoint_every_pass || last_checkpoint.elapsed() >= c.mul_f64(0.75)
            }) {
                last_checkpoint = std::time::Instant::now();
                if let Err(e) = write_partial(&out, &to_partial(r)) {
                    failed_checkpoints += 1;
                    let e = printable(&e.to_string());
                    bar.suspend(|| eprintln!("warning: checkpoint not written, rendering on: {e}"));
                }
            }
            Ok(())
        };
        let result = render_checkpointed(
            &compiled,
            &options,
            &tick,
            Checkpoints {
                every,
                write: &mut write,
            },
        )?;
        if let Some(d) = display.as_mut() {
            if let Err(e) = d.show(&result.beauty, result.window) {
                bar.suspend(|| eprintln!("warning: --display stopped: {e}"));
            }
        }
        result
    };
    bar.finish_and_clear();
    if let Some(j) = &json {
        j.finish();
    }
    if failed_checkpoints > 0 {
        eprintln!(
            "warning: {failed_checkpoints} checkpoint(s) could not be written to {}",
            printable(&out.display().to_string())
        );
    }
    result.stats.render_command = Some(replay_base_command(&args));
    // The global pool's threads: `--threads` sized it (`check_threads`), and the render's
    // own pool has as many.
    let threads = rayon::current_num_threads();
    result.stats.run = Some(run_info::run_info(
        &compiled,
        &result,
        threads,
        load_seconds,
        build_seconds,
    ));

    // Interrupted: the passes done are written as a partial render that `merge` finishes.
    // An adaptive render ends early by design; only a signal interrupts it, and what it has
    // is written as a whole image (its pixels' sample counts differ: not a partial render).
    let mut denoised = None;
    let output_start = std::time::Instant::now();
    let interrupted = match noise_target {
        Some(_) => interrupt::requested(),
        None => result.samples.end < range.end,
    };
    if interrupted && noise_target.is_none() {
        let hash = match partial {
            true => hash.clone(),
            false => split::partial_scene_hash(&input, &compiled, &techniques)?,
        };
        let part = Partial::of_render(&result, resolution, spp, seed, hash, args.aovs);
        write_partial(&out, &part)?;
    } else if partial {
        write_partial(&out, &to_partial(&result))?;
    } else if args.denoise {
        let image = denoise_render(&mut result)?;
        let part = rgb_part("denoised", &image, Vec::new());
        write_exr_placed(&out, &result.film_output(args.aovs), None, Some(part))?;
        denoised = Some(image);
    } else {
        write_exr(&out, &result.film_output(args.aovs))?;
    }
    let png = (!args.no_preview).then(|| out.with_extension("png"));
    if let Some(png) = &png {
        write_png(
            png,
            denoised.as_ref().unwrap_or(&result.beauty),
            args.exposure,
        )?;
    }
    // The files' time, without the denoiser's (its own `denoise_seconds`).
    let denoise_seconds = result.stats.run.as_ref().and_then(|r| r.denoise_seconds);
    if let Some(run) = &mut result.stats.run {
        let seconds = output_start.elapsed().as_secs_f64() - denoise_seconds.unwrap_or(0.0);
        run.output_seconds = Some(seconds.max(0.0));
    }
    if let Some(path) = &args.stats {
        result
            .stats
            .write_json(path)
            .with_context(|| format!("cannot write stats to {}", path.display()))?;
    }
    if !args.quiet {
        eprintln!("{}", result.stats);
        match &png {
            Some(png) => eprintln!("wrote {} and {}", out.display(), png.display()),
            None => eprintln!("wrote {}", out.display()),
        }
    }
    if interrupted && noise_target.is_some() {
        return Err(interrupt::Interrupted(format!(
            "interrupted: {} holds the image so far (an adaptive render cannot be resumed)",
            out.display()
        ))
        .into());
    }
    if interrupted {
        let (done, want) = (result.samples, range);
        let rest = out.with_file_name("rest.exr");
        return Err(interrupt::Interrupted(format!(
            "interrupted: {} holds samples {}..{} of {}..{} (a partial render); to finish:\n  \
             {} --samples {}..{} --out {}\n  risotto merge {} {} --out FINAL.exr",
            out.display(),
            done.start,
            done.end,
            want.start,
            want.end,
            finish_command(&args),
            done.end,
            want.end,
            rest.display(),
            out.display(),
            rest.display(),
        ))
        .into());
    }
    Ok(())
}

/// The render's beauty denoised (`--denoise`), with the time it took in the stats.
#[cfg(feature = "denoise")]
fn denoise_render(result: &mut RenderOutput) -> Result<Image> {
    let start = std::time::Instant::now();
    let image = risotto::denoise::denoise(&result.beauty, &result.albedo, &result.normal)?;
    if let Some(run) = &mut result.stats.run {
        run.denoise_seconds = Some(start.elapsed().as_secs_f64());
    }
    Ok(image)
}

/// Without the `denoise` feature `--denoise` is refused before the render starts.
#[cfg(not(feature = "denoise"))]
fn denoise_render(_: &mut RenderOutput) -> Result<Image> {
    anyhow::bail!("--denoise: built without the `denoise` feature")
}

/// The command that renders what an interrupted render left: the options that decide a
/// path and those a merge requires to match (window, AOVs).
fn finish_command(args: &RenderArgs) -> String {
    let mut cmd = replay_base_command(args);
    for (flag, value) in [
        ("--crop", &args.crop),
        ("--grid", &args.grid),
        ("--tile", &args.tile),
    ] {
        if let Some(v) = value {
            cmd += &format!(" {flag} {v}");
        }
    }
    if args.aovs {
        cmd += " --aovs";
    }
    cmd
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
    let registry = TechniqueRegistry::for_scene(scene);
    let mut t = Techniques::default();
    let mut given: Vec<(&str, String)> = Vec::new();
    for (flag, a) in &assignments {
        let tech = t.assign(&registry, a).with_context(|| flag.clone())?;
        let value = t.get(&registry, tech.name)?.to_string();
        if let Some((_, v)) = given.iter().find(|(n, v)| *n == tech.name && *v != value) {
            anyhow::bail!(
                "{flag}: {} was already set to {v} (by --lighting or another --technique)",
                tech.name
            );
        }
        given.push((tech.name, value));
        if !registry.applies(tech) {
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

fn convert_command(scene_path: &Path, out: &Path, defines: &[String]) -> Result<()> {
    let input = SceneInput::read(scene_path, &[], None)?;
    if scene_path != Path::new("-") && same_file(scene_path, out) {
        anyhow::bail!(
            "{}: the output would overwrite the scene being converted",
            out.display()
        );
    }
    let (toml, warnings) =
        risotto::loader::scene_file::convert_scene(&input.text, &input.path, defines, out)?;
    for w in &warnings {
        eprintln!("warning: {}", printable(w));
    }
    std::fs::write(out, toml).with_context(|| format!("{}: cannot write", out.display()))?;
    Ok(())
}

fn techniques_command(scene_path: &Path, defines: &[String]) -> Result<()> {
    let registry = MaterialRegistry::with_builtins();
    let input = SceneInput::read(scene_path, defines, None)?;
    let compiled = compile_scene(input.load(&registry)?)?;
    print!(
        "{}{}",
        technique::listing(&TechniqueRegistry::for_scene(&compiled)),
        risotto::tools::converge::listing(&compiled)
    );
    Ok(())
}

/// `--exposure`, checked by the engine's rule before any work.
pub(crate) fn check_exposure(stops: f32) -> Result<()> {
    risotto::engine::output::check_exposure(stops)
        .map_err(|why| anyhow::anyhow!("--exposure {stops}: {why}"))
}

/// `--threads`, checked by the engine's rule before the scene is loaded so a typo costs
/// nothing, and made the size of rayon's global pool: loading and compiling (the parallel
/// OBJ read, the BVH build's bins and subtrees) run there, and a render limited to N
/// threads uses N in every phase, as pbrt-v4's `--nthreads` and Mitsuba's `-t` do. Before
/// the scene is loaded, so nothing has started the global pool yet.
pub(crate) fn check_threads(threads: Option<usize>) -> Result<()> {
    let Some(n) = threads else { return Ok(()) };
    risotto::engine::render::check_threads(n)
        .map_err(|why| anyhow::anyhow!("--threads {n}: {why}"))?;
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build_global()
        .map_err(|e| anyhow::anyhow!("--threads {n}: cannot start the thread pool: {e}"))
}

fn compare_command(test: &Path, reference: &Path) -> Result<()> {
    let t = read_exr_rgb(test)?;
    let r = read_exr_rgb(reference)?;
    let m = compare(&t, &r)?;
    println!("{m}");
    Ok(())
}

/// Checks the outputs of `risotto render` and `risotto merge` before any work: `out` is an
/// EXR, the PNG preview beside it (when `preview`) and the stats file are distinct from it,
/// from each other and from the command's `inputs` (the scene, or the parts merged:
/// `(what, path)`), and each can be written (its directory exists, it is not a directory,
/// and it can be opened for writing). Nothing is created or truncated here.
pub(crate) fn check_outputs(
    inputs: &[(&str, &Path)],
    out: &Path,
    stats: Option<&Path>,
    preview: bool,
) -> Result<()> {
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
    let mut named: Vec<(&str, PathBuf)> = inputs
        .iter()
        .map(|&(what, p)| (what, p.to_path_buf()))
        .collect();
    named.push(("--out", out.to_path_buf()));
    if preview {
        named.push(("the PNG preview", png));
    }
    if let Some(stats) = stats {
        named.push(("--stats", stats.to_path_buf()));
    }
    // Each output against the inputs and the outputs before it (inputs may repeat: that
    // is the command's own error to report).
    for (i, (a, pa)) in named.iter().enumerate().skip(inputs.len()) {
        for (b, pb) in &named[..i] {
            anyhow::ensure!(
                !same_file(pa, pb),
                "{a} {} is the same file as {b} {}: one would overwrite the other",
                pa.display(),
                pb.display()
            );
        }
    }
    for (what, path) in named.iter().skip(inputs.len()) {
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
