//! Generate stage: one camera ray per path of the batch.

use super::queues::RayQueue;
use crate::integrator::PathBatch;
use crate::scene::CompiledScene;
use crate::stats::{System, SystemStats};
use risotto_systems::camera::push_camera_rays;

/// Fills `rays` with the camera rays of every path of `batch` (pixel-major, as the paths).
pub(super) fn camera_rays(
    scene: &CompiledScene,
    batch: &PathBatch,
    rays: &mut RayQueue,
    stats: &mut SystemStats,
) {
    let n = batch.paths.len();
    rays.rays.clear();
    stats.time(System::Camera, n, || {
        push_camera_rays(
            &scene.camera,
            &batch.paths.pixel,
            &batch.paths.sample,
            &batch.seeds,
            &scene.camera_stack,
            &mut rays.rays,
        )
    });
    rays.rays.debug_check();
    stats.add_rays(n);
}
