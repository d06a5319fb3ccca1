//! The `subsurface` material's `diffusion` mode: the seed's SSDiffusion with Christensen and
//! Burley's normalized diffusion profile ([`risotto_systems::bssrdf`]).
//!
//! For every ray that entered the volume (refracted in at `po`), the integrator
//! 1. traces a short **feeler** ray through `po` to learn the boundary's normal `n` there,
//!    and a second feeler from `po` along `-n` to the first hit on the volume's own
//!    boundary within `2 D`, where `D` ([`DiffusionMedium::reach`]) is the profile's reach,
//!    the largest `r_max` over the channels: that hit's depth is the object's **thickness**
//!    `T` there (none: `T` infinite, a half-space for the profile);
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
//!    `pdf(pi) = sum_k p_k sum_c (1/3) pdf_c(r_k) / (2 pi r_k) |n_i . a_k| / N_kc` and
//!    `weight_c = f_c R_c(dist) / pdf(pi)` (the layer factor `f_c` and `dist` below).
//!    `N_kc` is the number of hits the probe of axis `k` and channel `c`'s sphere through
//!    `pi` collects (0 terms where `pi` would come after the first [`MAX_PROBE_HITS`]).
//!    Where a thickness was measured, the three axes' lines through `pi` are traced
//!    (over the largest sphere, three more rays per thin entry) and counted per channel
//!    sphere: the pdf is then exact. Elsewhere -- the object is more than `2 D` thick
//!    under `po`, so each probe meets one surface, locally flat at the profile's scale --
//!    the sampled probe's count `N` is used for every axis and channel, the usual
//!    production approximation, which is exact for a flat half-space and biased by how
//!    much the untraced probes' counts differ on curved or cornered ones;
//! 5. returns `pi` as the ray's exit, the weight in its transmission, arriving from inside
//!    along a cosine-distributed direction about `n_i` (the direction distribution of light
//!    leaving a diffusing medium), so the dielectric boundary then refracts it out (or
//!    reflects it back in) as it does the random walk's exits.
//!
//! # Depth and thickness (the seed's steps 1 and 2)
//! The probes are shot from the depth `z = T / 2` below `po` (along `-n`): the part of each
//! probe's line above that depth finds the entry side, the part below it the far side, and
//! a hit is on the **far side** when its height `v . n` is below `-z`. With no thickness
//! measured (`T > 2 D`) the depth is the whole reach and every hit is on the entry side.
//! The energy is split between the sides by the **Kubelka-Munk** reflectance and
//! transmittance of a layer `T` thick whose infinitely thick reflectance is the albedo
//! ([`slab_reflectance_transmittance`], `R_inf = A`; its scattering coefficient
//! `S = (3/4) sigma_s (1 - g)` from the walked medium, see
//! [`crate::subsurface::SubsurfaceParams::slab_scattering`]): an entry-side hit weighs
//! `f = R_KM(S T) / A` times the profile at `dist = |v|`, a far-side hit
//! `f = T_KM(S T) / A` times the profile at `dist = |v - n (v . n)|`, its distance across
//! from `po`'s normal line (so that the whole far side of a flat layer, whatever `T`,
//! receives `T_KM`: the transmitted light spreads as the reflected light does). Each side's
//! estimate is the exact integral of its weighted profile over the surface the probes find
//! (the sampling is unchanged), so on a flat layer this estimates exactly reflectance
//! `R_KM` and transmittance `T_KM`, and on objects thicker than `2 D` the semi-infinite
//! profile as before. The split is an approximation of the diffusion model, not a
//! consistent estimator of the transport in a layer: two-flux theory for the energies
//! (exact for diffuse light in its model, `R + T <= 1` with equality without absorption),
//! the half-space profile's shape on both sides, and the thickness taken at `po` alone
//! (a wedge or a curved shell gets the thickness under the entry point). On slabs 0.1 to 3
//! mean free paths thick (`tests/subsurface.rs`) it reflects and transmits within 0.09 of
//! the random walk; without it the probes counted the far side as more of the entry side
//! (reflectance `A` and about as much again transmitted: up to 1.67 times the light in).
//!
//! With an index-matched boundary this estimates `L_o = int R(|pi - po|) E(pi) / pi dA`
//! exactly for the profile on objects thicker than `2 D`: a thick slab under a uniform sky
//! reflects `A` in every direction (the profile's normalization). The exit's last segment
//! starts a small inset below `pi` (within a quarter of the thickness) and runs to the
//! boundary, so that it cannot start within a large triangle's re-hit bound and miss it.

use glam::Vec3;
use risotto_components::{Hits, LobeSampled, Rays, Rgb, NO_HIT};
use risotto_engine::plugin::*;
use risotto_systems::bssrdf::{
    max_radius, profile, radius_pdf, sample_radius, slab_reflectance_transmittance,
};
use risotto_systems::bxdf::Frame;
use risotto_systems::medium::transmittance;
use risotto_systems::ray::{coordinate_epsilon, tmin_past_hit};
use risotto_systems::sampler::PathSampler;
use std::f32::consts::PI;

/// Hits on its own boundary a probe ray collects at most.
pub const MAX_PROBE_HITS: usize = 4;

/// Probability of each projection axis: the normal, then the two tangents.
const AXIS_PDF: [f32; 3] = [0.5, 0.25, 0.25];

/// The diffusion mode's medium: per channel the surface albedo `A`, the profile's shape
/// `d = mean_free_path / s(A)` and the two-flux scattering coefficient `S` of the thin-layer
/// split; `sigma_t` only attenuates shadow segments (which a dielectric boundary never lets
/// in).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffusionMedium {
    /// Surface (multiple-scattering) albedo per channel.
    pub albedo: Rgb,
    /// Profile shape `d` per channel, world units.
    pub d: Rgb,
    /// Kubelka-Munk scattering coefficient `S` per world unit, per channel: how fast a
    /// layer's reflectance grows with its thickness (see the module docs).
    pub slab_scattering: Rgb,
    /// Extinction for shadow segments.
    pub sigma_t: Rgb,
    /// Where the object is thin, count every axis' and channel's probe hits through the
    /// picked hit for the MIS pdf (by tracing them) instead of using the sampled probe's
    /// count `N` for all (see the module docs). On by default; off only to measure the
    /// approximation.
    pub exact_counts: bool,
}

impl DiffusionMedium {
    /// The profile's reach: the largest [`max_radius`] over the channels. Objects thicker
    /// than twice this are semi-infinite for the profile.
    pub fn reach(&self) -> f32 {
        max_radius(self.d.max_channel())
    }

    /// Per channel, the factors on the profile for the entry side and for the far side of a
    /// layer `thickness` thick (infinite: a half-space, `(1, 0)`): Kubelka-Munk's `R / A`
    /// and `T / A` ([`slab_reflectance_transmittance`]), so that the entry side reflects `R`
    /// and the far side transmits `T` in all.
    pub fn layer_factors(&self, thickness: f32) -> ([f32; 3], [f32; 3]) {
        if !thickness.is_finite() {
            return ([1.0; 3], [0.0; 3]);
        }
        let (a, s) = (self.albedo.to_array(), self.slab_scattering.to_array());
        let mut near = [0.0; 3];
        let mut far = [0.0; 3];
        for c in 0..3 {
            if a[c] > 0.0 {
                let (r, t) = slab_reflectance_transmittance(a[c], s[c] * thickness);
                near[c] = r / a[c];
                far[c] = t / a[c];
            }
        }
        (near, far)
    }
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
        self.diffuse(None, rays, samplers, services.ictx, out);
    }

    fn transmission(
        &self,
        segments: &Segments,
        _samplers: &mut [PathSampler],
        _ictx: &dyn risotto_engine::plugin::IntegratorContext,
        trans: &mut [Rgb],
        emission: &mut [Rgb],
    ) {
        for i in 0..segments.len() {
            trans[i] = transmittance(self.medium.sigma_t, segments.length[i]);
        }
        emission.fill(Rgb::BLACK);
    }
}

impl DiffusionInterior {
    /// The diffusion estimate of every ray's exit (see the module docs), each ray's profile
    /// from `per_ray[i]` if given (a `subsurface` material whose albedo or mean free path is
    /// a pattern, read at the ray's entry point), else from the interior's medium.
    pub fn diffuse(
        &self,
        per_ray: Option<&[DiffusionMedium]>,
        rays: &Rays,
        samplers: &mut [PathSampler],
        ictx: &mut dyn risotto_engine::plugin::IntegratorContext,
        out: &mut ShadeGroups,
    ) {
        let n = rays.len();
        if n == 0 {
            return;
        }
        if let Some(p) = per_ray {
            assert_eq!(p.len(), n, "one medium per ray");
        }
        let exact_counts = self.medium.exact_counts;
        let medium_of = |i: usize| per_ray.map_or(&self.medium, |p| &p[i]);
        let own: Vec<Option<u32>> = (0..n)
            .map(|i| rays.volume_stack[i].innermost().map(|e| e.shape))
            .collect();
        // 1. Feelers: a short ray through each entry point along the ray, from just outside,
        // for the normal there. A feeler must find the surface again, so it starts a positive
        // distance off it: 1000 `coordinate_epsilon`s of the point (the points' own bounds can
        // be zero).
        let mut fo = Vec::with_capacity(n);
        let mut fd = Vec::with_capacity(n);
        let mut fmax = Vec::with_capacity(n);
        for i in 0..n {
            let h = 1000.0 * coordinate_epsilon(rays.origin[i]);
            fo.push(rays.origin[i] - rays.direction[i] * h);
            fd.push(rays.direction[i]);
            fmax.push(2.0 * h);
        }
        let fmin = vec![0.0f32; n];
        let mut hits = Hits::default();
        ictx.closest_hits(&fo, &fd, &fmin, &fmax, &mut hits);
        let (t, prim, b1, b2) = (&hits.t, &hits.prim, &hits.b1, &hits.b2);
        let normals: Vec<Vec3> = (0..n)
            .map(|i| {
                let dir = rays.direction[i];
                if prim[i] != NO_HIT {
                    let s = ictx.surface_at(prim[i], fo[i], fd[i], t[i], b1[i], b2[i]);
                    if s.ng.dot(dir) < 0.0 {
                        s.ng
                    } else {
                        -s.ng
                    }
                } else {
                    -dir
                }
            })
            .collect();
        // 2. Thickness feelers: from each entry point along -n to the first hit on the
        // volume's own boundary, within twice the profile's reach.
        let mut feelers: Vec<Line> = (0..n)
            .map(|i| {
                let po = rays.origin[i];
                Line::new(
                    po,
                    -normals[i],
                    1000.0 * coordinate_epsilon(po),
                    2.0 * medium_of(i).reach(),
                )
            })
            .collect();
        trace_own_hits(ictx, &own, &mut feelers, 1);
        let thickness: Vec<f32> = (0..n)
            .map(|i| match feelers[i].hits.first() {
                Some(&(p, _)) => (p - rays.origin[i]).dot(-normals[i]).max(0.0),
                None => f32::INFINITY,
            })
            .collect();
        // 3. Probes.
        let mut probes: Vec<Probe> = Vec::with_capacity(n);
        for i in 0..n {
            let po = rays.origin[i];
            let d = medium_of(i).d.to_array();
            let [u_axis, u_channel, u_r, u_phi] = samplers[i].next_4d();
            let [u_lobe, u_pick, ux, uy] = samplers[i].next_4d();
            let c = ((u_channel * 3.0) as usize).min(2);
            let r = sample_radius(d[c], u_lobe, u_r);
            let r_max = max_radius(d[c]);
            let frame = Frame::from_normal(normals[i]);
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
                line: Line::new(
                    po + (e1 * phi.cos() + e2 * phi.sin()) * r + a * h,
                    -a,
                    0.0,
                    if valid { 2.0 * h } else { 0.0 },
                ),
                u_pick,
                u_exit: (ux, uy),
                axes,
            });
        }
        let mut lines: Vec<Line> = probes
            .iter_mut()
            .map(|p| std::mem::replace(&mut p.line, Line::new(Vec3::ZERO, Vec3::Z, 0.0, 0.0)))
            .collect();
        trace_own_hits(ictx, &own, &mut lines, MAX_PROBE_HITS);
        // 4. and 5.: pick a hit, weigh it, and leave from it.
        let picks: Vec<Option<(Vec3, Vec3, usize)>> = probes
            .iter()
            .zip(&lines)
            .map(|(p, line)| {
                let count = line.hits.len();
                (count > 0).then(|| {
                    let pick = ((p.u_pick * count as f32) as usize).min(count - 1);
                    (line.hits[pick].0, line.hits[pick].1, count)
                })
            })
            .collect();
        // Where the object is thin, the probes of the other axes (and of the other channels'
        // spheres) through the picked hit may find another number of hits than the sampled
        // one: trace the three axes' lines through it, over the largest sphere, and count.
        let mut recount: Vec<Line> = Vec::new();
        let mut recount_own: Vec<Option<u32>> = Vec::new();
        let mut recount_at = vec![usize::MAX; n];
        if exact_counts {
            for i in 0..n {
                let Some((pi, _, _)) = picks[i] else { continue };
                if !thickness[i].is_finite() {
                    continue;
                }
                let reach = medium_of(i).reach();
                recount_at[i] = recount.len();
                let v = pi - rays.origin[i];
                for &a in &probes[i].axes {
                    let b = v.dot(a);
                    let disc = (b * b - (v.length_squared() - reach * reach)).max(0.0);
                    let (hi, lo) = (-b + disc.sqrt(), -b - disc.sqrt());
                    recount.push(Line::new(pi + a * hi, -a, 0.0, (hi - lo).max(0.0)));
                    recount_own.push(own[i]);
                }
            }
            trace_own_hits(ictx, &recount_own, &mut recount, 2 * MAX_PROBE_HITS);
        }
        let mut exits = Exits::default();
        for (i, p) in probes.iter().enumerate() {
            let Some((pi, ng, count)) = picks[i] else {
                continue;
            };
            let m = medium_of(i);
            let (d, albedo, reach) = (m.d.to_array(), m.albedo.to_array(), m.reach());
            // The outward normal at the exit (the boundary's geometric normal is outward
            // for the closed shapes volumes are made of).
            let ni = ng;
            let po = rays.origin[i];
            let v = pi - po;
            let mut pdf = 0.0f32;
            for (k, &a) in p.axes.iter().enumerate() {
                let rk = (v - a * v.dot(a)).length();
                let cos = ni.dot(a).abs();
                for dc in d {
                    if !(rk < max_radius(dc) && rk > 0.0) {
                        continue;
                    }
                    let hits = if recount_at[i] == usize::MAX {
                        Some(count)
                    } else {
                        let line = &recount[recount_at[i] + k];
                        probe_count(&line.hits, pi, a, po, max_radius(dc), thickness[i])
                    };
                    if let Some(hits) = hits {
                        pdf += AXIS_PDF[k] / 3.0 * radius_pdf(dc, rk) / (2.0 * PI * rk) * cos
                            / hits as f32;
                    }
                }
            }
            if !(pdf > 0.0 && pdf.is_finite()) {
                continue;
            }
            // The depth the probes are shot from: half the thickness where the object is
            // thinner than twice the reach. Hits below it are on the far side.
            let depth = 0.5 * thickness[i];
            let (near, far) = m.layer_factors(thickness[i]);
            let height = v.dot(normals[i]);
            let weight = if height < -depth {
                // The far side: the transmitted profile over the distance across, from the
                // entry point's normal line.
                let across = (v - normals[i] * height).length();
                Rgb::new(
                    far[0] * profile(albedo[0], d[0], across),
                    far[1] * profile(albedo[1], d[1], across),
                    far[2] * profile(albedo[2], d[2], across),
                )
            } else {
                let dist = v.length();
                Rgb::new(
                    near[0] * profile(albedo[0], d[0], dist),
                    near[1] * profile(albedo[1], d[1], dist),
                    near[2] * profile(albedo[2], d[2], dist),
                )
            } * (1.0 / pdf);
            if !weight.is_finite() || weight.is_black() {
                continue;
            }
            // Cosine-distributed direction about the outward normal: the walk's last
            // segment, arriving at pi from inside.
            let (ux, uy) = p.u_exit;
            let (rr, phi) = (ux.sqrt(), 2.0 * PI * uy);
            let local = Vec3::new(rr * phi.cos(), rr * phi.sin(), (1.0 - ux).max(0.0).sqrt());
            let dir = Frame::from_normal(ni).to_world(local).normalize_or(ni);
            // The exit's last segment starts inside, `inset` below `pi` along the inward
            // normal, and runs to the first boundary it meets (the surface at `pi`). A
            // segment starting within a triangle's conservative re-hit bound of it (which
            // grows with the triangle's coordinates, not `pi`'s) would miss the surface and
            // be taken for an escape to the environment; the inset is kept within a quarter
            // of the thickness so that it stays inside thin objects.
            let inset = (1000.0 * coordinate_epsilon(pi))
                .max(1e-3 * reach)
                .min(0.25 * thickness[i]);
            exits.ray.push(i as u32);
            exits.origin.push(pi - ni * inset);
            exits.direction.push(dir);
            exits.tmin.push(0.0);
            exits.tmax.push(f32::INFINITY);
            exits.weight.push(weight);
            exits.events.push(1);
        }
        ictx.count_volume_events(risotto_engine::stats::VolumeEvent::Scatter, exits.ray.len());
        answer_exits(rays, &exits, ictx, out);
    }
}

/// A line traced for hits on a volume's own boundary: where it starts, how far it has been
/// traced, and the hits found (point and geometric normal).
struct Line {
    origin: Vec3,
    direction: Vec3,
    tmin: f32,
    tmax: f32,
    hits: Vec<(Vec3, Vec3)>,
}

impl Line {
    fn new(origin: Vec3, direction: Vec3, tmin: f32, tmax: f32) -> Line {
        Line {
            origin,
            direction,
            tmin,
            tmax,
            hits: Vec::new(),
        }
    }
}

/// Traces every line through whatever it crosses, collecting up to `max_hits` hits on the
/// boundary of line `i`'s own shape `own[i]` (other shapes' surfaces are passed through).
fn trace_own_hits(
    ictx: &mut dyn risotto_engine::plugin::IntegratorContext,
    own: &[Option<u32>],
    lines: &mut [Line],
    max_hits: usize,
) {
    let mut hits = Hits::default();
    for _ in 0..2 * max_hits.max(MAX_PROBE_HITS) {
        let live: Vec<usize> = (0..lines.len())
            .filter(|&i| lines[i].tmax > lines[i].tmin && lines[i].hits.len() < max_hits)
            .collect();
        if live.is_empty() {
            break;
        }
        let o: Vec<Vec3> = live.iter().map(|&i| lines[i].origin).collect();
        let dd: Vec<Vec3> = live.iter().map(|&i| lines[i].direction).collect();
        let lo: Vec<f32> = live.iter().map(|&i| lines[i].tmin).collect();
        let hi: Vec<f32> = live.iter().map(|&i| lines[i].tmax).collect();
        ictx.closest_hits(&o, &dd, &lo, &hi, &mut hits);
        let (t, prim, b1, b2) = (&hits.t, &hits.prim, &hits.b1, &hits.b2);
        for (j, &i) in live.iter().enumerate() {
            let p = &mut lines[i];
            if prim[j] == NO_HIT {
                p.tmax = p.tmin;
                continue;
            }
            let s = ictx.surface_at(prim[j], o[j], dd[j], t[j], b1[j], b2[j]);
            if Some(ictx.shape_of(prim[j])) == own[i] {
                p.hits.push((s.p, s.ng));
            }
            // Go on past this surface along the same line.
            p.tmin = tmin_past_hit(t[j], s.offset(), s.ng, dd[j]);
        }
    }
}

/// How many hits the probe of a sphere of radius `r_max` around `po` along `-a` through
/// `pi` collects (`hits`: the own-boundary hits along `-a` on the line through `pi`, over
/// a sphere at least as large), or `None` if `pi` comes after the first [`MAX_PROBE_HITS`]
/// and so cannot be picked. `pi` itself is counted whether or not the retrace found it
/// (hits within a small tolerance of it are taken for it).
fn probe_count(
    hits: &[(Vec3, Vec3)],
    pi: Vec3,
    a: Vec3,
    po: Vec3,
    r_max: f32,
    thickness: f32,
) -> Option<usize> {
    let tol = (1e-4 * r_max).min(0.1 * thickness);
    let (mut above, mut others) = (0usize, 0usize);
    for &(x, _) in hits {
        if (x - po).length() > r_max {
            continue;
        }
        let s = (x - pi).dot(a);
        if s.abs() <= tol {
            continue;
        }
        others += 1;
        if s > 0.0 {
            above += 1;
        }
    }
    (above < MAX_PROBE_HITS).then_some((others + 1).min(MAX_PROBE_HITS))
}

/// One ray's probe: its line, and the samples that pick a hit and the exit direction.
struct Probe {
    line: Line,
    u_pick: f32,
    u_exit: (f32, f32),
    axes: [Vec3; 3],
}
