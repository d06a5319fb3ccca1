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
