//! Reading OpenVDB float grids (`*.vdb`) into a [`DensityGrid`], through the `vdb-rs` crate
//! (no home-made VDB parser).
//!
//! # Convention
//! OpenVDB stores a sparse tree in **index space**: the value of voxel `(i, j, k)` sits at
//! the integer index coordinate `(i, j, k)`, its trilinear sampler (`BoxSampler`)
//! interpolates between those lattice points, and inactive voxels read as the background
//! (0 for the fog volumes renderers take as density). The reader turns the active voxels and
//! active tiles (8^3 and 128^3 blocks of one value) into a grid over their index bounding
//! box `[lo, hi]`, padded by one background voxel on every side: held block-sparse (the
//! VDB's leaf nodes as bricks, tiles and empty space one value each, nothing densified)
//! when at most [`SPARSE_FRACTION`] of the box's bricks hold active voxels, dense
//! otherwise; lookups return the same bits either way. With the grid's cell-centred
//! convention ([`risotto_systems::grid`]: clamp to the outermost voxels,
//! here the zero border) its field at index coordinate `x` is exactly OpenVDB's trilinear
//! field, background outside. The dense grid spans the index box `[lo - 1.5, hi + 1.5]`,
//! which is what fills the shape's bounds (as for every grid file): size the box to the
//! VDB's world bounds, `voxel_size * (hi - lo + 3)`, for undistorted voxels.
//!
//! # Limits
//! The grid must be a float grid (`Tree_float_5_4_3`, half-float storage included; vec3
//! grids are refused: `vdb-rs` 0.6 reads every tree's background and tile values as four
//! bytes and so reads a vec3 tree as empty, checked on `tests/data/small.vdb`), with
//! finite, non-negative active values and a dense size of at most
//! [`crate::grid_file::MAX_VOXELS`] (sparse: that many stored voxels and a brick table of
//! 1/16 of it, a box of up to 2048^3). The background value is taken as 0 (the crate does not
//! expose it); root-level tiles are not read. The file version must be 218 or later (OpenVDB
//! 3 on). Before the crate sees the file, `structure` (the submodule) checks every size and count it
//! declares against its length (the crate would allocate what a corrupt header asks for,
//! and an allocation failure aborts). The crate still panics on some malformed files: the
//! panic is caught without being printed ([`risotto_engine::expected_panic`]) and reported
//! as a format error naming the file.

use crate::grid_file::{format, GridFileError, MAX_VOXELS};
use risotto_engine::memory::release_freed_pages;
use risotto_systems::grid::{BrickBuilder, DensityGrid};
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

mod structure;

/// The grid read when the scene names none and the file has several.
pub const DEFAULT_GRID: &str = "density";

/// Runs the crate's `f`, turning its errors and (silenced) panics into format errors.
fn guarded<T, E: std::fmt::Display>(
    path: &Path,
    what: &str,
    f: impl FnOnce() -> Result<T, E>,
) -> Result<T, GridFileError> {
    match risotto_engine::expected_panic::catch(f) {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(e)) => Err(format(path, format!("{what}: {e}"))),
        Err(msg) => Err(format(
            path,
            format!("{what}: not a readable OpenVDB file ({msg})"),
        )),
    }
}

/// A visitor of active values; it stops a walk with its first error.
type Visit<'a> = &'a mut dyn FnMut(Active) -> Result<(), GridFileError>;

/// A walk over a grid's active values, calling the visitor on each.
type Walk<'a> = &'a dyn Fn(Visit<'_>) -> Result<(), GridFileError>;

/// One active value of the tree: a voxel (`size` 1) or a tile of `size^3` voxels.
#[derive(Clone, Copy)]
struct Active {
    origin: [i64; 3],
    size: i64,
    value: f32,
}

/// Reads float grid `name` (default: [`DEFAULT_GRID`], or the file's only float grid) of an
/// OpenVDB file (module docs: convention, limits).
pub fn read_vdb(path: &Path, name: Option<&str>) -> Result<DensityGrid, GridFileError> {
    let file = File::open(path).map_err(|cause| GridFileError::Io {
        path: PathBuf::from(path),
        cause,
    })?;
    let archive = structure::check_archive(path).map_err(|e| format(path, e))?;
    let mut reader = guarded(path, "header", || {
        vdb_rs::VdbReader::new(BufReader::new(file))
    })?;
    let mut names = reader.available_grids();
    names.sort();
    let is_float = |n: &str| {
        reader
            .grid_descriptors
            .get(n)
            .is_some_and(|d| d.grid_type.starts_with("Tree_float_"))
    };
    let floats: Vec<&String> = names.iter().filter(|n| is_float(n)).collect();
    let chosen = match name {
        Some(n) => {
            if !names.iter().any(|x| x == n) {
                return Err(format(
                    path,
                    format!("no grid named \"{n}\" (the file has: {})", names.join(", ")),
                ));
            }
            n.to_string()
        }
        None if names.iter().any(|x| x == DEFAULT_GRID) => DEFAULT_GRID.to_string(),
        None if floats.len() == 1 => floats[0].clone(),
        None => {
            return Err(format(
                path,
                format!(
                    "no grid named \"{DEFAULT_GRID}\" and {} float grids: name one with `name = ...` (the file has: {})",
                    floats.len(),
                    names.join(", ")
                ),
            ))
        }
    };
    let grid_type = reader.grid_descriptors[&chosen].grid_type.clone();
    if !is_float(&chosen) {
        // vdb-rs 0.6 reads a tree's background and tile values as 4 bytes whatever the value
        // type, so it misreads every vec3 tree as empty: refused rather than read wrong.
        let hint = if grid_type.starts_with("Tree_vec3") {
            ": vec3 grids are not read (the OpenVDB reader, vdb-rs 0.6, misreads their \
             trees); give a density per RGB channel as a 3-channel .vol or raw grid"
        } else {
            ""
        };
        return Err(format(
            path,
            format!("grid \"{chosen}\" is a {grid_type} grid, not a float grid{hint}"),
        ));
    }
    structure::check_float_grid(path, &archive, &chosen)
        .map_err(|e| format(path, format!("grid \"{chosen}\": {e}")))?;
    let grid = guarded(path, &format!("grid \"{chosen}\""), || {
        reader.read_grid::<f32>(&chosen)
    })?;
    // The tree is walked twice (bounds, then values) rather than listing its active values:
    // a list costs 40 bytes a voxel beside the tree and the dense grid (5.4 GB for a dense
    // 512^3 VDB). The second walk takes the tree apart as it goes ([`consume_tree`]).
    let what = format!("grid \"{chosen}\"");
    let walk =
        |visit: Visit<'_>| guarded(path, &what, || Ok::<_, String>(visit_all(&grid, visit)))?;
    let extent = active_extent(path, &chosen, &walk)?;
    let fill =
        |visit: Visit<'_>| guarded(path, &what, || Ok::<_, String>(consume_tree(grid, visit)))?;
    fill_grid(path, &chosen, extent, fill)
}

/// Visits the active values of `grid` (`vdb_rs::Grid::iter`), stopping at `visit`'s first
/// error.
fn visit_all(grid: &vdb_rs::Grid<f32>, visit: Visit<'_>) -> Result<(), GridFileError> {
    for (c, value, level) in grid.iter() {
        visit(Active {
            origin: [c.x as i64, c.y as i64, c.z as i64],
            size: level.scale() as i64,
            value,
        })?;
    }
    Ok(())
}

/// Visits the active values of `grid` as [`visit_all`] does (in another order: each root
/// node's tiles, then its children in z, y, x order), taking the tree apart on the way:
/// each child of a root node (an internal node of 128^3 voxels with its leaves, 8 MB of a
/// dense tree) is dropped once visited and its pages handed back to the system
/// ([`release_freed_pages`], every 4 MB of leaves: a tree's leaves are 2 KB allocations,
/// below glibc's mmap threshold, which stay resident until trimmed and which the grid being
/// filled, one mapping, does not reuse). The grid being filled then grows while
/// the tree shrinks, instead of the two being whole together at the load's peak (issue 36:
/// a dense 512^3 VDB peaked at twice its grid).
///
/// Each part is walked by `vdb_rs`'s own iterator, on a root node holding only that part,
/// so what is visited, tiles and values alike, is what `Grid::iter` visits.
fn consume_tree(grid: vdb_rs::Grid<f32>, visit: Visit<'_>) -> Result<(), GridFileError> {
    let vdb_rs::Grid {
        tree,
        mut transform,
        mut descriptor,
    } = grid;
    // A leaf's values (8^3 floats); what a trim can hand back.
    const LEAF_BYTES: usize = 512 * 4;
    const TRIM_BYTES: usize = 4 << 20;
    let mut freed = 0;
    for mut root in tree.root_nodes {
        let mut no_children = root.child_mask.clone();
        no_children.fill(false);
        let mut no_tiles = root.value_mask.clone();
        no_tiles.fill(false);
        // The children in the dense grid's memory order (z, then y, then x): consecutive
        // parts then fill whole slabs of its pages, which become resident as the parts'
        // leaves are freed (in the tree's own order, z fastest, the first few parts touch
        // every page of the grid).
        let mut children: Vec<u32> = root.child_mask.iter_ones().map(|i| i as u32).collect();
        children.sort_by_key(|idx| {
            root.nodes
                .get(idx)
                .map(|n| (n.origin.z, n.origin.y, n.origin.x))
        });
        let mut parts = vec![vdb_rs::Node5 {
            child_mask: no_children.clone(),
            value_mask: std::mem::take(&mut root.value_mask),
            nodes: Default::default(),
            data: std::mem::take(&mut root.data),
            origin: root.origin,
        }];
        for idx in children {
            let mut child_mask = no_children.clone();
            child_mask.set(idx as usize, true);
            // A missing child is the iterator's to report (it panics, `guarded` says so).
            let nodes = root
                .nodes
                .remove(&idx)
                .map(|n| (idx, n))
                .into_iter()
                .collect();
            parts.push(vdb_rs::Node5 {
                child_mask,
                value_mask: no_tiles.clone(),
                nodes,
                data: Vec::new(),
                origin: root.origin,
            });
        }
        drop(root);
        // Front to back, each part dropped as soon as it is visited; the freed pages handed
        // back every TRIM_BYTES of leaves (a trim walks malloc's free lists: once a part
        // would be thousands of walks on a large sparse tree).
        for part in parts {
            freed += part
                .nodes
                .values()
                .map(|n| n.nodes.len() * LEAF_BYTES)
                .sum::<usize>();
            let one = vdb_rs::Grid {
                tree: vdb_rs::Tree {
                    root_nodes: vec![part],
                },
                transform,
                descriptor,
            };
            visit_all(&one, visit)?;
            let vdb_rs::Grid {
                tree,
                transform: t,
                descriptor: d,
            } = one;
            (transform, descriptor) = (t, d);
            // Freed before the trim, not at the end of the iteration.
            drop(tree);
            if freed >= TRIM_BYTES {
                release_freed_pages();
                freed = 0;
            }
        }
    }
    release_freed_pages();
    Ok(())
}

/// A VDB is held block-sparse when at most this fraction of its box's `8^3` bricks hold
/// active voxels (tiles and empty space are one value per brick either way). Below it a
/// sparse grid takes at most about half the dense grid's memory (4 bytes of table per brick
/// beside the stored ones); above it the saving is small and the dense grid's lookups skip
/// the table. Measured in `benches/README.md`, "Media memory (issue 36)".
pub const SPARSE_FRACTION: f64 = 0.5;

/// The largest brick table of a sparse grid (entries, 4 bytes each; a box of 2048^3 voxels).
const MAX_BRICK_TABLE: usize = MAX_VOXELS / 16;

/// The padded grid of the active values `walk` visits (module docs), visited twice, the
/// second time by `fill` ([`active_extent`], then [`fill_grid`]).
#[cfg(test)]
fn to_grid(
    path: &Path,
    name: &str,
    walk: Walk<'_>,
    fill: impl FnOnce(Visit<'_>) -> Result<(), GridFileError>,
) -> Result<DensityGrid, GridFileError> {
    fill_grid(path, name, active_extent(path, name, walk)?, fill)
}

/// The index bounds of a grid's active values, and how many leaves hold them.
struct Extent {
    lo: [i64; 3],
    hi: [i64; 3],
    leaves: usize,
}

/// The [`Extent`] of the active values `walk` visits, after checking each value (finite,
/// not negative) and that there is one.
fn active_extent(path: &Path, name: &str, walk: Walk<'_>) -> Result<Extent, GridFileError> {
    let (mut lo, mut hi) = ([i64::MAX; 3], [i64::MIN; 3]);
    let mut any = false;
    // The leaf bricks (index >> 3) holding active voxels, counted as changes of leaf between
    // consecutive voxels: the tree visits a leaf's voxels together, so this is the leaf
    // count without a set of keys (12 MB for a dense 512^3 VDB); a walk in another order
    // only counts more and chooses dense.
    let mut leaves = 0usize;
    let mut last = None;
    walk(&mut |a: Active| {
        any = true;
        if !a.value.is_finite() || a.value < 0.0 {
            return Err(format(
                path,
                format!(
                    "grid \"{name}\": voxel ({}, {}, {}): value {} is {}",
                    a.origin[0],
                    a.origin[1],
                    a.origin[2],
                    a.value,
                    if a.value.is_finite() {
                        "negative (densities must be >= 0)"
                    } else {
                        "not finite"
                    }
                ),
            ));
        }
        for k in 0..3 {
            lo[k] = lo[k].min(a.origin[k]);
            hi[k] = hi[k].max(a.origin[k] + a.size - 1);
        }
        if a.size == 1 {
            let key = a.origin.map(|c| c >> 3);
            if last != Some(key) {
                leaves += 1;
                last = Some(key);
            }
        }
        Ok(())
    })?;
    if !any {
        return Err(format(
            path,
            format!("grid \"{name}\" has no active voxels"),
        ));
    }
    Ok(Extent { lo, hi, leaves })
}

/// The padded grid of the active values `fill` visits, within `extent` (module docs): held
/// block-sparse ([`risotto_systems::grid::Bricks`], bricks on the VDB's own leaf lattice, so
/// each leaf node is one brick) when at most [`SPARSE_FRACTION`] of the box's bricks hold
/// active voxels, dense otherwise.
fn fill_grid(
    path: &Path,
    name: &str,
    extent: Extent,
    fill: impl FnOnce(&mut dyn FnMut(Active) -> Result<(), GridFileError>) -> Result<(), GridFileError>,
) -> Result<DensityGrid, GridFileError> {
    let Extent { lo, hi, leaves } = extent;
    // One background voxel on each side: grid voxel p is index p + lo - 1, so storage
    // q = p + shift is on the VDB's leaf lattice when shift = (lo - 1) mod 8.
    let dims = [0, 1, 2].map(|k| (hi[k] - lo[k] + 3) as u64);
    let shift = lo.map(|l| (l - 1).rem_euclid(8) as usize);
    let too_big = |what: String| {
        format(
            path,
            format!(
                "grid \"{name}\": active index bounds ({}, {}, {})..({}, {}, {}) make {what}",
                lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
            ),
        )
    };
    let table = if dims.iter().all(|&d| d <= usize::MAX as u64 / 2) {
        BrickBuilder::table_len(dims.map(|d| d as usize), shift)
    } else {
        usize::MAX
    };
    let sparse = (leaves as f64) <= SPARSE_FRACTION * table as f64;
    let place = |a: &Active| [0, 1, 2].map(|k| (a.origin[k] - lo[k] + 1) as usize);
    if sparse {
        if table > MAX_BRICK_TABLE || leaves > MAX_VOXELS / 512 {
            return Err(too_big(format!(
                "a sparse grid of {} bricks ({} stored), more than {MAX_BRICK_TABLE} ({})",
                table,
                leaves,
                MAX_VOXELS / 512
            )));
        }
        let mut bricks = BrickBuilder::new(dims.map(|d| d as usize), shift);
        fill(&mut |a: Active| {
            bricks.fill(place(&a), [a.size as usize; 3], a.value);
            Ok(())
        })?;
        return DensityGrid::from_bricks(bricks.finish())
            .map_err(|e| format(path, format!("grid \"{name}\": {e}")));
    }
    let count = dims
        .iter()
        .try_fold(1u64, |a, &d| a.checked_mul(d))
        .filter(|&n| n <= MAX_VOXELS as u64)
        .ok_or_else(|| {
            too_big(format!(
                "a dense grid of {dims:?} voxels, more than {MAX_VOXELS}"
            ))
        })?;
    let dims = dims.map(|d| d as usize);
    let mut data = vec![0.0f32; count as usize];
    fill(&mut |a: Active| {
        let base = place(&a);
        let s = a.size as usize;
        for z in base[2]..base[2] + s {
            for y in base[1]..base[1] + s {
                let row = dims[0] * (y + dims[1] * z);
                data[row + base[0]..row + base[0] + s].fill(a.value);
            }
        }
        Ok(())
    })?;
    DensityGrid::new(dims, data).map_err(|e| format(path, format!("grid \"{name}\": {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn data(name: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../tests/data")
            .join(name)
    }

    /// The unit-cube point of index coordinate `x` of a grid read from index bounds `lo` with
    /// `dims` padded voxels (module docs: `u = (x - lo + 1.5) / dims`).
    fn unit(x: Vec3, lo: Vec3, dims: [usize; 3]) -> Vec3 {
        (x - lo + Vec3::splat(1.5)) / Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32)
    }

    #[test]
    fn a_small_vdb_reads_to_known_values_in_index_space() {
        // tests/data/make_vdb.py: value 1 + i + 10 j + 100 k at index (i - 2, j + 3, k + 7).
        let g = read_vdb(&data("small.vdb"), None).unwrap();
        assert_eq!(g.dims(), [7, 6, 5]);
        // Its voxels touch 4 leaves of a 4-brick box: held dense (SPARSE_FRACTION).
        assert!(g.bricks().is_none());
        let lo = Vec3::new(-2.0, 3.0, 7.0);
        for (i, j, k) in [(0, 0, 0), (4, 3, 2), (2, 1, 1), (1, 2, 0)] {
            let x = lo + Vec3::new(i as f32, j as f32, k as f32);
            let v = g.lookup(unit(x, lo, g.dims()));
            let want = 1.0 + i as f32 + 10.0 * j as f32 + 100.0 * k as f32;
            assert!(
                (v - want).abs() < 1e-4 * want,
                "({i}, {j}, {k}): {v} vs {want}"
            );
        }
        // Between lattice points: trilinear (the field is linear in i, j, k inside).
        let x = lo + Vec3::new(1.5, 0.25, 1.75);
        let v = g.lookup(unit(x, lo, g.dims()));
        let want = 1.0 + 1.5 + 2.5 + 175.0;
        assert!((v - want).abs() < 1e-3, "{v} vs {want}");
        // Half a voxel outside the last active one: half way to the background 0.
        let x = lo + Vec3::new(4.5, 0.0, 0.0);
        let v = g.lookup(unit(x, lo, g.dims()));
        assert!((v - 2.5).abs() < 1e-4, "{v}");
        // And the background beyond.
        assert_eq!(g.lookup(unit(lo - Vec3::splat(1.0), lo, g.dims())), 0.0);
        let t = read_vdb(&data("small.vdb"), Some("temperature")).unwrap();
        assert_eq!(t.dims(), [3, 3, 3]);
        assert_eq!(t.max(), 2.0);
    }

    /// Every 100th byte of `small.vdb` flipped (all bits, then the top bit), and lengths
    /// past the end written where the crate trusts them: each an error naming the file or
    /// the original grid, never an abort (which would end this test) nor a crate panic
    /// (which the structure check should have turned into a located error first).
    #[test]
    fn flipped_bytes_and_lying_sizes_are_errors_not_aborts() {
        let small = data("small.vdb");
        let bytes = std::fs::read(&small).unwrap();
        let dir = risotto_engine::scratch_dir::ScratchDir::new("vdb-flips");
        let p = dir.join("flipped.vdb");
        let (mut errors, mut panics) = (0, 0);
        for at in (0..bytes.len()).step_by(100) {
            for flip in [0xff, 0x80] {
                let mut b = bytes.clone();
                b[at] ^= flip;
                std::fs::write(&p, &b).unwrap();
                match read_vdb(&p, None) {
                    // A flipped mask bit or value is another well-formed grid.
                    Ok(g) => assert!(g.max().is_finite(), "byte {at} ^ {flip:#x}"),
                    Err(e) => {
                        let e = e.to_string();
                        assert!(e.contains("flipped.vdb"), "{e}");
                        errors += 1;
                        panics += e.contains("not a readable OpenVDB file") as usize;
                    }
                }
            }
        }
        assert!(errors > 100, "{errors}");
        // The structure check catches what the crate would panic on, nearly always.
        eprintln!("{errors} errors, {panics} crate panics");
        assert!(
            panics * 20 < errors,
            "{panics} crate panics of {errors} errors"
        );
        // A compressed size of 2^62 bytes in the first node buffer (the 3.6 PB allocation of
        // issue 37): the 8 bytes after the first root child's masks and metadata byte.
        let mut b = bytes.clone();
        let at = find_first_blosc_size(&b);
        b[at..at + 8].copy_from_slice(&(1i64 << 62).to_le_bytes());
        std::fs::write(&p, &b).unwrap();
        let e = read_vdb(&p, None).unwrap_err().to_string();
        assert!(
            e.contains("flipped.vdb") && e.contains("compressed node values needs"),
            "{e}"
        );
    }

    /// The offset of the first node buffer's compressed size in `small.vdb`: after the
    /// density grid's transform, topology header (16 bytes), root origin (12), two 4096-byte
    /// masks and the metadata byte.
    fn find_first_blosc_size(b: &[u8]) -> usize {
        let map = b"UniformScaleMap";
        let t = b
            .windows(map.len())
            .position(|w| w == map)
            .expect("the density grid's transform");
        t + map.len() + 5 * 24 + 16 + 12 + 8192 + 1
    }

    #[test]
    fn tiles_fill_their_blocks() {
        let g = read_vdb(&data("tile.vdb"), None).unwrap();
        assert_eq!(g.dims(), [10, 10, 10]);
        // No leaf holds voxels: held sparse, the tile one uniform brick (the bricks sit on
        // the VDB's leaf lattice), nothing stored.
        let bricks = g.bricks().expect("a tile-only VDB is held sparse");
        assert_eq!(bricks.stored_bricks(), 0);
        assert_eq!(bricks.brick_counts(), [3, 3, 3]);
        let lo = Vec3::ZERO;
        for x in [Vec3::ZERO, Vec3::splat(7.0), Vec3::new(3.0, 5.5, 0.5)] {
            assert_eq!(g.lookup(unit(x, lo, g.dims())), 0.25, "{x}");
        }
        assert_eq!(g.lookup(unit(Vec3::splat(8.0), lo, g.dims())), 0.0);
    }

    /// The tree taken apart visits what `Grid::iter` visits: the same voxels and tiles,
    /// values and sizes (small.vdb: leaves; tile.vdb: a tile and no leaf; each also with a
    /// 128^3 tile added to its root node where it has no child).
    #[test]
    fn the_consumed_tree_visits_what_the_iterator_does() {
        for (name, root_tile) in [
            ("small.vdb", false),
            ("tile.vdb", false),
            ("small.vdb", true),
            ("tile.vdb", true),
        ] {
            let read = || {
                let file = File::open(data(name)).unwrap();
                let mut reader = vdb_rs::VdbReader::new(BufReader::new(file)).unwrap();
                let mut grid = reader.read_grid::<f32>("density").unwrap();
                if root_tile {
                    let root = &mut grid.tree.root_nodes[0];
                    let free = (0..root.child_mask.len()).find(|&i| !root.child_mask[i]);
                    let k = free.unwrap();
                    root.value_mask.set(k, true);
                    root.data[k] = 0.5;
                }
                grid
            };
            let collect = |walk: &mut dyn FnMut(Visit<'_>) -> Result<(), GridFileError>| {
                let mut seen = Vec::new();
                walk(&mut |a: Active| {
                    seen.push((a.origin, a.size, a.value.to_bits()));
                    Ok(())
                })
                .unwrap();
                seen.sort();
                seen
            };
            let grid = read();
            let iterated = collect(&mut |v| visit_all(&grid, v));
            let mut consumed = Some(read());
            let taken = collect(&mut |v| consume_tree(consumed.take().unwrap(), v));
            assert!(!iterated.is_empty(), "{name}");
            assert_eq!(
                iterated.iter().any(|a| a.1 == 128),
                root_tile,
                "{name}: {iterated:?}"
            );
            assert_eq!(taken, iterated, "{name}");
        }
    }

    /// A walk over a list of active values (for [`to_grid`]).
    fn listed(active: &[Active]) -> impl Fn(Visit<'_>) -> Result<(), GridFileError> + '_ {
        move |visit| {
            for a in active {
                visit(*a)?;
            }
            Ok(())
        }
    }

    #[test]
    fn bad_vdb_files_and_names_are_reported() {
        let err = |p: &Path, name: Option<&str>| read_vdb(p, name).unwrap_err().to_string();
        let small = data("small.vdb");
        let e = err(&small, Some("smoke"));
        assert!(
            e.contains("small.vdb")
                && e.contains("\"smoke\"")
                && e.contains("density, temperature, velocity"),
            "{e}"
        );
        let e = err(&small, Some("velocity"));
        assert!(
            e.contains("Tree_vec3s")
                && e.contains("not a float grid")
                && e.contains("3-channel .vol"),
            "{e}"
        );
        let dir = risotto_engine::scratch_dir::ScratchDir::new("vdb");
        // Garbage, and the real file cut short at several places: errors, never a panic
        // escaping or a wrong grid.
        let bytes = std::fs::read(&small).unwrap();
        let garbage = dir.join("garbage.vdb");
        std::fs::write(&garbage, b"not a vdb file at all, really").unwrap();
        assert!(err(&garbage, None).contains("garbage.vdb"));
        let whole = read_vdb(&small, None).unwrap();
        let mut errors = 0;
        for cut in (0..bytes.len()).step_by(97) {
            let p = dir.join(format!("cut{cut}.vdb"));
            std::fs::write(&p, &bytes[..cut]).unwrap();
            match read_vdb(&p, None) {
                // A cut after the density grid's data leaves it whole.
                Ok(g) => assert_eq!(g, whole, "cut at {cut}"),
                Err(e) => {
                    assert!(e.to_string().contains(&format!("cut{cut}.vdb")), "{e}");
                    errors += 1;
                }
            }
        }
        assert!(errors > 100, "{errors}");
        assert!(err(&dir.join("missing.vdb"), None).contains("cannot read"));
        // Values are checked like every grid's.
        let negative = [Active {
            origin: [1, 2, 3],
            size: 1,
            value: -1.0,
        }];
        let e = to_grid(&small, "density", &listed(&negative), listed(&negative))
            .unwrap_err()
            .to_string();
        assert!(e.contains("(1, 2, 3)") && e.contains("negative"), "{e}");
        let huge = [
            Active {
                origin: [0, 0, 0],
                size: 1,
                value: 1.0,
            },
            Active {
                origin: [1 << 20, 1 << 20, 0],
                size: 1,
                value: 1.0,
            },
        ];
        let e = to_grid(&small, "density", &listed(&huge), listed(&huge))
            .unwrap_err()
            .to_string();
        assert!(e.contains("more than"), "{e}");
    }
}
