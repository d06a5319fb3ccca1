//! SIGINT and SIGTERM during `risotto render`: the first one ends the render after the
//! passes in flight and the samples done are written as a partial render (the checkpoint
//! format, which `risotto merge` finishes); a second one exits at once (status 130).
//! A farm's pre-emption (SIGTERM, then SIGKILL after a grace period) thus leaves a partial
//! EXR when the grace period is longer than a pass ([`INTERRUPTIBLE_PASS`], or the
//! `--checkpoint` interval).
//!
//! [`INTERRUPTIBLE_PASS`]: risotto::engine::render::INTERRUPTIBLE_PASS

use anyhow::{Context, Result};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

/// The flag the handlers set, once installed.
static FLAG: OnceLock<&'static AtomicBool> = OnceLock::new();

/// Installs the handlers (once per process) and returns the flag they set, for
/// [`RenderOptions::interrupt`](risotto::engine::render::RenderOptions::interrupt).
pub(crate) fn install() -> Result<&'static AtomicBool> {
    if let Some(flag) = FLAG.get() {
        return Ok(flag);
    }
    let flag = Arc::new(AtomicBool::new(false));
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        // Registered first, so it sees the flag as the previous signal left it: the second
        // signal exits at once (async-signal-safe `_exit`), the first only sets the flag.
        signal_hook::flag::register_conditional_shutdown(signal, 130, Arc::clone(&flag))
            .context("cannot install the interrupt handler")?;
        signal_hook::flag::register(signal, Arc::clone(&flag))
            .context("cannot install the interrupt handler")?;
    }
    // The handlers hold the flag for the rest of the process; so does the render.
    let flag: &'static AtomicBool = Box::leak(Box::new(flag));
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
