//! The path-trace recorder: what one path did at each of its vertices, for
//! `risotto render --replay X,Y,SAMPLE` ([`crate::replay`]).
//!
//! Recording is asked for per batch ([`PathBatch::trace`](crate::integrator::PathBatch::trace)
//! set to `Some`). The stage loop ([`PathTracer`](super::PathTracer)'s `run_batch`) then
//! reads the queues between its stages and fills the [`PathTrace`]; the stages and the
//! systems they call know nothing of it. Without a recorder, the loop pays one `Option`
//! test per stage per bounce of a batch.
//!
//! The recorder follows the batch's path 0 and reads the shade stage's per-group scratch
//! (Bxdf and light samples), which holds the last group shaded: the details are exact for a
//! batch of one path, which is what a replay renders. A bounce of the path is one
//! [`TraceVertex`]: the segments traced to reach it (more than one when the ray crossed
//! index-matched or false boundaries on the way), what it reached, the samples taken there,
//! the shadow rays cast and the radiance added.

use super::queues::Queues;
use crate::integrator::PathBatch;
use crate::scene::CompiledScene;
use crate::shade_groups::ShadingMode;
use crate::stats::{Stage, SystemStats, Termination};
use glam::Vec3;
use risotto_components::{LobeSampled, Rgb, VolumeStack};

/// Everything recorded about one path, vertex by vertex.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PathTrace {
    /// One entry per bounce of the path (the camera ray's is the first).
    pub vertices: Vec<TraceVertex>,
    /// Radiance of the path when it ended (what the film gets, unless it is not finite).
    pub radiance: Rgb,
    /// Why the path ended, when the stats said so (`None` only when nothing counted it).
    pub ended: Option<Termination>,
}

/// What one bounce of the path did.
#[derive(Clone, Debug, PartialEq)]
pub struct TraceVertex {
    /// Path depth of the vertex: the scattering vertices before it (that of the ray that
    /// arrived here, after the events of a random walk; 0 = seen from the camera), as in the
    /// stats' non-finite cases.
    pub depth: u32,
    /// The segments traced this bounce, in order; the last one reached the vertex.
    pub segments: Vec<TraceSegment>,
    /// What the last segment reached.
    pub event: VertexEvent,
    /// Throughput of the ray that arrived, before the last segment's transmission.
    pub throughput_in: Rgb,
    /// Transmission of the last segment (what a volume integrator returned; white outside
    /// volumes).
    pub transmission: Rgb,
    /// The Bxdf's (or phase function's) sample for the next bounce, where one was drawn.
    pub bxdf_sample: Option<BxdfSampleRecord>,
    /// The light sample of direct lighting, where one was drawn.
    pub light_sample: Option<LightSampleRecord>,
    /// Shadow rays cast from this bounce (by direct lighting, and by a volume integrator
    /// through the lighting delegate), with what survived their walk to the light.
    pub shadow_rays: Vec<ShadowRayRecord>,
    /// Throughput of the next ray, when the path went on.
    pub throughput_out: Option<Rgb>,
    /// Radiance the path gained during this bounce (emission, environment, direct light).
    pub added: Rgb,
    /// The path's radiance after this bounce.
    pub radiance: Rgb,
    /// Stages that produced non-finite values during this bounce (the NaN-provenance
    /// counters that went up), in [`Stage::ALL`] order.
    pub non_finite: Vec<Stage>,
    /// Why the path ended at this bounce, if it did.
    pub ended: Option<Termination>,
}

/// One traced segment (ray) of a bounce.
#[derive(Clone, Debug, PartialEq)]
pub struct TraceSegment {
    /// Start of the segment (the last event of a random walk, for walked rays).
    pub origin: Vec3,
    /// Unit direction.
    pub direction: Vec3,
    /// Throughput the ray carried.
    pub throughput: Rgb,
    /// The volume the segment travelled in (its innermost volume's material), if any.
    pub inside: Option<String>,
    /// Scattering events of a random walk the volume integrator ran inside the volume before
    /// this segment (counted in the depth); 0 when none.
    pub walk_events: u32,
    /// Where it ended.
    pub end: VertexEvent,
}

/// What a segment reached.
#[derive(Clone, Debug, PartialEq)]
pub enum VertexEvent {
    /// A surface that was shaded.
    Surface {
        /// The surface's material.
        material: String,
        /// The shape hit.
        shape: String,
        /// Hit position.
        position: Vec3,
        /// Shading normal.
        normal: Vec3,
        /// Whether the ray arrived from outside the shape (against the geometric normal).
        front_face: bool,
    },
    /// A point inside a volume that was shaded with its phase function.
    VolumeScatter {
        /// The volume's material.
        material: String,
        /// The point.
        position: Vec3,
    },
    /// An index-matched or false boundary the ray went through without a bounce.
    PassThrough {
        /// The surface's material.
        material: String,
        /// The shape crossed.
        shape: String,
        /// Where it was crossed.
        position: Vec3,
    },
    /// The ray left the scene (the environment, if any, was added).
    Escaped,
    /// The volume integrator returned nothing for the ray: absorbed in the volume.
    Absorbed,
}

/// A Bxdf or phase-function sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BxdfSampleRecord {
    /// Sampled direction.
    pub wi: Vec3,
    /// `f |cos| / pdf` (the phase function's `p / pdf` times the albedo).
    pub weight: Rgb,
    /// Solid-angle pdf (discrete probability for specular lobes); 0 = no sample.
    pub pdf: f32,
    /// Lobe bits of the sample.
    pub lobe: LobeSampled,
}

/// A light sample of direct lighting and the Bxdf's response to it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSampleRecord {
    /// Direction to the light sample.
    pub wi: Vec3,
    /// Distance to it (infinite for distant lights).
    pub distance: f32,
    /// Radiance (intensity for point lights) arriving from it, unoccluded.
    pub radiance: Rgb,
    /// The light pdf (solid angle, including the light's selection); 0 = no light sample
    /// (no shadow ray).
    pub pdf: f32,
    /// Whether the light is a Dirac light (no MIS).
    pub delta: bool,
    /// The Bxdf's value towards it (`f |cos|`; the phase function's `albedo p`).
    pub bxdf_value: Rgb,
    /// The sample's MIS weight (the power heuristic against the Bxdf's pdf towards it; 1 for
    /// Dirac lights and without MIS); 0 without a sample.
    pub mis_weight: f32,
}

/// A shadow ray of a bounce.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowRayRecord {
    /// Contribution if nothing is in the way (`throughput f Le mis / pdf`).
    pub unoccluded: Rgb,
    /// What reached the path after the walk to the light (occluders, transmission).
    pub transmitted: Rgb,
}

/// The bounce being recorded, until its end.
#[derive(Clone, Debug, Default)]
pub(super) struct Recorder {
    pub(super) trace: PathTrace,
    segments: Vec<TraceSegment>,
    radiance_before: Rgb,
    non_finite_before: [u64; Stage::COUNT],
    terminated_before: [u64; Termination::COUNT],
    /// The bounce's vertex, once shaded: depth, event, throughput in, transmission.
    shaded: Option<(u32, VertexEvent, Rgb, Rgb)>,
    bxdf_sample: Option<BxdfSampleRecord>,
    light_sample: Option<LightSampleRecord>,
    shadow: Vec<Rgb>,
    throughput_out: Option<Rgb>,
}

/// The material name of the innermost volume of `stack`.
fn inside(scene: &CompiledScene, stack: &VolumeStack) -> Option<String> {
    stack.innermost().map(|e| material_name(scene, e.material))
}

fn material_name(scene: &CompiledScene, m: u32) -> String {
    scene
        .materials
        .get(m as usize)
        .map_or_else(|| format!("#{m}"), |m| m.name.clone())
}

fn shape_name(scene: &CompiledScene, s: u32) -> String {
    scene
        .shapes
        .get(s as usize)
        .map_or_else(|| format!("#{s}"), |s| s.name.clone())
}

impl Recorder {
    /// A recorder that fills `trace` (emptied first).
    pub(super) fn new(mut trace: PathTrace) -> Self {
        trace.vertices.clear();
        Recorder {
            trace,
            ..Default::default()
        }
    }

    /// A bounce starts (its rays are in the ray queue).
    pub(super) fn begin_bounce(&mut self, batch: &PathBatch, stats: &SystemStats) {
        self.segments.clear();
        self.radiance_before = batch.paths.radiance.first().copied().unwrap_or_default();
        self.non_finite_before = stats.non_finite;
        self.terminated_before = stats.terminated;
        self.shaded = None;
        self.bxdf_sample = None;
        self.light_sample = None;
        self.shadow.clear();
        self.throughput_out = None;
    }

    /// A trace round answered the path's ray: one new segment, ending at the point it
    /// reached, as an escaped ray, or absorbed.
    pub(super) fn traced(&mut self, scene: &CompiledScene, q: &Queues) {
        let incoming = &q.hits.incoming;
        let Some(r) = (0..incoming.len()).rev().find(|&r| incoming.path[r] == 0) else {
            return;
        };
        let pts = &q.hits.groups.points;
        let point = (0..pts.len()).find(|&i| pts.ray_id[i] as usize == r);
        let end = match point {
            Some(i) => {
                let mode = q.hits.groups.groups.iter().find(|g| g.range.contains(&i));
                match mode.map(|g| g.mode) {
                    Some(ShadingMode::VolumeScatter) => VertexEvent::VolumeScatter {
                        material: material_name(scene, pts.material[i]),
                        position: pts.p[i],
                    },
                    _ => VertexEvent::Surface {
                        material: material_name(scene, pts.material[i]),
                        shape: shape_name(scene, pts.shape[i]),
                        position: pts.p[i],
                        normal: pts.nn[i],
                        front_face: pts.front_face[i],
                    },
                }
            }
            None if q.escaped.ray.iter().any(|&e| e as usize == r) => VertexEvent::Escaped,
            None => VertexEvent::Absorbed,
        };
        let transmission = match point {
            Some(i) => pts.transmission[i],
            None => q
                .escaped
                .ray
                .iter()
                .position(|&e| e as usize == r)
                .map_or(Rgb::WHITE, |k| q.escaped.transmission[k]),
        };
        let walked = &q.trace.answers.walked;
        let walk_events = if scene.features.volumes {
            (0..walked.len())
                .find(|&k| {
                    let w = q.trace.bundle_start + walked.ray[k] as usize;
                    incoming.path.get(w) == Some(&0)
                })
                .map_or(0, |k| walked.vertices[k])
        } else {
            0
        };
        self.segments.push(TraceSegment {
            origin: incoming.origin[r],
            direction: incoming.direction[r],
            throughput: incoming.throughput[r],
            inside: inside(scene, &incoming.volume_stack[r]),
            walk_events,
            end: end.clone(),
        });
        self.shaded = Some((
            incoming.depth[r] as u32,
            end,
            incoming.throughput[r],
            transmission,
        ));
    }

    /// The pass-through stage ran: a surface point it took out of the hit queue was an
    /// index-matched or false boundary.
    pub(super) fn passed(&mut self, q: &Queues) {
        let still_there = !q.hits.groups.points.is_empty();
        if let Some(last) = self.segments.last_mut() {
            if let VertexEvent::Surface {
                material,
                shape,
                position,
                ..
            } = &last.end
            {
                if !still_there {
                    last.end = VertexEvent::PassThrough {
                        material: material.clone(),
                        shape: shape.clone(),
                        position: *position,
                    };
                    if let Some(s) = &mut self.shaded {
                        s.1 = last.end.clone();
                    }
                }
            }
        }
    }

    /// Before the shade stage: empties the per-group scratch the recorder reads after it, so
    /// that what it finds there is this bounce's (the stage overwrites what it reads, so this
    /// changes nothing it computes).
    pub(super) fn before_shade(&mut self, q: &mut Queues) {
        q.group.samples.reset(0);
        let light = &mut q.group.light;
        light.wi.clear();
        light.distance.clear();
        light.radiance.clear();
        light.pdf.clear();
        light.delta.clear();
        light.margin.clear();
        light.value.clear();
        light.eval_pdf.clear();
        q.group.active.clear();
    }

    /// After the shade stage: the samples drawn at the vertex, the next ray and the shadow
    /// rays queued.
    pub(super) fn shaded(&mut self, q: &Queues) {
        let s = &q.group.samples;
        if !s.pdf.is_empty() {
            self.bxdf_sample = Some(BxdfSampleRecord {
                wi: s.wi[0],
                weight: s.weight[0],
                pdf: s.pdf[0],
                lobe: s.lobe[0],
            });
        }
        let l = &q.group.light;
        let active = q.group.active.first().copied().unwrap_or(false);
        if !l.pdf.is_empty() && !l.eval_pdf.is_empty() && active {
            let pdf = l.pdf[0];
            // The direct-lighting system leaves `w / pdf` where the Bxdf's pdf was.
            let mis_weight = if pdf != 0.0 { l.eval_pdf[0] * pdf } else { 0.0 };
            self.light_sample = Some(LightSampleRecord {
                wi: l.wi[0],
                distance: l.distance[0],
                radiance: l.radiance[0],
                pdf,
                delta: l.delta[0],
                bxdf_value: l.value[0],
                mis_weight,
            });
        }
        let next = &q.next.rays;
        self.throughput_out = (0..next.len())
            .find(|&r| next.path[r] == 0)
            .map(|r| next.throughput[r]);
        let shadow = &q.shadow.rays;
        self.shadow.clear();
        self.shadow.extend(
            (0..shadow.len())
                .filter(|&k| shadow.path[k] == 0)
                .map(|k| shadow.contribution[k]),
        );
    }

    /// After the transmission stage: the bounce's vertex is complete. `shadow_rays` is the
    /// number of shadow rays the transmission stage traced (all of path 0 here).
    pub(super) fn end_bounce(
        &mut self,
        q: &Queues,
        shadow_rays: usize,
        batch: &PathBatch,
        stats: &SystemStats,
    ) {
        let radiance = batch.paths.radiance.first().copied().unwrap_or_default();
        let non_finite = Stage::ALL
            .into_iter()
            .filter(|&s| stats.non_finite[s as usize] > self.non_finite_before[s as usize])
            .collect();
        let ended = Termination::ALL
            .into_iter()
            .find(|&t| stats.terminated[t as usize] > self.terminated_before[t as usize]);
        let transmitted = if shadow_rays == self.shadow.len() {
            &q.shadow.contribution[..shadow_rays.min(q.shadow.contribution.len())]
        } else {
            &[]
        };
        let shadow_rays = self
            .shadow
            .iter()
            .enumerate()
            .map(|(k, &unoccluded)| ShadowRayRecord {
                unoccluded,
                transmitted: transmitted.get(k).copied().unwrap_or(unoccluded),
            })
            .collect();
        let (depth, event, throughput_in, transmission) = match self.shaded.take() {
            Some(s) => s,
            None => (0, VertexEvent::Absorbed, Rgb::BLACK, Rgb::WHITE),
        };
        self.trace.vertices.push(TraceVertex {
            depth,
            segments: std::mem::take(&mut self.segments),
            event,
            throughput_in,
            transmission,
            bxdf_sample: self.bxdf_sample.take(),
            light_sample: self.light_sample.take(),
            shadow_rays,
            throughput_out: self.throughput_out.take(),
            added: radiance - self.radiance_before,
            radiance,
            non_finite,
            ended,
        });
        self.trace.radiance = radiance;
        if ended.is_some() {
            self.trace.ended = ended;
        }
    }
}
