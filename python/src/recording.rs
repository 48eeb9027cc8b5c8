//! `yggdrasil.open_recording` / `yggdrasil.Recording`: a recording of a live scene, any
//! cut of it a `Scene` queried in place; `yggdrasil.Recorder`: records a live scene.

use std::sync::Mutex;
use std::time::Duration;

use numpy::{IntoPyArray, PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use ygg_reader::{RecordError, SceneReader, SceneRecorder};
use ygg_store::recording::{Recording as StoredRecording, RecordingOptions, RecordingWriter};

use crate::errors::{QueryError, TransportError, file_error, receive_error, transport_error};
use crate::graph_home::lock;
use crate::scene::Scene;
use crate::snapshot::SnapshotSource;

/// Opens the recording in folder `path` (written by `ygg record` or `Recorder`): scans
/// its files once; every cut then opens in place with `Recording.at`.
///
/// Raises `FileError` for a folder that is not a recording or holds no complete cut.
#[pyfunction]
pub fn open_recording(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Recording> {
    let recording = py
        .detach(|| StoredRecording::open(&path))
        .map_err(|e| file_error(&e))?;
    Ok(Recording { recording })
}

/// A recording of a live scene: its cuts (`cuts`), any of them as a `Scene` (`at`), and
/// what changed between two moments (`changes`). Times are seconds since the Unix epoch
/// on the writer's clock, resolved to the microsecond.
#[pyclass(frozen, module = "yggdrasil", name = "Recording")]
pub struct Recording {
    recording: StoredRecording,
}

/// Seconds since the Unix epoch as ns, to the end of its microsecond: a float64 of
/// today's epoch seconds resolves about 0.24 µs, so a time read from `cuts` names its own
/// cut (negative or non-finite refused).
fn unix_ns(seconds: f64, what: &str) -> PyResult<u64> {
    if seconds.is_finite() && seconds >= 0.0 {
        Ok(((seconds * 1e6).round() as u64)
            .saturating_mul(1000)
            .saturating_add(999))
    } else {
        Err(QueryError::new_err(format!(
            "{what} must be a non-negative number of seconds since the Unix epoch, got {seconds}"
        )))
    }
}

impl Recording {
    /// The cut of `time` (the last published at or before it).
    fn cut_at_time(&self, time: f64, what: &str) -> PyResult<usize> {
        let t = unix_ns(time, what)?;
        self.recording.cut_at_time(t).ok_or_else(|| {
            QueryError::new_err(format!(
                "{what} {time}: no cut at or before it; the first cut is at {}",
                self.recording.cuts()[0].writer_unix_ns as f64 / 1e9
            ))
        })
    }
}

#[pymethods]
impl Recording {
    /// Every cut, as numpy arrays of one entry per cut: `generation` (uint64), `time`
    /// (float64, when the writer published it), `recorded_time` (float64, when the
    /// recorder wrote it), `bytes_added` (uint64, what the cut added to the files).
    #[getter]
    fn cuts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let cuts = self.recording.cuts();
        let d = PyDict::new(py);
        let col_u64 = |f: fn(&ygg_store::recording::CutSummary) -> u64| {
            cuts.iter().map(f).collect::<Vec<u64>>()
        };
        let col_s = |f: fn(&ygg_store::recording::CutSummary) -> u64| {
            cuts.iter().map(|c| f(c) as f64 / 1e9).collect::<Vec<f64>>()
        };
        d.set_item("generation", col_u64(|c| c.generation).into_pyarray(py))?;
        d.set_item("time", col_s(|c| c.writer_unix_ns).into_pyarray(py))?;
        d.set_item(
            "recorded_time",
            col_s(|c| c.recorder_unix_ns).into_pyarray(py),
        )?;
        d.set_item("bytes_added", col_u64(|c| c.bytes_added).into_pyarray(py))?;
        Ok(d)
    }

    /// Number of cuts.
    fn __len__(&self) -> usize {
        self.recording.cuts().len()
    }

    /// When the first cut was published (seconds since the Unix epoch).
    #[getter]
    fn start_time(&self) -> f64 {
        self.recording.cuts()[0].writer_unix_ns as f64 / 1e9
    }

    /// When the last cut was published (seconds since the Unix epoch).
    #[getter]
    fn end_time(&self) -> f64 {
        let cuts = self.recording.cuts();
        cuts[cuts.len() - 1].writer_unix_ns as f64 / 1e9
    }

    /// Damage found in the files (the cuts after it in its file are not readable).
    #[getter]
    fn defects(&self) -> Vec<String> {
        self.recording.defects().to_vec()
    }

    /// The scene as it was at `time` (the last cut published at or before it: Khronos'
    /// "nearest snapshot at or before t"), or at cut `generation` (the last cut of that
    /// generation or earlier), or the last cut when neither is given. The `Scene` is
    /// queried in place on the mapped recording.
    ///
    /// Raises `QueryError` when no cut matches, `FileError` when the cut fails validation.
    #[pyo3(signature = (time = None, generation = None))]
    fn at(&self, py: Python<'_>, time: Option<f64>, generation: Option<u64>) -> PyResult<Scene> {
        let cut = match (time, generation) {
            (Some(_), Some(_)) => {
                return Err(QueryError::new_err("give time or generation, not both"));
            }
            (Some(t), None) => self.cut_at_time(t, "time")?,
            (None, Some(g)) => self.recording.cut_at_generation(g).ok_or_else(|| {
                QueryError::new_err(format!(
                    "no cut of generation {g} or earlier; the first is {}",
                    self.recording.cuts()[0].generation
                ))
            })?,
            (None, None) => self.recording.cuts().len() - 1,
        };
        let scene = py
            .detach(|| self.recording.scene(cut))
            .map_err(|e| file_error(&e))?;
        Ok(Scene::new(SnapshotSource::Recorded(scene)))
    }

    /// What changed from the scene at `t0` to the scene at `t1` (seconds since the Unix
    /// epoch): a dict of `nodes_added`, `nodes_removed` (uint64 arrays), `nodes_moved`
    /// (uint64) with `moved_from` / `moved_to` (n x 3 float32) for nodes that moved by
    /// more than `tolerance` meters, `nodes_relabelled` (a list of `(id, old labels, new
    /// labels)`), `edges_added` / `edges_removed` (n x 2 uint64). Only the segments that
    /// differ between the two cuts are compared.
    #[pyo3(signature = (t0, t1, tolerance = 0.05))]
    fn changes<'py>(
        &self,
        py: Python<'py>,
        t0: f64,
        t1: f64,
        tolerance: f32,
    ) -> PyResult<Bound<'py, PyDict>> {
        if !(tolerance.is_finite() && tolerance >= 0.0) {
            return Err(QueryError::new_err(format!(
                "tolerance must be a non-negative number of meters, got {tolerance}"
            )));
        }
        let (a, b) = (self.cut_at_time(t0, "t0")?, self.cut_at_time(t1, "t1")?);
        let c = py
            .detach(|| self.recording.changes(a, b, tolerance))
            .map_err(|e| file_error(&e))?;
        let d = PyDict::new(py);
        let ids = |v: &[ygg_store::NodeId]| v.iter().map(|n| n.0).collect::<Vec<u64>>();
        let pairs = |py, v: &[(ygg_store::NodeId, ygg_store::NodeId)]| {
            let flat: Vec<u64> = v.iter().flat_map(|(a, b)| [a.0, b.0]).collect();
            PyArray1::from_vec(py, flat).reshape([v.len(), 2])
        };
        let points = |py, v: Vec<[f32; 3]>| {
            let n = v.len();
            PyArray1::from_vec(py, v.into_iter().flatten().collect()).reshape([n, 3])
        };
        d.set_item("nodes_added", ids(&c.nodes_added).into_pyarray(py))?;
        d.set_item("nodes_removed", ids(&c.nodes_removed).into_pyarray(py))?;
        let moved: Vec<u64> = c.nodes_moved.iter().map(|m| m.id.0).collect();
        d.set_item("nodes_moved", moved.into_pyarray(py))?;
        d.set_item(
            "moved_from",
            points(py, c.nodes_moved.iter().map(|m| m.from).collect())?,
        )?;
        d.set_item(
            "moved_to",
            points(py, c.nodes_moved.iter().map(|m| m.to).collect())?,
        )?;
        let relabelled: Vec<(u64, Vec<String>, Vec<String>)> = c
            .nodes_relabelled
            .into_iter()
            .map(|r| (r.id.0, r.from, r.to))
            .collect();
        d.set_item("nodes_relabelled", relabelled)?;
        d.set_item("edges_added", pairs(py, &c.edges_added)?)?;
        d.set_item("edges_removed", pairs(py, &c.edges_removed)?)?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!(
            "<yggdrasil.Recording {} ({} cuts)>",
            self.recording.dir().display(),
            self.recording.cuts().len()
        )
    }
}

/// Records a live scene into a recording folder: each cut `record_next` receives is
/// appended, each changed segment once. A reader like any other: it never slows the
/// writer.
#[pyclass(frozen, module = "yggdrasil", name = "Recorder")]
pub struct Recorder {
    recorder: Mutex<SceneRecorder>,
}

#[pymethods]
impl Recorder {
    /// Attaches to `scene_name` (waiting up to `wait_for_writer` seconds) and records
    /// into folder `path` (created if missing; an existing recording is continued in a
    /// new file). `max_size` (bytes) and `max_age` (seconds) drop the oldest files.
    ///
    /// Raises `TransportError` without a writer, `FileError` when the folder cannot be
    /// written.
    #[new]
    #[pyo3(signature = (scene_name, path, wait_for_writer = 5.0, max_size = None, max_age = None))]
    fn py_new(
        py: Python<'_>,
        scene_name: &str,
        path: std::path::PathBuf,
        wait_for_writer: f64,
        max_size: Option<u64>,
        max_age: Option<f64>,
    ) -> PyResult<Self> {
        let seconds = |v: f64, what: &str| {
            Duration::try_from_secs_f64(v).map_err(|_| {
                QueryError::new_err(format!("{what} must be a non-negative number of seconds"))
            })
        };
        let wait = seconds(wait_for_writer, "wait_for_writer")?;
        let max_age = max_age.map(|a| seconds(a, "max_age")).transpose()?;
        if max_size == Some(0) {
            return Err(QueryError::new_err("max_size must be positive"));
        }
        let options = RecordingOptions {
            max_bytes: max_size,
            max_age,
            ..RecordingOptions::default()
        };
        let reader = py
            .detach(|| {
                SceneReader::builder(scene_name)
                    .wait_for_writer(wait)
                    .open()
            })
            .map_err(|e| transport_error(&e))?;
        let writer = RecordingWriter::create(&path, options).map_err(|e| file_error(&e))?;
        Ok(Recorder {
            recorder: Mutex::new(SceneRecorder::new(reader, writer)),
        })
    }

    /// Waits (without the GIL) up to `timeout` seconds for a new cut and records it;
    /// True if one was recorded.
    ///
    /// Raises `TransportError` from the reader, `FileError` when the append failed (a
    /// full disk: the recording stays readable up to its last cut).
    #[pyo3(signature = (timeout = 1.0))]
    fn record_next(&self, py: Python<'_>, timeout: f64) -> PyResult<bool> {
        let timeout = Duration::try_from_secs_f64(timeout)
            .map_err(|_| QueryError::new_err("timeout must be a non-negative number of seconds"))?;
        let got = py.detach(|| lock(&self.recorder).record_next(timeout));
        match got {
            Ok(r) => Ok(r.is_some()),
            Err(RecordError::Receive(e)) => Err(receive_error(&e)),
            Err(RecordError::Recording(e)) => Err(file_error(&e)),
        }
    }

    /// Cuts recorded so far.
    #[getter]
    fn cuts_recorded(&self) -> u64 {
        lock(&self.recorder).cuts_recorded()
    }

    /// Bytes appended so far.
    #[getter]
    fn bytes_recorded(&self) -> u64 {
        lock(&self.recorder).bytes_recorded()
    }

    /// Syncs the recording to disk.
    fn sync(&self, py: Python<'_>) -> PyResult<()> {
        py.detach(|| lock(&self.recorder).recording().sync())
            .map_err(|e| TransportError::new_err(e.to_string()))
    }
}
