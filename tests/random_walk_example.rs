//! The `random_walk_subsurface` example: a random-walk interior written outside the engine
//! with the public plug-in API (`walked_glass`) renders the Mitsuba suite's `subsurface_like`
//! scene as the built-in walk (`dielectric` + `homogeneous` interior) does, within noise; a
//! wrong walk (albedo 0.9 instead of 0.99) is told apart.

#[path = "../examples/random_walk_subsurface.rs"]
mod example;

use example::{registry, render_text, walked_glass_scene, WalkedGlass, SUBSURFACE_LIKE};
use risotto::components::Rgb;
use risotto::engine::plugin::VolumeEvent;
use risotto::engine::render::RenderOutput;
use risotto::loader::load::scene_from_desc;
use risotto::loader::scene_file::parse_scene;
use std::path::Path;

/// Image size and samples per pixel of the comparison renders.
const SIZE: u32 = 64;
const SPP: u32 = 256;
/// Side of the square pixel blocks whose means are compared (an 8 x 8 grid of blocks).
const BLOCK: usize = 8;
/// The largest difference allowed, in standard deviations of the difference.
const Z_MAX: f64 = 4.0;

/// How two renders of the same scene differ, in units of the standard deviation of the
/// difference (from the renders' own per-pixel variances of the mean).
struct Agreement {
    /// Per channel: `(mean_a - mean_b) / sqrt(var_a + var_b)` of the image means.
    mean_z: [f64; 3],
    /// The largest `|z|` of a block mean (over blocks and channels) and its block.
    worst_block_z: f64,
    worst_block: (usize, usize, usize),
    /// Blocks (and channels) with `|z| >= Z_MAX`, of how many.
    blocks_out: usize,
    blocks: usize,
    /// Mean of `(a - b)^2 / (var_a + var_b)` over the pixels and channels with variance:
    /// about 1 for agreeing images with well-behaved noise, about 0.6 for these, whose
    /// per-pixel variance estimates are dominated by rare bright samples (which raise the
    /// estimate and the difference together).
    chi2_per_dof: f64,
    /// How many entries `chi2_per_dof` averages.
    dof: usize,
}

impl Agreement {
    fn within_noise(&self) -> bool {
        self.mean_z.iter().all(|z| z.abs() < Z_MAX) && self.blocks_out == 0
    }

    fn summary(&self) -> String {
        let (bx, by, c) = self.worst_block;
        format!(
            "image mean z = ({:.2}, {:.2}, {:.2}); block means: worst |z| = {:.2} (block \
             {bx},{by} channel {c}), {} of {} at |z| >= {Z_MAX}; chi2/dof = {:.3} over {} \
             pixel channels",
            self.mean_z[0],
            self.mean_z[1],
            self.mean_z[2],
            self.worst_block_z,
            self.blocks_out,
            self.blocks,
            self.chi2_per_dof,
            self.dof
        )
    }
}

/// The z-score of `a - b` given their variances; 0 when both are exactly equal (black
/// pixels, if any).
fn z(a: f64, b: f64, var: f64) -> f64 {
    if var > 0.0 {
        (a - b) / var.sqrt()
    } else if a == b {
        0.0
    } else {
        f64::INFINITY
    }
}

fn agreement(a: &RenderOutput, b: &RenderOutput) -> Agreement {
    let (w, h) = (a.beauty.width, a.beauty.height);
    assert_eq!((w, h), (b.beauty.width, b.beauty.height));
    // Sums of the pixel means and of their variances over a region, per channel: the
    // region's mean is sum / n, its variance var / n^2 (pixels are independent).
    let sums = |x0: usize, y0: usize, x1: usize, y1: usize| {
        let mut s = [[0.0f64; 3]; 4];
        for y in y0..y1 {
            for x in x0..x1 {
                let k = y * w + x;
                for (c, row) in [
                    a.beauty.pixels[k],
                    b.beauty.pixels[k],
                    a.variance.pixels[k],
                    b.variance.pixels[k],
                ]
                .iter()
                .enumerate()
                {
                    for (ch, v) in row.to_array().iter().enumerate() {
                        s[c][ch] += *v as f64;
                    }
                }
            }
        }
        s
    };
    let zs = |s: [[f64; 3]; 4], n: f64| -> [f64; 3] {
        std::array::from_fn(|c| z(s[0][c] / n, s[1][c] / n, (s[2][c] + s[3][c]) / (n * n)))
    };
    let mean_z = zs(sums(0, 0, w, h), (w * h) as f64);
    let (mut worst_block_z, mut worst_block, mut blocks_out, mut blocks) = (0.0, (0, 0, 0), 0, 0);
    for by in 0..h / BLOCK {
        for bx in 0..w / BLOCK {
            let s = sums(bx * BLOCK, by * BLOCK, (bx + 1) * BLOCK, (by + 1) * BLOCK);
            for (c, zc) in zs(s, (BLOCK * BLOCK) as f64).iter().enumerate() {
                blocks += 1;
                if zc.abs() >= Z_MAX {
                    blocks_out += 1;
                }
                if zc.abs() > worst_block_z {
                    (worst_block_z, worst_block) = (zc.abs(), (bx, by, c));
                }
            }
        }
    }
    let (mut chi2, mut dof) = (0.0f64, 0usize);
    for k in 0..w * h {
        let (pa, pb) = (a.beauty.pixels[k].to_array(), b.beauty.pixels[k].to_array());
        let (va, vb) = (
            a.variance.pixels[k].to_array(),
            b.variance.pixels[k].to_array(),
        );
        for c in 0..3 {
            let v = (va[c] + vb[c]) as f64;
            if v > 0.0 {
                chi2 += ((pa[c] - pb[c]) as f64).powi(2) / v;
                dof += 1;
            }
        }
    }
    Agreement {
        mean_z,
        worst_block_z,
        worst_block,
        blocks_out,
        blocks,
        chi2_per_dof: chi2 / dof.max(1) as f64,
        dof,
    }
}

fn scatter_events(out: &RenderOutput) -> u64 {
    out.stats.counters.volume_events[VolumeEvent::Scatter as usize]
}

fn render_checked(text: &str, name: &str) -> RenderOutput {
    let out = render_text(text, name).unwrap();
    assert_eq!(
        out.stats.counters.nan_dropped, 0,
        "{name}: NaN samples dropped"
    );
    assert!(out.beauty.pixels.iter().all(|p| p.is_finite()), "{name}");
    assert!(scatter_events(&out) > 0, "{name}: no scattering event");
    let m = out.beauty.mean();
    eprintln!(
        "{name}: mean ({:.4}, {:.4}, {:.4}), {} scattering events, {:.2} s",
        m[0],
        m[1],
        m[2],
        scatter_events(&out),
        out.stats.wall_seconds
    );
    out
}

/// `text` rendered at `size` x `size` pixels with `spp` samples per pixel.
///
/// # Panics
/// When `text` does not set the suite scene's resolution and sample count.
pub fn resized(text: &str, size: u32, spp: u32) -> String {
    let settings = "width = 256\nheight = 256\nspp = 64\n";
    assert!(
        text.contains(settings),
        "the scene's render settings changed"
    );
    text.replace(
        settings,
        &format!("width = {size}\nheight = {size}\nspp = {spp}\n"),
    )
}

/// `text` with another render seed: the two renders compared then draw independent
/// samples, as the z-scores (from each image's own variance) assume. With the same seed the
/// paths that never enter the ball would be the same in both, and the differences smaller
/// than the scores say.
fn reseeded(text: &str) -> String {
    assert!(text.contains("\nseed = 0\n"));
    text.replace("\nseed = 0\n", "\nseed = 1\n")
}

/// Renders the built-in and the walked versions of a scene and reports their agreement.
fn compare(builtin_text: &str, walked_text: &str, what: &str) -> Agreement {
    let builtin = render_checked(builtin_text, &format!("{what} (built-in walk)"));
    let ours = render_checked(&reseeded(walked_text), &format!("{what} (walked_glass)"));
    let a = agreement(&builtin, &ours);
    eprintln!(
        "{what}: walked_glass against the built-in walk: {}",
        a.summary()
    );
    a
}

#[test]
fn walked_glass_renders_subsurface_like_as_the_builtin_walk() {
    let builtin_text = resized(SUBSURFACE_LIKE, SIZE, SPP);
    let builtin = render_checked(&builtin_text, "subsurface_like (built-in walk)");
    let ours = render_checked(
        &reseeded(&walked_glass_scene(&builtin_text, 0.99)),
        "subsurface_like (walked_glass)",
    );
    let same = agreement(&builtin, &ours);
    eprintln!("albedo 0.99 against the built-in walk: {}", same.summary());
    assert!(same.within_noise(), "{}", same.summary());
    assert!(same.chi2_per_dof < 1.3, "{}", same.summary());

    // The comparison can fail: a walk that loses 10 % per event instead of 1 % renders a
    // much darker ball, far outside the noise.
    let wrong = render_checked(
        &reseeded(&walked_glass_scene(&builtin_text, 0.9)),
        "subsurface_like (walked_glass, albedo 0.9)",
    );
    let differs = agreement(&builtin, &wrong);
    eprintln!(
        "albedo 0.9 against the built-in walk: {}",
        differs.summary()
    );
    assert!(!differs.within_noise(), "{}", differs.summary());
    assert!(differs.worst_block_z > 3.0 * Z_MAX, "{}", differs.summary());
    assert!(
        differs.mean_z.iter().all(|z| z.abs() > Z_MAX),
        "{}",
        differs.summary()
    );
}

#[test]
fn a_chromatic_walked_glass_matches_the_builtin_walk() {
    // The same scene with a medium whose channels differ: the free flights then use
    // one-sample spectral MIS and the walk's weights are no longer exactly 1.
    let builtin_text = resized(SUBSURFACE_LIKE, SIZE, SPP);
    let walked_text = walked_glass_scene(&builtin_text, 0.99);
    let (grey_b, grey_w) = (
        "sigma_t = 20.0, albedo = 0.99",
        "sigma_t = 20.0\nalbedo = 0.99",
    );
    assert!(builtin_text.contains(grey_b) && walked_text.contains(grey_w));
    let (sigma_t, albedo) = ("[10.0, 20.0, 40.0]", "[0.99, 0.95, 0.8]");
    let a = compare(
        &builtin_text.replace(grey_b, &format!("sigma_t = {sigma_t}, albedo = {albedo}")),
        &walked_text.replace(grey_w, &format!("sigma_t = {sigma_t}\nalbedo = {albedo}")),
        "chromatic subsurface_like",
    );
    assert!(a.within_noise(), "{}", a.summary());
    assert!(a.chi2_per_dof < 1.3, "{}", a.summary());
}

#[test]
fn walk_events_count_towards_max_depth_as_in_the_builtin_walk() {
    // With a path-length bound the walk's events count as bounces: the walk ends a path at
    // the bound (`IntegratorContext::max_depth`) and reports its events with its exit
    // (`ShadeGroups::walked`), so that the path tracer's later bounces count from there.
    // (Without those rows the walked paths would go on longer: image mean z = -13 here,
    // where the unbounded scene cannot tell.)
    let unbounded = "max_depth = -1   # unbounded\n";
    let builtin_text = resized(SUBSURFACE_LIKE, SIZE, SPP);
    assert!(builtin_text.contains(unbounded));
    let builtin_text = builtin_text.replace(unbounded, "max_depth = 20\n");
    let a = compare(
        &builtin_text,
        &walked_glass_scene(&builtin_text, 0.99),
        "subsurface_like, max_depth 20",
    );
    assert!(a.within_noise(), "{}", a.summary());
    assert!(a.chi2_per_dof < 1.3, "{}", a.summary());
}

/// How fine the comparison is: an albedo 1 % off (0.98 instead of 0.99; measured z = 25 on
/// the image means) is outside the noise, so agreement above means agreement to better
/// than that.
#[test]
fn a_one_percent_albedo_error_is_seen() {
    let builtin_text = resized(SUBSURFACE_LIKE, SIZE, SPP);
    let a = compare(
        &builtin_text,
        &walked_glass_scene(&builtin_text, 0.98),
        "albedo 0.98",
    );
    assert!(!a.within_noise(), "{}", a.summary());
}

#[test]
fn registry_knows_walked_glass_and_checks_its_parameters() {
    let reg = registry();
    assert!(reg.contains("walked_glass") && reg.contains("dielectric"));
    let text = walked_glass_scene(SUBSURFACE_LIKE, 0.99);
    for (from, to, key) in [
        ("albedo = 0.99", "albedo = 1.5", "albedo"),
        ("albedo = 0.99", "albedo = [0.5, -0.1, 0.5]", "albedo"),
        ("sigma_t = 20.0\nalbedo", "sigma_t = -1\nalbedo", "sigma_t"),
        ("ior = 1.33\nsigma_t", "ior = 0\nsigma_t", "ior"),
        ("albedo = 0.99", "albedo = 0.99\ng = 0.3", "g"),
    ] {
        assert!(text.contains(from), "{from}");
        let bad = text.replacen(from, to, 1);
        let desc = parse_scene(&bad, Path::new("bad.toml")).unwrap();
        let err = match scene_from_desc(desc, &reg) {
            Ok(_) => panic!("accepted: {to}"),
            Err(e) => e.to_string(),
        };
        assert!(
            err.contains("bad.toml") && err.contains(key),
            "{to}: message {err}"
        );
    }
    // Numbers and colours both read as colours.
    let chromatic = text.replacen("albedo = 0.99", "albedo = [0.99, 0.95, 0.9]", 1);
    let desc = parse_scene(&chromatic, Path::new("ok.toml")).unwrap();
    assert!(scene_from_desc(desc, &reg).is_ok());
    let glass = WalkedGlass {
        ior: 1.33,
        sigma_t: Rgb::splat(20.0),
        albedo: Rgb::splat(0.99),
    };
    assert_eq!(risotto::engine::plugin::BxdfFactory::ior(&glass), 1.33);
}
