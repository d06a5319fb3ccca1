//! Records the source commit for `risotto render --stats` (`"run": {"commit": ...}`): the
//! output of `git rev-parse HEAD` when the build runs in a git checkout, nothing otherwise.

use std::process::Command;

fn main() {
    // Rebuild when HEAD moves (a commit, a checkout); a missing file is ignored by cargo.
    println!("cargo:rerun-if-changed=.git/HEAD");
    println!("cargo:rerun-if-changed=.git/refs/heads");
    println!("cargo:rerun-if-changed=.git/packed-refs");
    let commit = Command::new("git")
        .args(["rev-parse", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_owned())
        .filter(|s| s.len() == 40 && s.chars().all(|c| c.is_ascii_hexdigit()));
    if let Some(commit) = commit {
        println!("cargo:rustc-env=RISOTTO_COMMIT={commit}");
    }
}
