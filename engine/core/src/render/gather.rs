//! The render's output from its tiles: their films, AOVs and counters gathered into one
//! image of sums ([`gather`]), the means and layers a render writes, and the stats' scene
//! checks (non-finite cases named, the boundary validator's warnings).

use super::splats::add_splats;
use super::{RenderOutput, SampleRange, Tile, Window};
use crate::output::Image;
use crate::scene::CompiledScene;
use crate::stats::{RenderStats, SystemStats};
use risotto_components::Rgb;
use risotto_systems::film::{AovFilm, Film, SplatFilm};

/// The render output of `tiles` (which cover `window` and hold the samples `samples`).
pub(super) fn gather(
    scene: &CompiledScene,
    window: Window,
    samples: std::ops::Range<u32>,
    tiles: impl IntoIterator<Item = impl std::borrow::Borrow<Tile>>,
    start: std::time::Instant,
    splats: Option<(&SplatFilm, f64)>,
) -> RenderOutput {
    let (w, h) = (window.width(), window.height());
    let mut film = Film::new(w, h);
    // The AOV sums only where the tiles keep them (`RenderOptions::aovs`): 56 bytes a pixel.
    let mut aov_sums: Option<AovFilm> = None;
    let n = (w * h) as usize;
    let mut counters = SystemStats::default();
    // A final gather is handed the tiles by value and frees each once added.
    for tile in tiles {
        let (tile, stats) = std::borrow::Borrow::<Tile>::borrow(&tile);
        let (x0, y0) = (tile.x0 - window.x0, tile.y0 - window.y0);
        film.add_tile(&tile.film, x0, y0);
        if tile.aovs.holds_sums() {
            let sums = aov_sums.get_or_insert_with(|| AovFilm::new(w, h));
            sums.add_tile(&tile.aovs, x0, y0);
        }
        counters.merge(stats);
    }
    let aovs = aov_sums.unwrap_or_else(|| AovFilm::without_sums(w, h));
    if let Some((splat, scale)) = splats {
        add_splats(&mut film, window, splat, scale);
    }
    let image = |f: &dyn Fn(usize) -> Rgb| Image {
        width: w as usize,
        height: h as usize,
        pixels: (0..n).map(f).collect(),
    };
    let beauty = image(&|i| film.mean(i));
    let variance = image(&|i| film.variance_of_mean(i));
    let (albedo, normal, depth) = if aovs.holds_sums() {
        aov_means(&aovs, &film.count)
    } else {
        let empty = || Image {
            width: 0,
            height: 0,
            pixels: Vec::new(),
        };
        (empty(), empty(), Vec::new())
    };
    let sample_count = film.count.iter().map(|&c| c as f32).collect();
    let mut stats = RenderStats::new(counters, start.elapsed().as_secs_f64());
    stats.features = scene.features.names();
    stats.warnings.extend(scene.warnings.iter().cloned());
    validate_boundaries(scene, &mut stats);
    stats.non_finite_cases = name_non_finite_cases(scene, &stats.counters);
    RenderOutput {
        beauty,
        variance,
        sample_count,
        albedo,
        normal,
        depth,
        film,
        aovs,
        window,
        samples: SampleRange {
            start: samples.start,
            end: samples.end,
        },
        stats,
    }
}

/// The AOV layers of the sums `aovs` over `count` samples per pixel: mean albedo, mean
/// shading normal (`x, y, z` in `r, g, b`) and mean first-hit distance, as a render writes
/// them.
pub fn aov_means(aovs: &AovFilm, count: &[u32]) -> (Image, Image, Vec<f32>) {
    let (w, h) = (aovs.width as usize, aovs.height as usize);
    let n = w * h;
    let albedo = (0..n).map(|i| aovs.albedo_mean(i, count[i])).collect();
    let normal = (0..n)
        .map(|i| {
            let [x, y, z] = aovs.normal_mean(i, count[i]);
            Rgb::new(x, y, z)
        })
        .collect();
    let depth = (0..n).map(|i| aovs.depth_mean(i, count[i])).collect();
    (
        Image::from_pixels(w, h, albedo),
        Image::from_pixels(w, h, normal),
        depth,
    )
}

/// The kept non-finite cases of `counters`, with pixel coordinates, material names and the
/// scene's seed.
pub(crate) fn name_non_finite_cases(
    scene: &CompiledScene,
    counters: &SystemStats,
) -> Vec<crate::stats::NonFiniteCase> {
    let name = |m: u32| scene.materials.get(m as usize).map(|m| m.name.clone());
    counters
        .non_finite_events
        .iter()
        .map(|e| crate::stats::NonFiniteCase::of(e, scene.camera.width, scene.settings.seed, name))
        .collect()
}

/// The boundary validator: one warning per shape whose crossings corrupted volume stacks
/// (rays leaving it without having entered, entering it twice, or escaping the scene while
/// inside it), when that happened often enough not to be floating-point chance: at grazing
/// angles a ray can miss the far side of a closed shape by an ulp, which no scene can avoid
/// and which costs nothing visible. The threshold: at least 16 rays and one in 10^5 of all
/// rays traced.
fn validate_boundaries(scene: &CompiledScene, stats: &mut RenderStats) {
    let threshold = (stats.counters.rays / 100_000).max(16);
    let c = &stats.counters;
    let kinds: [(&[u64], &str); 3] = [
        (
            &c.unmatched_exits,
            "rays crossed its back face without having entered it",
        ),
        (
            &c.entered_twice,
            "rays crossed its front face while already inside it",
        ),
        (
            &c.escaped_inside,
            "rays left the scene while inside its volume",
        ),
    ];
    let mut warnings = Vec::new();
    for (counts, what) in kinds {
        for (shape, &n) in counts.iter().enumerate() {
            if n >= threshold {
                warnings.push(format!(
                    "shape \"{}\": {n} {what}; its boundary may not be closed (or its \
                     normals are inconsistent)",
                    scene.shapes[shape].name
                ));
            }
        }
    }
    stats.warnings.extend(warnings);
}
