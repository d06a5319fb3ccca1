use super::*;
use crate::sampler::SplitMix64;
use glam::Vec3;

/// Contributions spanning the documented range, `2^-24` to `2^20` (log-uniform), to random
/// pixels of a small film: `(pixel, value)`.
fn contributions(n: usize, pixels: u32, seed: u64) -> Vec<(u32, Rgb)> {
    let mut rng = SplitMix64(seed);
    let mut value = || (2.0f32).powf(-24.0 + 44.0 * rng.f32());
    let mut rng2 = SplitMix64(seed ^ 0x5555);
    (0..n)
        .map(|_| {
            let p = (rng2.next_u64() % u64::from(pixels)) as u32;
            (p, Rgb::new(value(), value(), value()))
        })
        .collect()
}

fn fixed(film: &SplatFilm) -> Vec<[i64; 3]> {
    (0..film.width() * film.height())
        .map(|p| film.sum_fixed(p))
        .collect()
}

/// The same contributions added in order, in reverse, shuffled, and from two threads
/// interleaved give the same bits; the sums are the exact sums to within the rounding of
/// each addition (`2^-33`).
#[test]
fn sums_do_not_depend_on_the_order_or_the_threads() {
    let (w, h) = (5, 4);
    let values = contributions(20_000, w * h, 1);
    let film = |order: &[(u32, Rgb)]| {
        let f = SplatFilm::new(w, h).unwrap();
        for &(p, v) in order {
            f.add(p, v);
        }
        f
    };
    let forward = film(&values);
    let reversed: Vec<_> = values.iter().rev().copied().collect();
    let mut shuffled = values.clone();
    let mut rng = SplitMix64(9);
    for i in (1..shuffled.len()).rev() {
        shuffled.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
    }
    assert_eq!(fixed(&forward), fixed(&film(&reversed)));
    assert_eq!(fixed(&forward), fixed(&film(&shuffled)));
    let threaded = SplatFilm::new(w, h).unwrap();
    std::thread::scope(|s| {
        for t in 0..2 {
            let (threaded, values) = (&threaded, &values);
            s.spawn(move || {
                for &(p, v) in values.iter().skip(t).step_by(2) {
                    threaded.add(p, v);
                }
            });
        }
    });
    assert_eq!(fixed(&forward), fixed(&threaded));
    assert_eq!(
        (forward.saturations(), forward.non_finite_dropped()),
        (0, 0)
    );
    // Against the exact sums (f64 sums of f32 values of this range are exact to 1e-16
    // relative, far below the fixed point's rounding).
    let mut exact = vec![[0.0f64; 3]; (w * h) as usize];
    let mut counts = vec![0u32; (w * h) as usize];
    for &(p, v) in &values {
        for (c, x) in [v.r, v.g, v.b].into_iter().enumerate() {
            exact[p as usize][c] += f64::from(x);
        }
        counts[p as usize] += 1;
    }
    for p in 0..w * h {
        let got = forward.sum(p);
        for c in 0..3 {
            // Half a unit per addition, plus the f64 reference's own rounding.
            let e = exact[p as usize][c];
            let bound = f64::from(counts[p as usize]) * 0.5 / SplatFilm::SCALE + 1e-12 * e;
            assert!((got[c] - e).abs() <= bound, "{p} {c}: {} vs {e}", got[c]);
        }
    }
}

/// Both ends of the documented range are exact: `2^-24` and `2^30` sum without rounding.
#[test]
fn the_range_ends_are_exact() {
    let film = SplatFilm::new(2, 1).unwrap();
    film.add(
        0,
        Rgb::new(2f32.powi(-24), 2f32.powi(30), 3.0 * 2f32.powi(-24)),
    );
    film.add(0, Rgb::new(2f32.powi(-24), 0.0, 0.0));
    assert_eq!(
        film.sum(0),
        [2f64.powi(-23), 2f64.powi(30), 3.0 * 2f64.powi(-24)]
    );
    assert_eq!(film.sum(1), [0.0; 3]);
    assert_eq!(film.saturations(), 0);
}

/// NaN and infinity in any channel drop the whole contribution (no channel added) and are
/// counted, by `add` and `add_filtered`.
#[test]
fn non_finite_values_are_dropped_and_counted() {
    let film = SplatFilm::new(3, 3).unwrap();
    film.add(4, Rgb::new(1.0, 2.0, 3.0));
    film.add(4, Rgb::new(f32::NAN, 1.0, 1.0));
    film.add(4, Rgb::new(5.0, f32::INFINITY, 1.0));
    film.add(4, Rgb::new(5.0, 1.0, f32::NEG_INFINITY));
    film.add_filtered(
        &PixelFilter::Tent { radius: 1.0 },
        Vec2::new(1.5, 1.5),
        Rgb::new(0.0, f32::NAN, 0.0),
    );
    assert_eq!(film.sum(4), [1.0, 2.0, 3.0]);
    assert_eq!(film.non_finite_dropped(), 4);
    for p in (0..9).filter(|&p| p != 4) {
        assert_eq!(film.sum(p), [0.0; 3]);
    }
    film.clear();
    assert_eq!((film.sum(4), film.non_finite_dropped()), ([0.0; 3], 0));
}

/// Sums beyond the range saturate at it (never wrap to the other sign) and each saturated
/// addition is counted; a single value beyond the range saturates by itself, either sign.
#[test]
fn saturation_is_counted_and_never_wraps() {
    let film = SplatFilm::new(1, 1).unwrap();
    let big = 2f32.powi(30);
    film.add(0, Rgb::new(big, 0.0, -1e30));
    assert_eq!(film.saturations(), 1);
    film.add(0, Rgb::new(big, 0.0, 0.0));
    assert_eq!(film.saturations(), 2);
    film.add(0, Rgb::new(big, 1e25, 0.0));
    assert_eq!(film.saturations(), 4);
    let [r, g, b] = film.sum_fixed(0);
    assert_eq!((r, g, b), (i64::MAX, i64::MAX, i64::MIN));
    assert!(film.sum(0)[0] > 2f64.powi(30));
    // Adding below the saturated value moves it back down by exactly that much.
    film.add(0, Rgb::new(-1.0, 0.0, 0.0));
    assert_eq!(film.sum_fixed(0)[0], i64::MAX - (1 << 32));
    assert_eq!(film.saturations(), 4);
}

/// `add_filtered` adds the value times each of `splat_weights`' weights to its pixel.
#[test]
fn add_filtered_spreads_by_the_splat_weights() {
    let (w, h) = (7, 5);
    let film = SplatFilm::new(w, h).unwrap();
    let filter = PixelFilter::Tent { radius: 1.5 };
    let pos = Vec2::new(2.3, 3.9);
    let value = Rgb::new(1.0, 0.5, 2.0);
    film.add_filtered(&filter, pos, value);
    let mut weights = SmallVec::new();
    splat_weights(&filter, pos, w, h, &mut weights);
    assert!(weights.len() >= 6);
    let mut total = 0.0;
    for p in 0..w * h {
        let want = weights.iter().find(|q| q.0 == p).map_or(0.0, |q| q.1);
        let got = film.sum(p);
        assert!((got[0] - f64::from(want)).abs() < 1e-6, "{p}");
        assert!((got[2] - 2.0 * f64::from(want)).abs() < 1e-6, "{p}");
        total += got[1];
    }
    assert!((total - 0.5 * f64::from(weights.iter().map(|q| q.1).sum::<f32>())).abs() < 1e-6);
    assert!(SplatFilm::new(1 << 14, 1 << 14).is_none());
}

/// The whole light-tracing chain the integrator uses: points of a uniformly emitting
/// Lambertian plane (radiance 1.5) filling a pinhole camera's view, connected with
/// `Camera::connect`, added with `add_filtered` (a tent of radius 1) and read with
/// `pixel_value`: every pixel is 1.5.
#[test]
fn light_traced_plane_reads_back_its_radiance() {
    use crate::camera::{Camera, Projection};
    let cam = Camera::look_at(
        Projection::Perspective { fov_deg: 50.0 },
        Vec3::new(0.2, 0.1, 3.0),
        Vec3::ZERO,
        Vec3::Y,
        10,
        8,
    )
    .unwrap()
    .with_filter(PixelFilter::Tent { radius: 1.0 });
    let film = SplatFilm::new(cam.width, cam.height).unwrap();
    let (l, side, n) = (1.5f32, 6.0f32, 1200u32);
    let mut rng = SplitMix64(4);
    for i in 0..n {
        for j in 0..n {
            let u = (Vec2::new(i as f32, j as f32) + rng.vec2()) / n as f32 - Vec2::splat(0.5);
            let p = Vec3::new(u.x * side, u.y * side, -0.5);
            if let Some(c) = cam.connect(p, Vec2::ZERO) {
                let value = l * c.wi.z * c.importance * side * side;
                film.add_filtered(&cam.filter, c.film, Rgb::splat(value));
            }
        }
    }
    let paths = u64::from(n * n);
    // The border pixels too: their footprints reach half a pixel out of the image, and
    // `connect` accepts the points there, as the camera's filtered rays go there.
    for y in 0..cam.height {
        for x in 0..cam.width {
            let v = film.pixel_value(y * cam.width + x, paths);
            for c in v {
                assert!((c / f64::from(l) - 1.0).abs() < 0.02, "({x}, {y}): {v:?}");
            }
        }
    }
    assert_eq!(film.pixel_value(0, 0), [0.0; 3]);
}

/// The pixel box's fast path adds exactly what the general footprint adds, at random
/// positions inside, on and outside the image's edges.
#[test]
fn the_pixel_boxs_fast_path_is_the_general_footprint() {
    let (fast, general) = (SplatFilm::new(7, 5).unwrap(), SplatFilm::new(7, 5).unwrap());
    let mut state = 99u64;
    let mut next = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
        ((state >> 40) as f32) / (1u64 << 24) as f32
    };
    let filter = PixelFilter::PIXEL_BOX;
    for k in 0..2000 {
        let film = match k % 4 {
            0 => Vec2::new((next() * 9.0).floor() - 1.0, (next() * 7.0).floor() - 1.0),
            _ => Vec2::new(next() * 9.0 - 1.0, next() * 7.0 - 1.0),
        };
        let value = Rgb::new(next(), next() * 3.0, next() * 0.1);
        fast.add_filtered(&filter, film, value);
        general.add_weighted(&filter, film, value);
    }
    for p in 0..35 {
        assert_eq!(fast.sum_fixed(p), general.sum_fixed(p), "pixel {p}");
    }
}
