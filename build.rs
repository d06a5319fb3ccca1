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
    denoise_rpath();
}

/// With the `denoise` feature and `OIDN_DIR` (the Open Image Denoise install the `oidn` crate
/// links, README "Denoising"), the binaries, tests and examples find the library at run time
/// through an rpath to `OIDN_DIR/lib`, so no `LD_LIBRARY_PATH` is needed.
fn denoise_rpath() {
    println!("cargo:rerun-if-env-changed=OIDN_DIR");
    if std::env::var_os("CARGO_FEATURE_DENOISE").is_none() {
        return;
    }
    let Some(dir) = std::env::var_os("OIDN_DIR") else {
        return;
    };
    let lib = std::path::Path::new(&dir).join("lib");
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("windows") {
        return;
    }
    println!("cargo:rustc-link-arg=-Wl,-rpath,{}", lib.display());
}
