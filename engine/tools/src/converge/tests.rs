//! Tests of `converge.rs`.

use super::*;
use risotto_components::Rgb;

fn noisy(seed: u64, sigma: f32) -> Image {
    let mut rng = risotto_systems::sampler::SplitMix64(seed);
    let pixels = (0..4096)
        .map(|i| {
            let base = 0.2 + (i % 64) as f32 / 64.0;
            let mut n = || (rng.f32() - 0.5) * sigma * 12f32.sqrt();
            Rgb::new(base + n(), base + n(), base + n())
        })
        .collect();
    Image::from_pixels(64, 64, pixels)
}

#[test]
fn the_halves_estimate_of_reference_noise_matches_its_true_mse() {
    // a, b: truth plus independent noise of standard deviation 0.1; their mean has
    // MSE 0.01 / 2 against the truth, which the halves must estimate.
    let truth = noisy(0, 0.0);
    let (r, noise, _) = combine_halves(&noisy(1, 0.1), &noisy(2, 0.1));
    let true_mse = compare(&r, &truth).unwrap().all.rmse.powi(2);
    assert!((true_mse - 0.005).abs() < 0.0005, "true {true_mse}");
    assert!(
        (noise - true_mse).abs() < 0.0005,
        "estimate {noise} vs {true_mse}"
    );
}

#[test]
fn a_point_against_itself_has_zero_error_and_bias() {
    let img = noisy(3, 0.1);
    let info = ReferenceInfo {
        source: "file".into(),
        path: Some("x".into()),
        spp: None,
        techniques: None,
        seconds: None,
        noise_mse: 0.0,
        noise_relmse: 0.0,
    };
    let s = [Sample {
        image: img.clone(),
        seconds: 0.5,
    }];
    let p = point(4, &s, &img, &info).unwrap();
    assert_eq!((p.mse, p.relmse, p.bias), (0.0, 0.0, [0.0; 3]));
    assert!(p.efficiency.is_nan());
    let other = noisy(4, 0.1);
    let q = point(4, &s, &other, &info).unwrap();
    assert!(q.mse > 0.0 && q.relmse > 0.0 && q.efficiency > 0.0);
}

#[test]
fn comparison_reads_the_fitted_lines_at_common_time_and_error() {
    // Two exact Monte Carlo curves MSE = k / t: b is 4 times less efficient, so at equal
    // time its MSE is 4x, and reaching equal MSE takes it 4x the time.
    let mk = |label: &str, k: f64| Curve {
        label: label.into(),
        techniques: BTreeMap::new(),
        points: [1.0, 2.0, 4.0]
            .iter()
            .map(|&t: &f64| Point {
                spp: t as u32,
                repeats: 1,
                seconds: t,
                seconds_mean: t,
                seconds_max: t,
                mse: k / t,
                mse_min: k / t,
                mse_max: k / t,
                rmse: (k / t).sqrt(),
                relmse: k / t,
                relmse_min: k / t,
                relmse_max: k / t,
                bias: [0.0; 3],
                efficiency: 1.0 / k,
            })
            .collect(),
        efficiency: 1.0 / k,
        mse_time_slope: -1.0,
        rmse_spp_slope: -0.5,
    };
    let sweep = Sweep {
        width: 1,
        height: 1,
        reference: ReferenceInfo {
            source: "file".into(),
            path: None,
            spp: None,
            techniques: None,
            seconds: None,
            noise_mse: 0.0,
            noise_relmse: 0.0,
        },
        curves: vec![mk("a", 1.0), mk("b", 4.0)],
    };
    let c = sweep.comparison();
    assert!((c.rows[0].equal_time_mse_ratio - 1.0).abs() < 1e-9);
    assert!((c.rows[1].equal_time_mse_ratio - 4.0).abs() < 1e-9);
    assert!((c.rows[1].equal_error_time_ratio - 4.0).abs() < 1e-9);
    assert_eq!(sweep.most_efficient().unwrap().label, "a");
    let (a, b) = fit_line(&[(0.0, 1.0), (1.0, 3.0), (2.0, 5.0)]).unwrap();
    assert!((a - 1.0).abs() < 1e-12 && (b - 2.0).abs() < 1e-12);
    let csv = sweep.csv();
    assert_eq!(csv.lines().count(), 7);
    assert!(csv
        .lines()
        .all(|l| l.split(',').count() == CSV_COLUMNS.len()));
}
