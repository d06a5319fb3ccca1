//! Camera ray generation.
//!
//! Conventions: image (0,0) is the top-left pixel; `right = normalize(cross(forward, up))`,
//! `image up = cross(right, forward)`. The perspective field of view is the full *horizontal*
//! angle. Samples are uniform over each pixel's square (a box pixel filter) unless the
//! camera's [`PixelFilter`] says otherwise: its film positions are then drawn from the
//! filter around the pixel centre ([`crate::pixel_filter`], filter importance sampling),
//! from the same two sampler dimensions.
//!
//! The thin-lens camera ([`Projection::ThinLens`]) follows Mitsuba 3's `thinlens` sensor
//! (`src/sensors/thinlens.cpp`, `ThinLensCamera::sample_ray`) and pbrt-v4's
//! `PerspectiveCamera::GenerateRay` (Pharr, Jakob, Humphreys, *Physically Based Rendering*,
//! 4th ed., sec. 5.2.3): the pinhole ray of the film position meets the focal plane, the
//! plane at `focus_distance` along the view direction (a plane, not a sphere: Mitsuba scales
//! the near-plane point by `focus_distance / z`), and the ray starts on a point of the lens
//! disk (radius `aperture_radius`, spanned by the image right and up axes, sampled with the
//! concentric map) and goes through that focal-plane point. Lens samples are sampler
//! dimensions 2 and 3, reserved for them ([`FIRST_PATH_DIMENSION`]), so a lens shifts no
//! other dimension; with `aperture_radius = 0` they are not drawn and the rays are the
//! pinhole camera's, bit for bit.
//!
//! The inverse direction, a scene point connected to the camera (light tracing, BDPT, VCM:
//! the film position, sensor importance and pdfs), is [`CameraConnection`]'s module,
//! `camera/importance.rs`.

mod importance;
pub use importance::{CameraConnection, CameraEndpoint};

use crate::pixel_filter::warp_pixel_jitter;
pub use crate::pixel_filter::PixelFilter;
use crate::sampler::{first_2d_column, sample_2d, PathSampler};
use crate::simd8::{Backend, Kernel8, Lanes8, Row8, Simd};
use crate::warp::sample_concentric_disk;
use glam::{Vec2, Vec3};
use risotto_components::{LobeSampled, Rays, Rgb, VolumeStack};

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
    /// Perspective through a thin lens (depth of field), as Mitsuba 3's `thinlens` sensor:
    /// rays start on the lens disk and meet the pinhole ray of their film position on the
    /// focal plane. `aperture_radius = 0` is exactly [`Projection::Perspective`].
    ThinLens {
        /// Full horizontal field of view in degrees, in (0, 180).
        fov_deg: f32,
        /// Radius of the lens disk in world units, finite and >= 0.
        aperture_radius: f32,
        /// Distance from the lens to the plane in focus, along the view direction, in world
        /// units, finite and > 0.
        focus_distance: f32,
    },
}

impl Projection {
    /// The lens of a thin-lens projection with a positive aperture: `(aperture_radius,
    /// focus_distance)`; `None` for every camera whose rays start at one point or are
    /// parallel (pinhole, orthographic, thin lens of radius 0).
    #[inline]
    pub fn lens(&self) -> Option<(f32, f32)> {
        match *self {
            Projection::ThinLens {
                aperture_radius,
                focus_distance,
                ..
            } if aperture_radius > 0.0 => Some((aperture_radius, focus_distance)),
            _ => None,
        }
    }
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
    /// The pixel reconstruction filter the film positions of the camera rays are drawn from.
    /// Defaults to [`PixelFilter::PIXEL_BOX`] (uniform over each pixel).
    pub filter: PixelFilter,
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
            filter: PixelFilter::PIXEL_BOX,
        })
    }

    /// This camera with pixel filter `filter`.
    pub fn with_filter(self, filter: PixelFilter) -> Camera {
        Camera { filter, ..self }
    }

    /// The ray through film position `film` (in pixels, (0,0) = top-left corner of the image);
    /// for a thin lens, the ray through the lens centre (the pinhole ray).
    #[inline]
    pub fn ray(&self, film: Vec2) -> (Vec3, Vec3) {
        self.ray_generator().ray(film)
    }

    /// The ray through film position `film` and lens sample `lens` in `[0, 1)^2` (mapped to
    /// the lens disk by the concentric map). Cameras without a lens ([`Projection::lens`] is
    /// `None`) ignore `lens`: the result is [`Self::ray`], bit for bit.
    #[inline]
    pub fn ray_through_lens(&self, film: Vec2, lens: Vec2) -> (Vec3, Vec3) {
        self.ray_generator().ray_through_lens(film, lens)
    }

    /// The per-camera constants of [`Self::ray`], computed once for a batch of rays.
    #[inline]
    fn ray_generator(&self) -> RayGenerator {
        let scale = match self.projection {
            Projection::Perspective { fov_deg } | Projection::ThinLens { fov_deg, .. } => {
                (0.5 * fov_deg.to_radians()).tan()
            }
            Projection::Orthographic { width } => 0.5 * width,
        };
        RayGenerator {
            camera: *self,
            w: self.width as f32,
            h: self.height as f32,
            scale,
        }
    }
}

/// A [`Camera`] with the constants of its ray computation hoisted (the tangent of the half
/// field of view costs a libm call, more than the rest of a ray).
struct RayGenerator {
    camera: Camera,
    w: f32,
    h: f32,
    /// `tan(fov / 2)` (perspective) or half the view width (orthographic).
    scale: f32,
}

impl RayGenerator {
    /// Normalised screen coordinates: x in [-1, 1] left to right, y in [-h/w, h/w] top to
    /// bottom flipped so +y is image up.
    #[inline(always)]
    fn screen(&self, film: Vec2) -> (f32, f32) {
        let (w, h) = (self.w, self.h);
        let sx = 2.0 * film.x / w - 1.0;
        let sy = (1.0 - 2.0 * film.y / h) * (h / w);
        (sx, sy)
    }

    /// Direction of a perspective ray.
    #[inline(always)]
    fn perspective(&self, film: Vec2) -> Vec3 {
        let (sx, sy) = self.screen(film);
        let c = &self.camera;
        let d = c.forward + c.right * (sx * self.scale) + c.up * (sy * self.scale);
        d.normalize()
    }

    /// Origin of an orthographic ray.
    #[inline(always)]
    fn orthographic(&self, film: Vec2) -> Vec3 {
        let (sx, sy) = self.screen(film);
        let c = &self.camera;
        c.from + c.right * (sx * self.scale) + c.up * (sy * self.scale)
    }

    #[inline(always)]
    fn ray(&self, film: Vec2) -> (Vec3, Vec3) {
        match self.camera.projection {
            Projection::Perspective { .. } | Projection::ThinLens { .. } => {
                (self.camera.from, self.perspective(film))
            }
            Projection::Orthographic { .. } => (self.orthographic(film), self.camera.forward),
        }
    }

    /// [`Self::ray`] through lens sample `lens` when the camera has a lens.
    #[inline(always)]
    fn ray_through_lens(&self, film: Vec2, lens: Vec2) -> (Vec3, Vec3) {
        match self.camera.projection.lens() {
            Some((radius, focus)) => self.thin_lens(film, lens, radius, focus),
            None => self.ray(film),
        }
    }

    /// The thin-lens ray of film position `film` and lens sample `u`: with the pinhole
    /// direction `d = forward + right a + up b` (its component along `forward` is 1), the
    /// focal-plane point is `from + focus d` and the lens point `from + radius (right x + up
    /// y)`, `(x, y)` the concentric disk point of `u`; the ray goes from the lens point to the
    /// focal-plane point.
    #[inline(always)]
    fn thin_lens(&self, film: Vec2, u: Vec2, radius: f32, focus: f32) -> (Vec3, Vec3) {
        let (sx, sy) = self.screen(film);
        let c = &self.camera;
        let d = c.forward + c.right * (sx * self.scale) + c.up * (sy * self.scale);
        let disk = sample_concentric_disk(u) * radius;
        let offset = c.right * disk.x + c.up * disk.y;
        (c.from + offset, (d * focus - offset).normalize())
    }
}

/// Film position of camera sample `(pixel, sample)`: the pixel's corner plus the jitter,
/// sampler dimensions 0 and 1, warped by the camera's filter unless it is the pixel box.
#[inline(always)]
fn film_position(camera: &Camera, pixel: u32, sample: u32, seed: u32) -> Vec2 {
    let px = pixel % camera.width;
    let py = pixel / camera.width;
    let mut jitter = sample_2d(seed, sample, 0);
    if !camera.filter.is_pixel_box() {
        warp_pixel_jitter(&camera.filter, std::slice::from_mut(&mut jitter));
    }
    Vec2::new(px as f32 + jitter.x, py as f32 + jitter.y)
}

/// The sampler dimension of the lens sample (2 and 3; the pixel jitter is 0 and 1).
pub const LENS_DIMENSION: u32 = 2;

/// Generates one camera ray per `(pixel, sample)` entry. Pixel jitter consumes sampler
/// dimensions 0 and 1, a thin lens 2 and 3 (paths continue at [`FIRST_PATH_DIMENSION`]).
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
    let gen = camera.ray_generator();
    let n = pixel.len();
    let (sample, seed) = (&sample[..n], &seed[..n]);
    let (origin, direction) = (&mut origin[..n], &mut direction[..n]);
    let lens = camera.projection.lens();
    for i in 0..n {
        let film = film_position(camera, pixel[i], sample[i], seed[i]);
        (origin[i], direction[i]) = match lens {
            Some((radius, focus)) => {
                let u = sample_2d(seed[i], sample[i], LENS_DIMENSION);
                gen.thin_lens(film, u, radius, focus)
            }
            None => gen.ray(film),
        };
    }
}

/// Appends one camera ray per `(pixel[i], sample[i], seed[i])` to `rays`: the first segment
/// of path `i`, starting in the volumes `stack` (jitter as in [`generate_camera_rays`]).
/// Written column by column: the projection decides which of origin and direction varies,
/// and every other column is a constant of camera rays (`tmin`
/// [`FREE_ORIGIN`](crate::intersect::FREE_ORIGIN), `tmax` infinity,
/// throughput 1, no lobe, depth and passes 0, pdf 0, `eta_scale` 1, dimension
/// [`FIRST_PATH_DIMENSION`], no shading context, `prev_p` = origin).
pub fn push_camera_rays(
    camera: &Camera,
    pixel: &[u32],
    sample: &[u32],
    seed: &[u32],
    stack: &VolumeStack,
    rays: &mut Rays,
) {
    let (base, end) = (rays.len(), rays.len() + pixel.len());
    push_camera_ray_geometry(
        camera,
        pixel,
        sample,
        seed,
        &mut rays.origin,
        &mut rays.direction,
    );
    rays.prev_p.extend_from_slice(&rays.origin[base..end]);
    // The camera is no computed surface point: hits close to it are decided exactly.
    rays.tmin.resize(end, crate::intersect::FREE_ORIGIN);
    rays.tmax.resize(end, f32::INFINITY);
    rays.path.extend(0..pixel.len() as u32);
    rays.throughput.resize(end, Rgb::WHITE);
    rays.lobe.resize(end, LobeSampled::NONE);
    rays.depth.resize(end, 0);
    rays.passes.resize(end, 0);
    rays.pdf.resize(end, 0.0);
    rays.eta_scale.resize(end, 1.0);
    rays.dimension.resize(end, FIRST_PATH_DIMENSION);
    rays.shading_ctx_index.resize(end, u32::MAX);
    rays.volume_stack.resize(end, stack.clone());
    debug_assert!(rays.is_consistent(), "a ray column was not filled");
}

/// The origins and directions of [`push_camera_rays`] alone, appended to `origin` and
/// `direction` (for callers that need no other column of a camera ray, whose other values
/// are its constants: `tmin` [`FREE_ORIGIN`](crate::intersect::FREE_ORIGIN), `tmax`
/// infinity, throughput 1).
pub fn push_camera_ray_geometry(
    camera: &Camera,
    pixel: &[u32],
    sample: &[u32],
    seed: &[u32],
    origin: &mut Vec<Vec3>,
    direction: &mut Vec<Vec3>,
) {
    let gen = camera.ray_generator();
    let n = pixel.len();
    let end = origin.len() + n;
    // The jitter of every sample first, eight per call of the column sampler.
    let mut jitter = vec![Vec2::ZERO; n];
    first_2d_column(&seed[..n], &sample[..n], &mut jitter);
    // The pixel box is the jitter itself: not warped, so its rays are those of a camera
    // without filters, bit for bit.
    if !camera.filter.is_pixel_box() {
        warp_pixel_jitter(&camera.filter, &mut jitter);
    }
    let width = camera.width;
    // A batch holds each pixel's samples together: the pixel's coordinates (an integer
    // division and remainder) are computed once per run of equal pixel indices.
    let mut last: Option<(u32, f32, f32)> = None;
    let films = pixel.iter().zip(&jitter).map(move |(&p, &j)| {
        let (x, y) = match last {
            Some((q, x, y)) if q == p => (x, y),
            _ => {
                let (x, y) = ((p % width) as f32, (p / width) as f32);
                last = Some((p, x, y));
                (x, y)
            }
        };
        Vec2::new(x + j.x, y + j.y)
    });
    if let Some((radius, focus)) = camera.projection.lens() {
        // Lens samples (dimensions 2 and 3) one ray at a time: a lens is rare and its rays
        // cost little beside their paths.
        origin.reserve(n);
        direction.reserve(n);
        for ((film, &seed), &sample) in films.zip(&seed[..n]).zip(&sample[..n]) {
            let u = sample_2d(seed, sample, LENS_DIMENSION);
            let (o, d) = gen.thin_lens(film, u, radius, focus);
            origin.push(o);
            direction.push(d);
        }
    } else {
        match camera.projection {
            Projection::Perspective { .. } | Projection::ThinLens { .. } => {
                origin.resize(end, camera.from);
                let films: Vec<Vec2> = films.collect();
                extend_perspective(Backend::best(), &gen, &films, direction);
            }
            Projection::Orthographic { .. } => {
                origin.extend(films.map(|film| gen.orthographic(film)));
                direction.resize(end, camera.forward);
            }
        }
    }
}

/// Appends `gen.perspective(film)` for every film position to `out`, eight rays at a time
/// on the lanes of `backend`.
fn extend_perspective(backend: Backend, gen: &RayGenerator, films: &[Vec2], out: &mut Vec<Vec3>) {
    out.reserve(films.len());
    backend.run(Perspective { gen, films, out });
}

/// The arguments of [`extend_perspective`], as a [`Kernel8`].
struct Perspective<'a> {
    gen: &'a RayGenerator,
    films: &'a [Vec2],
    out: &'a mut Vec<Vec3>,
}

impl Kernel8 for Perspective<'_> {
    type Output = ();
    /// [`RayGenerator::perspective`] operation for operation (no fused multiply-add), so
    /// the same bits; the last partial block one ray at a time.
    #[inline(always)]
    fn run<S: Simd>(self, s: S) {
        let (gen, c) = (self.gen, &self.gen.camera);
        let (chunks, rest) = self.films.as_chunks::<8>();
        let (w, h, scale) = (s.splat(gen.w), s.splat(gen.h), s.splat(gen.scale));
        let aspect = s.splat(gen.h / gen.w);
        let (two, one) = (s.splat(2.0), s.splat(1.0));
        for f in chunks {
            let (fx, fy) = (s.load(&Row8(f.map(|f| f.x))), s.load(&Row8(f.map(|f| f.y))));
            // RayGenerator::screen.
            let sx = two * fx / w - one;
            let sy = (one - two * fy / h) * aspect;
            let (a, b) = (sx * scale, sy * scale);
            // forward + right * a + up * b, per component.
            // (No closure: its body would be compiled without the kernel's target features.)
            let dx = s.splat(c.forward.x) + s.splat(c.right.x) * a + s.splat(c.up.x) * b;
            let dy = s.splat(c.forward.y) + s.splat(c.right.y) * a + s.splat(c.up.y) * b;
            let dz = s.splat(c.forward.z) + s.splat(c.right.z) * a + s.splat(c.up.z) * b;
            // Vec3::normalize: d * (1 / sqrt((x x + y y) + z z)).
            let recip = one / (dx * dx + dy * dy + dz * dz).sqrt();
            let (x, y, z) = (
                (dx * recip).to_array(),
                (dy * recip).to_array(),
                (dz * recip).to_array(),
            );
            self.out.extend((0..8).map(|j| Vec3::new(x[j], y[j], z[j])));
        }
        self.out
            .extend(rest.iter().map(|&film| gen.perspective(film)));
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

    /// Both projections, appended after an existing row: each ray is the camera's ray
    /// through the pixel corner plus the Sobol jitter of dimensions 0 and 1, and the other
    /// columns are the camera-ray constants.
    #[test]
    fn perspective_kernel_matches_scalar_reference_bit_for_bit() {
        // Every backend, every length (full blocks of eight and a remainder), film positions
        // across and outside the image (the kernel does not clamp).
        let mut rng = crate::sampler::SplitMix64(5);
        for (fov_deg, w, h) in [(35.0, 7, 5), (90.0, 256, 256), (10.0, 3, 400)] {
            let cam = Camera::look_at(
                Projection::Perspective { fov_deg },
                Vec3::new(0.5, 1.0, 4.0),
                Vec3::new(0.0, 0.2, 0.0),
                Vec3::Y,
                w,
                h,
            )
            .unwrap();
            let gen = cam.ray_generator();
            for len in [0usize, 1, 7, 8, 9, 16, 23, 300] {
                let films: Vec<Vec2> = (0..len)
                    .map(|_| (rng.vec2() * 1.2 - Vec2::splat(0.1)) * Vec2::new(w as f32, h as f32))
                    .collect();
                let want: Vec<[u32; 3]> = films
                    .iter()
                    .map(|&f| gen.perspective(f).to_array().map(f32::to_bits))
                    .collect();
                for backend in Backend::all() {
                    let mut got = vec![Vec3::X];
                    extend_perspective(backend, &gen, &films, &mut got);
                    let got: Vec<[u32; 3]> = got[1..]
                        .iter()
                        .map(|d| d.to_array().map(f32::to_bits))
                        .collect();
                    assert_eq!(got, want, "{backend:?}, fov {fov_deg}, len {len}");
                }
            }
        }
    }

    #[test]
    fn push_camera_rays_matches_camera_ray_per_sample() {
        use risotto_components::{RayRow, VolumeEntry};
        let projections = [
            Projection::Perspective { fov_deg: 35.0 },
            Projection::Orthographic { width: 3.0 },
            Projection::ThinLens {
                fov_deg: 35.0,
                aperture_radius: 0.2,
                focus_distance: 3.0,
            },
        ];
        for projection in projections {
            let (w, h) = (7, 5);
            let cam = Camera::look_at(
                projection,
                Vec3::new(0.5, 1.0, 4.0),
                Vec3::new(0.0, 0.2, 0.0),
                Vec3::Y,
                w,
                h,
            )
            .unwrap();
            let pixel: Vec<u32> = (0..w * h).chain([0, 34, 17]).collect();
            let sample: Vec<u32> = (0..pixel.len() as u32).map(|i| i % 4).collect();
            let seed: Vec<u32> = pixel
                .iter()
                .map(|&p| p.wrapping_mul(2_654_435_761))
                .collect();
            let mut stack = VolumeStack::new();
            stack.enter(VolumeEntry {
                material: 3,
                shape: 1,
                priority: 0,
            });
            let mut rays = Rays::default();
            rays.push(RayRow::default());
            push_camera_rays(&cam, &pixel, &sample, &seed, &stack, &mut rays);
            assert!(rays.is_consistent());
            assert_eq!(rays.len(), pixel.len() + 1);
            let n = pixel.len();
            let (mut o2, mut d2) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
            generate_camera_rays(&cam, &pixel, &sample, &seed, &mut o2, &mut d2);
            for i in 0..n {
                let r = rays.row(i + 1);
                let jitter = sample_2d(seed[i], sample[i], 0);
                let film = Vec2::new(
                    (pixel[i] % w) as f32 + jitter.x,
                    (pixel[i] / w) as f32 + jitter.y,
                );
                let lens = sample_2d(seed[i], sample[i], LENS_DIMENSION);
                let (o, d) = cam.ray_through_lens(film, lens);
                assert_eq!((r.origin, r.direction), (o, d));
                assert_eq!((o2[i], d2[i]), (o, d));
                assert!((d.length() - 1.0).abs() < 1e-6);
                assert_eq!(r.prev_p, o);
                assert_eq!(r.tmin.to_bits(), crate::intersect::FREE_ORIGIN.to_bits());
                assert_eq!(r.tmax, f32::INFINITY);
                assert_eq!(r.path, i as u32);
                assert_eq!(r.throughput, Rgb::WHITE);
                assert_eq!(r.lobe, LobeSampled::NONE);
                assert_eq!((r.depth, r.passes), (0, 0));
                assert_eq!((r.pdf, r.eta_scale), (0.0, 1.0));
                assert_eq!(r.dimension, FIRST_PATH_DIMENSION);
                assert_eq!(r.shading_ctx_index, u32::MAX);
                assert_eq!(r.volume_stack, stack);
            }
        }
    }

    /// A filtered camera's rays go through the pixel centre plus the filter's sample of
    /// the jitter dimensions (both ray generators, every projection), and reach beyond the
    /// pixel square, which the box-filtered camera's never do.
    #[test]
    fn filtered_camera_rays_go_through_the_filter_sample() {
        use crate::pixel_filter::GaussianFilter;
        let (w, h) = (9, 6);
        let filters = [
            PixelFilter::Tent { radius: 1.0 },
            PixelFilter::Gaussian(GaussianFilter::new(0.5, 2.0).unwrap()),
            PixelFilter::Box { radius: 1.5 },
        ];
        let projections = [
            Projection::Perspective { fov_deg: 50.0 },
            Projection::Orthographic { width: 3.0 },
            Projection::ThinLens {
                fov_deg: 35.0,
                aperture_radius: 0.2,
                focus_distance: 3.0,
            },
        ];
        let pixel: Vec<u32> = (0..w * h).flat_map(|p| [p; 16]).collect();
        let sample: Vec<u32> = (0..pixel.len() as u32).map(|i| i % 16).collect();
        let seed: Vec<u32> = pixel
            .iter()
            .map(|&p| crate::sampler::pixel_seed(3, p))
            .collect();
        for projection in projections {
            for filter in filters {
                let cam = Camera::look_at(
                    projection,
                    Vec3::new(0.5, 1.0, 4.0),
                    Vec3::new(0.0, 0.2, 0.0),
                    Vec3::Y,
                    w,
                    h,
                )
                .unwrap()
                .with_filter(filter);
                let mut rays = Rays::default();
                push_camera_rays(&cam, &pixel, &sample, &seed, &VolumeStack::new(), &mut rays);
                let n = pixel.len();
                let (mut o2, mut d2) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
                generate_camera_rays(&cam, &pixel, &sample, &seed, &mut o2, &mut d2);
                let mut outside = 0;
                for i in 0..n {
                    let u = sample_2d(seed[i], sample[i], 0);
                    let offset = Vec2::new(filter.sample_1d(u.x), filter.sample_1d(u.y));
                    let centre =
                        Vec2::new((pixel[i] % w) as f32, (pixel[i] / w) as f32) + Vec2::splat(0.5);
                    let film = centre + offset;
                    let lens = sample_2d(seed[i], sample[i], LENS_DIMENSION);
                    let (o, d) = cam.ray_through_lens(film, lens);
                    let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
                    assert!(close(rays.origin[i], o) && close(rays.direction[i], d));
                    assert!(close(o2[i], o) && close(d2[i], d));
                    outside += usize::from(offset.abs().max_element() > 0.5);
                }
                assert!(
                    outside > n / 20,
                    "{filter:?}: {outside} of {n} outside the pixel"
                );
            }
        }
    }

    fn thin_lens_camera(aperture_radius: f32, focus_distance: f32) -> Camera {
        Camera::look_at(
            Projection::ThinLens {
                fov_deg: 40.0,
                aperture_radius,
                focus_distance,
            },
            Vec3::new(1.0, 2.0, 6.0),
            Vec3::new(0.0, 0.5, 0.0),
            Vec3::Y,
            64,
            48,
        )
        .unwrap()
    }

    /// Every thin-lens ray of a film position crosses the focal plane (at `focus_distance`
    /// along the view direction) where the pinhole ray of that film position does, and
    /// starts on the lens disk (in the plane through `from` spanned by right and up).
    #[test]
    fn thin_lens_rays_meet_the_pinhole_ray_on_the_focal_plane() {
        let (radius, focus) = (0.3, 4.5);
        let cam = thin_lens_camera(radius, focus);
        let mut rng = crate::sampler::SplitMix64(11);
        let mut worst: f32 = 0.0;
        for _ in 0..200 {
            let film = rng.vec2() * Vec2::new(64.0, 48.0);
            let (o0, d0) = cam.ray(film);
            assert_eq!(o0, cam.from);
            // The pinhole ray's focal-plane point.
            let focal = o0 + d0 * (focus / d0.dot(cam.forward));
            for _ in 0..50 {
                let (o, d) = cam.ray_through_lens(film, rng.vec2());
                let rel = o - cam.from;
                assert!(
                    rel.dot(cam.forward).abs() < 1e-5,
                    "origin off the lens plane"
                );
                assert!(
                    rel.length() <= radius * (1.0 + 1e-5),
                    "origin off the lens disk"
                );
                assert!((d.length() - 1.0).abs() < 1e-5);
                let t = (focus - rel.dot(cam.forward)) / d.dot(cam.forward);
                worst = worst.max((o + d * t - focal).length());
            }
        }
        // Distances of about 5 world units: f32 rounding only.
        assert!(worst < 2e-5, "focal-plane miss {worst}");
    }

    /// The lens points are uniform over the disk: a chi-square test over 16 equal-area
    /// cells (4 rings of equal area x 4 quadrants) and the moments E[r^2] = R^2 / 2,
    /// E[x] = E[y] = 0, with the camera's own lens dimensions (the Sobol sampler's
    /// dimensions 2 and 3 across pixels and samples).
    #[test]
    fn thin_lens_origins_are_uniform_over_the_disk() {
        let radius = 0.5;
        let cam = thin_lens_camera(radius, 3.0);
        let (w, h) = (cam.width, cam.height);
        let pixel: Vec<u32> = (0..w * h).flat_map(|p| [p; 8]).collect();
        let sample: Vec<u32> = (0..pixel.len() as u32).map(|i| i % 8).collect();
        let seed: Vec<u32> = pixel
            .iter()
            .map(|&p| crate::sampler::pixel_seed(7, p))
            .collect();
        let mut rays = Rays::default();
        push_camera_rays(&cam, &pixel, &sample, &seed, &VolumeStack::new(), &mut rays);
        let n = rays.len();
        let mut counts = [0u32; 16];
        let (mut r2, mut mx, mut my) = (0.0f64, 0.0f64, 0.0f64);
        for o in &rays.origin {
            let rel = *o - cam.from;
            let (x, y) = (rel.dot(cam.right) / radius, rel.dot(cam.up) / radius);
            let q = x.powi(2) + y.powi(2);
            assert!(q <= 1.0 + 1e-5);
            let ring = ((q * 4.0) as usize).min(3);
            let quadrant = usize::from(x < 0.0) * 2 + usize::from(y < 0.0);
            counts[ring * 4 + quadrant] += 1;
            (r2, mx, my) = (r2 + q as f64, mx + x as f64, my + y as f64);
        }
        let expected = n as f64 / 16.0;
        let chi2: f64 = counts
            .iter()
            .map(|&c| (c as f64 - expected).powi(2) / expected)
            .sum();
        // 15 degrees of freedom: P(chi2 > 37.7) = 0.001.
        assert!(chi2 < 37.7, "chi2 {chi2}, counts {counts:?}");
        let n = n as f64;
        assert!((r2 / n - 0.5).abs() < 0.005, "E[r^2] {}", r2 / n);
        assert!((mx / n).abs() < 0.005 && (my / n).abs() < 0.005);
        // And the lens points are no constant: they differ between samples of a pixel.
        assert_ne!(rays.origin[0], rays.origin[1]);
    }

    /// `aperture_radius = 0` is the pinhole camera bit for bit (no lens dimension drawn).
    #[test]
    fn thin_lens_of_radius_zero_is_the_pinhole_camera() {
        let lens = thin_lens_camera(0.0, 2.0);
        let pinhole = Camera {
            projection: Projection::Perspective { fov_deg: 40.0 },
            ..lens
        };
        let pixel: Vec<u32> = (0..64 * 48).chain(0..37).collect();
        let sample: Vec<u32> = (0..pixel.len() as u32).map(|i| i % 3).collect();
        let seed: Vec<u32> = pixel.iter().map(|&p| p.wrapping_mul(0x9e37_79b9)).collect();
        let bits = |cam: &Camera| {
            let mut rays = Rays::default();
            push_camera_rays(cam, &pixel, &sample, &seed, &VolumeStack::new(), &mut rays);
            let (mut o, mut d) = (vec![Vec3::ZERO; pixel.len()], vec![Vec3::ZERO; pixel.len()]);
            generate_camera_rays(cam, &pixel, &sample, &seed, &mut o, &mut d);
            assert_eq!((&o, &d), (&rays.origin, &rays.direction));
            let bits = |v: &[Vec3]| -> Vec<[u32; 3]> {
                v.iter().map(|v| v.to_array().map(f32::to_bits)).collect()
            };
            (bits(&rays.origin), bits(&rays.direction))
        };
        assert_eq!(bits(&lens), bits(&pinhole));
        assert!(lens.projection.lens().is_none());
        assert!(thin_lens_camera(1e-6, 2.0).projection.lens().is_some());
    }

    #[test]
    fn degenerate_look_at_is_rejected() {
        let p = Projection::Perspective { fov_deg: 40.0 };
        assert!(Camera::look_at(p, Vec3::ZERO, Vec3::ZERO, Vec3::Y, 1, 1).is_none());
        assert!(Camera::look_at(p, Vec3::ZERO, Vec3::Y, Vec3::Y, 1, 1).is_none());
    }
}
