//! Indexes a reader builds itself from any [`SceneView`], for scopes the writer does
//! not index: [`build_layer_index`], [`build_subtree_index`], and [`IndexCache`], which
//! keeps them across generations for layers that did not change.

use super::archived::{KdIndex, build_tree};
use crate::query::visit_subtree;
use crate::{LayerId, NodeId, SceneView};
use rustc_hash::FxHashMap;

/// A kd-tree index over every point of `layer` in `view`, built by a reader for a layer
/// the writer does not index.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, index::{build_layer_index, SpatialIndex}};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let mesh = g.add_layer("mesh")?;
/// g.add_node(NodeId(1), mesh)?;
/// g.set_geometry(NodeId(1), vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])?;
/// let snapshot = g.to_snapshot();
/// let index = build_layer_index(&snapshot.view(), mesh);
/// assert_eq!(index.len(), 2);
/// # Ok(()) }
/// ```
pub fn build_layer_index<V: SceneView>(view: &V, layer: LayerId) -> KdIndex {
    let mut nodes: Vec<(NodeId, V::NodeRef<'_>)> = view
        .layer_nodes(layer)
        .map(|n| (view.node_id(n), n))
        .collect();
    nodes.sort_unstable_by_key(|n| n.0);
    index_over(view, nodes)
}

/// A kd-tree index over every point in the sub-tree of `root` in `view` (empty for an
/// unknown root), built by a reader for a sub-tree the writer does not index.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, index::{build_subtree_index, SpatialIndex}};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let (rooms, objects) = (g.add_layer("rooms")?, g.add_layer("objects")?);
/// g.add_layer_edge(rooms, objects)?;
/// g.add_node(NodeId(1), rooms)?;
/// g.add_node(NodeId(2), objects)?;
/// g.set_geometry(NodeId(2), vec![[1.0, 2.0, 0.0]])?;
/// g.nest(NodeId(1), NodeId(2))?;
/// let index = build_subtree_index(&g.to_snapshot().view(), NodeId(1));
/// assert_eq!(index.len(), 1);
/// # Ok(()) }
/// ```
pub fn build_subtree_index<V: SceneView>(view: &V, root: NodeId) -> KdIndex {
    let mut members = Vec::new();
    visit_subtree(view, root, |id| members.push(id));
    members.sort_unstable();
    let nodes: Vec<_> = members
        .into_iter()
        .filter_map(|id| Some((id, view.node(id)?)))
        .collect();
    index_over(view, nodes)
}

/// An index over the points of `nodes` (ascending by id): items are positions in the
/// id table of the nodes that have points.
fn index_over<'v, V: SceneView>(view: &'v V, nodes: Vec<(NodeId, V::NodeRef<'v>)>) -> KdIndex {
    let mut ids = Vec::new();
    let mut entries = Vec::new();
    for (id, n) in nodes {
        let points = view.points(n);
        if !points.is_empty() {
            let item = ids.len() as u32;
            ids.push(id);
            entries.extend(points.iter().map(|p| (item, *p)));
        }
    }
    KdIndex::new(&build_tree(&entries), ids)
}

/// Indexes a reader built itself, kept for as long as the layers they cover are
/// unchanged.
///
/// A layer index is reused while its layer's generation is unchanged; a sub-tree index
/// while the generations of the root's layer and of every layer below it in the layer
/// DAG are unchanged. Generations come from [`SceneView::layer_generation`], so the same
/// cache serves successive snapshots of one scene.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, index::{IndexCache, SpatialIndex}};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let (mesh, poses) = (g.add_layer("mesh")?, g.add_layer("poses")?);
/// g.add_node(NodeId(1), mesh)?;
/// g.set_geometry(NodeId(1), vec![[0.0, 0.0, 0.0]])?;
/// let mut cache = IndexCache::new();
/// assert_eq!(cache.layer(&g.to_snapshot().view(), mesh).len(), 1);
/// g.add_node(NodeId(2), poses)?; // another layer changes: the mesh index is kept
/// assert_eq!(cache.layer(&g.to_snapshot().view(), mesh).len(), 1);
/// assert_eq!(cache.builds(), 1);
/// # Ok(()) }
/// ```
#[derive(Debug, Default)]
pub struct IndexCache {
    layers: FxHashMap<LayerId, (u64, KdIndex)>,
    subtrees: FxHashMap<NodeId, (Vec<(LayerId, u64)>, KdIndex)>,
    builds: u64,
}

impl IndexCache {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// The index of `layer` in `view`, rebuilt only if the layer changed since it was
    /// built (or was never built).
    pub fn layer<V: SceneView>(&mut self, view: &V, layer: LayerId) -> &KdIndex {
        let generation = view.layer_generation(layer).unwrap_or(u64::MAX);
        let fresh = self
            .layers
            .get(&layer)
            .is_some_and(|(g, _)| *g == generation);
        if !fresh {
            self.builds += 1;
            self.layers
                .insert(layer, (generation, build_layer_index(view, layer)));
        }
        &self.layers[&layer].1
    }

    /// The index of `root`'s sub-tree in `view`, rebuilt only if a layer it may cover
    /// changed since it was built.
    pub fn subtree<V: SceneView>(&mut self, view: &V, root: NodeId) -> &KdIndex {
        let stamp = subtree_stamp(view, root);
        let fresh = self.subtrees.get(&root).is_some_and(|(s, _)| *s == stamp);
        if !fresh {
            self.builds += 1;
            self.subtrees
                .insert(root, (stamp, build_subtree_index(view, root)));
        }
        &self.subtrees[&root].1
    }

    /// How many indexes this cache has built so far.
    pub fn builds(&self) -> u64 {
        self.builds
    }
}

/// The generations of the root's layer and of every layer below it in the DAG.
fn subtree_stamp<V: SceneView>(view: &V, root: NodeId) -> Vec<(LayerId, u64)> {
    let Some(n) = view.node(root) else {
        return Vec::new();
    };
    let mut stack = vec![view.node_layer(n)];
    let mut stamp = Vec::new();
    while let Some(l) = stack.pop() {
        if stamp.iter().any(|(x, _)| *x == l) {
            continue;
        }
        stamp.push((l, view.layer_generation(l).unwrap_or(u64::MAX)));
        stack.extend(view.layer_children(l));
    }
    stamp.sort_unstable();
    stamp
}
