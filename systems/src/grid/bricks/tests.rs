use super::*;
use crate::grid::{DensityGrid, GridValueError, MajorantGrid};
use crate::sampler::SplitMix64;
use glam::Vec3;

/// A random sparse grid and its dense mirror: blobs of voxels, brick-sized tiles (aligned
/// and not), single voxels, overwrites, `-0.0` and exact zeros, over `dims` from `shift`.
fn random_pair(dims: [usize; 3], shift: [usize; 3], seed: u64) -> (DensityGrid, DensityGrid) {
    let mut rng = SplitMix64(seed);
    let mut b = BrickBuilder::new(dims, shift);
    let mut dense = vec![0.0f32; dims.iter().product()];
    let mut put = |b: &mut BrickBuilder, o: [usize; 3], s: [usize; 3], v: f32| {
        b.fill(o, s, v);
        for z in o[2]..(o[2] + s[2]).min(dims[2]) {
            for y in o[1]..(o[1] + s[1]).min(dims[1]) {
                for x in o[0]..(o[0] + s[0]).min(dims[0]) {
                    dense[x + dims[0] * (y + dims[1] * z)] = v;
                }
            }
        }
    };
    let at = |rng: &mut SplitMix64| dims.map(|n| (rng.f32() * n as f32) as usize % n);
    for k in 0..60 {
        let o = at(&mut rng);
        let v = match k % 7 {
            0 => 0.0,
            1 => -0.0,
            _ => rng.f32() * 4.0,
        };
        match k % 4 {
            // A tile on the bricks' own lattice (whole bricks become uniform).
            0 => {
                let o =
                    [0, 1, 2].map(|a| ((o[a] + shift[a]) / BRICK * BRICK).saturating_sub(shift[a]));
                put(&mut b, o, [BRICK; 3], v)
            }
            1 => put(&mut b, o, [1, 1, 1], v),
            2 => put(&mut b, o, [3, 11, 5], v),
            _ => put(&mut b, o, [BRICK; 3], v),
        }
    }
    // A blob: a smooth bump in a corner region (stored bricks of varying values).
    for z in 0..dims[2].min(12) {
        for y in 0..dims[1].min(10) {
            for x in 0..dims[0].min(9) {
                let v = ((x * y + z) % 5) as f32 * 0.5;
                put(&mut b, [x, y, z], [1, 1, 1], v);
            }
        }
    }
    let sparse = DensityGrid::from_bricks(b.finish()).unwrap();
    (sparse, DensityGrid::new(dims, dense).unwrap())
}

const CASES: [([usize; 3], [usize; 3]); 4] = [
    ([37, 29, 45], [3, 0, 7]),
    ([8, 8, 8], [0, 0, 0]),
    ([50, 9, 17], [1, 5, 2]),
    ([2, 1, 3], [7, 7, 7]),
];

#[test]
fn every_voxel_and_lookup_of_a_sparse_grid_has_the_dense_bits() {
    for (seed, (dims, shift)) in CASES.into_iter().enumerate() {
        let (sparse, dense) = random_pair(dims, shift, seed as u64 + 1);
        assert!(sparse.bricks().is_some() && dense.bricks().is_none());
        assert_eq!(sparse.dims(), dims);
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    assert_eq!(
                        sparse.voxel(x, y, z).to_bits(),
                        dense.voxel(x, y, z).to_bits(),
                        "{dims:?} {shift:?} ({x}, {y}, {z})"
                    );
                }
            }
        }
        assert_eq!(sparse.to_dense(), dense);
        assert_eq!(sparse.max(), dense.max());
        assert!((sparse.mean() - dense.mean()).abs() <= 1e-12 * dense.mean().max(1.0));
        let padded = (sparse.padded_with_zeros(), dense.padded_with_zeros());
        assert!(padded.0.bricks().is_some());
        assert_eq!(padded.0.to_dense().dense_data(), padded.1.dense_data());
        let mut rng = SplitMix64(seed as u64);
        for _ in 0..20000 {
            let p = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 1.2 - 0.1;
            assert_eq!(sparse.lookup(p).to_bits(), dense.lookup(p).to_bits(), "{p}");
            assert_eq!(
                padded.0.lookup(p).to_bits(),
                padded.1.lookup(p).to_bits(),
                "{p}"
            );
        }
    }
}

#[test]
fn the_majorant_grid_of_bricks_is_the_dense_one_and_bounds_every_voxel() {
    for (seed, (dims, shift)) in CASES.into_iter().enumerate() {
        let (sparse, dense) = random_pair(dims, shift, 40 + seed as u64);
        for res in [[1, 1, 1], [4, 4, 4], [16, 3, 5], dims] {
            let m = MajorantGrid::new(&sparse, res);
            assert_eq!(m, MajorantGrid::new(&dense, res), "{dims:?} {res:?}");
            // Every voxel centre and random points lie within their cell's bounds.
            for z in 0..dims[2] {
                for y in 0..dims[1] {
                    for x in 0..dims[0] {
                        let p = (Vec3::new(x as f32, y as f32, z as f32) + 0.5)
                            / Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32);
                        let [cx, cy, cz] = m.cell_of(p);
                        let v = sparse.voxel(x, y, z);
                        assert!(v <= m.max_at(cx, cy, cz) && v >= m.min_at(cx, cy, cz));
                    }
                }
            }
            let mut rng = SplitMix64(7);
            for _ in 0..5000 {
                let p = Vec3::new(rng.f32(), rng.f32(), rng.f32());
                let [cx, cy, cz] = m.cell_of(p);
                assert!(sparse.lookup(p) <= m.max_at(cx, cy, cz), "{p}");
            }
        }
    }
}

#[test]
fn memory_follows_the_stored_bricks_not_the_box() {
    // One 8^3 blob of varying values and one uniform tile in a 256^3 box: two of 32^3 bricks
    // at most, the tile none.
    let mut b = BrickBuilder::new([256, 256, 256], [0, 0, 0]);
    for i in 0..8 {
        b.fill([100 + i, 96, 96], [1, 8, 8], i as f32);
    }
    b.fill([16, 16, 16], [8, 8, 8], 0.5);
    // A brick written in parts that end up one value goes back to uniform.
    b.fill([40, 40, 40], [4, 8, 8], 2.0);
    b.fill([44, 40, 40], [4, 8, 8], 2.0);
    assert_eq!(b.stored_bricks(), 3);
    let g = DensityGrid::from_bricks(b.finish()).unwrap();
    let bricks = g.bricks().unwrap();
    assert_eq!(
        bricks.stored_bricks(),
        2,
        "the blob straddles two bricks in x"
    );
    assert_eq!(bricks.heap_bytes(), 4 * 32 * 32 * 32 + 2 * 512 * 4);
    assert_eq!(g.voxel(20, 20, 20), 0.5);
    assert_eq!(g.voxel(43, 47, 40), 2.0);
    assert_eq!(g.voxel(107, 100, 103), 7.0);
    assert_eq!(g.max(), 7.0);
    assert_eq!(g.heap_bytes(), bricks.heap_bytes());
}

#[test]
fn bad_values_in_bricks_are_located() {
    let mut b = BrickBuilder::new([20, 20, 20], [3, 3, 3]);
    b.fill([1, 2, 3], [1, 1, 1], f32::NAN);
    let e = DensityGrid::from_bricks(b.finish()).unwrap_err();
    assert!(
        matches!(
            e,
            GridValueError::Value {
                voxel: [1, 2, 3],
                ..
            }
        ),
        "{e}"
    );
    let mut b = BrickBuilder::new([20, 20, 20], [0, 0, 0]);
    b.fill([5, 6, 7], [1, 1, 1], -1.0);
    let e = DensityGrid::from_bricks(b.finish()).unwrap_err();
    assert!(
        matches!(e, GridValueError::Value { voxel: [5, 6, 7], value, .. } if value == -1.0),
        "{e}"
    );
    // A whole brick of infinity is a uniform brick, located at its first voxel.
    let mut b = BrickBuilder::new([20, 20, 20], [0, 0, 0]);
    b.fill([8, 0, 8], [8, 8, 8], f32::INFINITY);
    let e = DensityGrid::from_bricks(b.finish()).unwrap_err();
    assert!(
        matches!(
            e,
            GridValueError::Value {
                voxel: [8, 0, 8],
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("not finite"), "{e}");
}
