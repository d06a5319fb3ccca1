//! Criterion benches of the path tracer's column systems that run at every vertex, each
//! alone over one group of 4096 points: the sampler's column draws (and single draws, one
//! dimension at a time, as tracking takes them), light sampling
//! (`LightSet::sample_column`, the kernel the renderer runs, against the per-point
//! `sample_lights` reference; and from `scenes/fire.toml`'s volume emitter), emission sampling
//! (the start of the bidirectional integrators' light subpaths), shadow-ray spawning and path
//! continuation.
//!
//! The points are camera hits on `scenes/mitsuba-suite/cornell.toml`'s floor (`y = -1`,
//! uniform in the square), lit by its area light; the incoming rays come from the camera;
//! the Bxdf samples are cosine-weighted (a white Lambertian floor), at depth 6 so that
//! Russian roulette runs.

mod common;
use common::compile;
use criterion::{black_box, criterion_main, Criterion, Throughput};
use glam::{Vec2, Vec3};
use risotto::components::{
    LobeSampled, RayRow, Rays, Rgb, ShadingPointRow, ShadingPoints, ShadowRays,
};
use risotto::engine::scene::CompiledScene;
use risotto::systems::bxdf::{diffuse_eval, sample_cosine_hemisphere, Frame};
use risotto::systems::bxdf_samples::BxdfSamples;
use risotto::systems::direct_lighting::{spawn_shadow_rays, LightColumns, LightMis};
use risotto::systems::independent_sampler::SamplerKind;
use risotto::systems::lights::{sample_lights, LightSampleColumns};
use risotto::systems::path::{continue_paths, PathLimits, Vertices};
use risotto::systems::sampler::{
    next_2d_column, next_4d_column, pixel_seed, sample_2d, PathSampler,
};

const N: usize = 4096;
/// The floor's reflectance in cornell.toml.
const WHITE: Rgb = Rgb::new(0.725, 0.71, 0.68);
/// The camera in cornell.toml.
const EYE: Vec3 = Vec3::new(0.0, 0.0, 3.9);
/// The renderer's sampler dimensions per vertex (`path_tracer::DIMS_PER_VERTEX`).
const DIMS_PER_VERTEX: u32 = 8;
/// Scattering vertices before this group's: past `rr_depth = 5`, so the roulette runs.
const DEPTH: u16 = 6;

fn cornell() -> CompiledScene {
    compile("scenes/mitsuba-suite/cornell.toml")
}

/// The group: floor points and the camera rays that arrived there (ray `i` at point `i`).
fn floor_group() -> (ShadingPoints, Rays) {
    let (mut points, mut rays) = (ShadingPoints::default(), Rays::default());
    for i in 0..N {
        let u = sample_2d(1, i as u32, 0);
        let p = Vec3::new(u.x * 2.0 - 1.0, -1.0, u.y * 2.0 - 1.0);
        let to_eye = (EYE - p).normalize();
        points.push(ShadingPointRow {
            p,
            ng: Vec3::Y,
            p_offset: 1e-6,
            terminator_lift: Vec3::ZERO,
            nn: Vec3::Y,
            vn: to_eye,
            vlen: (EYE - p).length(),
            transmission: Rgb::WHITE,
            ray_id: i as u32,
            front_face: true,
            ior_outside: 1.0,
            ..Default::default()
        });
        rays.push(RayRow {
            origin: EYE,
            direction: -to_eye,
            tmax: f32::INFINITY,
            path: i as u32,
            throughput: Rgb::splat(0.3),
            depth: DEPTH,
            eta_scale: 1.0,
            dimension: DEPTH as u32 * DIMS_PER_VERTEX,
            prev_p: EYE,
            ..Default::default()
        });
    }
    (points, rays)
}

/// Each point's sampler, at the vertex's first dimension (an aligned four-dimension set, as
/// the renderer's vertices always are).
fn samplers(rays: &Rays, kind: SamplerKind) -> Vec<PathSampler> {
    (0..N)
        .map(|i| PathSampler {
            seed: pixel_seed(0, i as u32 / 16),
            sample: kind.address(i as u32 % 16),
            dimension: rays.dimension[i],
        })
        .collect()
}

fn sampler_columns(c: &mut Criterion) {
    let (_, rays) = floor_group();
    let mut g = c.benchmark_group("sampler");
    g.throughput(Throughput::Elements(N as u64));
    for (name, kind) in [
        ("sobol", SamplerKind::Sobol),
        ("independent", SamplerKind::Independent),
    ] {
        let start = samplers(&rays, kind);
        let (mut s, mut u2, mut u4) = (start.clone(), vec![Vec2::ZERO; N], vec![[0.0; 4]; N]);
        g.bench_function(format!("next_4d_column_{name}"), |b| {
            b.iter(|| {
                s.copy_from_slice(&start);
                next_4d_column(black_box(&mut s), &mut u4);
                black_box(&u4);
            })
        });
        g.bench_function(format!("next_2d_column_{name}"), |b| {
            b.iter(|| {
                s.copy_from_slice(&start);
                next_2d_column(black_box(&mut s), &mut u2);
                black_box(&u2);
            })
        });
        // One dimension at a time, as tracking's tentative collisions draw them: each
        // sampler's next `DRAWS` dimensions summed (the sum keeps the draws live).
        for (how, streamed) in [("next_1d", false), ("stream", true)] {
            g.bench_function(format!("{DRAWS}_single_draws_{how}_{name}"), |b| {
                b.iter(|| {
                    s.copy_from_slice(&start);
                    let mut sum = 0.0f32;
                    for p in black_box(&mut s).iter_mut() {
                        if streamed {
                            let mut stream = p.stream();
                            sum += (0..DRAWS).map(|_| stream.next_1d()).sum::<f32>();
                        } else {
                            sum += (0..DRAWS).map(|_| p.next_1d()).sum::<f32>();
                        }
                    }
                    black_box(sum)
                })
            });
        }
    }
    g.finish();
}

/// Dimensions drawn one at a time per sampler in the single-draw benches (ratio tracking
/// draws one per tentative collision: a variable number per ray).
const DRAWS: usize = 16;

/// The vertex's four-dimension sets: light position (0, 1), light selection (2), roulette (3).
fn vertex_sets(rays: &Rays) -> Vec<[f32; 4]> {
    let mut s = samplers(rays, SamplerKind::Sobol);
    let mut u4 = vec![[0.0; 4]; N];
    next_4d_column(&mut s, &mut u4);
    u4
}

/// Light-sample columns (owned), filled by the column kernel.
struct LightSamples {
    wi: Vec<Vec3>,
    distance: Vec<f32>,
    radiance: Vec<Rgb>,
    pdf: Vec<f32>,
    delta: Vec<bool>,
    margin: Vec<f32>,
}

impl LightSamples {
    fn new() -> Self {
        LightSamples {
            wi: vec![Vec3::Z; N],
            distance: vec![0.0; N],
            radiance: vec![Rgb::BLACK; N],
            pdf: vec![0.0; N],
            delta: vec![false; N],
            margin: vec![0.0; N],
        }
    }
    fn columns(&mut self) -> LightSampleColumns<'_> {
        LightSampleColumns {
            wi: &mut self.wi,
            distance: &mut self.distance,
            radiance: &mut self.radiance,
            pdf: &mut self.pdf,
            delta: &mut self.delta,
            margin: &mut self.margin,
        }
    }
}

fn light_sampling(c: &mut Criterion) {
    let scene = cornell();
    let (points, rays) = floor_group();
    let u4 = vertex_sets(&rays);
    let active = vec![true; N];
    let u_select: Vec<f32> = u4.iter().map(|u| u[2]).collect();
    let u: Vec<Vec2> = u4.iter().map(|u| Vec2::new(u[0], u[1])).collect();
    let mut rows = vec![None; N];
    let mut samples = LightSamples::new();
    let mut g = c.benchmark_group("lights");
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("cornell_area_light_4096_column", |b| {
        b.iter(|| {
            let mut out = samples.columns();
            scene.lights.sample_column(
                &scene.geometry,
                black_box(&points.p),
                black_box(&u4),
                &active,
                &mut out,
            );
            black_box(&out.pdf);
        })
    });
    // A volume emitter (scenes/fire.toml's flame, its emission grid's cells sampled by
    // power), lighting points on that scene's floor: in the MIS light set, the one that
    // holds volume emitters.
    let fire = compile("scenes/fire.toml");
    let fire_floor: Vec<Vec3> = (0..N)
        .map(|i| {
            let u = sample_2d(1, i as u32, 0);
            Vec3::new(u.x * 3.0 - 1.5, 0.0, u.y * 3.0 - 1.5)
        })
        .collect();
    fire.mis_lights.sample_column(
        &fire.geometry,
        &fire_floor,
        &u4,
        &active,
        &mut samples.columns(),
    );
    let lit = samples.pdf.iter().filter(|&&p| p > 0.0).count();
    // About 84 %: cells are drawn by their emission bound, and the other samples fall where
    // the interpolated emission is 0 (no sample).
    assert!(
        lit > N / 2,
        "{lit} of {N} floor points got a sample of the flame"
    );
    g.bench_function("fire_volume_emitter_4096_column", |b| {
        b.iter(|| {
            let mut out = samples.columns();
            fire.mis_lights.sample_column(
                &fire.geometry,
                black_box(&fire_floor),
                black_box(&u4),
                &active,
                &mut out,
            );
            black_box(&out.pdf);
        })
    });
    // Emission sampling, the start of light subpaths (`integrator = light | bdpt | vcm`):
    // a ray leaving cornell's area light, 4096 per iteration.
    let bounds = scene.geometry.bounds();
    let u_dir: Vec<Vec2> = u4.iter().map(|u| Vec2::new(u[3], u[0])).collect();
    g.bench_function("cornell_area_light_4096_emission", |b| {
        b.iter(|| {
            let mut emitted = 0u32;
            for k in 0..N {
                let e = scene.lights.sample_emission(
                    &scene.geometry,
                    bounds,
                    black_box(u_select[k]),
                    black_box(u[k]),
                    black_box(u_dir[k]),
                );
                emitted += e.is_some() as u32;
            }
            black_box(emitted)
        })
    });
    // The per-point reference the column kernel equals bit for bit.
    g.bench_function("cornell_area_light_4096_per_point", |b| {
        b.iter(|| {
            sample_lights(
                &scene.lights,
                &scene.geometry,
                black_box(&points.p),
                black_box(&u_select),
                black_box(&u),
                &mut rows,
            );
            black_box(&rows);
        })
    });
    g.finish();
}

fn shadow_ray_spawning(c: &mut Criterion) {
    let scene = cornell();
    let (points, rays) = floor_group();
    let u4 = vertex_sets(&rays);
    let mut light = LightSamples::new();
    scene.lights.sample_column(
        &scene.geometry,
        &points.p,
        &u4,
        &vec![true; N],
        &mut light.columns(),
    );
    // The white floor's response to the light samples (as `DiffuseBxdf::evaluate_samples`).
    let frame = Frame::from_normal(Vec3::Y);
    let (value, bxdf_pdf): (Vec<Rgb>, Vec<f32>) = (0..N)
        .map(|i| {
            let (wo, wi) = (frame.to_local(points.vn[i]), frame.to_local(light.wi[i]));
            diffuse_eval(WHITE, wo, wi)
        })
        .unzip();
    let mut pdf = bxdf_pdf.clone();
    let mut scratch = vec![0u32; N];
    let mut shadow = ShadowRays::default();
    let mut spawn = || {
        // The system overwrites the Bxdf pdfs with the contribution factors.
        pdf.copy_from_slice(&bxdf_pdf);
        let from = Vertices {
            points: &points,
            range: 0..N,
            on_surface: true,
            terminator_lift: false,
            incoming: &rays,
        };
        let light = LightColumns {
            samples: light.columns(),
            value: black_box(&value),
            pdf: &mut pdf,
            points: &mut scratch,
        };
        spawn_shadow_rays(
            from,
            None,
            &rays.dimension,
            light,
            LightMis::PowerHeuristic,
            None,
            &mut shadow.reuse_rows(N),
            0,
        )
    };
    // The area light above lights the whole floor: nearly every point gets a shadow ray.
    let written = spawn();
    assert!(written > N * 9 / 10, "{written} shadow rays of {N}");
    let mut g = c.benchmark_group("direct_lighting");
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("spawn_shadow_rays_4096", |b| b.iter(|| black_box(spawn())));
    g.finish();
}

fn path_continuation(c: &mut Criterion) {
    let (points, rays) = floor_group();
    let u4 = vertex_sets(&rays);
    let mut samples = BxdfSamples::default();
    samples.reset(N);
    for i in 0..N {
        let u = sample_2d(2, i as u32, 0);
        let local = sample_cosine_hemisphere(u);
        samples.wi[i] = Vec3::new(local.x, local.z, local.y);
        samples.weight[i] = WHITE;
        samples.pdf[i] = local.z * std::f32::consts::FRAC_1_PI;
        samples.lobe[i] = LobeSampled(LobeSampled::REFLECT.0 | LobeSampled::DIFFUSE.0);
        samples.eta[i] = 1.0;
    }
    let limits = PathLimits {
        max_depth: u32::MAX,
        rr_depth: 5,
        dims_per_vertex: DIMS_PER_VERTEX,
    };
    let mut next = Rays::default();
    let mut stack_errors = Vec::new();
    let mut continue_group = || {
        let from = Vertices {
            points: &points,
            range: 0..N,
            on_surface: true,
            terminator_lift: false,
            incoming: &rays,
        };
        continue_paths(
            limits,
            from,
            black_box(&samples),
            black_box(&u4),
            None,
            &mut stack_errors,
            &mut next.reuse_rows(N),
            0,
        )
    };
    // Throughput 0.3 x 0.725: the roulette keeps about sqrt(0.22) = 47 % of the paths.
    let done = continue_group();
    assert!(done.roulette > N / 3 && done.written > N / 3, "{done:?}");
    let mut g = c.benchmark_group("path");
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("continue_paths_4096", |b| {
        b.iter(|| black_box(continue_group()))
    });
    g.finish();
}

// criterion_group! expands to an undocumented `pub fn`; a private module keeps it out of the
// `missing_docs` lint without an allow attribute.
mod group {
    criterion::criterion_group!(
        benches,
        super::sampler_columns,
        super::light_sampling,
        super::shadow_ray_spawning,
        super::path_continuation
    );
}
criterion_main!(group::benches);
