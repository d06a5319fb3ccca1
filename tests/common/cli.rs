//! Helpers of the tests that run the `risotto` binary.

use std::process::{Command, Output};

/// Runs `risotto ARGS` to completion.
pub fn risotto(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_risotto"))
        .args(args)
        .output()
        .unwrap()
}

/// Asserts `out` succeeded (showing its stderr if not) and returns it.
pub fn ok(what: &str, out: Output) -> Output {
    assert!(
        out.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Asserts a clean failure: non-zero exit, no panic, and every `needle` in stderr.
pub fn assert_fails(what: &str, out: &Output, needles: &[&str]) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{what}: exit 0; stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "{what}: panicked: {stderr}");
    for n in needles {
        assert!(stderr.contains(n), "{what}: stderr lacks {n:?}: {stderr}");
    }
}

/// A small valid scene: floor, downward-facing square lamp, sky.
pub const SCENE: &str = r#"[render]
width = 16
height = 12
spp = 4
max_depth = 4

[camera]
fov = 40
from = [0, 1, 4]
to = [0, 0.5, 0]

[materials.floor]
type = "diffuse"
reflectance = 0.5

[materials.emitter]
type = "diffuse"
reflectance = 0

[[shapes]]
name = "floor"
type = "quad"
material = "floor"
corner = [-5, 0, -5]
edge1 = [0, 0, 10]
edge2 = [10, 0, 0]

[[shapes]]
name = "lamp"
type = "quad"
material = "emitter"
emission = 5
corner = [-0.5, 2, -0.5]
edge1 = [1, 0, 0]
edge2 = [0, 0, 1]

[[lights]]
name = "sky"
type = "environment"
radiance = 0.1
"#;

/// Asserts a clean failure whose stderr holds `needle` exactly once: a message printed with
/// its cause chain (`{:#}`) must not repeat a cause that is already part of it.
pub fn assert_fails_once(what: &str, out: &Output, needle: &str) {
    assert_fails(what, out, &[needle]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let n = stderr.matches(needle).count();
    assert_eq!(n, 1, "{what}: {needle:?} printed {n} times: {stderr}");
}

/// The 1-based line of the first occurrence of `needle` in `text`.
pub fn line_of(text: &str, needle: &str) -> usize {
    let at = text
        .find(needle)
        .unwrap_or_else(|| panic!("test bug: {needle:?} not in the text"));
    text[..at].matches('\n').count() + 1
}
