//! The error measures of a sweep: a point from its repeats' renders against the reference
//! (MSE, relMSE and their spread, the bias of the mean, time), a curve from its points
//! (efficiency and fitted slopes), the error-against-time model the comparison uses, and
//! the reference made of two independent halves with its own noise (module docs of
//! [`crate::converge`]).

use super::*;

/// The reference `(a + b) / 2` of two independent halves, with its estimated noise: the
/// MSE and relMSE it adds to any independent test image's (module docs).
pub fn combine_halves(a: &Image, b: &Image) -> (Image, f64, f64) {
    let pixels: Vec<_> = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(&x, &y)| (x + y) * 0.5)
        .collect();
    let (mut n, mut sq, mut rel) = (0u64, 0.0f64, 0.0f64);
    for ((x, y), r) in a.pixels.iter().zip(&b.pixels).zip(&pixels) {
        for ((x, y), r) in x.to_array().into_iter().zip(y.to_array()).zip(r.to_array()) {
            if !(x.is_finite() && y.is_finite()) {
                continue;
            }
            let d = f64::from(x) - f64::from(y);
            let r = f64::from(r);
            n += 1;
            sq += d * d / 4.0;
            rel += d * d / 4.0 / (r * r + DEFAULT_RELMSE_EPS);
        }
    }
    let n = n.max(1) as f64;
    (
        Image::from_pixels(a.width, a.height, pixels),
        sq / n,
        rel / n,
    )
}

/// A point from its repeats.
pub(super) fn point(
    raw: &RawPoint,
    reference: &Image,
    info: &ReferenceInfo,
    metric: ErrorMetric,
) -> Result<Point, ConvergeError> {
    let renders = &raw.renders;
    let mut mse = Vec::new();
    let mut relmse = Vec::new();
    let mut bias = [0.0f64; 3];
    for s in renders {
        let m = compare(&s.image, reference).map_err(|e| ConvergeError::Reference {
            path: info.path.clone().unwrap_or_else(|| "(rendered)".into()),
            cause: e,
        })?;
        mse.push(m.all.rmse * m.all.rmse - info.noise_mse);
        relmse.push(m.all.relmse - info.noise_relmse);
        for (b, c) in bias.iter_mut().zip(&m.per_channel) {
            *b += (c.mean_test - c.mean_ref) / renders.len() as f64;
        }
    }
    let seconds: Vec<f64> = renders.iter().map(|s| s.seconds).collect();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (m, t) = (mean(&mse), min(&seconds));
    let spp_mean: Vec<f64> = renders.iter().map(|s| s.spp_mean).collect();
    Ok(Point {
        spp: raw.spp,
        repeats: renders.len() as u32,
        seconds: t,
        seconds_mean: mean(&seconds),
        seconds_max: max(&seconds),
        mse: m,
        mse_min: min(&mse),
        mse_max: max(&mse),
        rmse: m.max(0.0).sqrt(),
        relmse: mean(&relmse),
        relmse_min: min(&relmse),
        relmse_max: max(&relmse),
        bias,
        efficiency: efficiency(
            match metric {
                ErrorMetric::Mse => m,
                ErrorMetric::RelMse => mean(&relmse),
            },
            t,
        ),
        noise_target: raw.noise_target,
        spp_mean: raw.noise_target.map(|_| mean(&spp_mean)),
    })
}

/// `1 / (error x seconds)`, NaN unless both are positive.
fn efficiency(error: f64, seconds: f64) -> f64 {
    if error > 0.0 && seconds > 0.0 {
        1.0 / (error * seconds)
    } else {
        f64::NAN
    }
}

/// The least-squares line `y = a + b x` through `(x, y)`; `None` with fewer than two
/// distinct `x`.
pub fn fit_line(xy: &[(f64, f64)]) -> Option<(f64, f64)> {
    let n = xy.len() as f64;
    if xy.len() < 2 {
        return None;
    }
    let (sx, sy) = xy.iter().fold((0.0, 0.0), |(a, b), &(x, y)| (a + x, b + y));
    let (mx, my) = (sx / n, sy / n);
    let sxx: f64 = xy.iter().map(|&(x, _)| (x - mx) * (x - mx)).sum();
    let sxy: f64 = xy.iter().map(|&(x, y)| (x - mx) * (y - my)).sum();
    if sxx <= 1e-12 {
        return None;
    }
    let b = sxy / sxx;
    Some((my - b * mx, b))
}

/// A curve from its points.
pub(super) fn curve(
    registry: &TechniqueRegistry,
    variant: &Variant,
    points: Vec<Point>,
    metric: ErrorMetric,
) -> Curve {
    let error = |p: &Point| p.error(metric).0;
    let valid = || points.iter().filter(|p| error(p) > 0.0 && p.seconds > 0.0);
    let error_time: Vec<(f64, f64)> = valid().map(|p| (p.seconds.ln(), error(p).ln())).collect();
    // The root of the error (RMSE, or relative RMSE) against spp.
    let root_spp: Vec<(f64, f64)> = valid()
        .map(|p| (p.samples().ln(), 0.5 * error(p).ln()))
        .collect();
    let last = points.last();
    let techniques = &variant.techniques;
    let adaptive = variant
        .adaptive
        .map_or(ADAPTIVE.default, super::variant::adaptive_value);
    Curve {
        label: variant.label(),
        techniques: registry
            .applicable()
            .map(|t| {
                let v = techniques.get(registry, t.name).unwrap_or("?");
                (t.name.to_string(), v.to_string())
            })
            .chain([(ADAPTIVE.name.to_string(), adaptive.to_string())])
            .collect(),
        efficiency: last.map_or(f64::NAN, |p| p.efficiency),
        mse_time_slope: fit_line(&error_time).map_or(f64::NAN, |(_, b)| b),
        rmse_spp_slope: fit_line(&root_spp).map_or(f64::NAN, |(_, b)| b),
        points,
    }
}

/// The line `ln error = a + b ln seconds` of a curve (the sweep's metric; "MSE" below). Render times of small images are
/// dominated by timer and scheduling noise, so a uniform curve's error is not fitted
/// against them: `b` is the least-squares slope of ln MSE against ln spp (-1 when that is
/// not negative, as for Monte Carlo), and time is taken proportional to spp at the curve's
/// mean seconds per sample (total seconds over total spp, so its largest renders weigh
/// most). `None` without a valid point.
///
/// An adaptive curve (its points have noise targets) is fitted against its **seconds**
/// directly: its time is not proportional to its samples, since its samples go where the
/// noise is, in the paths that cost most. On `scenes/adaptive-smoke-ball.toml` (README,
/// "Accuracy and its cost") a mean of 429 spp took 1.9 ms per spp and 934 spp 1.4 ms,
/// while the uniform renders took 0.9 to 1.0 ms per spp, so a fit against the mean spp
/// with one cost per sample would misplace its early points in time by up to 2x. Its renders take at least `2 min_spp` samples per pixel, so they are not
/// the millisecond renders whose times are noise.
pub(super) fn error_time_model(c: &Curve, metric: ErrorMetric) -> Option<(f64, f64)> {
    let error = |p: &Point| p.error(metric).0;
    let valid: Vec<&Point> = c
        .points
        .iter()
        .filter(|p| error(p) > 0.0 && p.seconds > 0.0)
        .collect();
    let adaptive = valid.iter().any(|p| p.noise_target.is_some());
    let x = |p: &Point| match adaptive {
        true => p.seconds,
        false => p.spp as f64,
    };
    let pts: Vec<(f64, f64)> = valid.iter().map(|p| (x(p).ln(), error(p).ln())).collect();
    let (a, b) = match fit_line(&pts) {
        Some((a, b)) if b < 0.0 => (a, b),
        _ => pts.last().map(|&(x, y)| (y + x, -1.0))?,
    };
    if adaptive {
        return Some((a, b));
    }
    let per_spp = valid.iter().map(|p| p.seconds).sum::<f64>()
        / valid.iter().map(|p| p.spp as f64).sum::<f64>();
    // ln MSE = a + b ln spp, spp = seconds / per_spp.
    Some((a - b * per_spp.ln(), b))
}
