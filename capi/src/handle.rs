//! The registry of live handles: every handle the library gives out is a boxed value
//! whose address is registered with its kind until it is destroyed, so a null, dangling
//! (already destroyed) or wrongly typed handle is refused with an error instead of being
//! dereferenced.
//!
//! # Invariants
//! * An address is in the registry with kind `T::KIND` exactly while it is the address
//!   of a live `Box<T>` made by [`register`] and not yet taken back by [`unregister`].
//! * Resolving checks the registry (or, while no handle has been unregistered since,
//!   the calling thread's last successful check of the same handle), then borrows the
//!   box. The C API documents that a handle must not be used from two threads at once,
//!   nor destroyed while another thread uses it (the check and the use are not one
//!   atomic step).
//!
//! A dangling handle whose address was reused for a new handle of the same kind cannot
//! be told apart from that new handle; that misuse is not detectable.

use crate::errors::{FfiError, FfiResult, YggStatus};
use rustc_hash::FxHashMap;
use std::cell::Cell;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard};

/// The kinds of handle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    Graph,
    Writer,
    Reader,
    Snapshot,
    Recording,
    Recorder,
}

/// A type handed to C as an opaque handle.
pub(crate) trait Handle: Sized {
    /// Its registry kind.
    const KIND: Kind;
    /// Its name in messages (`"graph"`, ...).
    const NAME: &'static str;
}

static LIVE: Mutex<Option<FxHashMap<usize, Kind>>> = Mutex::new(None);

/// Counts unregistrations: a thread's cached check (below) holds only while it is
/// unchanged. Incremented (Release) after the registry entry is removed and before the
/// box is freed; read with Acquire.
static UNREGISTERED: AtomicU64 = AtomicU64::new(0);

thread_local! {
    /// The last handle this thread found live: its address, kind and the value of
    /// [`UNREGISTERED`] then. While no handle has been unregistered since, it is still
    /// live, and a mutation loop on one handle checks it without taking the lock.
    static LAST_LIVE: Cell<(usize, Option<Kind>, u64)> = const { Cell::new((0, None, 0)) };
}

fn live() -> MutexGuard<'static, Option<FxHashMap<usize, Kind>>> {
    // The map is never left half-updated (single insert/remove calls): a panic elsewhere
    // while the lock was held cannot have broken it.
    LIVE.lock().unwrap_or_else(|p| p.into_inner())
}

/// Boxes `value`, registers its address and returns it as the handle.
pub(crate) fn register<T: Handle>(value: T) -> *mut T {
    let ptr = Box::into_raw(Box::new(value));
    live()
        .get_or_insert_with(FxHashMap::default)
        .insert(ptr as usize, T::KIND);
    ptr
}

/// Checks that `ptr` is a live handle of kind `T`.
fn check<T: Handle>(ptr: *const T, argument: &str) -> FfiResult {
    if ptr.is_null() {
        return Err(FfiError::null(argument));
    }
    let address = ptr as usize;
    let epoch = UNREGISTERED.load(Ordering::Acquire);
    if LAST_LIVE.get() == (address, Some(T::KIND), epoch) {
        return Ok(());
    }
    let kind = live().as_ref().and_then(|m| m.get(&address).copied());
    match kind {
        Some(k) if k == T::KIND => {
            LAST_LIVE.set((address, Some(k), epoch));
            Ok(())
        }
        Some(k) => Err(FfiError::new(
            YggStatus::InvalidHandle,
            format!("`{argument}` is a {k:?} handle, not a {} handle", T::NAME),
        )),
        None => Err(FfiError::new(
            YggStatus::InvalidHandle,
            format!(
                "`{argument}` is not a live {} handle (destroyed, or never created by this library)",
                T::NAME
            ),
        )),
    }
}

/// The value behind a live handle, shared.
pub(crate) fn resolve<'a, T: Handle>(ptr: *const T, argument: &str) -> FfiResult<&'a T> {
    check(ptr, argument)?;
    // SAFETY: `check` found `ptr` registered with `T::KIND`, so it is the address of a
    // live `Box<T>` (module invariant). The C API forbids destroying a handle while
    // another call uses it, so the box outlives this call's borrow.
    Ok(unsafe { &*ptr })
}

/// The value behind a live handle, exclusively.
pub(crate) fn resolve_mut<'a, T: Handle>(ptr: *mut T, argument: &str) -> FfiResult<&'a mut T> {
    check(ptr, argument)?;
    // SAFETY: as in `resolve`; in addition the C API forbids using a mutable handle
    // (graph, writer, reader) from two threads at once, so no other reference to the
    // box exists during this call.
    Ok(unsafe { &mut *ptr })
}

/// Unregisters a live handle and takes its box back (the caller drops it).
pub(crate) fn unregister<T: Handle>(ptr: *mut T, argument: &str) -> FfiResult<Box<T>> {
    check(ptr, argument)?;
    if let Some(m) = live().as_mut() {
        m.remove(&(ptr as usize));
    }
    // Every thread's cached check is void from now on (before the box is freed).
    UNREGISTERED.fetch_add(1, Ordering::Release);
    // SAFETY: `check` found `ptr` registered as a live `Box<T>` made by `register`, and
    // removing it from the registry makes this the only owner: no later call can
    // resolve it.
    Ok(unsafe { Box::from_raw(ptr) })
}
