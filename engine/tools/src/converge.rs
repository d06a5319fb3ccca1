//! The convergence sweep behind `risotto converge`: what accuracy costs in time, per
//! technique ([`risotto_engine::technique`]).
//!
//! One compiled scene is rendered with every variant (a [`Variant`]: a [`Techniques`]
//! choice, uniform or adaptive) at every samples-per-pixel count (an adaptive one at every
//! noise target), `repeats` times with seeds `seed, seed + 1, ...`, and each
//! render's wall time (the [`render`] call alone: no loading, compiling or writing) and
//! error against a reference are recorded. A point's time is its fastest repeat's (the
//! least disturbed by other load; the mean and the slowest are reported too). Before the sweep one uncounted 1-spp render warms
//! the thread pool and the sampler tables up, so the first point is not charged for them.
//!
//! # Metrics
//! Against the reference `r`, with [`compare`] (finite entries of all channels pooled):
//! `MSE = mean (t - r)^2`, `RMSE = sqrt(MSE)`, `relMSE = mean (t - r)^2 / (r^2 + 0.01)`, and the
//! bias of the mean per channel, `mean(t) - mean(r)`. Each point reports the mean over the
//! repeats and their min and max (error bars). The efficiency of a curve is
//! `1 / (MSE x seconds)` at its largest spp (for an unbiased Monte Carlo estimator it is
//! about constant along the curve, the usual figure of merit).
//!
//! The sweep's **error metric** ([`ErrorMetric`], `--metric`) is what the efficiency, the
//! fits, the equal-time and equal-error comparison and the plot use: the MSE by default, or
//! the relMSE, which weighs every pixel's error by its brightness, so that a few very bright
//! pixels whose error no technique changes (a small lamp seen in glass) do not hide what
//! the rest of the image does. Both are recorded for every point either way.
//!
//! # The reference's own noise
//! A reference rendered by the tool (`--reference-spp N`) is the mean `r = (a + b) / 2` of two
//! independent renders of `N / 2` spp each (seeds unused by the sweep). For a test image `t`
//! independent of it, `E (t - r)^2 = E (t - mu)^2 + Var r` per pixel, and since `a` and `b` are
//! independent with equal variance `v`, `E (a - b)^2 = 2 v` and `Var r = v / 2 =
//! E (a - b)^2 / 4`. So `mean (a - b)^2 / 4` is subtracted from every MSE, and `mean (a - b)^2 /
//! (4 (r^2 + 0.01))` from every relMSE (first order: it treats the denominator as exact).
//! The corrected values can come out slightly negative when the test error is below the
//! reference's noise; such points are left out of the plot and the fits. A reference given
//! as an EXR (`--reference REF.exr`) has no such estimate and is taken as exact.
//!
//! # The reference's technique
//! Unless one is given, a rendered reference uses the sweep's most efficient variant, judged
//! before any reference exists: among the variants whose every value converges to the exact
//! image (not, e.g., `scattering=single`), the largest `1 / (MSE x seconds)` at each
//! variant's largest spp, with the MSE of an unbiased estimator taken as its variance,
//! `mean (a - b)^2 / 2` over two renders with different seeds (the first two repeats, or one
//! extra render when the sweep has a single repeat).
//!
//! # Adaptive curves
//! A variant with `adaptive=on` ([`Variant`]) renders with a noise target
//! ([`NoiseTarget`]: a pixel stops once its estimated relative error is at the target)
//! instead of a fixed spp: its points are the targets of [`AdaptivePlan`], descending, each
//! with its `min_spp` and the sweep's largest spp as the most a pixel takes (the cap), and
//! each records its target and the mean spp its pixels took (the `sampleCount` layer's
//! mean). A curve stops at the first target at which every pixel took the cap: a smaller
//! one renders the same image. With a time budget the cap is not known in advance: the
//! adaptive curves render after the uniform ones, capped at the largest spp those reached
//! (at least `4 x min_spp`, so that pixels can stop early; `MAX_SPP` without a uniform
//! curve), their first target halved until a render takes the budget. Adaptive sampling's stopping rule is biased (it reads the
//! samples it stops on), so an adaptive variant never renders the reference.

use crate::compare::{compare, CompareError, DEFAULT_RELMSE_EPS};
use risotto_engine::output::Image;
use risotto_engine::render::{render, NoiseTarget, RenderError, RenderOptions};
use risotto_engine::scene::CompiledScene;
use risotto_engine::technique::{TechniqueError, TechniqueRegistry, Techniques};
use risotto_systems::sampler::MAX_SPP;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// Which samples-per-pixel counts each variant renders.
#[derive(Clone, Debug, PartialEq)]
pub enum SppPlan {
    /// These counts (ascending).
    List(Vec<u32>),
    /// 1, 2, 4, ... until a render (mean over the repeats) takes at least this many seconds.
    Budget(f64),
}

/// Where the reference comes from.
#[derive(Clone, Debug)]
#[allow(
    clippy::large_enum_variant,
    reason = "built once per sweep; the techniques it holds are plain `Copy` data"
)]
pub enum Reference {
    /// A given image (its path for the report); taken as exact.
    Image {
        /// The image.
        image: Image,
        /// Where it was read from.
        path: String,
    },
    /// Rendered by the sweep after the test renders, as two independent halves.
    Render {
        /// Samples per pixel (both halves together); `None`: 16 times the sweep's largest
        /// spp, at most `MAX_SPP`.
        spp: Option<u32>,
        /// The techniques it is rendered with; `None`: the sweep's most efficient variant
        /// among those that converge to the exact image, judged without a reference (see
        /// the module docs).
        techniques: Option<Techniques>,
    },
}

/// The error a sweep compares its techniques by (module docs, "Metrics").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ErrorMetric {
    /// `mean (t - r)^2`.
    #[default]
    Mse,
    /// `mean (t - r)^2 / (r^2 + 0.01)`.
    RelMse,
}

impl ErrorMetric {
    /// How tables and plots name it.
    pub fn label(self) -> &'static str {
        match self {
            ErrorMetric::Mse => "MSE",
            ErrorMetric::RelMse => "relMSE",
        }
    }

    /// The metric called `name` (`mse` or `relmse`).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "mse" => Some(ErrorMetric::Mse),
            "relmse" => Some(ErrorMetric::RelMse),
            _ => None,
        }
    }
}

/// What to sweep.
#[derive(Clone, Debug)]
pub struct ConvergeOptions {
    /// The variants, one curve each.
    pub variants: Vec<Variant>,
    /// The spp counts (of the uniform variants; the adaptive ones' cap is the largest).
    pub plan: SppPlan,
    /// The noise targets and minimum spp of the adaptive variants.
    pub adaptive: AdaptivePlan,
    /// Renders per point (different seeds).
    pub repeats: u32,
    /// The reference.
    pub reference: Reference,
    /// Threads, batch and tile size of every render (the techniques are set per variant).
    pub render: RenderOptions,
    /// The error the curves are compared by.
    pub metric: ErrorMetric,
}

/// Progress callbacks of [`run`].
pub struct Progress<'a> {
    /// A render starts: its description (`lighting=nee, 16 spp, repeat 1/2`).
    pub stage: &'a dyn Fn(&str),
    /// Samples finished (from worker threads).
    pub samples: &'a (dyn Fn(u64) + Sync),
}

/// Errors of the sweep.
#[derive(Debug, thiserror::Error)]
pub enum ConvergeError {
    /// A bad technique.
    #[error(transparent)]
    Technique(#[from] TechniqueError),
    /// A render failed.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// The reference cannot be compared with the renders.
    #[error("reference {path}: {cause}")]
    Reference {
        /// The reference.
        path: String,
        /// Why (part of the message, so not also `source()`, which would repeat it).
        cause: CompareError,
    },
    /// Bad options.
    #[error("{0}")]
    Options(String),
    /// Writing an output failed.
    #[error("cannot write {path}: {message}")]
    Write {
        /// The file.
        path: String,
        /// Why.
        message: String,
    },
}

/// One point of a curve: one spp count (or noise target), over the repeats.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Point {
    /// Samples per pixel (of an adaptive point: the most a pixel may take, the cap).
    pub spp: u32,
    /// Renders averaged.
    pub repeats: u32,
    /// Render seconds of the fastest repeat: the point's time (the measurement least
    /// disturbed by other load on the machine, as benchmarks take the minimum).
    pub seconds: f64,
    /// Mean render seconds of the repeats.
    pub seconds_mean: f64,
    /// Slowest repeat.
    pub seconds_max: f64,
    /// Mean MSE (reference noise subtracted), and the min and max over the repeats.
    pub mse: f64,
    /// Smallest MSE of a repeat.
    pub mse_min: f64,
    /// Largest MSE of a repeat.
    pub mse_max: f64,
    /// `sqrt(max(mse, 0))`.
    pub rmse: f64,
    /// Mean relMSE (reference noise subtracted).
    pub relmse: f64,
    /// Smallest relMSE of a repeat.
    pub relmse_min: f64,
    /// Largest relMSE of a repeat.
    pub relmse_max: f64,
    /// Mean bias of the image mean per channel, `mean(test) - mean(reference)`.
    pub bias: [f64; 3],
    /// `1 / (error x seconds)` with the sweep's metric ([`Sweep::metric`]) (NaN, `null` in
    /// JSON, when the error is not positive).
    pub efficiency: f64,
    /// The relative error an adaptive point's pixels stop at; `None` (absent in JSON) for
    /// a uniform point.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise_target: Option<f64>,
    /// The mean samples per pixel an adaptive point took (the `sampleCount` layer's mean,
    /// averaged over the repeats); `None` (absent in JSON) for a uniform point.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spp_mean: Option<f64>,
}

impl Point {
    /// The point's error by `metric`: its mean, smallest and largest over the repeats.
    pub fn error(&self, metric: ErrorMetric) -> (f64, f64, f64) {
        match metric {
            ErrorMetric::Mse => (self.mse, self.mse_min, self.mse_max),
            ErrorMetric::RelMse => (self.relmse, self.relmse_min, self.relmse_max),
        }
    }

    /// The samples per pixel the point took: its mean for an adaptive point, else its spp.
    pub fn samples(&self) -> f64 {
        self.spp_mean.unwrap_or(self.spp as f64)
    }
}

/// One variant's curve.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Curve {
    /// The variant's label ([`Variant::label`]).
    pub label: String,
    /// Every technique's value.
    pub techniques: BTreeMap<String, String>,
    /// Points in ascending spp (descending noise target).
    pub points: Vec<Point>,
    /// `1 / (MSE x seconds)` at the largest spp.
    pub efficiency: f64,
    /// Least-squares slope of ln MSE against ln seconds (about -1 for Monte Carlo; noisy
    /// where renders take milliseconds).
    pub mse_time_slope: f64,
    /// Least-squares slope of ln RMSE against ln spp (about -1/2 for Monte Carlo); of an
    /// adaptive curve, against ln of the mean spp.
    pub rmse_spp_slope: f64,
}

/// What the reference was.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ReferenceInfo {
    /// `"file"` or `"rendered"`.
    pub source: String,
    /// The file, when given.
    pub path: Option<String>,
    /// Samples per pixel, when rendered.
    pub spp: Option<u32>,
    /// Its techniques, when rendered.
    pub techniques: Option<String>,
    /// Render seconds (both halves), when rendered.
    pub seconds: Option<f64>,
    /// Its estimated noise subtracted from every MSE (0 for a file).
    pub noise_mse: f64,
    /// Its estimated noise subtracted from every relMSE (0 for a file).
    pub noise_relmse: f64,
}

/// The result of a sweep.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Sweep {
    /// Image width.
    pub width: usize,
    /// Image height.
    pub height: usize,
    /// The reference.
    pub reference: ReferenceInfo,
    /// The error the curves are compared by.
    pub metric: ErrorMetric,
    /// One curve per variant.
    pub curves: Vec<Curve>,
}

/// The columns of `converge.csv`, in order. `noise_target` and `spp_mean` are empty in the
/// rows of uniform points.
pub const CSV_COLUMNS: [&str; 19] = [
    "technique",
    "spp",
    "repeats",
    "seconds",
    "seconds_mean",
    "seconds_max",
    "mse",
    "mse_min",
    "mse_max",
    "rmse",
    "relmse",
    "relmse_min",
    "relmse_max",
    "bias_r",
    "bias_g",
    "bias_b",
    "efficiency",
    "noise_target",
    "spp_mean",
];

/// One finished render of the sweep.
struct Sample {
    image: Image,
    seconds: f64,
    /// Mean samples per pixel (the `sampleCount` layer's mean).
    spp_mean: f64,
    /// Fewest samples a pixel took.
    spp_min: u32,
}

/// The renders of one point: its spp (an adaptive point's cap) and noise target.
struct RawPoint {
    spp: u32,
    noise_target: Option<f64>,
    renders: Vec<Sample>,
}

/// Renders `scene` with `techniques` at `spp` (with a noise target: at most) and `seed`,
/// timing the render call.
fn timed_render(
    scene: &mut CompiledScene,
    base: &RenderOptions,
    techniques: &Techniques,
    (spp, noise_target): (u32, Option<NoiseTarget>),
    seed: u64,
    progress: &Progress,
) -> Result<Sample, RenderError> {
    scene.settings.spp = spp;
    scene.settings.seed = seed;
    let options = techniques.render_options(RenderOptions {
        noise_target,
        ..*base
    });
    let start = Instant::now();
    let out = render(scene, &options, progress.samples)?;
    let seconds = start.elapsed().as_secs_f64();
    let counts = &out.film.count;
    Ok(Sample {
        image: out.beauty,
        seconds,
        spp_mean: counts.iter().map(|&c| c as f64).sum::<f64>() / counts.len().max(1) as f64,
        spp_min: counts.iter().copied().min().unwrap_or(0),
    })
}

/// The samples that [`run`] renders, for a progress bar; `None` with a time budget or an
/// adaptive variant (whose samples are known only once rendered).
pub fn total_samples(options: &ConvergeOptions, pixels: u64) -> Option<u64> {
    let SppPlan::List(spps) = &options.plan else {
        return None;
    };
    if options.variants.iter().any(|v| v.adaptive.is_some()) {
        return None;
    }
    let sweep: u64 = spps.iter().map(|&s| s as u64).sum::<u64>()
        * options.variants.len() as u64
        * options.repeats as u64;
    let reference = match &options.reference {
        Reference::Image { .. } => 0,
        Reference::Render { spp, .. } => {
            reference_spp(*spp, spps.iter().copied().max().unwrap_or(1)) as u64
        }
    };
    Some((sweep + 1 + reference) * pixels)
}

/// The reference's spp: `requested`, or 16 times the largest spp of the sweep; even (two
/// halves), at least 2, at most `MAX_SPP`.
fn reference_spp(requested: Option<u32>, largest: u32) -> u32 {
    let n = requested.unwrap_or(largest.saturating_mul(16)).min(MAX_SPP);
    (n.div_ceil(2) * 2).clamp(2, MAX_SPP)
}

/// The most memory the sweep's renders may keep. Every render's image is kept until the
/// sweep ends (a rendered reference's spp follows from the largest spp reached, known only
/// then), so `--repeats 4294967295` or a long spp list on a large image would otherwise
/// grow without bound.
pub const MAX_KEPT_BYTES: u64 = 4 << 30;

/// The most points a curve of a time budget has: spp doubling from 1 to `MAX_SPP`, or
/// as many halvings of the first noise target.
const BUDGET_LEVELS: usize = MAX_SPP.ilog2() as usize + 1;

/// Errors when the images the sweep keeps would exceed [`MAX_KEPT_BYTES`]: one per point
/// (an spp count of a uniform variant, a noise target of an adaptive one; a budget's
/// curves have up to [`BUDGET_LEVELS`] points) and repeat.
fn check_kept_images(options: &ConvergeOptions, w: usize, h: usize) -> Result<(), ConvergeError> {
    let adaptive = options
        .variants
        .iter()
        .filter(|v| v.adaptive.is_some())
        .count() as u64;
    let uniform = options.variants.len() as u64 - adaptive;
    let (counts, targets, up_to) = match &options.plan {
        SppPlan::List(spps) => (
            spps.len() as u64,
            options.adaptive.noise_targets.len() as u64,
            "",
        ),
        SppPlan::Budget(_) => (BUDGET_LEVELS as u64, BUDGET_LEVELS as u64, "up to "),
    };
    let points = counts
        .saturating_mul(uniform)
        .saturating_add(targets.saturating_mul(adaptive));
    let images = points.saturating_mul(options.repeats as u64);
    let bytes =
        images.saturating_mul((w * h * std::mem::size_of::<risotto_components::Rgb>()) as u64);
    if bytes > MAX_KEPT_BYTES {
        return Err(ConvergeError::Options(format!(
            "--repeats {} x ({uniform} techniques x {up_to}{counts} spp counts + {adaptive} \
             adaptive x {up_to}{targets} noise targets) = {images} renders of {w}x{h} would \
             keep {:.1} GiB of images (at most {} GiB): fewer repeats, techniques, spp \
             counts or noise targets, or a smaller image",
            options.repeats,
            bytes as f64 / (1u64 << 30) as f64,
            MAX_KEPT_BYTES >> 30
        )));
    }
    Ok(())
}

/// Seeds of the reference halves: far from the sweep's `seed + repeat`.
const REFERENCE_SEED_OFFSET: u64 = 0x5eed_0000_0000;

/// Runs the sweep. `scene.settings.spp` and `seed` are changed (the seed it had is the first
/// repeat's).
pub fn run(
    scene: &mut CompiledScene,
    options: &ConvergeOptions,
    progress: &Progress,
) -> Result<Sweep, ConvergeError> {
    if options.variants.is_empty() {
        return Err(ConvergeError::Options("no techniques to sweep".into()));
    }
    if options.repeats == 0 {
        return Err(ConvergeError::Options(
            "--repeats 0: need at least one".into(),
        ));
    }
    let registry = TechniqueRegistry::for_scene(scene);
    for v in &options.variants {
        v.check(scene)?;
    }
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    if let Reference::Image { image, path } = &options.reference {
        if (image.width, image.height) != (w, h) {
            return Err(ConvergeError::Options(format!(
                "reference {path} is {}x{} but the scene renders {w}x{h}",
                image.width, image.height
            )));
        }
    }
    if let Reference::Render {
        techniques: Some(techniques),
        ..
    } = &options.reference
    {
        techniques.check_applicable(&registry)?;
    }
    let any_adaptive = options.variants.iter().any(|v| v.adaptive.is_some());
    if any_adaptive {
        options.adaptive.check()?;
    }
    match &options.plan {
        SppPlan::List(spps) => {
            if spps.is_empty() || spps.iter().any(|&s| s == 0 || s > MAX_SPP) {
                return Err(ConvergeError::Options(format!(
                    "--spp {spps:?}: need one or more counts between 1 and {MAX_SPP}"
                )));
            }
            let cap = spps.iter().copied().max().unwrap_or(1);
            let min = options.adaptive.min_spp;
            if any_adaptive && !options.adaptive.can_stop_below(cap) {
                return Err(ConvergeError::Options(format!(
                    "adaptive=on with --min-spp {min} and --spp up to {cap}: a pixel stops at \
                     2 x {min} samples at the earliest, so the cap, the largest spp, must be \
                     above {}; raise --spp or lower --min-spp",
                    2 * min
                )));
            }
        }
        SppPlan::Budget(s) => {
            if !(s.is_finite() && *s > 0.0) {
                return Err(ConvergeError::Options(format!(
                    "--budget {s}: need a positive number of seconds"
                )));
            }
        }
    }
    check_kept_images(options, w, h)?;
    let seed = scene.settings.seed;
    let base = options.render;

    // Warm-up: thread pool, sampler tables, allocator.
    (progress.stage)("warm-up");
    let first = &options.variants[0].techniques;
    timed_render(scene, &base, first, (1, None), seed, progress)?;

    let mut raw: Vec<Vec<RawPoint>> = (0..options.variants.len()).map(|_| Vec::new()).collect();
    let sweep = Levels {
        options,
        seed,
        progress,
    };
    match &options.plan {
        SppPlan::List(spps) => {
            // Every curve at once: the cap of the adaptive ones is known.
            let cap = spps.iter().copied().max().unwrap_or(1);
            sweep.render(scene, &mut raw, |_| true, cap)?;
        }
        SppPlan::Budget(_) => {
            sweep.render(scene, &mut raw, |v| v.adaptive.is_none(), MAX_SPP)?;
            let reached = largest_spp(&raw, &options.variants, false);
            let cap = reached
                .unwrap_or(MAX_SPP)
                .max(options.adaptive.min_spp.saturating_mul(4))
                .min(MAX_SPP);
            sweep.render(scene, &mut raw, |v| v.adaptive.is_some(), cap)?;
        }
    }
    let largest = largest_spp(&raw, &options.variants, true).unwrap_or(1);

    // The reference.
    let (reference, info) = match &options.reference {
        Reference::Image { image, path } => (
            image.clone(),
            ReferenceInfo {
                source: "file".into(),
                path: Some(path.clone()),
                spp: None,
                techniques: None,
                seconds: None,
                noise_mse: 0.0,
                noise_relmse: 0.0,
            },
        ),
        Reference::Render { spp, techniques } => {
            let n = reference_spp(*spp, largest);
            let chosen;
            let techniques = match techniques {
                Some(t) => t,
                None => {
                    chosen = most_efficient_converging(
                        scene,
                        &base,
                        &options.variants,
                        &raw,
                        seed.wrapping_add(options.repeats as u64),
                        progress,
                    )?;
                    &chosen
                }
            };
            let mut half = |k: u64| {
                (progress.stage)(&format!(
                    "reference ({}, {n} spp), half {}/2",
                    techniques.label(),
                    k + 1
                ));
                timed_render(
                    scene,
                    &base,
                    techniques,
                    (n / 2, None),
                    seed.wrapping_add(REFERENCE_SEED_OFFSET + k),
                    progress,
                )
            };
            let a = half(0)?;
            let b = half(1)?;
            let (image, noise_mse, noise_relmse) = combine_halves(&a.image, &b.image);
            (
                image,
                ReferenceInfo {
                    source: "rendered".into(),
                    path: None,
                    spp: Some(n),
                    techniques: Some(techniques.label()),
                    seconds: Some(a.seconds + b.seconds),
                    noise_mse,
                    noise_relmse,
                },
            )
        }
    };
    scene.settings.seed = seed;

    let mut curves = Vec::new();
    for (variant, points) in options.variants.iter().zip(&raw) {
        let mut pts = Vec::new();
        for p in points {
            pts.push(point(p, &reference, &info, options.metric)?);
        }
        curves.push(curve(&registry, variant, pts, options.metric));
    }
    Ok(Sweep {
        width: w,
        height: h,
        reference: info,
        metric: options.metric,
        curves,
    })
}

mod levels;
use levels::{largest_spp, Levels};
mod measure;
#[cfg(feature = "plots")]
pub mod plot;
pub use measure::{combine_halves, fit_line};
use measure::{curve, error_time_model, point};
mod reference;
use reference::most_efficient_converging;
mod report;
pub use report::{Comparison, ComparisonTable};
mod variant;
pub use variant::{
    adaptive_applies, listing, AdaptivePlan, Variant, ADAPTIVE, DEFAULT_MIN_SPP,
    DEFAULT_NOISE_TARGETS,
};

#[cfg(test)]
mod tests;
