//! An equirectangular (latitude-longitude) environment map: radiance arriving from every
//! direction at infinity, looked up nearest-texel or bilinearly, optionally rotated, and
//! importance sampled with a density that is exactly the one its `pdf` reports.
//!
//! **Direction convention** (the scene format's, see `docs/scene-format.md`): `+y` is up,
//! `u = 0.5 + atan2(x, -z) / 2π` runs from `+z` (`u = 0`) through `-x` (0.25), `-z` (0.5,
//! the image centre) and `+x` (0.75); `v = acos(y) / π` runs from straight up (`v = 0`, the
//! top row) to straight down. Mitsuba 3's `envmap` uses the same axes and the same sense
//! of `u` but puts `u = 0` at `-z` (`u = atan2(x, -z) / 2π`): the two differ by a half
//! turn about `y`, which the loader's `convention = "mitsuba"` composes into the rotation.
//!
//! **Bilinear lookup** uses Mitsuba 3's lattice (`src/emitters/envmap.cpp`,
//! `eval_spectrum`): column `i`'s centre is at `u = (i + 1/2) / w` and wraps across the
//! seam, row `j`'s centre at `v = j / (h - 1)` (the first and last rows sit on the poles).
//!
//! **Sampling** for the bilinear lookup follows pbrt-v4's `ImageInfiniteLight` idea (Pharr,
//! Jakob, Humphreys, *Physically Based Rendering*, 4th ed., §12.5.2): a piecewise-constant
//! density over the cells of the lattice, each cell weighted by the exact `(u, v)` average
//! of the bilinear radiance over it (the mean of its four corner texels) times the mean of
//! `sin θ` over its row of cells, `(cos θ0 - cos θ1) / (θ1 - θ0)`. The density is then an
//! approximation of radiance × `sin θ` (exact up to the variation of the bilinear
//! interpolant within a cell), and it is positive wherever the interpolated radiance is,
//! because a cell's radiance is positive somewhere only when one of its corners is. The
//! pdf reported is the sampler's own, exactly, so MIS weights are right. The change of
//! variables from `(u, v)` to solid angle is `p(ω) = p(u, v) / (2π² sin θ)` (PBR 3rd ed.
//! §14.2.4). A rotation preserves solid angle, so it changes no density.
//!
//! **Equal-area octahedral maps** ([`EnvProjection::EqualArea`], pbrt-v4's image infinite
//! lights; the mapping is in [`equal_area`]) are square, looked up nearest-texel as pbrt
//! does, and sampled piecewise constant over their texels in proportion to the texel's
//! channel average: every texel covers the same solid angle, `4π / (w h)`, so no `sin θ`
//! enters, and `p(ω) = p(u, v) / 4π`. Their own frame is pbrt's light frame (`+z` the
//! centre of the square), carried into the world by the same rotation.

use std::f32::consts::PI;

use glam::{Mat3, Vec2, Vec3};
use risotto_components::Rgb;

use crate::distribution::{bin_of, Distribution2D};

pub mod equal_area;
#[cfg(test)]
mod tests;

/// How an [`EnvironmentMap`]'s texels are laid over the sphere of directions.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum EnvProjection {
    /// Latitude-longitude ([`dir_to_uv`]), `+y` up: the scene format's and Mitsuba's.
    #[default]
    LatLong,
    /// pbrt-v4's equal-area octahedral square ([`equal_area`]), `+z` at its centre;
    /// nearest-texel only.
    EqualArea,
}

/// How an [`EnvironmentMap`] is looked up between texel centres.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum EnvFilter {
    /// Each texel is a constant patch of the sphere: column `i` covers `u` in
    /// `[i / w, (i + 1) / w)`, row `j` covers `v` in `[j / h, (j + 1) / h)`.
    Nearest,
    /// Bilinear between texel centres on Mitsuba 3's lattice (see the module docs).
    #[default]
    Bilinear,
}

/// Map coordinates of a direction, using the scene format's equirectangular convention:
/// `+y` up, `u = 0.5 + atan2(x, -z) / 2π`, `v = acos(y) / π` (so `-z` is the centre of the
/// map, `+x` is at `u = 0.75`, the top row is straight up). `u = 1` wraps to 0.
#[inline]
pub fn dir_to_uv(dir: Vec3) -> Vec2 {
    let mut u = 0.5 + dir.x.atan2(-dir.z) * (0.5 / PI);
    if u >= 1.0 {
        u -= 1.0;
    }
    let v = dir.y.clamp(-1.0, 1.0).acos() * (1.0 / PI);
    Vec2::new(u.max(0.0), v)
}

/// Inverse of [`dir_to_uv`]: `φ = 2π (u - 0.5)`, `θ = π v`,
/// `dir = (sin θ sin φ, cos θ, -sin θ cos φ)`.
#[inline]
pub fn uv_to_dir(uv: Vec2) -> Vec3 {
    let (sin_phi, cos_phi) = (2.0 * PI * (uv.x - 0.5)).sin_cos();
    let (sin_theta, cos_theta) = (PI * uv.y).sin_cos();
    Vec3::new(sin_theta * sin_phi, cos_theta, -sin_theta * cos_phi)
}

/// An equirectangular environment map (radiance per texel, row 0 at the top, i.e. `v = 0`,
/// direction `+y`), see [`dir_to_uv`] for the direction convention, looked up through an
/// [`EnvFilter`] and carried into the world by a rotation `to_world` (directions in the
/// map's own frame are `to_world⁻¹ ω`).
///
/// With [`EnvFilter::Nearest`] each texel is a constant-radiance patch of the sphere and the
/// sampling density is piecewise constant over the same patches, so within a texel the
/// estimator `L / p` only varies with `sin θ`. With [`EnvFilter::Bilinear`] the density is
/// piecewise constant over the bilinear lattice's cells (module docs).
#[derive(Clone, Debug)]
pub struct EnvironmentMap {
    width: usize,
    height: usize,
    pixels: Vec<Rgb>,
    filter: EnvFilter,
    projection: EnvProjection,
    /// Map frame to world (a rotation); `None` for the identity, which then costs nothing.
    rotation: Option<Rotation>,
    /// Over texels (nearest) or over the bilinear lattice's cells, `width x cell_rows`.
    dist: Distribution2D,
}

/// A rotation and its inverse.
#[derive(Clone, Copy, Debug)]
struct Rotation {
    to_world: Mat3,
    to_local: Mat3,
}

/// Rows of cells of the bilinear lattice: `h - 1` between `h` row centres (one for a
/// single-row map, which is then constant in `v`).
fn cell_rows(height: usize) -> usize {
    height.saturating_sub(1).max(1)
}

/// A texel's channel average for sampling weights: non-finite and negative count as 0.
/// Average, not luminance: every channel > 0 must give a density > 0, or radiance in that
/// channel would never be sampled (bias).
fn weight_of(p: Rgb) -> f32 {
    p.map(|c| if c.is_finite() { c.max(0.0) } else { 0.0 })
        .average()
}

impl EnvironmentMap {
    /// A nearest-texel, unrotated map from `width * height` texels (row-major, top row
    /// first).
    ///
    /// The sampling density is proportional to each texel's channel average times the
    /// solid angle of its row. The solid angle of row `j` is
    /// `Δφ (cos θ_j - cos θ_{j+1}) = Δφ · 2 sin(θ_mid) sin(π / 2h)`, i.e. proportional to
    /// `sin θ_mid`, which is the weight used (PBR 3rd ed. §14.2.4).
    ///
    /// # Panics
    /// When the dimensions are zero or do not match `pixels.len()`.
    pub fn new(pixels: Vec<Rgb>, width: usize, height: usize) -> Self {
        Self::with_filter(pixels, width, height, EnvFilter::Nearest, Mat3::IDENTITY)
    }

    /// A map looked up with `filter` and rotated by `to_world` (map frame to world; it must
    /// be a rotation, or a rotation with a mirror: the caller checks that it is
    /// orthonormal). Directions are renormalised after the inverse rotation, so rounding in
    /// `to_world` cannot push them off the sphere.
    ///
    /// # Panics
    /// When the dimensions are zero or do not match `pixels.len()`.
    pub fn with_filter(
        pixels: Vec<Rgb>,
        width: usize,
        height: usize,
        filter: EnvFilter,
        to_world: Mat3,
    ) -> Self {
        Self::with_projection(
            pixels,
            width,
            height,
            EnvProjection::LatLong,
            filter,
            to_world,
        )
    }

    /// [`Self::with_filter`] for a map laid out by `projection`. An
    /// [`EnvProjection::EqualArea`] map is looked up nearest-texel whatever `filter` says
    /// (the loader refuses a bilinear one).
    ///
    /// # Panics
    /// When the dimensions are zero or do not match `pixels.len()`.
    pub fn with_projection(
        pixels: Vec<Rgb>,
        width: usize,
        height: usize,
        projection: EnvProjection,
        filter: EnvFilter,
        to_world: Mat3,
    ) -> Self {
        assert!(
            width > 0 && height > 0 && pixels.len() == width * height,
            "EnvironmentMap::new: {} texels for {width}x{height}",
            pixels.len()
        );
        let filter = match projection {
            EnvProjection::LatLong => filter,
            EnvProjection::EqualArea => EnvFilter::Nearest,
        };
        let dist = match (projection, filter) {
            // Every texel covers the same solid angle.
            (EnvProjection::EqualArea, _) => {
                let weights: Vec<f32> = pixels.iter().map(|&p| weight_of(p)).collect();
                Distribution2D::new(&weights, width, height)
            }
            (_, EnvFilter::Nearest) => {
                let mut weights = Vec::with_capacity(pixels.len());
                for (j, row) in pixels.chunks_exact(width).enumerate() {
                    let sin_theta = (PI * (j as f32 + 0.5) / height as f32).sin();
                    weights.extend(row.iter().map(|&p| weight_of(p) * sin_theta));
                }
                Distribution2D::new(&weights, width, height)
            }
            (_, EnvFilter::Bilinear) => {
                let rows = cell_rows(height);
                let mut weights = Vec::with_capacity(width * rows);
                for j in 0..rows {
                    let (r0, r1) = (j * width, (j + 1).min(height - 1) * width);
                    // Mean of sin θ over the row of cells: ∫ sin θ dθ / Δθ.
                    let (t0, t1) = (
                        PI * j as f32 / rows as f32,
                        PI * (j + 1) as f32 / rows as f32,
                    );
                    let sin_mean = (t0.cos() - t1.cos()) / (t1 - t0);
                    weights.extend((0..width).map(|i| {
                        let i1 = (i + 1) % width;
                        let corners = [r0 + i, r0 + i1, r1 + i, r1 + i1];
                        let mean: f32 = corners.iter().map(|&k| weight_of(pixels[k])).sum();
                        0.25 * mean * sin_mean
                    }));
                }
                Distribution2D::new(&weights, width, rows)
            }
        };
        let rotation = (to_world != Mat3::IDENTITY).then(|| Rotation {
            to_world,
            to_local: to_world.inverse(),
        });
        EnvironmentMap {
            width,
            height,
            pixels,
            filter,
            projection,
            rotation,
            dist,
        }
    }

    /// How the texels are laid over the sphere.
    pub fn projection(&self) -> EnvProjection {
        self.projection
    }

    /// Map coordinates of the map-frame direction `local`.
    #[inline]
    fn uv_of(&self, local: Vec3) -> Vec2 {
        match self.projection {
            EnvProjection::LatLong => dir_to_uv(local),
            EnvProjection::EqualArea => equal_area::sphere_to_square(local),
        }
    }

    /// Map width in texels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Map height in texels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The lookup filter.
    pub fn filter(&self) -> EnvFilter {
        self.filter
    }

    /// The texel at map coordinates `uv` (nearest neighbour, whatever the filter).
    #[inline]
    pub fn lookup_uv(&self, uv: Vec2) -> Rgb {
        self.pixels[bin_of(uv.y, self.height) * self.width + bin_of(uv.x, self.width)]
    }

    /// Bilinear interpolation at map coordinates `uv` on Mitsuba 3's lattice (module docs):
    /// wraps in `u`, clamps to the pole rows in `v`.
    #[inline]
    pub fn bilinear_uv(&self, uv: Vec2) -> Rgb {
        let (w, h) = (self.width, self.height);
        let x = uv.x * w as f32 - 0.5;
        let xf = x.floor();
        // NaN (from a NaN direction) falls back to texel 0 without interpolation.
        let fx = if x - xf >= 0.0 { x - xf } else { 0.0 };
        let i0 = (xf as isize).rem_euclid(w as isize) as usize;
        let i1 = if i0 + 1 == w { 0 } else { i0 + 1 };
        let y = uv.y * (h - 1) as f32;
        let j0 = (y as usize).min(h.saturating_sub(2));
        let fy = if h > 1 {
            (y - j0 as f32).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let j1 = (j0 + 1).min(h - 1);
        let px = &self.pixels;
        let top = px[j0 * w + i0] * (1.0 - fx) + px[j0 * w + i1] * fx;
        let bottom = px[j1 * w + i0] * (1.0 - fx) + px[j1 * w + i1] * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The map's own frame's direction for the world direction `dir`.
    #[inline]
    fn to_local(&self, dir: Vec3) -> Vec3 {
        match &self.rotation {
            Some(r) => (r.to_local * dir).normalize_or_zero(),
            None => dir,
        }
    }

    /// Radiance at map coordinates `uv` through the map's filter.
    #[inline]
    fn filtered(&self, uv: Vec2) -> Rgb {
        match self.filter {
            EnvFilter::Nearest => self.lookup_uv(uv),
            EnvFilter::Bilinear => self.bilinear_uv(uv),
        }
    }

    /// Radiance arriving from direction `dir` (unit vector pointing away from the scene,
    /// in world space).
    #[inline]
    pub fn eval(&self, dir: Vec3) -> Rgb {
        self.filtered(self.uv_of(self.to_local(dir)))
    }

    /// Samples a direction proportionally to (approximately, for the bilinear filter)
    /// radiance × solid angle. Returns `(dir, radiance, pdf)` with the pdf per unit solid
    /// angle. The radiance and pdf are exactly [`eval`](Self::eval)`(dir)` and
    /// [`pdf`](Self::pdf)`(dir)`, so MIS weights computed later from `pdf(dir)` agree with
    /// the sampler. At the poles (`sin θ = 0`) the pdf is 0 and the caller should discard
    /// the sample.
    pub fn sample(&self, u: Vec2) -> (Vec3, Rgb, f32) {
        let (cell_uv, _) = self.dist.sample(u);
        let local = match (self.projection, self.filter) {
            (EnvProjection::EqualArea, _) => equal_area::square_to_sphere(cell_uv),
            (_, EnvFilter::Nearest) => uv_to_dir(cell_uv),
            (_, EnvFilter::Bilinear) => uv_to_dir(Vec2::new(
                wrap_unit(cell_uv.x + self.half_texel()),
                cell_uv.y,
            )),
        };
        let dir = match &self.rotation {
            Some(r) => (r.to_world * local).normalize_or_zero(),
            None => local,
        };
        // Re-derive (u, v) from the direction (once) so radiance and pdf are those that
        // `eval(dir)` / `pdf(dir)` compute, even where rounding crosses a cell edge.
        let local = self.to_local(dir);
        let uv = self.uv_of(local);
        (dir, self.filtered(uv), self.pdf_uv_dir(uv, local))
    }

    /// Solid-angle density of [`sample`](Self::sample) in (world) direction `dir`:
    /// `p(ω) = p(u, v) / (2π² sin θ)` (the Jacobian of `(u, v) -> ω` is `2π · π · sin θ`),
    /// or `p(u, v) / 4π` for an equal-area map.
    pub fn pdf(&self, dir: Vec3) -> f32 {
        let local = self.to_local(dir);
        self.pdf_uv_dir(self.uv_of(local), local)
    }

    /// Half a texel in `u`: the bilinear lattice's cells start at column centres.
    #[inline]
    fn half_texel(&self) -> f32 {
        0.5 / self.width as f32
    }

    /// [`pdf`](Self::pdf) with `local` in the map's frame and `uv = dir_to_uv(local)`.
    #[inline]
    fn pdf_uv_dir(&self, uv: Vec2, local: Vec3) -> f32 {
        if self.projection == EnvProjection::EqualArea {
            return self.dist.pdf(uv) * (1.0 / (4.0 * PI));
        }
        let sin_theta = (1.0 - local.y * local.y).max(0.0).sqrt();
        if sin_theta.is_nan() || sin_theta <= 0.0 {
            return 0.0;
        }
        let cell_uv = match self.filter {
            EnvFilter::Nearest => uv,
            EnvFilter::Bilinear => Vec2::new(wrap_unit(uv.x - self.half_texel()), uv.y),
        };
        self.dist.pdf(cell_uv) / (2.0 * PI * PI * sin_theta)
    }

    /// `∫ L(ω) dω` over the sphere per channel, for light selection. Nearest: exact, the
    /// sum of texel radiance times texel solid angle `(2π / w) (cos θ_j - cos θ_{j+1})`.
    /// Bilinear: each cell's mean radiance (the mean of its corners) times its solid angle,
    /// exact up to the correlation of the interpolant with `sin θ` within a cell.
    pub fn integral(&self) -> Rgb {
        use std::f64::consts::PI as PI64;
        let mut sum = [0.0f64; 3];
        let (w, h) = (self.width, self.height);
        let dphi = 2.0 * PI64 / w as f64;
        let mut add = |p: Rgb, omega: f64| {
            for (s, c) in sum.iter_mut().zip(p.to_array()) {
                *s += f64::from(c) * omega;
            }
        };
        match (self.projection, self.filter) {
            (EnvProjection::EqualArea, _) => {
                let omega = 4.0 * PI64 / (w * h) as f64;
                for &p in &self.pixels {
                    add(p, omega);
                }
            }
            (_, EnvFilter::Nearest) => {
                for (j, row) in self.pixels.chunks_exact(w).enumerate() {
                    let t0 = PI64 * j as f64 / h as f64;
                    let t1 = PI64 * (j + 1) as f64 / h as f64;
                    let omega = dphi * (t0.cos() - t1.cos());
                    for &p in row {
                        add(p, omega);
                    }
                }
            }
            (_, EnvFilter::Bilinear) => {
                let rows = cell_rows(h);
                for j in 0..rows {
                    let t0 = PI64 * j as f64 / rows as f64;
                    let t1 = PI64 * (j + 1) as f64 / rows as f64;
                    let omega = dphi * (t0.cos() - t1.cos());
                    let (r0, r1) = (j * w, (j + 1).min(h - 1) * w);
                    for i in 0..w {
                        let i1 = (i + 1) % w;
                        let px = &self.pixels;
                        let mean = (px[r0 + i] + px[r0 + i1] + px[r1 + i] + px[r1 + i1]) * 0.25;
                        add(mean, omega);
                    }
                }
            }
        }
        Rgb::new(sum[0] as f32, sum[1] as f32, sum[2] as f32)
    }
}

/// `x` wrapped into `[0, 1)` (for `x` within one period of it).
#[inline]
fn wrap_unit(x: f32) -> f32 {
    let x = if x >= 1.0 {
        x - 1.0
    } else if x < 0.0 {
        x + 1.0
    } else {
        x
    };
    // `x + 1` can round up to exactly 1 for a tiny negative `x`.
    if x >= 1.0 {
        0.0
    } else {
        x
    }
}
