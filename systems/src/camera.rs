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

mod box_pixels;
pub use box_pixels::PixelRect;
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
mod tests;
