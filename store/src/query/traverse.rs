//! Nesting navigation (parent, children, sub-tree, sub-scene graph) and traversals over
//! a layer's edges (BFS, DFS, shortest path).

use crate::{NodeId, SceneGraph, SceneView};
use rustc_hash::{FxHashMap, FxHashSet};
use std::collections::VecDeque;

/// The parent of `node` (the node nesting it), if any.
///
/// # Complexity
/// One node lookup: the parent pointer is stored with the node.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, query::parent};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let (rooms, places) = (g.add_layer("rooms")?, g.add_layer("places")?);
/// g.add_layer_edge(rooms, places)?;
/// g.add_node(NodeId(1), rooms)?;
/// g.add_node(NodeId(2), places)?;
/// g.nest(NodeId(1), NodeId(2))?;
/// assert_eq!(parent(&g, NodeId(2)), Some(NodeId(1)));
/// assert_eq!(parent(&g.to_snapshot().view(), NodeId(2)), Some(NodeId(1)));
/// # Ok(()) }
/// ```
pub fn parent<V: SceneView>(view: &V, node: NodeId) -> Option<NodeId> {
    view.parent(view.node(node)?)
}

/// The children of `node`, ascending (empty for an unknown node).
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, query::children};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let (rooms, places) = (g.add_layer("rooms")?, g.add_layer("places")?);
/// g.add_layer_edge(rooms, places)?;
/// g.add_node(NodeId(1), rooms)?;
/// for id in [3, 2] { g.add_node(NodeId(id), places)?; g.nest(NodeId(1), NodeId(id))?; }
/// assert_eq!(children(&g, NodeId(1)), [NodeId(2), NodeId(3)]);
/// assert_eq!(children(&g.to_snapshot().view(), NodeId(1)), [NodeId(2), NodeId(3)]);
/// # Ok(()) }
/// ```
pub fn children<V: SceneView>(view: &V, node: NodeId) -> Vec<NodeId> {
    view.node(node)
        .map(|n| view.children(n).collect())
        .unwrap_or_default()
}

/// The sub-tree of `root`: `root` and every node nested under it, transitively.
///
/// # Returns
/// Node ids ascending (empty for an unknown root).
///
/// # Complexity
/// O(s log s) for a sub-tree of s nodes.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, query::subtree};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let (b, r, p) = (g.add_layer("building")?, g.add_layer("rooms")?, g.add_layer("places")?);
/// g.add_layer_edge(b, r)?;
/// g.add_layer_edge(r, p)?;
/// g.add_node(NodeId(1), b)?;
/// g.add_node(NodeId(2), r)?;
/// g.add_node(NodeId(3), p)?;
/// g.nest(NodeId(1), NodeId(2))?;
/// g.nest(NodeId(2), NodeId(3))?;
/// assert_eq!(subtree(&g, NodeId(1)), [NodeId(1), NodeId(2), NodeId(3)]);
/// assert_eq!(subtree(&g.to_snapshot().view(), NodeId(2)), [NodeId(2), NodeId(3)]);
/// # Ok(()) }
/// ```
pub fn subtree<V: SceneView>(view: &V, root: NodeId) -> Vec<NodeId> {
    let mut out = Vec::new();
    visit_subtree(view, root, |id| out.push(id));
    out.sort_unstable();
    out
}

/// Calls `visit` for `root` and every node below it (pre-order, children ascending).
/// A child id that names no node (possible only in a damaged snapshot) is skipped.
pub(crate) fn visit_subtree<V: SceneView>(view: &V, root: NodeId, mut visit: impl FnMut(NodeId)) {
    let Some(r) = view.node(root) else { return };
    let mut stack = vec![r];
    let mut seen = FxHashSet::default();
    while let Some(n) = stack.pop() {
        let id = view.node_id(n);
        if !seen.insert(id) {
            continue; // only a damaged snapshot can nest a node twice
        }
        visit(id);
        stack.extend(view.children(n).rev().filter_map(|c| view.node(c)));
    }
}

/// The sub-scene graph over `nodes`: those nodes with their geometry, labels, features
/// and boxes, the edges and nestings among them, and *every* layer and DAG edge of the
/// scene (kept even when empty). Unknown ids are ignored.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, SceneView, query::{subgraph, edges_from}};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let (rooms, places) = (g.add_layer("rooms")?, g.add_layer("places")?);
/// g.add_layer_edge(rooms, places)?;
/// for id in 1..=3 { g.add_node(NodeId(id), places)?; }
/// g.add_edge(NodeId(1), NodeId(2), "hall")?;
/// g.add_edge(NodeId(2), NodeId(3), "hall")?;
/// let sub = subgraph(&g, &[NodeId(1), NodeId(2)]);
/// assert_eq!(sub.node_count(), 2);
/// assert_eq!(sub.layers().count(), 2);
/// assert_eq!(edges_from(&sub, NodeId(2)).len(), 0);
/// assert_eq!(subgraph(&g.to_snapshot().view(), &[NodeId(1), NodeId(2)]).node_count(), 2);
/// # Ok(()) }
/// ```
pub fn subgraph<V: SceneView>(view: &V, nodes: &[NodeId]) -> SceneGraph {
    let mut g = SceneGraph::new();
    let layers: Vec<_> = view.layers().collect();
    for &l in &layers {
        g.insert_layer_with_id(l, view.layer_name(l).unwrap_or_default());
    }
    for &l in &layers {
        for c in view.layer_children(l) {
            g.add_layer_edge(l, c)
                .expect("the source view's DAG is acyclic");
        }
    }
    let keep: FxHashSet<NodeId> = nodes
        .iter()
        .copied()
        .filter(|&n| view.node(n).is_some())
        .collect();
    let mut sorted: Vec<NodeId> = keep.iter().copied().collect();
    sorted.sort_unstable();
    for &id in &sorted {
        let n = view.node(id).expect("filtered");
        g.add_node(id, view.node_layer(n))
            .expect("fresh id in an existing layer");
        if !view.points(n).is_empty() {
            // A damaged snapshot could carry non-finite points; such geometry is dropped.
            let _ = g.set_geometry(id, view.points(n).to_vec());
        }
        for label in view.labels(n) {
            g.add_label(id, label).expect("node exists");
        }
        for (k, v) in view.features(n) {
            // A damaged snapshot could carry a NaN float; such a feature is dropped.
            let _ = g.set_feature(id, k, v.to_owned());
        }
        if view.aabb(n).is_some() {
            g.enable_bounding_box(id).expect("node exists");
        }
    }
    for &id in &sorted {
        let n = view.node(id).expect("filtered");
        for e in view.out_edges(n).filter(|e| keep.contains(&e.target)) {
            let _ = g.add_edge(e.source, e.target, e.description);
        }
        if let Some(p) = view.parent(n).filter(|p| keep.contains(p)) {
            let _ = g.nest(p, id);
        }
    }
    g
}

/// Which way traversals follow edges.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// Along edges, source to target.
    Outgoing,
    /// Both ways (for graphs whose edges are symmetric relations, like Spark-DSG's).
    Undirected,
}

fn neighbours<'a, V: SceneView>(view: &'a V, n: V::NodeRef<'a>, dir: Direction) -> Vec<NodeId> {
    let mut out: Vec<NodeId> = view.out_edges(n).map(|e| e.target).collect();
    if dir == Direction::Undirected {
        out.extend(view.in_edges(n).map(|e| e.source));
        out.sort_unstable();
        out.dedup();
    }
    out
}

/// Breadth-first order of the nodes reachable from `start` over its layer's edges.
/// Neighbours are visited in ascending id order, so the order is deterministic.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, query::{bfs, Direction}};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let places = g.add_layer("places")?;
/// for id in 1..=4 { g.add_node(NodeId(id), places)?; }
/// g.add_edge(NodeId(1), NodeId(3), "")?;
/// g.add_edge(NodeId(1), NodeId(2), "")?;
/// g.add_edge(NodeId(2), NodeId(4), "")?;
/// let order = bfs(&g, NodeId(1), Direction::Outgoing);
/// assert_eq!(order, [NodeId(1), NodeId(2), NodeId(3), NodeId(4)]);
/// assert_eq!(bfs(&g.to_snapshot().view(), NodeId(1), Direction::Outgoing), order);
/// # Ok(()) }
/// ```
pub fn bfs<V: SceneView>(view: &V, start: NodeId, dir: Direction) -> Vec<NodeId> {
    let Some(s) = view.node(start) else {
        return Vec::new();
    };
    let mut seen = FxHashSet::default();
    let mut order = Vec::new();
    let mut queue = VecDeque::from([s]);
    seen.insert(start);
    while let Some(n) = queue.pop_front() {
        order.push(view.node_id(n));
        for m in neighbours(view, n, dir) {
            if seen.insert(m) {
                queue.extend(view.node(m));
            }
        }
    }
    order
}

/// Depth-first pre-order of the nodes reachable from `start` over its layer's edges,
/// neighbours in ascending id order.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, query::{dfs, Direction}};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let places = g.add_layer("places")?;
/// for id in 1..=4 { g.add_node(NodeId(id), places)?; }
/// g.add_edge(NodeId(1), NodeId(3), "")?;
/// g.add_edge(NodeId(1), NodeId(2), "")?;
/// g.add_edge(NodeId(2), NodeId(4), "")?;
/// let order = dfs(&g, NodeId(1), Direction::Outgoing);
/// assert_eq!(order, [NodeId(1), NodeId(2), NodeId(4), NodeId(3)]);
/// assert_eq!(dfs(&g.to_snapshot().view(), NodeId(1), Direction::Outgoing), order);
/// # Ok(()) }
/// ```
pub fn dfs<V: SceneView>(view: &V, start: NodeId, dir: Direction) -> Vec<NodeId> {
    let Some(s) = view.node(start) else {
        return Vec::new();
    };
    let mut seen = FxHashSet::default();
    let mut order = Vec::new();
    let mut stack = vec![s];
    while let Some(n) = stack.pop() {
        let id = view.node_id(n);
        if !seen.insert(id) {
            continue;
        }
        order.push(id);
        let next = neighbours(view, n, dir);
        stack.extend(
            next.iter()
                .rev()
                .filter(|m| !seen.contains(m))
                .filter_map(|&m| view.node(m)),
        );
    }
    order
}

/// A path with the fewest edges from `from` to `to` (both included), or `None` when `to`
/// is unreachable. Among equally short paths, the one BFS finds first with neighbours
/// in ascending order is returned.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, query::{shortest_path, Direction}};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let places = g.add_layer("places")?;
/// for id in 1..=4 { g.add_node(NodeId(id), places)?; }
/// g.add_edge(NodeId(1), NodeId(2), "")?;
/// g.add_edge(NodeId(2), NodeId(3), "")?;
/// g.add_edge(NodeId(1), NodeId(4), "")?;
/// g.add_edge(NodeId(4), NodeId(3), "")?;
/// let path = shortest_path(&g, NodeId(1), NodeId(3), Direction::Outgoing);
/// assert_eq!(path, Some(vec![NodeId(1), NodeId(2), NodeId(3)]));
/// assert_eq!(shortest_path(&g.to_snapshot().view(), NodeId(1), NodeId(3), Direction::Outgoing), path);
/// # Ok(()) }
/// ```
pub fn shortest_path<V: SceneView>(
    view: &V,
    from: NodeId,
    to: NodeId,
    dir: Direction,
) -> Option<Vec<NodeId>> {
    let s = view.node(from)?;
    view.node(to)?;
    let mut prev: FxHashMap<NodeId, NodeId> = FxHashMap::default();
    let mut queue = VecDeque::from([s]);
    prev.insert(from, from);
    while let Some(n) = queue.pop_front() {
        let id = view.node_id(n);
        if id == to {
            let mut path = vec![to];
            let mut cur = to;
            while cur != from {
                cur = prev[&cur];
                path.push(cur);
            }
            path.reverse();
            return Some(path);
        }
        for m in neighbours(view, n, dir) {
            if let std::collections::hash_map::Entry::Vacant(e) = prev.entry(m) {
                e.insert(id);
                queue.extend(view.node(m));
            }
        }
    }
    None
}
