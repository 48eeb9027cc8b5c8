//! The writer handle (`ygg_writer`): a scene graph published through shared memory.
//!
//! Thread-safety of `ygg_writer`: not thread-safe. Use a writer, and the graph handle
//! `ygg_writer_graph` gives, from one thread at a time (they may move between threads).

use crate::args::{Out, str_arg};
use crate::errors::{FfiError, YggStatus, guard};
use crate::graph::YggGraph;
use crate::handle::{self, Handle, Kind};
use std::ffi::c_char;
use std::ptr::NonNull;
use std::time::Duration;
use ygg_store::{SceneGraph, SceneView};
use ygg_writer::{SceneWriter, WriterWaitError};

/// A writer serving one scene.
///
/// Thread-safety: not thread-safe. Use a writer and its graph from one thread at a time
/// (they may move between threads together).
pub struct YggWriter {
    writer: SceneWriter,
    /// The handle `ygg_writer_graph` gave out, destroyed with the writer.
    graph: Option<*mut YggGraph>,
}

impl Handle for YggWriter {
    const KIND: Kind = Kind::Writer;
    const NAME: &'static str = "writer";
}

/// Options of `ygg_writer_create`; a zero field keeps the default.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct YggWriterOptions {
    /// Most readers attached at once (default 8). Each costs shared memory for the
    /// samples it may hold.
    pub max_readers: usize,
    /// Initial capacity of a layer's shared-memory segment in bytes; grown in
    /// power-of-two steps (default 64 KiB).
    pub initial_segment_bytes: usize,
    /// Most segments the scene may have while this writer publishes it (default: a
    /// quarter more than the graph's layers, at least 256 more); a publish of more fails.
    /// Set it for a scene that starts small and grows; a lower bound makes readers attach
    /// faster.
    pub max_layers: usize,
    /// Rows the newest part of a layer takes before a new part starts (default 128): an
    /// appended node resends at most this many rows of its layer.
    pub part_rows: usize,
}

/// What one `ygg_writer_publish` sent.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct YggPublishReport {
    /// The snapshot generation published.
    pub generation: u64,
    /// Layers of which a part was (re)published.
    pub layers_sent: usize,
    /// Layers left as they were.
    pub layers_unchanged: usize,
    /// Bytes archived into shared memory (parts, chunks, structure and manifest).
    pub bytes_sent: usize,
    /// Parts (row chunks) of the changed layers that were (re)published.
    pub parts_sent: usize,
    /// Segments the published cut names.
    pub segments: usize,
}

/// A writer's state (`ygg_writer_status`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct YggWriterStatus {
    /// The generation of the last published snapshot (0 before the first publish).
    pub generation: u64,
    /// Nodes in the live graph.
    pub node_count: usize,
    /// Layers in the live graph.
    pub layer_count: usize,
}

/// Creates the writer of `scene` (ASCII letters, digits, `-`, `_`, `.`) and moves
/// `graph` into it: on success the graph handle is destroyed (use `ygg_writer_graph`
/// for the writer's live graph); on failure it stays the caller's, unchanged. Nothing is
/// published until `ygg_writer_publish`. `options` may be null (defaults).
///
/// Ownership: `*out` receives a new writer handle the caller destroys with
/// `ygg_writer_destroy`, which removes the scene's shared memory.
///
/// # Safety
/// `scene` is null or NUL-terminated; `options` is null or readable; `out` is null or
/// writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_writer_create(
    scene: *const c_char,
    graph: *mut YggGraph,
    options: *const YggWriterOptions,
    out: *mut *mut YggWriter,
) -> YggStatus {
    guard("ygg_writer_create", || {
        crate::logging::init();
        // SAFETY: the caller's contract for `scene` and `out`.
        let (scene, out) = unsafe { (str_arg(scene, "scene")?, Out::new(out, "out")?) };
        // SAFETY: `options` is null or points to a readable `YggWriterOptions`.
        let options = unsafe { options.as_ref() }.copied().unwrap_or_default();
        let source = handle::resolve_mut(graph, "graph")?;
        let Some(layers) = source.owned_layer_count() else {
            return Err(FfiError::invalid("the graph already belongs to a writer"));
        };
        let max_layers = match options.max_layers {
            0 => ygg_writer::default_max_layers(layers),
            n => n,
        };
        let mut builder = SceneWriter::builder(scene).max_layers(max_layers);
        if options.max_readers > 0 {
            builder = builder.max_readers(options.max_readers);
        }
        if options.initial_segment_bytes > 0 {
            builder = builder.initial_segment_bytes(options.initial_segment_bytes);
        }
        if options.part_rows > 0 {
            builder = builder.part_rows(options.part_rows);
        }
        // Created on an empty graph first so that a failure leaves the caller's graph
        // untouched; a writer has published nothing before its first `publish`, so
        // adopting the graph now is the same as creating it with the graph.
        let mut writer = builder
            .create(SceneGraph::new())
            .map_err(FfiError::wrap(YggStatus::WriterCreate, scene))?;
        *writer.graph_mut() = source.take_owned()?;
        drop(handle::unregister(graph, "graph")?);
        out.write(handle::register(YggWriter {
            writer,
            graph: None,
        }));
        Ok(())
    })
}

/// Destroys a writer and its graph handle; readers report the writer gone and keep the
/// last snapshot.
///
/// # Safety
/// Neither `writer` nor its graph handle is used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_writer_destroy(writer: *mut YggWriter) -> YggStatus {
    guard("ygg_writer_destroy", || {
        let w = handle::resolve_mut(writer, "writer")?;
        if let Some(graph) = w.graph.take() {
            drop(handle::unregister(graph, "writer's graph")?);
        }
        drop(handle::unregister(writer, "writer")?);
        Ok(())
    })
}

/// The writer's live graph, for mutations; readers see them at the next publish.
///
/// Ownership: `*graph` receives a handle owned by the writer (the same one on every
/// call), valid until `ygg_writer_destroy`; do not destroy it yourself.
///
/// # Safety
/// `graph` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_writer_graph(
    writer: *mut YggWriter,
    graph: *mut *mut YggGraph,
) -> YggStatus {
    guard("ygg_writer_graph", || {
        // SAFETY: the caller's contract for `graph`.
        let out = unsafe { Out::new(graph, "graph") }?;
        let w = handle::resolve_mut(writer, "writer")?;
        let handle = match w.graph {
            Some(g) => g,
            None => {
                let g = handle::register(YggGraph::of_writer(NonNull::from(&mut w.writer)));
                w.graph = Some(g);
                g
            }
        };
        out.write(handle);
        Ok(())
    })
}

/// Publishes every changed layer, then the manifest of the new cut. `report` may be
/// null.
///
/// # Safety
/// `report` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_writer_publish(
    writer: *mut YggWriter,
    report: *mut YggPublishReport,
) -> YggStatus {
    guard("ygg_writer_publish", || {
        let sent = handle::resolve_mut(writer, "writer")?
            .writer
            .publish()
            .map_err(FfiError::wrap(YggStatus::Publish, "publish"))?;
        if !report.is_null() {
            // SAFETY: non-null, writable by the caller's contract.
            let out = unsafe { Out::new(report, "report") }?;
            out.write(YggPublishReport {
                generation: sent.generation,
                layers_sent: sent.layers_sent,
                layers_unchanged: sent.layers_unchanged,
                bytes_sent: sent.bytes_sent,
                parts_sent: sent.parts_sent,
                segments: sent.segments,
            });
        }
        Ok(())
    })
}

/// The writer's state.
///
/// # Safety
/// `status` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_writer_status(
    writer: *mut YggWriter,
    status: *mut YggWriterStatus,
) -> YggStatus {
    guard("ygg_writer_status", || {
        // SAFETY: the caller's contract for `status`.
        let out = unsafe { Out::new(status, "status") }?;
        let w = &handle::resolve(writer, "writer")?.writer;
        out.write(YggWriterStatus {
            generation: w.generation(),
            node_count: w.graph().node_count(),
            layer_count: w.graph().layers().count(),
        });
        Ok(())
    })
}

/// Sleeps up to `timeout_ns` nanoseconds, returning early when SIGINT or SIGTERM
/// arrives: then `*stop_requested` is true (a serving loop's clock and exit in one
/// call).
///
/// # Safety
/// `stop_requested` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_writer_wait(
    writer: *mut YggWriter,
    timeout_ns: u64,
    stop_requested: *mut bool,
) -> YggStatus {
    guard("ygg_writer_wait", || {
        // SAFETY: the caller's contract for `stop_requested`.
        let out = unsafe { Out::new(stop_requested, "stop_requested") }?;
        let w = &handle::resolve(writer, "writer")?.writer;
        let stop = match w.publisher().wait(Duration::from_nanos(timeout_ns)) {
            Ok(()) => false,
            Err(WriterWaitError::Interrupt | WriterWaitError::TerminationRequest) => true,
        };
        out.write(stop);
        Ok(())
    })
}
