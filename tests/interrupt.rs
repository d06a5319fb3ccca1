//! SIGINT / SIGTERM during `risotto render` (issue 35): the first ends the render after the
//! pass in flight and writes the samples done as a partial render that `merge` finishes to
//! the uninterrupted image; a second exits at once. Each test sends real signals to a real
//! process.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};

mod common;
use common::cli::{ok, risotto, SCENE};
use risotto::engine::output::read_exr_rgb;
use risotto::tools::merge::read_partial;

fn setup(test: &str, spp: u32) -> (PathBuf, PathBuf) {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("interrupt-{test}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, SCENE.replace("spp = 4", &format!("spp = {spp}"))).unwrap();
    (dir, scene)
}

/// Starts `risotto render SCENE -o OUT --progress json -t 1 EXTRA...`.
fn start(scene: &Path, out: &Path, extra: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_risotto"))
        .args([
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
        .args(["--progress", "json", "-t", "1"])
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Waits until the render is under way (`started`: its first progress line, which comes
/// after a second; or, with `Some(file)`, until that file exists: the first checkpoint),
/// sends `signals` (`INT`, `TERM`) one after the other, and waits for the process. The
/// renders are sized to last far longer than that on any machine.
fn interrupt(mut child: Child, started: Option<&Path>, signals: &[&str]) -> Output {
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    match started {
        None => {
            let first = lines.next().expect("a progress line").unwrap();
            assert!(first.contains("\"event\":\"progress\""), "{first}");
        }
        Some(file) => {
            while !file.exists() {
                std::thread::sleep(std::time::Duration::from_millis(2));
            }
        }
    }
    for (i, s) in signals.iter().enumerate() {
        // Standard signals do not queue: two sent before the first is handled are one.
        if i > 0 {
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        let status = Command::new("kill")
            .args([&format!("-{s}"), &child.id().to_string()])
            .status()
            .unwrap();
        assert!(status.success());
    }
    for line in lines {
        line.unwrap();
    }
    child.wait_with_output().unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn sigint_writes_the_samples_done_and_merge_finishes_them() {
    // Short passes (the checkpoint interval), and the signal at the first checkpoint, so
    // the interrupt lands well before the end (6.3 M samples).
    let spp = 8192;
    let (dir, scene) = setup("int", spp);
    let out = dir.join("shot.exr");
    let child = start(&scene, &out, &["--checkpoint", "0.05", "--size", "32x24"]);
    let result = interrupt(child, Some(&out), &["INT"]);
    assert_eq!(result.status.code(), Some(130), "{}", stderr(&result));
    let msg = stderr(&result);
    assert!(
        msg.contains("interrupted:") && msg.contains("risotto merge"),
        "{msg}"
    );
    let part = read_partial(&out).unwrap();
    let (start, done) = (part.header.samples.start, part.header.samples.end);
    assert!(
        start == 0 && done > 0 && done < spp,
        "samples {start}..{done}"
    );
    assert!(part.film.count.iter().all(|&c| c == done));
    // The message's recipe: render the rest, merge, and get the uninterrupted image.
    let rest = dir.join("rest.exr");
    let range = format!("{done}..{spp}");
    let args = [
        "render",
        scene.to_str().unwrap(),
        "--size",
        "32x24",
        "--samples",
        &range,
        "-o",
    ];
    ok(
        "rest",
        risotto(&[&args[..], &[rest.to_str().unwrap(), "--quiet"]].concat()),
    );
    let merged = dir.join("merged.exr");
    ok(
        "merge",
        risotto(&[
            "merge",
            out.to_str().unwrap(),
            rest.to_str().unwrap(),
            "--out",
            merged.to_str().unwrap(),
        ]),
    );
    let whole = dir.join("whole.exr");
    let args = [
        "render",
        scene.to_str().unwrap(),
        "--size",
        "32x24",
        "-o",
        whole.to_str().unwrap(),
    ];
    ok("whole", risotto(&[&args[..], &["--quiet"]].concat()));
    let (m, w) = (
        read_exr_rgb(&merged).unwrap(),
        read_exr_rgb(&whole).unwrap(),
    );
    assert_eq!((m.width, m.height), (w.width, w.height));
    // Sample passes merge to the one-process sums up to f64 summation order (README).
    for (a, b) in m.pixels.iter().zip(&w.pixels) {
        for (x, y) in a.to_array().into_iter().zip(b.to_array()) {
            assert!((x - y).abs() <= 1e-6 * y.abs().max(1e-3), "{x} vs {y}");
        }
    }
}

#[test]
fn sigterm_without_checkpoints_ends_after_the_pass_in_flight() {
    // 200 M samples (a minute on one thread), passes of about two seconds.
    let spp = 65536;
    let (dir, scene) = setup("term", spp);
    let out = dir.join("shot.exr");
    let result = interrupt(start(&scene, &out, &["--size", "64x48"]), None, &["TERM"]);
    assert_eq!(result.status.code(), Some(130), "{}", stderr(&result));
    let part = read_partial(&out).unwrap();
    assert!(
        part.header.samples.end > 0 && part.header.samples.end < spp,
        "{:?}",
        part.header.samples
    );
    assert!(
        dir.join("shot.png").exists(),
        "the preview of the samples done"
    );
}

#[test]
fn a_second_signal_exits_at_once() {
    let spp = 65536;
    let (dir, scene) = setup("twice", spp);
    let out = dir.join("shot.exr");
    // Passes of a minute (the checkpoint interval): the first signal alone would wait for
    // the pass in flight, so only the second can end the process within the test.
    let args = ["--size", "64x48", "--checkpoint", "60"];
    let result = interrupt(start(&scene, &out, &args), None, &["INT", "INT"]);
    assert_eq!(result.status.code(), Some(130), "{}", stderr(&result));
    assert!(
        !stderr(&result).contains("holds samples"),
        "{}",
        stderr(&result)
    );
    // Only the first pass's checkpoint (one sample per pixel) was written.
    let part = read_partial(&out).unwrap();
    assert_eq!(part.header.samples.end, 1, "{:?}", part.header.samples);
    // And no temporary is left (the exit removes those of writes in flight).
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|f| f.ends_with(".tmp"))
        .collect();
    assert!(left.is_empty(), "temporaries left: {left:?}");
}
