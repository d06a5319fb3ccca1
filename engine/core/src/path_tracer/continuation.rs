//! Continue stage: Russian roulette and depth limits for a group's paths, and their next rays
//! (the path-continuation system of `risotto_systems::path`).

use super::{non_finite_case, DIMS_PER_VERTEX};
use crate::scene::CompiledScene;
use crate::stats::{Stage, SystemStats, Termination};
use risotto_components::{Paths, RayColumns, StackEvent};
use risotto_systems::bxdf_samples::BxdfSamples;
use risotto_systems::path::{continue_paths, PathLimits, Vertices};

/// Writes the next rays of the group's continuing paths to `out` from row `start` on, counts
/// the paths that end, and returns the number of rows written. `paths` (the batch's) names
/// the camera samples of non-finite cases.
#[allow(
    clippy::too_many_arguments,
    reason = "the columns it reads and writes, named"
)]
pub(crate) fn continue_group(
    scene: &CompiledScene,
    paths: &Paths,
    vertices: Vertices<'_>,
    samples: &BxdfSamples,
    u4: &[[f32; 4]],
    stack_errors: &mut Vec<(u32, StackEvent)>,
    out: &mut RayColumns<'_>,
    start: usize,
    stats: &mut SystemStats,
) -> usize {
    let settings = scene.settings;
    let f = scene.features;
    let stacks = f.volumes || f.transmissive || !scene.camera_stack.is_empty();
    let limits = PathLimits {
        max_depth: settings.max_depth,
        rr_depth: settings.rr_depth,
        dims_per_vertex: DIMS_PER_VERTEX,
    };
    stack_errors.clear();
    // NaN provenance: a sample with a non-finite pdf, or a usable pdf and a non-finite weight
    // (continue_paths ends such paths as absorbed).
    let m = vertices.range.len();
    let is_bad = |(w, &pdf): (&risotto_components::Rgb, &f32)| {
        !pdf.is_finite() || (pdf > 0.0 && !w.is_finite())
    };
    let bad = samples.weight[..m]
        .iter()
        .zip(&samples.pdf[..m])
        .map(|s| is_bad(s) as usize)
        .sum();
    let stage = if vertices.on_surface {
        Stage::Bxdf
    } else {
        Stage::Phase
    };
    stats.non_finite(stage, bad);
    if bad > 0 {
        let (pts, range, incoming) = (vertices.points, vertices.range.clone(), vertices.incoming);
        let rows = samples.weight[..m].iter().zip(&samples.pdf[..m]);
        for (k, _) in rows.enumerate().filter(|(_, s)| is_bad(*s)) {
            let i = range.start + k;
            let r = pts.ray_id[i] as usize;
            let (path, depth) = (incoming.path[r], incoming.depth[r]);
            non_finite_case(stats, paths, path, depth, stage, Some(pts.material[i]));
        }
    }
    let done = continue_paths(
        limits,
        vertices,
        samples,
        u4,
        stacks.then(|| scene.boundaries()),
        stack_errors,
        out,
        start,
    );
    for &(shape, event) in stack_errors.iter() {
        match event {
            StackEvent::UnmatchedExit => stats.unmatched_exit(shape),
            StackEvent::EnteredAgain => stats.entered_twice(shape),
            _ => {}
        }
    }
    stats.terminate(Termination::MaxDepth, done.max_depth);
    stats.terminate(Termination::Absorbed, done.absorbed);
    stats.terminate(Termination::RussianRoulette, done.roulette);
    stats.terminate(Termination::DepthLimit, done.depth_limit);
    done.written
}
