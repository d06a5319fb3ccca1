//! Replaying one camera sample: the path of pixel `(x, y)`'s sample `sample`, re-run alone
//! and single-threaded with the path-trace recorder on (`risotto render SCENE --replay
//! X,Y,SAMPLE`), so a user can see where a NaN (or a firefly) came from.
//!
//! The path is the render's own: a path's random numbers depend only on the render seed, its
//! pixel, its sample index and the sampler dimension (the pixel seed and sample address are
//! made as [`render_tile`](crate::integrator::render_tile) makes them), never on which other
//! paths share its batch, so the replayed path is the one the full render splatted (bit for
//! bit: `tests/nan_provenance.rs` compares it with a one-sample `--crop`/`--samples` render of
//! the pixel). Nothing is written to the film or to disk.
//!
//! ```no_run
//! # fn demo(scene: &risotto_engine::scene::CompiledScene) {
//! use risotto_engine::render::RenderOptions;
//! let replay = risotto_engine::replay::replay(scene, &RenderOptions::default(), 9, 7, 2)
//!     .expect("pixel and sample inside the render");
//! println!("{replay}");
//! for v in &replay.trace.vertices {
//!     if !v.non_finite.is_empty() {
//!         println!("depth {}: {:?}", v.depth, v.non_finite);
//!     }
//! }
//! # }
//! ```

use crate::integrator::{Integrator, PathBatch};
use crate::path_record::{PathTrace, TraceVertex, VertexEvent};
use crate::path_tracer::queues::Queues;
use crate::path_tracer::PathTracer;
use crate::render::{name_non_finite_cases, RenderError, RenderOptions};
use crate::scene::CompiledScene;
use crate::stats::{RenderStats, SystemStats};
use bumpalo::Bump;
use glam::Vec3;
use risotto_components::{LobeSampled, Rgb};
use risotto_systems::sampler::pixel_seed;
use std::fmt;

/// One replayed camera sample.
#[derive(Clone, Debug)]
pub struct Replay {
    /// Pixel column.
    pub x: u32,
    /// Pixel row.
    pub y: u32,
    /// Sample index within the pixel.
    pub sample: u32,
    /// The render seed.
    pub seed: u64,
    /// What the path did, vertex by vertex.
    pub trace: PathTrace,
    /// The path's stats (its non-finite counts and case, terminations, rays).
    pub stats: RenderStats,
}

impl Replay {
    /// The path's radiance (what the render splatted, unless it is not finite).
    pub fn radiance(&self) -> Rgb {
        self.trace.radiance
    }

    /// The first vertex at which something was not finite: a stage counted a non-finite
    /// value, or the throughput or radiance stopped being finite.
    pub fn first_non_finite(&self) -> Option<&TraceVertex> {
        self.trace.vertices.iter().find(|v| went_non_finite(v))
    }
}

/// Whether something became non-finite at `v`.
fn went_non_finite(v: &TraceVertex) -> bool {
    !v.non_finite.is_empty()
        || !v.radiance.is_finite()
        || v.throughput_out.is_some_and(|t| !t.is_finite())
}

/// Re-runs sample `sample` of pixel `(x, y)` of `scene` alone, single-threaded, with the
/// path tracer's recorder on. `options` supplies the techniques (lighting, sampler, volume
/// techniques); its threads, batch size, tiles, crop and sample range are not used.
///
/// # Errors
/// [`RenderError::Replay`] when the pixel is outside the image or the sample index is not
/// below the scene's samples per pixel.
pub fn replay(
    scene: &CompiledScene,
    options: &RenderOptions,
    x: u32,
    y: u32,
    sample: u32,
) -> Result<Replay, RenderError> {
    let (w, h, spp) = (scene.camera.width, scene.camera.height, scene.settings.spp);
    let err = |reason: String| RenderError::Replay {
        x,
        y,
        sample,
        reason,
    };
    if x >= w {
        return Err(err(format!(
            "x = {x} is outside the {w}x{h} image (columns 0 to {})",
            w.saturating_sub(1)
        )));
    }
    if y >= h {
        return Err(err(format!(
            "y = {y} is outside the {w}x{h} image (rows 0 to {})",
            h.saturating_sub(1)
        )));
    }
    if sample >= spp {
        return Err(err(format!(
            "sample {sample} is not below the scene's {spp} samples per pixel"
        )));
    }
    let integrator = options.integrator.unwrap_or(scene.settings.integrator);
    if integrator != crate::integrator::GlobalIntegrator::Path {
        // A bidirectional sample is two subpaths and every connection between them, and
        // light tracing lands on other pixels: there is no one path to record.
        return Err(err(format!(
            "replay records the path tracer's paths; integrator {} makes each sample from \
             a camera and a light subpath and their connections, which a path record cannot \
             hold (replay with --technique integrator=path)",
            integrator.name()
        )));
    }
    let start = std::time::Instant::now();
    let tracer = PathTracer {
        technique: options.technique,
        techniques: options.plugin_techniques,
        visible_emitters: crate::path_tracer::visible_emitters::for_scene(
            scene,
            options.visible_emitters,
        ),
    };
    // The one path, with the pixel seed and sample address the render gives it.
    let pixel = y * w + x;
    let mut batch = PathBatch::default();
    let row = batch.paths.append_default(1);
    row.pixel[0] = pixel;
    row.sample[0] = options.sampler.address(sample);
    row.depth[0] = f32::INFINITY;
    batch.seeds.push(pixel_seed(scene.settings.seed, pixel));
    batch.trace = Some(PathTrace::default());
    let mut queues = Queues::default();
    let mut counters = SystemStats::default();
    let arena = Bump::new();
    tracer.run_batch(scene, &mut batch, &mut queues, &mut counters, &arena);
    counters.add_samples(1);
    let trace = batch.trace.take().unwrap_or_default();
    if !trace.radiance.is_finite() {
        // What the film's splat does with it.
        counters.drop_nan(1);
    }
    let mut stats = RenderStats::new(counters, start.elapsed().as_secs_f64());
    stats.features = scene.features.names();
    stats.non_finite_cases = name_non_finite_cases(scene, &stats.counters);
    Ok(Replay {
        x,
        y,
        sample,
        seed: scene.settings.seed,
        trace,
        stats,
    })
}

/// A number for people: four decimals in the usual range, scientific notation outside it.
struct Num(f32);
impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        let a = v.abs();
        if !v.is_finite() || v == 0.0 || (1e-3..1e5).contains(&a) {
            write!(f, "{v:.4}")
        } else {
            write!(f, "{v:.3e}")
        }
    }
}

struct V3(Vec3);
impl fmt::Display for V3 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        write!(f, "({}, {}, {})", Num(v.x), Num(v.y), Num(v.z))
    }
}

struct C(Rgb);
impl fmt::Display for C {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let c = self.0;
        write!(f, "({}, {}, {})", Num(c.r), Num(c.g), Num(c.b))?;
        if !c.is_finite() {
            write!(f, " NOT FINITE")?;
        }
        Ok(())
    }
}

struct Lobe(LobeSampled);
impl fmt::Display for Lobe {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let bits = [
            (LobeSampled::REFLECT, "reflect"),
            (LobeSampled::TRANSMIT, "transmit"),
            (LobeSampled::DIFFUSE, "diffuse"),
            (LobeSampled::SPECULAR, "specular"),
            (LobeSampled::SCATTER, "scatter"),
            (LobeSampled::PASS, "pass"),
        ];
        let names: Vec<&str> = bits
            .iter()
            .filter(|(b, _)| self.0.contains(*b))
            .map(|(_, n)| *n)
            .collect();
        if names.is_empty() {
            write!(f, "none")
        } else {
            write!(f, "{}", names.join("+"))
        }
    }
}

/// What a segment or vertex reached, in words.
fn event(e: &VertexEvent) -> String {
    match e {
        VertexEvent::Surface {
            material,
            shape,
            position,
            front_face,
            ..
        } => format!(
            "surface of material \"{material}\" (shape \"{shape}\", {} face) at {}",
            if *front_face { "front" } else { "back" },
            V3(*position)
        ),
        VertexEvent::VolumeScatter { material, position } => {
            format!("volume scatter in \"{material}\" at {}", V3(*position))
        }
        VertexEvent::PassThrough {
            material,
            shape,
            position,
        } => format!(
            "crossed boundary \"{shape}\" (material \"{material}\", index-matched or false) at {}",
            V3(*position)
        ),
        VertexEvent::Escaped => "escaped the scene".into(),
        VertexEvent::Absorbed => "absorbed in the volume".into(),
    }
}

/// The replayed path, one block per vertex.
impl fmt::Display for Replay {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "replay of pixel ({}, {}) sample {}, seed {} (one path, single-threaded)",
            self.x, self.y, self.sample, self.seed
        )?;
        let first_bad = self
            .trace
            .vertices
            .iter()
            .position(went_non_finite)
            .unwrap_or(usize::MAX);
        for (k, v) in self.trace.vertices.iter().enumerate() {
            writeln!(f, "depth {}: {}", v.depth, event(&v.event))?;
            for s in &v.segments {
                write!(
                    f,
                    "  ray from {} direction {} throughput {}",
                    V3(s.origin),
                    V3(s.direction),
                    C(s.throughput)
                )?;
                if let Some(m) = &s.inside {
                    write!(f, ", inside \"{m}\"")?;
                }
                if s.walk_events > 0 {
                    let n = s.walk_events;
                    let events = if n == 1 { "event" } else { "events" };
                    write!(f, ", after a random walk of {n} {events} in the volume")?;
                }
                writeln!(f)?;
                if s.end != v.event {
                    writeln!(f, "    {}", event(&s.end))?;
                }
            }
            write!(f, "  throughput in {}", C(v.throughput_in))?;
            if v.transmission != Rgb::WHITE {
                write!(f, ", segment transmission {}", C(v.transmission))?;
            }
            writeln!(f)?;
            match &v.light_sample {
                Some(l) if l.pdf == 0.0 && l.pdf.is_finite() => {
                    writeln!(f, "  light sample: none (light pdf 0)")?;
                }
                Some(l) => writeln!(
                    f,
                    "  light sample: direction {} distance {} radiance {} light pdf {}{}, \
                     bxdf value {}, mis weight {}",
                    V3(l.wi),
                    Num(l.distance),
                    C(l.radiance),
                    Num(l.pdf),
                    if l.delta { " (delta light)" } else { "" },
                    C(l.bxdf_value),
                    Num(l.mis_weight)
                )?,
                None => {}
            }
            for s in &v.shadow_rays {
                writeln!(
                    f,
                    "  shadow ray: unoccluded {} -> transmitted {}",
                    C(s.unoccluded),
                    C(s.transmitted)
                )?;
            }
            if let Some(b) = &v.bxdf_sample {
                let what = match v.event {
                    VertexEvent::VolumeScatter { .. } => "phase",
                    _ => "bxdf",
                };
                writeln!(
                    f,
                    "  {what} sample: direction {} weight {} pdf {} lobe {}",
                    V3(b.wi),
                    C(b.weight),
                    Num(b.pdf),
                    Lobe(b.lobe)
                )?;
            }
            match (&v.throughput_out, v.ended) {
                (Some(t), _) => writeln!(f, "  throughput out {}", C(*t))?,
                (None, Some(end)) => writeln!(f, "  path ended: {}", end.name())?,
                (None, None) => writeln!(f, "  path ended")?,
            }
            writeln!(f, "  added {}, radiance {}", C(v.added), C(v.radiance))?;
            if k == first_bad {
                write!(f, "  <-- became non-finite here")?;
                if !v.non_finite.is_empty() {
                    let stages: Vec<&str> = v.non_finite.iter().map(|s| s.name()).collect();
                    write!(f, " (non-finite values from: {})", stages.join(", "))?;
                }
                writeln!(f)?;
            } else if !v.non_finite.is_empty() {
                let stages: Vec<&str> = v.non_finite.iter().map(|s| s.name()).collect();
                writeln!(f, "  non-finite values from: {}", stages.join(", "))?;
            }
        }
        let r = self.radiance();
        if r.is_finite() {
            write!(f, "radiance {} (splatted into the pixel)", C(r))
        } else {
            write!(f, "radiance {} (dropped at the film)", C(r))
        }
    }
}
