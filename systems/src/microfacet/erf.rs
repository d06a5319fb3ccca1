//! The error function and its inverse in single precision, for the Beckmann distribution
//! (its Smith `Lambda` and its visible-normal sampler are written with them).

/// `erf(x)` to an absolute error below `1.5e-7` (Abramowitz and Stegun 1964, formula
/// 7.1.26, evaluated in `f64` and extended to negative `x` by oddness). `erf(+-inf) = +-1`.
#[inline]
pub fn erf(x: f32) -> f32 {
    const P: f64 = 0.327_591_1;
    const A: [f64; 5] = [
        0.254_829_592,
        -0.284_496_736,
        1.421_413_741,
        -1.453_152_027,
        1.061_405_429,
    ];
    let ax = (x as f64).abs();
    let t = 1.0 / (1.0 + P * ax);
    let poly = t * (A[0] + t * (A[1] + t * (A[2] + t * (A[3] + t * A[4]))));
    let y = 1.0 - poly * (-ax * ax).exp();
    (if x < 0.0 { -y } else { y }) as f32
}

/// `erf^-1(x)` for `x` in `(-1, 1)` (Giles 2010, "Approximating the erfinv function", GPU
/// Computing Gems, the single-precision rational approximation: relative error a few
/// `1e-7`); `+-inf` at `+-1`, NaN outside.
#[inline]
pub fn erfinv(x: f32) -> f32 {
    if x.abs() >= 1.0 {
        return if x.abs() == 1.0 {
            x * f32::INFINITY
        } else {
            f32::NAN
        };
    }
    let w = -((1.0 - x) * (1.0 + x)).ln();
    let p = if w < 5.0 {
        let w = w - 2.5;
        [
            3.432_739_4e-7,
            -3.523_387_7e-6,
            -4.391_506_5e-6,
            2.185_808_7e-4,
            -1.253_725e-3,
            -4.177_681_6e-3,
            0.246_640_73,
            1.501_409_4,
        ]
        .iter()
        .fold(2.810_226_4e-8f32, |p, &c| c + p * w)
    } else {
        let w = w.sqrt() - 3.0;
        [
            1.009_505_6e-4,
            1.349_343_2e-3,
            -3.673_428_4e-3,
            5.739_507_7e-3,
            -7.622_461_3e-3,
            9.438_870_5e-3,
            1.001_674,
            2.832_976_8,
        ]
        .iter()
        .fold(-2.002_142_6e-4f32, |p, &c| c + p * w)
    };
    p * x
}

/// `1 / sqrt(pi)`.
pub const FRAC_1_SQRT_PI: f32 = (1.0 / 1.772_453_850_905_516) as f32;

/// `sqrt(pi)` in `f64`, for the tests.
#[cfg(test)]
const SQRT_PI: f64 = 1.772_453_850_905_516;

#[cfg(test)]
mod tests {
    use super::*;

    /// `erf` by its Maclaurin series (exact to `f64` rounding for `|x| <= 3`): a reference
    /// that shares nothing with the rational approximation.
    fn erf_series(x: f64) -> f64 {
        let mut term = x;
        let mut sum = x;
        for n in 1..200 {
            term *= -x * x / n as f64;
            sum += term / (2 * n + 1) as f64;
        }
        2.0 / SQRT_PI * sum
    }

    #[test]
    fn erf_matches_its_series() {
        for i in -300..=300 {
            let x = i as f64 / 100.0;
            let got = erf(x as f32) as f64;
            assert!((got - erf_series(x)).abs() < 3e-7, "erf({x}) = {got}");
        }
        assert_eq!(erf(f32::INFINITY), 1.0);
        assert_eq!(erf(f32::NEG_INFINITY), -1.0);
    }

    #[test]
    fn erfinv_inverts_erf() {
        for i in -999..=999 {
            let y = i as f32 / 1000.0;
            let x = erfinv(y);
            assert!(
                (erf_series(x as f64) - y as f64).abs() < 2e-6,
                "erfinv({y}) = {x}"
            );
        }
        // Deep in the tail (the second branch): erf(3.5) = 1 - 7.43e-7.
        let x = erfinv(1.0 - 7.430_984e-7);
        assert!((x - 3.5).abs() < 0.02, "{x}");
        assert_eq!(erfinv(1.0), f32::INFINITY);
    }
}
