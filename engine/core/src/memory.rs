//! Handing freed memory back to the system where the allocator keeps it.
//!
//! A renderer's peak resident memory is what a farm node must have; memory the allocator
//! holds free counts in it as much as memory in use. glibc keeps freed blocks below its
//! mmap threshold (which grows up to 32 MB as large blocks are freed) in its heap, resident,
//! until they are reused or trimmed. After a large transient is freed, and before the next
//! large allocations, [`release_freed_pages`] returns those pages, so the next peak is what
//! is live rather than what is live plus what was (issue 36).

/// Hands the pages of freed heap memory back to the system: glibc's `malloc_trim(0)`, which
/// since glibc 2.8 releases whole free pages anywhere in the heap, not only at its top. It
/// walks malloc's free lists, so it is for the ends of large phases (a mesh's build, a VDB
/// tree's parts), not for loops. Elsewhere than Linux with glibc it does nothing.
#[allow(unsafe_code, reason = "malloc_trim is a C function")]
pub fn release_freed_pages() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim takes no pointers and only releases memory malloc holds free.
    unsafe {
        libc::malloc_trim(0);
    }
}
