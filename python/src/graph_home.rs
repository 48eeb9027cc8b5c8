//! The Rust side of a Python `SceneGraph`: where its graph lives (owned, or inside the
//! writer that publishes it) and the locking every mutation goes through. The Python
//! methods are in `graph.rs`; this module is what `scene`, `files`, `reader` and `writer`
//! need of it, below them all.

use std::sync::{Arc, Mutex, MutexGuard};

use pyo3::prelude::*;
use pyo3::types::PyString;
use ygg_store::{EditResult, LayerId, SceneGraph};
use ygg_writer::SceneWriter;

use crate::errors::{MutationError, mutation_error};

/// A writer shared by a `Writer` and the `SceneGraph` it publishes (`None` once closed).
pub type SharedWriter = Arc<Mutex<Option<SceneWriter>>>;

/// Locks `m`; a poisoned lock (a panic while held) still holds a consistent value, since
/// every mutation either applies fully or not at all.
pub fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Where a Python `SceneGraph`'s graph lives.
pub enum GraphHome {
    /// In the Python object (boxed: a graph is large, a writer handle small).
    Owned(Box<SceneGraph>),
    /// In a writer, which publishes it.
    Published(SharedWriter),
}

/// A scene graph you build and edit: layers in a DAG, nodes with features, labels and
/// geometry, intra-layer edges and nesting. Every mutation validates and either applies
/// fully or raises `MutationError`, leaving the graph unchanged.
///
/// Layers are given by name or by id (the int `add_layer` returns).
#[pyclass(frozen, module = "yggdrasil", name = "SceneGraph")]
pub struct PySceneGraph {
    home: Mutex<GraphHome>,
}

impl PySceneGraph {
    /// A Python graph owning `graph`.
    pub fn from_graph(graph: SceneGraph) -> Self {
        PySceneGraph {
            home: Mutex::new(GraphHome::Owned(Box::new(graph))),
        }
    }

    /// The graph's home, locked.
    pub fn home(&self) -> MutexGuard<'_, GraphHome> {
        lock(&self.home)
    }

    /// Runs `f` on the graph (refused once its writer is closed).
    pub fn with<T>(&self, f: impl FnOnce(&mut SceneGraph) -> T) -> PyResult<T> {
        let mut home = self.home();
        match &mut *home {
            GraphHome::Owned(g) => Ok(f(g)),
            GraphHome::Published(w) => match lock(w).as_mut() {
                Some(w) => Ok(f(w.graph_mut())),
                None => Err(MutationError::new_err(
                    "the writer publishing this graph was closed",
                )),
            },
        }
    }

    /// Runs a mutation; its refusal raises `MutationError` (graph unchanged).
    pub fn edit<T>(&self, f: impl FnOnce(&mut SceneGraph) -> EditResult<T>) -> PyResult<T> {
        self.with(f)?.map_err(|e| mutation_error(&e))
    }

    /// The layer given by name or id.
    pub fn layer(g: &SceneGraph, layer: &Bound<'_, PyAny>) -> EditResult<LayerId> {
        match layer.cast::<PyString>() {
            Ok(name) => g.layer_id(&name.to_string_lossy()),
            Err(_) => {
                let id: u32 = layer.extract().unwrap_or(u32::MAX);
                Ok(LayerId(id))
            }
        }
    }
}
