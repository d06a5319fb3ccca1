//! Writes the sparse-media benchmark's OpenVDB grids (issue 36): a `N^3` index box
//! (`0..N` per axis) holding six smooth blobs that fill about 5 % of it, as a cloud from a
//! simulation would come, either alone (`sparse`: only the blobs' leaves are written, plus
//! one voxel at each of two opposite corners so the active bounding box is the whole
//! `N^3`) or over a haze of 0.01 in every voxel (`dense`: every leaf active).
//!
//! ```text
//! cargo run --release --example vdb_blobs -- 512 sparse target/blobs512_sparse.vdb
//! cargo run --release --example vdb_blobs -- 512 dense target/blobs512_dense.vdb
//! ```
//!
//! `vdb_blobs time FILE.vdb` reads a grid as the renderer does and times what the render's
//! stats do not split out: the majorant grid build (16^3 cells, the default, and 64^3) and
//! a million random trilinear lookups, on the grid as held (sparse or dense) and on its
//! dense copy, with the bytes each takes.
//!
//! Blob `b` is `(1 - |p - c_b|^2 / r^2)^2` inside radius `r = 0.126` of its centre (unit-box
//! coordinates `p = (i + 0.5) / N`): six balls of that radius are 5.0 % of the box.
//! Deterministic. `benches/vdb512_sparse.toml` and `vdb512_dense.toml` render them
//! (`benches/README.md`, "Media memory (issue 36)").

mod write;

/// Blob centres (unit box) and radius.
const CENTRES: [[f64; 3]; 6] = [
    [0.3, 0.3, 0.3],
    [0.7, 0.35, 0.5],
    [0.45, 0.7, 0.3],
    [0.6, 0.6, 0.72],
    [0.25, 0.55, 0.7],
    [0.75, 0.25, 0.2],
];
const RADIUS: f64 = 0.126;

/// The blobs' density at index `c` of an `n^3` box.
fn blobs(c: [i32; 3], n: i32) -> f32 {
    let p = c.map(|i| (i as f64 + 0.5) / n as f64);
    let mut d = 0.0;
    for centre in CENTRES {
        let r2 = (0..3).map(|a| (p[a] - centre[a]).powi(2)).sum::<f64>() / (RADIUS * RADIUS);
        if r2 < 1.0 {
            d += (1.0 - r2) * (1.0 - r2);
        }
    }
    d as f32
}

/// The best of 3 wall times of `f`, in seconds, and its last result.
fn best_of_3<T>(mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..3 {
        let t = std::time::Instant::now();
        out = Some(std::hint::black_box(f()));
        best = best.min(t.elapsed().as_secs_f64());
    }
    (best, out.expect("three runs"))
}

/// `vdb_blobs time FILE.vdb` (module docs).
fn time(path: &str) -> Result<(), String> {
    use risotto::systems::grid::{DensityGrid, MajorantGrid};
    let t = std::time::Instant::now();
    let grid = risotto::loader::grid_file::read_grid_named(std::path::Path::new(path), None, None)
        .map_err(|e| e.to_string())?;
    println!(
        "{path}: read in {:.3} s, dims {:?}",
        t.elapsed().as_secs_f64(),
        grid.dims()
    );
    let dense = grid.bricks().map(|_| grid.to_dense());
    let report = |what: &str, g: &DensityGrid| {
        let held = match g.bricks() {
            Some(b) => format!(
                "sparse, {} of {} bricks stored",
                b.stored_bricks(),
                b.brick_counts().iter().product::<usize>()
            ),
            None => "dense".into(),
        };
        println!("  {what} ({held}): {:.1} MB", g.heap_bytes() as f64 / 1e6);
        for res in [16, 64] {
            let (s, _) = best_of_3(|| MajorantGrid::new(g, [res; 3]));
            println!("    majorant grid {res}^3: {:.4} s", s);
        }
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let points: Vec<glam::Vec3> = (0..1_000_000)
            .map(|_| glam::Vec3::new(next(), next(), next()))
            .collect();
        let (s, sum) = best_of_3(|| points.iter().map(|&p| g.lookup(p) as f64).sum::<f64>());
        println!("    1e6 random lookups: {:.4} s (sum {sum:.6})", s);
    };
    report("as read", &grid);
    if let Some(d) = &dense {
        report("dense copy", d);
    }
    Ok(())
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let [mode, path] = args.as_slice() {
        if mode == "time" {
            return time(path);
        }
    }
    let [n, kind, out] = args.as_slice() else {
        return Err("usage: vdb_blobs N sparse|dense OUT.vdb | vdb_blobs time FILE.vdb".into());
    };
    let n: i32 = n
        .parse()
        .ok()
        .filter(|&n| n >= 2)
        .ok_or_else(|| format!("N `{n}` is not a size of at least 2"))?;
    let haze = match kind.as_str() {
        "sparse" => 0.0,
        "dense" => 0.01,
        other => return Err(format!("`{other}` is neither sparse nor dense")),
    };
    let corner = |c: [i32; 3]| c == [0; 3] || c == [n - 1; 3];
    let value = |c: [i32; 3]| {
        let v = blobs(c, n) + haze;
        if v == 0.0 && corner(c) {
            1e-3
        } else {
            v
        }
    };
    let file = std::fs::File::create(out).map_err(|e| format!("{out}: {e}"))?;
    let mut w = std::io::BufWriter::new(file);
    let leaves = write::write_vdb(&mut w, "density", 1.0 / n as f64, [0; 3], [n; 3], value)
        .map_err(|e| format!("{out}: {e}"))?;
    let total = (n as usize).div_ceil(8).pow(3);
    println!(
        "{out}: {leaves} of {total} leaves ({:.1} %)",
        100.0 * leaves as f64 / total as f64
    );
    Ok(())
}
