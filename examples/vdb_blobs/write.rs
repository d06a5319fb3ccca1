//! A minimal OpenVDB writer: one float grid (`Tree_float_5_4_3`), file version 224, no
//! compression, a uniform-scale transform, every leaf that holds a non-zero value written
//! with its non-zero voxels active (no tiles). What `vdb-rs` 0.6 and risotto's structure check
//! (`engine/loader/src/grid_file/vdb/structure.rs`) read: the byte layout of OpenVDB
//! `io/Archive.cc`, `tree/RootNode.h`, `InternalNode.h` and `LeafNode.h` with node metadata
//! byte 6 (all values stored) and child offsets `x` slowest (`(x << 2L) + (y << L) + z`).
//! Shared by `examples/vdb_blobs` (the issue-36 benchmark grids) and `tests/heterogeneous.rs`.

use std::collections::BTreeMap;
use std::io::{Seek, SeekFrom, Write};

/// Voxels per leaf edge, leaves per internal-4 edge (16), internal-4s per internal-5 edge (32).
const LEAF: i32 = 8;
const N4: i32 = 128;
const N5: i32 = 4096;

/// The leaves holding a non-zero value, grouped: internal-5 origin, internal-4 offset,
/// leaf offsets with their active masks (each in file order).
type Topology = BTreeMap<[i32; 3], BTreeMap<u32, Vec<(u32, [u64; 8])>>>;

/// The offset of `c` in a node of `2^log2` children of `child` voxels each (`x` slowest).
fn offset(c: [i32; 3], node: i32, child: i32, log2: u32) -> u32 {
    let l = |v: i32| (v.rem_euclid(node) / child) as u32;
    (l(c[0]) << (2 * log2)) + (l(c[1]) << log2) + l(c[2])
}

/// The 512 values of the leaf at `origin` (`x` slowest) and its active mask.
fn leaf(origin: [i32; 3], value: &impl Fn([i32; 3]) -> f32) -> ([f32; 512], [u64; 8]) {
    let (mut v, mut mask) = ([0.0f32; 512], [0u64; 8]);
    for i in 0..512 {
        let c = [
            origin[0] + (i as i32 >> 6),
            origin[1] + ((i as i32 >> 3) & 7),
            origin[2] + (i as i32 & 7),
        ];
        v[i] = value(c);
        if v[i] != 0.0 {
            mask[i / 64] |= 1 << (i % 64);
        }
    }
    (v, mask)
}

fn string(w: &mut impl Write, s: &str) -> std::io::Result<()> {
    w.write_all(&(s.len() as u32).to_le_bytes())?;
    w.write_all(s.as_bytes())
}

fn mask(w: &mut impl Write, words: &[u64]) -> std::io::Result<()> {
    words.iter().try_for_each(|m| w.write_all(&m.to_le_bytes()))
}

/// Metadata byte 6 (every value stored) and `n` zeros (an internal node's tile values).
fn zero_values(w: &mut impl Write, n: usize) -> std::io::Result<()> {
    w.write_all(&[6])?;
    w.write_all(&vec![0u8; 4 * n])
}

/// Writes float grid `name` of the voxels `value(i, j, k)` for index coordinates in
/// `lo..hi` (0 outside, inactive where 0) with voxel size `voxel_size`. Returns the number
/// of leaves written. `value` is called twice per voxel (topology, then data), so nothing
/// of the grid is held beside one leaf.
pub fn write_vdb(
    w: &mut (impl Write + Seek),
    name: &str,
    voxel_size: f64,
    lo: [i32; 3],
    hi: [i32; 3],
    value: impl Fn([i32; 3]) -> f32,
) -> std::io::Result<usize> {
    let inside = |c: [i32; 3]| (0..3).all(|a| c[a] >= lo[a] && c[a] < hi[a]);
    let value = |c: [i32; 3]| if inside(c) { value(c) } else { 0.0 };
    let start = lo.map(|l| l.div_euclid(LEAF) * LEAF);
    let mut topology = Topology::new();
    let mut leaves = 0;
    for x in (start[0]..hi[0]).step_by(LEAF as usize) {
        for y in (start[1]..hi[1]).step_by(LEAF as usize) {
            for z in (start[2]..hi[2]).step_by(LEAF as usize) {
                let o = [x, y, z];
                let active = leaf(o, &value).1;
                if active.iter().all(|&m| m == 0) {
                    continue;
                }
                let root = o.map(|c| c.div_euclid(N5) * N5);
                topology
                    .entry(root)
                    .or_default()
                    .entry(offset(o, N5, N4, 5))
                    .or_default()
                    .push((offset(o, N4, LEAF, 4), active));
                leaves += 1;
            }
        }
    }
    for node4s in topology.values_mut() {
        node4s
            .values_mut()
            .for_each(|l| l.sort_unstable_by_key(|e| e.0));
    }
    // Archive header (no metadata), one grid descriptor with offsets patched at the end.
    w.write_all(&0x5644_4220u64.to_le_bytes())?;
    w.write_all(&224u32.to_le_bytes())?;
    w.write_all(&10u32.to_le_bytes())?;
    w.write_all(&0u32.to_le_bytes())?;
    w.write_all(&[1])?;
    w.write_all(b"00000000-0000-0000-0000-000000000000")?;
    w.write_all(&0u32.to_le_bytes())?;
    w.write_all(&1u32.to_le_bytes())?;
    string(w, name)?;
    string(w, "Tree_float_5_4_3")?;
    string(w, "")?;
    let offsets_at = w.stream_position()?;
    w.write_all(&[0u8; 24])?;
    let grid_pos = w.stream_position()?;
    w.write_all(&0u32.to_le_bytes())?; // no compression
    w.write_all(&0u32.to_le_bytes())?; // no grid metadata
    string(w, "UniformScaleMap")?;
    let s = voxel_size;
    for v in [s, s, 1.0 / s, 1.0 / (s * s), 0.5 / s] {
        for _ in 0..3 {
            w.write_all(&v.to_le_bytes())?;
        }
    }
    // Topology: buffer count, background 0, no root tiles, the internal-5 children.
    w.write_all(&1u32.to_le_bytes())?;
    w.write_all(&0f32.to_le_bytes())?;
    w.write_all(&0u32.to_le_bytes())?;
    w.write_all(&(topology.len() as u32).to_le_bytes())?;
    let child_mask = |bits: usize, set: &mut dyn Iterator<Item = u32>| {
        let mut m = vec![0u64; bits / 64];
        set.for_each(|i| m[i as usize / 64] |= 1 << (i % 64));
        m
    };
    for (root, node4s) in &topology {
        root.iter()
            .try_for_each(|c| w.write_all(&c.to_le_bytes()))?;
        mask(w, &child_mask(32768, &mut node4s.keys().copied()))?;
        mask(w, &[0; 512])?;
        zero_values(w, 32768)?;
        for leaves in node4s.values() {
            mask(w, &child_mask(4096, &mut leaves.iter().map(|e| e.0)))?;
            mask(w, &[0; 64])?;
            zero_values(w, 4096)?;
            for (_, active) in leaves {
                // The leaf's value mask (written again before its values): vdb-rs takes the
                // active voxels from this copy.
                mask(w, active)?;
            }
        }
    }
    let block_pos = w.stream_position()?;
    for (root, node4s) in &topology {
        for (&i4, leaves) in node4s {
            let n4 = [(i4 >> 10) as i32, ((i4 >> 5) & 31) as i32, (i4 & 31) as i32];
            for &(i3, _) in leaves {
                let l = [(i3 >> 8) as i32, ((i3 >> 4) & 15) as i32, (i3 & 15) as i32];
                let o = [0, 1, 2].map(|a| root[a] + n4[a] * N4 + l[a] * LEAF);
                let (values, m) = leaf(o, &value);
                mask(w, &m)?;
                w.write_all(&[6])?;
                for v in values {
                    w.write_all(&v.to_le_bytes())?;
                }
            }
        }
    }
    let end_pos = w.stream_position()?;
    w.seek(SeekFrom::Start(offsets_at))?;
    for p in [grid_pos, block_pos, end_pos] {
        w.write_all(&p.to_le_bytes())?;
    }
    w.seek(SeekFrom::Start(end_pos))?;
    Ok(leaves)
}
