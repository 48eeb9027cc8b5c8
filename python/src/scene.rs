//! `yggdrasil.Scene`: a validated snapshot queried in place, with every query of the
//! paper (each a call of the one implementation in `ygg_store::query`).

use std::sync::Arc;

use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use ygg_dsg::layout;
use ygg_dsg::objects::cone_view;
use ygg_store::query;
use ygg_store::{EdgeRef, FeatureRef, FeatureValue, NodeId, SceneView};

use crate::batch;
use crate::convert::{self, direction, point, points, scope};
use crate::errors::{query_error, unknown_node};
use crate::graph_home::PySceneGraph;
use crate::node::{Layer, Node};
use crate::objects::ObjectQueries;
use crate::snapshot::{ObjectCatalog, SnapshotSource, SnapshotView};
use crate::whereabouts::{AgentPose, RoomScope};

/// `nearest_nodes_many`'s answer: ids (a masked `uint64` array, masked for none) and
/// distances (`float32`, `inf` for none).
type NearestArrays<'py> = (Bound<'py, PyAny>, Bound<'py, PyArray1<f32>>);

/// An edge as Python sees it: `(source, target, description)`.
type EdgeTuple = (u64, u64, String);

fn edge_tuple(e: EdgeRef<'_>) -> EdgeTuple {
    (e.source.0, e.target.0, e.description.to_owned())
}

fn ids(nodes: Vec<NodeId>) -> Vec<u64> {
    nodes.into_iter().map(|n| n.0).collect()
}

/// A consistent, validated snapshot of a scene graph (from a `.ygg` file, a live scene, or
/// `SceneGraph.snapshot()`), queried in place without copying.
///
/// Node ids are Python ints (u64). Node sets come back ascending; ranked results break
/// distance ties by the smaller id. A `Scene` never changes: a reader hands out a new one
/// per snapshot. Everything taken from it (nodes, point arrays, object queries) keeps its
/// bytes alive.
#[pyclass(frozen, module = "yggdrasil", name = "Scene")]
pub struct Scene {
    snapshot: Arc<SnapshotView>,
    objects: Arc<ObjectCatalog>,
}

impl Scene {
    /// A scene over a validated snapshot.
    pub fn new(source: SnapshotSource) -> Self {
        let snapshot = SnapshotView::open(source);
        let objects = ObjectCatalog::whole(Arc::clone(&snapshot));
        Scene { snapshot, objects }
    }

    /// The snapshot and its view.
    pub fn snapshot(&self) -> &Arc<SnapshotView> {
        &self.snapshot
    }

    fn node_ref(&self, id: u64) -> PyResult<()> {
        self.snapshot
            .view()
            .node(NodeId(id))
            .map(|_| ())
            .ok_or_else(|| unknown_node(id))
    }
}

#[pymethods]
impl Scene {
    /// The snapshot generation (a writer's publish counter; 0 for a file).
    #[getter]
    fn generation(&self) -> u64 {
        self.snapshot.generation()
    }

    /// Every layer's name, in ascending layer id order.
    #[getter]
    fn layers(&self) -> Vec<String> {
        let v = self.snapshot.view();
        v.layers()
            .filter_map(|l| v.layer_name(l).map(str::to_owned))
            .collect()
    }

    /// The layer called `name`.
    ///
    /// Raises `QueryError` if there is none.
    fn layer(&self, name: &str) -> PyResult<Layer> {
        Layer::new(Arc::clone(&self.snapshot), name)
    }

    /// Total number of nodes.
    #[getter]
    fn node_count(&self) -> usize {
        self.snapshot.view().node_count()
    }

    /// Whether a node with this id exists.
    fn has_node(&self, id: u64) -> bool {
        self.snapshot.view().node(NodeId(id)).is_some()
    }

    /// The node with this id.
    ///
    /// Raises `QueryError` if there is none.
    fn node(&self, id: u64) -> PyResult<Node> {
        self.node_ref(id)?;
        Ok(Node::new(Arc::clone(&self.snapshot), NodeId(id)))
    }

    /// The object queries of `ygg query` over the whole scene (`scene.objects.nearest(p)`).
    #[getter]
    fn objects(&self) -> ObjectQueries {
        ObjectQueries::new(Arc::clone(&self.objects))
    }

    /// The object queries restricted to the objects in `root`'s sub-tree (a room, say).
    ///
    /// Raises `QueryError` if `root` is not a node of the scene.
    fn objects_in(&self, root: u64) -> PyResult<ObjectQueries> {
        self.node_ref(root)?;
        Ok(ObjectQueries::new(ObjectCatalog::subtree(
            Arc::clone(&self.snapshot),
            NodeId(root),
        )))
    }

    /// Answers one query of the `ygg query` contract, given as a dict (read
    /// directly, no JSON encoding) or a JSON string, exactly as the CLI answers the same
    /// line: `{"ids": [...]}`.
    ///
    /// `{"op": "nearest_object", "point": [x, y, z]}`,
    /// `{"op": "objects_within", "point": [x, y, z], "radius": r}`,
    /// `{"op": "visible_objects", "eye": [..], "dir": [..], "half_angle_deg": a, "range": m}`,
    /// `{"op": "objects_with_label", "label": "light"}`.
    ///
    /// Raises `QueryError` with the CLI's message for a malformed query.
    fn query<'py>(&self, py: Python<'py>, q: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyDict>> {
        let query = convert::object_query(q)?;
        let answer = ObjectQueries::new(Arc::clone(&self.objects)).answer(&query)?;
        let out = PyDict::new(py);
        out.set_item("ids", answer)?;
        Ok(out)
    }

    /// The at most `m` nodes closest to `point` as `(id, distance)` pairs, nearest first
    /// (a node's distance is its closest point's), over the whole graph or one `layer`.
    #[pyo3(signature = (point, m = 1, layer = None))]
    fn nearest_nodes(
        &self,
        point: &Bound<'_, PyAny>,
        m: usize,
        layer: Option<&str>,
    ) -> PyResult<Vec<(u64, f32)>> {
        let v = self.snapshot.view();
        let c = convert::point(point, "point")?;
        let found = query::nearest_nodes(v, scope(v, layer)?, c, m).map_err(|e| query_error(&e))?;
        Ok(found.into_iter().map(|(n, d)| (n.0, d)).collect())
    }

    /// Nodes with a point at distance `<= radius` from `point`, ascending.
    #[pyo3(signature = (point, radius, layer = None))]
    fn nodes_within_radius(
        &self,
        point: &Bound<'_, PyAny>,
        radius: f32,
        layer: Option<&str>,
    ) -> PyResult<Vec<u64>> {
        let v = self.snapshot.view();
        let c = convert::point(point, "point")?;
        query::nodes_within_radius(v, scope(v, layer)?, c, radius)
            .map(ids)
            .map_err(|e| query_error(&e))
    }

    /// Like `nearest_nodes`, restricted to `root`'s sub-tree.
    #[pyo3(signature = (root, point, m = 1))]
    fn nearest_in_subtree(
        &self,
        root: u64,
        point: &Bound<'_, PyAny>,
        m: usize,
    ) -> PyResult<Vec<(u64, f32)>> {
        self.node_ref(root)?;
        let c = convert::point(point, "point")?;
        let found = query::nearest_in_subtree(self.snapshot.view(), NodeId(root), c, m)
            .map_err(|e| query_error(&e))?;
        Ok(found.into_iter().map(|(n, d)| (n.0, d)).collect())
    }

    /// Nodes in `root`'s sub-tree with a point inside the view cone (apex `eye`,
    /// direction `dir`, `half_angle_deg` in degrees in `[0, 180]` as everywhere in the
    /// package, `range` in metres; bounds inclusive).
    fn visible(
        &self,
        root: u64,
        eye: &Bound<'_, PyAny>,
        dir: &Bound<'_, PyAny>,
        half_angle_deg: f32,
        range: f32,
    ) -> PyResult<Vec<u64>> {
        self.node_ref(root)?;
        let cone = cone_view(
            point(eye, "eye")?,
            point(dir, "dir")?,
            half_angle_deg,
            range,
        )
        .map_err(|e| query_error(&e))?;
        query::visible(self.snapshot.view(), NodeId(root), &cone)
            .map(ids)
            .map_err(|e| query_error(&e))
    }

    /// Nodes carrying `label`, ascending.
    #[pyo3(signature = (label, layer = None))]
    fn nodes_with_label(&self, label: &str, layer: Option<&str>) -> PyResult<Vec<u64>> {
        let v = self.snapshot.view();
        Ok(ids(query::nodes_with_label(v, scope(v, layer)?, label)))
    }

    /// Nodes whose features match every `key: value` of `features`, ascending.
    #[pyo3(signature = (features, layer = None))]
    fn nodes_matching(
        &self,
        features: &Bound<'_, PyDict>,
        layer: Option<&str>,
    ) -> PyResult<Vec<u64>> {
        let v = self.snapshot.view();
        let mut owned: Vec<(String, FeatureValue)> = Vec::with_capacity(features.len());
        for (k, value) in features.iter() {
            let key: String = k.extract().map_err(|_| {
                crate::errors::QueryError::new_err(format!(
                    "features: keys must be str, got {}",
                    convert::describe(&k)
                ))
            })?;
            let what = format!("features[{key:?}]");
            owned.push((key, convert::feature_from_py(&value, &what)?));
        }
        let pairs: Vec<(&str, FeatureRef<'_>)> = owned
            .iter()
            .map(|(k, v)| (k.as_str(), v.as_ref()))
            .collect();
        Ok(ids(query::nodes_matching(v, scope(v, layer)?, &pairs)))
    }

    /// Nodes carrying every feature key of `keys`, ascending.
    #[pyo3(signature = (keys, layer = None))]
    fn nodes_having(&self, keys: Vec<String>, layer: Option<&str>) -> PyResult<Vec<u64>> {
        let v = self.snapshot.view();
        let keys: Vec<&str> = keys.iter().map(String::as_str).collect();
        Ok(ids(query::nodes_having(v, scope(v, layer)?, &keys)))
    }

    /// Edges leaving `node` as `(source, target, description)`, ascending by target.
    fn edges_from(&self, node: u64) -> PyResult<Vec<EdgeTuple>> {
        self.node_ref(node)?;
        Ok(query::edges_from(self.snapshot.view(), NodeId(node))
            .into_iter()
            .map(edge_tuple)
            .collect())
    }

    /// Edges entering `node` as `(source, target, description)`, ascending by source.
    fn edges_to(&self, node: u64) -> PyResult<Vec<EdgeTuple>> {
        self.node_ref(node)?;
        Ok(query::edges_to(self.snapshot.view(), NodeId(node))
            .into_iter()
            .map(edge_tuple)
            .collect())
    }

    /// Edges whose description is `description`, as `(source, target, description)`.
    #[pyo3(signature = (description, layer = None))]
    fn edges_matching(&self, description: &str, layer: Option<&str>) -> PyResult<Vec<EdgeTuple>> {
        let v = self.snapshot.view();
        Ok(query::edges_matching(v, scope(v, layer)?, description)
            .into_iter()
            .map(edge_tuple)
            .collect())
    }

    /// The node's parent (`None` if it is not nested).
    fn parent(&self, node: u64) -> PyResult<Option<u64>> {
        self.node_ref(node)?;
        Ok(query::parent(self.snapshot.view(), NodeId(node)).map(|p| p.0))
    }

    /// The node's children, ascending.
    fn children(&self, node: u64) -> PyResult<Vec<u64>> {
        self.node_ref(node)?;
        Ok(ids(query::children(self.snapshot.view(), NodeId(node))))
    }

    /// `root` and every node nested below it, transitively, ascending.
    fn subtree(&self, root: u64) -> PyResult<Vec<u64>> {
        self.node_ref(root)?;
        Ok(ids(query::subtree(self.snapshot.view(), NodeId(root))))
    }

    /// The sub-scene graph over `nodes`: those nodes, the edges and nestings among them,
    /// and every layer of the scene, as a new editable `SceneGraph`.
    fn subgraph(&self, nodes: Vec<u64>) -> PySceneGraph {
        let nodes: Vec<NodeId> = nodes.into_iter().map(NodeId).collect();
        PySceneGraph::from_graph(query::subgraph(self.snapshot.view(), &nodes))
    }

    /// Breadth-first order of the nodes reachable from `start` over its layer's edges
    /// (`direction`: `"out"` along edges, `"both"` undirected); neighbours ascending.
    #[pyo3(signature = (start, direction = "out"))]
    fn bfs(&self, start: u64, direction: &str) -> PyResult<Vec<u64>> {
        self.node_ref(start)?;
        let dir = convert::direction(direction)?;
        Ok(ids(query::bfs(self.snapshot.view(), NodeId(start), dir)))
    }

    /// Depth-first pre-order from `start` (as `bfs`).
    #[pyo3(signature = (start, direction = "out"))]
    fn dfs(&self, start: u64, direction: &str) -> PyResult<Vec<u64>> {
        self.node_ref(start)?;
        let dir = convert::direction(direction)?;
        Ok(ids(query::dfs(self.snapshot.view(), NodeId(start), dir)))
    }

    /// A shortest path (fewest edges) from `source` to `target` over their layer's edges,
    /// both ends included; `None` if `target` is unreachable.
    #[pyo3(signature = (source, target, direction = "out"))]
    fn shortest_path(
        &self,
        source: u64,
        target: u64,
        direction: &str,
    ) -> PyResult<Option<Vec<u64>>> {
        self.node_ref(source)?;
        self.node_ref(target)?;
        let dir = self::direction(direction)?;
        Ok(
            query::shortest_path(self.snapshot.view(), NodeId(source), NodeId(target), dir)
                .map(ids),
        )
    }

    /// `nearest_nodes(p, 1, layer)` for each row of `points` (an `(n, 3)` array), without
    /// the GIL: `(ids, distances)` of length n, the ids a `numpy.ma` masked `uint64`
    /// array (node ids use all 64 bits, so no id value can mean "none"), masked where the
    /// scope holds no point, and the distances `float32`, `inf` there.
    #[pyo3(signature = (points, layer = None))]
    fn nearest_nodes_many<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
        layer: Option<&str>,
    ) -> PyResult<NearestArrays<'py>> {
        let queries = self::points(points, "points")?;
        let scope = scope(self.snapshot.view(), layer)?;
        let snapshot = Arc::clone(&self.snapshot);
        let answers = py.detach(move || {
            batch::map(&queries, |c| {
                query::nearest_nodes(snapshot.view(), scope, *c, 1).map(|found| {
                    found
                        .first()
                        .map_or((None, f32::INFINITY), |&(n, d)| (Some(n), d))
                })
            })
        });
        let answers = answers.map_err(|e| query_error(&e))?;
        let (ids, dists): (Vec<Option<NodeId>>, Vec<f32>) = answers.into_iter().unzip();
        Ok((batch::masked_ids(py, &ids)?, dists.into_pyarray(py)))
    }

    /// The newest agent pose (the `AGENTS` layer's largest id with a point) and the pose
    /// before it; `None` when the scene has no pose yet.
    fn newest_pose(&self) -> Option<AgentPose> {
        layout::newest_pose(self.snapshot.view()).map(AgentPose::from)
    }

    /// The room (a node of the `ROOMS` layer) whose box holds `point` in x and y (the
    /// smallest id when several do), or `None`.
    fn room_of(&self, point: &Bound<'_, PyAny>) -> PyResult<Option<u64>> {
        let p = convert::point(point, "point")?;
        Ok(layout::room_of(self.snapshot.view(), &p).map(|r| r.0))
    }

    /// Where `room`'s objects live in a per-room layout (chocolate, mint, saffron): its
    /// mesh layer and claimed group node (`scene.objects_in(scope.claimed)` answers over
    /// the room's objects); `None` in another layout or for an unknown room.
    fn room_scope(&self, room: u64) -> Option<RoomScope> {
        let v = self.snapshot.view();
        layout::room_scope(v, NodeId(room)).map(|s| RoomScope::new(v, s))
    }

    /// The distinct parents of `nodes` (the objects owning mesh nodes), ascending; nodes
    /// without a parent or not in the scene are left out.
    fn owners(&self, nodes: Vec<u64>) -> Vec<u64> {
        ids(layout::owners(
            self.snapshot.view(),
            nodes.into_iter().map(NodeId),
        ))
    }

    fn __repr__(&self) -> String {
        let v = self.snapshot.view();
        format!(
            "<yggdrasil.Scene generation={} layers={} nodes={}>",
            self.snapshot.generation(),
            v.layers().count(),
            v.node_count()
        )
    }
}
