//! Splitting a render into farm tasks and putting it back together: the `--crop`,
//! `--grid/--tile` and `--chunks/--chunk` arguments, the scene hash partial renders carry,
//! and the `merge` and `info` commands (`engine::merge` does the work).

use crate::scene_input::SceneInput;
use crate::MergeArgs;
use anyhow::{Context, Result};
use risotto::engine::output::write_png;
use risotto::engine::render::{SampleRange, Window};
use risotto::engine::scene::CompiledScene;
use risotto::engine::technique::Techniques;
use risotto::tools::merge::{merge, read_partial, scene_hash, write_partial};
use std::path::Path;

/// The scene hash of a partial render ([`scene_hash`]): the scene file's bytes, the settings
/// and techniques that change the image, and the path and bytes of every file the scene
/// reads (meshes, grids, environment maps), so that a task that saw a different mesh is
/// refused at merge time.
pub(crate) fn partial_scene_hash(
    input: &SceneInput,
    compiled: &CompiledScene,
    techniques: &Techniques,
) -> Result<String> {
    let settings = &compiled.settings;
    let resolution = (compiled.camera.width, compiled.camera.height);
    let scene = &input.path;
    let text = input.hashed_text();
    let effective = format!(
        "{}x{} max_depth={} rr_depth={} max_passes={} techniques={}",
        resolution.0,
        resolution.1,
        settings.max_depth,
        settings.rr_depth,
        settings.max_passes,
        techniques.label()
    );
    // Every file the scene reads (meshes, grids, environment maps), path and contents:
    // a task that saw a different mesh is refused at merge time.
    let mut files = Vec::with_capacity(compiled.files.len());
    for path in &compiled.files {
        let bytes = std::fs::read(path).with_context(|| {
            format!(
                "{}: cannot read {} (a file the scene reads) to hash it",
                scene.display(),
                path.display()
            )
        })?;
        files.push((path.to_string_lossy().into_owned(), bytes));
    }
    let mut pieces: Vec<&[u8]> = vec![&text, effective.as_bytes()];
    for (name, bytes) in &files {
        pieces.push(name.as_bytes());
        pieces.push(bytes);
    }
    Ok(scene_hash(&pieces))
}

/// Two whole numbers `A{sep}B` of option `flag`.
pub(crate) fn number_pair(flag: &str, s: &str, sep: char) -> Result<(u32, u32)> {
    let (a, b) = s
        .split_once(sep)
        .with_context(|| format!("{flag} {s}: expected two whole numbers A{sep}B"))?;
    let num = |t: &str| -> Result<u32> {
        t.trim()
            .parse()
            .with_context(|| format!("{flag} {s}: \"{t}\" is not a whole number"))
    };
    Ok((num(a)?, num(b)?))
}

/// The window of `--grid COLSxROWS --tile COL,ROW` in a `w` x `h` image.
pub(crate) fn grid_tile(grid: &str, tile: &str, w: u32, h: u32) -> Result<Window> {
    let (cols, rows) = number_pair("--grid", grid, 'x')?;
    anyhow::ensure!(
        (1..=w).contains(&cols) && (1..=h).contains(&rows),
        "--grid {grid}: need 1 to {w} columns and 1 to {h} rows for the {w}x{h} image"
    );
    let (c, r) = number_pair("--tile", tile, ',')?;
    anyhow::ensure!(
        c < cols && r < rows,
        "--tile {tile}: outside the {cols}x{rows} grid (COL below {cols}, ROW below {rows})"
    );
    let cut = |i: u32, n: u32, len: u32| (i as u64 * len as u64 / n as u64) as u32;
    Ok(Window {
        x0: cut(c, cols, w),
        y0: cut(r, rows, h),
        x1: cut(c + 1, cols, w),
        y1: cut(r + 1, rows, h),
    })
}

/// The sample range of `--chunks n --chunk j` of `spp` samples.
pub(crate) fn sample_chunk(n: u32, j: u32, spp: u32) -> Result<SampleRange> {
    anyhow::ensure!(
        (1..=spp).contains(&n),
        "--chunks {n}: need 1 to {spp} chunks (the scene's spp)"
    );
    anyhow::ensure!(j < n, "--chunk {j}: must be below --chunks {n}");
    let cut = |i: u32| (i as u64 * spp as u64 / n as u64) as u32;
    Ok(SampleRange {
        start: cut(j),
        end: cut(j + 1),
    })
}

/// Parses `--crop X0,Y0,X1,Y1`.
pub(crate) fn parse_crop(s: &str) -> Result<Window> {
    let v: Vec<&str> = s.split(',').collect();
    anyhow::ensure!(
        v.len() == 4,
        "--crop {s}: expected four whole numbers X0,Y0,X1,Y1"
    );
    let mut n = [0u32; 4];
    for (i, t) in v.iter().enumerate() {
        n[i] = t
            .trim()
            .parse()
            .with_context(|| format!("--crop {s}: \"{t}\" is not a whole number"))?;
    }
    Ok(Window {
        x0: n[0],
        y0: n[1],
        x1: n[2],
        y1: n[3],
    })
}

pub(crate) fn merge_command(args: MergeArgs) -> Result<()> {
    crate::check_exposure(args.exposure)?;
    let inputs: Vec<(&str, &Path)> = args
        .parts
        .iter()
        .map(|p| ("the part", p.as_path()))
        .collect();
    let stats = args
        .stats
        .clone()
        .unwrap_or_else(|| args.out.with_extension("stats.json"));
    crate::check_outputs(&inputs, &args.out, Some(&stats), true)?;
    let mut parts = Vec::with_capacity(args.parts.len());
    for path in &args.parts {
        parts.push((path.clone(), read_partial(path)?));
    }
    let merged = merge(&parts)?;
    write_partial(&args.out, &merged)?;
    let png = args.out.with_extension("png");
    write_png(&png, &merged.beauty(), args.exposure)?;
    let mut text = serde_json::to_string_pretty(&merged.header.stats)?;
    text.push('\n');
    risotto::engine::output::write_file_atomically(&stats, text.as_bytes())
        .with_context(|| format!("cannot write stats to {}", stats.display()))?;
    eprintln!(
        "merged {} parts into {}, {} and {}",
        parts.len(),
        args.out.display(),
        png.display(),
        stats.display()
    );
    Ok(())
}

pub(crate) fn info_command(path: &Path) -> Result<()> {
    let p = read_partial(path)?;
    let h = &p.header;
    let w = h.window;
    println!(
        "{}",
        serde_json::json!({
            "resolution": [h.resolution.0, h.resolution.1],
            "window": [w.x0, w.y0, w.x1, w.y1],
            "samples": [h.samples.start, h.samples.end],
            "spp": h.spp,
            "seed": h.seed,
            "scene_hash": h.scene_hash,
            "aovs": p.aovs.is_some(),
        })
    );
    Ok(())
}
