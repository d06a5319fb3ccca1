//! What a film costs in memory, and the check that a render's film fits the machine.
//!
//! A render's film (the per-pixel sums of every tile, gathered into one image of sums,
//! then the means and the output layers made from it) peaks at about
//! [`FILM_BYTES_PER_PIXEL`] of resident memory per pixel of the window, measured by
//! `tests/film_memory.rs` (the peak resident memory of renders of 512^2 and 1024^2 films of
//! an otherwise trivial scene, differenced). The pixel limit
//! ([`MAX_FILM_PIXELS`](super::MAX_FILM_PIXELS)) bounds any request a file can make; this
//! check refuses, before anything is allocated, a film that the machine's memory cannot
//! hold, with both figures in the message, rather than letting the operating system kill
//! the process part way through.

/// Peak resident bytes a render's film takes per pixel of its window, without AOVs
/// (measured: see the module docs). A bidirectional integrator's splat film adds
/// [`SplatFilm`](risotto_systems::film::SplatFilm)'s 24 bytes, the AOVs
/// [`AOV_BYTES_PER_PIXEL`].
pub const FILM_BYTES_PER_PIXEL: u64 = 108;

/// What keeping the first-hit AOVs ([`RenderOptions::aovs`](super::RenderOptions::aovs))
/// adds to a render's peak a pixel, measured as [`FILM_BYTES_PER_PIXEL`] is (111.6 bytes
/// on Linux, 2026-12-07): the f64 sums of albedo, normal and depth in every tile and again
/// in the gathered image (56 bytes each; their means in the output, 28 bytes, come after
/// the tiles are freed). Without them a render's peak is half what it was when every render
/// kept them (224 bytes a pixel).
pub const AOV_BYTES_PER_PIXEL: u64 = 112;

/// The memory a film of `pixels` pixels needs, in bytes (saturating).
pub fn film_bytes(pixels: u64) -> u64 {
    pixels.saturating_mul(FILM_BYTES_PER_PIXEL)
}

/// What adaptive sampling ([`NoiseTarget`](super::NoiseTarget), either rule) adds to a
/// render's peak a pixel, measured as [`FILM_BYTES_PER_PIXEL`] is (80.3 bytes on Linux,
/// 2026-12-07, without AOVs; 108.8 with them): the estimates made at each pass end (means, variances, counts and errors,
/// 32 bytes), the tiles' sample ranges for the next pass (8 bytes,
/// [`TileFilm::sample_ranges`]), and the summary's copies of the means and variances beside
/// the gathered output.
///
/// [`TileFilm::sample_ranges`]: crate::integrator::TileFilm::sample_ranges
pub const ADAPTIVE_BYTES_PER_PIXEL: u64 = 80;

/// What the unbiased stopping rule ([`StoppingRule::Unbiased`](super::StoppingRule)) adds
/// on top of [`ADAPTIVE_BYTES_PER_PIXEL`], measured the same way (4 bytes, 2026-12-07): the
/// pilot's pooled per-sample errors, held for the whole render. The pilot's tile films (a
/// [`Film`]'s radiance sums, squared sums and count, 52 bytes: no AOVs,
/// [`TileFilm::without_aovs`]) and its estimates are dropped before the image's passes,
/// and their peak is below the render's later one.
///
/// [`Film`]: risotto_systems::film::Film
/// [`TileFilm::without_aovs`]: crate::integrator::TileFilm::without_aovs
pub const PILOT_BYTES_PER_PIXEL: u64 = 4;

/// `Err(message)` when a film of `pixels` pixels, `bytes_per_pixel` each (the renderer's:
/// [`FILM_BYTES_PER_PIXEL`], plus [`ADAPTIVE_BYTES_PER_PIXEL`] when adaptive and
/// [`PILOT_BYTES_PER_PIXEL`] with the unbiased stopping rule), needs more than `physical`
/// bytes of memory.
pub fn check_film_memory(
    pixels: u64,
    bytes_per_pixel: u64,
    physical: Option<u64>,
) -> Result<(), String> {
    let need = pixels.saturating_mul(bytes_per_pixel);
    match physical {
        Some(have) if need > have => Err(format!(
            "a film of {pixels} pixels needs about {:.1} GB ({bytes_per_pixel} bytes a \
             pixel), more than this machine's {:.1} GB of memory; render it in parts \
             (`--crop`, then `risotto merge`)",
            need as f64 / 1e9,
            have as f64 / 1e9
        )),
        _ => Ok(()),
    }
}

/// The machine's physical memory in bytes: `MemTotal` of `/proc/meminfo` (Linux); `None`
/// where that cannot be read (the check is then the pixel limit alone).
pub fn physical_memory() -> Option<u64> {
    proc_bytes(&std::fs::read_to_string("/proc/meminfo").ok()?, "MemTotal")
}

/// The line `KEY:  123456 kB` of a Linux `/proc` text (`/proc/meminfo`,
/// `/proc/PID/status`), in bytes; `None` without it or in another unit.
pub fn proc_bytes(text: &str, key: &str) -> Option<u64> {
    let line = text
        .lines()
        .find(|l| l.strip_prefix(key).is_some_and(|r| r.starts_with(':')))?;
    let mut parts = line[key.len() + 1..].split_whitespace();
    let kib: u64 = parts.next()?.parse().ok()?;
    (parts.next()? == "kB").then(|| kib.saturating_mul(1024))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mem_total_parses_in_bytes_and_rejects_other_units() {
        let text = "MemTotal:       24576000 kB\nMemFree:         1000 kB\n";
        assert_eq!(proc_bytes(text, "MemTotal"), Some(24_576_000 * 1024));
        assert_eq!(proc_bytes("MemTotal: 12 MB\n", "MemTotal"), None);
        assert_eq!(proc_bytes("MemFree: 12 kB\n", "MemTotal"), None);
        assert_eq!(proc_bytes("MemTotalX: 12 kB\n", "MemTotal"), None);
    }

    #[test]
    fn a_film_larger_than_memory_is_refused_with_both_figures() {
        // 8192^2 pixels need about 7.2 GB: refused on a 4 GB machine, accepted on 8 GB and
        // where the memory is unknown.
        let pixels = 8192 * 8192;
        let film = FILM_BYTES_PER_PIXEL;
        let err = check_film_memory(pixels, film, Some(4 << 30)).unwrap_err();
        assert!(err.contains("67108864 pixels"), "{err}");
        assert!(err.contains("7.2 GB"), "{err}");
        assert!(err.contains("4.3 GB"), "{err}");
        assert!(check_film_memory(pixels, film, Some(8 << 30)).is_ok());
        assert!(check_film_memory(pixels, film, None).is_ok());
        assert!(check_film_memory(u64::MAX, film, Some(1)).is_err());
        // With the AOVs (220 bytes a pixel, 14.8 GB) and adaptive with the unbiased rule
        // (192 bytes a pixel, 12.9 GB): over an 8 GB machine (8.6 GB) that holds the plain
        // film.
        let aovs = film + AOV_BYTES_PER_PIXEL;
        let err = check_film_memory(pixels, aovs, Some(8 << 30)).unwrap_err();
        assert!(
            err.contains("220 bytes a pixel") && err.contains("14.8 GB"),
            "{err}"
        );
        let adaptive = film + ADAPTIVE_BYTES_PER_PIXEL + PILOT_BYTES_PER_PIXEL;
        let err = check_film_memory(pixels, adaptive, Some(8 << 30)).unwrap_err();
        assert!(err.contains("192 bytes a pixel"), "{err}");
        assert!(err.contains("12.9 GB"), "{err}");
    }
}
