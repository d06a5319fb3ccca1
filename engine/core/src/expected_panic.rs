//! Catching the panics of code known to panic on bad input (a third-party decoder given a
//! corrupt file) without printing them: the error is reported by the caller, naming the
//! file, and a panic message with a backtrace note would read as a crash.
//!
//! The panic hook is process-wide, so swapping it around the caught call would race other
//! threads (their real panics would go unprinted, or ours printed). Instead one hook is
//! installed once ([`std::sync::Once`]) that stays silent while the panicking thread is
//! inside [`catch`] (a thread-local depth) and otherwise hands the panic to the hook that
//! was there before, so every other panic prints exactly as it would have.

use std::cell::Cell;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Once;

thread_local! {
    /// How many [`catch`] calls this thread is inside.
    static EXPECTING: Cell<u32> = const { Cell::new(0) };
}

static INSTALL: Once = Once::new();

/// Installs the silencing hook over the current one (once per process; later calls do
/// nothing). [`catch`] calls it; a program that sets its own hook should call this after.
pub fn install() {
    INSTALL.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if EXPECTING.with(Cell::get) == 0 {
                previous(info);
            }
        }));
    });
}

/// Runs `f`, returning its result, or the panic's message if it panicked, without printing
/// that panic. `f` is treated as unwind safe: the caller discards what a panic leaves half
/// built.
pub fn catch<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    install();
    EXPECTING.with(|d| d.set(d.get() + 1));
    let result = catch_unwind(AssertUnwindSafe(f));
    EXPECTING.with(|d| d.set(d.get() - 1));
    result.map_err(|panic| {
        panic
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_else(|| "a panic without a message".to_string())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_caught_panic_is_returned_and_the_silent_scope_ends_with_the_call() {
        assert_eq!(catch(|| 7), Ok(7));
        let e = catch(|| -> u32 { panic!("bad header {}", 3) }).unwrap_err();
        assert_eq!(e, "bad header 3");
        // Nested: the outer scope is still silent after the inner one ends.
        let e = catch(|| {
            let _ = catch(|| panic!("inner"));
            panic!("outer")
        })
        .unwrap_err();
        assert_eq!(e, "outer");
        // Outside a scope the depth is back to 0 (panics print through the old hook).
        assert_eq!(EXPECTING.with(Cell::get), 0);
    }
}
