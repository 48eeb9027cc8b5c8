//! Pattern queries: nodes by label, by feature keys and values; edges by end or
//! description. Label and key lookups go through the inverted indexes.

use super::Scope;
use crate::{EdgeRef, FeatureRef, NodeId, SceneView};

/// Nodes in `scope` carrying `label`.
///
/// # Arguments
/// * `view` – a live graph or an archived snapshot.
/// * `scope` – the whole graph or one layer.
/// * `label` – the label to look for.
///
/// # Returns
/// Matching node ids, ascending.
///
/// # Complexity
/// O(1) when no node carries the label (one hash lookup in the graph-level index),
/// otherwise O(k log k) for k matches.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, Scope, query::nodes_with_label};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let objects = g.add_layer("objects")?;
/// g.add_node(NodeId(7), objects)?;
/// g.add_label(NodeId(7), "chair")?;
/// assert_eq!(nodes_with_label(&g, Scope::Graph, "chair"), vec![NodeId(7)]);
/// let snapshot = g.to_snapshot();
/// assert_eq!(nodes_with_label(&snapshot.view(), Scope::Graph, "chair"), vec![NodeId(7)]);
/// assert!(nodes_with_label(&g, Scope::Graph, "unicorn").is_empty());
/// # Ok(()) }
/// ```
pub fn nodes_with_label<V: SceneView>(view: &V, scope: Scope, label: &str) -> Vec<NodeId> {
    let mut out = Vec::new();
    for layer in view.layers_with_label(label) {
        if scope.contains(layer) {
            out.extend(view.nodes_with_label(layer, label).map(|n| view.node_id(n)));
        }
    }
    out.sort_unstable();
    out
}

/// Nodes in `scope` whose features match every `(key, value)` pair.
///
/// # Arguments
/// * `features` – required key/value pairs; an empty list matches every node in scope.
///
/// # Returns
/// Matching node ids, ascending.
///
/// # Complexity
/// O(1) when no node has the first key; otherwise linear in the nodes having it.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, Scope, FeatureRef, FeatureValue, query::nodes_matching};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let objects = g.add_layer("objects")?;
/// for (id, color) in [(1, "red"), (2, "blue")] {
///     g.add_node(NodeId(id), objects)?;
///     g.set_feature(NodeId(id), "color", FeatureValue::from(color))?;
/// }
/// let want = [("color", FeatureRef::Str("blue"))];
/// assert_eq!(nodes_matching(&g, Scope::Graph, &want), vec![NodeId(2)]);
/// assert_eq!(nodes_matching(&g.to_snapshot().view(), Scope::Graph, &want), vec![NodeId(2)]);
/// # Ok(()) }
/// ```
pub fn nodes_matching<V: SceneView>(
    view: &V,
    scope: Scope,
    features: &[(&str, FeatureRef<'_>)],
) -> Vec<NodeId> {
    let Some(&(first, _)) = features.first() else {
        return all_nodes(view, scope);
    };
    let mut out = Vec::new();
    for layer in view.layers_with_key(first) {
        if !scope.contains(layer) {
            continue;
        }
        out.extend(
            view.nodes_with_key(layer, first)
                .filter(|&n| {
                    features
                        .iter()
                        .all(|(k, v)| view.feature(n, k).as_ref() == Some(v))
                })
                .map(|n| view.node_id(n)),
        );
    }
    out.sort_unstable();
    out
}

/// Nodes in `scope` that have every key in `keys` (any value).
///
/// # Returns
/// Matching node ids, ascending; an empty `keys` matches every node in scope.
///
/// # Complexity
/// O(1) when no node has the first key; otherwise linear in the nodes having it.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, Scope, FeatureValue, query::nodes_having};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let places = g.add_layer("places")?;
/// g.add_node(NodeId(1), places)?;
/// g.add_node(NodeId(2), places)?;
/// g.set_feature(NodeId(2), "traversable", FeatureValue::Bool(true))?;
/// assert_eq!(nodes_having(&g, Scope::Layer(places), &["traversable"]), vec![NodeId(2)]);
/// assert_eq!(nodes_having(&g.to_snapshot().view(), Scope::Layer(places), &["traversable"]), vec![NodeId(2)]);
/// # Ok(()) }
/// ```
pub fn nodes_having<V: SceneView>(view: &V, scope: Scope, keys: &[&str]) -> Vec<NodeId> {
    let Some(&first) = keys.first() else {
        return all_nodes(view, scope);
    };
    let mut out = Vec::new();
    for layer in view.layers_with_key(first) {
        if !scope.contains(layer) {
            continue;
        }
        out.extend(
            view.nodes_with_key(layer, first)
                .filter(|&n| keys.iter().all(|k| view.feature(n, k).is_some()))
                .map(|n| view.node_id(n)),
        );
    }
    out.sort_unstable();
    out
}

fn all_nodes<V: SceneView>(view: &V, scope: Scope) -> Vec<NodeId> {
    let mut out: Vec<NodeId> = scope
        .layers(view)
        .into_iter()
        .flat_map(|l| {
            view.layer_nodes(l)
                .map(|n| view.node_id(n))
                .collect::<Vec<_>>()
        })
        .collect();
    out.sort_unstable();
    out
}

/// Edges leaving `node`, ascending by target (empty for an unknown node).
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, query::edges_from};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let places = g.add_layer("places")?;
/// for id in 1..=3 { g.add_node(NodeId(id), places)?; }
/// g.add_edge(NodeId(1), NodeId(3), "door")?;
/// g.add_edge(NodeId(1), NodeId(2), "hall")?;
/// let targets: Vec<_> = edges_from(&g, NodeId(1)).iter().map(|e| e.target).collect();
/// assert_eq!(targets, [NodeId(2), NodeId(3)]);
/// assert_eq!(edges_from(&g.to_snapshot().view(), NodeId(1)), edges_from(&g, NodeId(1)));
/// # Ok(()) }
/// ```
pub fn edges_from<V: SceneView>(view: &V, node: NodeId) -> Vec<EdgeRef<'_>> {
    view.node(node)
        .map(|n| view.out_edges(n).collect())
        .unwrap_or_default()
}

/// Edges entering `node`, ascending by source (empty for an unknown node).
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, query::edges_to};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let places = g.add_layer("places")?;
/// for id in 1..=3 { g.add_node(NodeId(id), places)?; }
/// g.add_edge(NodeId(3), NodeId(1), "door")?;
/// g.add_edge(NodeId(2), NodeId(1), "hall")?;
/// let sources: Vec<_> = edges_to(&g, NodeId(1)).iter().map(|e| e.source).collect();
/// assert_eq!(sources, [NodeId(2), NodeId(3)]);
/// assert_eq!(edges_to(&g.to_snapshot().view(), NodeId(1)), edges_to(&g, NodeId(1)));
/// # Ok(()) }
/// ```
pub fn edges_to<V: SceneView>(view: &V, node: NodeId) -> Vec<EdgeRef<'_>> {
    view.node(node)
        .map(|n| view.in_edges(n).collect())
        .unwrap_or_default()
}

/// Edges in `scope` whose description equals `description`, ascending by (source, target).
///
/// # Complexity
/// O(E) over the edges in scope (descriptions are not indexed).
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, Scope, query::edges_matching};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let rooms = g.add_layer("rooms")?;
/// for id in 1..=3 { g.add_node(NodeId(id), rooms)?; }
/// g.add_edge(NodeId(1), NodeId(2), "door")?;
/// g.add_edge(NodeId(2), NodeId(3), "wall")?;
/// let doors = edges_matching(&g, Scope::Graph, "door");
/// assert_eq!((doors[0].source, doors[0].target), (NodeId(1), NodeId(2)));
/// assert_eq!(edges_matching(&g.to_snapshot().view(), Scope::Graph, "door"), doors);
/// # Ok(()) }
/// ```
pub fn edges_matching<'a, V: SceneView>(
    view: &'a V,
    scope: Scope,
    description: &str,
) -> Vec<EdgeRef<'a>> {
    let mut out: Vec<EdgeRef<'a>> = Vec::new();
    for layer in scope.layers(view) {
        for n in view.layer_nodes(layer) {
            out.extend(view.out_edges(n).filter(|e| e.description == description));
        }
    }
    out.sort_unstable_by_key(|e| (e.source, e.target));
    out
}
