use super::*;
use crate::pixel_filter::{splat_weights, GaussianFilter, PixelFilter};
use crate::sampler::SplitMix64;
use smallvec::SmallVec;
use std::f32::consts::PI;

const W: u32 = 16;
const H: u32 = 12;

fn projections() -> [Projection; 3] {
    [
        Projection::Perspective { fov_deg: 60.0 },
        Projection::ThinLens {
            fov_deg: 50.0,
            aperture_radius: 0.3,
            focus_distance: 2.5,
        },
        Projection::Orthographic { width: 3.0 },
    ]
}

fn camera(projection: Projection) -> Camera {
    Camera::look_at(
        projection,
        Vec3::new(0.4, 0.3, 4.0),
        Vec3::new(0.0, 0.1, 0.0),
        Vec3::Y,
        W,
        H,
    )
    .unwrap()
}

/// `ray(film)` and back: `raster_of` of the ray's direction (its origin, orthographic) is
/// the film position, and `connect` of a point on the ray through any lens point is the
/// film position, that lens point, the ray's reverse direction and the distance along it.
#[test]
fn raster_of_and_connect_invert_the_camera_ray() {
    let mut rng = SplitMix64(17);
    for projection in projections() {
        let cam = camera(projection);
        let mut worst: f32 = 0.0;
        for _ in 0..2000 {
            // Clear of the border by more than the round trip's rounding.
            let film = Vec2::splat(0.01) + rng.vec2() * Vec2::new(W as f32 - 0.02, H as f32 - 0.02);
            let (o, d) = cam.ray(film);
            let back = match projection {
                Projection::Orthographic { .. } => cam.raster_of(o),
                _ => cam.raster_of(d),
            };
            worst = worst.max((back.expect("inside the image") - film).abs().max_element());
            let u = rng.vec2();
            let (o, d) = cam.ray_through_lens(film, u);
            let t = 0.5 + 6.0 * rng.f32();
            let c = cam.connect(o + d * t, u).expect("in front, inside");
            worst = worst.max((c.film - film).abs().max_element());
            assert!((c.lens_point - o).length() < 1e-4, "{projection:?}");
            assert!((c.wi + d).length() < 1e-4, "{projection:?}");
            assert!((c.distance - t).abs() < 1e-4 * t.max(1.0), "{projection:?}");
            assert!(c.importance > 0.0 && c.pdf_dir > 0.0);
        }
        assert!(worst < 1e-3, "{projection:?}: {worst} px");
    }
}

/// Points behind the camera, on its eye or film plane, and projecting outside the image
/// are refused; a filter wider than the pixel box accepts points just outside, up to its
/// reach, as its camera rays go there.
#[test]
fn connect_rejects_points_behind_or_outside() {
    for projection in projections() {
        let cam = camera(projection);
        let behind = cam.from - cam.forward * 2.0 + cam.right * 0.01;
        assert_eq!(cam.connect(behind, Vec2::splat(0.5)), None);
        // Just behind the eye / film plane (on it, rounding decides the side).
        let on_plane = cam.from + cam.right * 0.1 - cam.forward * 1e-4;
        assert_eq!(cam.connect(on_plane, Vec2::splat(0.3)), None);
        let on_ray = |film: Vec2| {
            let (o, d) = cam.ray(film);
            o + d * 3.0
        };
        for film in [Vec2::new(-0.2, 5.0), Vec2::new(3.0, H as f32 + 0.3)] {
            assert_eq!(cam.connect(on_ray(film), Vec2::splat(0.5)), None);
            let (o, d) = cam.ray(film);
            let probe = if let Projection::Orthographic { .. } = projection {
                o
            } else {
                d
            };
            assert_eq!(cam.raster_of(probe), None);
            assert_eq!(cam.pdf_ray(o, d), 0.0);
        }
        // A tent of radius 1.5 reaches one pixel beyond the border.
        let tent = cam.with_filter(PixelFilter::Tent { radius: 1.5 });
        let c = tent.connect(on_ray(Vec2::new(-0.7, 5.0)), Vec2::splat(0.5));
        assert!((c.expect("within the filter's reach").film.x + 0.7).abs() < 1e-3);
        assert_eq!(
            tent.connect(on_ray(Vec2::new(-1.2, 5.0)), Vec2::splat(0.5)),
            None
        );
    }
}

/// `pdf_ray` over the sphere of directions from the eye and from a lens point off the
/// centre integrates to 1 (a 1500 x 1500 equal-area grid), for the pixel box and a tent
/// whose footprint leaves the image; it is `1 / (A cos^3)` with `A = 4 tan^2(fov/2) h / w`
/// inside the image; and the mean of `1 / pdf` over the camera's own rays is the image's
/// solid angle (`E[1/p] = |support|`), in closed form `4 atan(ab / sqrt(1 + a^2 + b^2))`
/// for the rectangle of half-sides `a, b` at distance 1.
#[test]
fn pdf_direction_integrates_to_one_and_is_the_inverse_cosine_cubed_law() {
    let lens = camera(projections()[1]);
    let cams = [
        (camera(projections()[0]), Vec3::ZERO),
        (lens, lens.right * 0.2 - lens.up * 0.1),
        (
            camera(projections()[0]).with_filter(PixelFilter::Tent { radius: 1.5 }),
            Vec3::ZERO,
        ),
    ];
    let n = 1500;
    for (cam, offset) in cams {
        let origin = cam.from + offset;
        let mut sum = 0.0f64;
        for i in 0..n {
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - z * z).max(0.0).sqrt();
            for j in 0..n {
                let phi = 2.0 * PI * (j as f32 + 0.5) / n as f32;
                let d = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                sum += f64::from(cam.pdf_ray(origin, d));
            }
        }
        let integral = sum * 4.0 * std::f64::consts::PI / (n * n) as f64;
        assert!(
            (integral - 1.0).abs() < 0.01,
            "{:?}: {integral}",
            cam.filter
        );
    }
    let cam = camera(projections()[0]);
    let s = 30f32.to_radians().tan();
    let area = 4.0 * s * s * H as f32 / W as f32;
    let mut rng = SplitMix64(5);
    let mut inv = 0.0f64;
    let m = 200_000;
    for _ in 0..m {
        let film = rng.vec2() * Vec2::new(W as f32, H as f32);
        let (_, d) = cam.ray(film);
        let p = cam.pdf_direction(d);
        let cos = d.dot(cam.forward);
        assert!((p * area * cos.powi(3) - 1.0).abs() < 1e-4, "{film}");
        inv += 1.0 / f64::from(p);
    }
    let (a, b) = (f64::from(s), f64::from(s * H as f32 / W as f32));
    let solid_angle = 4.0 * (a * b / (1.0 + a * a + b * b).sqrt()).atan();
    assert!((inv / m as f64 / solid_angle - 1.0).abs() < 1e-3);
    assert!((cam.film_area() - area).abs() < 1e-6 * area);
    assert_eq!(cam.lens_area(), 1.0);
    assert!((lens.lens_area() - PI * 0.09).abs() < 1e-6);
}

/// A square of the plane through `centre` spanned by the unit axes `e1, e2`, side `side`,
/// emitting radiance `radiance(p)` (Lambertian, towards `e1 x e2`), light-traced by brute
/// force: a jittered `n x n` grid of points (area density `1 / side^2`), each connected to
/// the camera through a random lens sample, splatted with weight `L |cos| importance /
/// pdf_area` by the camera's filter, scaled by `width * height / N`. Per pixel: the
/// estimate and its standard error (of the unstratified estimator: an upper bound).
fn light_trace(
    cam: &Camera,
    (centre, e1, e2, side): (Vec3, Vec3, Vec3, f32),
    radiance: &dyn Fn(Vec3) -> f32,
    n: u32,
    seed: u64,
) -> Vec<(f64, f64)> {
    let normal = e1.cross(e2);
    let pixels = (cam.width * cam.height) as usize;
    let (mut sum, mut sum_sq) = (vec![0.0f64; pixels], vec![0.0f64; pixels]);
    let mut rng = SplitMix64(seed);
    let mut out = SmallVec::new();
    for i in 0..n {
        for j in 0..n {
            let u = (Vec2::new(i as f32, j as f32) + rng.vec2()) / n as f32 - Vec2::splat(0.5);
            let p = centre + (e1 * u.x + e2 * u.y) * side;
            let Some(c) = cam.connect(p, rng.vec2()) else {
                continue;
            };
            let cos = normal.dot(c.wi);
            if cos <= 0.0 {
                continue;
            }
            let value = f64::from(radiance(p) * cos * c.importance * side * side);
            splat_weights(&cam.filter, c.film, cam.width, cam.height, &mut out);
            for &(pixel, w) in &out {
                sum[pixel as usize] += value * f64::from(w);
                sum_sq[pixel as usize] += (value * f64::from(w)).powi(2);
            }
        }
    }
    let scale = f64::from(cam.width * cam.height) / f64::from(n * n);
    sum.iter()
        .zip(&sum_sq)
        .map(|(s, s2)| (s * scale, s2.sqrt() * scale))
        .collect()
}

/// The plane of the light-tracing tests: facing the camera, tilted, larger than the view
/// from every lens point.
fn emitter() -> (Vec3, Vec3, Vec3, f32) {
    let e1 = Vec3::new(1.0, 0.0, -0.3).normalize();
    let e2 = Vec3::new(0.1, 1.0, 0.2).normalize();
    let e2 = (e2 - e1 * e1.dot(e2)).normalize();
    (Vec3::new(0.0, 0.1, -0.5), e1, e2, 9.0)
}

/// Normalisation: a Lambertian plane of uniform radiance L filling the view, light-traced
/// with `connect`'s importance, gives L in every pixel, for the pinhole (pixel box and a
/// Gaussian filter), the thin lens with an aperture and the orthographic camera. (Without
/// the cosine-cubed law the corners would be off by ~20 %, without the aspect ratio in the
/// film area by 25 %.)
#[test]
fn light_traced_uniform_emitter_gives_its_radiance_in_every_pixel() {
    let l = 2.5f64;
    let mut cams: Vec<Camera> = projections().map(camera).to_vec();
    cams.push(camera(projections()[0]).with_filter(PixelFilter::Gaussian(
        GaussianFilter::new(0.5, 1.5).unwrap(),
    )));
    for (k, cam) in cams.iter().enumerate() {
        let image = light_trace(cam, emitter(), &|_| l as f32, 1500, k as u64);
        // A Gaussian's weights do not sum to exactly 1 (its lattice sum), nor at the
        // border, where its footprint leaves the image: the pixel box here, or the interior.
        let interior = |p: usize| {
            let (x, y) = (p as u32 % W, p as u32 / W);
            cam.filter.is_pixel_box() || ((2..W - 2).contains(&x) && (2..H - 2).contains(&y))
        };
        let tolerance = if cam.filter.is_pixel_box() { 0.0 } else { 0.03 };
        // The jittered grid stratifies the pinhole and orthographic estimates far below
        // their (unstratified) standard error: those must be within 1.5 % per pixel. The
        // thin lens's random lens points do not stratify: its 4 x 4 blocks of pixels are
        // held to their combined error as well (about 3 %).
        let stratified = cam.projection.lens().is_none();
        let mut blocks = [(0.0f64, 0.0f64); (W / 4 * (H / 4)) as usize];
        for (p, &(v, se)) in image.iter().enumerate().filter(|(p, _)| interior(*p)) {
            let err = (v - l).abs();
            assert!(
                err < 4.5 * se + tolerance * l && (!stratified || err < (0.015 + tolerance) * l),
                "{:?} pixel {p}: {v} +- {se}",
                cam.projection
            );
            let b = &mut blocks[(p as u32 / W / 4 * (W / 4) + p as u32 % W / 4) as usize];
            (b.0, b.1) = (b.0 + v - l, b.1 + se * se);
        }
        if cam.filter.is_pixel_box() {
            for (b, &(err, var)) in blocks.iter().enumerate() {
                assert!(
                    err.abs() < 4.5 * var.sqrt(),
                    "{:?} block {b}: {err}",
                    cam.projection
                );
            }
            let mean = image.iter().map(|p| p.0).sum::<f64>() / image.len() as f64;
            assert!(
                (mean / l - 1.0).abs() < 0.005,
                "{:?}: {mean}",
                cam.projection
            );
        }
    }
}

/// A light-traced image matches the camera's own filter-importance-sampled estimate of a
/// varying radiance field, pixel for pixel (the border pixels included, which gather from
/// outside the image within the filter's reach), for a tent of radius 1.5 and a Gaussian,
/// through the pinhole, the thin lens and the orthographic camera: the splat weights and
/// the importance estimate what the camera's rays estimate.
#[test]
fn light_traced_image_matches_the_filtered_camera_estimate() {
    let (centre, e1, e2, side) = emitter();
    let radiance = move |p: Vec3| {
        let (x, y) = ((p - centre).dot(e1), (p - centre).dot(e2));
        1.0 + 0.8 * (4.0 * x).sin() * (3.0 * y).cos() + if x > 0.3 { 1.5 } else { 0.0 }
    };
    let filters = [
        PixelFilter::Tent { radius: 1.5 },
        PixelFilter::Gaussian(GaussianFilter::new(0.5, 2.0).unwrap()),
    ];
    let normal = e1.cross(e2);
    let mut rng = SplitMix64(99);
    for (k, projection) in projections().into_iter().enumerate() {
        let filter = filters[k % 2];
        let cam = camera(projection).with_filter(filter);
        let light = light_trace(&cam, emitter(), &radiance, 1500, 7 + k as u64);
        let m = 4000;
        let mut spread = (f64::INFINITY, 0.0f64);
        for (p, &(lt, lt_se)) in light.iter().enumerate() {
            let c = Vec2::new((p as u32 % W) as f32 + 0.5, (p as u32 / W) as f32 + 0.5);
            let (mut s, mut s2) = (0.0f64, 0.0f64);
            for _ in 0..m {
                let u = rng.vec2();
                let film = c + Vec2::new(filter.sample_1d(u.x), filter.sample_1d(u.y));
                let (o, d) = cam.ray_through_lens(film, rng.vec2());
                let t = (centre - o).dot(normal) / d.dot(normal);
                let q = o + d * t;
                let r = (q - centre).dot(e1).abs().max((q - centre).dot(e2).abs());
                assert!(t > 0.0 && r < 0.5 * side, "the emitter fills the view");
                let v = f64::from(radiance(q));
                (s, s2) = (s + v, s2 + v * v);
            }
            let pt = s / f64::from(m);
            let pt_se = ((s2 / f64::from(m) - pt * pt).max(0.0) / f64::from(m)).sqrt();
            let z = (lt - pt).abs() / (lt_se * lt_se + pt_se * pt_se).sqrt();
            spread = (spread.0.min(pt), spread.1.max(pt));
            assert!(
                z < 4.5,
                "{projection:?} {filter:?} pixel {p}: {lt} +- {lt_se} vs {pt} +- {pt_se}"
            );
        }
        // The field does vary across the image: matching it means something.
        assert!(spread.1 - spread.0 > 1.0, "{spread:?}");
    }
}

/// `pdf_area` converts a perspective density per solid angle with `|cos| / d^2` and the
/// orthographic per-film-area density with `|cos|` alone: the area density at a plane of
/// the camera's own rays (through random lens points for the thin lens), checked by the
/// fraction of camera rays landing in a patch against `connect`'s `pdf_dir` (equal to
/// `pdf_ray`) integrated over the patch and averaged over the lens.
#[test]
fn pdf_area_is_the_density_of_camera_ray_hits() {
    for projection in projections() {
        let cam = camera(projection);
        // A patch on a tilted plane near the view centre.
        let (centre, e1, e2, _) = emitter();
        let normal = e1.cross(e2);
        let (half, n) = (0.4, 1_000_000);
        let mut rng = SplitMix64(1);
        let mut inside = 0u32;
        for _ in 0..n {
            let film = rng.vec2() * Vec2::new(W as f32, H as f32);
            let (o, d) = cam.ray_through_lens(film, rng.vec2());
            let q = o + d * ((centre - o).dot(normal) / d.dot(normal));
            inside +=
                u32::from((q - centre).dot(e1).abs() < half && (q - centre).dot(e2).abs() < half);
        }
        // The predicted probability: pdf_area over a 20 x 20 grid of the patch, averaged
        // over an 8 x 8 grid of lens samples.
        let (mut want, cells) = (0.0f64, 20);
        let lens = 8;
        for i in 0..cells * cells {
            let s = (Vec2::new((i % cells) as f32, (i / cells) as f32) + Vec2::splat(0.5))
                / cells as f32
                - Vec2::splat(0.5);
            let q = centre + (e1 * s.x + e2 * s.y) * (2.0 * half);
            for k in 0..lens * lens {
                let u = (Vec2::new((k % lens) as f32, (k / lens) as f32) + Vec2::splat(0.5))
                    / lens as f32;
                let Some(c) = cam.connect(q, u) else { continue };
                let pdf_ray = cam.pdf_ray(c.lens_point, -c.wi);
                assert!((c.pdf_dir / pdf_ray - 1.0).abs() < 1e-4, "{projection:?}");
                let pdf = cam.pdf_area(c.pdf_dir, c.distance, normal.dot(c.wi));
                want += f64::from(pdf) * f64::from(4.0 * half * half)
                    / f64::from(cells * cells * lens * lens);
            }
        }
        let got = f64::from(inside) / f64::from(n);
        assert!(
            (got / want - 1.0).abs() < 0.03,
            "{projection:?}: {got} vs {want}"
        );
    }
}
