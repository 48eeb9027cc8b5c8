//! [`SceneView`]: the one read interface that every query is written against.
//!
//! | backend | type | how it answers |
//! |---|---|---|
//! | live graph | [`crate::SceneGraph`] | hash map of nodes, per-layer posting sets |
//! | archived snapshot (file or shared memory) | [`crate::ArchivedScene`] | validated rkyv columns, zero-copy |
//!
//! Every query in [`crate::query`] is generic over `V: SceneView`, so both backends run
//! the same code and give the same answers (property-tested).
//!
//! # Required, provided and optional methods
//! A backend implements the twelve required methods: layers ([`SceneView::layers`],
//! [`SceneView::layer_name`], [`SceneView::layer_children`],
//! [`SceneView::layer_generation`], [`SceneView::layer_nodes`]) and nodes
//! ([`SceneView::node_id`], [`SceneView::points`], [`SceneView::parent`],
//! [`SceneView::aabb`], [`SceneView::out_edges`], [`SceneView::labels`],
//! [`SceneView::features`]). Every other method has a default body that derives its
//! answer from those by a scan (a node by id, a node's layer, children, in-edges, layer
//! parents, names, label and key lookups, counts); a backend with a faster path
//! overrides it, as the live graph and the archive do (hash maps, inverted indexes,
//! binary searches). Defaults and overrides give the same answers (`store/tests/view_defaults.rs`).
//!
//! Spatial indexes are the optional part: [`SceneView::layer_index`] and
//! [`SceneView::node_index`] return none by default, and a [`SpatialIndex`] (a
//! [`crate::index::LiveIndex`] on the live graph, a zero-copy
//! [`crate::index::ArchivedIndex`] on a snapshot) where the backend keeps one; the
//! spatial queries use it when present and scan otherwise.
//!
//! The trait and its `&V` forwarding are generated from one list of methods
//! (`scene_view!`), so a method added to the trait is forwarded too.

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

/// Defines [`SceneView`] from one list of its methods, and the `&V` forwarding of every
/// one of them (so a view behind a reference keeps the backend's fast paths).
macro_rules! scene_view {
    (
        $(#[$trait_meta:meta])*
        required {
            $(
                $(#[$req_meta:meta])*
                fn $req:ident $(<$req_lt:lifetime>)?
                (
                    &$($req_self_lt:lifetime)? $req_self:ident
                    $(, $req_arg:ident: $req_ty:ty)* $(,)?
                ) -> $req_ret:ty;
            )*
        }
        provided {
            $(
                $(#[$pro_meta:meta])*
                fn $pro:ident $(<$pro_lt:lifetime>)?
                (
                    &$($pro_self_lt:lifetime)? $pro_self:ident
                    $(, $pro_arg:ident: $pro_ty:ty)* $(,)?
                ) -> $pro_ret:ty $pro_body:block
            )*
        }
    ) => {
        $(#[$trait_meta])*
        pub trait SceneView {
            /// A handle to one node of this view.
            type NodeRef<'a>: Copy
            where
                Self: 'a;

            $(
                $(#[$req_meta])*
                fn $req $(<$req_lt>)? (
                    &$($req_self_lt)? $req_self $(, $req_arg: $req_ty)*
                ) -> $req_ret;
            )*
            $(
                $(#[$pro_meta])*
                fn $pro $(<$pro_lt>)? (
                    &$($pro_self_lt)? $pro_self $(, $pro_arg: $pro_ty)*
                ) -> $pro_ret $pro_body
            )*
        }

        /// A shared reference to a view is a view (so a query target can hold
        /// `&SceneGraph`); every method, provided ones included, forwards to the view.
        impl<V: SceneView + ?Sized> SceneView for &V {
            type NodeRef<'a>
                = V::NodeRef<'a>
            where
                Self: 'a;

            $(
                fn $req $(<$req_lt>)? (
                    &$($req_self_lt)? $req_self $(, $req_arg: $req_ty)*
                ) -> $req_ret {
                    (**$req_self).$req($($req_arg),*)
                }
            )*
            $(
                fn $pro $(<$pro_lt>)? (
                    &$($pro_self_lt)? $pro_self $(, $pro_arg: $pro_ty)*
                ) -> $pro_ret {
                    (**$pro_self).$pro($($pro_arg),*)
                }
            )*
        }
    };
}

scene_view! {
    /// Read-only access to a scene graph, live or archived.
    ///
    /// Nodes are reached through a cheap handle ([`SceneView::NodeRef`]) so a query looks a
    /// node up once and then reads its columns directly. A handle is valid for as long as
    /// the borrow of the view it came from.
    ///
    /// A backend implements the required methods; the provided ones derive their answers
    /// from them by a scan (the cost each states), and a backend overrides those it answers
    /// faster. The spatial index methods are optional: none by default.
    required {
        /// Every layer, in ascending id order.
        fn layers(&self) -> impl Iterator<Item = LayerId> + '_;
        /// The name of a layer.
        fn layer_name(&self, layer: LayerId) -> Option<&str>;
        /// Layers this layer encompasses (DAG children), ascending.
        fn layer_children(&self, layer: LayerId) -> Vec<LayerId>;
        /// A layer's generation: it changes whenever the layer's content changes (`None`
        /// for an unknown layer). Readers key the indexes they build on it.
        fn layer_generation(&self, layer: LayerId) -> Option<u64>;
        /// The nodes of a layer, in no particular order.
        fn layer_nodes(&self, layer: LayerId) -> impl Iterator<Item = Self::NodeRef<'_>> + '_;

        /// A node's id.
        fn node_id<'a>(&'a self, node: Self::NodeRef<'a>) -> NodeId;
        /// A node's geometry (empty if none).
        fn points<'a>(&'a self, node: Self::NodeRef<'a>) -> Points<'a>;
        /// A node's parent.
        fn parent<'a>(&'a self, node: Self::NodeRef<'a>) -> Option<NodeId>;
        /// A node's bounding box, if enabled and its sub-tree has a point.
        fn aabb<'a>(&'a self, node: Self::NodeRef<'a>) -> Option<Aabb>;
        /// Edges leaving a node, ascending by target id.
        fn out_edges<'a>(
            &'a self,
            node: Self::NodeRef<'a>,
        ) -> impl Iterator<Item = EdgeRef<'a>> + 'a;
        /// A node's labels, in no particular order.
        fn labels<'a>(&'a self, node: Self::NodeRef<'a>) -> impl Iterator<Item = &'a str> + 'a;
        /// A node's features, in no particular order.
        fn features<'a>(
            &'a self,
            node: Self::NodeRef<'a>,
        ) -> impl Iterator<Item = (&'a str, FeatureRef<'a>)> + 'a;
    }
    provided {
        /// The layer with this name. By default a scan of the layer names: O(layers).
        fn layer_by_name(&self, name: &str) -> Option<LayerId> {
            self.layers().find(|&l| self.layer_name(l) == Some(name))
        }
        /// Layers encompassing this layer (DAG parents), ascending. By default a scan of
        /// every layer's children: O(layers + DAG edges).
        fn layer_parents(&self, layer: LayerId) -> Vec<LayerId> {
            self.layers()
                .filter(|&p| self.layer_children(p).contains(&layer))
                .collect()
        }
        /// Number of nodes in a layer (0 for an unknown layer). By default a count of
        /// [`SceneView::layer_nodes`]: O(nodes of the layer).
        fn layer_len(&self, layer: LayerId) -> usize {
            self.layer_nodes(layer).count()
        }
        /// Total number of nodes. By default the sum of [`SceneView::layer_len`].
        fn node_count(&self) -> usize {
            self.layers().map(|l| self.layer_len(l)).sum()
        }

        /// The node with this id. By default a scan of every layer: O(nodes).
        fn node(&self, id: NodeId) -> Option<Self::NodeRef<'_>> {
            self.layers()
                .flat_map(|l| self.layer_nodes(l))
                .find(|&n| self.node_id(n) == id)
        }
        /// A node's layer. By default a scan for the layer that holds it: O(nodes); a
        /// handle this view did not give out lies in no layer, and gets
        /// `LayerId(u32::MAX)`.
        fn node_layer<'a>(&'a self, node: Self::NodeRef<'a>) -> LayerId {
            let id = self.node_id(node);
            self.layers()
                .find(|&l| self.layer_nodes(l).any(|n| self.node_id(n) == id))
                .unwrap_or(LayerId(u32::MAX))
        }
        /// A node's children, ascending by id. By default a scan of the nodes of its
        /// layer's DAG children (a child lies in one of them): O(their nodes).
        fn children<'a>(
            &'a self,
            node: Self::NodeRef<'a>,
        ) -> impl DoubleEndedIterator<Item = NodeId> + ExactSizeIterator + 'a {
            let id = self.node_id(node);
            let mut children: Vec<NodeId> = self
                .layer_children(self.node_layer(node))
                .into_iter()
                .flat_map(|l| {
                    self.layer_nodes(l)
                        .filter(|&n| self.parent(n) == Some(id))
                        .map(|n| self.node_id(n))
                        .collect::<Vec<_>>()
                })
                .collect();
            children.sort_unstable();
            children.into_iter()
        }
        /// Edges entering a node, ascending by source id. By default a scan of the
        /// out-edges of its layer (an edge joins two nodes of one layer): O(edges of the
        /// layer).
        fn in_edges<'a>(
            &'a self,
            node: Self::NodeRef<'a>,
        ) -> impl Iterator<Item = EdgeRef<'a>> + 'a {
            let id = self.node_id(node);
            let mut edges: Vec<EdgeRef<'a>> = self
                .layer_nodes(self.node_layer(node))
                .flat_map(|n| self.out_edges(n))
                .filter(|e| e.target == id)
                .collect();
            edges.sort_by_key(|e| e.source);
            edges.into_iter()
        }

        /// A node's feature `key`, if present. By default a scan of its features.
        fn feature<'a>(&'a self, node: Self::NodeRef<'a>, key: &str) -> Option<FeatureRef<'a>> {
            self.features(node).find(|(k, _)| *k == key).map(|(_, v)| v)
        }
        /// Whether a node carries `label`. By default a scan of its labels.
        fn has_label<'a>(&'a self, node: Self::NodeRef<'a>, label: &str) -> bool {
            self.labels(node).any(|l| l == label)
        }
        /// Nodes of `layer` carrying `label`, in no particular order. By default a scan
        /// of the layer; the live graph and the archive answer from an inverted index.
        fn nodes_with_label<'a>(
            &'a self,
            layer: LayerId,
            label: &str,
        ) -> impl Iterator<Item = Self::NodeRef<'a>> {
            self.layer_nodes(layer)
                .filter(move |&n| self.has_label(n, label))
        }
        /// Nodes of `layer` carrying feature `key`, in no particular order. By default a
        /// scan of the layer; the live graph and the archive answer from an inverted
        /// index.
        fn nodes_with_key<'a>(
            &'a self,
            layer: LayerId,
            key: &str,
        ) -> impl Iterator<Item = Self::NodeRef<'a>> {
            self.layer_nodes(layer)
                .filter(move |&n| self.feature(n, key).is_some())
        }
        /// Layers holding at least one node with this label, in no particular order. By
        /// default a scan of every layer; indexed backends answer in O(1) when absent.
        fn layers_with_label(&self, label: &str) -> impl Iterator<Item = LayerId> {
            self.layers()
                .filter(move |&l| self.nodes_with_label(l, label).next().is_some())
        }
        /// Layers holding at least one node with this feature key, in no particular
        /// order. By default a scan of every layer.
        fn layers_with_key(&self, key: &str) -> impl Iterator<Item = LayerId> {
            self.layers()
                .filter(move |&l| self.nodes_with_key(l, key).next().is_some())
        }

        /// Optional: the index over every point of `layer`, if this view keeps one (none
        /// by default; queries then scan).
        fn layer_index(&self, layer: LayerId) -> Option<impl SpatialIndex + '_> {
            let _ = layer;
            None::<NoIndex>
        }
        /// Optional: the index over every point in `node`'s sub-tree, if this view keeps
        /// one (none by default; a published snapshot keeps none for a sub-tree of few
        /// points: queries walk it).
        fn node_index(&self, node: NodeId) -> Option<impl SpatialIndex + '_> {
            let _ = node;
            None::<NoIndex>
        }
        /// Optional: whether the graph indexes `node`'s sub-tree, whether or not this
        /// view carries the tree ([`SceneView::node_index`] may give none for a small
        /// sub-tree). By default whether [`SceneView::node_index`] gives one.
        fn has_node_index(&self, node: NodeId) -> bool {
            self.node_index(node).is_some()
        }
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
