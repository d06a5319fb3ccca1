//! Shade stage: for each group of the hit queue (one material, one mode), the transmission of
//! the incident segment, emission, first-hit AOVs, the Bxdf (a phase function for volume
//! points) and its samples; the group's direct lighting and the continuation of its paths
//! are the next two stages, run on the same group while its closure lives.

use super::continuation::continue_group;
use super::direct_lighting::{sample_lights, LitGroup};
use super::queues::{scratch, GroupScratch, Queues};
use super::shading_normals::discard_bxdf_samples;
use super::surface_caches::SurfaceCaches;
use super::{non_finite_case, PathTracer};
use crate::integrator::{LightingTechnique, PathBatch};
use crate::plugin::{InstanceHints, ParamCache, PatternCounters, ShadingContext};
use crate::scene::CompiledScene;
use crate::shade_groups::ShadingMode;
use crate::stats::{Stage, System, SystemStats};
use bumpalo::Bump;
use risotto_components::{LobeSampled, Rgb, VolumeStack};
use risotto_systems::direct_lighting::LightMis;
use risotto_systems::path::Vertices;
use risotto_systems::sampler::{next_4d_column, sample_1d, PathSampler};

/// Shades every group of `q.hits`: writes the next bounce's rays to `q.next` and the shadow
/// rays to `q.shadow` (after those the lighting delegate queued during the trace stage).
/// `first_bounce` is true when the hits may belong to camera rays (the first iteration of the
/// batch), the only ones that record AOVs.
///
/// The next rays and the shadow rays go into rows made up front for all groups
/// (`reuse_rows`) and truncated to the rows written after the last group, instead of pushing
/// row by row: a push checks capacity and stores the length of each of the 15 columns.
///
/// The parameter caches of groups whose material computes an interior go to `surfaces`,
/// for the interiors their rays enter next (`surface_caches`).
#[allow(
    clippy::too_many_arguments,
    reason = "the stage's inputs, each named; grouping them would hide which it reads"
)]
pub(super) fn shade_groups<'a>(
    tracer: &PathTracer,
    scene: &CompiledScene,
    batch: &mut PathBatch,
    q: &mut Queues,
    stats: &mut SystemStats,
    arena: &'a Bump,
    counters: &'a PatternCounters,
    surfaces: &mut SurfaceCaches<'a>,
    first_bounce: bool,
) {
    let settings = scene.settings;
    let features = scene.features;
    let Queues {
        hits,
        next,
        shadow,
        group,
        emissive_material,
        ..
    } = q;
    let GroupScratch {
        samples,
        samplers,
        u4: u4_buf,
        active: active_buf,
        light,
        albedo: albedo_buf,
        stack_errors,
        ..
    } = group;
    let groups = std::mem::take(&mut hits.groups.groups);
    let (pts, incoming) = (&hits.groups.points, &mut hits.incoming);
    let paths = &mut batch.paths;
    let total: usize = groups.iter().map(|g| g.range.len()).sum();
    let shade_start = std::time::Instant::now();
    // Without materials that compute interiors or let rays cross their surface, no stack
    // ever gets an entry (only shapes of such materials are tracked): every stack is the
    // empty default and the stack columns need no per-row copies.
    let stacks = features.volumes || features.transmissive || !scene.camera_stack.is_empty();
    let light_sampling_possible =
        tracer.technique != LightingTechnique::BxdfOnly && tracer.nee_lights(scene).can_sample();
    let mis = match tracer.technique {
        LightingTechnique::NeeOnly => LightMis::None,
        _ => LightMis::PowerHeuristic,
    };
    // `next` holds no live rows here, only the dead rows of an earlier bounce, which the
    // continue stage overwrites column by column.
    let mut shadow_out = shadow.spare.reuse_rows(total);
    let mut next_out = next.rays.reuse_rows(total);
    next_out.tmin.fill(0.0);
    next_out.tmax.fill(f32::INFINITY);
    debug_assert!(stacks || next_out.volume_stack.iter().all(VolumeStack::is_empty));
    debug_assert!(stacks || shadow_out.volume_stack.iter().all(VolumeStack::is_empty));
    let (mut shadow_len, mut next_len) = (0, 0);
    for grp in &groups {
        let range = grp.range.clone();
        let ray_id = &pts.ray_id[range.clone()];
        let m = ray_id.len();
        // Transmission of the incident segment multiplies the throughput first (only volume
        // integrators return points with transmission other than 1).
        if features.volumes {
            for (&r, &tr) in ray_id.iter().zip(&pts.transmission[range.clone()]) {
                incoming.throughput[r as usize] *= tr;
            }
        }
        if features.area_lights && emissive_material[grp.material as usize] {
            let shape = &pts.shape[range.clone()];
            let front = &pts.front_face[range.clone()];
            for (k, ((&r, &shape), &front)) in ray_id.iter().zip(shape).zip(front).enumerate() {
                // The cheap tests first: most points are not on emitters.
                if shape == u32::MAX || !front {
                    continue;
                }
                if let Some(le) = scene.shapes[shape as usize].emission {
                    // Throughput already includes the transmission.
                    let i = range.start + k;
                    let bad = tracer.add_emission(
                        scene,
                        pts,
                        incoming,
                        paths,
                        r as usize,
                        i,
                        le,
                        Rgb::WHITE,
                    );
                    stats.non_finite(Stage::Emission, bad);
                    if bad > 0 {
                        let (path, depth) = (incoming.path[r as usize], incoming.depth[r as usize]);
                        let material = Some(grp.material);
                        non_finite_case(stats, paths, path, depth, Stage::Emission, material);
                    }
                }
            }
        }
        let factory = scene.materials[grp.material as usize].factory.as_ref();
        let cache = arena.alloc(ParamCache::new(arena, counters));
        let ctx = ShadingContext::new(pts, range.clone(), grp.mode, grp.material, &[])
            .with_factory(factory)
            .with_cache(cache);
        let bxdf_start = std::time::Instant::now();
        let bxdf = factory.begin_scatter(&ctx, grp.mode, arena);
        let lobes = bxdf.lobes();

        let n = incoming.len();
        let (in_depth, in_passes, in_path, in_dimension) = (
            &incoming.depth[..n],
            &incoming.passes[..n],
            &incoming.path[..n],
            &incoming.dimension[..n],
        );
        // AOVs at the first vertex.
        let first_vertex = |r: usize| in_depth[r] == 0 && in_passes[r] == 0;
        if first_bounce && ray_id.iter().any(|&r| first_vertex(r as usize)) {
            let albedo = scratch(albedo_buf, m, Rgb::BLACK);
            bxdf.albedo(&ctx, albedo);
            let (nn, vlen) = (&pts.nn[range.clone()][..m], &pts.vlen[range.clone()][..m]);
            for k in 0..m {
                let r = ray_id[k] as usize;
                if first_vertex(r) {
                    let path = in_path[r] as usize;
                    paths.albedo[path] = albedo[k];
                    paths.normal[path] = nn[k];
                    paths.depth[path] = vlen[k];
                }
            }
        }
        // Per-point samplers at this vertex's dimensions, and which points may continue (the
        // next segment must fit in max_depth), in one pass over the incoming rays.
        let num_paths = paths.len();
        let (seed, sample) = (&batch.seeds[..num_paths], &paths.sample[..num_paths]);
        let active = scratch(active_buf, m, false);
        samplers.clear();
        samplers.extend(ray_id.iter().zip(active.iter_mut()).map(|(&r, active)| {
            let r = r as usize;
            let path = in_path[r] as usize;
            *active = (in_depth[r] as u32 + 2) <= settings.max_depth;
            PathSampler {
                seed: seed[path],
                sample: sample[path],
                dimension: in_dimension[r],
            }
        }));
        // The vertex's first four dimensions: light position, light selection, Russian
        // roulette (one SIMD Sobol evaluation when aligned, see DIMS_PER_VERTEX).
        let u4 = scratch(u4_buf, m, [0.0; 4]);
        let vertices = Vertices {
            points: pts,
            range: range.clone(),
            on_surface: grp.mode == ShadingMode::Scatter,
            terminator_lift: features.terminator_offset,
            incoming,
        };
        if light_sampling_possible && lobes.contains(LobeSampled::DIFFUSE) {
            // One column draw for the group; leaves the samplers at the vertex's dimension
            // 4, where the Bxdf starts.
            next_4d_column(&mut samplers[..m], u4);
            let group = LitGroup {
                vertices: vertices.clone(),
                weight: None,
                u4,
                active,
                mis,
            };
            shadow_len += sample_lights(
                scene,
                tracer.nee_lights(scene),
                group,
                &mut *bxdf,
                &ctx,
                paths,
                in_dimension,
                light,
                &mut shadow_out,
                shadow_len,
                stats,
            );
        } else {
            for (s, u) in samplers.iter_mut().zip(u4.iter_mut()) {
                u[3] = sample_1d(s.seed, s.sample, s.dimension + 3);
                // The Bxdf starts at the vertex's dimension 4.
                s.dimension += 4;
            }
        }
        // Bxdf sampling for the next bounce.
        samples.reset(m);
        bxdf.generate_samples(&ctx, samplers, samples);
        if scene.discards_disagreeing_directions() && grp.mode == ShadingMode::Scatter {
            discard_bxdf_samples(pts, range.clone(), features.terminator_offset, samples);
        }
        let system = match grp.mode {
            ShadingMode::VolumeScatter => System::Phase,
            _ => System::Bxdf,
        };
        stats.record(system, m, bxdf_start.elapsed().as_secs_f64());
        let written = continue_group(
            scene,
            paths,
            vertices,
            samples,
            u4,
            stack_errors,
            &mut next_out,
            next_len,
            stats,
        );
        if grp.mode == ShadingMode::Scatter
            && scene.material_info[grp.material as usize]
                .hints
                .contains(InstanceHints::COMPUTES_INTERIOR)
        {
            surfaces.push(next_len..next_len + written, grp.material, cache);
        }
        next_len += written;
    }
    next.rays.truncate(next_len);
    // The shadow rays go after those volume integrators queued during the trace stage.
    shadow.spare.truncate(shadow_len);
    if shadow.rays.is_empty() {
        std::mem::swap(&mut shadow.rays, &mut shadow.spare);
    } else {
        shadow.rays.extend_from(&shadow.spare);
    }
    stats.record(System::Shade, total, shade_start.elapsed().as_secs_f64());
    hits.groups.groups = groups;
}
