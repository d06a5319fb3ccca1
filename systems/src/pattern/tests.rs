use super::*;
use crate::sampler::SplitMix64;

mod grid;
mod image_lookup;
use grid::{rotated_grid, zero_border_grid};

fn graph(nodes: Vec<Node>) -> PatternGraph {
    PatternGraph::new(nodes).unwrap()
}

fn fbm(frequency: f32, octaves: u32) -> Fbm {
    Fbm::new(frequency, octaves, 2.0, 0.5, 7).unwrap()
}

fn texture() -> Arc<Texture> {
    // 4 x 2 texels with distinct channels.
    let texels = (0..8)
        .map(|i| Rgb::new(i as f32 / 8.0, 1.0 - i as f32 / 8.0, (i % 3) as f32))
        .collect();
    Arc::new(Texture::new(4, 2, texels).unwrap())
}

fn density_grid() -> Arc<DensityGrid> {
    let data = (0..4 * 3 * 2).map(|i| ((i * 7) % 11) as f32).collect();
    Arc::new(DensityGrid::new([4, 3, 2], data).unwrap())
}

fn one(g: &PatternGraph, p: Vec3, u: f32, v: f32) -> Rgb {
    let mut out = [Rgb::BLACK];
    eval(g, &[p], &[u], &[v], &mut out);
    out[0]
}

/// Every node type alone, and composites of every combinator.
fn test_graphs() -> Vec<(&'static str, PatternGraph)> {
    let c = |r, g, b| Node::Constant(Rgb::new(r, g, b));
    let checker = |space| Node::Checker {
        scale: 3.0,
        a: Rgb::new(0.1, 0.5, 0.9),
        b: Rgb::new(0.8, 0.2, 0.4),
        space,
    };
    let gradient = |axis| Node::Gradient {
        axis,
        from: 1.0,
        to: -0.5,
        a: Rgb::new(0.0, 1.0, 0.3),
        b: Rgb::new(1.0, 0.0, 0.3),
    };
    let grid = Node::Grid {
        grid: density_grid(),
        min: Vec3::new(-1.0, 0.0, -2.0),
        max: Vec3::new(1.0, 0.5, 2.0),
        to_box: None,
        border: GridBorder::Clamp,
    };
    vec![
        ("constant", graph(vec![c(0.2, 0.4, 0.6)])),
        ("noise", graph(vec![Node::Noise(fbm(1.7, 1))])),
        ("fbm", graph(vec![Node::Noise(fbm(0.9, 6))])),
        ("checker_p", graph(vec![checker(Space::P)])),
        ("checker_uv", graph(vec![checker(Space::Uv)])),
        ("gradient_y", graph(vec![gradient(Axis::Y)])),
        ("gradient_v", graph(vec![gradient(Axis::V)])),
        (
            "image",
            graph(vec![Node::Image(texture(), Default::default())]),
        ),
        ("grid", graph(vec![grid.clone()])),
        ("rotated grid", graph(vec![rotated_grid()])),
        ("zero-border grid", graph(vec![zero_border_grid()])),
        (
            "fraction(grid, add(noise remapped, gradient))",
            graph(vec![
                zero_border_grid(),
                Node::Noise(fbm(1.0, 3)),
                Node::Remap {
                    a: 1,
                    from: [-1.0, 1.0],
                    to: [0.0, 2.0],
                },
                gradient(Axis::X),
                Node::Add { a: 2, b: 3 },
                Node::Fraction { a: 0, b: 4 },
            ]),
        ),
        (
            "mix(checker, image, noise)",
            graph(vec![
                checker(Space::P),
                Node::Image(texture(), Default::default()),
                Node::Noise(fbm(2.0, 3)),
                Node::Mix { a: 0, b: 1, t: 2 },
            ]),
        ),
        (
            "multiply(remap(noise), gradient)",
            graph(vec![
                Node::Noise(fbm(1.0, 4)),
                Node::Remap {
                    a: 0,
                    from: [-1.0, 1.0],
                    to: [0.2, 0.9],
                },
                gradient(Axis::X),
                Node::Multiply { a: 1, b: 2 },
            ]),
        ),
        (
            "scale(mix(grid, constant, gradient))",
            graph(vec![
                grid,
                c(0.5, 0.0, 2.0),
                gradient(Axis::Z),
                Node::Mix { a: 0, b: 1, t: 2 },
                Node::Scale {
                    a: 3,
                    factor: Rgb::new(0.5, 2.0, 0.0),
                },
            ]),
        ),
        (
            "multiply(noise, noise) (signs mixed)",
            graph(vec![
                Node::Noise(fbm(1.3, 2)),
                Node::Noise(Fbm::new(0.7, 3, 1.9, 0.6, 99).unwrap()),
                Node::Multiply { a: 0, b: 1 },
                Node::Remap {
                    a: 2,
                    from: [1.0, -1.0],
                    to: [0.0, 1.0],
                },
            ]),
        ),
        (
            "power(noise, 0.5) (negative inputs read as 0)",
            graph(vec![
                Node::Noise(fbm(2.1, 3)),
                Node::Power {
                    a: 0,
                    exponent: 0.5,
                },
            ]),
        ),
    ]
}

#[test]
fn power_raises_each_channel_and_clamps_negatives_to_zero() {
    let g = graph(vec![
        Node::Gradient {
            axis: Axis::X,
            from: 0.0,
            to: 1.0,
            a: Rgb::splat(-0.5),
            b: Rgb::new(0.25, 0.64, 1.0),
        },
        Node::Power {
            a: 0,
            exponent: 0.5,
        },
    ]);
    assert_eq!(one(&g, Vec3::X, 0.0, 0.0), Rgb::new(0.5, 0.8, 1.0));
    assert_eq!(one(&g, Vec3::ZERO, 0.0, 0.0), Rgb::BLACK);
    let (lo, hi) = bounds(&g, Vec3::NEG_INFINITY, Vec3::INFINITY);
    assert_eq!(lo, Rgb::BLACK);
    assert!(
        (hi - Rgb::new(0.5, 0.8, 1.0)).max_channel().abs() < 1e-3,
        "{hi:?}"
    );
    assert!(PatternGraph::new(vec![
        Node::Constant(Rgb::WHITE),
        Node::Power {
            a: 0,
            exponent: 0.0
        },
    ])
    .is_err());
}

#[test]
fn evaluated_values_lie_within_the_bounds_of_random_boxes() {
    let mut rng = SplitMix64(0xB0B5);
    let mut checked = 0usize;
    for (name, g) in test_graphs() {
        let mut violations = 0usize;
        for b in 0..200 {
            // Boxes from tiny (inside one checker cell) to large, some unbounded.
            let centre = (Vec3::new(rng.f32(), rng.f32(), rng.f32()) - 0.5) * 6.0;
            let size = 10f32.powf(-3.0 + 4.0 * rng.f32());
            let half = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * size;
            let (mut lo, hi) = (centre - half, centre + half);
            if b % 50 == 0 {
                lo.x = f32::NEG_INFINITY;
            }
            let (blo, bhi) = bounds(&g, lo, hi);
            let lo = lo.max(Vec3::splat(-1e6));
            let n = 64;
            let p: Vec<Vec3> = (0..n)
                .map(|_| lo + (hi - lo) * Vec3::new(rng.f32(), rng.f32(), rng.f32()))
                .collect();
            let u: Vec<f32> = (0..n).map(|_| rng.f32() * 5.0 - 2.0).collect();
            let v: Vec<f32> = (0..n).map(|_| rng.f32() * 5.0 - 2.0).collect();
            let mut out = vec![Rgb::BLACK; n];
            eval(&g, &p, &u, &v, &mut out);
            for (i, o) in out.iter().enumerate() {
                let inside = |x: f32, l: f32, h: f32| l <= x && x <= h;
                if !(inside(o.r, blo.r, bhi.r)
                    && inside(o.g, blo.g, bhi.g)
                    && inside(o.b, blo.b, bhi.b))
                {
                    if violations == 0 {
                        eprintln!("{name}: {o:?} at {} outside {blo:?} .. {bhi:?}", p[i]);
                    }
                    violations += 1;
                }
                checked += 1;
            }
        }
        assert_eq!(violations, 0, "{name}: values outside their bounds");
    }
    assert_eq!(checked, 17 * 200 * 64);
}

#[test]
fn bounds_are_exact_for_constant_checker_and_gradient() {
    let g = graph(vec![Node::Constant(Rgb::new(0.1, 0.2, 0.3))]);
    let c = Rgb::new(0.1, 0.2, 0.3);
    assert_eq!(bounds(&g, Vec3::ZERO, Vec3::ONE), (c, c));
    let (a, b) = (Rgb::splat(0.25), Rgb::splat(0.75));
    let checker = graph(vec![Node::Checker {
        scale: 1.0,
        a,
        b,
        space: Space::P,
    }]);
    // Inside cell (0, 0, 0): even; inside (1, 0, 0): odd; across: both.
    assert_eq!(bounds(&checker, Vec3::splat(0.1), Vec3::splat(0.9)), (a, a));
    let odd = (Vec3::new(1.1, 0.1, 0.1), Vec3::new(1.9, 0.9, 0.9));
    assert_eq!(bounds(&checker, odd.0, odd.1), (b, b));
    assert_eq!(bounds(&checker, Vec3::splat(0.5), Vec3::splat(1.5)), (a, b));
    let gradient = graph(vec![Node::Gradient {
        axis: Axis::X,
        from: 0.0,
        to: 2.0,
        a: Rgb::BLACK,
        b: Rgb::WHITE,
    }]);
    assert_eq!(
        bounds(
            &gradient,
            Vec3::new(0.5, -9.0, -9.0),
            Vec3::new(1.5, 9.0, 9.0)
        ),
        (Rgb::splat(0.25), Rgb::splat(0.75))
    );
    assert_eq!(
        bounds(
            &gradient,
            Vec3::splat(f32::NEG_INFINITY),
            Vec3::splat(f32::INFINITY)
        ),
        (Rgb::BLACK, Rgb::WHITE)
    );
}

#[test]
fn checker_parity_by_p_and_by_uv() {
    let (a, b) = (Rgb::splat(0.1), Rgb::splat(0.9));
    let g = graph(vec![Node::Checker {
        scale: 2.0,
        a,
        b,
        space: Space::P,
    }]);
    // Cells are 0.5 wide: (0.25, .., ..) is cell (0, 0, 0), even.
    assert_eq!(one(&g, Vec3::splat(0.25), 0.0, 0.0), a);
    assert_eq!(one(&g, Vec3::new(0.75, 0.25, 0.25), 0.0, 0.0), b);
    assert_eq!(one(&g, Vec3::new(0.75, 0.75, 0.25), 0.0, 0.0), a);
    assert_eq!(one(&g, Vec3::new(-0.25, 0.25, 0.25), 0.0, 0.0), b);
    assert_eq!(one(&g, Vec3::new(-0.25, -0.25, -0.25), 0.0, 0.0), b);
    let uv = graph(vec![Node::Checker {
        scale: 4.0,
        a,
        b,
        space: Space::Uv,
    }]);
    assert_eq!(one(&uv, Vec3::ZERO, 0.1, 0.1), a);
    assert_eq!(one(&uv, Vec3::ZERO, 0.3, 0.1), b);
    assert_eq!(one(&uv, Vec3::splat(7.3), 0.3, 0.3), a, "P is ignored");
}

#[test]
fn gradient_and_remap_reach_their_endpoints_and_clamp() {
    let (a, b) = (Rgb::new(0.0, 0.5, 1.0), Rgb::new(1.0, 0.5, 0.0));
    let g = graph(vec![Node::Gradient {
        axis: Axis::U,
        from: 0.2,
        to: 0.6,
        a,
        b,
    }]);
    assert_eq!(one(&g, Vec3::ZERO, 0.2, 0.0), a);
    assert_eq!(one(&g, Vec3::ZERO, 0.6, 0.0), b);
    assert_eq!(one(&g, Vec3::ZERO, -5.0, 0.0), a);
    assert_eq!(one(&g, Vec3::ZERO, 5.0, 0.0), b);
    let mid = one(&g, Vec3::ZERO, 0.4, 0.0);
    assert!(
        (mid - Rgb::splat(0.5)).map(f32::abs).max_channel() < 1e-6,
        "{mid:?}"
    );
    let r = |x: f32| {
        let g = graph(vec![
            Node::Constant(Rgb::splat(x)),
            Node::Remap {
                a: 0,
                from: [2.0, 4.0],
                to: [10.0, 0.0],
            },
        ]);
        one(&g, Vec3::ZERO, 0.0, 0.0).r
    };
    assert_eq!((r(2.0), r(4.0), r(3.0)), (10.0, 0.0, 5.0));
    assert_eq!((r(-1.0), r(9.0)), (10.0, 0.0), "clamped");
}

#[test]
fn perlin_noise_vanishes_at_lattice_points_and_stays_in_range() {
    let f = fbm(1.0, 1);
    let mut rng = SplitMix64(3);
    for x in -3..4 {
        for y in -3..4 {
            for z in -3..4 {
                let p = Vec3::new(x as f32, y as f32, z as f32);
                assert_eq!(perlin(f.permutation(), p), 0.0, "{p}");
            }
        }
    }
    // At frequency 4 the lattice points are k / 4.
    let g = graph(vec![Node::Noise(fbm(4.0, 1))]);
    assert_eq!(one(&g, Vec3::new(0.25, -0.5, 1.75), 0.0, 0.0), Rgb::BLACK);
    let (mut lo, mut hi) = (0.0f32, 0.0f32);
    for _ in 0..100_000 {
        let p = (Vec3::new(rng.f32(), rng.f32(), rng.f32()) - 0.5) * 40.0;
        let n = perlin(f.permutation(), p);
        lo = lo.min(n);
        hi = hi.max(n);
    }
    assert!(lo >= -PERLIN_BOUND && hi <= PERLIN_BOUND, "{lo} .. {hi}");
    // Not degenerate: the noise reaches well beyond +-0.5 (its true extremes are near 1).
    assert!(lo < -0.6 && hi > 0.6, "{lo} .. {hi}");
    // Different seeds give different noise.
    let other = Fbm::new(1.0, 1, 2.0, 0.5, 8).unwrap();
    let p = Vec3::new(0.3, 0.6, 0.2);
    assert_ne!(perlin(f.permutation(), p), perlin(other.permutation(), p));
}

#[test]
fn fbm_with_one_octave_is_the_noise_and_sums_octaves_otherwise() {
    let f1 = Fbm::new(2.5, 1, 3.0, 0.4, 11).unwrap();
    let f3 = Fbm::new(2.5, 3, 3.0, 0.4, 11).unwrap();
    let mut rng = SplitMix64(5);
    for _ in 0..1000 {
        let p = (Vec3::new(rng.f32(), rng.f32(), rng.f32()) - 0.5) * 10.0;
        assert_eq!(f1.eval(p), perlin(f1.permutation(), p * 2.5));
        assert!(f3.eval(p).abs() <= f3.bound());
    }
    assert_eq!(f1.bound(), PERLIN_BOUND);
    assert!((f3.bound() - PERLIN_BOUND * (1.0 + 0.4 + 0.16)).abs() < 1e-6);
}

#[test]
fn image_texel_centres_read_back_the_texels() {
    let t = texture();
    let g = graph(vec![Node::Image(t.clone(), Default::default())]);
    for y in 0..2 {
        for x in 0..4 {
            let (u, v) = ((x as f32 + 0.5) / 4.0, 1.0 - (y as f32 + 0.5) / 2.0);
            assert_eq!(one(&g, Vec3::ZERO, u, v), t.texel(x, y), "texel ({x}, {y})");
            // Repeat wrap: one period further reads the same texel.
            assert_eq!(one(&g, Vec3::ZERO, u + 1.0, v - 2.0), t.texel(x, y));
        }
    }
    // Halfway between the first two texels of the top row.
    let mid = one(&g, Vec3::ZERO, 0.25, 0.75);
    let close = |a: Rgb, b: Rgb| (a - b).map(f32::abs).max_channel() < 1e-6;
    assert!(close(mid, (t.texel(0, 0) + t.texel(1, 0)) * 0.5), "{mid:?}");
    // Across the seam: halfway between the last and the first column.
    let seam = one(&g, Vec3::ZERO, 0.0, 0.75);
    assert!(
        close(seam, (t.texel(3, 0) + t.texel(0, 0)) * 0.5),
        "{seam:?}"
    );
}

#[test]
fn add_and_fraction_are_the_sum_and_the_part_of_the_whole() {
    let c = |r, g, b| Node::Constant(Rgb::new(r, g, b));
    let nodes = [
        c(0.2, 0.0, 3.0),
        c(0.6, 0.0, 1.0),
        Node::Add { a: 0, b: 1 },
        Node::Fraction { a: 0, b: 1 },
        Node::Fraction { a: 2, b: 0 },
    ];
    let at = |root: usize| one(&graph(nodes[..=root].to_vec()), Vec3::ZERO, 0.0, 0.0);
    assert_eq!(at(2), Rgb::new(0.8, 0.0, 4.0));
    // 0.2 / 0.8, 0 / 0 read as 0, 3 / 4.
    let f = at(3);
    assert!(
        (f.r - 0.25).abs() < 1e-6 && f.g == 0.0 && (f.b - 0.75).abs() < 1e-6,
        "{f:?}"
    );
    let f = at(4);
    assert!(
        (f.r - 0.8).abs() < 1e-6 && f.g == 0.0 && (f.b - 4.0 / 7.0).abs() < 1e-6,
        "{f:?}"
    );
}

#[test]
fn blocks_give_the_same_values_as_points_one_by_one() {
    let (_, g) = test_graphs().swap_remove(9);
    let mut rng = SplitMix64(17);
    let n = 3 * BLOCK + 5;
    let p: Vec<Vec3> = (0..n)
        .map(|_| Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 4.0)
        .collect();
    let u: Vec<f32> = (0..n).map(|_| rng.f32()).collect();
    let mut out = vec![Rgb::BLACK; n];
    eval(&g, &p, &u, &u, &mut out);
    for i in (0..n).step_by(37) {
        assert_eq!(out[i], one(&g, p[i], u[i], u[i]), "point {i}");
    }
}

#[test]
fn graphs_refuse_forward_references_and_bad_parameters() {
    let c = Node::Constant(Rgb::WHITE);
    assert!(PatternGraph::new(vec![]).is_err());
    let forward = PatternGraph::new(vec![c.clone(), Node::Multiply { a: 0, b: 1 }]);
    assert!(
        matches!(forward, Err(PatternError::Structure(_))),
        "{forward:?}"
    );
    let remap = Node::Remap {
        a: 0,
        from: [1.0, 1.0],
        to: [0.0, 1.0],
    };
    assert!(PatternGraph::new(vec![c.clone(), remap]).is_err());
    assert!(Fbm::new(1.0, 0, 2.0, 0.5, 0).is_err());
    assert!(Fbm::new(1.0, 17, 2.0, 0.5, 0).is_err());
    assert!(Fbm::new(-1.0, 4, 2.0, 0.5, 0).is_err());
    assert!(Texture::new(2, 2, vec![Rgb::WHITE; 3]).is_err());
    assert!(Texture::new(1, 1, vec![Rgb::splat(f32::NAN)]).is_err());
    let g = graph(vec![
        c,
        Node::Image(texture(), Default::default()),
        Node::Multiply { a: 0, b: 1 },
    ]);
    assert!(g.reads_uv());
    assert!(!graph(vec![Node::Noise(fbm(1.0, 2))]).reads_uv());
}

#[test]
fn lipschitz_noise_bounds_hold_on_small_and_large_boxes_and_are_tight_when_small() {
    let mut rng = SplitMix64(0x11F5);
    let fbms = [
        fbm(1.7, 1),
        fbm(0.9, 6),
        Fbm::new(3.0, 8, 2.3, 0.7, 5).unwrap(),
        Fbm::new(0.05, 16, 1.9, 0.55, 11).unwrap(),
    ];
    let (mut violations, mut checked) = (0usize, 0usize);
    let mut small_widths = Vec::new();
    for f in &fbms {
        for b in 0..400 {
            // Box sides from 1e-5 to 1e2, centres near the origin and far from it.
            let reach = if b % 4 == 0 { 2000.0 } else { 8.0 };
            let centre = (Vec3::new(rng.f32(), rng.f32(), rng.f32()) - 0.5) * reach;
            let size = 10f32.powf(-5.0 + 7.0 * rng.f32());
            let half = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * size;
            let (lo, hi) = (centre - half, centre + half);
            let (l, h) = f.bounds_over(lo, hi);
            assert!(l <= h && l >= -f.bound() && h <= f.bound());
            if size < 1e-3 {
                small_widths.push((h - l) / (2.0 * f.bound()));
            }
            for k in 0..64 {
                // Corners and faces too: the extremes of a box are often on its boundary.
                let t = if k < 8 {
                    Vec3::new((k & 1) as f32, ((k >> 1) & 1) as f32, (k >> 2) as f32)
                } else {
                    Vec3::new(rng.f32(), rng.f32(), rng.f32())
                };
                let p = lo + (hi - lo) * t;
                let v = f.eval(p);
                if !(l <= v && v <= h) {
                    if violations == 0 {
                        eprintln!("{v} at {p} outside [{l}, {h}] (box {lo} .. {hi})");
                    }
                    violations += 1;
                }
                checked += 1;
            }
        }
    }
    assert_eq!(violations, 0, "noise values outside their Lipschitz bounds");
    assert_eq!(checked, 4 * 400 * 64);
    // Tiny boxes get a small fraction of the global interval (the old bound's width is 1).
    small_widths.sort_by(f32::total_cmp);
    let median = small_widths[small_widths.len() / 2];
    assert!(
        median < 0.05,
        "median relative width {median} of tiny boxes"
    );
}

#[test]
fn noise_bounds_over_unbounded_boxes_are_the_global_bound() {
    let f = fbm(2.0, 4);
    let g = f.bound();
    assert_eq!(f.bounds_over(Vec3::NEG_INFINITY, Vec3::ZERO), (-g, g));
    assert_eq!(f.bounds_over(Vec3::splat(f32::NAN), Vec3::ONE), (-g, g));
    // A box much wider than the lattice: every octave's interval is clamped.
    assert_eq!(
        f.bounds_over(Vec3::splat(-100.0), Vec3::splat(100.0)),
        (-g, g)
    );
}
