//! SIGINT and SIGTERM during `risotto render`: the first one ends the render after the
//! passes in flight and the samples done are written as a partial render (the checkpoint
//! format, which `risotto merge` finishes); a second one exits at once (status 130), after
//! removing the temporaries of the outputs being written (so a second Ctrl-C during the
//! final write leaves the previous file, or none, and no hidden `.NAME.PID.tmp`).
//! A farm's pre-emption (SIGTERM, then SIGKILL after a grace period) thus leaves a partial
//! EXR when the grace period is longer than a pass ([`INTERRUPTIBLE_PASS`], or the
//! `--checkpoint` interval).
//!
//! [`INTERRUPTIBLE_PASS`]: risotto::engine::render::INTERRUPTIBLE_PASS

use anyhow::{Context, Result};
use risotto::engine::output::remove_temporaries_for_exit;
use signal_hook::consts::{SIGINT, SIGTERM};
use signal_hook::iterator::Signals;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::OnceLock;

/// The flag the handlers set, once installed.
static FLAG: OnceLock<&'static AtomicBool> = OnceLock::new();

/// Installs the handlers (once per process) and returns the flag they set, for
/// [`RenderOptions::interrupt`](risotto::engine::render::RenderOptions::interrupt).
pub(crate) fn install() -> Result<&'static AtomicBool> {
    if let Some(flag) = FLAG.get() {
        return Ok(flag);
    }
    let flag: &'static AtomicBool = Box::leak(Box::new(AtomicBool::new(false)));
    // The signals are handled on a thread of their own (signal-hook's self-pipe iterator),
    // not in the handler: removing files and exiting are not async-signal-safe.
    let mut signals =
        Signals::new([SIGINT, SIGTERM]).context("cannot install the interrupt handler")?;
    std::thread::Builder::new()
        .name("interrupts".into())
        .spawn(move || {
            for _ in signals.forever() {
                if flag.swap(true, Ordering::SeqCst) {
                    // Held until the process is gone: no write starts or renames meanwhile.
                    let _writes = remove_temporaries_for_exit();
                    std::process::exit(130);
                }
            }
        })
        .context("cannot start the interrupt handler's thread")?;
    Ok(FLAG.get_or_init(|| flag))
}

/// Whether an interrupt has arrived.
pub(crate) fn requested() -> bool {
    FLAG.get().is_some_and(|f| f.load(Ordering::Relaxed))
}

/// The error of an interrupted render: what was written and how to finish it.
#[derive(Debug)]
pub(crate) struct Interrupted(pub(crate) String);

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Interrupted {}
