//! `yggdrasil.Node` and `yggdrasil.Layer`: one node or layer of a `Scene`, read from the
//! snapshot on each access.

use std::sync::Arc;

use numpy::{PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use ygg_dsg::layout::STORED_BOX_FEATURES;
use ygg_store::{FeatureRef, LayerId, NodeId, SceneView};

use crate::convert::feature_to_py;
use crate::errors::{unknown_layer, unknown_node};
use crate::points::{SnapshotOwner, points_array};
use crate::snapshot::SnapshotView;

/// `Layer.spark_dsg_columns`: ids, positions, names, semantic labels, stored boxes,
/// parents and the edges leaving the layer's nodes.
type SparkDsgColumns<'py> = (
    Vec<u64>,
    Bound<'py, PyArray2<f64>>,
    Vec<String>,
    Vec<i64>,
    Vec<Option<[f64; 6]>>,
    Vec<Option<u64>>,
    Vec<(u64, u64)>,
);

/// An axis-aligned box as `((min_x, min_y, min_z), (max_x, max_y, max_z))`.
type BoxTuple = ((f32, f32, f32), (f32, f32, f32));

/// One node of a `Scene` (`scene.node(id)`); keeps the scene's snapshot alive.
#[pyclass(frozen, module = "yggdrasil", name = "Node")]
pub struct Node {
    snapshot: Arc<SnapshotView>,
    id: NodeId,
}

impl Node {
    /// The node `id` of `snapshot` (which must hold it).
    pub fn new(snapshot: Arc<SnapshotView>, id: NodeId) -> Self {
        Node { snapshot, id }
    }

    /// Runs `f` on the scene's view and this node's handle.
    fn with<T>(
        &self,
        f: impl FnOnce(&ygg_store::ArchivedScene<'_>, ygg_store::snapshot::ArchivedNodeRef) -> T,
    ) -> PyResult<T> {
        let view = self.snapshot.view();
        let node = view.node(self.id).ok_or_else(|| unknown_node(self.id.0))?;
        Ok(f(view, node))
    }
}

impl SnapshotOwner for Node {
    fn snapshot(&self) -> &SnapshotView {
        &self.snapshot
    }
}

#[pymethods]
impl Node {
    /// The node id.
    #[getter]
    fn id(&self) -> u64 {
        self.id.0
    }

    /// The name of the node's layer.
    #[getter]
    fn layer(&self) -> PyResult<String> {
        self.with(|v, n| v.layer_name(v.node_layer(n)).unwrap_or_default().to_owned())
    }

    /// The parent's id (`None` if the node is not nested).
    #[getter]
    fn parent(&self) -> PyResult<Option<u64>> {
        self.with(|v, n| v.parent(n).map(|p| p.0))
    }

    /// The children's ids, ascending.
    #[getter]
    fn children(&self) -> PyResult<Vec<u64>> {
        self.with(|v, n| v.children(n).map(|c| c.0).collect())
    }

    /// The node's labels, sorted.
    #[getter]
    fn labels(&self) -> PyResult<Vec<String>> {
        self.with(|v, n| {
            let mut labels: Vec<String> = v.labels(n).map(str::to_owned).collect();
            labels.sort_unstable();
            labels
        })
    }

    /// The node's features as a new dict (str, int, float or bool values).
    #[getter]
    fn features<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        self.with(|v, n| {
            for (k, value) in v.features(n) {
                out.set_item(k, feature_to_py(py, value)?)?;
            }
            Ok::<_, PyErr>(())
        })??;
        Ok(out)
    }

    /// The node's bounding box `((min), (max))` when it keeps one and its sub-tree has a
    /// point, else `None`.
    #[getter]
    fn aabb(&self) -> PyResult<Option<BoxTuple>> {
        self.with(|v, n| {
            v.aabb(n).map(|b| {
                (
                    (b.min[0], b.min[1], b.min[2]),
                    (b.max[0], b.max[1], b.max[2]),
                )
            })
        })
    }

    /// The node's geometry: a read-only `(n, 3)` `float32` numpy array viewing the mapped
    /// snapshot (no copy). It keeps the snapshot alive for as long as it lives.
    #[getter]
    fn points<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        points_array(slf, slf.get().id)
    }

    fn __repr__(&self) -> PyResult<String> {
        let layer = self.layer()?;
        Ok(format!("<yggdrasil.Node {} layer={layer:?}>", self.id.0))
    }
}

/// One layer of a `Scene` (`scene.layer(name)`).
#[pyclass(frozen, module = "yggdrasil", name = "Layer")]
pub struct Layer {
    snapshot: Arc<SnapshotView>,
    id: LayerId,
}

impl Layer {
    /// The layer called `name` of `snapshot`.
    pub fn new(snapshot: Arc<SnapshotView>, name: &str) -> PyResult<Self> {
        let id = snapshot
            .view()
            .layer_by_name(name)
            .ok_or_else(|| unknown_layer(name))?;
        Ok(Layer { snapshot, id })
    }

    fn names(v: &ygg_store::ArchivedScene<'_>, layers: Vec<LayerId>) -> Vec<String> {
        layers
            .into_iter()
            .filter_map(|l| v.layer_name(l).map(str::to_owned))
            .collect()
    }
}

#[pymethods]
impl Layer {
    /// The layer id.
    #[getter]
    fn id(&self) -> u32 {
        self.id.0
    }

    /// The layer name.
    #[getter]
    fn name(&self) -> String {
        let v = self.snapshot.view();
        v.layer_name(self.id).unwrap_or_default().to_owned()
    }

    /// The layer's generation (changes whenever its content changes).
    #[getter]
    fn generation(&self) -> u64 {
        self.snapshot.view().layer_generation(self.id).unwrap_or(0)
    }

    /// The ids of the layer's nodes, ascending.
    #[getter]
    fn nodes(&self) -> Vec<u64> {
        let v = self.snapshot.view();
        let mut ids: Vec<u64> = v.layer_nodes(self.id).map(|n| v.node_id(n).0).collect();
        ids.sort_unstable();
        ids
    }

    /// Names of the layers this layer encompasses (its DAG children).
    #[getter]
    fn children(&self) -> Vec<String> {
        let v = self.snapshot.view();
        Self::names(v, v.layer_children(self.id))
    }

    /// Names of the layers encompassing this layer (its DAG parents).
    #[getter]
    fn parents(&self) -> Vec<String> {
        let v = self.snapshot.view();
        Self::names(v, v.layer_parents(self.id))
    }

    fn __len__(&self) -> usize {
        self.snapshot.view().layer_len(self.id)
    }

    /// The layer as the columns `yggdrasil.dsg` builds its nodes from, in one pass, rows
    /// ascending by id: `(ids, positions, names, semantic_labels, boxes, parents, edges)`.
    /// `positions` is an `(n, 3)` `float64` array (the `position_x/y/z` features, else the
    /// first point, else zeros); `names` `""` and `semantic_labels` `2**32 - 1` where the
    /// node has none; `boxes` the six stored Spark-DSG box features or `None`; `parents`
    /// the parent id or `None`; `edges` every `(source, target)` leaving the layer's nodes.
    fn spark_dsg_columns<'py>(&self, py: Python<'py>) -> SparkDsgColumns<'py> {
        let v = self.snapshot.view();
        let mut nodes: Vec<_> = v
            .layer_nodes(self.id)
            .map(|n| (v.node_id(n).0, n))
            .collect();
        nodes.sort_unstable_by_key(|&(id, _)| id);
        let n = nodes.len();
        let (mut ids, mut positions, mut names) = (
            Vec::with_capacity(n),
            Vec::with_capacity(n * 3),
            Vec::with_capacity(n),
        );
        let (mut labels, mut boxes, mut parents) = (
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
        );
        let mut edges = Vec::new();
        for (id, node) in nodes {
            ids.push(id);
            let (mut xyz, mut has_xyz) = ([0.0f64; 3], 0);
            let (mut name, mut label) = (String::new(), i64::from(u32::MAX));
            let (mut bbox, mut has_box) = ([0.0f64; 6], 0);
            for (key, value) in v.features(node) {
                let number = match value {
                    FeatureRef::Float(x) => x,
                    FeatureRef::Int(i) => i as f64,
                    FeatureRef::Str(s) => {
                        if key == "name" {
                            name = s.to_owned();
                        }
                        continue;
                    }
                    FeatureRef::Bool(_) => continue,
                };
                match key {
                    "semantic_label" => label = number as i64,
                    "position_x" | "position_y" | "position_z" => {
                        xyz[usize::from(key.as_bytes()[9] - b'x')] = number;
                        has_xyz += 1;
                    }
                    _ => {
                        if let Some(i) = STORED_BOX_FEATURES.iter().position(|k| *k == key) {
                            bbox[i] = number;
                            has_box += 1;
                        }
                    }
                }
            }
            if has_xyz < 3 {
                let pts = v.points(node);
                xyz = pts.first().map_or([0.0; 3], |p| p.map(f64::from));
            }
            positions.extend_from_slice(&xyz);
            names.push(name);
            labels.push(label);
            boxes.push((has_box == 6).then_some(bbox));
            parents.push(v.parent(node).map(|p| p.0));
            edges.extend(v.out_edges(node).map(|e| (e.source.0, e.target.0)));
        }
        let positions = numpy::PyArray1::from_vec(py, positions)
            .reshape([n, 3])
            .expect("3 numbers per node");
        (ids, positions, names, labels, boxes, parents, edges)
    }

    fn __repr__(&self) -> String {
        format!(
            "<yggdrasil.Layer {:?} nodes={}>",
            self.name(),
            self.__len__()
        )
    }
}
