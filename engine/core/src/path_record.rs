//! Path records: what one path did at each of its vertices (the segments traced, what each
//! reached, the samples taken, the shadow rays cast, the radiance added). A global
//! integrator fills one when a batch asks for it ([`PathBatch::trace`](crate::integrator::PathBatch::trace));
//! `risotto render --replay X,Y,SAMPLE` prints it ([`crate::replay`]). Plain data: the
//! integrator contract names these records, not any integrator's recorder.

use crate::stats::{Stage, Termination};
use glam::Vec3;
use risotto_components::{LobeSampled, Rgb};

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
