//! Emitters seen directly from the camera, estimated with more pixel samples than the paths.
//!
//! A pixel's value is `I = E + S`: `E`, the integral over the pixel of the emission the camera
//! ray hits first, and `S`, everything that scatters at least once. At an emitter's silhouette
//! `E` is a step of the whole emitted radiance across the pixel, and its error is that of
//! counting how many of the pixel's points fall on either side of the edge: with `N` points of
//! a (0, m, 2)-net and an edge parallel to an axis, the count is off by one at most and the
//! variance is `f (1 - f) / N^2` times the squared step (`f` the edge's position within its
//! stratum). On `cornell` the light's outline, 0.4 % of the pixels, held 28 % of the image's
//! variance at 64 spp (`benches/README.md`, "Against Mitsuba 3").
//!
//! Each path sample `s` of a pixel therefore also traces [`EXTRA_CAMERA_SAMPLES`] camera rays
//! at the pixel's Sobol points `s + j spp` (`j = 1 ..= K`, same per-pixel digital shift as
//! the path's own point `s`): together the `(K + 1) spp` points are the first points of the
//! same (0, 2)-sequence, a net with `K + 1` times the strata. Each ray's directly visible
//! emission, and the path's own (`add_emission` at depth 0), count `1 / (K + 1)`. Every point
//! is uniform over the pixel, so each of the `K + 1` estimates of `E` is unbiased and so is
//! their mean; `S` is the paths' as before.
//!
//! The extra rays cost little. They are made only for the pixels whose rays may reach the
//! box around the emitters (a conservative screen-space bound,
//! [`Camera::pixels_seeing_box`](risotto_systems::camera::Camera::pixels_seeing_box)); of
//! those, most miss every emitter, which a test against the emitters' triangles alone (at
//! most [`MAX_EMITTER_TRIANGLES`]) tells, and only those that may hit one are traced through
//! the scene, where the closest hit decides as for any camera ray.
//!
//! Only where a camera ray's first hit decides `E` alone: no volumes and no surface a path
//! ray can pass (transmissive, partly opaque), a camera in no volume, and emissive triangles
//! (the environment seen directly stays the paths' alone).

use crate::integrator::PathBatch;
use crate::scene::CompiledScene;
use crate::stats::{System, SystemStats};
use glam::Vec3;
use risotto_components::NO_HIT;
use risotto_systems::camera::push_camera_ray_geometry;
use risotto_systems::intersect::{intersect_closest, FREE_ORIGIN};
use risotto_systems::lights::Light;
use risotto_systems::sampler::MAX_SPP;

/// The `visible_emitters` technique: whether the directly visible emission takes the extra
/// camera points (where the scene allows: see the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum VisibleEmitters {
    /// `K + 1` camera points per path sample for the directly visible emission.
    #[default]
    Supersampled,
    /// The paths' own camera rays alone.
    Paths,
}

/// Extra camera rays per path sample for the directly visible emission (`K`).
pub const EXTRA_CAMERA_SAMPLES: u32 = 3;

/// Most emissive triangles the extra rays are tested against one by one; scenes with more
/// keep the paths' own estimate.
pub const MAX_EMITTER_TRIANGLES: usize = 32;

/// The choice `choice` as it applies to `scene`: supersampled only where the scene allows
/// it (`applies`). Resolved once per render, so that the per-hit `share` reads no scene.
pub fn for_scene(scene: &CompiledScene, choice: VisibleEmitters) -> VisibleEmitters {
    if applies(scene, choice) {
        VisibleEmitters::Supersampled
    } else {
        VisibleEmitters::Paths
    }
}

/// The share of the directly visible emission each camera ray carries under the resolved
/// choice ([`for_scene`]): `1 / (K + 1)` where the extra rays are traced, else 1.
pub(super) fn share(resolved: VisibleEmitters) -> f32 {
    match resolved {
        VisibleEmitters::Supersampled => 1.0 / (EXTRA_CAMERA_SAMPLES + 1) as f32,
        VisibleEmitters::Paths => 1.0,
    }
}

/// Whether the technique asks for the extra points (`choice`), and the scene's camera rays
/// find their directly visible emission at their first hit and there is some to find (see
/// the module documentation).
fn applies(scene: &CompiledScene, choice: VisibleEmitters) -> bool {
    let f = &scene.features;
    choice == VisibleEmitters::Supersampled
        && EXTRA_CAMERA_SAMPLES > 0
        && f.area_lights
        && !(f.volumes || f.transmissive || f.opacity || f.emissive_media)
        && scene.camera_stack.is_empty()
        && scene.settings.max_depth >= 1
        // The extra points' indices stay inside the Sobol tables.
        && scene.settings.spp.saturating_mul(EXTRA_CAMERA_SAMPLES + 1) <= MAX_SPP
        && few_triangle_emitters(scene)
}

/// Whether every emitter is a flat triangle (not a sphere, not in an instance) and there
/// are at most [`MAX_EMITTER_TRIANGLES`].
fn few_triangle_emitters(scene: &CompiledScene) -> bool {
    let num_triangles = scene.geometry.num_triangles();
    let mut count = 0;
    for light in scene.lights.lights() {
        if let Light::Area { prim, .. } = light {
            count += 1;
            if count > MAX_EMITTER_TRIANGLES || *prim as usize >= num_triangles {
                return false;
            }
        }
    }
    true
}

/// Buffers of the extra camera rays, kept by a worker across batches.
#[derive(Debug, Default)]
pub struct VisibleEmitterScratch {
    emitters: Vec<[Vec3; 3]>,
    /// The batch's paths whose pixels may see the emitters, and their pixels and seeds.
    path: Vec<u32>,
    pixel: Vec<u32>,
    seed: Vec<u32>,
    camera_origin: Vec<Vec3>,
    camera_direction: Vec<Vec3>,
    sample: Vec<u32>,
    candidate: Vec<u32>,
    origin: Vec<Vec3>,
    direction: Vec<Vec3>,
    tmin: Vec<f32>,
    tmax: Vec<f32>,
    t: Vec<f32>,
    prim: Vec<u32>,
    b1: Vec<f32>,
    b2: Vec<f32>,
}

/// Adds to every path of `batch` its share of the emission its extra camera rays see first.
pub(super) fn add_extra_samples(
    scene: &CompiledScene,
    batch: &mut PathBatch,
    s: &mut VisibleEmitterScratch,
    stats: &mut SystemStats,
) {
    let n = batch.paths.len();
    let spp = scene.settings.spp;
    let weight = share(VisibleEmitters::Supersampled);
    s.emitters.clear();
    s.emitters
        .extend(scene.lights.lights().iter().filter_map(|l| match l {
            Light::Area { prim, .. } => Some(scene.geometry.triangle(*prim as usize)),
            _ => None,
        }));
    let bounds = &emitter_bounds(&s.emitters);
    // The paths whose pixels' rays may reach the emitters' box at all (on `cornell` a few
    // hundred of the 65,536 pixels): no other path's extra rays are made.
    let camera = &scene.camera;
    let (pixel, seeds) = (&batch.paths.pixel[..n], &batch.seeds[..n]);
    let sample = &batch.paths.sample[..n];
    s.path.clear();
    match camera.pixels_seeing_box(bounds[0], bounds[1]) {
        Some(rect) => s
            .path
            .extend((0..n as u32).filter(|&k| rect.contains(pixel[k as usize], camera.width))),
        None => s.path.extend(0..n as u32),
    }
    let seen = s.path.len();
    if seen == 0 {
        return;
    }
    s.pixel.clear();
    s.pixel.extend(s.path.iter().map(|&k| pixel[k as usize]));
    s.seed.clear();
    s.seed.extend(s.path.iter().map(|&k| seeds[k as usize]));
    for j in 1..=EXTRA_CAMERA_SAMPLES {
        s.sample.clear();
        s.sample
            .extend(s.path.iter().map(|&k| sample[k as usize] + j * spp));
        s.camera_origin.clear();
        s.camera_direction.clear();
        stats.time(System::Camera, seen, || {
            push_camera_ray_geometry(
                camera,
                &s.pixel,
                &s.sample,
                &s.seed,
                &mut s.camera_origin,
                &mut s.camera_direction,
            )
        });
        // The rays that may hit an emitter, and their columns for the scene's closest hit.
        // A camera ray's other columns are constants (`push_camera_rays`): `tmin`
        // `FREE_ORIGIN`, `tmax` infinity, throughput 1.
        let (origin, direction) = (&s.camera_origin, &s.camera_direction);
        let (tmin, tmax) = (FREE_ORIGIN, f32::INFINITY);
        let emitters = &s.emitters;
        // Indices into the seen paths' rays.
        s.candidate.clear();
        s.candidate.extend((0..seen as u32).filter(|&k| {
            let (o, d) = (origin[k as usize], direction[k as usize]);
            may_hit_box(bounds, o, d, tmin, tmax)
                && emitters.iter().any(|tri| may_hit(tri, o, d, tmin, tmax))
        }));
        let m = s.candidate.len();
        if m == 0 {
            continue;
        }
        let c = &s.candidate;
        s.origin.clear();
        s.origin.extend(c.iter().map(|&k| origin[k as usize]));
        s.direction.clear();
        s.direction.extend(c.iter().map(|&k| direction[k as usize]));
        s.tmin.clear();
        s.tmin.resize(m, tmin);
        s.tmax.clear();
        s.tmax.resize(m, tmax);
        s.t.resize(m, 0.0);
        s.b1.resize(m, 0.0);
        s.b2.resize(m, 0.0);
        s.prim.resize(m, NO_HIT);
        let (t, prim, b1, b2) = (
            &mut s.t[..m],
            &mut s.prim[..m],
            &mut s.b1[..m],
            &mut s.b2[..m],
        );
        stats.time(System::Intersect, m, || {
            let (o, d) = (&s.origin, &s.direction);
            intersect_closest(&scene.geometry, o, d, &s.tmin, &s.tmax, t, prim, b1, b2)
        });
        stats.add_rays(m);
        for (i, &k) in s.candidate.iter().enumerate() {
            if s.prim[i] == NO_HIT {
                continue;
            }
            let shape = scene.shape_of_prim(s.prim[i]);
            let Some(le) = scene.shapes[shape as usize].emission else {
                continue;
            };
            let (o, d) = (s.origin[i], s.direction[i]);
            let surf = (scene.geometry).surface_at(s.prim[i], o, d, s.t[i], s.b1[i], s.b2[i]);
            // One-sided emitters, as `PathTracer::surface_emission`.
            if d.dot(surf.ng) < 0.0 {
                let path = s.path[k as usize] as usize;
                batch.paths.radiance[path] += le * weight;
            }
        }
    }
}

/// Whether the ray `o + t d`, `t` in `[tmin, tmax]`, may cross triangle `tri`: the
/// Moller-Trumbore test (Moller and Trumbore 1997) with every bound widened by a relative
/// margin, so that rounding can only admit a ray the scene's own closest-hit test then
/// settles, never turn one away.
#[inline]
fn may_hit(tri: &[Vec3; 3], o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> bool {
    const MARGIN: f32 = 1e-3;
    let (e1, e2) = (tri[1] - tri[0], tri[2] - tri[0]);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        // A ray in the triangle's plane sees no emission (one-sided, zero projected area).
        return false;
    }
    let inv = 1.0 / det;
    let s = o - tri[0];
    let b1 = s.dot(p) * inv;
    let q = s.cross(e1);
    let b2 = d.dot(q) * inv;
    let t = e2.dot(q) * inv;
    b1 >= -MARGIN
        && b2 >= -MARGIN
        && b1 + b2 <= 1.0 + MARGIN
        && t >= tmin - MARGIN * tmin.abs().max(1.0)
        && t <= tmax * (1.0 + MARGIN)
}

/// The box around `triangles`, widened on every side by a margin relative to its size (a
/// flat emitter's box has no thickness): what [`may_hit_box`] tests first.
fn emitter_bounds(triangles: &[[Vec3; 3]]) -> [Vec3; 2] {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for v in triangles.iter().flatten() {
        lo = lo.min(*v);
        hi = hi.max(*v);
    }
    let margin = 1e-3 * (hi - lo).max_element() + 1e-6 * hi.abs().max(lo.abs()).max_element();
    [lo - Vec3::splat(margin), hi + Vec3::splat(margin)]
}

/// Whether the ray `o + t d`, `t` in `[tmin, tmax]`, may cross the box `b` (slab test,
/// Kay and Kajiya 1986). A direction component of 0 gives infinite slab distances, which
/// `min` / `max` order as they should; only a ray running in the plane of a face (a NaN
/// distance, which `min` / `max` drop) may be turned away, and it passes the emitters at
/// least the margin away. The margin also absorbs rounding.
#[inline]
fn may_hit_box(b: &[Vec3; 2], o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> bool {
    let inv = d.recip();
    let (t0, t1) = ((b[0] - o) * inv, (b[1] - o) * inv);
    let near = t0.min(t1).max_element().max(tmin);
    let far = t0.max(t1).min_element().min(tmax);
    near <= far + 1e-3 * far.abs() + 1e-6
}
