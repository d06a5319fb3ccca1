//! A random-walk subsurface interior written outside the engine, with the public plug-in API
//! only, registered as the scene-file material type `walked_glass`.
//!
//! Run with `cargo run --release --example random_walk_subsurface`; it renders the Mitsuba
//! suite's `subsurface_like` scene (`scenes/mitsuba-suite/subsurface_like.toml`) with its
//! translucent ball made of `walked_glass` and writes `random_walk_subsurface.exr` and `.png`
//! to the system's temporary directory. `tests/random_walk_example.rs` checks that the image
//! agrees, within its noise, with the one the built-in walk (`dielectric` + `homogeneous`
//! interior) renders.
//!
//! # How this maps onto the RIS volume-integrator contract
//!
//! The seed document ("Writing Volume Integrators", sections "Multiple Scattering" and
//! "Subsurface") describes an integrator that traces its own rays inside the volume and
//! returns only hits; risotto's plug-in API (`risotto::engine::plugin`) has the same shape,
//! batch-oriented:
//!
//! | RIS | risotto |
//! |---|---|
//! | `RixBxdfFactory` | [`BxdfFactory`] ([`WalkedGlass`] here) |
//! | `GetInstanceHints`: `k_ComputesInterior \| k_InteriorTransmission` | `COMPUTES_INTERIOR \| INTERIOR_TRANSMISSION \| INTERIOR_SCATTERS \| TRANSMITS`, what the built-in `dielectric` + `homogeneous` material says |
//! | `BeginScatter` -> `RixBxdf` | [`BxdfFactory::begin_scatter`] -> the engine's public `DielectricBxdf` |
//! | `BeginInterior` -> `RixVolumeIntegrator` | [`BxdfFactory::begin_interior`] -> [`WalkInterior`], in the batch arena |
//! | `GetNearestHits` of a volume | [`VolumeIntegrator::nearest_hits`]: the whole walk runs inside it |
//! | the walker's probe rays (`RixIntegratorContext::GetNearestHits` without shading) | [`IntegratorContext::closest_hits`] (bare rays) and [`IntegratorContext::surface_at`] (the boundary's point, normal and error bound) |
//! | returning the exit as a hit, `transmission` = the walk's weight | [`answer_exits`] over an [`Exits`] table: the walk's last segment traced again through the context, the weight multiplied into `transmission` (points) and `miss_transmission` (misses) |
//! | (no RIS equivalent) the walk's last segment and event count | also [`answer_exits`], into [`ShadeGroups::walked`]: the path tracer continues from the last event and counts the events as bounces |
//! | `GetTransmission(maxDist)` | [`VolumeIntegrator::transmission`]: `exp(-sigma_t d)` |
//! | `maxPathLength` | [`IntegratorContext::max_depth`] bounds the events |
//! | statistics | [`IntegratorContext::count_volume_events`] |
//!
//! # The walk
//!
//! Each ray handed to `nearest_hits` travels inside the ball. Its walker repeats, until it
//! leaves or dies:
//!
//! 1. **Trace** the segment ahead to the nearest surface `d_hit` (`closest_hits`).
//! 2. **Free flight.** Sample a distance from `pdf(t) = sigma_t exp(-sigma_t t)` by inverting
//!    the CDF, `t = -ln(1 - u) / sigma_t` (`risotto::systems::medium::sample_free_flight`;
//!    in a chromatic medium one channel `c` is picked with probability `p_c` proportional
//!    to the path's throughput and the mixture `sum_c p_c sigma_t,c exp(-sigma_t,c t)` is
//!    the pdf, one-sample spectral MIS). If `t >= d_hit` the walker passes to the surface,
//!    with probability `exp(-sigma_t d_hit)`, which is exactly the transmittance: the pass
//!    weight `T / P(pass)` is 1 (grey). Else it scatters at `t`, with weight
//!    `sigma_s T(t) / pdf(t) = sigma_s / sigma_t = albedo` (grey): **the walk's weight is
//!    multiplied by the albedo at every event**.
//! 3. **Russian roulette** at each event: the walker survives with probability
//!    `q = clamp(A, 0.05, 1)` where `A = sum_c b_c w_c / sum_c b_c` is its weight `w`
//!    averaged over the throughput `b` the ray brought in, and survivors divide `w` by `q`.
//!    Unbiased, since `E[w'] = q (w / q) + (1 - q) 0 = w` (Arvo and Kirk 1990); in a grey
//!    medium it is analog absorption (death with probability `1 - albedo`, weight stays 1).
//! 4. **Scatter**: a new direction from the isotropic phase function
//!    (`risotto::systems::phase::isotropic_sample`, `p = 1 / 4pi` sampled exactly, so the
//!    weight `p / pdf` is 1).
//!
//! A walker that reaches the boundary is answered to the global integrator as an ordinary
//! surface hit: `ictx.nearest_hits` on the walk's last segment returns the boundary point,
//! whose `transmission` gets the walk's weight; the path tracer then shades it with the
//! dielectric (which refracts the walker out, or reflects it back in, when this integrator
//! is called again). Walkers killed by the roulette or by the depth bound return nothing
//! (absorbed).
//!
//! Simpler than the built-in walk (`risotto::builtins::media::random_walk`): every step traces a
//! ray (the built-in skips the ray for steps inside a ball known to be empty of surfaces,
//! [`IntegratorContext::clearance`]), the phase function is isotropic only, there are no
//! albedo patterns and no emission, and there is no test for media so dense that float
//! spacing freezes the walk (a generous event cap ends such walks instead).
//!
//! # The material
//!
//! ```toml
//! [materials.translucent]
//! type = "walked_glass"
//! ior = 1.33        # of the interior, default 1.5
//! sigma_t = 20.0    # extinction per world unit, number or [r, g, b], each >= 0 and finite
//! albedo = 0.99     # single-scattering albedo, number or [r, g, b], each in [0, 1]
//! ```

use risotto::builtins::builtin::DielectricBxdf;
use risotto::bumpalo::Bump;
use risotto::components::{Hits, LobeSampled, Rays, Rgb, NO_HIT};
use risotto::engine::output::{write_exr, write_png};
use risotto::engine::plugin::{
    answer_exits, Bxdf, BxdfFactory, Exits, InstanceHints, IntegratorContext, Segments,
    ShadeGroups, ShadingContext, ShadingMode, VolumeEvent, VolumeIntegrator, VolumeServices,
};
use risotto::engine::render::{render, RenderOptions, RenderOutput};
use risotto::glam::{Vec2, Vec3};
use risotto::loader::load::{scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::{parse_scene, MaterialParams, SceneError};
use risotto::systems::medium::{channel_pdf, sample_free_flight, transmittance};
use risotto::systems::phase::isotropic_sample;
use risotto::systems::ray::before_hit;
use risotto::systems::sampler::{PathSampler, SplitMix64};
use std::path::Path;

/// The smallest survival probability of the roulette (a medium of low albedo would
/// otherwise kill almost every walker at its first event).
pub const Q_FLOOR: f32 = 0.05;

/// Events after which a walk is abandoned: a guard against a walker trapped by a boundary
/// that leaks numerically, far beyond a real walk in any sensible medium.
pub const MAX_EVENTS: u32 = 1 << 20;

/// The factory of the `walked_glass` material type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WalkedGlass {
    /// Index of refraction of the interior.
    pub ior: f32,
    /// Extinction coefficient per channel (per world unit).
    pub sigma_t: Rgb,
    /// Single-scattering albedo per channel.
    pub albedo: Rgb,
}

impl WalkedGlass {
    /// The factory for a material table of a scene file (see the module docs for the keys).
    pub fn from_params(p: &MaterialParams) -> Result<Self, SceneError> {
        p.deny_unknown(&["ior", "sigma_t", "albedo"])?;
        let ior = p.f32_where("ior", Some(1.5), "> 0 and finite", |v| {
            v > 0.0 && v.is_finite()
        })?;
        let sigma_t = p.rgb_where("sigma_t", None, "every channel >= 0 and finite", |c| {
            c.min_channel() >= 0.0 && c.is_finite()
        })?;
        let albedo = p.rgb_where("albedo", None, "every channel in [0, 1]", |c| {
            c.min_channel() >= 0.0 && c.max_channel() <= 1.0
        })?;
        Ok(WalkedGlass {
            ior,
            sigma_t,
            albedo,
        })
    }
}

impl BxdfFactory for WalkedGlass {
    fn instance_hints(&self) -> InstanceHints {
        // As the built-in `dielectric` surface (no cheap shadows) with a non-emissive
        // `homogeneous` interior: the same features, so the scheduler runs the same stages.
        InstanceHints::TRANSMITS
            | InstanceHints::COMPUTES_INTERIOR
            | InstanceHints::INTERIOR_TRANSMISSION
            | InstanceHints::INTERIOR_SCATTERS
    }

    fn begin_scatter<'a>(
        &'a self,
        _ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a) {
        // Only surface points are ever shaded: the walk returns no points inside the volume
        // (`ShadingMode::VolumeScatter`), it scatters there itself.
        arena.alloc(DielectricBxdf {
            ior: self.ior,
            tint: Rgb::WHITE,
        })
    }

    fn begin_interior<'a>(
        &'a self,
        _ctx: &'a ShadingContext<'a>,
        _mode: ShadingMode,
        arena: &'a Bump,
    ) -> Option<&'a mut (dyn VolumeIntegrator + 'a)> {
        Some(arena.alloc(WalkInterior {
            sigma_t: self.sigma_t,
            sigma_s: self.sigma_t * self.albedo,
        }))
    }

    fn ior(&self) -> f32 {
        self.ior
    }
}

/// The interior closure: a homogeneous medium walked to its boundary. Plain data, as
/// closures in the arena must be.
#[derive(Clone, Copy, Debug)]
pub struct WalkInterior {
    /// Extinction coefficient per channel.
    pub sigma_t: Rgb,
    /// Scattering coefficient per channel (`albedo * sigma_t`).
    pub sigma_s: Rgb,
}

/// One live walker.
struct Walker {
    /// Its ray in the table `nearest_hits` answers.
    ray: u32,
    origin: Vec3,
    direction: Vec3,
    tmin: f32,
    tmax: f32,
    weight: Rgb,
    events: u32,
    /// The first flight's two numbers and the first phase sample, from the path's sampler;
    /// later numbers come from `rng`.
    first: [f32; 4],
    rng: SplitMix64,
}

impl Walker {
    /// The next two uniform numbers of the walk: the path sampler's before the first event,
    /// the walker's own stream after.
    fn next_2d(&mut self, which: usize) -> Vec2 {
        if self.events == 0 {
            Vec2::new(self.first[which], self.first[which + 1])
        } else {
            self.rng.vec2()
        }
    }
}

/// The walk's weight averaged over the throughput the ray brought in (the survival
/// probability of the roulette before clamping; see the module docs).
fn carried(throughput: Rgb, w: Rgb) -> f32 {
    let b = throughput.map(|c| c.max(0.0));
    let sum = b.r + b.g + b.b;
    if sum > 0.0 && sum.is_finite() {
        (b.r * w.r + b.g * w.g + b.b * w.b) / sum
    } else {
        w.average()
    }
}

impl VolumeIntegrator for WalkInterior {
    fn nearest_hits(
        &mut self,
        rays: &Rays,
        samplers: &mut [PathSampler],
        _lobes_wanted: LobeSampled,
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
        let ictx = services.ictx;
        let max_depth = ictx.max_depth();
        let mut walkers: Vec<Walker> = samplers
            .iter_mut()
            .enumerate()
            .map(|(i, s)| {
                let first = s.next_4d();
                // A stream of this path sample's own (the sampler's state after the draw);
                // the sampler keeps no stratification over hundreds of events anyway.
                let key = ((s.seed as u64) << 32 | s.sample as u64)
                    ^ (s.dimension as u64).wrapping_mul(0x9E6C_63D0_676A_9A99)
                    ^ 0x5EED_3A1C;
                Walker {
                    ray: i as u32,
                    origin: rays.origin[i],
                    direction: rays.direction[i],
                    tmin: rays.tmin[i],
                    tmax: rays.tmax[i],
                    weight: Rgb::WHITE,
                    events: 0,
                    first,
                    rng: SplitMix64(key),
                }
            })
            .collect();
        let mut exits: Vec<Walker> = Vec::new();
        let (mut scattered, mut absorbed) = (0usize, 0usize);
        let mut hits = Hits::default();
        let (mut o, mut d, mut tmin, mut tmax) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        while !walkers.is_empty() {
            // 1. The segment ahead of every live walker, to the nearest surface.
            o.clear();
            d.clear();
            tmin.clear();
            tmax.clear();
            for w in &walkers {
                o.push(w.origin);
                d.push(w.direction);
                tmin.push(w.tmin);
                tmax.push(w.tmax);
            }
            ictx.closest_hits(&o, &d, &tmin, &tmax, &mut hits);
            let mut live = Vec::with_capacity(walkers.len());
            for (j, mut w) in walkers.drain(..).enumerate() {
                let r = w.ray as usize;
                if hits.prim[j] == NO_HIT {
                    // Nothing ahead: the ray has already left the closed boundary (a grazing
                    // entry whose chord is shorter than the spawn offset). It escapes.
                    exits.push(w);
                    continue;
                }
                let seg = hits.t[j];
                // 2. A free flight on the segment.
                let u = w.next_2d(0);
                let pdf = channel_pdf(rays.throughput[r] * w.weight);
                let f = sample_free_flight(self.sigma_t, self.sigma_s, pdf, u.x, u.y, seg);
                if !f.scattered {
                    w.weight *= f.weight;
                    exits.push(w);
                    continue;
                }
                scattered += 1;
                // The event strictly inside: a point within rounding of the boundary could
                // land on its far side, and the next segment would never see it again.
                let s = ictx.surface_at(
                    hits.prim[j],
                    w.origin,
                    w.direction,
                    seg,
                    hits.b1[j],
                    hits.b2[j],
                );
                let end = before_hit(seg, s.offset(), s.ng, w.origin, w.direction);
                let end = if end < w.tmin {
                    0.5 * (w.tmin + seg)
                } else {
                    end
                };
                let t = f.t.min(end).max(w.tmin.min(0.5 * seg));
                let p = w.origin + w.direction * t;
                let u_phase = w.next_2d(2);
                w.events += 1;
                // The path's segment after this event would be number depth + events + 1.
                if rays.depth[r] as u32 + w.events + 1 > max_depth || w.events > MAX_EVENTS {
                    absorbed += 1;
                    continue;
                }
                // 3. Russian roulette on the weight times the albedo.
                w.weight *= f.weight;
                let q = carried(rays.throughput[r], w.weight).clamp(Q_FLOOR, 1.0);
                if w.weight.is_black() || (q < 1.0 && w.rng.f32() >= q) {
                    absorbed += 1;
                    continue;
                }
                w.weight *= 1.0 / q;
                // 4. Isotropic scattering.
                let (wi, _pdf) = isotropic_sample(u_phase);
                w.origin = p;
                w.direction = wi;
                w.tmin = 0.0;
                w.tmax = f32::INFINITY;
                live.push(w);
            }
            walkers = live;
        }
        ictx.count_volume_events(VolumeEvent::Scatter, scattered);
        ictx.count_volume_events(VolumeEvent::Absorbed, absorbed);
        ictx.count_volume_events(VolumeEvent::Pass, exits.len());
        // The contract's answer for walks a volume integrator runs itself: each exit's last
        // segment traced again (the boundary point, an ordinary Scatter point the path
        // tracer shades with the dielectric, or a miss), the walk's weight multiplied into
        // its transmission, the events reported so that they count as bounces.
        let mut table = Exits::default();
        for w in &exits {
            table.ray.push(w.ray);
            table.origin.push(w.origin);
            table.direction.push(w.direction);
            table.tmin.push(w.tmin);
            table.tmax.push(w.tmax);
            table.weight.push(w.weight);
            table.events.push(w.events);
        }
        answer_exits(rays, &table, ictx, out);
    }

    fn transmission(
        &self,
        segments: &Segments,
        _samplers: &mut [PathSampler],
        _ictx: &dyn IntegratorContext,
        trans: &mut [Rgb],
        emission: &mut [Rgb],
    ) {
        // The straight-line transmittance. The ball's dielectric blocks shadow rays, so in
        // the suite's scene no shadow segment ever runs inside it.
        for i in 0..segments.len() {
            trans[i] = transmittance(self.sigma_t, segments.length[i]);
        }
        emission.fill(Rgb::BLACK);
    }

    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

/// The built-in material types plus `walked_glass`.
pub fn registry() -> MaterialRegistry {
    let mut registry = MaterialRegistry::with_builtins();
    registry.register("walked_glass", |p| {
        Ok(Box::new(WalkedGlass::from_params(p)?))
    });
    registry
}

/// The Mitsuba suite's `subsurface_like` scene: a smooth dielectric ball (ior 1.33) filled
/// with a dense isotropic medium (`sigma_t` 20, albedo 0.99) under an area light and a grey
/// sky, written with the built-in `homogeneous` interior (which walks).
pub const SUBSURFACE_LIKE: &str = include_str!("../scenes/mitsuba-suite/subsurface_like.toml");

/// The built-in ball's material lines of [`SUBSURFACE_LIKE`].
const BUILTIN_BALL: &str = "type = \"dielectric\"\nior = 1.33       # int_ior 1.33, ext_ior 1.0 (vacuum outside)\ninterior = { type = \"homogeneous\", sigma_t = 20.0, albedo = 0.99, phase = { type = \"isotropic\" } }\n";

/// `text` ([`SUBSURFACE_LIKE`] or a variant) with the ball made of `walked_glass` of the
/// same ior and `sigma_t`, and single-scattering albedo `albedo`.
///
/// # Panics
/// When `text` does not contain the suite scene's ball material.
pub fn walked_glass_scene(text: &str, albedo: f32) -> String {
    assert!(
        text.contains(BUILTIN_BALL),
        "the scene's ball material changed"
    );
    let ours =
        format!("type = \"walked_glass\"\nior = 1.33\nsigma_t = 20.0\nalbedo = {albedo:?}\n");
    text.replace(BUILTIN_BALL, &ours)
}

/// Parses `text` (reported as `name` in messages), builds it with [`registry`] and renders it.
pub fn render_text(text: &str, name: &str) -> Result<RenderOutput, Box<dyn std::error::Error>> {
    let desc = parse_scene(text, Path::new(name))?;
    let scene = scene_from_desc(desc, &registry())?;
    let compiled = scene.compile()?;
    Ok(render(&compiled, &RenderOptions::default(), &|_| {})?)
}

#[allow(
    dead_code,
    reason = "the test that includes this file calls the other items"
)]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    // The suite's own settings (256 x 256, 64 spp); the Mitsuba reference's mean is 0.5126.
    let text = walked_glass_scene(SUBSURFACE_LIKE, 0.99);
    let out = render_text(&text, "subsurface_like_walked.toml")?;
    let dir = std::env::temp_dir();
    let exr = dir.join("random_walk_subsurface.exr");
    let png = dir.join("random_walk_subsurface.png");
    write_exr(&exr, &out.film_output(false))?;
    write_png(&png, &out.beauty, 0.0)?;
    let m = out.beauty.mean();
    let events = out.stats.counters.volume_events[VolumeEvent::Scatter as usize];
    println!(
        "walked_glass: {}x{} px, mean RGB ({:.4}, {:.4}, {:.4}), {} scattering events, {:.2} s",
        out.beauty.width, out.beauty.height, m[0], m[1], m[2], events, out.stats.wall_seconds
    );
    println!("wrote {} and {}", exr.display(), png.display());
    Ok(())
}
