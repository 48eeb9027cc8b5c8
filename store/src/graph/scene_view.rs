//! [`SceneView`] for the live [`SceneGraph`].

use super::scene_graph::{Node, SceneGraph};
use crate::feature::StoredValue;
use crate::index::SpatialIndex;
use crate::view::{EdgeRef, SceneView};
use crate::{Aabb, FeatureRef, LayerId, NodeId, Points};

impl SceneGraph {
    fn value_ref(&self, v: &StoredValue) -> FeatureRef<'_> {
        match *v {
            StoredValue::Str(s) => FeatureRef::Str(self.strings.resolve(s)),
            StoredValue::Int(v) => FeatureRef::Int(v),
            StoredValue::Float(v) => FeatureRef::Float(v),
            StoredValue::Bool(v) => FeatureRef::Bool(v),
        }
    }
}

impl SceneView for SceneGraph {
    type NodeRef<'a> = &'a Node;

    fn layers(&self) -> impl Iterator<Item = LayerId> + '_ {
        self.layers.keys().copied()
    }

    fn layer_name(&self, layer: LayerId) -> Option<&str> {
        self.layers.get(&layer).map(|l| l.name.as_str())
    }

    fn layer_by_name(&self, name: &str) -> Option<LayerId> {
        self.layer_names.get(name).copied()
    }

    fn layer_children(&self, layer: LayerId) -> Vec<LayerId> {
        let mut v = self
            .layers
            .get(&layer)
            .map(|l| l.children.clone())
            .unwrap_or_default();
        v.sort_unstable();
        v
    }

    fn layer_parents(&self, layer: LayerId) -> Vec<LayerId> {
        let mut v = self
            .layers
            .get(&layer)
            .map(|l| l.parents.clone())
            .unwrap_or_default();
        v.sort_unstable();
        v
    }

    fn layer_len(&self, layer: LayerId) -> usize {
        self.layers.get(&layer).map_or(0, |l| l.nodes.len())
    }

    fn layer_nodes(&self, layer: LayerId) -> impl Iterator<Item = &Node> + '_ {
        self.layers
            .get(&layer)
            .into_iter()
            .flat_map(|l| l.nodes.iter().map(|n| &self.nodes[n]))
    }

    fn node(&self, id: NodeId) -> Option<&Node> {
        self.nodes.get(&id)
    }

    fn node_id<'a>(&'a self, node: &'a Node) -> NodeId {
        node.id
    }

    fn node_layer<'a>(&'a self, node: &'a Node) -> LayerId {
        node.layer
    }

    fn points<'a>(&'a self, node: &'a Node) -> Points<'a> {
        Points::from(&node.points[..])
    }

    fn parent<'a>(&'a self, node: &'a Node) -> Option<NodeId> {
        node.parent
    }

    fn children<'a>(
        &'a self,
        node: &'a Node,
    ) -> impl DoubleEndedIterator<Item = NodeId> + ExactSizeIterator + 'a {
        node.children.iter().copied()
    }

    fn aabb<'a>(&'a self, node: &'a Node) -> Option<Aabb> {
        node.aabb
    }

    fn out_edges<'a>(&'a self, node: &'a Node) -> impl Iterator<Item = EdgeRef<'a>> + 'a {
        node.out_edges.iter().map(move |&(t, d)| EdgeRef {
            source: node.id,
            target: t,
            description: self.strings.resolve(d),
        })
    }

    fn in_edges<'a>(&'a self, node: &'a Node) -> impl Iterator<Item = EdgeRef<'a>> + 'a {
        node.in_edges.iter().map(move |&(s, d)| EdgeRef {
            source: s,
            target: node.id,
            description: self.strings.resolve(d),
        })
    }

    fn labels<'a>(&'a self, node: &'a Node) -> impl Iterator<Item = &'a str> + 'a {
        node.labels.iter().map(|&s| self.strings.resolve(s))
    }

    fn features<'a>(
        &'a self,
        node: &'a Node,
    ) -> impl Iterator<Item = (&'a str, FeatureRef<'a>)> + 'a {
        node.features
            .iter()
            .map(|(k, v)| (self.strings.resolve(*k), self.value_ref(v)))
    }

    fn layers_with_label(&self, label: &str) -> impl Iterator<Item = LayerId> {
        self.strings
            .get(label)
            .and_then(|s| self.label_layers.get(&s))
            .into_iter()
            .flatten()
            .copied()
    }

    fn layers_with_key(&self, key: &str) -> impl Iterator<Item = LayerId> {
        self.strings
            .get(key)
            .and_then(|s| self.key_layers.get(&s))
            .into_iter()
            .flatten()
            .copied()
    }

    fn nodes_with_label<'a>(
        &'a self,
        layer: LayerId,
        label: &str,
    ) -> impl Iterator<Item = &'a Node> {
        let set = self
            .strings
            .get(label)
            .and_then(|s| self.layers.get(&layer)?.label_postings.get(&s));
        set.into_iter().flatten().map(|n| &self.nodes[n])
    }

    fn nodes_with_key<'a>(&'a self, layer: LayerId, key: &str) -> impl Iterator<Item = &'a Node> {
        let set = self
            .strings
            .get(key)
            .and_then(|s| self.layers.get(&layer)?.key_postings.get(&s));
        set.into_iter().flatten().map(|n| &self.nodes[n])
    }

    fn layer_generation(&self, layer: LayerId) -> Option<u64> {
        SceneGraph::layer_generation(self, layer)
    }

    fn layer_index(&self, layer: LayerId) -> Option<impl SpatialIndex + '_> {
        self.indexes.layer(layer)
    }

    fn node_index(&self, node: NodeId) -> Option<impl SpatialIndex + '_> {
        self.indexes.node(node)
    }
}
