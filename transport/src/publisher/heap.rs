//! Giving freed heap back to the operating system after a dead reader is cleaned up.
//!
//! Removing a SIGKILLed reader's resources (iceoryx2's stale-node cleanup, then dropping its
//! connections) allocates and frees a few hundred kilobytes in the writer's helper thread.
//! glibc keeps such freed memory in the thread's arena, so a writer that outlives hundreds of
//! killed readers grew its RSS by ~15 kB per kill while its heap in use stayed flat
//! (heaptrack: the same 44.9 MB peak with and without 150 kills; `bench/results/soak.md`).
//! Clean departures free less, but the same way.
//! `malloc_trim` returns those free pages; it runs only after a reader left or died (the
//! helper thread checks once a second).
#![cfg_attr(
    target_env = "gnu",
    expect(
        unsafe_code,
        reason = "malloc_trim is a foreign function; it has no safe binding"
    )
)]

/// Returns free heap pages of every malloc arena to the operating system (glibc only; a
/// no-op elsewhere, where the allocator decides on its own).
pub(crate) fn release_free_heap() {
    #[cfg(target_env = "gnu")]
    // SAFETY: malloc_trim(3) takes no pointers and only inspects the allocator's own state
    // under each arena's lock, so it is safe to call from any thread at any time; its result
    // (whether memory was released) is not needed.
    unsafe {
        libc::malloc_trim(0);
    }
}
