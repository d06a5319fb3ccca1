//! Camera ray generation.
//!
//! Conventions: image (0,0) is the top-left pixel; `right = normalize(cross(forward, up))`,
//! `image up = cross(right, forward)`. The perspective field of view is the full *horizontal*
//! angle. Samples are uniform over each pixel's square (a box pixel filter).

use crate::sampler::{sample_2d, PathSampler};
use glam::{Vec2, Vec3};

/// Projection of a [`Camera`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Pinhole perspective with a full horizontal field of view, in degrees, in (0, 180).
    Perspective {
        /// Full horizontal field of view in degrees.
        fov_deg: f32,
    },
    /// Orthographic with a world-space view width.
    Orthographic {
        /// Width of the view in world units.
        width: f32,
    },
}

/// A camera placed by look-at, with an image size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Projection.
    pub projection: Projection,
    /// Eye position.
    pub from: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Unit image-right direction.
    pub right: Vec3,
    /// Unit image-up direction.
    pub up: Vec3,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Camera {
    /// A camera at `from` looking at `to`. Returns `None` when `from == to` or `up` is parallel
    /// to the view direction.
    pub fn look_at(
        projection: Projection,
        from: Vec3,
        to: Vec3,
        up: Vec3,
        width: u32,
        height: u32,
    ) -> Option<Camera> {
        let forward = (to - from).try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        let up = right.cross(forward);
        Some(Camera {
            projection,
            from,
            forward,
            right,
            up,
            width,
            height,
        })
    }

    /// The ray through film position `film` (in pixels, (0,0) = top-left corner of the image).
    #[inline]
    pub fn ray(&self, film: Vec2) -> (Vec3, Vec3) {
        let w = self.width as f32;
        let h = self.height as f32;
        // Normalised screen coordinates: x in [-1, 1] left to right, y in [-h/w, h/w] top to
        // bottom flipped so +y is image up.
        let sx = 2.0 * film.x / w - 1.0;
        let sy = (1.0 - 2.0 * film.y / h) * (h / w);
        match self.projection {
            Projection::Perspective { fov_deg } => {
                let tan_half = (0.5 * fov_deg.to_radians()).tan();
                let d = self.forward + self.right * (sx * tan_half) + self.up * (sy * tan_half);
                (self.from, d.normalize())
            }
            Projection::Orthographic { width } => {
                let half = 0.5 * width;
                let o = self.from + self.right * (sx * half) + self.up * (sy * half);
                (o, self.forward)
            }
        }
    }
}

/// Generates one camera ray per `(pixel, sample)` entry. Pixel jitter consumes sampler
/// dimensions 0 and 1; `next_dimension` is set to 2 for every ray.
///
/// Inputs: `pixel`, `sample`, `seed` (per-pixel scrambling seed). Outputs: `origin`,
/// `direction`.
pub fn generate_camera_rays(
    camera: &Camera,
    pixel: &[u32],
    sample: &[u32],
    seed: &[u32],
    origin: &mut [Vec3],
    direction: &mut [Vec3],
) {
    let width = camera.width;
    for i in 0..pixel.len() {
        let px = pixel[i] % width;
        let py = pixel[i] / width;
        let jitter = sample_2d(seed[i], sample[i], 0);
        let (o, d) = camera.ray(Vec2::new(px as f32 + jitter.x, py as f32 + jitter.y));
        origin[i] = o;
        direction[i] = d;
    }
}

/// The sampler dimension the first bounce starts at: the pixel jitter uses 0 and 1, 2 and 3
/// are kept for lens sampling, so every vertex's dimensions start on a multiple of 4 (one
/// SIMD evaluation of four Sobol dimensions, [`crate::sampler::sample_4d`]).
pub const FIRST_PATH_DIMENSION: u32 = 4;

/// Convenience for tests and plug-ins: a [`PathSampler`] positioned after the camera jitter.
pub fn path_sampler(seed: u32, sample: u32) -> PathSampler {
    PathSampler {
        seed,
        sample,
        dimension: FIRST_PATH_DIMENSION,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_looks_forward_and_corners_span_fov() {
        let cam = Camera::look_at(
            Projection::Perspective { fov_deg: 90.0 },
            Vec3::new(0.0, 0.0, 5.0),
            Vec3::ZERO,
            Vec3::Y,
            100,
            100,
        )
        .unwrap();
        let (_, d) = cam.ray(Vec2::new(50.0, 50.0));
        assert!((d - Vec3::NEG_Z).length() < 1e-6);
        // Left edge of a 90-degree horizontal fov: 45 degrees to the left.
        let (_, d) = cam.ray(Vec2::new(0.0, 50.0));
        assert!((d.x + std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-5);
        // Top of the image is +y.
        let (_, d) = cam.ray(Vec2::new(50.0, 0.0));
        assert!(d.y > 0.7);
        // Right is +x when looking down -z with +y up.
        let (_, d) = cam.ray(Vec2::new(100.0, 50.0));
        assert!(d.x > 0.7);
    }

    #[test]
    fn orthographic_rays_are_parallel_and_span_width() {
        let cam = Camera::look_at(
            Projection::Orthographic { width: 4.0 },
            Vec3::new(0.0, 0.0, 5.0),
            Vec3::ZERO,
            Vec3::Y,
            10,
            10,
        )
        .unwrap();
        let (o0, d0) = cam.ray(Vec2::new(0.0, 5.0));
        let (o1, d1) = cam.ray(Vec2::new(10.0, 5.0));
        assert_eq!(d0, d1);
        assert!(((o1 - o0).length() - 4.0).abs() < 1e-5);
    }

    #[test]
    fn degenerate_look_at_is_rejected() {
        let p = Projection::Perspective { fov_deg: 40.0 };
        assert!(Camera::look_at(p, Vec3::ZERO, Vec3::ZERO, Vec3::Y, 1, 1).is_none());
        assert!(Camera::look_at(p, Vec3::ZERO, Vec3::Y, Vec3::Y, 1, 1).is_none());
    }
}
