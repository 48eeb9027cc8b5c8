//! [`SceneView`]: the one read interface that every query is written against.
//!
//! | backend | type | how it answers |
//! |---|---|---|
//! | live graph | [`crate::SceneGraph`] | hash map of nodes, per-layer posting sets |
//! | archived snapshot (file or shared memory) | [`crate::ArchivedScene`] | columns of validated rkyv bytes, zero-copy |
//!
//! Every query in [`crate::query`] is generic over `V: SceneView`, so both backends run
//! the same code and give the same answers (property-tested).
//!
//! Spatial indexes are reached through the view too: [`SceneView::layer_index`] and
//! [`SceneView::node_index`] return a [`SpatialIndex`] (a [`crate::index::LiveIndex`]
//! on the live graph, a zero-copy [`crate::index::ArchivedIndex`] on a snapshot), and the
//! spatial queries use it when present and scan otherwise.

use crate::index::SpatialIndex;
use crate::{Aabb, FeatureRef, LayerId, NodeId, Point, Points};

/// A directed edge as a view reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct EdgeRef<'a> {
    /// Source node.
    pub source: NodeId,
    /// Target node.
    pub target: NodeId,
    /// The edge's description.
    pub description: &'a str,
}

/// Read-only access to a scene graph, live or archived.
///
/// Nodes are reached through a cheap handle ([`SceneView::NodeRef`]) so a query looks a
/// node up once and then reads its columns directly. A handle is valid for as long as
/// the borrow of the view it came from.
pub trait SceneView {
    /// A handle to one node of this view.
    type NodeRef<'a>: Copy
    where
        Self: 'a;

    /// Every layer, in ascending id order.
    fn layers(&self) -> impl Iterator<Item = LayerId> + '_;
    /// The name of a layer.
    fn layer_name(&self, layer: LayerId) -> Option<&str>;
    /// The layer with this name.
    fn layer_by_name(&self, name: &str) -> Option<LayerId>;
    /// Layers this layer encompasses (DAG children), ascending.
    fn layer_children(&self, layer: LayerId) -> Vec<LayerId>;
    /// Layers encompassing this layer (DAG parents), ascending.
    fn layer_parents(&self, layer: LayerId) -> Vec<LayerId>;
    /// Number of nodes in a layer (0 for an unknown layer).
    fn layer_len(&self, layer: LayerId) -> usize;
    /// The nodes of a layer, in no particular order.
    fn layer_nodes(&self, layer: LayerId) -> impl Iterator<Item = Self::NodeRef<'_>> + '_;

    /// The node with this id.
    fn node(&self, id: NodeId) -> Option<Self::NodeRef<'_>>;
    /// A node's id.
    fn node_id<'a>(&'a self, node: Self::NodeRef<'a>) -> NodeId;
    /// A node's layer.
    fn node_layer<'a>(&'a self, node: Self::NodeRef<'a>) -> LayerId;
    /// A node's geometry (empty if none).
    fn points<'a>(&'a self, node: Self::NodeRef<'a>) -> Points<'a>;
    /// A node's parent.
    fn parent<'a>(&'a self, node: Self::NodeRef<'a>) -> Option<NodeId>;
    /// A node's children, ascending by id.
    fn children<'a>(
        &'a self,
        node: Self::NodeRef<'a>,
    ) -> impl DoubleEndedIterator<Item = NodeId> + ExactSizeIterator + 'a;
    /// A node's bounding box, if enabled and its sub-tree has a point.
    fn aabb<'a>(&'a self, node: Self::NodeRef<'a>) -> Option<Aabb>;
    /// Edges leaving a node, ascending by target id.
    fn out_edges<'a>(&'a self, node: Self::NodeRef<'a>) -> impl Iterator<Item = EdgeRef<'a>> + 'a;
    /// Edges entering a node, ascending by source id.
    fn in_edges<'a>(&'a self, node: Self::NodeRef<'a>) -> impl Iterator<Item = EdgeRef<'a>> + 'a;
    /// A node's labels, in no particular order.
    fn labels<'a>(&'a self, node: Self::NodeRef<'a>) -> impl Iterator<Item = &'a str> + 'a;
    /// A node's features, in no particular order.
    fn features<'a>(
        &'a self,
        node: Self::NodeRef<'a>,
    ) -> impl Iterator<Item = (&'a str, FeatureRef<'a>)> + 'a;

    /// Layers holding at least one node with this label (inverted index; O(1) when absent).
    fn layers_with_label(&self, label: &str) -> impl Iterator<Item = LayerId>;
    /// Layers holding at least one node with this feature key.
    fn layers_with_key(&self, key: &str) -> impl Iterator<Item = LayerId>;
    /// Nodes of `layer` carrying `label` (inverted index).
    fn nodes_with_label<'a>(
        &'a self,
        layer: LayerId,
        label: &str,
    ) -> impl Iterator<Item = Self::NodeRef<'a>>;
    /// Nodes of `layer` carrying feature `key` (inverted index).
    fn nodes_with_key<'a>(
        &'a self,
        layer: LayerId,
        key: &str,
    ) -> impl Iterator<Item = Self::NodeRef<'a>>;

    /// A node's feature `key`, if present.
    fn feature<'a>(&'a self, node: Self::NodeRef<'a>, key: &str) -> Option<FeatureRef<'a>> {
        self.features(node).find(|(k, _)| *k == key).map(|(_, v)| v)
    }
    /// Whether a node carries `label`.
    fn has_label<'a>(&'a self, node: Self::NodeRef<'a>, label: &str) -> bool {
        self.labels(node).any(|l| l == label)
    }
    /// Total number of nodes.
    fn node_count(&self) -> usize {
        self.layers().map(|l| self.layer_len(l)).sum()
    }

    /// A layer's generation: it changes whenever the layer's content changes (`None` for
    /// an unknown layer). Readers key the indexes they build on it.
    fn layer_generation(&self, layer: LayerId) -> Option<u64>;

    /// The index over every point of `layer`, if this view keeps one.
    fn layer_index(&self, layer: LayerId) -> Option<impl SpatialIndex + '_> {
        let _ = layer;
        None::<NoIndex>
    }

    /// The index over every point in `node`'s sub-tree, if this view keeps one (a
    /// published snapshot keeps none for a sub-tree of few points: queries walk it).
    fn node_index(&self, node: NodeId) -> Option<impl SpatialIndex + '_> {
        let _ = node;
        None::<NoIndex>
    }

    /// Whether the graph indexes `node`'s sub-tree, whether or not this view carries the
    /// tree ([`SceneView::node_index`] may give none for a small sub-tree).
    fn has_node_index(&self, node: NodeId) -> bool {
        self.node_index(node).is_some()
    }
}

/// The index type of views that keep no index (uninhabited).
enum NoIndex {}

impl SpatialIndex for NoIndex {
    fn len(&self) -> usize {
        match *self {}
    }

    fn node_of(&self, _item: u32) -> Option<NodeId> {
        match *self {}
    }

    fn nearest_visit<F: FnMut(f32, u32) -> f32>(&self, _c: &Point, _f: F) {
        match *self {}
    }

    fn points_within<F: FnMut(f32, u32, &Point)>(&self, _c: &Point, _r2: f32, _f: F) {
        match *self {}
    }

    fn memory_bytes(&self) -> usize {
        match *self {}
    }
}

/// A shared reference to a view is a view (so a query target can hold `&SceneGraph`).
impl<V: SceneView + ?Sized> SceneView for &V {
    type NodeRef<'a>
        = V::NodeRef<'a>
    where
        Self: 'a;

    fn layers(&self) -> impl Iterator<Item = LayerId> + '_ {
        (**self).layers()
    }
    fn layer_name(&self, layer: LayerId) -> Option<&str> {
        (**self).layer_name(layer)
    }
    fn layer_by_name(&self, name: &str) -> Option<LayerId> {
        (**self).layer_by_name(name)
    }
    fn layer_children(&self, layer: LayerId) -> Vec<LayerId> {
        (**self).layer_children(layer)
    }
    fn layer_parents(&self, layer: LayerId) -> Vec<LayerId> {
        (**self).layer_parents(layer)
    }
    fn layer_len(&self, layer: LayerId) -> usize {
        (**self).layer_len(layer)
    }
    fn layer_nodes(&self, layer: LayerId) -> impl Iterator<Item = Self::NodeRef<'_>> + '_ {
        (**self).layer_nodes(layer)
    }
    fn node(&self, id: NodeId) -> Option<Self::NodeRef<'_>> {
        (**self).node(id)
    }
    fn node_id<'a>(&'a self, node: Self::NodeRef<'a>) -> NodeId {
        (**self).node_id(node)
    }
    fn node_layer<'a>(&'a self, node: Self::NodeRef<'a>) -> LayerId {
        (**self).node_layer(node)
    }
    fn points<'a>(&'a self, node: Self::NodeRef<'a>) -> Points<'a> {
        (**self).points(node)
    }
    fn parent<'a>(&'a self, node: Self::NodeRef<'a>) -> Option<NodeId> {
        (**self).parent(node)
    }
    fn children<'a>(
        &'a self,
        node: Self::NodeRef<'a>,
    ) -> impl DoubleEndedIterator<Item = NodeId> + ExactSizeIterator + 'a {
        (**self).children(node)
    }
    fn aabb<'a>(&'a self, node: Self::NodeRef<'a>) -> Option<Aabb> {
        (**self).aabb(node)
    }
    fn out_edges<'a>(&'a self, node: Self::NodeRef<'a>) -> impl Iterator<Item = EdgeRef<'a>> + 'a {
        (**self).out_edges(node)
    }
    fn in_edges<'a>(&'a self, node: Self::NodeRef<'a>) -> impl Iterator<Item = EdgeRef<'a>> + 'a {
        (**self).in_edges(node)
    }
    fn labels<'a>(&'a self, node: Self::NodeRef<'a>) -> impl Iterator<Item = &'a str> + 'a {
        (**self).labels(node)
    }
    fn features<'a>(
        &'a self,
        node: Self::NodeRef<'a>,
    ) -> impl Iterator<Item = (&'a str, FeatureRef<'a>)> + 'a {
        (**self).features(node)
    }
    fn layers_with_label(&self, label: &str) -> impl Iterator<Item = LayerId> {
        (**self).layers_with_label(label)
    }
    fn layers_with_key(&self, key: &str) -> impl Iterator<Item = LayerId> {
        (**self).layers_with_key(key)
    }
    fn nodes_with_label<'a>(
        &'a self,
        layer: LayerId,
        label: &str,
    ) -> impl Iterator<Item = Self::NodeRef<'a>> {
        (**self).nodes_with_label(layer, label)
    }
    fn nodes_with_key<'a>(
        &'a self,
        layer: LayerId,
        key: &str,
    ) -> impl Iterator<Item = Self::NodeRef<'a>> {
        (**self).nodes_with_key(layer, key)
    }
    fn feature<'a>(&'a self, node: Self::NodeRef<'a>, key: &str) -> Option<FeatureRef<'a>> {
        (**self).feature(node, key)
    }
    fn has_label<'a>(&'a self, node: Self::NodeRef<'a>, label: &str) -> bool {
        (**self).has_label(node, label)
    }
    fn node_count(&self) -> usize {
        (**self).node_count()
    }
    fn layer_generation(&self, layer: LayerId) -> Option<u64> {
        (**self).layer_generation(layer)
    }
    fn layer_index(&self, layer: LayerId) -> Option<impl SpatialIndex + '_> {
        (**self).layer_index(layer)
    }
    fn node_index(&self, node: NodeId) -> Option<impl SpatialIndex + '_> {
        (**self).node_index(node)
    }
    fn has_node_index(&self, node: NodeId) -> bool {
        (**self).has_node_index(node)
    }
}
