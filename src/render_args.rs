//! `risotto render`'s command line: every option, documented for `--help`.

use std::path::PathBuf;

use crate::display;

#[derive(clap::Args)]
pub(crate) struct RenderArgs {
    /// The scene file (TOML, see docs/scene-format.md), or `-` to read it from standard input
    /// (relative paths in it then resolve against the current directory).
    pub(crate) scene: PathBuf,
    /// Override a scene value by its TOML path, KEY.PATH=VALUE (repeatable; the later wins):
    /// `-D render.spp=16`, `-D materials.glass.ior=1.33`, `-D shapes.0.radius=2`; arrays of
    /// tables are indexed from 0, values are TOML (a bare word is a string). See
    /// docs/scene-format.md, "Overrides".
    #[arg(short = 'D', long = "define", value_name = "KEY.PATH=VALUE")]
    pub(crate) defines: Vec<String>,
    /// Samples per pixel (overrides the scene).
    #[arg(long)]
    pub(crate) spp: Option<u32>,
    /// Image size WIDTHxHEIGHT (overrides the scene's `render.width` and `render.height`).
    #[arg(long, value_name = "WxH")]
    pub(crate) size: Option<String>,
    /// Output EXR; the PNG preview is written beside it. Defaults to SCENE_STEM.exr in the
    /// current directory (render.exr for a scene from standard input).
    #[arg(short = 'o', long)]
    pub(crate) out: Option<PathBuf>,
    /// Do not write the PNG preview.
    #[arg(long)]
    pub(crate) no_preview: bool,
    /// Write render statistics as JSON to this file.
    #[arg(long)]
    pub(crate) stats: Option<PathBuf>,
    /// Worker threads (defaults to all cores), for every phase: reading the scene, building it
    /// and rendering
    #[arg(short = 't', long)]
    pub(crate) threads: Option<usize>,
    /// Sampler seed (overrides the scene).
    #[arg(long)]
    pub(crate) seed: Option<u64>,
    /// Maximum path segments (overrides the scene; -1 = unbounded).
    #[arg(long, allow_negative_numbers = true)]
    pub(crate) max_depth: Option<i64>,
    /// Exposure of the PNG preview in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub(crate) exposure: f32,
    /// Also write albedo, normal and depth AOVs into the EXR (means of each sample's first
    /// hit). Partial renders (--crop, --grid, --samples, --chunks, --checkpoint, --partial)
    /// then carry the AOVs' f64 sums too, and `risotto merge` writes the same layers.
    #[arg(long)]
    pub(crate) aovs: bool,
    /// Denoise the image with Intel Open Image Denoise, guided by the albedo and normal
    /// layers: the EXR keeps the noisy beauty and gains a `denoised` part, and the PNG
    /// preview shows the denoised image. Needs a build with the `denoise` feature (README,
    /// "Denoising"); not with the flags of partial renders.
    #[arg(long, conflicts_with_all = [
        "crop", "grid", "tile", "chunks", "chunk", "samples", "checkpoint", "partial",
    ])]
    pub(crate) denoise: bool,
    /// Direct-lighting technique: mis (the default), nee, bxdf. An alias of
    /// `--technique lighting=VALUE`.
    #[arg(long)]
    pub(crate) lighting: Option<String>,
    /// A technique, NAME=VALUE (repeatable); `risotto techniques SCENE` lists them.
    #[arg(long = "technique", value_name = "NAME=VALUE")]
    pub(crate) techniques: Vec<String>,
    /// Paths per batch (1 to 16777216: a batch's tables are allocated whole).
    #[arg(long, default_value_t = 4096)]
    pub(crate) batch_size: usize,
    /// Render only this pixel window of the full image, X0,Y0,X1,Y1 (columns X0..X1, rows
    /// Y0..Y1, half-open; same camera and per-pixel seeds as the whole render). Writes a
    /// partial EXR for `risotto merge`.
    #[arg(long, value_name = "X0,Y0,X1,Y1", conflicts_with = "grid")]
    pub(crate) crop: Option<String>,
    /// Cut the image into COLSxROWS tiles (column c of C spans c*W/C..(c+1)*W/C) and render
    /// the tile --tile COL,ROW: --crop for farm task indices.
    #[arg(long, value_name = "COLSxROWS", requires = "tile")]
    pub(crate) grid: Option<String>,
    /// The tile of --grid to render, COL,ROW counted from 0 at the top left.
    #[arg(long, value_name = "COL,ROW", requires = "grid")]
    pub(crate) tile: Option<String>,
    /// Cut each pixel's spp into N sample chunks (chunk j spans j*spp/N..(j+1)*spp/N) and
    /// render chunk --chunk J: --samples for farm task indices.
    #[arg(long, value_name = "N", requires = "chunk", conflicts_with = "samples")]
    pub(crate) chunks: Option<u32>,
    /// The chunk of --chunks to render, from 0.
    #[arg(long, value_name = "J", requires = "chunks")]
    pub(crate) chunk: Option<u32>,
    /// Render only the sample indices START..END (half-open) of each pixel. Writes a partial
    /// EXR for `risotto merge`.
    #[arg(long, value_name = "START..END")]
    pub(crate) samples: Option<String>,
    /// Write the partial EXR to --out about every SECONDS while rendering (atomically), so
    /// a killed render loses at most about that much work; see README, "Splitting, merging and resuming".
    #[arg(long, value_name = "SECONDS")]
    pub(crate) checkpoint: Option<f64>,
    /// Write the merge data (a partial EXR) even for a whole render.
    #[arg(long)]
    pub(crate) partial: bool,
    /// Adaptive sampling: each pixel stops once its estimated relative error (standard
    /// error over value, as --stopping-rule estimates it) is at most X, e.g. 0.02; the
    /// scene's spp (or --spp) is then the most a pixel takes. See README, "Accuracy and its cost".
    #[arg(
        long,
        value_name = "X",
        conflicts_with_all = ["samples", "chunks", "checkpoint", "partial", "crop", "grid"]
    )]
    pub(crate) noise_target: Option<f32>,
    /// With --noise-target: the samples every pixel takes before any stops.
    #[arg(
        long,
        value_name = "N",
        default_value_t = 16,
        requires = "noise_target"
    )]
    pub(crate) min_spp: u32,
    /// With --noise-target: which samples decide that a pixel stops. `window`: its own and
    /// its eight neighbours' (spends the samples best; biased where light arrives by rare
    /// paths). `unbiased`: a pilot of --min-spp samples a pixel, discarded, and the pixels
    /// before it, never its own samples (an unbiased mean, for --min-spp more samples a
    /// pixel). See README, "Renders that stop at a requested accuracy".
    #[arg(
        long,
        value_enum,
        default_value_t = StoppingRuleArg::Window,
        requires = "noise_target"
    )]
    pub(crate) stopping_rule: StoppingRuleArg,
    /// Show the image while it renders in the tev viewer listening at HOST:PORT (default
    /// 127.0.0.1:14158, tev's own), updated about every second (pbrt-v4's
    /// --display-server). A viewer that is not there costs a warning, not the render.
    #[arg(
        long,
        alias = "display-server",
        value_name = "HOST:PORT",
        num_args = 0..=1,
        default_missing_value = display::DEFAULT_ADDRESS
    )]
    pub(crate) display: Option<String>,
    /// No progress bar and no summary.
    #[arg(long)]
    pub(crate) quiet: bool,
    /// How progress is shown: `bar` (on stderr), `json` (one JSON object per line on stdout,
    /// at most one a second, for farm managers; see README, "Splitting, merging and resuming"), or `none`.
    #[arg(long, value_enum, default_value_t = ProgressMode::Bar)]
    pub(crate) progress: ProgressMode,
    /// Re-run only sample SAMPLE of pixel X,Y (column, row from the top left), alone and
    /// single-threaded, and print each vertex of its path (position, material or volume,
    /// throughput, Bxdf and light pdfs, radiance added, where it became non-finite) on
    /// stdout. Writes no image. The stats' non-finite cases print this command.
    #[arg(
        long,
        value_name = "X,Y,SAMPLE",
        conflicts_with_all = [
            "out", "stats", "crop", "grid", "tile", "chunks", "chunk", "samples",
            "checkpoint", "partial", "aovs", "denoise",
        ]
    )]
    pub(crate) replay: Option<String>,
}

/// `risotto render --stopping-rule`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum StoppingRuleArg {
    Window,
    Unbiased,
}

impl From<StoppingRuleArg> for risotto::engine::render::StoppingRule {
    fn from(rule: StoppingRuleArg) -> Self {
        match rule {
            StoppingRuleArg::Window => Self::Window,
            StoppingRuleArg::Unbiased => Self::Unbiased,
        }
    }
}

/// `risotto render --progress`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum ProgressMode {
    Bar,
    Json,
    None,
}
