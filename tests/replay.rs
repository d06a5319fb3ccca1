//! Replaying one camera sample (issue 14): `engine::replay::replay` re-runs exactly the path
//! the render splatted, single-threaded, and records its vertices; `risotto render
//! --replay X,Y,SAMPLE` prints them and rejects pixels and samples outside the render.

mod common;
use common::cli::{assert_fails, risotto};
use common::scratch_dir;
use risotto::engine::integrator::LightingTechnique;
use risotto::engine::path_tracer::VertexEvent;
use risotto::engine::render::{render, RenderOptions, SampleRange, Window};
use risotto::engine::replay::replay;
use risotto::engine::scene::CompiledScene;
use risotto::loader::load::{compile_scene, load_scene_file, MaterialRegistry};
use risotto::systems::independent_sampler::SamplerKind;
use std::path::Path;

fn load(path: &str) -> CompiledScene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    let scene = load_scene_file(&path, &MaterialRegistry::with_builtins()).unwrap();
    compile_scene(scene).unwrap()
}

/// The replayed path is the render's: its radiance has the bits of a one-sample render of
/// the pixel (`--crop` of the pixel, `--samples S..S+1`), in scenes with surfaces only,
/// glass, a scattering medium and a random-walk subsurface material, and with other
/// techniques than the defaults.
#[test]
fn a_replayed_sample_is_the_rendered_sample_bit_for_bit() {
    let independent_nee = RenderOptions {
        sampler: SamplerKind::Independent,
        technique: LightingTechnique::NeeOnly,
        ..RenderOptions::default()
    };
    let scenes = [
        ("scenes/cornell-box.toml", RenderOptions::default()),
        ("scenes/cornell-box.toml", independent_nee),
        ("scenes/glass-sphere.toml", RenderOptions::default()),
        ("scenes/smoke.toml", RenderOptions::default()),
        ("scenes/smoke.toml", independent_nee),
        ("scenes/marble.toml", RenderOptions::default()),
        ("scenes/fire.toml", RenderOptions::default()),
    ];
    for (path, techniques) in scenes {
        let scene = load(path);
        let (w, h) = (scene.camera.width, scene.camera.height);
        let mut vertices = 0;
        for (k, (x, y)) in [(w / 2, h / 2), (w / 3, 2 * h / 3), (3 * w / 5, h / 4)]
            .into_iter()
            .enumerate()
        {
            let sample = (7 * k as u32 + 3) % scene.settings.spp;
            let options = RenderOptions {
                crop: Some(Window {
                    x0: x,
                    y0: y,
                    x1: x + 1,
                    y1: y + 1,
                }),
                samples: Some(SampleRange {
                    start: sample,
                    end: sample + 1,
                }),
                ..techniques
            };
            let rendered = render(&scene, &options, &|_| {}).unwrap().beauty.pixels[0];
            let r = replay(&scene, &techniques, x, y, sample).unwrap();
            let got = r.radiance();
            assert_eq!(
                [got.r, got.g, got.b].map(f32::to_bits),
                [rendered.r, rendered.g, rendered.b].map(f32::to_bits),
                "{path} pixel ({x}, {y}) sample {sample}: replay {got:?}, render {rendered:?}\n{r}"
            );
            let v = &r.trace.vertices;
            assert!(!v.is_empty(), "{path}: {r}");
            assert_eq!(v[0].depth, 0, "{path}: {r}");
            assert!(v.windows(2).all(|w| w[0].depth < w[1].depth), "{path}: {r}");
            // Every vertex but the last went on; the last says why it ended.
            assert!(
                v[..v.len() - 1].iter().all(|v| v.throughput_out.is_some()),
                "{r}"
            );
            assert!(r.trace.ended.is_some(), "{path}: {r}");
            assert_eq!(v.last().unwrap().radiance, got, "{path}: {r}");
            assert_eq!(r.stats.counters.samples, 1);
            vertices += v.len();
        }
        assert!(vertices > 3, "{path}: paths of {vertices} vertices in all");
    }
}

/// What the recorder sees in a scene with a scattering medium: volume-scatter vertices with
/// phase-function samples, and the depth grows by one per vertex.
#[test]
fn replay_records_volume_scatter_vertices_and_their_samples() {
    let scene = load("scenes/smoke.toml");
    let (w, h) = (scene.camera.width, scene.camera.height);
    let mut scatter = 0;
    for sample in 0..8 {
        let r = replay(&scene, &RenderOptions::default(), w / 2, h / 2, sample).unwrap();
        for v in &r.trace.vertices {
            if let VertexEvent::VolumeScatter { material, .. } = &v.event {
                scatter += 1;
                assert!(!material.is_empty());
                let s = v.bxdf_sample.expect("a phase sample at a volume vertex");
                assert!(s.pdf > 0.0 && s.weight.is_finite(), "{r}");
                assert!(r.to_string().contains("volume scatter in"), "{r}");
            }
        }
    }
    assert!(
        scatter > 0,
        "no volume scatter vertex in 8 paths through the smoke"
    );
}

/// What the recorder sees of the shadow rays: in a scene of opaque surfaces each arrives
/// whole or blocked (black), in the smoke some arrive attenuated by the medium. Counted over
/// the nonzero contributions of the paths of a few pixels and samples, every kind the scene
/// can have turns up.
#[test]
fn replay_records_what_shadow_rays_transmit() {
    use risotto::components::Rgb;
    for (path, medium) in [
        ("scenes/cornell-box.toml", false),
        ("scenes/smoke.toml", true),
    ] {
        let scene = load(path);
        let (w, h) = (scene.camera.width, scene.camera.height);
        let (mut whole, mut blocked, mut attenuated) = (0, 0, 0);
        for (x, y) in [(w / 2, h / 2), (w / 4, 3 * h / 4), (3 * w / 4, h / 3)] {
            for sample in 0..8 {
                let r = replay(&scene, &RenderOptions::default(), x, y, sample).unwrap();
                let records = r.trace.vertices.iter().flat_map(|v| &v.shadow_rays);
                for s in records.filter(|s| s.unoccluded != Rgb::BLACK) {
                    let (u, t) = (s.unoccluded, s.transmitted);
                    if t == u {
                        whole += 1;
                    } else if t == Rgb::BLACK {
                        blocked += 1;
                    } else {
                        attenuated += 1;
                        assert!(t.r <= u.r && t.g <= u.g && t.b <= u.b, "{path}: {r}");
                    }
                }
            }
        }
        assert!(whole > 0, "{path}: no shadow ray arrived whole");
        if medium {
            assert!(
                attenuated > 0,
                "{path}: no shadow ray attenuated by the smoke"
            );
        } else {
            assert!(blocked > 0, "{path}: no shadow ray blocked");
            assert_eq!(attenuated, 0, "{path}: opaque surfaces only attenuate");
        }
    }
}

#[test]
fn replay_rejects_pixels_and_samples_outside_the_render() {
    let scene = load("scenes/cornell-box.toml");
    let (w, h, spp) = (scene.camera.width, scene.camera.height, scene.settings.spp);
    let o = RenderOptions::default();
    let e = replay(&scene, &o, w, 0, 0).unwrap_err().to_string();
    assert!(
        e.contains(&format!("x = {w} is outside the {w}x{h} image")),
        "{e}"
    );
    let e = replay(&scene, &o, 0, h, 0).unwrap_err().to_string();
    assert!(e.contains(&format!("y = {h} is outside")), "{e}");
    let e = replay(&scene, &o, 0, 0, spp).unwrap_err().to_string();
    assert!(
        e.contains(&format!("sample {spp} is not below the scene's {spp}")),
        "{e}"
    );
    assert!(replay(&scene, &o, w - 1, h - 1, spp - 1).is_ok());
}

#[test]
fn cli_replay_prints_the_vertices_and_writes_nothing() {
    let dir = scratch_dir("replay", "cli");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, common::cli::SCENE).unwrap();
    let scene = scene.to_str().unwrap();
    let out = risotto(&["render", scene, "--replay", "8,9,2"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stdout.starts_with("replay of pixel (8, 9) sample 2, seed 0"),
        "{stdout}"
    );
    // The lower rows see the floor: a surface vertex with its samples, then more.
    assert!(
        stdout.contains("depth 0: surface of material \"floor\""),
        "{stdout}"
    );
    assert!(stdout.contains("bxdf sample: direction"), "{stdout}");
    assert!(stdout.contains("light sample:"), "{stdout}");
    assert!(
        stdout.contains("throughput in (1.0000, 1.0000, 1.0000)"),
        "{stdout}"
    );
    assert!(stdout.contains("depth 1: "), "{stdout}");
    assert!(stdout.contains("(splatted into the pixel)"), "{stdout}");
    assert!(!stdout.contains("became non-finite"), "{stdout}");
    // Nothing written: no EXR or PNG beside the scene or in the current directory.
    let written: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert_eq!(written.len(), 1, "{written:?}");
    assert!(!Path::new("scene.exr").exists());
}

#[test]
fn cli_replay_rejects_pixels_samples_and_malformed_values() {
    let dir = scratch_dir("replay", "cli-errors");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, common::cli::SCENE).unwrap();
    let scene = scene.to_str().unwrap();
    let cases: [(&[&str], &[&str]); 7] = [
        (
            &["--replay", "16,0,0"],
            &["--replay 16,0,0", "x = 16 is outside the 16x12 image"],
        ),
        (
            &["--replay", "0,12,0"],
            &["--replay 0,12,0", "y = 12 is outside the 16x12 image"],
        ),
        (
            &["--replay", "0,0,4"],
            &["--replay 0,0,4", "sample 4 is not below the scene's 4"],
        ),
        (&["--replay", "0,0,4", "--spp", "8"], &[]),
        (&["--replay", "1,2"], &["--replay 1,2", "X,Y,SAMPLE"]),
        (
            &["--replay", "1,-2,0"],
            &["--replay 1,-2,0", "\"-2\" is not a whole number"],
        ),
        (
            &["--replay", "1,2,0", "--crop", "0,0,4,4"],
            &["--replay", "--crop"],
        ),
    ];
    for (extra, needles) in cases {
        let mut args = vec!["render", scene];
        args.extend_from_slice(extra);
        let out = risotto(&args);
        if needles.is_empty() {
            // --spp raises the scene's samples per pixel: sample 4 exists then.
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert!(out.status.success(), "{extra:?}: {stderr}");
        } else {
            assert_fails(&format!("{extra:?}"), &out, needles);
        }
    }
}

/// In a random-walk subsurface material the recorder reports the walk each entering ray
/// made inside the volume (`walk_events`, looked up among the rays of the volume's bundle):
/// some segments of centre-pixel paths in marble.toml carry a walk of at least one event.
#[test]
fn replay_records_random_walks_inside_subsurface_volumes() {
    let scene = load("scenes/marble.toml");
    let (w, h) = (scene.camera.width, scene.camera.height);
    let mut walks = 0;
    for sample in 0..8 {
        let r = replay(&scene, &RenderOptions::default(), w / 2, h / 2, sample).unwrap();
        for v in &r.trace.vertices {
            for s in &v.segments {
                if s.walk_events > 0 {
                    walks += 1;
                    assert!(r.to_string().contains("after a random walk of"), "{r}");
                }
            }
        }
    }
    assert!(
        walks > 0,
        "no segment of 8 centre-pixel paths reports a random walk"
    );
}
