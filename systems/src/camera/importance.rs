//! The camera as an endpoint of light subpaths: importance, raster position and pdfs.
//!
//! Light tracing, BDPT and VCM connect light-subpath vertices to the camera and add their
//! contribution at the film position the connection projects to (Veach's thesis, sec.
//! 10.2; pbrt-v4's `PerspectiveCamera::We`, `PDF_We` and `SampleWi`, `cameras.cpp`, and
//! Pharr, Jakob, Humphreys, *Physically Based Rendering*, 3rd ed., sec. 16.1.1; SmallVCM's
//! `camera.hxx`). Everything here inverts [`Camera::ray`] / [`Camera::ray_through_lens`]
//! exactly: the same screen mapping, horizontal field of view, focal plane and concentric
//! lens map.
//!
//! # Normalisation
//!
//! A light subpath of throughput `beta` arriving at point `p`, whose Bxdf sends `f |cos_p|`
//! towards the camera along [`CameraConnection::wi`] with transmittance `T`, contributes
//! `beta * f * |cos_p| * T * importance` at film position [`CameraConnection::film`], spread
//! over the pixels by [`crate::pixel_filter::splat_weights`]. The image is then (sum of the
//! splats) `* width * height / N`, `N` the number of light subpaths traced; each pixel is
//! then the filter-weighted mean radiance the path tracer's camera rays estimate (for the
//! pixel box, the mean radiance over the pixel).
//!
//! Derivation, for a pinhole with horizontal field of view `fov` on a `w x h` image: the
//! image spans the rectangle `[-s, s] x [-s h/w, s h/w]` (`s = tan(fov / 2)`) on the plane
//! at distance 1 along `forward`, of area `A = 4 s^2 h / w`. The camera draws film positions
//! uniformly over it (for the pixel box), so the direction `w` at angle `theta` from
//! `forward` has solid-angle density `pdf_dir = 1 / (A cos^3 theta)` (the plane's area
//! density times `dist^2 / cos = 1 / cos^3`). With `We = 1 / (A cos^4 theta)`, `int We cos
//! dw = 1` over the image and the whole-image measurement is its mean radiance; a pixel is
//! `1 / (w h)` of that area, hence the factor `w * h`. The pinhole's position is a Dirac
//! delta, so connecting to it costs `We` times the camera-side geometry term `cos theta /
//! d^2`: `importance = 1 / (A cos^3 theta d^2)`.
//!
//! The thin lens (radius `r`, focal plane at `focus_distance`) samples its lens point
//! uniformly (area density `1 / (pi r^2)`) and `We = 1 / (A pi r^2 cos^4 theta)`, `theta`
//! the angle of the ray from the lens point; connecting through lens point `y` divides by
//! the lens density, so `importance = 1 / (A cos^3 theta d^2)` again, and `pdf_dir = 1 / (A
//! cos^3 theta)` (the focal plane's point is uniform over `A focus^2`, at distance `focus /
//! cos theta` from the lens point). The film position is where the ray from `y` through `p`
//! meets the focal plane, seen from the lens centre.
//!
//! The orthographic camera's rays start uniformly on the film rectangle, of area
//! `A_o = width^2 h / w` in world units, all along `forward` (a Dirac direction). A point `p`
//! projects along `forward` to its film point, and a film area `dA` sees `dA / |cos_p|` of
//! the surface, so `importance = 1 / A_o` (no distance term), and the camera's "direction
//! density" is the film-position density `1 / A_o` per unit area perpendicular to `forward`
//! ([`Camera::pdf_area`] converts both kinds to an area density at a hit).
//!
//! # Pixel filters
//!
//! `importance` does not depend on the filter: the filter enters through the splat weights.
//! A filter wider than the pixel box makes the camera draw film positions up to its reach
//! outside the image, so [`Camera::connect`] accepts points projecting there, and the
//! camera's densities carry the factor [`crate::pixel_filter::film_coverage`] (1 inside
//! the image for the pixel box): the density with which the filter-sampled camera draws a
//! film position, relative to uniform over the image.

use super::{Camera, Projection, RayGenerator};
use crate::pixel_filter::film_coverage;
use crate::warp::sample_concentric_disk;
use glam::{Vec2, Vec3};

/// A light-subpath vertex seen by the camera ([`Camera::connect`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraConnection {
    /// Film position in pixels ((0,0) the top-left corner of the image): the film position
    /// whose camera ray (through the same lens point) passes through the vertex.
    pub film: Vec2,
    /// The camera vertex: `from` for pinholes, the lens point of the lens sample (thin
    /// lens), the film-plane point the vertex projects to (orthographic).
    pub lens_point: Vec3,
    /// Unit direction from the vertex towards `lens_point`.
    pub wi: Vec3,
    /// `|lens_point - p|`.
    pub distance: f32,
    /// Sensor importance `We` times the camera-side geometry factor, over the density of
    /// choosing `lens_point`: times the light subpath's throughput, `f |cos|` at the vertex
    /// towards `wi` and the transmittance, the value to splat (the module's
    /// normalisation).
    pub importance: f32,
    /// Density with which the camera samples the ray `(lens_point, -wi)`: per solid angle
    /// for the perspective projections (pbrt-v4's `PDF_We` `pdfDir`, SmallVCM's
    /// `cameraPdfW`), per unit film area for the orthographic one ([`Camera::pdf_area`]).
    pub pdf_dir: f32,
}

impl Camera {
    /// Area of the image on the plane at distance 1 along `forward` (perspective: `4
    /// tan^2(fov / 2) h / w`) or of the film rectangle in world units (orthographic:
    /// `width^2 h / w`).
    pub fn film_area(&self) -> f32 {
        self.endpoint().area
    }

    /// Area of the lens: `pi r^2` for a thin lens with an aperture, 1 otherwise (the pinhole
    /// and the orthographic film position are handled as Dirac positions, as pbrt-v4 does).
    pub fn lens_area(&self) -> f32 {
        match self.projection.lens() {
            Some((radius, _)) => std::f32::consts::PI * radius * radius,
            None => 1.0,
        }
    }

    /// [`film_coverage`] of the camera's filter at `film`.
    #[inline]
    fn coverage(&self, film: Vec2) -> f32 {
        film_coverage(&self.filter, film, self.width, self.height)
    }

    /// The inverse of [`Camera::ray`]: the film position of a ray direction `p` from the eye
    /// (pinhole, or the lens centre of a thin lens) or, for the orthographic projection,
    /// of a point `p` (projected along `forward` whatever its depth: a ray's origin lies on
    /// the film plane up to rounding). `None` when no pixel's filter covers the position
    /// (outside the image, by more than the filter reaches for filters wider than the pixel
    /// box) or when the direction `p` points behind a perspective camera.
    pub fn raster_of(&self, p: Vec3) -> Option<Vec2> {
        let film = self.endpoint().project(p)?;
        (self.coverage(film) > 0.0).then_some(film)
    }

    /// The density of the camera ray from `origin` along unit direction `d`: per solid angle
    /// `coverage / (A cos^3 theta)` for the perspective projections (`origin` a lens point;
    /// the film position is where the ray meets the focal plane), per unit film area
    /// `coverage / A_o` for the orthographic one (`origin` on the film; `d` must point along
    /// `forward`). 0 outside the image or behind the camera. Many rays:
    /// [`CameraEndpoint::pdf_ray`].
    pub fn pdf_ray(&self, origin: Vec3, d: Vec3) -> f32 {
        self.endpoint().pdf_ray(origin, d)
    }

    /// [`Camera::pdf_ray`] of a camera ray with direction `d` from the eye (the lens centre
    /// of a thin lens): what [`Camera::connect`] reports as `pdf_dir`; 0 outside the image.
    /// For the orthographic projection, the density of the ray through the film centre.
    pub fn pdf_direction(&self, d: Vec3) -> f32 {
        self.pdf_ray(self.from, d)
    }

    /// The camera's density `pdf_dir` of a ray (from [`Camera::pdf_ray`]) converted to an
    /// area density at the surface it reaches at `distance`, where the cosine between the
    /// ray and the surface normal is `cos_hit`: `pdf_dir |cos_hit| / distance^2` for the
    /// perspective projections, `pdf_dir |cos_hit|` for the orthographic one (its film
    /// area projects along parallel rays).
    pub fn pdf_area(&self, pdf_dir: f32, distance: f32, cos_hit: f32) -> f32 {
        match self.projection {
            Projection::Orthographic { .. } => pdf_dir * cos_hit.abs(),
            _ => pdf_dir * cos_hit.abs() / (distance * distance),
        }
    }

    /// The direction from the lens centre to the focal-plane point of the ray from `origin`
    /// along `d` (`d` itself for a camera without lens, where the origin is the eye).
    #[inline]
    fn focal_direction(&self, origin: Vec3, d: Vec3) -> Vec3 {
        match self.projection.lens() {
            // The ray meets the focal plane at `origin + d t`, `t = (focus - z0) / (d .
            // forward)`, `z0` the origin's depth (0 on the lens).
            Some((_, focus)) => {
                let rel = origin - self.from;
                let t = (focus - rel.dot(self.forward)) / d.dot(self.forward);
                rel + d * t
            }
            None => d,
        }
    }

    /// The lens point of lens sample `u` (the concentric map of `thin_lens`), or the eye.
    #[inline]
    fn lens_point(&self, u: Vec2) -> Vec3 {
        match self.projection.lens() {
            Some((radius, _)) => {
                let disk = sample_concentric_disk(u) * radius;
                self.from + self.right * disk.x + self.up * disk.y
            }
            None => self.from,
        }
    }

    /// Connects point `p` to the camera through the lens point of lens sample `u_lens` (a
    /// thin lens with an aperture; ignored otherwise): the film position, camera vertex,
    /// direction, distance, importance and direction density of the module's
    /// normalisation. `None` when `p` is behind the camera (or on its lens / film plane) or
    /// projects where no pixel's filter reaches. Many points: [`CameraEndpoint::connect`].
    pub fn connect(&self, p: Vec3, u_lens: Vec2) -> Option<CameraConnection> {
        self.endpoint().connect(p, u_lens)
    }

    /// The camera with the constants of [`Camera::connect`] and [`Camera::pdf_ray`] computed
    /// once, for many points or rays (each call would otherwise take the tangent of the half
    /// field of view twice, a libm call, more than the rest of a connection).
    pub fn endpoint(&self) -> CameraEndpoint {
        let gen = self.ray_generator();
        let area = 4.0 * gen.scale * gen.scale * gen.h / gen.w;
        CameraEndpoint { gen, area }
    }
}

/// A [`Camera`] as the end of light subpaths, its constants hoisted ([`Camera::endpoint`]).
pub struct CameraEndpoint {
    gen: RayGenerator,
    /// [`Camera::film_area`].
    area: f32,
}

impl CameraEndpoint {
    /// The film position of `v` without the image test: `v` a direction from the eye
    /// (perspective projections; `None` unless in front) or a point (orthographic). The
    /// inverse of `RayGenerator::screen` and the ray construction.
    #[inline]
    pub(super) fn project(&self, v: Vec3) -> Option<Vec2> {
        let gen = &self.gen;
        let c = &gen.camera;
        let (a, b) = match c.projection {
            Projection::Perspective { .. } | Projection::ThinLens { .. } => {
                let z = v.dot(c.forward);
                if !positive(z) {
                    return None;
                }
                (v.dot(c.right) / z, v.dot(c.up) / z)
            }
            Projection::Orthographic { .. } => {
                let rel = v - c.from;
                (rel.dot(c.right), rel.dot(c.up))
            }
        };
        // screen: sx = 2 x / w - 1, sy = (1 - 2 y / h) h / w, and (a, b) = scale (sx, sy).
        let (sx, sy) = (a / gen.scale, b / gen.scale);
        let film = Vec2::new(
            0.5 * gen.w * (sx + 1.0),
            0.5 * gen.h * (1.0 - sy * gen.w / gen.h),
        );
        film.is_finite().then_some(film)
    }

    /// The density of the camera ray from `origin` along unit direction `d`: per solid angle
    /// `coverage / (A cos^3 theta)` for the perspective projections (`origin` a lens point;
    /// the film position is where the ray meets the focal plane), per unit film area
    /// `coverage / A_o` for the orthographic one (`origin` on the film; `d` must point along
    /// `forward`). 0 outside the image or behind the camera.
    pub fn pdf_ray(&self, origin: Vec3, d: Vec3) -> f32 {
        let c = &self.gen.camera;
        let cos = d.dot(c.forward);
        if !positive(cos) {
            return 0.0;
        }
        let film = match c.projection {
            Projection::Orthographic { .. } => self.project(origin),
            Projection::Perspective { .. } | Projection::ThinLens { .. } => {
                self.project(c.focal_direction(origin, d))
            }
        };
        let Some(film) = film else { return 0.0 };
        let coverage = c.coverage(film);
        match c.projection {
            Projection::Orthographic { .. } => coverage / self.area,
            _ => coverage / (self.area * cos * cos * cos),
        }
    }

    /// Connects point `p` to the camera through the lens point of lens sample `u_lens` (a
    /// thin lens with an aperture; ignored otherwise): the film position, camera vertex,
    /// direction, distance, importance and direction density of the module's
    /// normalisation. `None` when `p` is behind the camera (or on its lens / film plane) or
    /// projects where no pixel's filter reaches.
    pub fn connect(&self, p: Vec3, u_lens: Vec2) -> Option<CameraConnection> {
        let c = &self.gen.camera;
        if let Projection::Orthographic { .. } = c.projection {
            let depth = (p - c.from).dot(c.forward);
            if !positive(depth) {
                return None;
            }
            let film = self.project(p)?;
            let coverage = c.coverage(film);
            if !positive(coverage) {
                return None;
            }
            let area = self.area;
            return Some(CameraConnection {
                film,
                lens_point: p - c.forward * depth,
                wi: -c.forward,
                distance: depth,
                importance: 1.0 / area,
                pdf_dir: coverage / area,
            });
        }
        let lens_point = c.lens_point(u_lens);
        let to_p = p - lens_point;
        let distance = to_p.length();
        let d = to_p / distance;
        let cos = d.dot(c.forward);
        if !(positive(cos) && distance.is_finite()) {
            return None;
        }
        let film = self.project(c.focal_direction(lens_point, d))?;
        let coverage = c.coverage(film);
        if !positive(coverage) {
            return None;
        }
        let pdf_w = 1.0 / (self.area * cos * cos * cos);
        Some(CameraConnection {
            film,
            lens_point,
            wi: -d,
            distance,
            importance: pdf_w / (distance * distance),
            pdf_dir: coverage * pdf_w,
        })
    }
}

/// `x > 0`, false for NaN: the test that refuses points behind the camera and positions no
/// pixel covers, NaN included.
#[inline]
fn positive(x: f32) -> bool {
    x > 0.0
}

#[cfg(test)]
mod tests;
