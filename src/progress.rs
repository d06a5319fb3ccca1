//! `risotto render --progress json`: machine-readable progress lines for farm managers that
//! parse a task's output (Deadline, OpenCue, Tractor and the like read a task's stdout).
//!
//! One JSON object per line on stdout, at most one a second and a last one when the render
//! ends: `{"event":"progress","samples_done":N,"samples_total":T,"fraction":F,
//! "samples_per_second":S,"elapsed_seconds":E,"eta_seconds":R}` (`eta_seconds` is `null`
//! before the first sample), then `"event":"done"` with the same fields.

use std::io::Write as _;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Counts samples from the render's workers and prints a line when one is due.
pub struct JsonProgress {
    total: u64,
    done: AtomicU64,
    start: Instant,
    interval: Duration,
    last: Mutex<Instant>,
}

impl JsonProgress {
    /// Progress over `total` samples, a line at most every `interval`.
    pub fn new(total: u64, interval: Duration) -> Self {
        let start = Instant::now();
        JsonProgress {
            total,
            done: AtomicU64::new(0),
            start,
            interval,
            last: Mutex::new(start),
        }
    }

    /// Adds `n` finished samples (called from any worker).
    pub fn inc(&self, n: u64) {
        self.done.fetch_add(n, Ordering::Relaxed);
        // Only one worker prints; the others never wait for it.
        let Ok(mut last) = self.last.try_lock() else {
            return;
        };
        if last.elapsed() >= self.interval {
            *last = Instant::now();
            self.print("progress");
        }
    }

    /// The last line.
    pub fn finish(&self) {
        self.print("done");
    }

    /// The line for the current state.
    pub fn line(&self, event: &str) -> String {
        let done = self.done.load(Ordering::Relaxed).min(self.total);
        let elapsed = self.start.elapsed().as_secs_f64();
        let rate = if elapsed > 0.0 {
            done as f64 / elapsed
        } else {
            0.0
        };
        let eta = if rate > 0.0 {
            format!("{:.3}", (self.total - done) as f64 / rate)
        } else {
            "null".to_string()
        };
        let fraction = if self.total > 0 {
            done as f64 / self.total as f64
        } else {
            1.0
        };
        format!(
            "{{\"event\":\"{event}\",\"samples_done\":{done},\"samples_total\":{},\
             \"fraction\":{fraction:.6},\"samples_per_second\":{rate:.1},\
             \"elapsed_seconds\":{elapsed:.3},\"eta_seconds\":{eta}}}",
            self.total
        )
    }

    fn print(&self, event: &str) {
        let mut out = std::io::stdout().lock();
        // A closed stdout must not stop the render.
        let _ = writeln!(out, "{}", self.line(event));
        let _ = out.flush();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_are_json_with_the_counts() {
        let p = JsonProgress::new(1000, Duration::from_secs(3600));
        let first: serde_json::Value = serde_json::from_str(&p.line("progress")).unwrap();
        assert_eq!(first["samples_done"], 0);
        assert!(first["eta_seconds"].is_null());
        p.inc(250);
        std::thread::sleep(Duration::from_millis(5));
        let v: serde_json::Value = serde_json::from_str(&p.line("done")).unwrap();
        assert_eq!(v["event"], "done");
        assert_eq!(v["samples_done"], 250);
        assert_eq!(v["samples_total"], 1000);
        assert!((v["fraction"].as_f64().unwrap() - 0.25).abs() < 1e-9);
        assert!(v["samples_per_second"].as_f64().unwrap() > 0.0);
        assert!(v["eta_seconds"].as_f64().unwrap() > 0.0);
    }
}
