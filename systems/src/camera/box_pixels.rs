//! Which pixels' camera rays can meet a box: a conservative screen-space bound, so that work
//! only a ray through the box can use (the extra camera rays that look for directly visible
//! emitters) is skipped for every other pixel.
//!
//! For the perspective projection, a box wholly in front of the eye (every corner at a
//! positive depth along `forward`) projects into the convex hull of its corners' projections
//! (a central projection maps the segments of a convex set in front of the eye to segments),
//! so the corners' film positions bound the film position of every ray through the box.
//! For the orthographic projection every ray is parallel to `forward` and the same holds for
//! the corners projected along it. A pixel's film positions lie within the camera filter's
//! reach of its centre ([`crate::pixel_filter::warp_pixel_jitter`]: `0.5 +- radius`, the
//! pixel box `[0, 1)`), so the pixels are those whose reach overlaps the bound, widened by
//! one pixel for rounding (the rays are computed in `f32` from the film position, the bound
//! from the corners: both are within a few ulps of exact, far below a pixel).

use super::Camera;
use glam::{Vec2, Vec3};
use std::ops::Range;

/// A rectangle of pixels: columns `x`, rows `y` (possibly empty).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PixelRect {
    /// Columns, left to right.
    pub x: Range<u32>,
    /// Rows, top to bottom.
    pub y: Range<u32>,
}

impl PixelRect {
    /// Whether pixel `pixel` (row-major index into an image `width` pixels wide) is inside.
    #[inline]
    pub fn contains(&self, pixel: u32, width: u32) -> bool {
        self.x.contains(&(pixel % width)) && self.y.contains(&(pixel / width))
    }

    /// Whether no pixel is inside.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty() || self.y.is_empty()
    }
}

impl Camera {
    /// The pixels of the image whose camera rays may meet the axis-aligned box `[lo, hi]`:
    /// every pixel outside has no ray (at any sample, through any filter offset) that
    /// enters the box. `None` where the camera cannot bound them, so that every pixel may:
    /// a thin lens with an aperture (its rays start anywhere on the lens), a perspective
    /// camera with part of the box level with or behind the eye, or a box with a
    /// non-finite corner.
    pub fn pixels_seeing_box(&self, lo: Vec3, hi: Vec3) -> Option<PixelRect> {
        if self.projection.lens().is_some() || !(lo.is_finite() && hi.is_finite()) {
            return None;
        }
        let endpoint = self.endpoint();
        let (mut min, mut max) = (Vec2::INFINITY, Vec2::NEG_INFINITY);
        for corner in 0..8 {
            let p = Vec3::new(
                if corner & 1 == 0 { lo.x } else { hi.x },
                if corner & 2 == 0 { lo.y } else { hi.y },
                if corner & 4 == 0 { lo.z } else { hi.z },
            );
            // A direction from the eye for the perspective projection, the point itself for
            // the orthographic one (`CameraEndpoint::project`'s argument).
            let v = match self.projection {
                super::Projection::Orthographic { .. } => p,
                _ => p - self.from,
            };
            let film = endpoint.project(v)?;
            min = min.min(film);
            max = max.max(film);
        }
        // Pixel `x` holds film positions in `[x + 0.5 - reach, x + 0.5 + reach]`.
        let reach = self.filter.radius().max(0.5);
        let margin = 1.0;
        let first = (min - Vec2::splat(0.5 + reach + margin)).floor();
        let last = (max + Vec2::splat(reach + margin - 0.5)).ceil();
        let clip = |lo: f32, hi: f32, size: u32| -> Range<u32> {
            // Saturating float-to-int conversion: film positions far off the image (a box
            // just in front of the eye) clip to its border.
            let start = (lo.max(0.0) as u32).min(size);
            let end = ((hi + 1.0).max(0.0) as u32).min(size);
            start..end.max(start)
        };
        Some(PixelRect {
            x: clip(first.x, last.x, self.width),
            y: clip(first.y, last.y, self.height),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Projection;
    use crate::pixel_filter::PixelFilter;
    use crate::splitmix::SplitMix64;

    /// Whether the ray `o + t d`, `t > 0`, meets the box `[lo, hi]` (slab test).
    fn ray_meets_box(o: Vec3, d: Vec3, lo: Vec3, hi: Vec3) -> bool {
        let inv = d.recip();
        let (t0, t1) = ((lo - o) * inv, (hi - o) * inv);
        let near = t0.min(t1).max_element().max(0.0);
        let far = t0.max(t1).min_element();
        near <= far
    }

    fn camera(projection: Projection, filter: PixelFilter) -> Camera {
        Camera::look_at(
            projection,
            Vec3::new(0.3, 0.2, 4.0),
            Vec3::ZERO,
            Vec3::Y,
            96,
            64,
        )
        .unwrap()
        .with_filter(filter)
    }

    /// Every pixel with a ray (dense film positions over the filter's reach) that meets the
    /// box is inside the rectangle, and the rectangle is not the whole image: checked over
    /// boxes anywhere in front of the camera, for both projections and wide filters.
    #[test]
    fn every_pixel_whose_rays_meet_the_box_is_inside() {
        // Each projection with the pixel box and with a filter reaching past the pixel.
        let cameras = [
            (
                Projection::Perspective { fov_deg: 50.0 },
                PixelFilter::Tent { radius: 2.0 },
            ),
            (
                Projection::Orthographic { width: 3.0 },
                PixelFilter::Box { radius: 1.5 },
            ),
        ]
        .into_iter()
        .flat_map(|(p, wide)| [camera(p, PixelFilter::PIXEL_BOX), camera(p, wide)]);
        let mut rng = SplitMix64(7);
        let mut u = || rng.f32();
        for cam in cameras {
            let reach = cam.filter.radius().max(0.5);
            let (mut inside_some, mut smaller) = (0, 0);
            for _ in 0..40 {
                let c = Vec3::new(4.0 * u() - 2.0, 3.0 * u() - 1.5, 2.0 * u() - 1.0);
                let half = Vec3::new(0.4 * u(), 0.3 * u(), 0.2 * u());
                let (lo, hi) = (c - half, c + half);
                let rect = cam
                    .pixels_seeing_box(lo, hi)
                    .expect("box in front of the eye");
                assert!(rect.x.end <= cam.width && rect.y.end <= cam.height);
                let (w, h) = (cam.width, cam.height);
                for py in 0..h {
                    for px in 0..w {
                        // Film positions over the pixel's reach, its border included.
                        let steps = 6;
                        let mut seen = false;
                        for i in 0..=steps {
                            for j in 0..=steps {
                                let off =
                                    |k: u32| 0.5 - reach + 2.0 * reach * k as f32 / steps as f32;
                                let film = Vec2::new(px as f32 + off(i), py as f32 + off(j));
                                let (o, d) = cam.ray(film);
                                seen |= ray_meets_box(o, d, lo, hi);
                            }
                        }
                        if seen {
                            inside_some += 1;
                            assert!(
                                rect.contains(py * w + px, w),
                                "pixel ({px}, {py}) sees the box [{lo}, {hi}] outside {rect:?}"
                            );
                        }
                    }
                }
                smaller += usize::from((rect.x.len() as u32) < w || (rect.y.len() as u32) < h);
            }
            assert!(
                inside_some > 100,
                "too few pixels see a box ({inside_some})"
            );
            // The bound is useful: most boxes leave some pixels out.
            assert!(smaller > 30, "{smaller} of 40 boxes bound pixels away");
        }
    }

    /// A small box far from the view axis bounds a small rectangle around its projection;
    /// one behind the image bounds no pixel.
    #[test]
    fn a_small_box_bounds_a_few_pixels() {
        let cam = camera(
            Projection::Perspective { fov_deg: 50.0 },
            PixelFilter::PIXEL_BOX,
        );
        let film = cam
            .endpoint()
            .project(Vec3::new(0.5, 0.4, 0.0) - cam.from)
            .unwrap();
        let e = Vec3::splat(0.01);
        let rect = cam
            .pixels_seeing_box(Vec3::new(0.5, 0.4, 0.0) - e, Vec3::new(0.5, 0.4, 0.0) + e)
            .unwrap();
        assert!(rect.x.contains(&(film.x as u32)) && rect.y.contains(&(film.y as u32)));
        // Half a pixel of box, the pixel reach and the margin on both sides, rounded out.
        assert!(rect.x.len() <= 6 && rect.y.len() <= 6, "{rect:?}");
        // Far to the right of the view: off the image.
        let off = Vec3::new(40.0, 0.0, 0.0);
        let rect = cam.pixels_seeing_box(off - e, off + e).unwrap();
        assert!(rect.is_empty(), "{rect:?}");
    }

    /// No bound where the camera cannot give one: a box reaching behind a perspective
    /// camera's eye, a lens with an aperture, a non-finite box.
    #[test]
    fn no_bound_behind_the_eye_through_a_lens_or_for_a_non_finite_box() {
        let cam = camera(
            Projection::Perspective { fov_deg: 50.0 },
            PixelFilter::PIXEL_BOX,
        );
        assert_eq!(
            cam.pixels_seeing_box(Vec3::splat(-1.0), Vec3::splat(5.0)),
            None
        );
        assert_eq!(
            cam.pixels_seeing_box(Vec3::splat(-1.0), Vec3::new(1.0, 1.0, f32::INFINITY)),
            None
        );
        let lens = camera(
            Projection::ThinLens {
                fov_deg: 50.0,
                aperture_radius: 0.1,
                focus_distance: 4.0,
            },
            PixelFilter::PIXEL_BOX,
        );
        assert_eq!(
            lens.pixels_seeing_box(Vec3::splat(-0.1), Vec3::splat(0.1)),
            None
        );
    }
}
