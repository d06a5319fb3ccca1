//! Tests of `converge.rs`.

use super::*;
use risotto_components::Rgb;
use risotto_engine::render::StoppingRule;

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
    let raw = RawPoint {
        spp: 4,
        noise_target: None,
        renders: vec![Sample {
            image: img.clone(),
            seconds: 0.5,
            spp_mean: 4.0,
            spp_min: 4,
        }],
    };
    let p = point(&raw, &img, &info, ErrorMetric::Mse).unwrap();
    assert_eq!((p.mse, p.relmse, p.bias), (0.0, 0.0, [0.0; 3]));
    assert!(p.efficiency.is_nan());
    assert_eq!((p.noise_target, p.spp_mean), (None, None));
    let other = noisy(4, 0.1);
    let q = point(&raw, &other, &info, ErrorMetric::Mse).unwrap();
    assert!(q.mse > 0.0 && q.relmse > 0.0 && q.efficiency > 0.0);
    assert_eq!(
        (q.error(ErrorMetric::Mse).0, q.efficiency),
        (q.mse, 1.0 / (q.mse * 0.5))
    );
    // The relMSE metric: the same measures, compared by the relMSE (which differs).
    let r = point(&raw, &other, &info, ErrorMetric::RelMse).unwrap();
    assert_eq!((r.mse, r.relmse), (q.mse, q.relmse));
    assert_ne!(r.relmse, r.mse);
    assert_eq!(
        (r.error(ErrorMetric::RelMse).0, r.efficiency),
        (r.relmse, 1.0 / (r.relmse * 0.5))
    );
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
                noise_target: None,
                spp_mean: None,
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
        metric: ErrorMetric::Mse,
        curves: vec![mk("a", 1.0), mk("b", 4.0)],
    };
    let c = sweep.comparison();
    assert!((c.rows[0].equal_time_error_ratio - 1.0).abs() < 1e-9);
    assert!((c.rows[1].equal_time_error_ratio - 4.0).abs() < 1e-9);
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

/// A reference that is exact (a file), for hand-made sweeps.
fn exact() -> ReferenceInfo {
    ReferenceInfo {
        source: "file".into(),
        path: None,
        spp: None,
        techniques: None,
        seconds: None,
        noise_mse: 0.0,
        noise_relmse: 0.0,
    }
}

/// A hand-made point of `seconds` and `mse`, adaptive when `target` is given.
fn made(spp: u32, seconds: f64, mse: f64, target: Option<(f64, f64)>) -> Point {
    Point {
        spp,
        repeats: 1,
        seconds,
        seconds_mean: seconds,
        seconds_max: seconds,
        mse,
        mse_min: mse,
        mse_max: mse,
        rmse: mse.sqrt(),
        relmse: mse,
        relmse_min: mse,
        relmse_max: mse,
        bias: [0.0; 3],
        efficiency: 1.0 / (mse * seconds),
        noise_target: target.map(|(t, _)| t),
        spp_mean: target.map(|(_, m)| m),
    }
}

#[test]
fn an_adaptive_point_records_its_target_and_mean_spp_in_csv_and_json() {
    let img = noisy(5, 0.1);
    let sample = |spp_mean: f64| Sample {
        image: noisy(6, 0.1),
        seconds: 0.25,
        spp_mean,
        spp_min: 32,
    };
    let raw = RawPoint {
        spp: 256,
        noise_target: Some(0.1),
        renders: vec![sample(40.0), sample(50.0)],
    };
    let p = point(&raw, &img, &exact(), ErrorMetric::Mse).unwrap();
    // The mean over the repeats of each render's mean spp; the cap stays the spp.
    assert_eq!(
        (p.spp, p.noise_target, p.spp_mean),
        (256, Some(0.1), Some(45.0))
    );
    assert_eq!(p.samples(), 45.0);
    let adaptive = Variant {
        techniques: Techniques::default(),
        adaptive: Some(StoppingRule::Window),
    };
    assert_eq!(adaptive.label(), "adaptive=on");
    let uniform = made(4, 0.1, 0.01, None);
    let sweep = Sweep {
        width: 64,
        height: 64,
        reference: exact(),
        metric: ErrorMetric::Mse,
        curves: vec![
            curve(
                &TechniqueRegistry::new(Default::default(), []),
                &Variant::from(Techniques::default()),
                vec![uniform],
                ErrorMetric::Mse,
            ),
            curve(
                &TechniqueRegistry::new(Default::default(), []),
                &adaptive,
                vec![p],
                ErrorMetric::Mse,
            ),
        ],
    };
    assert_eq!(sweep.curves[1].techniques["adaptive"], "on");
    assert_eq!(sweep.curves[0].techniques["adaptive"], "off");
    let csv = sweep.csv();
    let rows: Vec<Vec<&str>> = csv.lines().map(|l| l.split(',').collect()).collect();
    let col = |name: &str| CSV_COLUMNS.iter().position(|c| *c == name).unwrap();
    // The new columns come last, after the existing ones in their order.
    assert_eq!(&CSV_COLUMNS[17..], ["noise_target", "spp_mean"]);
    assert_eq!(CSV_COLUMNS[16], "efficiency");
    assert_eq!(rows[0], CSV_COLUMNS);
    assert_eq!(
        (rows[1][col("noise_target")], rows[1][col("spp_mean")]),
        ("", "")
    );
    assert_eq!(rows[2][col("technique")], "adaptive=on");
    assert_eq!(rows[2][col("spp")], "256");
    assert_eq!(rows[2][col("noise_target")], "1e-1");
    assert_eq!(rows[2][col("spp_mean")].parse::<f64>(), Ok(45.0));
    let json = sweep.json();
    let points = |c: usize| json["curves"][c]["points"][0].clone();
    assert!(points(0).get("noise_target").is_none() && points(0).get("spp_mean").is_none());
    assert_eq!(points(1)["spp_mean"], 45.0);
    assert_eq!(points(1)["noise_target"], 0.1);
}

#[test]
fn the_comparison_fits_an_adaptive_curve_against_its_seconds() {
    // Uniform: MSE = 1 / t at spp = t. Adaptive: every point capped at 256 spp, MSE =
    // 2 / t^2, its pixels taking a mean of 3, 4 and 8 samples (not proportional to its
    // time: its samples cost more where the noise is). At the common time 4 s: 0.25
    // against 0.125, so the uniform curve has 2x the MSE; the common MSE 0.25 the adaptive
    // curve reaches at sqrt(8) s, so the uniform one takes 4 / sqrt(8) = sqrt(2) x its
    // time. Fitted against the cap or the mean spp these would be lost.
    let times = [1.0f64, 2.0, 4.0];
    let uniform: Vec<Point> = times
        .iter()
        .map(|&t| made(t as u32, t, 1.0 / t, None))
        .collect();
    let adaptive: Vec<Point> = times
        .iter()
        .zip([(0.4, 3.0), (0.2, 4.0), (0.1, 8.0)])
        .map(|(&t, target)| made(256, t, 2.0 / (t * t), Some(target)))
        .collect();
    let registry = TechniqueRegistry::new(Default::default(), []);
    let on = Variant {
        techniques: Techniques::default(),
        adaptive: Some(StoppingRule::Window),
    };
    let sweep = Sweep {
        width: 1,
        height: 1,
        reference: exact(),
        metric: ErrorMetric::Mse,
        curves: vec![
            curve(
                &registry,
                &Techniques::default().into(),
                uniform,
                ErrorMetric::Mse,
            ),
            curve(&registry, &on, adaptive, ErrorMetric::Mse),
        ],
    };
    let c = sweep.comparison();
    assert!((c.equal_time_seconds - 4.0).abs() < 1e-12);
    assert!(
        (c.rows[0].equal_time_error_ratio - 2.0).abs() < 1e-9,
        "{c:?}"
    );
    assert!(
        (c.rows[1].equal_time_error_ratio - 1.0).abs() < 1e-9,
        "{c:?}"
    );
    let r = c.rows[0].equal_error_time_ratio;
    assert!((r - 2f64.sqrt()).abs() < 1e-9, "{c:?}");
}

#[test]
fn the_image_memory_guard_counts_the_adaptive_points() {
    // 4096 x 4096 pixels of 12 bytes: 21.3 images fit in 4 GiB. Ten uniform spp counts and
    // eleven adaptive targets are 21 images; a twelfth target is one too many.
    let options = |targets: usize| ConvergeOptions {
        variants: vec![
            Techniques::default().into(),
            Variant {
                techniques: Techniques::default(),
                adaptive: Some(StoppingRule::Window),
            },
        ],
        plan: SppPlan::List((0..10).map(|i| 1 << i).collect()),
        adaptive: AdaptivePlan {
            noise_targets: (0..targets).map(|i| 0.5f64.powi(i as i32)).collect(),
            min_spp: 4,
        },
        repeats: 1,
        reference: Reference::Render {
            spp: None,
            techniques: None,
        },
        render: RenderOptions::default(),
        metric: ErrorMetric::Mse,
    };
    assert!(check_kept_images(&options(11), 4096, 4096).is_ok());
    let e = check_kept_images(&options(12), 4096, 4096).unwrap_err();
    assert!(e.to_string().contains("12 noise targets"), "{e}");
}
