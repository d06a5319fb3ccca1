//! The files a scene names, decoded once per scene load and shared by every entity that
//! names them (issue 37: one 1 MB `.vol` named by 3,000 media was read 3,000 times, 3.1 GB).
//!
//! A [`SideFiles`] lives in the [`Source`](crate::diagnostics::Source) of one scene file
//! while it is read. Entries are keyed by the file's canonical path (so `a/../g.vol` and
//! `g.vol` are one file) and by a string of the load parameters that change the decoded
//! result (a VDB grid's name, a raw grid's header, a texture's channels); values are type
//! erased (`Arc<dyn Any>`) because the decoders live in the loader. Errors are not kept:
//! each entity that names a bad file reports it at its own key.

use std::any::Any;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

type Entry = Arc<dyn Any + Send + Sync>;

/// Decoded side files by (canonical path, load parameters); see the module docs.
#[derive(Default)]
pub struct SideFiles {
    entries: Mutex<HashMap<(PathBuf, String), Entry>>,
    decodes: Mutex<usize>,
}

impl std::fmt::Debug for SideFiles {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SideFiles")
            .field("decodes", &self.decodes())
            .finish_non_exhaustive()
    }
}

impl SideFiles {
    /// The value decoded from `path` with `params`, decoding it with `load` the first time
    /// (or when an earlier decode failed). A file that cannot be canonicalized (a missing
    /// one) is keyed by `path` as given, so `load` reports it.
    pub fn get_or_load<T: Any + Send + Sync, E>(
        &self,
        path: &Path,
        params: &str,
        load: impl FnOnce() -> Result<T, E>,
    ) -> Result<Arc<T>, E> {
        let key = (
            std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf()),
            params.to_string(),
        );
        let found = self.lock().get(&key).cloned();
        if let Some(entry) = found.and_then(|e| e.downcast::<T>().ok()) {
            return Ok(entry);
        }
        // Decoded outside the lock: loads of one scene run on one thread, and a decoder
        // that panics must not poison the map.
        let value = Arc::new(load()?);
        *self.decodes.lock().unwrap_or_else(|p| p.into_inner()) += 1;
        self.lock().insert(key, value.clone() as Entry);
        Ok(value)
    }

    /// How many files (with parameters) were decoded so far: a count of real reads, for
    /// tests and statistics.
    pub fn decodes(&self) -> usize {
        *self.decodes.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<(PathBuf, String), Entry>> {
        self.entries.lock().unwrap_or_else(|p| p.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_is_decoded_once_per_parameters_and_shared() {
        let dir = crate::scratch_dir::ScratchDir::new("side-files");
        let p = dir.join("g.vol");
        std::fs::write(&p, b"x").unwrap();
        let cache = SideFiles::default();
        let load = || Ok::<_, String>(vec![1.0f32; 4]);
        let a = cache.get_or_load(&p, "", load).unwrap();
        // The same file by another spelling, same parameters: the same value.
        let b = cache
            .get_or_load(&dir.join(".").join("g.vol"), "", load)
            .unwrap();
        assert!(Arc::ptr_eq(&a, &b));
        assert_eq!(cache.decodes(), 1);
        // Other parameters decode again.
        let c = cache.get_or_load(&p, "name=t", load).unwrap();
        assert!(!Arc::ptr_eq(&a, &c));
        assert_eq!(cache.decodes(), 2);
        // Errors are not kept.
        let e = cache.get_or_load::<Vec<f32>, _>(&dir.join("missing"), "", || Err("no"));
        assert_eq!(e.unwrap_err(), "no");
        let ok = cache.get_or_load(&dir.join("missing"), "", load).unwrap();
        assert_eq!(*ok, vec![1.0; 4]);
        assert_eq!(cache.decodes(), 3);
    }
}
