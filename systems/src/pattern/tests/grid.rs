//! Grid nodes: placement in a box, a box of its own (`to_box`) and pbrt's zero border.

use super::*;

/// The density grid in the box [-1, 1] x [0, 0.5] x [-2, 2], turned 30 degrees about the
/// axis (1, 2, 3), mirrored in x and moved by (0.5, -1, 2).
pub(super) fn rotated_grid() -> Node {
    let placement = glam::Affine3A::from_scale_rotation_translation(
        Vec3::new(-1.0, 1.0, 1.0),
        glam::Quat::from_axis_angle(
            Vec3::new(1.0, 2.0, 3.0).normalize(),
            std::f32::consts::FRAC_PI_6,
        ),
        Vec3::new(0.5, -1.0, 2.0),
    );
    Node::Grid {
        grid: density_grid(),
        min: Vec3::new(-1.0, 0.0, -2.0),
        max: Vec3::new(1.0, 0.5, 2.0),
        to_box: Some(placement.inverse()),
        border: GridBorder::Clamp,
    }
}

/// The density grid with a zero border in the box [-1, 1] x [0, 0.5] x [-2, 2].
pub(super) fn zero_border_grid() -> Node {
    Node::Grid {
        grid: Arc::new(density_grid().padded_with_zeros()),
        min: Vec3::new(-1.0, 0.0, -2.0),
        max: Vec3::new(1.0, 0.5, 2.0),
        to_box: None,
        border: GridBorder::Zero,
    }
}

/// pbrt-v4's `SampledGrid::Lookup` over the box [min, max] (`util/containers.h`): voxel `i`
/// at `(i + 1/2) / n`, trilinear, indices outside the grid read 0; 0 outside the box (the
/// cuboid medium's bounds), written from its description, in f64.
fn pbrt_lookup(grid: &DensityGrid, min: Vec3, max: Vec3, p: Vec3) -> f64 {
    let u = (p - min) / (max - min);
    if !(u.cmpge(Vec3::ZERO).all() && u.cmple(Vec3::ONE).all()) {
        return 0.0;
    }
    let d = grid.dims();
    let at = |x: i64, y: i64, z: i64| -> f64 {
        let inside = |v: i64, n: usize| (0..n as i64).contains(&v);
        if inside(x, d[0]) && inside(y, d[1]) && inside(z, d[2]) {
            grid.voxel(x as usize, y as usize, z as usize) as f64
        } else {
            0.0
        }
    };
    let s = [0, 1, 2].map(|k| u[k] as f64 * d[k] as f64 - 0.5);
    let i = s.map(|v| v.floor() as i64);
    let f = [0, 1, 2].map(|k| s[k] - i[k] as f64);
    let mut v = 0.0;
    for corner in 0..8 {
        let o = [corner & 1, (corner >> 1) & 1, (corner >> 2) & 1];
        let w: f64 = (0..3)
            .map(|k| if o[k] == 1 { f[k] } else { 1.0 - f[k] })
            .product();
        v += w * at(i[0] + o[0] as i64, i[1] + o[1] as i64, i[2] + o[2] as i64);
    }
    v
}

#[test]
fn a_zero_border_grid_is_pbrts_sampled_grid_in_its_box() {
    let g = graph(vec![zero_border_grid()]);
    let clamp = graph(vec![Node::Grid {
        grid: density_grid(),
        min: Vec3::new(-1.0, 0.0, -2.0),
        max: Vec3::new(1.0, 0.5, 2.0),
        to_box: None,
        border: GridBorder::Clamp,
    }]);
    let (min, max) = (Vec3::new(-1.0, 0.0, -2.0), Vec3::new(1.0, 0.5, 2.0));
    let mut rng = SplitMix64(7);
    let (mut near_faces, mut outside) = (0, 0);
    for _ in 0..4000 {
        // Points over a box 20 % larger than the grid's.
        let t = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 1.2 - 0.1;
        let p = min + (max - min) * t;
        let want = pbrt_lookup(&density_grid(), min, max, p);
        let got = one(&g, p, 0.0, 0.0).r as f64;
        assert!(
            (got - want).abs() <= 1e-5 * want.max(1.0),
            "{p}: {got} vs {want}"
        );
        outside += (want == 0.0 && one(&clamp, p, 0.0, 0.0).r > 0.0) as usize;
        near_faces +=
            (want > 0.0 && (got - one(&clamp, p, 0.0, 0.0).r as f64).abs() > 1e-3) as usize;
    }
    // Where the two borders differ (so the test can fail): outside the box and near faces.
    assert!(outside > 500 && near_faces > 500, "{outside} {near_faces}");
    // A zero-border node whose grid cannot hold its padding is refused.
    let thin = Node::Grid {
        grid: Arc::new(DensityGrid::new([2, 3, 3], vec![1.0; 18]).unwrap()),
        min: Vec3::ZERO,
        max: Vec3::ONE,
        to_box: None,
        border: GridBorder::Zero,
    };
    assert!(PatternGraph::new(vec![thin]).is_err());
}

#[test]
fn a_placed_grid_is_the_grid_at_the_point_mapped_into_its_box() {
    let Node::Grid {
        to_box: Some(t), ..
    } = rotated_grid()
    else {
        unreachable!()
    };
    let (placed, plain) = (
        graph(vec![rotated_grid()]),
        graph(vec![Node::Grid {
            grid: density_grid(),
            min: Vec3::new(-1.0, 0.0, -2.0),
            max: Vec3::new(1.0, 0.5, 2.0),
            to_box: None,
            border: GridBorder::Clamp,
        }]),
    );
    let mut differ = 0;
    for i in 0..200 {
        let p = Vec3::new(
            (i as f32 * 0.37).sin() * 2.0,
            (i as f32 * 0.71).cos() * 2.0,
            (i as f32 * 0.13).sin() * 3.0,
        );
        let a = one(&placed, p, 0.0, 0.0);
        assert_eq!(a, one(&plain, t.transform_point3(p), 0.0, 0.0), "{p}");
        differ += (a != one(&plain, p, 0.0, 0.0)) as usize;
    }
    // The placement matters (the test could fail).
    assert!(differ > 100, "{differ}");
    // A transform that is not finite is refused.
    let bad = Node::Grid {
        grid: density_grid(),
        min: Vec3::ZERO,
        max: Vec3::ONE,
        to_box: Some(glam::Affine3A::from_scale(Vec3::splat(f32::NAN))),
        border: GridBorder::Clamp,
    };
    assert!(PatternGraph::new(vec![bad]).is_err());
}

#[test]
fn grid_nodes_place_the_grid_in_their_box() {
    let grid = DensityGrid::new([2, 1, 1], vec![0.0, 1.0]).unwrap();
    let g = graph(vec![Node::Grid {
        grid: Arc::new(grid),
        min: Vec3::new(10.0, 0.0, 0.0),
        max: Vec3::new(12.0, 1.0, 1.0),
        to_box: None,
        border: GridBorder::Clamp,
    }]);
    // Mitsuba's 2-voxel check, on the box: 0, 0, 0.5, 1, 1 at 0, 1/4, 1/2, 3/4, 1.
    let at = |x: f32| one(&g, Vec3::new(x, 0.5, 0.5), 0.0, 0.0).r;
    assert_eq!(
        [at(10.0), at(10.5), at(11.0), at(11.5), at(12.0)],
        [0.0, 0.0, 0.5, 1.0, 1.0]
    );
    assert_eq!(
        bounds(&g, Vec3::new(10.0, 0.0, 0.0), Vec3::new(10.4, 1.0, 1.0))
            .1
            .r,
        1.0,
        "the first cell's support reaches the second voxel"
    );
}

/// `ClampInBox` (Mitsuba's medium, which exists only inside its grid's box): the clamped
/// lookup inside the box, faces included, 0 outside; its bounds reach 0 only where the
/// region leaves the box.
#[test]
fn a_clamp_in_box_grid_is_zero_outside_its_box_only() {
    let node = |border| Node::Grid {
        grid: Arc::new(DensityGrid::new([2, 1, 1], vec![0.25, 1.0]).unwrap()),
        min: Vec3::new(10.0, 0.0, 0.0),
        max: Vec3::new(12.0, 1.0, 1.0),
        to_box: None,
        border,
    };
    let (boxed, clamped) = (
        graph(vec![node(GridBorder::ClampInBox)]),
        graph(vec![node(GridBorder::Clamp)]),
    );
    let at = |g: &PatternGraph, x: f32, y: f32| one(g, Vec3::new(x, y, 0.5), 0.0, 0.0).r;
    for x in [10.0, 10.3, 11.0, 11.7, 12.0] {
        assert_eq!(
            at(&boxed, x, 0.5),
            at(&clamped, x, 0.5),
            "inside at x = {x}"
        );
    }
    assert_eq!(
        at(&boxed, 10.0, 0.5),
        0.25,
        "the outermost voxel extends to the face"
    );
    for (x, y) in [(9.99, 0.5), (12.01, 0.5), (11.0, -0.01), (11.0, 1.5)] {
        assert_eq!(at(&boxed, x, y), 0.0, "outside at ({x}, {y})");
        assert!(at(&clamped, x, y) > 0.0);
    }
    let lo = |a: Vec3, b: Vec3| bounds(&boxed, a, b).0.r;
    // (Bounds are widened by a few ulps for the lerps' rounding.)
    let inside = lo(Vec3::new(10.0, 0.0, 0.0), Vec3::new(12.0, 1.0, 1.0));
    assert!(inside <= 0.25 && inside > 0.2499, "{inside}");
    assert_eq!(lo(Vec3::new(9.0, 0.0, 0.0), Vec3::new(12.0, 1.0, 1.0)), 0.0);
    assert!(bounds(&boxed, Vec3::splat(-5.0), Vec3::splat(20.0)).1.r >= 1.0);
}
