//! `risotto render --progress json`: machine-readable progress lines for farm managers that
//! parse a task's output (Deadline, OpenCue, Tractor and the like read a task's stdout).
//!
//! One JSON object per line on stdout, at most one a second and a last one when the render
//! ends: `{"event":"progress","samples_done":N,"samples_total":T,"fraction":F,
//! "samples_per_second":S,"elapsed_seconds":E,"eta_seconds":R,"samples_total_is_a_cap":C}`
//! (`eta_seconds` is `null` before the first sample; `C` is `true` for an adaptive render,
//! whose `T` is only the most it can take, and whose `eta_seconds` is then `null` until
//! the last line), then `"event":"done"` with the same fields.

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
    format!("{} samples/s", human_count(per_second))
}

/// A count, three significant digits with an SI prefix: `1.23 M`, `999`, `4.50`; `0` for
/// nothing (and for what is not a count: negative or not finite).
fn human_count(n: f64) -> String {
    if !n.is_finite() || n <= 0.0 {
        return "0".into();
    }
    let (value, prefix) = [(1e9, " G"), (1e6, " M"), (1e3, " k")]
        .into_iter()
        .find(|&(scale, _)| n >= scale)
        .map_or((n, ""), |(scale, p)| (n / scale, p));
    let decimals = if value >= 100.0 {
        0
    } else if value >= 10.0 {
        1
    } else {
        2
    };
    format!("{value:.decimals$}{prefix}")
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

/// The bar of an adaptive render (`--noise-target`): it stops when its pixels reach the
/// target, so the scene's spp times the pixels is only the most it can take. The bar shows
/// the samples done against that cap, and no percentage or time left, which would be the
/// cap's.
pub fn adaptive_bar_style() -> indicatif::ProgressStyle {
    indicatif::ProgressStyle::with_template(
        "{spinner} [{elapsed_precise}] {wide_bar} {samples} of at most {cap} samples, {rate} \
         (adaptive: stops at the noise target)",
    )
    .expect("static template is valid")
    .with_key(
        "rate",
        |state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
            let _ = w.write_str(&human_rate(state.per_sec()));
        },
    )
    .with_key(
        "samples",
        |state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
            let _ = w.write_str(&human_count(state.pos() as f64));
        },
    )
    .with_key(
        "cap",
        |state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
            let _ = w.write_str(&human_count(state.len().unwrap_or(0) as f64));
        },
    )
}

/// Counts samples from the render's workers and prints a line when one is due.
pub struct JsonProgress {
    total: u64,
    /// Whether `total` is only the most the render can take (an adaptive render): then
    /// there is no time left to estimate.
    at_most: bool,
    done: AtomicU64,
    start: Instant,
    interval: Duration,
    last: Mutex<Instant>,
}

impl JsonProgress {
    /// Progress over `total` samples, or at most `total` when `at_most` (an adaptive
    /// render), a line at most every `interval`.
    pub fn new(total: u64, at_most: bool, interval: Duration) -> Self {
        let start = Instant::now();
        JsonProgress {
            total,
            at_most,
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
        let eta = if self.at_most {
            // An adaptive render ends below its cap: nothing is left when it is done, and
            // before that the cap's time left is not the render's.
            match event {
                "done" => "0.000".to_string(),
                _ => "null".to_string(),
            }
        } else if rate > 0.0 {
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
             \"elapsed_seconds\":{elapsed:.3},\"eta_seconds\":{eta},\
             \"samples_total_is_a_cap\":{}}}",
            self.total, self.at_most
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
        assert_eq!(human_count(999.0), "999");
        assert_eq!(human_count(0.0), "0");
    }

    #[test]
    fn lines_are_json_with_the_counts() {
        let p = JsonProgress::new(1000, false, Duration::from_secs(3600));
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
        assert_eq!(v["samples_total_is_a_cap"], false);
    }

    /// An adaptive render's total is a cap: no time left is estimated from it, and the
    /// lines say so.
    #[test]
    fn an_adaptive_renders_lines_give_no_time_left() {
        let p = JsonProgress::new(1000, true, Duration::from_secs(3600));
        p.inc(250);
        std::thread::sleep(Duration::from_millis(5));
        let v: serde_json::Value = serde_json::from_str(&p.line("progress")).unwrap();
        assert!(v["eta_seconds"].is_null(), "{v}");
        assert_eq!(v["samples_total_is_a_cap"], true);
        assert_eq!(v["samples_total"], 1000);
        // It ends below the cap, with nothing left.
        let done: serde_json::Value = serde_json::from_str(&p.line("done")).unwrap();
        assert_eq!(done["eta_seconds"].as_f64(), Some(0.0), "{done}");
    }

    /// A terminal that keeps everything the bar draws.
    #[derive(Debug, Default)]
    struct Screen(std::sync::Arc<Mutex<String>>);

    impl indicatif::TermLike for Screen {
        fn width(&self) -> u16 {
            160
        }
        fn move_cursor_up(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_down(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_right(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_left(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn write_line(&self, s: &str) -> std::io::Result<()> {
            self.write_str(s)
        }
        fn write_str(&self, s: &str) -> std::io::Result<()> {
            self.0.lock().unwrap().push_str(s);
            Ok(())
        }
        fn clear_line(&self) -> std::io::Result<()> {
            Ok(())
        }
        fn flush(&self) -> std::io::Result<()> {
            Ok(())
        }
    }

    /// The bar as drawn with `style` at 37 % of 4.19 M samples.
    fn drawn(style: indicatif::ProgressStyle) -> String {
        let screen = Screen::default();
        let shown = screen.0.clone();
        let target = indicatif::ProgressDrawTarget::term_like(Box::new(screen));
        let bar = indicatif::ProgressBar::with_draw_target(Some(4_194_304), target);
        bar.set_style(style);
        bar.set_position(1_551_892);
        bar.tick();
        let text = shown.lock().unwrap().clone();
        text
    }

    #[test]
    fn an_adaptive_bar_shows_samples_against_the_cap_and_no_time_left() {
        let adaptive = drawn(adaptive_bar_style());
        assert!(
            adaptive.contains("1.55 M of at most 4.19 M samples"),
            "{adaptive}"
        );
        assert!(
            !adaptive.contains('%') && !adaptive.contains("left"),
            "{adaptive}"
        );
        // The uniform bar, drawn the same way, has both.
        let uniform = drawn(bar_style());
        assert!(
            uniform.contains("37%") && uniform.contains("left"),
            "{uniform}"
        );
    }
}
