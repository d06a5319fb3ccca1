//! Helpers of the tests that run the `risotto` binary.

use std::process::{Command, Output};

/// Runs `risotto ARGS` to completion.
pub fn risotto(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_risotto"))
        .args(args)
        .output()
        .unwrap()
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
