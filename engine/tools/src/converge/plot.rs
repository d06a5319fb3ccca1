//! The convergence plot of a [`Sweep`]: log-log RMSE against render seconds, one labelled
//! curve per technique (min/max error bars over the repeats), the efficiency
//! `1 / (MSE x seconds)` of each in the legend. Drawn with plotters once per backend: a
//! bitmap (encoded as PNG with the `png` crate) and an SVG.
//!
//! Text is laid out with DejaVu Sans, embedded in the binary (the `dejavu` crate) and
//! registered with plotters' `ab_glyph` text backend, so plots render the same on a machine
//! without any font installed (plotters' default `ttf` backend asks the system's fontconfig).

use crate::converge::{ErrorMetric, Sweep};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Plot width in pixels (PNG) or user units (SVG).
pub const PLOT_WIDTH: u32 = 1000;
/// Plot height.
pub const PLOT_HEIGHT: u32 = 680;

/// Curve colours: distinguishable, and readable on white.
const COLOURS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// Registers the embedded font as plotters' `sans-serif` (once).
fn register_font() -> Result<(), String> {
    static DONE: std::sync::OnceLock<Result<(), String>> = std::sync::OnceLock::new();
    DONE.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular())
            .map_err(|_| "the embedded DejaVu Sans font does not load".to_string())
    })
    .clone()
}

/// One curve's drawable points: `(seconds, root of the error, of the best repeat's, of the worst's)`,
/// leaving out points whose corrected error is not positive.
fn drawable(sweep: &Sweep) -> Vec<Vec<(f64, f64, f64, f64)>> {
    sweep
        .curves
        .iter()
        .map(|c| {
            c.points
                .iter()
                .map(|p| (p.seconds, p.error(sweep.metric)))
                .filter(|&(t, (e, _, _))| e > 0.0 && t > 0.0)
                .map(|(t, (e, lo, hi))| (t, e.sqrt(), lo.max(e * 1e-3).sqrt(), hi.max(e).sqrt()))
                .collect()
        })
        .collect()
}

/// Draws the plot on `root`.
fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, sweep: &Sweep) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let curves = drawable(sweep);
    let all = || curves.iter().flatten();
    let (mut x0, mut x1, mut y0, mut y1) = all().fold(
        (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64),
        |(a, b, c, d), &(t, _, lo, hi)| (a.min(t), b.max(t), c.min(lo), d.max(hi)),
    );
    if !(x0.is_finite() && y0.is_finite() && x1 > 0.0 && y1 > 0.0) {
        (x0, x1, y0, y1) = (0.01, 1.0, 1e-3, 1.0);
    }
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!(
                "Error vs render time ({}x{}, {} reference)",
                sweep.width, sweep.height, sweep.reference.source
            ),
            ("sans-serif", 24),
        )
        .margin(18)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(log_axis(x0 / 1.4, x1 * 1.4), log_axis(y0 / 1.6, y1 * 1.6))
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("render time (s)")
        .y_desc(match sweep.metric {
            ErrorMetric::Mse => "RMSE vs reference",
            ErrorMetric::RelMse => "relative RMSE vs reference",
        })
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 17))
        .x_label_formatter(&|x| seconds_label(*x))
        .y_label_formatter(&|y| format!("{y:.1e}"))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(e)?;
    for (i, (c, pts)) in sweep.curves.iter().zip(&curves).enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let style = colour.stroke_width(2);
        chart
            .draw_series(LineSeries::new(pts.iter().map(|p| (p.0, p.1)), style))
            .map_err(e)?
            .label(format!(
                "{}   1/({}\u{b7}s) = {:.3e}",
                c.label,
                sweep.metric.label(),
                c.efficiency
            ))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], style));
        chart
            .draw_series(
                pts.iter()
                    .map(|p| Circle::new((p.0, p.1), 4, colour.filled())),
            )
            .map_err(e)?;
        chart
            .draw_series(
                pts.iter()
                    .filter(|p| p.3 > p.2)
                    .map(|p| ErrorBar::new_vertical(p.0, p.2, p.1, p.3, colour, 8)),
            )
            .map_err(e)?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .label_font(("sans-serif", 15))
        .draw()
        .map_err(e)?;
    root.present().map_err(e)
}

/// Writes the plot of `sweep` as a PNG to `png` and as an SVG to `svg`.
pub fn plot_sweep(sweep: &Sweep, png: &Path, svg: &Path) -> Result<(), String> {
    register_font()?;
    let (w, h) = (PLOT_WIDTH, PLOT_HEIGHT);
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        draw(&root, sweep)?;
    }
    let file = std::fs::File::create(png).map_err(|e| format!("{}: {e}", png.display()))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder
        .write_header()
        .and_then(|mut wr| wr.write_image_data(&rgb))
        .map_err(|e| format!("{}: {e}", png.display()))?;
    let root = SVGBackend::new(svg, (w, h)).into_drawing_area();
    draw(&root, sweep)
}

/// A log axis on `[lo, hi]` with its ticks from [`log_ticks`]. plotters' own log key points
/// put a light point at 10 times each decade's start as well as the next decade's bold
/// one, a float apart, so that axes spanning about one decade drew the same label twice, on
/// top of itself.
fn log_axis(lo: f64, hi: f64) -> plotters::coord::combinators::WithKeyPoints<LogCoord<f64>> {
    let (labelled, lines) = log_ticks(lo, hi);
    (lo..hi)
        .log_scale()
        .with_key_points(labelled)
        .with_light_points(lines)
}

/// The ticks of a log axis on `[lo, hi]` (`0 < lo < hi`): labelled ones at 1, 2 and 5 times
/// each power of ten, light grid lines at 1 to 9 times each, each value once and in
/// increasing order. Where fewer than two labelled values fall inside, every grid line is
/// labelled.
fn log_ticks(lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    let (mut labelled, mut lines) = (Vec::new(), Vec::new());
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return (labelled, lines);
    }
    for k in lo.log10().floor() as i32..=hi.log10().ceil() as i32 {
        for m in 1..=9 {
            // m 10^k rounded once (0.3, not 3 x 0.1).
            let v = if k < 0 {
                m as f64 / 10f64.powi(-k)
            } else {
                m as f64 * 10f64.powi(k)
            };
            if v < lo || v > hi {
                continue;
            }
            lines.push(v);
            if matches!(m, 1 | 2 | 5) {
                labelled.push(v);
            }
        }
    }
    if labelled.len() < 2 {
        labelled = lines.clone();
    }
    (labelled, lines)
}

/// A time axis label: three decimals with the trailing zeros dropped ("0.25", "6", "10"),
/// short enough that a log axis's labels between 1 and 10 s do not run into each other.
fn seconds_label(x: f64) -> String {
    let s = format!("{x:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

#[cfg(test)]
mod tests {
    #[test]
    fn log_ticks_are_each_value_once_and_labelled_at_one_two_five() {
        let (labelled, lines) = super::log_ticks(0.007, 0.16);
        assert_eq!(labelled, [0.01, 0.02, 0.05, 0.1]);
        assert_eq!(lines.first(), Some(&0.007));
        assert_eq!(lines.last(), Some(&0.1));
        assert_eq!(lines.len(), 3 + 9 + 1);
        assert!(lines.windows(2).all(|w| w[0] < w[1]), "{lines:?}");
        // Within one decade and short of its 2 and 5: every grid line gets a label.
        let (labelled, lines) = super::log_ticks(0.3, 0.45);
        assert_eq!((labelled.clone(), lines), (vec![0.3, 0.4], vec![0.3, 0.4]));
        assert!(super::log_ticks(0.0, 1.0).0.is_empty());
    }

    #[test]
    fn seconds_labels_drop_trailing_zeros() {
        assert_eq!(super::seconds_label(6.0), "6");
        assert_eq!(super::seconds_label(10.0), "10");
        assert_eq!(super::seconds_label(0.25), "0.25");
        assert_eq!(super::seconds_label(0.0015), "0.002");
    }
}
