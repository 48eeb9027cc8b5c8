//! Files: `.ygg` snapshots, Spark-DSG imports, and the built-in office.

use std::path::Path;

use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use serde::Deserialize;
use serde_json::value::RawValue;
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

/// `spark_dsg_json_parts`' answer: each node's attributes and each edge's info as JSON
/// text, the metadata and the mesh as JSON text (`None` when absent).
type JsonParts = (
    Vec<(u64, String)>,
    Vec<(u64, u64, String)>,
    Option<String>,
    Option<String>,
);

/// The parts of a Spark-DSG JSON file read as text: only their extent is parsed.
#[derive(Deserialize)]
struct RawParts<'a> {
    #[serde(borrow, default)]
    nodes: Vec<RawNodePart<'a>>,
    #[serde(borrow, default)]
    edges: Vec<RawEdgePart<'a>>,
    #[serde(borrow, default)]
    metadata: Option<&'a RawValue>,
    #[serde(borrow, default)]
    mesh: Option<&'a RawValue>,
}

#[derive(Deserialize)]
struct RawNodePart<'a> {
    id: u64,
    #[serde(borrow, default)]
    attributes: Option<&'a RawValue>,
}

#[derive(Deserialize)]
struct RawEdgePart<'a> {
    source: u64,
    target: u64,
    #[serde(borrow, default)]
    info: Option<&'a RawValue>,
}

/// The parts of a Spark-DSG JSON file that `yggdrasil.dsg` reads on demand (what a scene
/// does not keep), without the GIL: `(nodes, edges, metadata, mesh)`, each node as
/// `(id, attributes)` and each edge as `(source, target, info)` with JSON text values,
/// the metadata and the mesh as JSON text or `None`.
///
/// Raises `FileError` naming the file if it cannot be read or is not a Spark-DSG JSON
/// object.
#[pyfunction]
pub fn spark_dsg_json_parts(py: Python<'_>, path: std::path::PathBuf) -> PyResult<JsonParts> {
    py.detach(|| {
        let fail = |what: String| FileError::new_err(format!("{}: {what}", path.display()));
        let bytes = std::fs::read(&path).map_err(|e| fail(e.to_string()))?;
        let parts: RawParts<'_> =
            serde_json::from_slice(&bytes).map_err(|e| fail(format!("not Spark-DSG JSON: {e}")))?;
        let text = |v: Option<&RawValue>| v.map_or_else(|| "{}".to_owned(), |v| v.get().to_owned());
        Ok((
            parts
                .nodes
                .iter()
                .map(|n| (n.id, text(n.attributes)))
                .collect(),
            parts
                .edges
                .iter()
                .map(|e| (e.source, e.target, text(e.info)))
                .collect(),
            parts.metadata.map(|v| v.get().to_owned()),
            parts.mesh.map(|v| v.get().to_owned()),
        ))
    })
}

/// `spark_dsg_json_mesh`'s answer: the flags `(has_colors, has_timestamps, has_labels,
/// has_first_seen_stamps)`, then points `(n, 3)` `float32`, colors `(n, 4)` `uint8`,
/// stamps `uint64`, labels `uint32`, first-seen stamps `uint64` and faces `(m, 3)`
/// `uint64`.
type MeshArrays<'py> = (
    (bool, bool, bool, bool),
    Bound<'py, PyArray2<f32>>,
    Bound<'py, PyArray2<u8>>,
    Bound<'py, PyArray1<u64>>,
    Bound<'py, PyArray1<u32>>,
    Bound<'py, PyArray1<u64>>,
    Bound<'py, PyArray2<u64>>,
);

/// A mesh color: `{"r", "g", "b", "a"}` (1.1) or `[r, g, b(, a)]`.
#[derive(Deserialize)]
#[serde(untagged)]
enum RawColor {
    Object {
        r: u8,
        g: u8,
        b: u8,
        #[serde(default = "opaque")]
        a: u8,
    },
    List(Vec<u8>),
}

fn opaque() -> u8 {
    255
}

fn yes() -> bool {
    true
}

/// A Spark-DSG JSON mesh object.
#[derive(Deserialize)]
struct RawJsonMesh {
    #[serde(default = "yes")]
    has_colors: bool,
    #[serde(default = "yes")]
    has_timestamps: bool,
    #[serde(default = "yes")]
    has_labels: bool,
    #[serde(default = "yes")]
    has_first_seen_stamps: bool,
    #[serde(default)]
    points: Vec<[f64; 3]>,
    #[serde(default)]
    colors: Vec<RawColor>,
    #[serde(default)]
    stamps: Vec<u64>,
    #[serde(default)]
    labels: Vec<u32>,
    #[serde(default)]
    first_seen_stamps: Vec<u64>,
    #[serde(default)]
    faces: Vec<[u64; 3]>,
}

/// A Spark-DSG JSON mesh object (the text `spark_dsg_json_parts` gives) as numpy arrays:
/// `((has_colors, has_timestamps, has_labels, has_first_seen_stamps), points, colors,
/// stamps, labels, first_seen_stamps, faces)`. A per-vertex array whose length is not
/// the number of points comes back zero-filled (colors opaque black).
///
/// Raises `FileError` if the text is not a mesh object.
#[pyfunction]
pub fn spark_dsg_json_mesh<'py>(py: Python<'py>, text: &str) -> PyResult<MeshArrays<'py>> {
    let m: RawJsonMesh = py
        .detach(|| serde_json::from_str(text))
        .map_err(|e| FileError::new_err(format!("not a Spark-DSG mesh: {e}")))?;
    let n = m.points.len();
    let points: Vec<f32> = m.points.iter().flatten().map(|&x| x as f32).collect();
    let mut colors = vec![0u8; n * 4];
    if m.colors.len() == n {
        for (out, c) in colors.chunks_exact_mut(4).zip(&m.colors) {
            match c {
                RawColor::Object { r, g, b, a } => out.copy_from_slice(&[*r, *g, *b, *a]),
                RawColor::List(v) => {
                    out[3] = 255;
                    out.iter_mut().zip(v).for_each(|(o, x)| *o = *x);
                }
            }
        }
    } else {
        colors.chunks_exact_mut(4).for_each(|c| c[3] = 255);
    }
    let per_vertex = |v: Vec<u64>| if v.len() == n { v } else { vec![0; n] };
    let labels = if m.labels.len() == n {
        m.labels
    } else {
        vec![0; n]
    };
    let faces: Vec<u64> = m.faces.iter().flatten().copied().collect();
    Ok((
        (
            m.has_colors,
            m.has_timestamps,
            m.has_labels,
            m.has_first_seen_stamps,
        ),
        PyArray1::from_vec(py, points).reshape([n, 3])?,
        PyArray1::from_vec(py, colors).reshape([n, 4])?,
        PyArray1::from_vec(py, per_vertex(m.stamps)),
        PyArray1::from_vec(py, labels),
        PyArray1::from_vec(py, per_vertex(m.first_seen_stamps)),
        PyArray1::from_vec(py, faces).reshape([m.faces.len(), 3])?,
    ))
}
