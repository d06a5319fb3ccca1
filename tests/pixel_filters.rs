//! Pixel reconstruction filters against Mitsuba 3: `scenes/mitsuba-suite/filter_strips`
//! (thin emissive strips seen directly, so every pixel is the filter's average of sharp
//! edges) rendered by Mitsuba 3.9.1 with `rfilter` gaussian and tent (64 x 64, 65536 spp,
//! llvm_ad_rgb, `sample_border` on; the command is in `filter_strips.xml`). Mitsuba splats
//! each sample into every pixel its filter covers and divides by the weight sum; risotto
//! draws film positions from the filter (weight 1): the same expected pixel for a filter
//! that is never negative. The box-filtered render must fail the same comparison, so the
//! test sees the filter.

use risotto::engine::output::read_exr_rgb;
use risotto::engine::render::{render, RenderOptions, RenderOutput};
use risotto::loader::load::{scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::{load_scene, PixelFilter};
use risotto::systems::pixel_filter::GaussianFilter;
use risotto::tools::compare::compare;
use std::path::Path;

/// The samples per pixel of the committed references.
const REFERENCE_SPP: f64 = 65536.0;

fn render_with(filter: PixelFilter, spp: u32) -> RenderOutput {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut desc = load_scene(&root.join("scenes/mitsuba-suite/filter_strips.toml")).unwrap();
    desc.render.filter = filter;
    desc.render.spp = spp;
    let compiled = scene_from_desc(desc, &MaterialRegistry::with_builtins())
        .unwrap()
        .compile()
        .unwrap();
    render(&compiled, &RenderOptions::default(), &|_| {}).unwrap()
}

/// Relative differences of the channel means, and the block z-scores of the difference
/// (8 x 8 pixel blocks, channels pooled): the variance of a block's sum is the render's own
/// (the film's variance of each pixel mean, which assumes independent samples, an
/// overestimate for the Sobol sampler) plus the reference's, the same integrand at
/// `REFERENCE_SPP` independent samples.
fn mean_diffs_and_block_z(out: &RenderOutput, reference: &str, spp: u32) -> ([f64; 3], Vec<f64>) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let reference = read_exr_rgb(&root.join(reference)).unwrap();
    let m = compare(&out.beauty, &reference).unwrap();
    let means = [0, 1, 2].map(|c| m.per_channel[c].mean_reldiff);
    let (w, h) = (64usize, 64usize);
    let scale = 1.0 + f64::from(spp) / REFERENCE_SPP;
    let mut z = Vec::new();
    for by in (0..h).step_by(8) {
        for bx in (0..w).step_by(8) {
            let (mut d, mut v) = (0.0f64, 0.0f64);
            for y in by..by + 8 {
                for x in bx..bx + 8 {
                    let k = y * w + x;
                    let (a, b, var) = (
                        out.beauty.pixels[k],
                        reference.pixels[k],
                        out.variance.pixels[k],
                    );
                    d += f64::from(a.r + a.g + a.b) - f64::from(b.r + b.g + b.b);
                    v += scale * f64::from(var.r + var.g + var.b);
                }
            }
            // A block that none of the render's samples saw lit (zero variance) is black
            // but for the far tail of the filter, which the reference's 256 times as many
            // samples may reach: there the reference may hold at most a trace.
            z.push(if v > 0.0 {
                d / v.sqrt()
            } else if d.abs() < 0.01 {
                0.0
            } else {
                f64::INFINITY
            });
        }
    }
    (means, z)
}

fn max_abs(z: &[f64]) -> f64 {
    z.iter().fold(0.0f64, |m, &v| m.max(v.abs()))
}

#[test]
fn gaussian_and_tent_filters_match_mitsuba_and_the_box_does_not() {
    let spp = 256;
    let gaussian = PixelFilter::Gaussian(GaussianFilter::new(0.5, 2.0).unwrap());
    let tent = PixelFilter::Tent { radius: 1.0 };
    let cases = [
        (gaussian, "tests/data/filter_strips-gaussian-mitsuba-64.exr"),
        (tent, "tests/data/filter_strips-tent-mitsuba-64.exr"),
    ];
    let box_render = render_with(PixelFilter::PIXEL_BOX, spp);
    for (filter, reference) in cases {
        let out = render_with(filter, spp);
        assert_eq!(out.stats.counters.nan_dropped, 0);
        let (means, z) = mean_diffs_and_block_z(&out, reference, spp);
        eprintln!("{filter:?}: means {means:?}, max |z| {}", max_abs(&z));
        for (c, m) in means.iter().enumerate() {
            assert!(m.abs() < 0.01, "{filter:?}: channel {c} mean off by {m}");
        }
        // 64 blocks: |z| > 4.5 has probability ~5e-4 under pure noise.
        assert!(max_abs(&z) < 4.5, "{filter:?} differs from Mitsuba: {z:?}");
        // The box-filtered image has the same means (a filter keeps the integral) but not
        // the same blocks: the comparison sees the filter.
        let (box_means, box_z) = mean_diffs_and_block_z(&box_render, reference, spp);
        eprintln!(
            "box vs {reference}: means {box_means:?}, max |z| {}",
            max_abs(&box_z)
        );
        assert!(
            max_abs(&box_z) > 10.0,
            "the box filter passes for {filter:?}: {box_z:?}"
        );
    }
    // And the two filters are told apart from each other.
    let out = render_with(tent, spp);
    let (_, z) = mean_diffs_and_block_z(&out, cases[0].1, spp);
    assert!(
        max_abs(&z) > 10.0,
        "the tent passes for the Gaussian: {z:?}"
    );
}
