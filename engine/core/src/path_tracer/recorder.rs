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
use risotto_components::{Rgb, VolumeStack};

use crate::path_record::*;

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
            // The traced table is the spare now, its contributions transmitted.
            let traced = &q.shadow.spare.contribution;
            &traced[..shadow_rays.min(traced.len())]
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
