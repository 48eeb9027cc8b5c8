//! Recordings (`ygg_recording`, `ygg_recorder`): open a recording and get any recorded
//! moment as a snapshot handle (queried in place on the mapped files, with every snapshot
//! accessor and query); record a live scene.
//!
//! Thread-safety of `ygg_recording`: immutable once opened; any number of threads may
//! call `ygg_recording_*` at once. `ygg_recorder` is not thread-safe (one thread at a
//! time).

use crate::args::{Out, str_arg};
use crate::errors::{FfiError, FfiResult, YggStatus, guard};
use crate::handle::{self, Handle, Kind};
use crate::snapshot::YggSnapshot;
use std::ffi::c_char;
use std::time::Duration;
use ygg_reader::{RecordError, SceneReader, SceneRecorder};
use ygg_store::recording::{Recording, RecordingOptions, RecordingWriter};

/// An opened recording.
///
/// Thread-safety: immutable; any number of threads may use it at once.
pub struct YggRecording {
    recording: Recording,
}

impl Handle for YggRecording {
    const KIND: Kind = Kind::Recording;
    const NAME: &'static str = "recording";
}

/// A recorder of a live scene.
///
/// Thread-safety: not thread-safe; use it from one thread at a time.
pub struct YggRecorder {
    recorder: SceneRecorder,
}

impl Handle for YggRecorder {
    const KIND: Kind = Kind::Recorder;
    const NAME: &'static str = "recorder";
}

/// One recorded cut (`ygg_recording_cut`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct YggCutInfo {
    /// The cut's generation.
    pub generation: u64,
    /// When the writer published it, ns since the Unix epoch (writer's clock).
    pub writer_unix_ns: u64,
    /// When the recorder wrote it, ns since the Unix epoch.
    pub recorder_unix_ns: u64,
    /// Bytes the cut added to the recording.
    pub bytes_added: u64,
}

/// Opens the recording in folder `path` (written by `ygg record` or `ygg_recorder`).
///
/// Ownership: `*out` receives a new handle the caller destroys with
/// `ygg_recording_destroy`.
///
/// # Safety
/// `path` is null or NUL-terminated; `out` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_recording_open(
    path: *const c_char,
    out: *mut *mut YggRecording,
) -> YggStatus {
    guard("ygg_recording_open", || {
        // SAFETY: the caller's contract for `path` and `out`.
        let (path, out) = unsafe { (str_arg(path, "path")?, Out::new(out, "out")?) };
        let recording = Recording::open(path).map_err(FfiError::wrap(YggStatus::Io, "open"))?;
        out.write(handle::register(YggRecording { recording }));
        Ok(())
    })
}

/// Destroys a recording. Snapshots it gave stay valid until destroyed themselves.
///
/// # Safety
/// `recording` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_recording_destroy(recording: *mut YggRecording) -> YggStatus {
    guard("ygg_recording_destroy", || {
        drop(handle::unregister(recording, "recording")?);
        Ok(())
    })
}

/// The number of cuts in `*count`.
///
/// # Safety
/// `count` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_recording_cut_count(
    recording: *const YggRecording,
    count: *mut usize,
) -> YggStatus {
    guard("ygg_recording_cut_count", || {
        // SAFETY: the caller's contract for `count`.
        let out = unsafe { Out::new(count, "count") }?;
        out.write(
            handle::resolve(recording, "recording")?
                .recording
                .cuts()
                .len(),
        );
        Ok(())
    })
}

/// Cut `index` (0 = the first) in `*info`; `YGG_STATUS_NOT_FOUND` past the last.
///
/// # Safety
/// `info` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_recording_cut(
    recording: *const YggRecording,
    index: usize,
    info: *mut YggCutInfo,
) -> YggStatus {
    guard("ygg_recording_cut", || {
        // SAFETY: the caller's contract for `info`.
        let out = unsafe { Out::new(info, "info") }?;
        let cuts = handle::resolve(recording, "recording")?.recording.cuts();
        let c = cuts.get(index).ok_or_else(|| {
            FfiError::new(
                YggStatus::NotFound,
                format!("no cut {index}; the recording holds {}", cuts.len()),
            )
        })?;
        out.write(YggCutInfo {
            generation: c.generation,
            writer_unix_ns: c.writer_unix_ns,
            recorder_unix_ns: c.recorder_unix_ns,
            bytes_added: c.bytes_added,
        });
        Ok(())
    })
}

/// The scene as it was at `unix_ns` (ns since the Unix epoch, writer's clock): the last
/// cut published at or before it, as a snapshot handle in `*snapshot`.
/// `YGG_STATUS_NOT_FOUND` before the first cut.
///
/// Ownership: `*snapshot` receives a new handle the caller destroys with
/// `ygg_snapshot_destroy`; it keeps the recording's files mapped until then.
///
/// # Safety
/// `snapshot` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_recording_at_time(
    recording: *const YggRecording,
    unix_ns: u64,
    snapshot: *mut *mut YggSnapshot,
) -> YggStatus {
    guard("ygg_recording_at_time", || {
        // SAFETY: the caller's contract for `snapshot`.
        let out = unsafe { Out::new(snapshot, "snapshot") }?;
        let r = &handle::resolve(recording, "recording")?.recording;
        let cut = r.cut_at_time(unix_ns).ok_or_else(|| {
            FfiError::new(
                YggStatus::NotFound,
                format!("no cut at or before {unix_ns} ns since the Unix epoch"),
            )
        })?;
        deliver(r, cut, out)
    })
}

/// The cut of generation `generation` (the last one of that generation or earlier), as
/// a snapshot handle in `*snapshot`; `YGG_STATUS_NOT_FOUND` when every cut is newer.
///
/// Ownership: as `ygg_recording_at_time`.
///
/// # Safety
/// `snapshot` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_recording_at_generation(
    recording: *const YggRecording,
    generation: u64,
    snapshot: *mut *mut YggSnapshot,
) -> YggStatus {
    guard("ygg_recording_at_generation", || {
        // SAFETY: the caller's contract for `snapshot`.
        let out = unsafe { Out::new(snapshot, "snapshot") }?;
        let r = &handle::resolve(recording, "recording")?.recording;
        let cut = r.cut_at_generation(generation).ok_or_else(|| {
            FfiError::new(
                YggStatus::NotFound,
                format!("no cut of generation {generation} or earlier"),
            )
        })?;
        deliver(r, cut, out)
    })
}

/// Cut `cut` of `recording`, validated and joined, as a new snapshot handle in `out`.
fn deliver(recording: &Recording, cut: usize, out: Out<*mut YggSnapshot>) -> FfiResult {
    let scene = recording
        .scene(cut)
        .map_err(FfiError::wrap(YggStatus::Io, "cut"))?;
    out.write(handle::register(YggSnapshot::recorded(scene)));
    Ok(())
}

/// Attaches to live scene `scene` (waiting up to `wait_for_writer_ms` for its writer) and
/// records into folder `path` (created if missing; an existing recording is continued
/// in a new file).
///
/// Ownership: `*out` receives a new handle the caller destroys with
/// `ygg_recorder_destroy` (which syncs the recording).
///
/// # Safety
/// `scene` and `path` are null or NUL-terminated; `out` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_recorder_open(
    scene: *const c_char,
    path: *const c_char,
    wait_for_writer_ms: u64,
    out: *mut *mut YggRecorder,
) -> YggStatus {
    guard("ygg_recorder_open", || {
        // SAFETY: the caller's contract for `scene`, `path` and `out`.
        let (scene, path, out) = unsafe {
            (
                str_arg(scene, "scene")?,
                str_arg(path, "path")?,
                Out::new(out, "out")?,
            )
        };
        let reader = SceneReader::builder(scene)
            .wait_for_writer(Duration::from_millis(wait_for_writer_ms))
            .open()
            .map_err(FfiError::wrap(YggStatus::ReaderOpen, scene))?;
        let writer = RecordingWriter::create(path, RecordingOptions::default())
            .map_err(FfiError::wrap(YggStatus::Io, "recording"))?;
        out.write(handle::register(YggRecorder {
            recorder: SceneRecorder::new(reader, writer),
        }));
        Ok(())
    })
}

/// Waits up to `timeout_ns` for a new cut and records it; `*recorded` tells whether one
/// was. `YGG_STATUS_RECEIVE` from the reader, `YGG_STATUS_IO` when the append failed
/// (the recording stays readable up to its last cut).
///
/// # Safety
/// `recorded` is null or writable; `recorder` is not used by another thread.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_recorder_record_next(
    recorder: *mut YggRecorder,
    timeout_ns: u64,
    recorded: *mut bool,
) -> YggStatus {
    guard("ygg_recorder_record_next", || {
        // SAFETY: the caller's contract for `recorded`.
        let out = unsafe { Out::new(recorded, "recorded") }?;
        let r = &mut handle::resolve_mut(recorder, "recorder")?.recorder;
        match r.record_next(Duration::from_nanos(timeout_ns)) {
            Ok(report) => out.write(report.is_some()),
            Err(RecordError::Receive(e)) => {
                return Err(FfiError::wrap(YggStatus::Receive, "receive")(e));
            }
            Err(RecordError::Recording(e)) => {
                return Err(FfiError::wrap(YggStatus::Io, "record")(e));
            }
        }
        Ok(())
    })
}

/// Destroys a recorder; the recording is synced to disk first.
///
/// # Safety
/// `recorder` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_recorder_destroy(recorder: *mut YggRecorder) -> YggStatus {
    guard("ygg_recorder_destroy", || {
        let r = handle::unregister(recorder, "recorder")?;
        r.recorder
            .recording()
            .sync()
            .map_err(FfiError::wrap(YggStatus::Io, "sync"))?;
        Ok(())
    })
}
