use super::*;
use serde_json::Value;

fn sample_worker(scale: u64) -> SystemStats {
    let mut s = SystemStats::new();
    s.record(System::Camera, 100 * scale as usize, 0.5);
    s.record(System::Intersect, 200 * scale as usize, 1.0);
    s.record(System::Intersect, 50, 0.25);
    s.add_rays(250 * scale as usize);
    s.add_samples(100 * scale as usize);
    s.terminate(Termination::Escaped, 60);
    s.terminate(Termination::MaxDepth, 40 * scale as usize);
    s.drop_nan(scale as usize);
    s
}

#[test]
fn names_follow_the_schema() {
    let names: Vec<_> = System::ALL.iter().map(|s| s.name()).collect();
    assert_eq!(
        names,
        [
            "camera",
            "intersect",
            "shade",
            "bxdf",
            "lights",
            "transmission",
            "occlusion",
            "partition",
            "volume",
            "phase",
            "splat",
            "emit",
            "connect",
            "merge"
        ]
    );
    for (i, s) in System::ALL.iter().enumerate() {
        assert_eq!(*s as usize, i);
    }
    for (i, t) in Termination::ALL.iter().enumerate() {
        assert_eq!(*t as usize, i);
        let n = t.name();
        assert!(n.chars().all(|c| c.is_ascii_lowercase() || c == '_'), "{n}");
    }
    assert_eq!(Termination::RussianRoulette.name(), "russian_roulette");
}

#[test]
fn time_records_calls_items_and_elapsed_time() {
    let mut s = SystemStats::new();
    let out = s.time(System::Bxdf, 7, || {
        std::thread::sleep(std::time::Duration::from_millis(20));
        42
    });
    assert_eq!(out, 42);
    s.time(System::Bxdf, 3, || ());
    let c = s.system(System::Bxdf);
    assert_eq!((c.calls, c.items), (2, 10));
    assert!(c.seconds >= 0.02 && c.seconds < 5.0, "{}", c.seconds);
    assert_eq!(s.system(System::Splat).calls, 0);
}

#[test]
fn merge_adds_everything() {
    let mut a = sample_worker(1);
    let b = sample_worker(2);
    a.merge(&b);
    let i = a.system(System::Intersect);
    assert_eq!((i.calls, i.items), (4, 200 + 50 + 400 + 50));
    assert!((i.seconds - 2.5).abs() < 1e-12);
    assert_eq!(a.system(System::Camera).items, 300);
    assert_eq!(a.rays, 750);
    assert_eq!(a.samples, 300);
    assert_eq!(a.terminated[Termination::Escaped as usize], 120);
    assert_eq!(a.terminated[Termination::MaxDepth as usize], 120);
    assert_eq!(a.terminated[Termination::Absorbed as usize], 0);
    assert_eq!(a.nan_dropped, 3);
    // Merging an empty accumulator changes nothing.
    let before = a.clone();
    a.merge(&SystemStats::new());
    assert_eq!(a, before);
}

#[test]
fn json_schema() {
    let mut stats = RenderStats::new(sample_worker(1), 2.0);
    stats.features = vec!["volumes".into(), "environment".into()];
    let v: Value = serde_json::from_str(&stats.to_json()).unwrap();
    let obj = v.as_object().unwrap();
    let keys: Vec<&str> = obj.keys().map(String::as_str).collect();
    let mut want = [
        "systems",
        "rays",
        "samples",
        "terminated",
        "nan_dropped",
        "wall_seconds",
        "features",
    ];
    want.sort_unstable();
    let mut got = keys.clone();
    got.sort_unstable();
    assert_eq!(got, want, "no warnings key without warnings");

    let systems = v["systems"].as_object().unwrap();
    // never-run systems are absent
    let mut sys_keys: Vec<&str> = systems.keys().map(String::as_str).collect();
    sys_keys.sort_unstable();
    assert_eq!(sys_keys, ["camera", "intersect"]);
    for (_, c) in systems {
        let c = c.as_object().unwrap();
        assert_eq!(c.len(), 3);
        assert!(c["calls"].is_u64() && c["items"].is_u64() && c["seconds"].is_f64());
    }
    assert_eq!(v["systems"]["intersect"]["calls"], 2);
    assert_eq!(v["systems"]["intersect"]["items"], 250);
    assert_eq!(v["systems"]["intersect"]["seconds"].as_f64(), Some(1.25));
    assert_eq!(v["rays"], 250);
    assert_eq!(v["samples"], 100);
    assert!(v["rays"].is_u64() && v["samples"].is_u64() && v["nan_dropped"].is_u64());
    assert_eq!(v["nan_dropped"], 1);
    assert_eq!(v["wall_seconds"].as_f64(), Some(2.0));
    let term = v["terminated"].as_object().unwrap();
    assert_eq!(term.len(), 2);
    assert_eq!(term["escaped"], 60);
    assert_eq!(term["max_depth"], 40);
    assert_eq!(v["features"], serde_json::json!(["volumes", "environment"]));

    stats.warnings.push("light has zero power".into());
    let v: Value = serde_json::from_str(&stats.to_json()).unwrap();
    assert_eq!(v["warnings"], serde_json::json!(["light has zero power"]));
}

#[test]
fn empty_stats_serialise_to_empty_maps() {
    let v: Value = serde_json::from_str(&RenderStats::default().to_json()).unwrap();
    assert_eq!(v["systems"], serde_json::json!({}));
    assert_eq!(v["terminated"], serde_json::json!({}));
    assert_eq!(v["features"], serde_json::json!([]));
    assert_eq!(v["rays"], 0);
}

#[test]
fn write_json_and_display() {
    let stats = RenderStats::new(sample_worker(1), 2.0);
    let path = std::env::temp_dir().join(format!("risotto-stats-{}.json", std::process::id()));
    stats.write_json(&path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let _ = std::fs::remove_file(&path);
    let v: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["rays"], 250);

    let shown = stats.to_string();
    assert!(shown.contains("intersect"), "{shown}");
    assert!(!shown.contains("splat"), "{shown}");
    // camera: 100 items in 0.5 s = 0.0002 Mitems/s; samples: 100 / 2 s
    assert!(shown.contains("0.00"), "{shown}");
    assert!(shown.contains("escaped 60 (60.0%)"), "{shown}");
    assert!(shown.contains("max_depth 40 (40.0%)"), "{shown}");
    assert!(shown.contains("nan dropped: 1"), "{shown}");
    assert!(!shown.contains("non-finite"), "{shown}");
}

#[test]
fn non_finite_counts_merge_serialise_and_show_by_stage() {
    let mut a = sample_worker(1);
    a.non_finite(Stage::Bxdf, 2);
    let mut b = SystemStats::new();
    b.non_finite(Stage::Volume, 5);
    b.non_finite(Stage::Bxdf, 1);
    a.merge(&b);
    assert_eq!(a.non_finite[Stage::Bxdf as usize], 3);
    let stats = RenderStats::new(a, 1.0);
    let v: Value = serde_json::from_str(&stats.to_json()).unwrap();
    assert_eq!(v["non_finite"], serde_json::json!({"bxdf": 3, "volume": 5}));
    let shown = stats.to_string();
    assert!(
        shown.contains("non-finite values by stage: bxdf 3 volume 5"),
        "{shown}"
    );
    let names: Vec<_> = Stage::ALL.iter().map(|s| s.name()).collect();
    assert_eq!(names.len(), Stage::COUNT);
    assert!(Stage::ALL.iter().enumerate().all(|(i, s)| *s as usize == i));
    let rgb = risotto_components::Rgb::new;
    let col = [
        rgb(1.0, 0.0, 0.0),
        rgb(f32::NAN, 0.0, 0.0),
        rgb(0.0, 0.0, f32::INFINITY),
    ];
    assert_eq!(count_non_finite(&col), 2);
}

fn event(pixel: u32, sample: u32, depth: u32, stage: Stage) -> NonFiniteEvent {
    NonFiniteEvent {
        pixel,
        sample,
        depth,
        stage,
        material: Some(1),
    }
}

#[test]
fn non_finite_cases_keep_the_smallest_keys_whatever_the_order_and_the_split() {
    // Twenty camera samples, some with two events (the shallower one must win).
    let mut events = Vec::new();
    for k in 0..20u32 {
        let (pixel, sample) = (k * 7 % 23, k % 3);
        events.push(event(pixel, sample, 3, Stage::Transmission));
        if k % 2 == 0 {
            events.push(event(pixel, sample, 1, Stage::Lighting));
            events.push(event(pixel, sample, 1, Stage::Bxdf));
        }
    }
    let mut want: Vec<NonFiniteEvent> = Vec::new();
    for e in &events {
        match want.iter_mut().find(|w| w.key() == e.key()) {
            Some(w) if e.rank() < w.rank() => *w = *e,
            Some(_) => {}
            None => want.push(*e),
        }
    }
    want.sort_by_key(NonFiniteEvent::key);
    want.truncate(MAX_NON_FINITE_CASES);
    assert_eq!(want.len(), MAX_NON_FINITE_CASES);
    assert!(want.iter().any(|e| e.stage == Stage::Bxdf && e.depth == 1));

    let mut forward = SystemStats::new();
    events.iter().for_each(|&e| forward.non_finite_event(e));
    let mut backward = SystemStats::new();
    events
        .iter()
        .rev()
        .for_each(|&e| backward.non_finite_event(e));
    assert_eq!(forward.non_finite_events, want);
    assert_eq!(backward.non_finite_events, want);
    // Split over three workers and merged in either order.
    let mut workers = [SystemStats::new(), SystemStats::new(), SystemStats::new()];
    for (i, &e) in events.iter().enumerate() {
        workers[i % 3].non_finite_event(e);
    }
    for order in [[0, 1, 2], [2, 0, 1]] {
        let mut merged = SystemStats::new();
        for w in order {
            merged.merge(&workers[w]);
        }
        assert_eq!(merged.non_finite_events, want);
    }
    // The cheap pre-test agrees with what is kept.
    let last = want.last().unwrap().key();
    assert!(forward.wants_non_finite_case(last));
    assert!(forward.wants_non_finite_case((0, 0)));
    assert!(!forward.wants_non_finite_case((last.0 + 1, 0)));
}

#[test]
fn non_finite_cases_serialise_and_show_with_their_replay_command() {
    let mut c = SystemStats::new();
    c.non_finite(Stage::Bxdf, 1);
    c.non_finite_event(event(2 * 16 + 9, 3, 1, Stage::Bxdf));
    let mut stats = RenderStats::new(c, 1.0);
    let names = ["floor".to_string(), "ball".to_string()];
    stats.non_finite_cases = stats
        .counters
        .non_finite_events
        .iter()
        .map(|e| NonFiniteCase::of(e, 16, 42, |m| names.get(m as usize).cloned()))
        .collect();
    let v: Value = serde_json::from_str(&stats.to_json()).unwrap();
    let want = serde_json::json!([{"x": 9, "y": 2, "sample": 3, "depth": 1,
        "stage": "bxdf", "material": "ball", "seed": 42,
        "replay": "risotto render SCENE --replay 9,2,3"}]);
    assert_eq!(v["non_finite_cases"], want);
    stats.render_command = Some("risotto render s.toml --seed 42".into());
    let shown = stats.to_string();
    assert!(
        shown.contains(
            "non-finite sample: pixel (9, 2) sample 3 depth 1 stage bxdf material \"ball\" \
             seed 42: risotto render s.toml --seed 42 --replay 9,2,3"
        ),
        "{shown}"
    );
    // No cases, no key.
    let v: Value = serde_json::from_str(&RenderStats::default().to_json()).unwrap();
    assert!(v.get("non_finite_cases").is_none());
}
