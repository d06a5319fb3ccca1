//! Issue 37: a single extreme voxel must not make a heterogeneous medium unrenderable. The
//! majorant cells its trilinear support touches get its bound, and null-collision tracking
//! costs `majorant x length` lookups there (a voxel of 1e9 in `hetero_grid` took a 0.12 s
//! render past 60 s). Dense segments are now integrated exactly
//! (`risotto_systems::tracking::dense`): these tests bound the tracking **work** (counters,
//! never wall time) and check the images against a reference that does not use the dense
//! code.

mod common;
use common::scratch_dir;

use risotto::engine::render::{render, RenderOptions, RenderOutput};
use risotto::engine::stats::VolumeEvent;
use risotto::loader::load::{scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::parse_scene;
use std::path::Path;

/// The harness's 64^3 grid (Mitsuba `.vol`: a 48-byte header, then `f32` values, x
/// fastest) with voxel `(32, 32, 32)`, at the centre of the box, set to `peak`, written to
/// `dir/NAME`; `None` keeps the grid as it is.
fn hetero_grid_vol(dir: &Path, name: &str, peak: Option<f32>) {
    let src =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/mitsuba-suite/hetero_grid_density.vol");
    let mut bytes = std::fs::read(src).unwrap();
    assert_eq!(bytes.len(), 48 + 4 * 64 * 64 * 64);
    if let Some(peak) = peak {
        let at = 48 + 4 * (32 + 64 * (32 + 64 * 32));
        bytes[at..at + 4].copy_from_slice(&peak.to_le_bytes());
    }
    std::fs::write(dir.join(name), bytes).unwrap();
}

/// A 4^3 `.vol` of `0.1` with voxel `(1, 1, 1)` set to `peak`, written to `dir/NAME`.
fn small_vol(dir: &Path, name: &str, peak: f32) {
    let mut bytes = b"VOL".to_vec();
    bytes.push(3);
    for v in [1i32, 4, 4, 4, 1] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    for k in 0..64 {
        let v = if k == 1 + 4 * (1 + 4) { peak } else { 0.1f32 };
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(dir.join(name), bytes).unwrap();
}

/// `scenes/mitsuba-suite/hetero_grid.toml` over the grid `dir/grid`, `size^2` pixels at `spp`,
/// horizontal field of view `fov` degrees, `majorant_grid` cells per axis.
fn render_hetero(
    dir: &Path,
    grid: &str,
    size: u32,
    spp: u32,
    fov: f32,
    cells: u32,
    seed: u64,
) -> RenderOutput {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/mitsuba-suite/hetero_grid.toml");
    let text = std::fs::read_to_string(src).unwrap();
    let text = text
        .replace("width = 256", &format!("width = {size}"))
        .replace("height = 256", &format!("height = {size}"))
        .replace("spp = 64", &format!("spp = {spp}"))
        .replace("seed = 0", &format!("seed = {seed}"))
        .replace("fov = 40 ", &format!("fov = {fov} "))
        .replace("hetero_grid_density.vol", grid)
        .replace(
            "scale = 10,",
            &format!("scale = 10, majorant_grid = {cells},"),
        );
    assert!(text.contains(&format!("majorant_grid = {cells}")) && text.contains(grid));
    let desc = parse_scene(&text, &dir.join("scene.toml")).unwrap();
    let scene = scene_from_desc(desc, &MaterialRegistry::with_builtins())
        .unwrap()
        .compile()
        .unwrap();
    let out = render(&scene, &RenderOptions::default(), &|_| {}).unwrap();
    assert_eq!(out.stats.counters.nan_dropped, 0);
    assert_eq!(out.stats.counters.majorant_violations, 0);
    out
}

/// The tracking work of a render: the free flights' tentative collisions, the shadow rays'
/// and the lookups of the dense segments' exact integrals.
fn tracking_work(out: &RenderOutput) -> u64 {
    let c = &out.stats.counters;
    c.volume_events[VolumeEvent::Null as usize]
        + c.volume_events[VolumeEvent::Scatter as usize]
        + c.shadow_collisions
        + c.dense_lookups
}

#[test]
fn one_voxel_of_1e9_in_hetero_grid_costs_about_the_normal_work() {
    // The case at 32 x 32, 4 spp. Before dense segments this render tracked about
    // 1e6 tentative collisions per ray crossing the voxel's cells and did not finish.
    let d = scratch_dir("dense_majorant", "hetero_grid");
    hetero_grid_vol(&d, "normal.vol", None);
    hetero_grid_vol(&d, "hot.vol", Some(1e9));
    let normal = render_hetero(&d, "normal.vol", 32, 4, 40.0, 16, 1);
    let hot = render_hetero(&d, "hot.vol", 32, 4, 40.0, 16, 1);
    let (w0, w1) = (tracking_work(&normal), tracking_work(&hot));
    eprintln!(
        "work: normal {w0}, one voxel 1e9 {w1} ({} dense segments)",
        hot.stats.counters.dense_segments
    );
    assert_eq!(normal.stats.counters.dense_segments, 0);
    assert!(hot.stats.counters.dense_segments > 0);
    assert!(w1 <= 5 * w0, "work {w1} vs normal {w0}");
}

#[test]
fn a_4_cubed_grid_with_one_voxel_of_1e9_costs_bounded_work() {
    // The 4^3 grid of 0.1 with one voxel of 1e9 (16 x 16 at 1 spp ran past 120 s):
    // every cell of the voxel's support is extreme. 32 x 32 at 2 spp.
    let d = scratch_dir("dense_majorant", "small");
    small_vol(&d, "small.vol", 1e9);
    let out = render_hetero(&d, "small.vol", 32, 2, 40.0, 16, 0);
    let work = tracking_work(&out);
    let paths = 32 * 32 * 2;
    eprintln!(
        "work {work} for {paths} paths ({} dense segments)",
        out.stats.counters.dense_segments
    );
    assert!(out.stats.counters.dense_segments > 0);
    assert!(work < 500 * paths, "work {work}");
}

#[test]
fn dense_segments_render_what_tracking_renders() {
    // A voxel of 3000 at the box's centre (extinction 3e4 per unit, an opaque blob about two
    // voxels across), seen close up (4 degrees). With 16^3 majorant cells a ray crossing
    // the blob's cells meets `majorant x length` up to 1875 > TRACKING_CAP (1024): dense
    // segments. With 64^3 cells (one per voxel) every segment is below the cap (at most
    // 3e4 x sqrt(3) / 64 = 812), so the reference is plain delta and ratio tracking, no
    // dense code. Independent seeds; per channel, the image means and 4 x 4-pixel block
    // means agree within their standard errors.
    let d = scratch_dir("dense_majorant", "reference");
    hetero_grid_vol(&d, "blob.vol", Some(3000.0));
    let size = 32;
    let test = render_hetero(&d, "blob.vol", size, 64, 4.0, 16, 3);
    let reference = render_hetero(&d, "blob.vol", size, 256, 4.0, 64, 4);
    assert!(test.stats.counters.dense_segments > 1000);
    assert_eq!(reference.stats.counters.dense_segments, 0);
    let block = 4usize;
    let blocks = size as usize / block;
    let (mut worst, mut chi2, mut count) = (0.0f64, 0.0f64, 0usize);
    for c in 0..3 {
        let ch = |p: &risotto::components::Rgb| p.to_array()[c] as f64;
        let mean_var = |out: &RenderOutput, cells: &mut dyn Iterator<Item = usize>| {
            let (mut m, mut v, mut n) = (0.0, 0.0, 0.0);
            for i in cells {
                m += ch(&out.beauty.pixels[i]);
                v += ch(&out.variance.pixels[i]);
                n += 1.0;
            }
            (m / n, v / (n * n))
        };
        let all = || 0..(size * size) as usize;
        let (m0, v0) = mean_var(&reference, &mut all());
        let (m1, v1) = mean_var(&test, &mut all());
        let z = (m1 - m0) / (v0 + v1).sqrt();
        eprintln!("channel {c}: mean {m1:.5} vs reference {m0:.5} (z {z:.2})");
        assert!(z.abs() < 4.0, "channel {c}: {m1} vs {m0}, z {z}");
        for by in 0..blocks {
            for bx in 0..blocks {
                let cells = || {
                    (0..block * block).map(move |k| {
                        (by * block + k / block) * size as usize + bx * block + k % block
                    })
                };
                let (m0, v0) = mean_var(&reference, &mut cells());
                let (m1, v1) = mean_var(&test, &mut cells());
                if v0 + v1 > 0.0 {
                    let z = (m1 - m0) / (v0 + v1).sqrt();
                    worst = worst.max(z.abs());
                    chi2 += z * z;
                    count += 1;
                }
            }
        }
    }
    // The blocks' z^2 average about 1 for matching images (Owen-scrambled Sobol converges
    // faster than its iid variance estimate says, which only lowers it); a blob of the
    // wrong size, transparent or too dark, raises it far above.
    let mean_chi2 = chi2 / count as f64;
    eprintln!("block z-test: mean z^2 {mean_chi2:.3} over {count} blocks, worst |z| {worst:.2}");
    assert!(mean_chi2 < 1.5, "mean z^2 {mean_chi2}");
    assert!(worst < 5.5, "worst block |z| {worst}");
}
