use super::*;
use crate::sampler::SplitMix64;

#[test]
fn lane_wise_scans_agree_with_plain_folds() {
    // Lengths around the lane count (the remainder path) and a long one; the first bad
    // value anywhere (in a lane or in the remainder) is found.
    let mut rng = SplitMix64(9);
    for n in [1usize, 7, 8, 9, 17, 1000, 4099] {
        let values: Vec<f32> = (0..n).map(|_| rng.f32() * 5.0).collect();
        let (valid, max, sum) = scan(&values);
        assert!(valid);
        assert_eq!(max, values.iter().copied().fold(0.0, f32::max), "n = {n}");
        let plain: f64 = values.iter().map(|&v| v as f64).sum();
        assert!((sum - plain).abs() <= 1e-12 * plain.max(1.0), "n = {n}");
        let (hi, lo) = bounds_of(&values, (0.0, f32::INFINITY));
        assert_eq!(hi, values.iter().copied().fold(0.0, f32::max));
        assert_eq!(lo, values.iter().copied().fold(f32::INFINITY, f32::min));
        for bad in [-1.0, f32::NAN, f32::INFINITY] {
            for at in [0, n / 2, n - 1] {
                let mut v = values.clone();
                v[at] = bad;
                assert!(!scan(&v).0, "n = {n}, {bad} at {at} not seen");
            }
        }
    }
    assert_eq!(bounds_of(&[], (0.0, f32::INFINITY)), (0.0, f32::INFINITY));
}

#[test]
fn the_harness_two_voxel_check() {
    // README section e: a 2-voxel grid [0, 1] evaluates to 0, 0, 0.5, 1, 1.
    let g = DensityGrid::new([2, 1, 1], vec![0.0, 1.0]).unwrap();
    let got: Vec<f32> = [0.0, 0.25, 0.5, 0.75, 1.0]
        .iter()
        .map(|&x| g.lookup(Vec3::new(x, 0.5, 0.5)))
        .collect();
    assert_eq!(got, vec![0.0, 0.0, 0.5, 1.0, 1.0]);
    // The same along y and z, and in between: linear between the centres.
    let gy = DensityGrid::new([1, 2, 1], vec![0.0, 1.0]).unwrap();
    assert_eq!(gy.lookup(Vec3::new(0.0, 0.625, 0.0)), 0.75);
    let gz = DensityGrid::new([1, 1, 2], vec![2.0, 4.0]).unwrap();
    assert_eq!(gz.lookup(Vec3::new(0.3, 0.3, 0.375)), 2.5); // g = 0.75 - 0.5
                                                            // Outside the cube: clamped.
    assert_eq!(g.lookup(Vec3::new(-3.0, 0.5, 0.5)), 0.0);
    assert_eq!(g.lookup(Vec3::new(7.0, 0.5, 0.5)), 1.0);
}

#[test]
fn trilinear_reproduces_an_affine_field_and_the_voxels() {
    // f = 1 + 2x + 3y + 4z at the cell centres is reproduced exactly between them.
    let dims = [4, 3, 5];
    let f = |p: Vec3| 1.0 + 2.0 * p.x + 3.0 * p.y + 4.0 * p.z;
    let centre = |i: usize, n: usize| (i as f32 + 0.5) / n as f32;
    let mut data = Vec::new();
    for z in 0..5 {
        for y in 0..3 {
            for x in 0..4 {
                data.push(f(Vec3::new(centre(x, 4), centre(y, 3), centre(z, 5))));
            }
        }
    }
    let g = DensityGrid::new(dims, data).unwrap();
    assert_eq!(g.voxel(3, 1, 2), f(Vec3::new(0.875, 0.5, 0.5)));
    let mut rng = SplitMix64(5);
    for _ in 0..1000 {
        // Points between the outermost centres.
        let p = Vec3::new(
            0.125 + 0.75 * rng.f32(),
            1.0 / 6.0 + (2.0 / 3.0) * rng.f32(),
            0.1 + 0.8 * rng.f32(),
        );
        assert!((g.lookup(p) - f(p)).abs() < 1e-5, "{p}");
    }
}

#[test]
fn bad_values_and_sizes_are_located() {
    let e = DensityGrid::new([2, 2, 1], vec![0.0, 1.0, -2.0, 0.0]).unwrap_err();
    assert_eq!(
        e,
        GridValueError::Value {
            index: 2,
            voxel: [0, 1, 0],
            value: -2.0
        }
    );
    assert!(e.to_string().contains("voxel (0, 1, 0)") && e.to_string().contains("-2"));
    let e = DensityGrid::new([1, 1, 2], vec![0.0, f32::NAN]).unwrap_err();
    assert!(e.to_string().contains("not finite"), "{e}");
    let e = DensityGrid::new([2, 2, 2], vec![0.0; 7]).unwrap_err();
    assert!(matches!(
        e,
        GridValueError::Size {
            expected: 8,
            got: 7,
            ..
        }
    ));
    assert!(DensityGrid::new([0, 1, 1], vec![]).is_err());
}

/// A rough random grid for the majorant tests.
fn random_grid(dims: [usize; 3], seed: u64) -> DensityGrid {
    let mut rng = SplitMix64(seed);
    let n = dims.iter().product();
    DensityGrid::new(dims, (0..n).map(|_| rng.f32() * rng.f32() * 3.0).collect()).unwrap()
}

#[test]
fn majorant_bounds_hold_everywhere() {
    for (dims, res) in [
        ([64, 64, 64], [16, 16, 16]),
        ([7, 5, 3], [4, 4, 4]),
        ([2, 9, 1], [3, 2, 5]),
    ] {
        let g = random_grid(dims, dims[0] as u64);
        let m = MajorantGrid::new(&g, res);
        let mut rng = SplitMix64(11);
        for _ in 0..20000 {
            let p = Vec3::new(rng.f32(), rng.f32(), rng.f32());
            let [cx, cy, cz] = m.cell_of(p);
            let v = g.lookup(p);
            assert!(v <= m.max_at(cx, cy, cz), "{dims:?} {p}: {v}");
            assert!(v >= m.min_at(cx, cy, cz), "{dims:?} {p}: {v}");
        }
        // Cell corners and faces, the worst case for the support.
        for cz in 0..res[2] {
            for cy in 0..res[1] {
                for cx in 0..res[0] {
                    for k in 0..8 {
                        let f = |c: usize, r: usize, bit: usize| {
                            ((c + ((k >> bit) & 1)) as f32 / r as f32).min(1.0)
                        };
                        let p = Vec3::new(f(cx, res[0], 0), f(cy, res[1], 1), f(cz, res[2], 2));
                        assert!(g.lookup(p) <= m.max_at(cx, cy, cz));
                    }
                }
            }
        }
    }
    let g = random_grid([8, 8, 8], 3);
    let global = MajorantGrid::global(&g);
    assert_eq!(global.max_at(0, 0, 0), g.max());
}

#[test]
fn the_dda_visits_the_cells_in_order_and_covers_the_clipped_segment() {
    let g = random_grid([8, 8, 8], 9);
    let m = MajorantGrid::new(&g, [4, 4, 4]);
    let mut rng = SplitMix64(2);
    for _ in 0..500 {
        let o = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 1.6 - 0.3;
        let d = (Vec3::new(rng.f32(), rng.f32(), rng.f32()) - 0.5) * 3.0;
        let tmax = 2.0 * rng.f32();
        let segs: Vec<MajorantSegment> = m.traverse(o, d, 0.0, tmax).collect();
        let mut prev: Option<f32> = None;
        for s in &segs {
            assert!(s.t0 < s.t1 || (s.t1 - s.t0).abs() < 1e-6, "{s:?}");
            if let Some(p) = prev {
                assert_eq!(p, s.t0, "contiguous");
            }
            prev = Some(s.t1);
            // The segment's midpoint is in the cell whose bound it carries.
            let mid = o + d * (0.5 * (s.t0 + s.t1));
            let [cx, cy, cz] = m.cell_of(mid);
            assert_eq!(s.majorant, m.max_at(cx, cy, cz), "{o} {d} {s:?}");
        }
        // Total length = the part of [0, tmax] inside the cube (by sampling).
        let covered: f32 = segs.iter().map(|s| s.t1 - s.t0).sum();
        let steps = 2000;
        let inside = (0..steps)
            .filter(|&k| {
                let t = (k as f32 + 0.5) / steps as f32 * tmax;
                let p = o + d * t;
                p.cmpge(Vec3::ZERO).all() && p.cmple(Vec3::ONE).all()
            })
            .count() as f32
            / steps as f32
            * tmax;
        assert!((covered - inside).abs() < 3.0 * tmax / steps as f32 + 1e-5);
    }
    // An axis-parallel ray through the middle visits 4 cells of length 0.25.
    let segs: Vec<_> = m
        .traverse(Vec3::new(-1.0, 0.6, 0.6), Vec3::X, 0.0, f32::INFINITY)
        .collect();
    assert_eq!(segs.len(), 4);
    assert!((segs[0].t0 - 1.0).abs() < 1e-6 && (segs[3].t1 - 2.0).abs() < 1e-6);
}
