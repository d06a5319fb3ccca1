//! Unit tests of the samplers: sequences, column draws, streams.
use super::*;

#[test]
fn samples_are_in_unit_interval_and_stratified() {
    // The first 2^k Sobol points of one dimension fall one per stratum of width 2^-k
    // (a (0,1)-sequence property Owen scrambling preserves).
    let seed = pixel_seed(7, 123);
    for dim in [0u32, 1, 5, 255, 256, 300] {
        let mut strata = [false; 64];
        for i in 0..64 {
            let v = sample_1d(seed, i, dim);
            assert!((0.0..1.0).contains(&v));
            strata[(v * 64.0) as usize] = true;
        }
        assert!(strata.iter().all(|&s| s), "dimension {dim} not stratified");
    }
}

#[test]
fn four_and_two_dimensional_samples_equal_one_dimensional_ones() {
    // sample_4d / sample_2d / next_4d are only faster paths: they must return exactly
    // the per-dimension values, including past the first 256-dimension block and at
    // unaligned starts.
    let seed = pixel_seed(11, 4321);
    for sample in [0u32, 1, 7, 1000] {
        for set in [0u32, 1, 63, 64, 65, 200, 100_000] {
            let v = sample_4d(seed, sample, set);
            for k in 0..4 {
                assert_eq!(v[k], sample_1d(seed, sample, 4 * set + k as u32));
            }
        }
        for dim in [0u32, 1, 2, 3, 254, 255, 256, 301] {
            let v = sample_2d(seed, sample, dim);
            assert_eq!(v.x, sample_1d(seed, sample, dim));
            assert_eq!(v.y, sample_1d(seed, sample, dim + 1));
            let mut s = PathSampler {
                seed,
                sample,
                dimension: dim,
            };
            let w = s.next_4d();
            assert_eq!(s.dimension, dim + 4);
            for k in 0..4 {
                assert_eq!(w[k], sample_1d(seed, sample, dim + k as u32));
            }
        }
    }
}

#[test]
fn a_dimension_stream_draws_what_next_1d_draws() {
    // The stream only caches each set: from any start, for both samplers, its draws
    // and the dimension it leaves must be those of as many `next_1d` calls.
    let seed = pixel_seed(5, 777);
    for sample in [0u32, 3, 1000, SamplerKind::Independent.address(3)] {
        for start in [0u32, 1, 3, 4, 6, 255, 257] {
            let mut a = PathSampler {
                seed,
                sample,
                dimension: start,
            };
            let mut b = a;
            let mut stream = a.stream();
            let drawn: Vec<f32> = (0..11).map(|_| stream.next_1d()).collect();
            let expected: Vec<f32> = (0..11).map(|_| b.next_1d()).collect();
            assert_eq!(drawn, expected, "sample {sample}, start {start}");
            assert_eq!(a.dimension, start + 11);
            assert_eq!(a.next_1d(), b.next_1d());
        }
    }
}

#[test]
fn column_draws_equal_per_sampler_draws() {
    // The column kernels are only faster paths: on every backend, every length (full
    // blocks of eight and a remainder), aligned and unaligned dimensions (which fall
    // back per sampler), set 0 and large sets must give exactly the scalar reference
    // next_4d / next_2d and advance the same.
    let mut rng = SplitMix64(99);
    for n in [0usize, 1, 3, 4, 5, 8, 13, 64, 203] {
        for unaligned_every in [0usize, 1, 3, 7] {
            let samplers: Vec<PathSampler> = (0..n)
                .map(|i| {
                    let set = [0u32, 1, 2, 63, 64, 1000][i % 6];
                    let shift = if unaligned_every > 0 && i % unaligned_every == 0 {
                        1 + i as u32 % 3
                    } else {
                        0
                    };
                    PathSampler {
                        seed: rng.next_u64() as u32,
                        sample: (rng.next_u64() % (2 * MAX_SPP as u64)) as u32,
                        dimension: 4 * set + shift,
                    }
                })
                .collect();
            for backend in Backend::all() {
                let mut col = samplers.clone();
                let mut out4 = vec![[0.0f32; 4]; n];
                next_4d_column_on(backend, &mut col, &mut out4);
                let mut out2 = vec![Vec2::ZERO; n];
                next_2d_column_on(backend, &mut col, &mut out2);
                for (i, s) in samplers.iter().enumerate() {
                    let mut one = *s;
                    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    let (want4, want2) = (one.next_4d(), one.next_2d());
                    let what = format!("{backend:?}, n {n}, point {i}");
                    assert_eq!(bits(&out4[i]), bits(&want4), "4d: {what}");
                    assert_eq!(
                        bits(&out2[i].to_array()),
                        bits(&want2.to_array()),
                        "2d: {what}"
                    );
                    assert_eq!(col[i].dimension, one.dimension);
                    assert_eq!((col[i].seed, col[i].sample), (s.seed, s.sample));
                }
            }
        }
    }
}

#[test]
fn camera_column_equals_per_sample_draws() {
    // The camera's set-0 column must equal sample_2d at dimension 0 for every length,
    // on every backend.
    let mut rng = SplitMix64(7);
    for n in [0usize, 1, 4, 7, 8, 9, 16, 23] {
        let seed: Vec<u32> = (0..n).map(|_| rng.next_u64() as u32).collect();
        let sample: Vec<u32> = (0..n).map(|_| rng.next_u64() as u32 % MAX_SPP).collect();
        for backend in Backend::all() {
            let mut jitter = vec![Vec2::ZERO; n];
            first_2d_column_on(backend, &seed, &sample, &mut jitter);
            for i in 0..n {
                let want = sample_2d(seed[i], sample[i], 0);
                assert_eq!(
                    jitter[i].to_array().map(f32::to_bits),
                    want.to_array().map(f32::to_bits),
                    "{backend:?}, n {n}, point {i}"
                );
            }
        }
    }
}

#[test]
fn sets_equal_sobol_burley_bit_for_bit() {
    // The table-driven evaluation must be exactly the crate's sample_4d of the set's own
    // sequence, for all sample indices and many seeds and sets past the camera's.
    for sample in 0..MAX_SPP {
        let seed = pixel_seed(sample as u64, sample.wrapping_mul(2_654_435_761));
        let set = 1 + sample % 97;
        let expected = sobol_burley::sample_4d(sample, 0, set_seed(seed, set));
        assert_eq!(sample_4d(seed, sample, set), expected, "sample {sample}");
        let d = 4 * set + sample % 4;
        assert_eq!(
            sample_1d(seed, sample, d),
            sobol_burley::sample(sample, d % 4, set_seed(seed, set))
        );
    }
}

/// The 23 bits of a sample in [0, 1) (exact: samples are multiples of 2^-23).
fn unit_bits(v: f32) -> u32 {
    (v * (1u32 << 23) as f32) as u32
}

#[test]
fn camera_set_is_a_digitally_shifted_sobol_sequence() {
    // Every pixel's camera points are one Sobol sequence XOR that pixel's words: the
    // XOR of two pixels' points is the same for every sample (an Owen scramble, which
    // permutes digits depending on the leading ones, would fail this), and dimension
    // 0 is van der Corput's radical inverse of the sample index, shifted.
    let (a, b) = (pixel_seed(3, 10), pixel_seed(3, 11));
    let shift_a = camera_set(a, 0).map(unit_bits);
    let between = std::array::from_fn::<u32, 4, _>(|d| {
        unit_bits(camera_set(a, 0)[d]) ^ unit_bits(camera_set(b, 0)[d])
    });
    assert_ne!(
        shift_a,
        camera_set(b, 0).map(unit_bits),
        "pixels share a shift"
    );
    for k in 0..4096u32 {
        let (pa, pb) = (
            camera_set(a, k).map(unit_bits),
            camera_set(b, k).map(unit_bits),
        );
        for d in 0..4 {
            assert_eq!(pa[d] ^ pb[d], between[d], "sample {k}, dimension {d}");
        }
        assert_eq!(pa[0] ^ shift_a[0], k.reverse_bits() >> 9, "sample {k}");
        // The dimension functions read the same set.
        for d in 0..4 {
            assert_eq!(sample_1d(a, k, d as u32), camera_set(a, k)[d]);
        }
    }
}

#[test]
fn camera_pairs_form_a_net_for_every_pixel() {
    // The shift keeps the (0,2)-sequence property: for many pixels, the first 64
    // jitters put one point in every elementary interval of area 1/64, and the first
    // 2^k of them one in each of area 2^-k.
    for pixel in 0..200 {
        let seed = pixel_seed(9, pixel);
        for k in [1u32, 2, 4, 6] {
            let n = 1usize << k;
            for j in 0..=k {
                let (cols, rows) = (1usize << j, 1usize << (k - j));
                let points = (0..n as u32).map(|i| sample_2d(seed, i, 0).into());
                let cells = cell_counts(points, cols, rows);
                assert!(
                    cells.iter().all(|&c| c == 1),
                    "pixel {pixel}, {n} points, {cols}x{rows}: {cells:?}"
                );
            }
        }
    }
}

#[test]
fn every_set_starts_with_a_stratified_2d_pair() {
    // Padding: each set is Sobol's first dimensions, whose first two form a (0,2)-sequence:
    // 16 points put exactly one point in every elementary interval of area 1/16 (16x1,
    // 8x2, 4x4, 2x8 and 1x16 grids). Later dimensions of one Sobol sequence do not have
    // this for every pair.
    let seed = pixel_seed(5, 77);
    for set in [0u32, 1, 2, 3, 37, 1000] {
        for (cols, rows) in [(16usize, 1usize), (8, 2), (4, 4), (2, 8), (1, 16)] {
            let points = (0..16).map(|i| {
                let v = sample_4d(seed, i, set);
                (v[0], v[1])
            });
            let cells = cell_counts(points, cols, rows);
            assert!(
                cells.iter().all(|&c| c == 1),
                "set {set}, {cols}x{rows}: {cells:?}"
            );
        }
    }
}

#[test]
fn seeds_decorrelate_pixels() {
    let a: Vec<f32> = (0..16).map(|i| sample_1d(pixel_seed(0, 1), i, 0)).collect();
    let b: Vec<f32> = (0..16).map(|i| sample_1d(pixel_seed(0, 2), i, 0)).collect();
    assert_ne!(a, b);
    let mean: f32 = (0..4096)
        .map(|p| sample_1d(pixel_seed(3, p), 0, 2))
        .sum::<f32>()
        / 4096.0;
    assert!((mean - 0.5).abs() < 0.02, "mean {mean}");
}

/// How many of `points` (in `[0, 1)^2`) fall in each cell of a `cols x rows` grid, row by row.
fn cell_counts(points: impl IntoIterator<Item = (f32, f32)>, cols: usize, rows: usize) -> Vec<u32> {
    let mut cells = vec![0u32; cols * rows];
    for (x, y) in points {
        cells[(y * rows as f32) as usize * cols + (x * cols as f32) as usize] += 1;
    }
    cells
}
