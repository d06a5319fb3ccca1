//! The random walk inside a homogeneous medium, run by the volume integrator itself: the
//! seed's SSDiffusion shape (the integrator traces its own rays and returns only hits) with
//! path-traced transport inside instead of a diffusion profile.
//!
//! # What it does
//! [`walk_bundle`] takes a bundle of rays travelling in the medium and walks every one of
//! them, in a tight loop over the bundle: trace the live walkers to the nearest surface
//! (the boundary, or anything inside it), sample a free flight on each segment (one-sample
//! spectral MIS over the RGB channels, [`sample_free_flight`], with the medium's exact
//! homogeneous transmittance), and for the walkers that scatter, sample the phase function
//! and go again. A walker whose flight passes its segment has reached a surface: that hit
//! (or miss) is its **exit**, returned to the global integrator as an ordinary surface
//! point, with the walk's weight in its transmission and the walk's last segment in
//! [`ShadeGroups::walked`] (the global integrator then shades the boundary -- a dielectric
//! reflects the walker back in or refracts it out -- as for any hit). The global
//! integrator sees one bounce per boundary interaction, never one per scattering event.
//!
//! # Steps without rays
//! After every traced event the walker learns its **clearance**, the distance to the
//! nearest surface ([`risotto_systems::clearance`], a BVH distance query), and keeps the
//! ball of that radius (less a rounding margin) around the event: a segment between two
//! points of a ball that contains no surface crosses none, so every later step that ends
//! inside the ball is taken without tracing (the same random numbers, the same event as a
//! traced step would give). Deep inside a dense medium a walker takes dozens of steps per
//! ray; near the boundary the balls shrink and every step is traced. Traced steps ask only
//! for surfaces up to the sampled distance (plus a margin), which the BVH culls early.
//!
//! No light is sampled at the walk's events. That is exact (the walk is an unbiased
//! estimator of every order of scattering on its own: every event's outgoing direction
//! comes from the phase function, and emitters found by a walk segment count with full
//! weight) and it is the efficient choice where a shadow ray from inside the medium cannot
//! reach a light: behind a boundary that blocks shadow rays (a dielectric without cheap
//! shadows, an opaque surface), with no point light inside. That is the rule by which a
//! `homogeneous` interior walks on its own ([`crate::media::Scattering::Multiple`]); a
//! `subsurface` material and `scattering = "walk"` always walk.
//!
//! # Weights and Russian roulette
//! Let `w` be the walk's weight (per channel, starting at 1) and `b` the throughput the ray
//! carried into the volume. The channel probabilities of every flight are `p_c ∝ b_c w_c`.
//! With those, the scalar `A = sum_c b_c w_c / sum_c b_c` **never increases**: at a
//! scattering event (`w'_c = w_c sigma_s,c T_c / sum_k p_k sigma_t,k T_k`)
//! `A' = A sum_c b_c w_c sigma_s,c T_c / sum_k b_k w_k sigma_t,k T_k <= A` because
//! `sigma_s <= sigma_t`, and on a pass (`w'_c = w_c T_c / sum_k p_k T_k`) `A' = A`. `A` is
//! the albedo-corrected throughput of the walk: the fraction of the incoming path's weight
//! the walk still carries.
//!
//! After each scattering event the walk survives with probability
//! `q = clamp(A, Q_FLOOR, 1)` and divides `w` by `q`. **Unbiased**: `q` depends only on the
//! walk so far, and `E[w'] = q (w / q) + (1 - q) 0 = w` (Arvo and Kirk 1990, "Particle
//! transport and image synthesis", sec. 3.3). **Bounded**: survivors have `A' = A / q`,
//! which is exactly 1 while `A >= Q_FLOOR` and below 1 otherwise, so `A <= 1` for the
//! whole walk however long it is, and each channel `w_c <= A sum_k b_k / b_c`. In a grey
//! medium `A` is the walk weight itself and the rule is analog absorption: the walker dies
//! with probability `1 - albedo` per event and carries weight exactly 1.
//!
//! Mitsuba's rule, `q = min(max_c(throughput) eta^2, 0.95)` applied to the whole path
//! throughput, caps `q` at 0.95 while the walk's throughput stays near 1 (albedo 0.99): the
//! survivors' weights then grow by `0.99 / 0.95` per event and long walks reach weights of
//! 100+ (the harness's `subsurface_like` notes). Here `q` is not capped below 1, so weights
//! cannot grow. The floor keeps a medium of very low albedo from killing nearly every
//! walker at its first event (survivors then weigh `A / Q_FLOOR < 1`).
//!
//! # Emission
//! In an emissive medium (`emission` = `j`, radiance per unit length) every step adds the
//! exact integral of what the medium emits along its segment, from the step's start to the
//! surface ahead, `j (1 - exp(-sigma_t d)) / sigma_t` per channel
//! ([`emitted_radiance`]), times the walk's weight at the step's start, to the ray's
//! [`ShadeGroups::emitted`] row: the step's radiance is that emission plus what the flight
//! estimates (in-scattered light at the event, or the radiance at the surface), so adding
//! the exact part is unbiased and costs no variance. It needs `d` for every step, so in an
//! emissive medium every step is traced to the surface ahead and no empty balls are kept
//! (no steps without rays): the walk costs one ray per event there. Walks that end inside
//! (roulette, depth limit) keep what they gathered before.
//!
//! # Sampler dimensions
//! A walk draws one aligned set of four dimensions from the path's sampler (the first
//! flight's channel and distance, the first phase sample), so thin media stay stratified
//! where it matters; the rest of the walk (hundreds of events in a dense medium, where no
//! sampler keeps its stratification) comes from a SplitMix64 stream seeded by the path's
//! sampler state, deterministic per pixel sample.

use risotto_engine::plugin::{answer_exits, Exits, IntegratorContext};

use super::emission::emission_along;
use super::HomogeneousMedium;
use crate::scatter_patterns::{hg_at, PointPattern};
use glam::{Vec2, Vec3};
use risotto_components::{Hits, Rays, Rgb, NO_HIT};
use risotto_engine::plugin::VolumeLightMis;
use risotto_engine::shade_groups::ShadeGroups;
use risotto_engine::stats::VolumeEvent;
use risotto_systems::medium::{
    channel_pdf, emitted_radiance, flights_frozen, flights_may_freeze_within, sample_free_flight,
    FreeFlight,
};
use risotto_systems::phase::PhaseFunction;
use risotto_systems::ray::{before_hit, coordinate_epsilon};
use risotto_systems::sampler::{PathSampler, SplitMix64};

/// The smallest survival probability of the walk's Russian roulette (see the module docs).
pub const Q_FLOOR: f32 = 0.05;

/// Scattering events after which a walk is abandoned: a guard against a walker trapped by a
/// boundary that leaks numerically, far beyond any real walk (a sphere of radius 1000 mean
/// free paths with albedo 1 takes about a million).
pub const MAX_WALK_EVENTS: u32 = 1 << 22;

/// The state of the live walkers, one row per walker (structure of arrays).
#[derive(Default)]
struct Walkers {
    /// Index of the walker's ray in the bundle.
    ray: Vec<u32>,
    origin: Vec<Vec3>,
    direction: Vec<Vec3>,
    tmin: Vec<f32>,
    tmax: Vec<f32>,
    weight: Vec<Rgb>,
    events: Vec<u32>,
    rng: Vec<SplitMix64>,
    /// The first flight's channel and distance numbers and the first phase sample, from the
    /// path's sampler (used while `events == 0`).
    first: Vec<[f32; 4]>,
    /// Centre and radius of a ball known to hold no surface (radius 0: none known): steps
    /// that end in it need no ray.
    anchor: Vec<Vec3>,
    radius: Vec<f32>,
}

impl Walkers {
    fn len(&self) -> usize {
        self.ray.len()
    }
    /// Keeps row `from` as row `to` (`to <= from`).
    fn keep(&mut self, from: usize, to: usize) {
        self.ray[to] = self.ray[from];
        self.origin[to] = self.origin[from];
        self.direction[to] = self.direction[from];
        self.tmin[to] = self.tmin[from];
        self.tmax[to] = self.tmax[from];
        self.weight[to] = self.weight[from];
        self.events[to] = self.events[from];
        self.rng[to] = self.rng[from].clone();
        self.first[to] = self.first[from];
        self.anchor[to] = self.anchor[from];
        self.radius[to] = self.radius[from];
    }
    fn truncate(&mut self, n: usize) {
        self.ray.truncate(n);
        self.origin.truncate(n);
        self.direction.truncate(n);
        self.tmin.truncate(n);
        self.tmax.truncate(n);
        self.weight.truncate(n);
        self.events.truncate(n);
        self.rng.truncate(n);
        self.first.truncate(n);
        self.anchor.truncate(n);
        self.radius.truncate(n);
    }
}

/// A random stream seeded by the path's sampler state without drawing from it, `salt`
/// telling apart the streams of different uses (0: the walk's). SplitMix64 mixes its state
/// on every draw, so neighbouring seeds give unrelated streams.
pub fn sampler_stream(s: &PathSampler, salt: u64) -> SplitMix64 {
    let key = ((s.seed as u64) << 32 | s.sample as u64)
        ^ (s.dimension as u64).wrapping_mul(0xD1B5_4A32_D192_ED03)
        ^ salt;
    SplitMix64(key)
}

/// A uniform number in `[0, 1)` from the top 24 of 32 random bits (every multiple of
/// 2^-24 reachable, as the samplers give).
#[inline]
fn unit(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// `sum_c b_c w_c / sum_c b_c`: the walk's albedo-corrected throughput `A` (module docs).
#[inline]
fn carried(b: Rgb, w: Rgb) -> f32 {
    let sum = b.r.max(0.0) + b.g.max(0.0) + b.b.max(0.0);
    if sum > 0.0 && sum.is_finite() {
        (b.r.max(0.0) * w.r + b.g.max(0.0) * w.g + b.b.max(0.0) * w.b) / sum
    } else {
        (w.r + w.g + w.b) / 3.0
    }
}

/// Walks every ray of `rays` (a bundle travelling in `medium`) to its exit and appends the
/// exits to `out`: the surface points (and misses) the walks' last segments reach, with the
/// walk's weight multiplied into their transmission, and the walked rays' last segments in
/// `out.walked` (see the module docs). Walkers killed by the roulette, the depth limit or the
/// event guard return nothing (the caller counts them absorbed). `samplers[i]` is ray `i`'s
/// sample source; each advances by four dimensions.
///
/// `light`: the medium as a light, whose samples the first step of each walk is weighed
/// against ([`crate::media::emission`]; later steps follow scattering events, which
/// sample no light, and keep the exact emission).
pub fn walk_bundle(
    medium: &HomogeneousMedium,
    light: Option<&VolumeLightMis<'_>>,
    rays: &Rays,
    samplers: &mut [PathSampler],
    ictx: &mut dyn IntegratorContext,
    out: &mut ShadeGroups,
) {
    let (sigma_t, sigma_s) = (medium.sigma_t, medium.sigma_s);
    let uniform = Uniform {
        sigma_t,
        sigma_s,
        grey: is_grey(sigma_t, sigma_s),
    };
    walk_bundle_in(medium, uniform, light, rays, samplers, ictx, out);
}

/// [`walk_bundle`] where each ray walks in a medium of its own extinction and scattering
/// coefficients `per_ray[i] = (sigma_t, sigma_s)` (a `subsurface` material whose albedo or
/// mean free path is a pattern, read at the ray's entry point); the rest of `medium` (phase
/// function, patterns, emission) is shared.
pub fn walk_bundle_per_ray(
    medium: &HomogeneousMedium,
    per_ray: &[(Rgb, Rgb)],
    rays: &Rays,
    samplers: &mut [PathSampler],
    ictx: &mut dyn IntegratorContext,
    out: &mut ShadeGroups,
) {
    assert_eq!(per_ray.len(), rays.len(), "one medium per ray");
    walk_bundle_in(medium, PerRay(per_ray), None, rays, samplers, ictx, out);
}

fn walk_bundle_in<C: Coefficients>(
    medium: &HomogeneousMedium,
    coefficients: C,
    light: Option<&VolumeLightMis<'_>>,
    rays: &Rays,
    samplers: &mut [PathSampler],
    ictx: &mut dyn IntegratorContext,
    out: &mut ShadeGroups,
) {
    let n = rays.len();
    if n == 0 {
        return;
    }
    let mut walk = Walk {
        coefficients,
        phase: medium.phase,
        max_depth: ictx.max_depth(),
        albedo: medium.albedo_pattern.as_deref().map(PointPattern::new),
        g: medium.g_pattern.as_deref().map(PointPattern::new),
        frozen: 0,
        largest_coordinate: {
            let (lo, hi) = ictx.scene_bounds();
            lo.abs().max(hi.abs()).max_element()
        },
    };
    // An emissive medium's exact segment integrals need every step's full segment: each
    // step is traced to the surface ahead, without empty balls (module docs, "Emission").
    let emits = medium.emits();
    let mut emitted = vec![Rgb::BLACK; if emits { n } else { 0 }];
    let mut w = Walkers::default();
    for (i, s) in samplers.iter_mut().enumerate() {
        let first = s.next_4d();
        w.ray.push(i as u32);
        w.origin.push(rays.origin[i]);
        w.direction.push(rays.direction[i]);
        w.tmin.push(rays.tmin[i]);
        w.tmax.push(rays.tmax[i]);
        w.weight.push(Rgb::WHITE);
        w.events.push(0);
        w.rng.push(sampler_stream(s, 0));
        w.first.push(first);
        w.anchor.push(rays.origin[i]);
        w.radius.push(0.0);
    }
    let mut exits = Exits::default();
    let mut hits = Hits::default();
    let (mut flights, mut query) = (Vec::new(), Vec::new());
    let (mut traced, mut free, mut passes) = (0usize, 0usize, 0usize);
    while w.len() > 0 {
        // Each walker takes the steps that end inside its empty ball without a ray (the
        // segment from a point of the ball to another cannot cross a surface), until one
        // would leave the ball: that flight is traced below.
        //
        // The flight's distance does not depend on where the segment ends (only whether it
        // scatters does), so the trace needs the surfaces only up to the sampled distance,
        // plus a margin to see a boundary just beyond it for the clamp below.
        flights.clear();
        query.clear();
        let mut live = 0;
        for j in 0..w.len() {
            let r = w.ray[j] as usize;
            let mut alive = true;
            loop {
                let (u_channel, u_distance) = if w.events[j] == 0 {
                    (w.first[j][0], w.first[j][1])
                } else {
                    let u = w.rng[j].next_u64();
                    (unit(u as u32), unit((u >> 32) as u32))
                };
                let pdf = if walk.coefficients.grey(r) {
                    [1.0 / 3.0; 3]
                } else {
                    channel_pdf(rays.throughput[r] * w.weight[j])
                };
                let f = walk.flight(r, pdf, u_channel, u_distance, w.tmax[j]);
                if f.scattered && w.radius[j] > 0.0 {
                    let p = w.origin[j] + w.direction[j] * f.t;
                    if (p - w.anchor[j]).length_squared() < w.radius[j] * w.radius[j] {
                        free += 1;
                        match walk.event(&mut w, j, rays, r, f.weight, p) {
                            true => continue,
                            false => {
                                alive = false;
                                break;
                            }
                        }
                    }
                }
                let end = if f.scattered && !emits {
                    // How far past the event the segment is traced: a gate with no surface
                    // yet, in `coordinate_epsilon`s of the event.
                    let margin = 4000.0 * coordinate_epsilon(w.origin[j] + w.direction[j] * f.t);
                    (f.t + margin).min(w.tmax[j])
                } else {
                    w.tmax[j]
                };
                flights.push((f, pdf, u_channel, u_distance));
                query.push(end);
                break;
            }
            if alive {
                if live != j {
                    w.keep(j, live);
                }
                live += 1;
            }
        }
        w.truncate(live);
        let m = w.len();
        if m == 0 {
            break;
        }
        ictx.closest_hits(&w.origin, &w.direction, &w.tmin, &query, &mut hits);
        let (t_hit, prim, b1, b2) = (&hits.t, &hits.prim, &hits.b1, &hits.b2);
        if emits {
            // The emission of every step's segment, to the surface ahead (nothing for a
            // segment with nothing ahead: it has left the medium), at the walk's weight
            // before the step.
            for j in 0..m {
                let seg = if prim[j] != NO_HIT {
                    t_hit[j]
                } else {
                    f32::INFINITY
                };
                let r = w.ray[j] as usize;
                let e = if w.events[j] == 0 {
                    // The ray's own first segment: weighed against the light samples of the
                    // vertex it left, if any.
                    emission_along(medium, rays, r, seg, light, &samplers[r])
                } else {
                    emitted_radiance(walk.coefficients.at(r).0, medium.emission, seg)
                };
                emitted[r] += w.weight[j] * e;
            }
            ictx.count_volume_events(VolumeEvent::Emission, m);
        }
        let mut live = 0;
        for j in 0..m {
            let r = w.ray[j] as usize;
            let (o, d) = (w.origin[j], w.direction[j]);
            let hit = prim[j] != NO_HIT;
            let (mut f, pdf, u_channel, u_distance) = flights[j];
            if hit && (!f.scattered || t_hit[j] <= f.t) {
                // A surface before the sampled distance: the flight passes to it, with the
                // pass weight of that segment (the same numbers, so the same channel and
                // distance, now beyond the segment's end).
                f = walk.flight(r, pdf, u_channel, u_distance, t_hit[j]);
            }
            if !f.scattered {
                passes += 1;
                exits.ray.push(r as u32);
                exits.origin.push(o);
                exits.direction.push(d);
                exits.tmin.push(w.tmin[j]);
                exits.tmax.push(w.tmax[j]);
                exits.weight.push(w.weight[j] * f.weight);
                exits.events.push(w.events[j]);
                continue;
            }
            traced += 1;
            // Keep the event strictly inside: a point within the spawn offset of a boundary
            // just beyond it (or of the segment's start, for a segment leaving the
            // boundary) could round to the far side, and the walk's next segment would not
            // see the boundary again (the same clamp as the homogeneous interior's).
            let mut t = f.t;
            if hit {
                let seg = t_hit[j];
                let s = ictx.surface_at(prim[j], o, d, seg, b1[j], b2[j]);
                let end = before_hit(seg, s.offset(), s.ng, o, d);
                t = t.min(if end < w.tmin[j] {
                    0.5 * (w.tmin[j] + seg)
                } else {
                    end
                });
                t = t.max(w.tmin[j].min(0.5 * seg));
            } else {
                t = t.max(w.tmin[j]);
            }
            let p = o + d * t;
            if !walk.event(&mut w, j, rays, r, f.weight, p) {
                continue;
            }
            // A new empty ball around the event: the distance to the nearest surface, less
            // a relative margin for its rounding (`coordinate_epsilon`s of the event: the
            // nearest surface's bound is not known here), so that no free step ends within
            // rounding of a surface.
            if !emits {
                let c = ictx.clearance(p, f32::INFINITY);
                w.anchor[j] = p;
                w.radius[j] = (c * (1.0 - 1e-3) - 1000.0 * coordinate_epsilon(p)).max(0.0);
            }
            if live != j {
                w.keep(j, live);
            }
            live += 1;
        }
        w.truncate(live);
    }
    ictx.count_volume_events(VolumeEvent::Scatter, traced + free);
    ictx.count_volume_events(VolumeEvent::Pass, passes);
    ictx.count_volume_events(VolumeEvent::Frozen, walk.frozen);
    let evals =
        walk.albedo.as_ref().map_or(0, |a| a.evals) + walk.g.as_ref().map_or(0, |g| g.evals);
    ictx.count_volume_pattern_evals(evals);
    for (i, &e) in emitted.iter().enumerate() {
        out.emitted.push(i as u32, e);
    }
    answer_exits(rays, &exits, ictx, out);
}

/// Whether `(sigma_t, sigma_s)` are the same in every channel.
#[inline]
fn is_grey(st: Rgb, ss: Rgb) -> bool {
    st.r == st.g && st.g == st.b && ss.r == ss.g && ss.g == ss.b
}

/// Where a bundle's walks take their `(sigma_t, sigma_s)` from (a type parameter, so the
/// common uniform walk pays nothing for the per-ray one).
trait Coefficients {
    /// Ray `r`'s `(sigma_t, sigma_s)`.
    fn at(&self, r: usize) -> (Rgb, Rgb);
    /// Whether ray `r`'s medium is alike in every channel (channel probabilities then do
    /// not matter).
    fn grey(&self, r: usize) -> bool;
}

/// One medium for every ray.
struct Uniform {
    sigma_t: Rgb,
    sigma_s: Rgb,
    grey: bool,
}

impl Coefficients for Uniform {
    #[inline]
    fn at(&self, _r: usize) -> (Rgb, Rgb) {
        (self.sigma_t, self.sigma_s)
    }
    #[inline]
    fn grey(&self, _r: usize) -> bool {
        self.grey
    }
}

/// A medium per ray.
struct PerRay<'a>(&'a [(Rgb, Rgb)]);

impl Coefficients for PerRay<'_> {
    #[inline]
    fn at(&self, r: usize) -> (Rgb, Rgb) {
        self.0[r]
    }
    #[inline]
    fn grey(&self, r: usize) -> bool {
        is_grey(self.0[r].0, self.0[r].1)
    }
}

/// The medium and limits of one bundle's walks.
struct Walk<'g, C> {
    coefficients: C,
    phase: PhaseFunction,
    max_depth: u32,
    /// The albedo pattern, read at each event (`sigma_s` is then `sigma_t`,
    /// [`crate::scatter_patterns`]).
    albedo: Option<PointPattern<'g>>,
    /// The HG `g` pattern, read at each event (`phase` is then HG).
    g: Option<PointPattern<'g>>,
    /// Walks ended at a point their flights could not move from
    /// ([`flights_frozen`](risotto_systems::medium::flights_frozen)).
    frozen: usize,
    /// The largest coordinate magnitude in the scene's bounds, where every walk stays: the
    /// per-event freezing test runs only for media that may freeze there.
    largest_coordinate: f32,
}

impl<C: Coefficients> Walk<'_, C> {
    /// A free flight of ray `r` on a segment of length `tmax` ([`sample_free_flight`]).
    #[inline]
    fn flight(
        &self,
        r: usize,
        pdf: [f32; 3],
        u_channel: f32,
        u_distance: f32,
        tmax: f32,
    ) -> FreeFlight {
        let (st, ss) = self.coefficients.at(r);
        sample_free_flight(st, ss, pdf, u_channel, u_distance, tmax)
    }

    /// Walker `j` (of ray `r`) scatters at `p` with the flight weight `flight_weight`: the
    /// depth limit, the roulette and the phase sample. Writes the next segment into the
    /// walker's row and returns true, or false when the walk ends here.
    #[inline]
    fn event(
        &mut self,
        w: &mut Walkers,
        j: usize,
        rays: &Rays,
        r: usize,
        flight_weight: Rgb,
        p: Vec3,
    ) -> bool {
        let first = w.events[j] == 0;
        let events = w.events[j] + 1;
        // The next segment from this event is segment depth + events + 1 of the path:
        // beyond max_depth nothing it finds counts, so the walk ends here.
        if rays.depth[r] as u32 + events + 1 > self.max_depth || events > MAX_WALK_EVENTS {
            return false;
        }
        let sigma_t = self.coefficients.at(r).0;
        if flights_may_freeze_within(sigma_t, self.largest_coordinate) && flights_frozen(sigma_t, p)
        {
            // The walk could not move from here, nor gather anything: it ends.
            self.frozen += 1;
            return false;
        }
        // Russian roulette on the albedo-corrected throughput (module docs). A walk that
        // carries nothing (albedo 0) ends here rather than walking on with weight 0.
        let mut weight = w.weight[j] * flight_weight;
        if let Some(albedo) = &mut self.albedo {
            weight *= albedo.at(p);
        }
        if weight.is_black() {
            return false;
        }
        let q = carried(rays.throughput[r], weight).clamp(Q_FLOOR, 1.0);
        let u = w.rng[j].next_u64();
        if q < 1.0 {
            if unit(u as u32) >= q {
                return false;
            }
            weight *= 1.0 / q;
        }
        let u_lobe = unit((u >> 32) as u32);
        let u_phase = if first {
            Vec2::new(w.first[j][2], w.first[j][3])
        } else {
            let v = w.rng[j].next_u64();
            Vec2::new(unit(v as u32), unit((v >> 32) as u32))
        };
        let phase = match &mut self.g {
            Some(g) => hg_at(g.at(p)),
            None => self.phase,
        };
        let (wi, pdf) = phase.sample(-w.direction[j], u_phase, u_lobe);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return false;
        }
        w.origin[j] = p;
        w.direction[j] = wi;
        w.tmin[j] = 0.0;
        w.tmax[j] = f32::INFINITY;
        w.weight[j] = weight;
        w.events[j] = events;
        true
    }
}
