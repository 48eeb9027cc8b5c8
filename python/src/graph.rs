//! `yggdrasil.SceneGraph`: the live, editable graph with the mutations of the Rust API.
//!
//! A graph handed to a `Writer` stays editable from Python: its mutations then go to the
//! writer's graph, and `Writer.publish()` sends the layers they changed.

use pyo3::prelude::*;
use ygg_store::{NodeId, SceneGraph, SceneView, query};

use crate::convert::{feature_from_py, points, scope};
use crate::errors::{MutationError, file_error, unknown_node};
use crate::graph_home::PySceneGraph;
use crate::scene::Scene;
use crate::snapshot::SnapshotSource;

#[pymethods]
impl PySceneGraph {
    /// An empty graph.
    #[new]
    fn py_new() -> Self {
        PySceneGraph::from_graph(SceneGraph::new())
    }

    /// Imports a Spark-DSG file (JSON, `.json.gz` or binary `.sparkdsg`) into one of the
    /// paper's layouts: `"vanilla"`, `"chocolate"`, `"mint"` (default) or `"saffron"`.
    /// With `lenient=True`, what Spark-DSG itself would refuse is dropped rather than
    /// failing the import.
    ///
    /// Raises `FileError` naming the file and what is wrong.
    #[staticmethod]
    #[pyo3(signature = (path, layout = "mint", lenient = false))]
    fn import_spark_dsg(
        py: Python<'_>,
        path: std::path::PathBuf,
        layout: &str,
        lenient: bool,
    ) -> PyResult<Self> {
        crate::files::import_spark_dsg(py, &path, layout, lenient).map(Self::from_graph)
    }

    /// Adds a layer and returns its id.
    fn add_layer(&self, name: &str) -> PyResult<u32> {
        self.edit(|g| g.add_layer(name)).map(|l| l.0)
    }

    /// The id of the layer called `name`.
    fn layer_id(&self, name: &str) -> PyResult<u32> {
        self.edit(|g| g.layer_id(name)).map(|l| l.0)
    }

    /// Removes an empty layer and its DAG edges.
    fn remove_layer(&self, layer: &Bound<'_, PyAny>) -> PyResult<()> {
        self.edit(|g| g.remove_layer(Self::layer(g, layer)?))
    }

    /// Adds the DAG edge `parent -> child` (parent encompasses child).
    fn add_layer_edge(&self, parent: &Bound<'_, PyAny>, child: &Bound<'_, PyAny>) -> PyResult<()> {
        self.edit(|g| {
            let (p, c) = (Self::layer(g, parent)?, Self::layer(g, child)?);
            g.add_layer_edge(p, c)
        })
    }

    /// Removes the DAG edge `parent -> child` (no nesting may use it).
    fn remove_layer_edge(
        &self,
        parent: &Bound<'_, PyAny>,
        child: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        self.edit(|g| {
            let (p, c) = (Self::layer(g, parent)?, Self::layer(g, child)?);
            g.remove_layer_edge(p, c)
        })
    }

    /// Adds node `id` to `layer`.
    fn add_node(&self, id: u64, layer: &Bound<'_, PyAny>) -> PyResult<()> {
        self.edit(|g| {
            let l = Self::layer(g, layer)?;
            g.add_node(NodeId(id), l)
        })
    }

    /// Removes a node with its edges and nestings.
    fn remove_node(&self, id: u64) -> PyResult<()> {
        self.edit(|g| g.remove_node(NodeId(id)))
    }

    /// Replaces a node's geometry with `points` (an `(n, 3)` array-like; `[]` for none).
    fn set_geometry(&self, py: Python<'_>, id: u64, points: &Bound<'_, PyAny>) -> PyResult<()> {
        let pts = if points.len().is_ok_and(|n| n == 0) {
            Vec::new()
        } else {
            self::points(points, "points")
                .map_err(|e| MutationError::new_err(e.value(py).to_string()))?
        };
        self.edit(|g| g.set_geometry(NodeId(id), pts))
    }

    /// Appends `points` (an `(n, 3)` array-like) to a node's geometry: a growing mesh costs
    /// the appended points, not its whole list.
    fn append_points(&self, py: Python<'_>, id: u64, points: &Bound<'_, PyAny>) -> PyResult<()> {
        if points.len().is_ok_and(|n| n == 0) {
            return self.edit(|g| g.append_points(NodeId(id), &[]));
        }
        let pts = self::points(points, "points")
            .map_err(|e| MutationError::new_err(e.value(py).to_string()))?;
        self.edit(|g| g.append_points(NodeId(id), &pts))
    }

    /// Sets feature `key` of a node to a str, int, float or bool.
    fn set_feature(
        &self,
        py: Python<'_>,
        id: u64,
        key: &str,
        value: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let value = feature_from_py(value, "value")
            .map_err(|e| MutationError::new_err(e.value(py).to_string()))?;
        self.edit(|g| g.set_feature(NodeId(id), key, value))
    }

    /// Removes feature `key` of a node.
    fn remove_feature(&self, id: u64, key: &str) -> PyResult<()> {
        self.edit(|g| g.remove_feature(NodeId(id), key))
    }

    /// Adds a label to a node (a node holds a set of labels).
    fn add_label(&self, id: u64, label: &str) -> PyResult<()> {
        self.edit(|g| g.add_label(NodeId(id), label))
    }

    /// Removes a label from a node.
    fn remove_label(&self, id: u64, label: &str) -> PyResult<()> {
        self.edit(|g| g.remove_label(NodeId(id), label))
    }

    /// Adds the edge `source -> target` (both in one layer) with a description.
    #[pyo3(signature = (source, target, description = ""))]
    fn add_edge(&self, source: u64, target: u64, description: &str) -> PyResult<()> {
        self.edit(|g| g.add_edge(NodeId(source), NodeId(target), description))
    }

    /// Removes the edge `source -> target`.
    fn remove_edge(&self, source: u64, target: u64) -> PyResult<()> {
        self.edit(|g| g.remove_edge(NodeId(source), NodeId(target)))
    }

    /// Nests `child` under `parent` (along a DAG edge of their layers).
    fn nest(&self, parent: u64, child: u64) -> PyResult<()> {
        self.edit(|g| g.nest(NodeId(parent), NodeId(child)))
    }

    /// Removes `child`'s nesting.
    fn unnest(&self, child: u64) -> PyResult<()> {
        self.edit(|g| g.unnest(NodeId(child)))
    }

    /// Keeps an exact bounding box of the node's sub-tree.
    fn enable_bounding_box(&self, id: u64) -> PyResult<()> {
        self.edit(|g| g.enable_bounding_box(NodeId(id)))
    }

    /// Stops keeping the node's bounding box.
    fn disable_bounding_box(&self, id: u64) -> PyResult<()> {
        self.edit(|g| g.disable_bounding_box(NodeId(id)))
    }

    /// Keeps a live kd-tree over every point of `layer`.
    fn enable_layer_index(&self, layer: &Bound<'_, PyAny>) -> PyResult<()> {
        self.edit(|g| {
            let l = Self::layer(g, layer)?;
            g.enable_layer_index(l)
        })
    }

    /// Drops `layer`'s kd-tree.
    fn disable_layer_index(&self, layer: &Bound<'_, PyAny>) -> PyResult<()> {
        self.edit(|g| {
            let l = Self::layer(g, layer)?;
            g.disable_layer_index(l)
        })
    }

    /// Keeps a live kd-tree over every point in the node's sub-tree.
    fn enable_node_index(&self, id: u64) -> PyResult<()> {
        self.edit(|g| g.enable_node_index(NodeId(id)))
    }

    /// Drops the node's kd-tree.
    fn disable_node_index(&self, id: u64) -> PyResult<()> {
        self.edit(|g| g.disable_node_index(NodeId(id)))
    }

    /// Whether a node with this id exists.
    fn has_node(&self, id: u64) -> PyResult<bool> {
        self.with(|g| g.node(NodeId(id)).is_some())
    }

    /// Total number of nodes.
    #[getter]
    fn node_count(&self) -> PyResult<usize> {
        self.with(|g| g.node_count())
    }

    /// Every layer's name, in ascending id order.
    #[getter]
    fn layers(&self) -> PyResult<Vec<String>> {
        self.with(|g| {
            g.layers()
                .filter_map(|l| g.layer_name(l).map(str::to_owned))
                .collect()
        })
    }

    /// Writes the graph to a `.ygg` snapshot file (atomically: a reader of the old file
    /// keeps its bytes). Raises `FileError` naming the path.
    fn save(&self, path: std::path::PathBuf) -> PyResult<()> {
        self.with(|g| g.save(&path))?.map_err(|e| file_error(&e))
    }

    /// Nodes carrying `label` (in `layer`, or anywhere), ascending: the query of
    /// `Scene.nodes_with_label`, answered by the live graph without taking a snapshot.
    #[pyo3(signature = (label, layer = None))]
    fn nodes_with_label(&self, label: &str, layer: Option<&str>) -> PyResult<Vec<u64>> {
        self.with(|g| {
            let found = query::nodes_with_label(&*g, scope(&*g, layer)?, label);
            Ok(found.into_iter().map(|n| n.0).collect())
        })?
    }

    /// Edges leaving `node` as `(source, target, description)`, ascending by target: the
    /// query of `Scene.edges_from`, answered by the live graph.
    fn edges_from(&self, node: u64) -> PyResult<Vec<(u64, u64, String)>> {
        self.with(|g| {
            if g.node(NodeId(node)).is_none() {
                return Err(unknown_node(node));
            }
            Ok(query::edges_from(&*g, NodeId(node))
                .into_iter()
                .map(|e| (e.source.0, e.target.0, e.description.to_owned()))
                .collect())
        })?
    }

    /// An archived, validated snapshot of the graph as it is now, queried like a file.
    fn snapshot(&self) -> PyResult<Scene> {
        let file = self.with(|g| g.to_snapshot())?;
        Ok(Scene::new(SnapshotSource::File(file)))
    }

    fn __repr__(&self) -> PyResult<String> {
        self.with(|g| {
            format!(
                "<yggdrasil.SceneGraph layers={} nodes={}>",
                g.layers().count(),
                g.node_count()
            )
        })
    }
}
