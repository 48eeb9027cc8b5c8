//! `yggdrasil.Reader`: attaches to a live scene and hands out its snapshots as `Scene`s.

use std::sync::Mutex;
use std::time::Duration;

use pyo3::prelude::*;
use ygg_reader::{SceneReader, SceneSnapshot, WriterStatus};

use crate::errors::{QueryError, TransportError, receive_error, transport_error};
use crate::graph_home::lock;
use crate::scene::Scene;
use crate::snapshot::SnapshotSource;

fn seconds(value: f64, what: &str) -> PyResult<Duration> {
    Duration::try_from_secs_f64(value).map_err(|_| {
        QueryError::new_err(format!(
            "{what} must be a non-negative number of seconds, got {value}"
        ))
    })
}

/// A reader of one live scene, published by a writer process through shared memory.
///
/// Each snapshot is validated once when it arrives (shared memory is untrusted) and is
/// then queried in place. Waiting releases the GIL.
#[pyclass(frozen, module = "yggdrasil", name = "Reader")]
pub struct Reader {
    reader: Mutex<Option<SceneReader>>,
    scene: String,
}

impl Reader {
    fn with<T>(&self, py: Python<'_>, f: impl FnOnce(&mut SceneReader) -> T + Send) -> PyResult<T>
    where
        T: Send,
    {
        py.detach(|| {
            let mut slot = lock(&self.reader);
            slot.as_mut().map(f)
        })
        .ok_or_else(|| {
            TransportError::new_err(format!("reader of scene {:?} is closed", self.scene))
        })
    }

    fn scene(snapshot: Option<SceneSnapshot>) -> Option<Scene> {
        snapshot.map(|s| Scene::new(SnapshotSource::Live(s)))
    }
}

#[pymethods]
impl Reader {
    /// Attaches to `scene_name`, waiting up to `wait_for_writer` seconds for its writer
    /// (without the GIL). With `copy_segments=True` each new layer is copied into private
    /// memory before validation, for a writer you do not trust.
    ///
    /// Raises `TransportError` if no writer serves the scene in time.
    #[new]
    #[pyo3(signature = (scene_name, wait_for_writer = 0.0, copy_segments = false))]
    fn py_new(
        py: Python<'_>,
        scene_name: &str,
        wait_for_writer: f64,
        copy_segments: bool,
    ) -> PyResult<Self> {
        let wait = seconds(wait_for_writer, "wait_for_writer")?;
        let reader = py
            .detach(|| {
                SceneReader::builder(scene_name)
                    .wait_for_writer(wait)
                    .copy_segments(copy_segments)
                    .open()
            })
            .map_err(|e| transport_error(&e))?;
        Ok(Reader {
            reader: Mutex::new(Some(reader)),
            scene: scene_name.to_owned(),
        })
    }

    /// Blocks (without the GIL) until a snapshot newer than the last one arrives, or
    /// `timeout` seconds pass: the new `Scene`, or `None` on timeout.
    ///
    /// Raises `WriterGoneError` once when the writer exits (the last snapshot stays
    /// usable and a restarted writer is picked up), `TransportError` for a rejected
    /// snapshot.
    #[pyo3(signature = (timeout = 1.0))]
    fn wait_next(&self, py: Python<'_>, timeout: f64) -> PyResult<Option<Scene>> {
        let timeout = seconds(timeout, "timeout")?;
        let got = self.with(py, |r| r.wait_next(timeout))?;
        got.map(Self::scene).map_err(|e| receive_error(&e))
    }

    /// The newest snapshot without blocking (`None` before the first one arrived).
    /// A rejected snapshot raises `TransportError` once; until a newer one arrives, later
    /// calls return the last accepted snapshot.
    fn latest(&self, py: Python<'_>) -> PyResult<Option<Scene>> {
        let got = self.with(py, |r| r.latest())?;
        got.map(Self::scene).map_err(|e| receive_error(&e))
    }

    /// The writer's state as the reader last saw it: `"unknown"`, `"alive"` or `"gone"`.
    #[getter]
    fn writer_status(&self, py: Python<'_>) -> PyResult<&'static str> {
        self.with(py, |r| match r.writer_status() {
            WriterStatus::Unknown => "unknown",
            WriterStatus::Alive => "alive",
            WriterStatus::Gone => "gone",
        })
    }

    /// The scene name.
    #[getter]
    fn scene_name(&self) -> &str {
        &self.scene
    }

    /// How many layer segments this reader has validated (unchanged layers are not
    /// validated again).
    #[getter]
    fn validations(&self, py: Python<'_>) -> PyResult<u64> {
        self.with(py, |r| r.validations())
    }

    /// Detaches from the scene. Scenes already handed out stay usable.
    fn close(&self) {
        lock(&self.reader).take();
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    fn __exit__(
        &self,
        _kind: Option<&Bound<'_, PyAny>>,
        _value: Option<&Bound<'_, PyAny>>,
        _traceback: Option<&Bound<'_, PyAny>>,
    ) {
        self.close();
    }

    fn __repr__(&self) -> String {
        format!("<yggdrasil.Reader scene={:?}>", self.scene)
    }
}
