//! `yggdrasil.Writer`: publishes a `SceneGraph` under a scene name.

use std::sync::{Arc, Mutex};

use pyo3::prelude::*;
use pyo3::types::PyDict;
use ygg_writer::SceneWriter;

use crate::errors::{MutationError, TransportError, transport_error};
use crate::graph_home::{GraphHome, PySceneGraph, SharedWriter, lock};

/// Publishes a `SceneGraph` to readers in other processes through shared memory.
///
/// The graph stays editable from Python: after `Writer(name, graph)`, every mutation of
/// `graph` goes to the writer's graph, and `publish()` sends only the layers that
/// changed, then a manifest naming the new consistent snapshot. `close()` (or leaving a
/// `with` block) stops publishing, removes the scene's shared memory and gives the graph
/// back to the `SceneGraph`.
#[pyclass(frozen, module = "yggdrasil", name = "Writer")]
pub struct Writer {
    writer: SharedWriter,
    graph: Py<PySceneGraph>,
    scene: String,
}

#[pymethods]
impl Writer {
    /// Creates the scene `scene_name` and publishes `graph` as its first snapshot.
    ///
    /// `max_layers` bounds the scene's segments while this writer publishes it (default:
    /// a quarter more than the graph's and at least 256 more; set it for a graph that
    /// starts small and grows). `part_rows` is how many rows the newest part of a layer
    /// takes before a new part starts (default 128): appending a node resends at most
    /// that many rows of its layer.
    ///
    /// Raises `TransportError` (the scene is already served, a bad name, ...) and
    /// `MutationError` if `graph` is already published by another writer.
    #[new]
    #[pyo3(signature = (scene_name, graph, max_readers = 8, max_layers = None, part_rows = None))]
    fn py_new(
        py: Python<'_>,
        scene_name: &str,
        graph: Py<PySceneGraph>,
        max_readers: usize,
        max_layers: Option<usize>,
        part_rows: Option<usize>,
    ) -> PyResult<Self> {
        if part_rows == Some(0) {
            return Err(pyo3::exceptions::PyValueError::new_err(
                "part_rows must be at least 1",
            ));
        }
        let owned = {
            let mut home = graph.get().home();
            match &mut *home {
                GraphHome::Owned(g) => std::mem::take(&mut **g),
                GraphHome::Published(_) => {
                    return Err(MutationError::new_err(
                        "this SceneGraph is already published by a Writer; close it first",
                    ));
                }
            }
        };
        // The writer takes a clone: a failed create returns no graph, and the Python
        // graph must stay as it was when construction fails.
        let created = py.detach(|| {
            let mut builder = SceneWriter::builder(scene_name).max_readers(max_readers);
            if let Some(rows) = part_rows {
                builder = builder.part_rows(rows);
            }
            match max_layers {
                Some(n) => builder.max_layers(n),
                None => builder,
            }
            .create(owned.clone())
        });
        let mut writer = match created {
            Ok(w) => w,
            Err(e) => {
                *graph.get().home() = GraphHome::Owned(Box::new(owned));
                return Err(transport_error(&e));
            }
        };
        drop(owned);
        if let Err(e) = py.detach(|| writer.publish()) {
            *graph.get().home() = GraphHome::Owned(Box::new(writer.graph().clone()));
            return Err(transport_error(&e));
        }
        let shared: SharedWriter = Arc::new(Mutex::new(Some(writer)));
        *graph.get().home() = GraphHome::Published(Arc::clone(&shared));
        Ok(Writer {
            writer: shared,
            graph,
            scene: scene_name.to_owned(),
        })
    }

    /// Publishes the layers changed since the last publish, then a manifest (without the
    /// GIL). Returns `{"generation", "layers_sent", "parts_sent", "layers_unchanged",
    /// "bytes_sent", "segments"}` (`parts_sent`: the row chunks of the changed layers that
    /// changed; `segments`: every segment the cut names).
    ///
    /// Raises `TransportError` (shared memory full, ...; nothing is half-published).
    fn publish<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let report = py
            .detach(|| lock(&self.writer).as_mut().map(SceneWriter::publish))
            .ok_or_else(|| {
                TransportError::new_err(format!("writer of scene {:?} is closed", self.scene))
            })?
            .map_err(|e| transport_error(&e))?;
        let out = PyDict::new(py);
        out.set_item("generation", report.generation)?;
        out.set_item("layers_sent", report.layers_sent)?;
        out.set_item("layers_unchanged", report.layers_unchanged)?;
        out.set_item("bytes_sent", report.bytes_sent)?;
        out.set_item("parts_sent", report.parts_sent)?;
        out.set_item("segments", report.segments)?;
        Ok(out)
    }

    /// The generation of the last snapshot published.
    #[getter]
    fn generation(&self) -> PyResult<u64> {
        lock(&self.writer)
            .as_ref()
            .map(SceneWriter::generation)
            .ok_or_else(|| {
                TransportError::new_err(format!("writer of scene {:?} is closed", self.scene))
            })
    }

    /// The graph being published (the `SceneGraph` given to the constructor).
    #[getter]
    fn graph(&self, py: Python<'_>) -> Py<PySceneGraph> {
        self.graph.clone_ref(py)
    }

    /// The scene name.
    #[getter]
    fn scene_name(&self) -> &str {
        &self.scene
    }

    /// Stops publishing and removes the scene's shared memory; the graph goes back to the
    /// `SceneGraph`, editable as before. Readers keep their last snapshot and see the
    /// writer gone. Closing twice does nothing.
    fn close(&self, py: Python<'_>) {
        let Some(writer) = lock(&self.writer).take() else {
            return;
        };
        let graph = writer.graph().clone();
        py.detach(|| drop(writer));
        *self.graph.get().home() = GraphHome::Owned(Box::new(graph));
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    fn __exit__(
        &self,
        py: Python<'_>,
        _kind: Option<&Bound<'_, PyAny>>,
        _value: Option<&Bound<'_, PyAny>>,
        _traceback: Option<&Bound<'_, PyAny>>,
    ) {
        self.close(py);
    }

    fn __repr__(&self) -> String {
        format!("<yggdrasil.Writer scene={:?}>", self.scene)
    }
}
