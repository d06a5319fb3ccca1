//! A homogeneous medium's emission along path rays, and the medium as a light
//! ([`risotto_engine::plugin::volume_light`]).
//!
//! # Along path rays
//! A ray crossing the medium on `[0, d]` gathers `int_0^d T(s) j ds` with
//! `T(s) = exp(-sigma_t s)` (the in-scattered and transmitted terms are the free flight's,
//! independently). Where no light sample competes for the emission, the weight of the
//! unidirectional technique is 1 everywhere and the integral is exact:
//! `j (1 - exp(-sigma_t d)) / sigma_t` per channel ([`emitted_radiance`]).
//!
//! # As a light
//! Behind an index-matched `interface`, the medium is also a [`VolumeEmitter`]. It is one
//! cell over the shape's bounds, with `j_max = j` and the tracking bound `rate` below.
//! Every vertex that light-samples it needs the density with which path rays reach `x`,
//! to weigh its sample against them. So the rays that a light sample competed with
//! (`VolumeLightMis::weighs`) gather the weighted integral `int_0^d T(s) j w_U(x(s)) ds`
//! instead, with a point estimator of known density. The estimator sums
//! `T(s_k) j w_U(x_k) / rate` over the comb of points `s_k = (k + u) / rate`, `k = 0, 1,
//! ...`, below `d`, with one uniform `u` per ray (systematic sampling): every point of the
//! line is covered by exactly one tooth's stratum of length `1 / rate`, so
//! `E[sum_k f(s_k)] = rate int_0^d f(s) ds` and the sum is unbiased. Its density in volume
//! measure is `pdf_dir(w) rate / s^2`, for the direction's pdf `pdf_dir` and the distance
//! `s` from the ray's last vertex. That is the heterogeneous media's collision estimator
//! with `majorant = rate` (tentative collisions of rate `majorant`), so
//! [`VolumeLightMis::unidirectional_weight`] gives `w_U` and the light side `w_V`
//! unchanged, and the two form a partition of unity. The comb's count is fixed by `d` up
//! to one, so it has far less variance than a Poisson process of the same rate; only
//! the smooth integrand is sampled.
//!
//! `rate = max(max_c sigma_t,c, EMISSION_COLLISIONS_PER_CELL / width)` for the widest side
//! `width` of the box: at least about one point per crossing of a thin medium, and no more
//! points than a tracker's tentative collisions in a dense one. The sum stops where `T`
//! falls below `1e-12` in every channel: the rest of the integral is below `1e-12 j /
//! sigma_t`, far below the sum's rounding. Camera rays, rays after a
//! Dirac event and every ray under `lighting = nee | bxdf` keep the exact integral.
//!
//! In a random walk (`scattering = "walk"`) only each walk's first step is weighed: the
//! walk's events sample no light, so the segments after them compete with no light sample
//! (a light sample from the vertex the ray left estimates the unscattered emission only)
//! and keep the exact integral.

use super::random_walk::sampler_stream;
use super::HomogeneousMedium;
use glam::Vec3;
use risotto_components::{Rays, Rgb};
use risotto_engine::plugin::{EmitterSupport, VolumeEmitter, VolumeLightMis};
use risotto_systems::grid::DensityGrid;
use risotto_systems::medium::{emitted_radiance, transmittance};
use risotto_systems::sampler::PathSampler;
use risotto_systems::volume_lights::EmissionField;
use std::sync::Arc;

/// Transmittance below which the point estimator stops (module docs).
const TAIL: f32 = 1e-12;

/// The rate (points per unit length) of the point estimator over the box `(lo, hi)` (module docs).
fn rate(m: &HomogeneousMedium, bounds: (Vec3, Vec3)) -> f32 {
    m.sigma_t
        .max_channel()
        .max(emission_floor(bounds, [1, 1, 1]))
}

impl HomogeneousMedium {
    /// The medium placed in `bounds` as a volume emitter: one cell, emitting `emission`
    /// within `support`, with the point estimator's rate as its tracking bound (module
    /// docs). `None` when it does not emit or the box has no volume.
    pub fn volume_emitter(
        &self,
        bounds: (Vec3, Vec3),
        support: EmitterSupport,
    ) -> Option<VolumeEmitter> {
        if !self.emits() {
            return None;
        }
        let one = DensityGrid::constant([1, 1, 1], 1.0).ok()?;
        let field = EmissionField::Grid {
            grid: Arc::new(one),
            scale: self.emission,
        };
        let majorant = vec![rate(self, bounds)];
        VolumeEmitter::new(
            bounds,
            [1, 1, 1],
            &[self.emission],
            majorant,
            field,
            support,
        )
        .ok()
    }
}

/// The salt of the point estimator's random stream ([`sampler_stream`]: no sampler
/// dimension is drawn, so scenes where no light sample competes keep their images).
const STREAM_SALT: u64 = 0x5851_F42D_4C95_7F2D;

/// The emission ray `i` of `rays` gathers on its segment `[0, d]` in medium `m`: exact, or
/// with `light` and a ray it weighs, the point estimator of the weighted integral (module
/// docs). `d = inf` (nothing ahead) gathers nothing.
pub(crate) fn emission_along(
    m: &HomogeneousMedium,
    rays: &Rays,
    i: usize,
    d: f32,
    light: Option<&VolumeLightMis<'_>>,
    sampler: &PathSampler,
) -> Rgb {
    let Some(light) = light.filter(|l| l.weighs(rays, i)) else {
        return emitted_radiance(m.sigma_t, m.emission, d);
    };
    if !d.is_finite() {
        return Rgb::BLACK;
    }
    let (lo, hi) = light.emitter.bounds();
    let rate = light.emitter.mis_majorant(0.5 * (lo + hi));
    if !(rate > 0.0 && rate.is_finite()) {
        return emitted_radiance(m.sigma_t, m.emission, d);
    }
    // One uniform offset for the whole comb of points `(k + u) / rate`.
    let u = sampler_stream(sampler, STREAM_SALT).f32();
    let (o, dir) = (rays.origin[i], rays.direction[i]);
    let mut sum = Rgb::BLACK;
    for k in 0u32.. {
        let s = (k as f32 + u) / rate;
        if s >= d {
            break;
        }
        let t = transmittance(m.sigma_t, s);
        if t.max_channel() < TAIL {
            // What is left is below TAIL j / sigma_t: far below the sum's rounding.
            break;
        }
        sum += t * light.unidirectional_weight(rays, i, o + dir * s);
    }
    m.emission * sum * (1.0 / rate)
}

/// Tentative collisions per majorant-cell width that a ray gets at least in a cell where
/// the medium emits (see [`HeterogeneousInterior`](crate::heterogeneous::HeterogeneousInterior)'s emission estimators).
pub const EMISSION_COLLISIONS_PER_CELL: f32 = 1.0;

/// The tentative-collision rate an emitting cell gets at least: [`EMISSION_COLLISIONS_PER_CELL`]
/// per width of the widest side of a cell, for the box `(lo, hi)` cut into `res` cells (the
/// widest, not the narrowest: a flat box would otherwise get a rate that a ray travelling
/// along it could not get through); 0 for a box without extent.
pub fn emission_floor((lo, hi): (glam::Vec3, glam::Vec3), res: [usize; 3]) -> f32 {
    let extent = (hi - lo).to_array();
    let width = (0..3)
        .map(|a| extent[a] / res[a].max(1) as f32)
        .filter(|w| *w > 0.0 && w.is_finite())
        .fold(0.0f32, f32::max);
    if width > 0.0 {
        (EMISSION_COLLISIONS_PER_CELL / width).min(f32::MAX)
    } else {
        0.0
    }
}
