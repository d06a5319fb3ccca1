//! The heterogeneous medium's volume integrator: free flights, transmittance and emission
//! along each ray (the estimators are described in the [module docs](super)).

use super::field::Field;
use super::{emission_floor, HeterogeneousEmission, HeterogeneousMedium, Tracking};
use crate::media::retain_points;
use crate::scatter_patterns::scale_by_albedo;
use glam::{Affine3A, Vec3};
use risotto_components::{LobeSampled, Rays, Rgb, ShadingPointRow, ShadingPoints};
use risotto_engine::plugin::*;
use risotto_engine::stats::VolumeEvent;
use risotto_systems::grid::GridRay;
use risotto_systems::grid::{Dda, MajorantGrid, MajorantSegment};
use risotto_systems::medium::channel_pdf;
use risotto_systems::ray_marching::{
    ray_marching_free_flight, ray_marching_transmittance, unbiased_ray_marching,
};
use risotto_systems::sampler::PathSampler;
use risotto_systems::spectral_tracking::{
    delta_tracking_emitting_rgb, delta_tracking_transmittance_rgb, ratio_tracking_channels,
    ratio_tracking_emitting_rgb, ratio_tracking_rgb, ray_marching_transmittance_rgb,
    spectral_tracking_channels, spectral_tracking_emitting, unbiased_ray_marching_rgb, PerChannel,
    RgbTransmittance,
};
use risotto_systems::tracking::dense::DenseGrid;
use risotto_systems::tracking::{
    delta_tracking_dense, delta_tracking_emitting, delta_tracking_transmittance_dense,
    ratio_tracking_dense, ratio_tracking_emitting, FreeFlight, Transmittance,
};
use std::sync::Arc;

/// The heterogeneous medium's volume integrator, bound to the bundle's shading context (which
/// carries the shape's object space and bounds, where the grid is placed: rays are mapped
/// into object space, with the same parameter `t`, and the grid turns with its shape).
pub struct HeterogeneousInterior<'a> {
    /// The medium.
    pub medium: &'a HeterogeneousMedium,
    /// The context `begin_interior` bound.
    pub ctx: &'a ShadingContext<'a>,
}

/// Sampler dimensions are consumed in multiples of this (see the module docs).
const DIMENSION_SET: u32 = 4;

/// Rounds the dimensions `s` consumed since `start` up to whole sets (at least one).
fn align(s: &mut PathSampler, start: u32) {
    let used = s.dimension.wrapping_sub(start).max(1);
    s.dimension = start.wrapping_add(used.next_multiple_of(DIMENSION_SET));
}

/// The majorant segments a ray crosses in an emissive medium: the density's, scaled to
/// extinction, with the bound of every cell where the medium emits raised to at least
/// `minorant + floor` (see [`HeterogeneousInterior`]'s emission docs). The emission grid's
/// cells are traversed in lockstep with the density's (same resolution, same ray: the same
/// segments).
struct EmissiveSegments<'g> {
    density: Dda<'g>,
    emission: Option<Dda<'g>>,
    scale: f32,
    floor: f32,
}

impl Iterator for EmissiveSegments<'_> {
    type Item = MajorantSegment;
    #[inline]
    fn next(&mut self) -> Option<MajorantSegment> {
        let g = self.density.next()?;
        let emits = match &mut self.emission {
            Some(e) => e.next().is_some_and(|e| e.majorant > 0.0),
            None => g.majorant > 0.0,
        };
        let mut s = g.scaled(self.scale);
        if emits {
            s.majorant = s.majorant.max(s.minorant + self.floor);
        }
        Some(s)
    }
}

impl HeterogeneousInterior<'_> {
    /// The majorant segments of the grid-space ray `(o, d)` on `[0, tmax]`, raised where an
    /// emissive medium emits ([`EmissiveSegments`]); for a medium that does not emit, the
    /// density's segments scaled to extinction (a floor of 0 raises nothing).
    fn emissive_segments<'g>(
        &self,
        grids: &'g Majorants,
        o: Vec3,
        d: Vec3,
        tmax: f32,
    ) -> EmissiveSegments<'g> {
        let m = self.medium;
        let floor = if m.emits() {
            emission_floor(self.bounds(), grids.density.res())
        } else {
            0.0
        };
        let emission = grids.emission.as_ref().map(|e| e.traverse(o, d, 0.0, tmax));
        EmissiveSegments {
            density: grids.density.traverse(o, d, 0.0, tmax),
            emission,
            scale: m.majorant_scale(),
            floor,
        }
    }

    /// The object box the grid's unit cube is placed in (the shape's object-space bounds).
    fn bounds(&self) -> (Vec3, Vec3) {
        self.ctx.volume_bounds().unwrap_or((Vec3::ZERO, Vec3::ONE))
    }

    /// The shape's object-to-world transform, `None` for the identity (no mapping at all,
    /// so shapes without a transform render exactly as before transforms existed).
    fn to_world(&self) -> Option<Affine3A> {
        self.ctx
            .volume_space()
            .filter(|s| !s.is_identity())
            .map(|s| s.object_to_world)
    }

    /// The fields and majorant grids of one integrator call over the shape's bounds: the
    /// density (the grid, or the pattern), the emission pattern if the medium emits one,
    /// and the majorant grids of the density and, where the emission has its own field, of
    /// the emission (same resolution).
    fn fields(&self) -> Fields<'_> {
        let m = self.medium;
        let (lo, hi) = self.bounds();
        let to_world = self.to_world();
        let density = match (&m.density_pattern, &m.density_channels) {
            (Some(p), _) => Field::pattern(&p.graph, p.channel_weights.is_some(), lo, hi, to_world),
            (None, Some(c)) => Field::Channels(c),
            (None, None) => Field::Grid(&m.density),
        };
        let emission = match &m.emission {
            Some(HeterogeneousEmission::Pattern(p)) => {
                Some(Field::pattern(&p.graph, false, lo, hi, to_world))
            }
            _ => None,
        };
        Fields {
            grids: self.majorants(lo, hi),
            density,
            emission,
        }
    }

    /// The majorant grids over the object box `[lo, hi]` ([`Self::fields`]).
    fn majorants(&self, lo: Vec3, hi: Vec3) -> Majorants {
        let m = self.medium;
        let to_world = self.to_world();
        let density = match &m.density_pattern {
            Some(p) => p.majorants_in(lo, hi, to_world),
            None => m.majorants.clone(),
        };
        let emission = match &m.emission {
            Some(HeterogeneousEmission::Grid { majorants, .. }) => Some(majorants.clone()),
            Some(HeterogeneousEmission::Pattern(p)) => Some(p.majorants_in(lo, hi, to_world)),
            _ => None,
        };
        Majorants { density, emission }
    }

    /// The emission coefficient at grid point `uvw`, where the extinction is `sigma_t`
    /// (the call's [`Fields`]).
    #[inline]
    fn emission_at(&self, uvw: Vec3, sigma_t: f32, fields: &Fields<'_>) -> Rgb {
        let m = self.medium;
        match &m.emission {
            None => Rgb::BLACK,
            Some(HeterogeneousEmission::FollowsDensity(c)) if m.density_channels.is_some() => {
                // A per-channel density: the largest channel's (the `density` grid).
                *c * m.density.lookup(uvw)
            }
            Some(HeterogeneousEmission::FollowsDensity(c)) => {
                // sigma_t is the densest channel's (module docs), max_scale * density.
                let smax = m.max_scale();
                let density = if smax > 0.0 {
                    sigma_t / smax
                } else {
                    fields.density.grey(uvw)
                };
                *c * density
            }
            Some(HeterogeneousEmission::Grid { grid, scale, .. }) => *scale * grid.lookup(uvw),
            Some(HeterogeneousEmission::Pattern(_)) => fields
                .emission
                .as_ref()
                .map_or(Rgb::BLACK, |p| p.colour(uvw)),
        }
    }

    /// Transmittance of one world-space segment with the medium's `tracking`, and the
    /// emission reaching its start, for an emissive medium.
    fn segment_emission(
        &self,
        fields: &Fields<'_>,
        o: Vec3,
        d: Vec3,
        length: f32,
        tracking: Tracking,
        s: &mut PathSampler,
    ) -> (RgbTransmittance, Rgb) {
        let m = self.medium;
        let (o, d) = self.to_grid(o, d);
        let segs = self.emissive_segments(&fields.grids, o, d, length);
        let smax = m.max_scale();
        let sigma = |t: f32| smax * fields.density.grey(o + d * t);
        let emission = |t: f32, sigma_t: f32| self.emission_at(o + d * t, sigma_t, fields);
        let start = s.dimension;
        let mut stream = s.stream();
        let rand = || stream.next_1d();
        // The ray-marching estimators gather no emission: emissive media ratio-track.
        let residual = tracking == Tracking::Residual;
        let r = if m.per_channel_density() {
            let scale = m.scale;
            let sigma = PerChannel(|t: f32| scale * fields.density.colour(o + d * t));
            match tracking {
                Tracking::Delta => {
                    let (f, e) = spectral_tracking_channels(segs, sigma, [1.0; 3], emission, rand);
                    (f.pass_value(), e)
                }
                _ => ratio_tracking_channels(segs, sigma, Some(emission), rand, residual),
            }
        } else if m.is_chromatic() {
            let k = m.channel_ratios();
            match tracking {
                Tracking::Delta => delta_tracking_emitting_rgb(segs, sigma, k, emission, rand),
                _ => ratio_tracking_emitting_rgb(segs, sigma, k, emission, rand, residual),
            }
        } else {
            let (t, e) = match tracking {
                Tracking::Delta => {
                    let (f, e) = delta_tracking_emitting(segs, sigma, emission, rand);
                    let t = Transmittance {
                        value: if f.collided { 0.0 } else { 1.0 },
                        nulls: f.nulls + f.collided as u32,
                        violations: f.violations,
                    };
                    (t, e)
                }
                _ => ratio_tracking_emitting(segs, sigma, emission, rand, residual),
            };
            (grey(t), e)
        };
        align(s, start);
        r
    }

    /// `(origin, direction)` of a world-space ray in the grid's unit cube (the same `t`):
    /// mapped to the shape's object space (the direction not renormalised, so `t`, and with
    /// it distances and extinctions per world unit, stay those of the world ray), then to the
    /// unit cube over the object-space bounds.
    fn to_grid(&self, o: Vec3, d: Vec3) -> (Vec3, Vec3) {
        let (o, d) = match self.ctx.volume_space() {
            Some(s) => (s.point_to_object(o), s.vector_to_object(d)),
            None => (o, d),
        };
        let (lo, hi) = self.bounds();
        let inv = 1.0 / (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
        ((o - lo) * inv, d * inv)
    }

    /// The ray-marching step in world units: the medium's `march_step`, or the smallest
    /// voxel extent in the shape's bounds (in world units, for a shape with a transform).
    fn march_step(&self) -> f32 {
        self.medium.march_step.unwrap_or_else(|| {
            let (lo, hi) = self.ctx.volume_bounds().unwrap_or((Vec3::ZERO, Vec3::ONE));
            // A pattern density marches by its majorant cells, four steps per cell.
            let dims = match &self.medium.density_pattern {
                Some(p) => p.res.map(|r| r.saturating_mul(4)),
                None => self.medium.density.dims(),
            };
            let mut voxel = (hi - lo) / Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32);
            if let Some(m) = self.to_world() {
                // The voxel's edges in world units (the step is a distance along world rays).
                voxel = Vec3::new(
                    m.transform_vector3(Vec3::X * voxel.x).length(),
                    m.transform_vector3(Vec3::Y * voxel.y).length(),
                    m.transform_vector3(Vec3::Z * voxel.z).length(),
                );
            }
            let v = voxel.min_element();
            // A flat box (zero extent on an axis) marches by its other voxels.
            if v > 0.0 {
                v
            } else {
                voxel.max_element().max(f32::MIN_POSITIVE)
            }
        })
    }

    /// The exact optical depth along the grid-space ray `(o, d)` for the trackers' dense
    /// segments ([`risotto_systems::tracking::dense`]): for a grey medium over a density
    /// grid, whose field is trilinear; `None` (every segment tracked) for a pattern or a
    /// per-channel density, and for a chromatic scale.
    fn dense_grid(&self, o: Vec3, d: Vec3) -> Option<DenseGrid<'_>> {
        let m = self.medium;
        let grid = m.density_pattern.is_none() && m.density_channels.is_none();
        (grid && !m.is_chromatic()).then(|| {
            DenseGrid::new(GridRay {
                grid: &m.density,
                origin: o,
                direction: d,
                scale: m.majorant_scale(),
            })
        })
    }

    /// Transmittance of one world-space segment with `tracking`, per channel, and the
    /// dense segments integrated exactly on the way.
    fn segment_transmittance(
        &self,
        fields: &Fields<'_>,
        o: Vec3,
        d: Vec3,
        length: f32,
        tracking: Tracking,
        s: &mut PathSampler,
    ) -> (RgbTransmittance, (u32, u32)) {
        let m = self.medium;
        let (o, d) = self.to_grid(o, d);
        let smax = m.majorant_scale();
        let mut dense = self.dense_grid(o, d);
        let segs = || {
            fields
                .grids
                .density
                .traverse(o, d, 0.0, length)
                .map(|g| g.scaled(smax))
        };
        let sigma = |t: f32| smax * fields.density.grey(o + d * t);
        let start = s.dimension;
        let mut stream = s.stream();
        let mut rand = || stream.next_1d();
        let r = if m.per_channel_density() {
            let scale = m.scale;
            let sigma_c = |t: f32| scale * fields.density.colour(o + d * t);
            channel_transmittance(segs, sigma_c, tracking, &mut rand, self.march_step())
        } else if m.is_chromatic() {
            // One grey majorant (the densest channel's), three running estimates
            // (risotto_systems::spectral_tracking).
            let k = m.channel_ratios();
            match tracking {
                Tracking::Ratio => ratio_tracking_rgb(segs(), sigma, k, rand, false),
                Tracking::Residual => ratio_tracking_rgb(segs(), sigma, k, rand, true),
                Tracking::Delta => delta_tracking_transmittance_rgb(segs(), sigma, k, rand),
                Tracking::RayMarching => {
                    ray_marching_transmittance_rgb(segs(), sigma, k, rand, self.march_step())
                }
                Tracking::UnbiasedRayMarching => {
                    unbiased_ray_marching_rgb(segs, sigma, k, rand, self.march_step())
                }
            }
        } else {
            grey(match tracking {
                Tracking::Ratio => ratio_tracking_dense(segs(), sigma, &mut dense, rand, false),
                Tracking::Residual => ratio_tracking_dense(segs(), sigma, &mut dense, rand, true),
                Tracking::Delta => {
                    delta_tracking_transmittance_dense(segs(), sigma, &mut dense, rand)
                }
                Tracking::RayMarching => {
                    ray_marching_transmittance(segs(), sigma, rand, self.march_step())
                }
                Tracking::UnbiasedRayMarching => {
                    unbiased_ray_marching(segs, sigma, rand, self.march_step())
                }
            })
        };
        align(s, start);
        (r, dense.map_or((0, 0), |g| (g.taken, g.lookups)))
    }
}

/// The majorant grids of one integrator call ([`HeterogeneousInterior::fields`]).
struct Majorants {
    density: Arc<MajorantGrid>,
    emission: Option<Arc<MajorantGrid>>,
}

/// The coefficient fields of one integrator call and their majorant grids
/// ([`HeterogeneousInterior::fields`]).
struct Fields<'a> {
    grids: Majorants,
    density: Field<'a>,
    emission: Option<Field<'a>>,
}

impl Fields<'_> {
    /// Pattern evaluations so far (the stats' `pattern_evals`).
    fn evals(&self) -> u64 {
        self.density.evals() + self.emission.as_ref().map_or(0, Field::evals)
    }
}

/// Transmittance of a per-channel density (`sigma_c(t)` per channel, each bounded by the
/// grey majorant segments `segs`, whose minorants bound every channel from below): ratio,
/// residual and delta tracking with the per-channel spectral estimators; the marching
/// estimators march each channel with the grey estimator (the same segments, the random
/// numbers drawn in turn), since one march no longer serves three channels whose ratios
/// vary.
fn channel_transmittance<I: Iterator<Item = MajorantSegment>>(
    segs: impl Fn() -> I,
    sigma_c: impl Fn(f32) -> Rgb,
    tracking: Tracking,
    rand: &mut impl FnMut() -> f32,
    step: f32,
) -> RgbTransmittance {
    let sigma = PerChannel(&sigma_c);
    let none = None::<fn(f32, f32) -> Rgb>;
    match tracking {
        Tracking::Ratio => ratio_tracking_channels(segs(), sigma, none, rand, false).0,
        Tracking::Residual => ratio_tracking_channels(segs(), sigma, none, rand, true).0,
        Tracking::Delta => {
            let f = spectral_tracking_channels(segs(), sigma, [1.0; 3], |_, _| Rgb::BLACK, rand);
            f.0.pass_value()
        }
        Tracking::RayMarching | Tracking::UnbiasedRayMarching => {
            let mut out = RgbTransmittance::default();
            let mut value = [0.0; 3];
            for (c, v) in value.iter_mut().enumerate() {
                let one = |t: f32| sigma_c(t).to_array()[c];
                let t = if tracking == Tracking::RayMarching {
                    ray_marching_transmittance(segs(), one, &mut *rand, step)
                } else {
                    unbiased_ray_marching(&segs, one, &mut *rand, step)
                };
                *v = t.value;
                out.nulls += t.nulls;
                out.violations += t.violations;
            }
            out.value = Rgb::from_array(value);
            out
        }
    }
}

/// A grey estimate as the same value in every channel.
fn grey(t: Transmittance) -> RgbTransmittance {
    RgbTransmittance {
        value: Rgb::splat(t.value),
        nulls: t.nulls,
        violations: t.violations,
    }
}

impl VolumeIntegrator for HeterogeneousInterior<'_> {
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        samplers: &mut [PathSampler],
        _lobes_wanted: LobeSampled,
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
        let m = self.medium;
        let n = rays.len();
        let (p0, g0, m0) = (out.points.len(), out.groups.len(), out.misses.len());
        services.ictx.nearest_hits(rays, out);
        // Each ray's segment in the medium: to its hit, or to where it leaves the grid.
        let mut tmax = rays.tmax.clone();
        for k in p0..out.points.len() {
            let r = out.points.ray_id[k] as usize;
            tmax[r] = tmax[r].min(out.points.vlen[k]);
        }
        let mut scattered = vec![false; n];
        let mut t = vec![0.0f32; n];
        let (mut nulls, mut violations) = (0u64, 0u64);
        let (mut dense_taken, mut dense_lookups) = (0u64, 0u64);
        let tracking = services
            .ictx
            .technique(super::TRACKING.name)
            .and_then(Tracking::from_name)
            .unwrap_or(m.tracking);
        let step = self.march_step();
        let emits = m.emits();
        let smax = m.majorant_scale();
        // A chromatic medium's flights carry per-channel weights (spectral MIS); a grey one's
        // are 1 on passing and the albedo at a collision, as before. A per-channel density
        // is chromatic whatever its scale (its channels' ratios vary in space).
        let per_channel = m.per_channel_density();
        let chromatic = m.is_chromatic() || per_channel;
        let scale = m.scale;
        let k = m.channel_ratios();
        let mut weight = vec![Rgb::WHITE; if chromatic { n } else { 0 }];
        let fields = self.fields();
        let emission_at = |uvw: Vec3, sigma_t: f32| self.emission_at(uvw, sigma_t, &fields);
        // MIS against light sampling of this medium's emitter (risotto_engine::plugin::volume_light): the
        // collision estimator's weight at the ray's tentative collision at `t`.
        let volume_light = services.volume_light;
        let light_weight = |i: usize, t: f32| {
            volume_light.map_or(1.0, |l| {
                l.unidirectional_weight(rays, i, rays.origin[i] + rays.direction[i] * t)
            })
        };
        for i in 0..n {
            if tmax[i] == f32::INFINITY {
                // Nothing ahead: the ray has already left the medium's closed boundary, which
                // it crossed within its `tmin` (a grazing entry). It escapes, as in the
                // homogeneous medium (`scatter_inside`), rather than scattering in the
                // empty corners of the grid.
                continue;
            }
            let (o, d) = self.to_grid(rays.origin[i], rays.direction[i]);
            let s = &mut samplers[i];
            let start = s.dimension;
            let mut stream = s.stream();
            let sigma = |t: f32| smax * fields.density.grey(o + d * t);
            let f = if chromatic {
                // One-sample spectral MIS over the channels, in proportion to the path's
                // throughput (as the homogeneous medium), or one channel for comparison.
                let p = match m.single_channel {
                    Some(c) => {
                        let mut p = [0.0; 3];
                        p[c.min(2)] = 1.0;
                        p
                    }
                    None => channel_pdf(rays.throughput[i]),
                };
                // Ray-marched free flights are grey only: a chromatic medium's flights are
                // always tracked (module docs). An emissive one gathers pbrt-v4's estimate at
                // the flight's running per-channel weight.
                let segs = self.emissive_segments(&fields.grids, o, d, tmax[i]);
                let emission = |t: f32, sigma_t: f32| {
                    if emits {
                        emission_at(o + d * t, sigma_t) * light_weight(i, t)
                    } else {
                        Rgb::BLACK
                    }
                };
                let rand = || stream.next_1d();
                let (f, e) = if per_channel {
                    let sigma_c = PerChannel(|t: f32| scale * fields.density.colour(o + d * t));
                    spectral_tracking_channels(segs, sigma_c, p, emission, rand)
                } else {
                    spectral_tracking_emitting(segs, sigma, k, p, emission, rand)
                };
                if emits {
                    out.emitted.push(i as u32, e);
                }
                weight[i] = f.weight;
                FreeFlight {
                    t: f.t,
                    collided: f.collided,
                    nulls: f.nulls,
                    violations: f.violations,
                }
            } else if emits {
                // pbrt-v4's estimator: j / majorant at every tentative collision (module
                // docs), at the path's weight, which delta tracking keeps at 1.
                let (f, e) = delta_tracking_emitting(
                    self.emissive_segments(&fields.grids, o, d, tmax[i]),
                    sigma,
                    |t, sigma_t| emission_at(o + d * t, sigma_t) * light_weight(i, t),
                    || stream.next_1d(),
                );
                out.emitted.push(i as u32, e);
                f
            } else {
                let segs = fields
                    .grids
                    .density
                    .traverse(o, d, 0.0, tmax[i])
                    .map(|g| g.scaled(smax));
                if tracking == Tracking::RayMarching {
                    ray_marching_free_flight(segs, sigma, || stream.next_1d(), step)
                } else {
                    // Grey here (chromatic media took the branch above): a density grid's
                    // dense segments are integrated exactly.
                    let mut dense = self.dense_grid(o, d);
                    let f = delta_tracking_dense(segs, sigma, &mut dense, || stream.next_1d());
                    if let Some(g) = dense {
                        dense_taken += g.taken as u64;
                        dense_lookups += g.lookups as u64;
                    }
                    f
                }
            };
            align(s, start);
            nulls += f.nulls as u64;
            violations += f.violations as u64;
            scattered[i] = f.collided;
            t[i] = match f.collided {
                // Strictly inside the boundaries (as the homogeneous medium's events).
                true => crate::media::event_inside(services.ictx, rays, i, f.t, tmax[i]),
                false => f.t,
            };
        }
        if chromatic {
            // Passing rays' hits and misses carry the pass weight (the scattering rays'
            // leave below).
            for k in p0..out.points.len() {
                out.points.transmission[k] *= weight[out.points.ray_id[k] as usize];
            }
            for k in m0..out.misses.len() {
                out.miss_transmission[k] *= weight[out.misses[k] as usize];
            }
        }
        let ictx = &mut *services.ictx;
        ictx.count_majorant_violations(violations);
        ictx.count_dense_segments(dense_taken, dense_lookups);
        ictx.count_volume_pattern_evals(fields.evals());
        if emits {
            ictx.count_volume_events(VolumeEvent::Emission, n);
        }
        let events = scattered.iter().filter(|&&s| s).count();
        ictx.count_volume_events(VolumeEvent::Scatter, events);
        ictx.count_volume_events(VolumeEvent::Pass, n - events);
        ictx.count_volume_events(VolumeEvent::Null, nulls as usize);
        if events == 0 {
            return;
        }
        // Passing rays keep their hits (weight 1, or the chromatic pass weight); the hits and
        // misses of rays that scatter leave.
        let keep: Vec<bool> = (p0..out.points.len())
            .map(|k| !scattered[out.points.ray_id[k] as usize])
            .collect();
        retain_points(out, p0, &keep, g0);
        let mut j = m0;
        for k in m0..out.misses.len() {
            if !scattered[out.misses[k] as usize] {
                out.misses[j] = out.misses[k];
                out.miss_transmission[j] = out.miss_transmission[k];
                j += 1;
            }
        }
        out.misses.truncate(j);
        out.miss_transmission.truncate(j);
        // The scattering points: a volume-sampling context at P = o + t d, weight albedo
        // (times the flight's per-channel weight, for a chromatic medium).
        let own = (self.ctx.num_points() != n).then(|| {
            let mut pts = ShadingPoints::with_capacity(n);
            for i in 0..n {
                let (o, d) = (rays.origin[i], rays.direction[i]);
                pts.push(ShadingPointRow::in_volume(
                    o,
                    d,
                    i as u32,
                    self.ctx.material(),
                ));
            }
            pts
        });
        let own_ctx = own.as_ref().map(|pts| {
            let c = ShadingContext::new(pts, 0..n, ShadingMode::Interior, self.ctx.material(), &[]);
            match self.ctx.volume_space() {
                Some(space) => c.with_volume_space(space),
                None => c,
            }
        });
        let parent = own_ctx.as_ref().unwrap_or(self.ctx);
        let mut v = parent.begin_volume_sampling();
        v.set_along_rays(rays, &t);
        let mut w: Vec<Rgb> = if chromatic {
            weight.iter().map(|&w| w * m.albedo).collect()
        } else {
            vec![m.albedo; n]
        };
        if let Some(graph) = &m.albedo_pattern {
            // The albedo pattern at the scattering points (world P), one column.
            let evals = scale_by_albedo(graph, rays, &t, &scattered, &mut w);
            self.ctx.count_pattern_evals(evals);
        }
        v.set_transmission(&w);
        v.end_volume_sampling(&scattered, out);
    }

    fn transmission(
        &self,
        segments: &Segments,
        samplers: &mut [PathSampler],
        ictx: &dyn risotto_engine::plugin::IntegratorContext,
        trans: &mut [Rgb],
        emission: &mut [Rgb],
    ) {
        let tracking = ictx
            .technique(super::TRACKING.name)
            .and_then(Tracking::from_name)
            .unwrap_or(self.medium.tracking);
        let fields = self.fields();
        // Emission nobody uses is not gathered: the plain trackers then estimate the same
        // transmittance (unbiased either way) without an emission lookup per collision.
        if self.medium.emits() && ictx.emission_wanted() {
            for i in 0..segments.len() {
                let (r, e) = self.segment_emission(
                    &fields,
                    segments.origin[i],
                    segments.direction[i],
                    segments.length[i],
                    tracking,
                    &mut samplers[i],
                );
                trans[i] = r.value;
                ictx.count_majorant_violations(r.violations as u64);
                ictx.count_shadow_collisions(r.nulls as u64);
                emission[i] = e;
            }
            self.ctx.count_pattern_evals(fields.evals());
            return;
        }
        for i in 0..segments.len() {
            let (r, dense) = self.segment_transmittance(
                &fields,
                segments.origin[i],
                segments.direction[i],
                segments.length[i],
                tracking,
                &mut samplers[i],
            );
            trans[i] = r.value;
            ictx.count_majorant_violations(r.violations as u64);
            ictx.count_dense_segments(dense.0 as u64, dense.1 as u64);
            ictx.count_shadow_collisions(r.nulls as u64);
        }
        self.ctx.count_pattern_evals(fields.evals());
        emission.fill(Rgb::BLACK);
    }
}
