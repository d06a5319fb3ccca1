//! What a [`Sweep`] reports: the equal-time and equal-error comparison of its curves, the
//! printed table, and the CSV, JSON and plot files.

use super::*;

/// One row of [`Sweep::comparison`].
#[derive(Clone, Debug, serde::Serialize)]
pub struct Comparison {
    /// The variant.
    pub label: String,
    /// Its efficiency.
    pub efficiency: f64,
    /// Its error (the sweep's metric) at the common time over the best one's.
    pub equal_time_error_ratio: f64,
    /// Its time to reach the common error over the best one's.
    pub equal_error_time_ratio: f64,
}

/// The common time and error of [`Sweep::comparison`] and its rows.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ComparisonTable {
    /// The time every curve reaches (the smallest of their largest times).
    pub equal_time_seconds: f64,
    /// The error every curve reaches (the largest of their smallest errors).
    pub equal_error: f64,
    /// One row per curve.
    pub rows: Vec<Comparison>,
}

impl Sweep {
    /// Equal-time error and equal-error time of every curve relative to the best, read off
    /// each curve's line `ln MSE = a + b ln seconds` (fitted against spp with time
    /// proportional to spp, an adaptive curve's against its seconds; see `error_time_model`)
    /// at the largest time all curves reach and at the smallest MSE all reach.
    pub fn comparison(&self) -> ComparisonTable {
        let models: Vec<Option<(f64, f64)>> = self
            .curves
            .iter()
            .map(|c| error_time_model(c, self.metric))
            .collect();
        let t = self
            .curves
            .iter()
            .filter_map(|c| c.points.iter().map(|p| p.seconds).reduce(f64::max))
            .fold(f64::INFINITY, f64::min);
        let e = self
            .curves
            .iter()
            .filter_map(|c| {
                c.points
                    .iter()
                    .map(|p| p.error(self.metric).0)
                    .filter(|&m| m > 0.0)
                    .reduce(f64::min)
            })
            .fold(0.0, f64::max);
        let mse_at = |m: &Option<(f64, f64)>| m.map_or(f64::NAN, |(a, b)| (a + b * t.ln()).exp());
        let time_at =
            |m: &Option<(f64, f64)>| m.map_or(f64::NAN, |(a, b)| ((e.ln() - a) / b).exp());
        let mses: Vec<f64> = models.iter().map(mse_at).collect();
        let times: Vec<f64> = models.iter().map(time_at).collect();
        let best = |v: &[f64]| {
            v.iter()
                .copied()
                .filter(|x| x.is_finite())
                .fold(f64::INFINITY, f64::min)
        };
        let (best_mse, best_time) = (best(&mses), best(&times));
        ComparisonTable {
            equal_time_seconds: t,
            equal_error: e,
            rows: self
                .curves
                .iter()
                .zip(mses.iter().zip(&times))
                .map(|(c, (m, s))| Comparison {
                    label: c.label.clone(),
                    efficiency: c.efficiency,
                    equal_time_error_ratio: m / best_mse,
                    equal_error_time_ratio: s / best_time,
                })
                .collect(),
        }
    }

    /// The curve with the highest efficiency.
    pub fn most_efficient(&self) -> Option<&Curve> {
        self.curves
            .iter()
            .filter(|c| c.efficiency.is_finite())
            .max_by(|a, b| a.efficiency.total_cmp(&b.efficiency))
    }

    /// The printed table: one row per curve with its efficiency, slopes, equal-time MSE and
    /// equal-error time relative to the best.
    pub fn table(&self) -> String {
        let cmp = self.comparison();
        let width = self
            .curves
            .iter()
            .map(|c| c.label.len())
            .max()
            .unwrap_or(9)
            .max(9);
        let mut s = String::new();
        let _ = writeln!(
            s,
            "reference: {}",
            match (&self.reference.path, self.reference.spp) {
                (Some(p), _) => p.clone(),
                (None, Some(n)) => format!(
                    "rendered, {} at {n} spp ({:.2} s), noise {} {:.3e} subtracted",
                    self.reference.techniques.as_deref().unwrap_or("?"),
                    self.reference.seconds.unwrap_or(f64::NAN),
                    self.metric.label(),
                    match self.metric {
                        ErrorMetric::Mse => self.reference.noise_mse,
                        ErrorMetric::RelMse => self.reference.noise_relmse,
                    }
                ),
                (None, None) => "?".into(),
            }
        );
        let m = self.metric.label();
        let _ = writeln!(
            s,
            "equal time: {:.3} s; equal error: {m} {:.3e}",
            cmp.equal_time_seconds, cmp.equal_error
        );
        let _ = writeln!(
            s,
            "{:<width$}  {:>8}  {:>8}  {:>10}  {:>10}  {:>14}  {:>15}",
            "technique",
            "max spp",
            "seconds",
            format!("1/({m}*s)"),
            "RMSE~spp^b",
            format!("equal-time {m}"),
            format!("equal-{m} time")
        );
        for (c, row) in self.curves.iter().zip(&cmp.rows) {
            let last = c.points.last();
            let _ = writeln!(
                s,
                "{:<width$}  {:>8}  {:>8.3}  {:>10.3e}  {:>10.2}  {:>13.2}x  {:>14.2}x",
                c.label,
                last.map_or(0, |p| p.spp),
                last.map_or(f64::NAN, |p| p.seconds),
                c.efficiency,
                c.rmse_spp_slope,
                row.equal_time_error_ratio,
                row.equal_error_time_ratio
            );
        }
        s
    }

    /// `converge.csv`: a header of [`CSV_COLUMNS`], then one row per point (`noise_target`
    /// and `spp_mean` empty for a uniform point).
    pub fn csv(&self) -> String {
        let mut s = CSV_COLUMNS.join(",");
        s.push('\n');
        for c in &self.curves {
            for p in &c.points {
                let nums = [
                    p.seconds,
                    p.seconds_mean,
                    p.seconds_max,
                    p.mse,
                    p.mse_min,
                    p.mse_max,
                    p.rmse,
                    p.relmse,
                    p.relmse_min,
                    p.relmse_max,
                    p.bias[0],
                    p.bias[1],
                    p.bias[2],
                    p.efficiency,
                ];
                let _ = write!(s, "{},{},{}", c.label, p.spp, p.repeats);
                for x in nums {
                    let _ = write!(s, ",{x:e}");
                }
                // Adaptive points only; empty cells for uniform ones.
                let target = p.noise_target.map_or(String::new(), |x| format!("{x:e}"));
                let mean = p.spp_mean.map_or(String::new(), |x| format!("{x:e}"));
                let _ = write!(s, ",{target},{mean}");
                s.push('\n');
            }
        }
        s
    }

    /// `converge.json`: the sweep (reference, curves with their points) and the comparison.
    pub fn json(&self) -> serde_json::Value {
        serde_json::json!({
            "width": self.width,
            "height": self.height,
            "reference": self.reference,
            "metric": self.metric,
            "curves": self.curves,
            "comparison": self.comparison(),
        })
    }

    /// Writes `converge.csv`, `converge.json`, `converge.png` and `converge.svg` into `dir`
    /// (created if needed).
    pub fn write_all(&self, dir: &Path) -> Result<(), ConvergeError> {
        let write = |name: &str, text: String| {
            let path = dir.join(name);
            std::fs::write(&path, text).map_err(|e| ConvergeError::Write {
                path: path.display().to_string(),
                message: e.to_string(),
            })
        };
        std::fs::create_dir_all(dir).map_err(|e| ConvergeError::Write {
            path: dir.display().to_string(),
            message: e.to_string(),
        })?;
        write("converge.csv", self.csv())?;
        let json = serde_json::to_string_pretty(&self.json()).unwrap_or_default();
        write("converge.json", json + "\n")?;
        self.write_plots(dir)
    }

    /// The plots `converge.png` and `converge.svg` in `dir`.
    #[cfg(feature = "plots")]
    fn write_plots(&self, dir: &Path) -> Result<(), ConvergeError> {
        super::plot::plot_sweep(self, &dir.join("converge.png"), &dir.join("converge.svg")).map_err(
            |e| ConvergeError::Write {
                path: dir.join("converge.png").display().to_string(),
                message: e,
            },
        )
    }

    /// Without the `plots` feature there are no plots: the CSV and JSON hold every number.
    #[cfg(not(feature = "plots"))]
    fn write_plots(&self, _dir: &Path) -> Result<(), ConvergeError> {
        Ok(())
    }
}
