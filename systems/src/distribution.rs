//! Piecewise-constant distributions for importance sampling (the environment map's
//! sampling, [`crate::environment_map`], is built on them).
//!
//! The 1D and 2D distributions follow Pharr, Jakob, Humphreys, *Physically Based Rendering*
//! (3rd ed.), §13.6.5 (inverting the CDF of a piecewise-constant 1D function) and §13.6.7
//! (2D sampling as a marginal density over rows times a conditional density within the
//! row).
//!
//! Robustness rules (no NaN ever comes out):
//! - negative or non-finite input values count as 0;
//! - an all-zero (or empty) function falls back to the uniform distribution;
//! - a zero-valued bin is never returned by sampling when the total is non-zero, and its
//!   pdf is 0.

use glam::Vec2;

/// Largest `f32` below 1; sampled positions stay in `[0, 1)`.
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// The bin of `x` among `n` equal bins of `[0, 1]` (`x = 1` belongs to the last bin).
/// Every lookup (pdf, texel fetch) goes through this one formula so that a sampled position
/// and a later lookup of that position agree on the bin.
#[inline]
pub(crate) fn bin_of(x: f32, n: usize) -> usize {
    // `as usize` saturates: negative and NaN give 0.
    ((x * n as f32) as usize).min(n - 1)
}

/// Nudges `x` by single ulps until `bin_of(x, n) == bin`. `(bin + du) / n` can round across
/// the bin edge (e.g. `du` just below 1); the nudge keeps sample and pdf consistent.
#[inline]
fn snap_into_bin(mut x: f32, bin: usize, n: usize) -> f32 {
    while bin_of(x, n) > bin {
        x = f32::from_bits(x.to_bits() - 1);
    }
    while bin_of(x, n) < bin {
        x = f32::from_bits(x.to_bits() + 1);
    }
    x
}

/// Clamps a random number into `[0, 1)` (NaN becomes 0).
#[inline]
fn clamp_unit(u: f32) -> f32 {
    if u >= 0.0 {
        u.min(ONE_MINUS_EPSILON)
    } else {
        0.0
    }
}

/// A piecewise-constant density on `[0, 1)` with `n` equal bins, proportional to the given
/// values.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    /// Sanitised bin values (all 1 in the uniform fallback).
    func: Vec<f32>,
    /// `cdf[i]` = probability of bins `< i`; `n + 1` entries, `cdf[0] = 0`, `cdf[n] = 1`.
    cdf: Vec<f32>,
    /// `∫ func` over `[0, 1]` = mean of `func`.
    func_int: f32,
    /// Sum of `func`.
    func_sum: f32,
    /// Integral of the sanitised input (0 when the fallback is active).
    input_int: f32,
}

impl Distribution1D {
    /// A distribution proportional to `values` (negative/non-finite entries count as 0).
    /// All-zero or empty input gives the uniform distribution (an empty input has one bin).
    pub fn new(values: &[f32]) -> Self {
        let mut func: Vec<f32> = values
            .iter()
            .map(|&v| if v.is_finite() && v > 0.0 { v } else { 0.0 })
            .collect();
        if func.is_empty() {
            func.push(0.0);
        }
        let n = func.len();
        // Accumulate in f64: with many bins a running f32 sum loses the small ones.
        let total: f64 = func.iter().map(|&v| f64::from(v)).sum();
        let input_int = (total / n as f64) as f32;
        let uniform = total <= 0.0;
        if uniform {
            func.iter_mut().for_each(|v| *v = 1.0);
        }
        let total = if uniform { n as f64 } else { total };
        let mut cdf = Vec::with_capacity(n + 1);
        cdf.push(0.0f32);
        let mut run = 0.0f64;
        for &v in &func {
            run += f64::from(v);
            cdf.push((run / total) as f32);
        }
        // Exactly 1 at the end, so every u in [0, 1) falls into some bin.
        cdf[n] = 1.0;
        Distribution1D {
            func,
            cdf,
            func_int: (total / n as f64) as f32,
            func_sum: total as f32,
            input_int,
        }
    }

    /// Number of bins.
    pub fn len(&self) -> usize {
        self.func.len()
    }

    /// Always false (an empty input still has one bin).
    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// `∫₀¹ f(x) dx` of the (sanitised) input function; 0 for all-zero input even though
    /// sampling then falls back to uniform.
    pub fn integral(&self) -> f32 {
        self.input_int
    }

    /// The CDF, `len() + 1` entries: entry `i` is the probability of the bins below `i`
    /// (the first is 0, the last 1). [`Self::sample_discrete`] returns the number of entries
    /// `1..len()` that are `<= u` after clamping `u` into `[0, 1)`.
    pub fn cdf(&self) -> &[f32] {
        &self.cdf
    }

    /// Largest bin index `o` with `cdf[o] <= u`. Zero-probability bins have
    /// `cdf[o] == cdf[o + 1]`, so taking the *largest* such index skips them.
    #[inline]
    fn find_bin(&self, u: f32) -> usize {
        let n = self.func.len();
        if n <= 16 {
            // Few bins (e.g. choosing among a handful of lights): counting the CDF entries
            // <= u compiles to compares without branches, where a binary search mispredicts
            // about every other step on random u. Same result as the search below.
            return self.cdf[1..n].iter().filter(|&&c| c <= u).count();
        }
        self.cdf[..n].partition_point(|&c| c <= u).saturating_sub(1)
    }

    /// Samples a position by inverting the CDF (PBR 3rd ed. eq. 13.5 and §13.6.5). Returns
    /// `(x in [0, 1), pdf(x), bin index)`. The pdf is positive whenever the input has a
    /// non-zero total.
    pub fn sample_continuous(&self, u: f32) -> (f32, f32, usize) {
        let u = clamp_unit(u);
        let n = self.func.len();
        let o = self.find_bin(u);
        let width = self.cdf[o + 1] - self.cdf[o];
        // Position within the bin: the CDF is linear there.
        let du = if width > 0.0 {
            ((u - self.cdf[o]) / width).clamp(0.0, ONE_MINUS_EPSILON)
        } else {
            0.0
        };
        let x = ((o as f32 + du) / n as f32).min(ONE_MINUS_EPSILON);
        let x = snap_into_bin(x, o, n);
        (x, self.func[o] / self.func_int, o)
    }

    /// Samples a bin with probability proportional to its value: `(index, pmf)`.
    #[inline]
    pub fn sample_discrete(&self, u: f32) -> (usize, f32) {
        let o = self.find_bin(clamp_unit(u));
        (o, self.func[o] / self.func_sum)
    }

    /// Density of [`sample_continuous`](Self::sample_continuous) at `x` (0 outside
    /// `[0, 1]`).
    pub fn pdf(&self, x: f32) -> f32 {
        if !(0.0..=1.0).contains(&x) {
            return 0.0;
        }
        self.func[bin_of(x, self.func.len())] / self.func_int
    }

    /// Probability of [`sample_discrete`](Self::sample_discrete) returning bin `i` (0 out of
    /// range).
    pub fn pmf(&self, i: usize) -> f32 {
        self.func.get(i).map_or(0.0, |&v| v / self.func_sum)
    }
}

/// A piecewise-constant density on `[0, 1)²` over a `width` x `height` grid (row-major,
/// row 0 at `v = 0`), sampled as marginal-over-rows times conditional-within-row
/// (PBR 3rd ed. §13.6.7).
#[derive(Clone, Debug)]
pub struct Distribution2D {
    width: usize,
    height: usize,
    /// One distribution over `u` per row.
    conditional: Vec<Distribution1D>,
    /// Distribution over rows, proportional to each row's integral.
    marginal: Distribution1D,
}

impl Distribution2D {
    /// A distribution proportional to `values` (row-major, `width * height` entries).
    ///
    /// # Panics
    /// When the dimensions are zero or do not match `values.len()`.
    pub fn new(values: &[f32], width: usize, height: usize) -> Self {
        assert!(
            width > 0 && height > 0 && values.len() == width * height,
            "Distribution2D::new: {} values for {width}x{height}",
            values.len()
        );
        let conditional: Vec<Distribution1D> = values
            .chunks_exact(width)
            .map(Distribution1D::new)
            .collect();
        // Rows weighted by their true integral: an all-zero row gets weight 0 (its uniform
        // fallback conditional is then never used by sampling).
        let row_int: Vec<f32> = conditional.iter().map(Distribution1D::integral).collect();
        Distribution2D {
            width,
            height,
            conditional,
            marginal: Distribution1D::new(&row_int),
        }
    }

    /// Grid width (bins along `u`).
    pub fn width(&self) -> usize {
        self.width
    }

    /// Grid height (bins along `v`).
    pub fn height(&self) -> usize {
        self.height
    }

    /// `∫∫ f(u, v) du dv` of the input (0 for all-zero input).
    pub fn integral(&self) -> f32 {
        self.marginal.integral()
    }

    /// Samples `(u, v)` in `[0, 1)²` from two uniform numbers; returns the point and its
    /// density `p(u, v) = p(v) p(u | v)`.
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (v, pdf_v, row) = self.marginal.sample_continuous(u.y);
        let (x, pdf_u, _) = self.conditional[row].sample_continuous(u.x);
        (Vec2::new(x, v), pdf_u * pdf_v)
    }

    /// Density of [`sample`](Self::sample) at `uv` (0 outside the unit square).
    pub fn pdf(&self, uv: Vec2) -> f32 {
        if !((0.0..=1.0).contains(&uv.x) && (0.0..=1.0).contains(&uv.y)) {
            return 0.0;
        }
        let row = bin_of(uv.y, self.height);
        self.conditional[row].pdf(uv.x) * self.marginal.pdf(uv.y)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    use crate::sampler::SplitMix64 as Rng;
    /// Pearson's chi-square statistic of observed counts against expected probabilities.
    /// Bins with zero probability must be empty. Returns (statistic, degrees of freedom).
    pub(crate) fn chi_square(counts: &[u64], probs: &[f64], n: u64) -> (f64, usize) {
        let mut stat = 0.0;
        let mut df = 0usize;
        for (&c, &p) in counts.iter().zip(probs) {
            if p == 0.0 {
                assert_eq!(c, 0, "a zero-probability bin was sampled");
                continue;
            }
            let e = p * n as f64;
            stat += (c as f64 - e).powi(2) / e;
            df += 1;
        }
        (stat, df.saturating_sub(1))
    }

    /// A loose upper quantile (~p < 1e-5) of chi-square with `df` degrees of freedom:
    /// mean `df`, standard deviation `sqrt(2 df)`. A wrong sampler exceeds it by orders of
    /// magnitude at these sample counts.
    pub(crate) fn chi_square_limit(df: usize) -> f64 {
        df as f64 + 6.0 * (2.0 * df as f64).sqrt() + 10.0
    }

    const FUNC: [f32; 10] = [0.0, 1.0, 3.0, 0.0, 0.5, 2.0, 0.0, 7.0, 0.02, 4.0];

    #[test]
    fn one_d_histogram_matches_pdf_within_bins() {
        let d = Distribution1D::new(&FUNC);
        let sum: f64 = FUNC.iter().map(|&v| f64::from(v)).sum();
        assert!((d.integral() as f64 - sum / 10.0).abs() < 1e-6);
        // Four sub-bins per bin: also checks that x is uniform inside its bin.
        let sub = 4;
        let probs: Vec<f64> = FUNC
            .iter()
            .flat_map(|&v| std::iter::repeat_n(f64::from(v) / sum / sub as f64, sub))
            .collect();
        let mut counts = vec![0u64; FUNC.len() * sub];
        let mut rng = Rng(7);
        let n = 400_000;
        for _ in 0..n {
            let (x, pdf, i) = d.sample_continuous(rng.f32());
            assert!((0.0..1.0).contains(&x));
            assert_eq!(i, (x * 10.0) as usize);
            // analytic density: f(x) / ∫f
            let want = f64::from(FUNC[i]) / (sum / 10.0);
            assert!(
                (f64::from(pdf) - want).abs() < 1e-5 * want,
                "{pdf} vs {want}"
            );
            assert_eq!(pdf, d.pdf(x));
            counts[(x * (10 * sub) as f32) as usize] += 1;
        }
        let (stat, df) = chi_square(&counts, &probs, n);
        assert!(stat < chi_square_limit(df), "chi2 {stat} with {df} dof");
    }

    #[test]
    fn one_d_discrete_matches_pmf() {
        let d = Distribution1D::new(&FUNC);
        let sum: f64 = FUNC.iter().map(|&v| f64::from(v)).sum();
        let probs: Vec<f64> = FUNC.iter().map(|&v| f64::from(v) / sum).collect();
        let mut counts = vec![0u64; FUNC.len()];
        let mut rng = Rng(11);
        let n = 200_000;
        for _ in 0..n {
            let (i, pmf) = d.sample_discrete(rng.f32());
            assert!((f64::from(pmf) - probs[i]).abs() < 1e-6);
            assert_eq!(pmf, d.pmf(i));
            counts[i] += 1;
        }
        let (stat, df) = chi_square(&counts, &probs, n);
        assert!(stat < chi_square_limit(df), "chi2 {stat} with {df} dof");
        let total: f32 = (0..FUNC.len()).map(|i| d.pmf(i)).sum();
        assert!((total - 1.0).abs() < 1e-6);
    }

    #[test]
    fn one_d_edges_and_degenerate_inputs() {
        let d = Distribution1D::new(&FUNC);
        // Extreme random numbers never land on zero bins and stay inside [0, 1).
        for u in [0.0, 1e-30, ONE_MINUS_EPSILON, 1.0, 2.0, -1.0, f32::NAN] {
            let (x, pdf, i) = d.sample_continuous(u);
            assert!(
                (0.0..1.0).contains(&x) && pdf > 0.0 && FUNC[i] > 0.0,
                "u={u}"
            );
            let (j, pmf) = d.sample_discrete(u);
            assert!(pmf > 0.0 && FUNC[j] > 0.0, "u={u}");
        }
        assert_eq!(d.sample_continuous(0.0).2, 1);
        assert_eq!(d.sample_continuous(1.0).2, 9);
        assert_eq!(d.pdf(0.05), 0.0);
        assert_eq!(d.pdf(1.5), 0.0);
        assert_eq!(d.pdf(f32::NAN), 0.0);

        // All zero (and garbage) -> uniform, no NaN.
        for vals in [
            &[0.0f32; 5][..],
            &[f32::NAN, -1.0, f32::INFINITY][..],
            &[][..],
        ] {
            let d = Distribution1D::new(vals);
            assert_eq!(d.integral(), 0.0);
            for k in 0..20 {
                let u = k as f32 / 20.0;
                let (x, pdf, _) = d.sample_continuous(u);
                assert!((x - u).abs() < 1e-6, "uniform: x = u");
                assert_eq!(pdf, 1.0);
                let (_, pmf) = d.sample_discrete(u);
                assert!((pmf * d.len() as f32 - 1.0).abs() < 1e-6);
            }
        }
        // Bin edges that round across: many bins, u just below a CDF step.
        let d = Distribution1D::new(&[1.0; 3]);
        let mut rng = Rng(3);
        for _ in 0..10_000 {
            let (x, pdf, i) = d.sample_continuous(rng.f32());
            assert_eq!(bin_of(x, 3), i);
            assert_eq!(pdf, 1.0);
        }
        let d = Distribution1D::new(&[1.0; 7]);
        for i in 0..7u32 {
            let edge = (i + 1) as f32 / 7.0;
            for k in 0..4 {
                let u = f32::from_bits(edge.to_bits() - k);
                let (x, _, o) = d.sample_continuous(u);
                assert_eq!(bin_of(x, 7), o);
            }
        }
    }

    #[test]
    fn one_d_pdf_integrates_to_one() {
        let d = Distribution1D::new(&FUNC);
        let m = 100_000;
        let s: f64 = (0..m)
            .map(|k| f64::from(d.pdf((k as f32 + 0.5) / m as f32)))
            .sum::<f64>()
            / m as f64;
        assert!((s - 1.0).abs() < 1e-4, "{s}");
    }

    fn grid_values(w: usize, h: usize) -> Vec<f32> {
        let mut rng = Rng(99);
        (0..w * h)
            .map(|i| {
                if i % 7 == 3 {
                    0.0
                } else {
                    rng.f32() * rng.f32() * 10.0
                }
            })
            .collect()
    }

    #[test]
    fn two_d_histogram_matches_pdf() {
        let (w, h) = (8, 6);
        let mut vals = grid_values(w, h);
        // a whole zero row must never be sampled
        vals[2 * w..3 * w].iter_mut().for_each(|v| *v = 0.0);
        let d = Distribution2D::new(&vals, w, h);
        let sum: f64 = vals.iter().map(|&v| f64::from(v)).sum();
        let probs: Vec<f64> = vals.iter().map(|&v| f64::from(v) / sum).collect();
        let mut counts = vec![0u64; w * h];
        let mut rng = Rng(5);
        let n = 300_000;
        for _ in 0..n {
            let (uv, pdf) = d.sample(rng.vec2());
            assert!((0.0..1.0).contains(&uv.x) && (0.0..1.0).contains(&uv.y));
            let (i, j) = ((uv.x * w as f32) as usize, (uv.y * h as f32) as usize);
            // density = f / mean(f)
            let want = f64::from(vals[j * w + i]) * (w * h) as f64 / sum;
            assert!(
                (f64::from(pdf) - want).abs() < 1e-4 * want,
                "{pdf} vs {want}"
            );
            assert_eq!(pdf, d.pdf(uv));
            counts[j * w + i] += 1;
        }
        let (stat, df) = chi_square(&counts, &probs, n);
        assert!(stat < chi_square_limit(df), "chi2 {stat} with {df} dof");
        assert!((f64::from(d.integral()) - sum / (w * h) as f64).abs() < 1e-5);
    }

    #[test]
    fn two_d_all_zero_is_uniform() {
        let d = Distribution2D::new(&[0.0; 12], 4, 3);
        let mut rng = Rng(1);
        for _ in 0..1000 {
            let (uv, pdf) = d.sample(rng.vec2());
            assert_eq!(pdf, 1.0);
            assert_eq!(d.pdf(uv), 1.0);
        }
        assert_eq!(d.pdf(Vec2::new(1.5, 0.5)), 0.0);
    }
}
