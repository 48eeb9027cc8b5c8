//! `yggdrasil`: the Python package of Yggdrasil (PyO3, built by maturin).
//!
//! The extension module `yggdrasil._yggdrasil` binds the Rust crates; the pure-Python
//! part of the package (`python/yggdrasil/`) re-exports it and adds the spark_dsg-style
//! facade `yggdrasil.dsg` and the benchmark `yggdrasil.bench`.
//!
//! * `scene::Scene`: a validated snapshot (`open(path)`, `Reader.wait_next()`,
//!   `SceneGraph.snapshot()`), with every query of `ygg_store::query`.
//! * `objects::ObjectQueries`: the object contract of `ygg query`
//!   (`ygg_dsg::objects`), singly and in batches.
//! * `graph::PySceneGraph` and `writer::Writer`: building and publishing a graph.
//! * `reader::Reader`: following a live scene; `recording`: recordings of one
//!   (`open_recording`, `Recording.at`, `Recorder`).
//! * `errors`: the exception hierarchy; `log_level`: the transport's log level (quiet
//!   unless `YGG_LOG` or `set_log_level` asks for more).
//!
//! Bindings call the Rust queries; no query is implemented here. Queries on a snapshot
//! hold the GIL only for short, non-blocking work; waits and batch queries release it.

mod batch;
mod convert;
mod errors;
mod files;
mod graph;
mod graph_home;
mod log_level;
mod node;
mod objects;
mod points;
mod reader;
mod recording;
mod scene;
mod snapshot;
mod whereabouts;
mod writer;

use pyo3::prelude::*;

/// The extension module `yggdrasil._yggdrasil`.
#[pymodule]
fn _yggdrasil(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    ygg_transport::init_binding_logging();
    m.add_function(wrap_pyfunction!(log_level::set_log_level, m)?)?;
    m.add_function(wrap_pyfunction!(files::open, m)?)?;
    m.add_function(wrap_pyfunction!(recording::open_recording, m)?)?;
    m.add_function(wrap_pyfunction!(files::write_office, m)?)?;
    m.add_function(wrap_pyfunction!(files::office_graph, m)?)?;
    m.add_function(wrap_pyfunction!(files::spark_dsg_json_parts, m)?)?;
    m.add_function(wrap_pyfunction!(files::spark_dsg_json_mesh, m)?)?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<node::Node>()?;
    m.add_class::<node::Layer>()?;
    m.add_class::<objects::ObjectQueries>()?;
    m.add_class::<graph_home::PySceneGraph>()?;
    m.add_class::<reader::Reader>()?;
    m.add_class::<recording::Recording>()?;
    m.add_class::<recording::Recorder>()?;
    m.add_class::<writer::Writer>()?;
    m.add_class::<whereabouts::AgentPose>()?;
    m.add_class::<whereabouts::RoomScope>()?;
    m.add("NO_NODE", batch::NO_NODE)?;
    m.add("Error", py.get_type::<errors::Error>())?;
    m.add("FileError", py.get_type::<errors::FileError>())?;
    m.add("QueryError", py.get_type::<errors::QueryError>())?;
    m.add("MutationError", py.get_type::<errors::MutationError>())?;
    m.add("TransportError", py.get_type::<errors::TransportError>())?;
    m.add("WriterGoneError", py.get_type::<errors::WriterGoneError>())?;
    Ok(())
}
