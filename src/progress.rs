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

/// A rate for the progress bar, three significant digits with an SI prefix:
/// `2.59 M samples/s` rather than indicatif's `2,590,365.4194/s`.
pub fn human_rate(per_second: f64) -> String {
    if !per_second.is_finite() || per_second <= 0.0 {
        return "- samples/s".into();
    }
    let (value, prefix) = [(1e9, " G "), (1e6, " M "), (1e3, " k ")]
        .into_iter()
        .find(|&(scale, _)| per_second >= scale)
        .map_or((per_second, " "), |(scale, p)| (per_second / scale, p));
    let decimals = if value >= 100.0 {
        0
    } else if value >= 10.0 {
        1
    } else {
        2
    };
    format!("{value:.decimals$}{prefix}samples/s")
}

/// The progress bar's style: elapsed time, bar, percentage, [`human_rate`], time left.
pub fn bar_style() -> indicatif::ProgressStyle {
    indicatif::ProgressStyle::with_template(
        "{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% {rate}, {eta} left",
    )
    .expect("static template is valid")
    .with_key(
        "rate",
        |state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
            let _ = w.write_str(&human_rate(state.per_sec()));
        },
    )
}

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
    fn rates_read_like_numbers() {
        assert_eq!(human_rate(2_590_365.419_4), "2.59 M samples/s");
        assert_eq!(human_rate(15_300.0), "15.3 k samples/s");
        assert_eq!(human_rate(999.0), "999 samples/s");
        assert_eq!(human_rate(4.5), "4.50 samples/s");
        assert_eq!(human_rate(3.2e9), "3.20 G samples/s");
        assert_eq!(human_rate(f64::NAN), "- samples/s");
    }

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
