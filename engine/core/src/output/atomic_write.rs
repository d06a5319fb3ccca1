//! Outputs written as a whole or not at all: a temporary beside the file, flushed to disk,
//! renamed over it; temporaries removed on every exit a process can take.
//!
//! - A failed write removes its temporary.
//! - A process ending during a write on purpose (the driver's second interrupt) removes the
//!   temporaries in flight first: [`remove_temporaries_for_exit`].
//! - A process killed outright (SIGKILL, a power cut) cannot; the next write of the same
//!   file removes the temporaries of processes that no longer run (their names carry the
//!   process id; Linux, where `/proc` tells which processes run).

use super::OutputError;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

/// The temporaries writes are filling.
type InFlight = Mutex<Vec<PathBuf>>;

/// The temporaries [`write_atomically`] is filling.
static IN_FLIGHT: InFlight = Mutex::new(Vec::new());

fn lock(list: &InFlight) -> MutexGuard<'_, Vec<PathBuf>> {
    // A writer that panicked left a consistent list (pushes and removals are single steps).
    list.lock().unwrap_or_else(|p| p.into_inner())
}

/// Removes every temporary a write in flight is filling and returns the guard of their
/// list: while the caller holds it no write can start or finish, so a process that exits
/// holding it (`std::process::exit` from a signal-handling thread) leaves no temporary
/// behind and every output either as it was or complete.
pub fn remove_temporaries_for_exit() -> MutexGuard<'static, Vec<PathBuf>> {
    remove_in_flight(&IN_FLIGHT)
}

fn remove_in_flight(list: &InFlight) -> MutexGuard<'_, Vec<PathBuf>> {
    let mut list = lock(list);
    for tmp in list.drain(..) {
        let _ = std::fs::remove_file(tmp);
    }
    list
}

/// `bytes` as the file `path`, written as a whole or not at all ([`write_atomically`]).
pub fn write_file_atomically(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    write_atomically(path, |tmp| {
        std::fs::write(tmp, bytes).map_err(|cause| OutputError::Io {
            path: path.to_path_buf(),
            cause,
        })
    })
}

/// Writes `path` as a whole or not at all: `write` fills a temporary file beside it
/// (`.NAME.PID.tmp`, same directory, so the rename cannot cross file systems), which is
/// flushed to disk (`fsync`) and then renamed over `path`. A process stopped during the
/// write leaves `path` as it was (and at most the temporary, which the module's exits
/// remove); a failed write removes the temporary. Readers never see a half-written image
/// under the final name.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), OutputError>,
) -> Result<(), OutputError> {
    write_listed(&IN_FLIGHT, path, write)
}

/// [`write_atomically`] with its temporary listed in `in_flight` while it is filled.
fn write_listed(
    in_flight: &InFlight,
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), OutputError>,
) -> Result<(), OutputError> {
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    remove_stale_temporaries(path, &name);
    let tmp = path.with_file_name(temporary_name(&name, std::process::id()));
    lock(in_flight).push(tmp.clone());
    let io = |cause| OutputError::Io {
        path: path.to_path_buf(),
        cause,
    };
    let result = write(&tmp)
        .and_then(|()| File::open(&tmp).and_then(|f| f.sync_all()).map_err(io))
        .and_then(|()| std::fs::rename(&tmp, path).map_err(io));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    } else if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        // The rename itself is durable once the directory is (best effort: not every
        // platform can open a directory).
        if let Ok(d) = File::open(dir) {
            let _ = d.sync_all();
        }
    }
    lock(in_flight).retain(|t| *t != tmp);
    result
}

/// The temporary of output `name` written by process `pid`.
fn temporary_name(name: &str, pid: u32) -> String {
    format!(".{name}.{pid}.tmp")
}

/// The process id in `file`, if it is a temporary of output `name` (`.NAME.PID.tmp`).
fn temporary_pid(file: &str, name: &str) -> Option<u32> {
    let pid = file
        .strip_prefix('.')?
        .strip_prefix(name)?
        .strip_prefix('.')?
        .strip_suffix(".tmp")?;
    // Digits only: `u32::from_str` would also take a leading `+`.
    pid.bytes()
        .all(|b| b.is_ascii_digit())
        .then(|| pid.parse().ok())
        .flatten()
}

/// Removes the temporaries of output `path` (named `name`) left by processes that no longer
/// run: a process killed while writing it. Only where `/proc` lists the running processes
/// (Linux); elsewhere nothing is removed, since a temporary may be another process's write in
/// progress.
fn remove_stale_temporaries(path: &Path, name: &str) {
    let proc = Path::new("/proc");
    if !proc.join("self").exists() {
        return;
    }
    let dir = match path.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(d) => d,
        None => Path::new("."),
    };
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let own = std::process::id();
    for entry in entries.flatten() {
        let file = entry.file_name();
        let Some(pid) = file.to_str().and_then(|f| temporary_pid(f, name)) else {
            continue;
        };
        if pid != own && !proc.join(pid.to_string()).exists() {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(test: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("risotto-atomic-{test}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn temporary_names_round_trip_and_reject_others() {
        let t = temporary_name("out.exr", 4321);
        assert_eq!(t, ".out.exr.4321.tmp");
        assert_eq!(temporary_pid(&t, "out.exr"), Some(4321));
        assert_eq!(temporary_pid(".out.exr.+12.tmp", "out.exr"), None);
        assert_eq!(temporary_pid(".out.exr.12.tmp", "out.png"), None);
        assert_eq!(temporary_pid(".out.exr.x.tmp", "out.exr"), None);
        assert_eq!(temporary_pid("out.exr.12.tmp", "out.exr"), None);
    }

    #[cfg(unix)]
    #[test]
    fn a_write_removes_the_temporaries_of_dead_processes_only() {
        if !Path::new("/proc/self").exists() {
            return;
        }
        let d = dir("stale");
        let out = d.join("out.exr");
        // A process id no process has (above Linux's pid_max limit of 2^22).
        let dead = d.join(temporary_name("out.exr", 4_000_000_000));
        // A running process's temporary (this one's parent) and another output's.
        let alive = d.join(temporary_name(
            "out.exr",
            std::os::unix::process::parent_id(),
        ));
        let other = d.join(temporary_name("other.exr", 4_000_000_000));
        for f in [&dead, &alive, &other] {
            std::fs::write(f, b"partial").unwrap();
        }
        write_file_atomically(&out, b"whole").unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"whole");
        assert!(!dead.exists(), "a dead process's temporary stays");
        assert!(alive.exists(), "a running process's temporary was removed");
        assert!(other.exists(), "another output's temporary was removed");
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn an_exit_during_a_write_removes_its_temporary_and_blocks_new_writes() {
        // A list of its own: the process-wide one is shared with the other tests' writes.
        static LIST: InFlight = Mutex::new(Vec::new());
        let d = dir("exit");
        let out = d.join("out.exr");
        let (started, go) = (std::sync::mpsc::channel(), std::sync::mpsc::channel::<()>());
        let (started_tx, started_rx) = started;
        let (go_tx, go_rx) = go;
        let writer = std::thread::spawn(move || {
            write_listed(&LIST, &out, |tmp| {
                std::fs::write(tmp, b"half").unwrap();
                started_tx.send(tmp.to_path_buf()).unwrap();
                go_rx.recv().unwrap();
                Ok(())
            })
        });
        let tmp = started_rx.recv().unwrap();
        assert!(tmp.exists());
        let held = remove_in_flight(&LIST);
        assert!(!tmp.exists(), "the temporary in flight was not removed");
        assert!(held.is_empty());
        // The process would exit here; instead let the writer finish: its rename fails
        // (the temporary is gone) and the output was never half written.
        drop(held);
        go_tx.send(()).unwrap();
        assert!(writer.join().unwrap().is_err());
        assert!(!d.join("out.exr").exists());
        let _ = std::fs::remove_dir_all(&d);
    }
}
