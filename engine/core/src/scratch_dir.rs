//! Scratch directories for unit tests of the engine's crates and of plug-in crates
//! (integration tests can use Cargo's `CARGO_TARGET_TMPDIR`, which unit tests do not get).

use std::path::{Path, PathBuf};

/// A fresh, empty directory in the system's temporary directory, unique to the test process
/// and `name`, removed with everything in it when dropped (also when the test fails), so
/// test runs leave nothing behind.
pub struct ScratchDir(PathBuf);

impl ScratchDir {
    /// A fresh directory named after `name` and this process.
    ///
    /// # Panics
    /// When the directory cannot be created (a test's environment is broken).
    pub fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("risotto-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Self(dir)
    }
}

impl std::ops::Deref for ScratchDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
