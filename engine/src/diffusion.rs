//! The `subsurface` material's `diffusion` mode: the seed's SSDiffusion with Christensen and
//! Burley's normalized diffusion profile ([`risotto_systems::bssrdf`]).
//!
//! For every ray that entered the volume (refracted in at `po`), the integrator
//! 1. traces a short **feeler** ray through `po` to learn the boundary's normal `n` there;
//! 2. picks a channel (uniformly) and a radius `r` from that channel's profile (sampled
//!    exactly), an angle, and one of three **projection axes** -- the normal (probability
//!    1/2) and the two tangents (1/4 each), as production disk sampling does (King, Kulla,
//!    Conty and Fajardo 2013, "BSSRDF importance sampling") -- and traces a **probe ray**
//!    along the axis through the disk point, within the sphere of radius `r_max` around
//!    `po`;
//! 3. collects the probe's hits on the volume's own boundary (at most [`MAX_PROBE_HITS`])
//!    and picks one, `pi`, uniformly;
//! 4. weighs it by the profile over its pdf, **multiple-importance weighted** over the
//!    three axes and three channels (one-sample balance heuristic): with `v = pi - po`,
//!    `r_k` its distance from axis `k`'s line through `po`, and `n_i` the normal at `pi`,
//!    `pdf(pi) = sum_k p_k sum_c (1/3) pdf_c(r_k) / (2 pi r_k) |n_i . a_k| / N` (`N` the
//!    number of hits of the sampled probe -- the same `N` is used for the other axes'
//!    probes, which are not traced: the usual production approximation) and
//!    `weight_c = R_c(|v|) / pdf(pi)`;
//! 5. returns `pi` as the ray's exit, the weight in its transmission, arriving from inside
//!    along a cosine-distributed direction about `n_i` (the direction distribution of light
//!    leaving a diffusing medium), so the dielectric boundary then refracts it out (or
//!    reflects it back in) as it does the random walk's exits.
//!
//! With an index-matched boundary this estimates `L_o = int R(|pi - po|) E(pi) / pi dA`
//! exactly for the profile: a thick slab under a uniform sky reflects `A` in every
//! direction (the profile's normalization). Where the object is thinner than the profile
//! (`r_max` is 27 shape lengths), the probes find the far side as well and light passes
//! through without the medium's geometry (no attenuation by thickness): diffusion's known
//! failure on thin features, which `scenes/subsurface-thin.toml` shows against the walk.

use crate::plugin::*;
use crate::random_walk::{answer_exits, Exits};
use glam::Vec3;
use risotto_components::{LobeSampled, Rays, Rgb, NO_HIT};
use risotto_systems::bssrdf::{max_radius, profile, radius_pdf, sample_radius};
use risotto_systems::bxdf::Frame;
use risotto_systems::intersect::intersect_closest;
use risotto_systems::medium::transmittance;
use risotto_systems::ray::{coordinate_epsilon, tmin_past_hit};
use risotto_systems::sampler::PathSampler;
use std::f32::consts::PI;

/// Hits on its own boundary a probe ray collects at most.
pub const MAX_PROBE_HITS: usize = 4;

/// Probability of each projection axis: the normal, then the two tangents.
const AXIS_PDF: [f32; 3] = [0.5, 0.25, 0.25];

/// The diffusion mode's medium: per channel the surface albedo `A` and the profile's shape
/// `d = mean_free_path / s(A)`; `sigma_t` only attenuates shadow segments (which a
/// dielectric boundary never lets in).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffusionMedium {
    /// Surface (multiple-scattering) albedo per channel.
    pub albedo: Rgb,
    /// Profile shape `d` per channel, world units.
    pub d: Rgb,
    /// Extinction for shadow segments.
    pub sigma_t: Rgb,
}

/// The volume integrator of `mode = "diffusion"` (see the module docs).
pub struct DiffusionInterior {
    /// The medium.
    pub medium: DiffusionMedium,
}

impl VolumeIntegrator for DiffusionInterior {
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        samplers: &mut [PathSampler],
        _lobes_wanted: LobeSampled,
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
        let n = rays.len();
        if n == 0 {
            return;
        }
        let ictx = services.ictx;
        let scene = ictx.scene;
        let geometry = &scene.geometry;
        let m = &self.medium;
        let d = m.d.to_array();
        let albedo = m.albedo.to_array();
        // 1. Feelers: a short ray through each entry point along the ray, from just outside.
        // A feeler must find the surface again, so it starts a positive distance off it:
        // 1000 `coordinate_epsilon`s of the point (the points' own bounds can be zero).
        let mut fo = Vec::with_capacity(n);
        let mut fd = Vec::with_capacity(n);
        let mut fmax = Vec::with_capacity(n);
        for i in 0..n {
            let h = 1000.0 * coordinate_epsilon(rays.origin[i]);
            fo.push(rays.origin[i] - rays.direction[i] * h);
            fd.push(rays.direction[i]);
            fmax.push(2.0 * h);
        }
        let (mut t, mut prim, mut b1, mut b2) =
            (vec![0.0; n], vec![NO_HIT; n], vec![0.0; n], vec![0.0; n]);
        let fmin = vec![0.0f32; n];
        intersect_closest(
            geometry, &fo, &fd, &fmin, &fmax, &mut t, &mut prim, &mut b1, &mut b2,
        );
        // 2. Probes.
        let mut probes: Vec<Probe> = Vec::with_capacity(n);
        for i in 0..n {
            let (po, dir) = (rays.origin[i], rays.direction[i]);
            let normal = if prim[i] != NO_HIT {
                let s = geometry.surface_at(prim[i], fo[i], fd[i], t[i], b1[i], b2[i]);
                if s.ng.dot(dir) < 0.0 {
                    s.ng
                } else {
                    -s.ng
                }
            } else {
                -dir
            };
            let [u_axis, u_channel, u_r, u_phi] = samplers[i].next_4d();
            let [u_lobe, u_pick, ux, uy] = samplers[i].next_4d();
            let c = ((u_channel * 3.0) as usize).min(2);
            let r = sample_radius(d[c], u_lobe, u_r);
            let r_max = max_radius(d[c]);
            let frame = Frame::from_normal(normal);
            let axes = [frame.n, frame.s, frame.t];
            let k = if u_axis < AXIS_PDF[0] {
                0
            } else if u_axis < AXIS_PDF[0] + AXIS_PDF[1] {
                1
            } else {
                2
            };
            let (a, e1, e2) = (axes[k], axes[(k + 1) % 3], axes[(k + 2) % 3]);
            let phi = 2.0 * PI * u_phi;
            let valid = r < r_max && d[c] > 0.0;
            let h = (r_max * r_max - r * r).max(0.0).sqrt();
            probes.push(Probe {
                origin: po + (e1 * phi.cos() + e2 * phi.sin()) * r + a * h,
                direction: -a,
                tmin: 0.0,
                tmax: if valid { 2.0 * h } else { 0.0 },
                hits: Vec::new(),
                u_pick,
                u_exit: (ux, uy),
                axes,
            });
        }
        // 3. Trace the probes, collecting hits on each ray's own boundary.
        let own: Vec<Option<u32>> = (0..n)
            .map(|i| rays.volume_stack[i].innermost().map(|e| e.shape))
            .collect();
        for _ in 0..2 * MAX_PROBE_HITS {
            let live: Vec<usize> = (0..n)
                .filter(|&i| {
                    probes[i].tmax > probes[i].tmin && probes[i].hits.len() < MAX_PROBE_HITS
                })
                .collect();
            if live.is_empty() {
                break;
            }
            let o: Vec<Vec3> = live.iter().map(|&i| probes[i].origin).collect();
            let dd: Vec<Vec3> = live.iter().map(|&i| probes[i].direction).collect();
            let lo: Vec<f32> = live.iter().map(|&i| probes[i].tmin).collect();
            let hi: Vec<f32> = live.iter().map(|&i| probes[i].tmax).collect();
            let k = live.len();
            let (mut t, mut prim, mut b1, mut b2) =
                (vec![0.0; k], vec![NO_HIT; k], vec![0.0; k], vec![0.0; k]);
            intersect_closest(
                geometry, &o, &dd, &lo, &hi, &mut t, &mut prim, &mut b1, &mut b2,
            );
            for (j, &i) in live.iter().enumerate() {
                let p = &mut probes[i];
                if prim[j] == NO_HIT {
                    p.tmax = p.tmin;
                    continue;
                }
                let s = geometry.surface_at(prim[j], o[j], dd[j], t[j], b1[j], b2[j]);
                if Some(scene.prim_shape[prim[j] as usize]) == own[i] {
                    p.hits.push((s.p, s.ng));
                }
                // Go on past this surface along the same line.
                p.tmin = tmin_past_hit(t[j], s.offset(), s.ng, dd[j]);
            }
        }
        // 4. and 5.: pick a hit, weigh it, and leave from it.
        let mut exits = Exits::default();
        for (i, p) in probes.iter().enumerate() {
            let count = p.hits.len();
            if count == 0 {
                continue;
            }
            let pick = ((p.u_pick * count as f32) as usize).min(count - 1);
            let (pi, ng) = p.hits[pick];
            // The outward normal at the exit (the boundary's geometric normal is outward
            // for the closed shapes volumes are made of).
            let ni = ng;
            let v = pi - rays.origin[i];
            let dist = v.length();
            let mut pdf = 0.0f32;
            for (k, &a) in p.axes.iter().enumerate() {
                let rk = (v - a * v.dot(a)).length();
                let cos = ni.dot(a).abs();
                for dc in d {
                    if rk < max_radius(dc) && rk > 0.0 {
                        pdf += AXIS_PDF[k] / 3.0 * radius_pdf(dc, rk) / (2.0 * PI * rk) * cos;
                    }
                }
            }
            pdf /= count as f32;
            if !(pdf > 0.0 && pdf.is_finite()) {
                continue;
            }
            let weight = Rgb::new(
                profile(albedo[0], d[0], dist),
                profile(albedo[1], d[1], dist),
                profile(albedo[2], d[2], dist),
            ) * (1.0 / pdf);
            if !weight.is_finite() || weight.is_black() {
                continue;
            }
            // Cosine-distributed direction about the outward normal: the walk's last
            // segment, arriving at pi from inside.
            let (ux, uy) = p.u_exit;
            let (rr, phi) = (ux.sqrt(), 2.0 * PI * uy);
            let local = Vec3::new(rr * phi.cos(), rr * phi.sin(), (1.0 - ux).max(0.0).sqrt());
            let dir = Frame::from_normal(ni).to_world(local).normalize_or(ni);
            // A feeler that finds the surface at `pi` again (as the entry feelers above).
            let delta = 1000.0 * coordinate_epsilon(pi);
            exits.ray.push(i as u32);
            exits.origin.push(pi - dir * delta);
            exits.direction.push(dir);
            exits.tmin.push(0.0);
            exits.tmax.push(2.0 * delta);
            exits.weight.push(weight);
            exits.events.push(1);
        }
        ictx.stats
            .volume_event(crate::stats::VolumeEvent::Scatter, exits.ray.len());
        answer_exits(rays, &exits, ictx, out);
    }

    fn transmission(
        &self,
        segments: &Segments,
        _samplers: &mut [PathSampler],
        _ictx: &crate::context::IntegratorContext<'_>,
        trans: &mut [Rgb],
        emission: &mut [Rgb],
    ) {
        for i in 0..segments.len() {
            trans[i] = transmittance(self.medium.sigma_t, segments.length[i]);
        }
        emission.fill(Rgb::BLACK);
    }
}

/// One ray's probe: its line, how far it has been traced, and the boundary hits found.
struct Probe {
    origin: Vec3,
    direction: Vec3,
    tmin: f32,
    tmax: f32,
    hits: Vec<(Vec3, Vec3)>,
    u_pick: f32,
    u_exit: (f32, f32),
    axes: [Vec3; 3],
}
