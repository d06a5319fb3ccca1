//! The rays a bidirectional integrator traces, by the strategy that needs them: the work
//! count that bounds its cost per sample against the path tracer's (issue 34). The path
//! tracer's own split is in the systems' counters already (`intersect` items: camera and
//! continuation rays; `occlusion` items: shadow rays).

use serde::Serialize;

/// Rays traced by a bidirectional integrator, by kind. All 0 under the path tracer (and not
/// reported then).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct BidirRays {
    /// Camera subpath rays: the camera rays and their continuations.
    pub camera: u64,
    /// Light subpath rays: the emitted rays and their continuations.
    pub light: u64,
    /// Shadow rays of light samples at camera vertices (next-event estimation).
    pub light_samples: u64,
    /// Shadow rays connecting camera vertices to light vertices.
    pub connections: u64,
    /// Shadow rays connecting light vertices to the camera (light tracing's splats).
    pub camera_connections: u64,
}

impl BidirRays {
    /// Adds `other`'s counts.
    pub fn merge(&mut self, other: &BidirRays) {
        self.camera += other.camera;
        self.light += other.light;
        self.light_samples += other.light_samples;
        self.connections += other.connections;
        self.camera_connections += other.camera_connections;
    }

    /// True when no ray was counted (not a bidirectional render).
    pub fn is_empty(&self) -> bool {
        *self == BidirRays::default()
    }
}
