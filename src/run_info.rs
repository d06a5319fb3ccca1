//! The `"run"` facts of `--stats` ([`RunInfo`]): build, image, threads, phase times and
//! peak memory.

use risotto::engine::render::RenderOutput;
use risotto::engine::scene::CompiledScene;
use risotto::engine::stats::RunInfo;

/// The run facts of the render `result` of `scene` on `threads` workers, after
/// `load_seconds` of loading and `build_seconds` of compiling.
pub(crate) fn run_info(
    scene: &CompiledScene,
    result: &RenderOutput,
    threads: usize,
    load_seconds: f64,
    build_seconds: f64,
) -> RunInfo {
    let w = result.window;
    RunInfo {
        version: env!("CARGO_PKG_VERSION").to_owned(),
        commit: option_env!("RISOTTO_COMMIT").map(str::to_owned),
        resolution: [scene.camera.width, scene.camera.height],
        window: [w.x0, w.y0, w.x1, w.y1],
        spp: scene.settings.spp,
        samples: [result.samples.start, result.samples.end],
        threads,
        load_seconds,
        build_seconds,
        render_seconds: result.stats.wall_seconds,
        denoise_seconds: None,
        output_seconds: None,
        peak_resident_bytes: peak_resident_bytes(),
    }
}

/// The process's peak resident set size so far: `VmHWM` of `/proc/self/status` (Linux);
/// `None` where there is no such file.
pub(crate) fn peak_resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    parse_vm_hwm(&status)
}

/// `VmHWM:   123456 kB` in a `/proc/PID/status` text, in bytes.
fn parse_vm_hwm(status: &str) -> Option<u64> {
    risotto::engine::render::proc_bytes(status, "VmHWM")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vm_hwm_is_read_in_bytes() {
        let status = "Name:\trisotto\nVmPeak:\t  9000 kB\nVmHWM:\t   2048 kB\nVmRSS:\t 1000 kB\n";
        assert_eq!(parse_vm_hwm(status), Some(2048 * 1024));
        assert_eq!(parse_vm_hwm("VmRSS: 1 kB\n"), None);
        assert_eq!(parse_vm_hwm("VmHWM: 12 MB\n"), None);
        // This process: more than a megabyte, if the platform has the file.
        if let Some(b) = peak_resident_bytes() {
            assert!(b > 1 << 20, "{b}");
        }
    }
}
