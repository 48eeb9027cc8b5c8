//! Files: `.ygg` snapshots, Spark-DSG imports, and the built-in office.

use std::path::Path;

use pyo3::prelude::*;
use ygg_dsg::layout::{self, Layout};
use ygg_dsg::{ImportOptions, office};
use ygg_store::{SceneGraph, SnapshotFile};

use crate::errors::{FileError, QueryError, file_error};
use crate::graph_home::PySceneGraph;
use crate::scene::Scene;
use crate::snapshot::SnapshotSource;

/// Opens a `.ygg` snapshot file: maps it and validates every segment once; queries then
/// run on the mapped bytes.
///
/// Raises `FileError` for a missing, foreign, truncated or corrupted file.
#[pyfunction]
pub fn open(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Scene> {
    let file = py
        .detach(|| SnapshotFile::open(&path))
        .map_err(|e| file_error(&e))?;
    Ok(Scene::new(SnapshotSource::File(file)))
}

/// Imports a Spark-DSG file into a `SceneGraph` in one of the paper's layouts.
pub fn import_spark_dsg(
    py: Python<'_>,
    path: &Path,
    layout: &str,
    lenient: bool,
) -> PyResult<SceneGraph> {
    let layout: Layout = layout
        .parse()
        .map_err(|e: String| QueryError::new_err(format!("layout: {e}")))?;
    let options = if lenient {
        ImportOptions::LENIENT
    } else {
        ImportOptions::default()
    };
    py.detach(|| {
        let imported = ygg_dsg::read_file_with(path, options).map_err(|e| file_error(&e))?;
        layout::build(&imported.graph, layout).map_err(|e| file_error(&e))
    })
}

/// Writes the built-in office (the uHumans2 office's counts, generated from `seed`;
/// `scale` 1.0 is full size) as a Spark-DSG file at `path`: binary if it ends in
/// `.sparkdsg`, JSON otherwise. spark_dsg 1.1.3 loads either.
#[pyfunction]
#[pyo3(signature = (path, seed = 7, scale = 1.0))]
pub fn write_office(
    py: Python<'_>,
    path: std::path::PathBuf,
    seed: u64,
    scale: f64,
) -> PyResult<()> {
    py.detach(|| {
        let graph = office::generate(office::OfficeParams { seed, scale });
        let written = if path.extension().is_some_and(|e| e == "sparkdsg") {
            ygg_dsg::write_binary(&graph, &path)
        } else {
            ygg_dsg::write_json(&graph, &path)
        };
        written.map_err(|e| FileError::new_err(crate::errors::message(&e)))
    })
}

/// The built-in office in one of the paper's layouts, as a `SceneGraph`.
#[pyfunction]
#[pyo3(signature = (layout = "mint", seed = 7, scale = 1.0))]
pub fn office_graph(py: Python<'_>, layout: &str, seed: u64, scale: f64) -> PyResult<PySceneGraph> {
    let layout: Layout = layout
        .parse()
        .map_err(|e: String| QueryError::new_err(format!("layout: {e}")))?;
    py.detach(|| {
        let graph = office::generate(office::OfficeParams { seed, scale });
        layout::build(&graph, layout).map_err(|e| file_error(&e))
    })
    .map(PySceneGraph::from_graph)
}
