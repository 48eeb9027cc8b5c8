//! The reader handle (`ygg_reader`): attach to a published scene and receive validated
//! snapshots.
//!
//! Thread-safety of `ygg_reader`: not thread-safe. Use a reader from one thread at a
//! time (it may move between threads). The snapshots it gives are independent handles
//! (see `ygg_snapshot`).

use crate::args::{Out, str_arg};
use crate::errors::{FfiError, FfiResult, YggStatus, guard};
use crate::handle::{self, Handle, Kind};
use crate::snapshot::YggSnapshot;
use std::ffi::c_char;
use std::time::Duration;
use ygg_reader::{SceneReader, SceneReceiveError, SceneSnapshot, WriterStatus};

/// A reader of one scene.
///
/// Thread-safety: not thread-safe. Use a reader from one thread at a time (it may move
/// between threads); the snapshots it gives are independent handles.
pub struct YggReader {
    reader: SceneReader,
}

impl Handle for YggReader {
    const KIND: Kind = Kind::Reader;
    const NAME: &'static str = "reader";
}

/// Options of `ygg_reader_open`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct YggReaderOptions {
    /// How long to wait for a writer to create the scene, milliseconds (0: fail at once
    /// when no writer serves it).
    pub wait_for_writer_ms: u64,
    /// Copy each newly received layer into private memory and validate and query the
    /// copy (for a writer you do not trust); costs a copy of every changed layer.
    pub copy_segments: bool,
    /// Let SIGINT/SIGTERM end a wait (`ygg_reader_wait_next` then fails with
    /// `YGG_STATUS_RECEIVE` and `ygg_reader_termination_requested` turns true). Off by
    /// default: a library should not take over an application's signals.
    pub handle_termination_signals: bool,
}

/// Whether the writer of a scene is alive (`ygg_reader_writer_status`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum YggWriterState {
    /// Not checked yet.
    Unknown = 0,
    /// A live writer publishes the scene.
    Alive = 1,
    /// The writer exited or died; the last snapshot stays available.
    Gone = 2,
}

/// Attaches to `scene`, waiting for its writer as `options` says (`options` may be
/// null: no wait, zero-copy, no signal handling).
///
/// Ownership: `*out` receives a new reader handle the caller destroys with
/// `ygg_reader_destroy`.
///
/// # Safety
/// `scene` is null or NUL-terminated; `options` is null or readable; `out` is null or
/// writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_reader_open(
    scene: *const c_char,
    options: *const YggReaderOptions,
    out: *mut *mut YggReader,
) -> YggStatus {
    guard("ygg_reader_open", || {
        crate::logging::init();
        // SAFETY: the caller's contract for `scene` and `out`.
        let (scene, out) = unsafe { (str_arg(scene, "scene")?, Out::new(out, "out")?) };
        // SAFETY: `options` is null or points to a readable `YggReaderOptions`.
        let options = unsafe { options.as_ref() }.copied().unwrap_or_default();
        let reader = SceneReader::builder(scene)
            .wait_for_writer(Duration::from_millis(options.wait_for_writer_ms))
            .copy_segments(options.copy_segments)
            .handle_termination_signals(options.handle_termination_signals)
            .open()
            .map_err(FfiError::wrap(YggStatus::ReaderOpen, scene))?;
        out.write(handle::register(YggReader { reader }));
        Ok(())
    })
}

/// Destroys a reader. Snapshots it gave stay valid until destroyed themselves.
///
/// # Safety
/// `reader` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_reader_destroy(reader: *mut YggReader) -> YggStatus {
    guard("ygg_reader_destroy", || {
        drop(handle::unregister(reader, "reader")?);
        Ok(())
    })
}

/// A received snapshot as a new handle in `out`, or null for none.
fn deliver(
    received: Result<Option<SceneSnapshot>, SceneReceiveError>,
    out: Out<*mut YggSnapshot>,
) -> FfiResult {
    let snapshot = received.map_err(FfiError::wrap(YggStatus::Receive, "receive"))?;
    out.write(snapshot.map_or(std::ptr::null_mut(), |s| {
        handle::register(YggSnapshot::live(s))
    }));
    Ok(())
}

/// Blocks (on the writer's event, no polling) until a snapshot newer than the reader's
/// current one arrives or `timeout_ns` nanoseconds pass. `*snapshot` receives a new
/// snapshot handle, or null on timeout.
///
/// Ownership: the caller destroys a non-null `*snapshot` with `ygg_snapshot_destroy`;
/// it keeps the shared-memory samples mapped until then.
///
/// # Safety
/// `snapshot` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_reader_wait_next(
    reader: *mut YggReader,
    timeout_ns: u64,
    snapshot: *mut *mut YggSnapshot,
) -> YggStatus {
    guard("ygg_reader_wait_next", || {
        // SAFETY: the caller's contract for `snapshot`.
        let out = unsafe { Out::new(snapshot, "snapshot") }?;
        let r = &mut handle::resolve_mut(reader, "reader")?.reader;
        deliver(r.wait_next(Duration::from_nanos(timeout_ns)), out)
    })
}

/// The newest snapshot without blocking: `*snapshot` receives a new handle, or null
/// before a first snapshot arrived. A rejected snapshot is reported once; until a newer
/// one arrives, later calls give the last accepted snapshot.
///
/// Ownership: as `ygg_reader_wait_next`.
///
/// # Safety
/// `snapshot` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_reader_latest(
    reader: *mut YggReader,
    snapshot: *mut *mut YggSnapshot,
) -> YggStatus {
    guard("ygg_reader_latest", || {
        // SAFETY: the caller's contract for `snapshot`.
        let out = unsafe { Out::new(snapshot, "snapshot") }?;
        let r = &mut handle::resolve_mut(reader, "reader")?.reader;
        deliver(r.latest(), out)
    })
}

/// Whether the scene's writer is alive or gone.
///
/// # Safety
/// `state` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_reader_writer_status(
    reader: *mut YggReader,
    state: *mut YggWriterState,
) -> YggStatus {
    guard("ygg_reader_writer_status", || {
        // SAFETY: the caller's contract for `state`.
        let out = unsafe { Out::new(state, "state") }?;
        out.write(
            match handle::resolve(reader, "reader")?.reader.writer_status() {
                WriterStatus::Unknown => YggWriterState::Unknown,
                WriterStatus::Alive => YggWriterState::Alive,
                WriterStatus::Gone => YggWriterState::Gone,
            },
        );
        Ok(())
    })
}

/// Whether SIGINT/SIGTERM was received (with `handle_termination_signals`).
///
/// # Safety
/// `requested` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_reader_termination_requested(
    reader: *mut YggReader,
    requested: *mut bool,
) -> YggStatus {
    guard("ygg_reader_termination_requested", || {
        // SAFETY: the caller's contract for `requested`.
        let out = unsafe { Out::new(requested, "requested") }?;
        out.write(
            handle::resolve(reader, "reader")?
                .reader
                .termination_requested(),
        );
        Ok(())
    })
}
