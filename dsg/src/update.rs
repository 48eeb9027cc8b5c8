//! Incremental updates of a [`DsgGraph`]: the nodes that changed or were added (a Spark-DSG
//! graph of their own), then the nodes and edges removed, as hydra_msgs' `DsgUpdate` with
//! `full_update = false` carries them.
//!
//! Semantics (those of spark_dsg's `updateGraph` without `remove_stale`, plus explicit
//! removals):
//! * removals first: each of `deleted_edges` (pairs, either orientation, any kind of edge),
//!   then each of `deleted_nodes` with every edge touching it; ids that are not in the
//!   graph are ignored (the sender may remove what it never sent);
//! * then every node of the part replaces the node with its id (keeping that node's
//!   parent unless the part gives it one) or is appended; a node keeps its layer: a part
//!   node with a known id in another layer is an error;
//! * then every edge of the part is added (an edge the graph already has is updated
//!   in place): edges are only ever removed by `deleted_edges` or with a node, never by
//!   their absence from a part, so a part that moves one node holds that node alone;
//! * the part's mesh, when it has one, replaces the graph's; its labelspaces are merged in.
//!
//! Everything is checked before anything changes: an update that fails leaves the
//! graph as it was, and the result keeps every invariant of [`DsgGraph`].

use rustc_hash::{FxHashMap, FxHashSet};

use crate::model::{DsgEdge, DsgGraph, DsgNode, DsgParentEdge};

/// An incremental update that does not fit the graph.
#[derive(Debug, thiserror::Error)]
pub enum UpdateError {
    /// `deleted_edges` must hold (source, target) pairs.
    #[error("deleted_edges holds {0} ids: an odd number, not (source, target) pairs")]
    OddEdgeList(usize),
    /// A part node under a known id in another layer.
    #[error("node {id} is in {known} but the update puts it in {update}: a node keeps its layer")]
    LayerChange {
        /// The node id.
        id: u64,
        /// Its layer in the graph.
        known: String,
        /// Its layer in the update.
        update: String,
    },
    /// A part edge to a node neither in the graph nor in the part.
    #[error(
        "the update's edge {first} - {second} names node {missing}, which the graph does not hold"
    )]
    DanglingEdge {
        /// First end.
        first: u64,
        /// Second end.
        second: u64,
        /// The end that is missing.
        missing: u64,
    },
    /// A node that claims a vertex past the end of the mesh.
    #[error("node {id} claims mesh vertex {vertex}, but the mesh has {vertices} vertices")]
    Claim {
        /// The node id.
        id: u64,
        /// The vertex claimed.
        vertex: u32,
        /// Vertices of the mesh.
        vertices: usize,
    },
    /// The update's `layer_contents` do not decode.
    #[error("the update's layer_contents: {0}")]
    Decode(#[from] crate::DsgImportError),
    /// An incremental update with no graph to apply it to.
    #[error("an incremental update, but no full update was applied before it")]
    NoGraph,
}

/// What [`DsgGraph::apply_update`] changed.
#[derive(Debug, Default)]
pub struct UpdateReport {
    /// Nodes replaced in place: their index in [`DsgGraph::nodes`] and previous value.
    pub replaced: Vec<(usize, DsgNode)>,
    /// Nodes appended.
    pub added: usize,
    /// Nodes removed.
    pub removed: usize,
    /// Edges added, updated or removed (parents included).
    pub edges_changed: usize,
    /// Whether the mesh, the layers or the labelspaces changed.
    pub rest_changed: bool,
}

impl UpdateReport {
    /// Whether only nodes were replaced (no node added or removed, no edge, mesh, layer or
    /// labelspace changed): the update is then those nodes' new values alone.
    pub fn nodes_only(&self) -> bool {
        self.added == 0 && self.removed == 0 && self.edges_changed == 0 && !self.rest_changed
    }
}

/// An unordered node pair.
fn pair(a: u64, b: u64) -> (u64, u64) {
    (a.min(b), a.max(b))
}

impl DsgGraph {
    /// Applies an incremental update (see the module docs): `part` holds the nodes changed
    /// or added and the edges added, `deleted_nodes` the nodes removed and `deleted_edges`
    /// the edges removed as consecutive (source, target) pairs.
    ///
    /// # Errors
    /// An [`UpdateError`] naming the node or edge that does not fit; the graph is then
    /// unchanged.
    ///
    /// # Examples
    /// ```
    /// use ygg_dsg::office::{generate, OfficeParams};
    /// let mut g = generate(OfficeParams { seed: 1, scale: 0.01 });
    /// let mut moved = g.nodes[0].clone();
    /// moved.position[0] += 1.0;
    /// let part = ygg_dsg::DsgGraph { nodes: vec![moved.clone()], layers: g.layers.clone(), ..Default::default() };
    /// let report = g.apply_update(part, &[], &[])?;
    /// assert!(report.nodes_only());
    /// assert_eq!(g.nodes[0].position, moved.position);
    /// # Ok::<(), ygg_dsg::UpdateError>(())
    /// ```
    pub fn apply_update(
        &mut self,
        part: DsgGraph,
        deleted_nodes: &[u64],
        deleted_edges: &[u64],
    ) -> Result<UpdateReport, UpdateError> {
        if deleted_edges.len() % 2 == 1 {
            return Err(UpdateError::OddEdgeList(deleted_edges.len()));
        }
        let deleted: FxHashSet<u64> = deleted_nodes.iter().copied().collect();
        let index = self.node_index();
        let part_ids: FxHashMap<u64, &DsgNode> = part.nodes.iter().map(|n| (n.id, n)).collect();
        let known = |id: u64| {
            part_ids.contains_key(&id) || (index.contains_key(&id) && !deleted.contains(&id))
        };
        // Check everything first.
        for n in &part.nodes {
            if let Some(&i) = index.get(&n.id)
                && !deleted.contains(&n.id)
                && self.nodes[i].layer != n.layer
            {
                return Err(UpdateError::LayerChange {
                    id: n.id,
                    known: self.nodes[i].layer.to_string(),
                    update: n.layer.to_string(),
                });
            }
        }
        let part_edges = part_edge_list(&part);
        for &(a, b, _) in &part_edges {
            for end in [a, b] {
                if !known(end) {
                    return Err(UpdateError::DanglingEdge {
                        first: a,
                        second: b,
                        missing: end,
                    });
                }
            }
        }
        let vertices = part
            .mesh
            .as_ref()
            .or(self.mesh.as_ref())
            .map(|m| m.points.len());
        if let Some(vertices) = vertices {
            let claims = part.nodes.iter().chain(
                // A new mesh must still hold what the other nodes claim.
                self.nodes
                    .iter()
                    .filter(|n| part.mesh.is_some() && !part_ids.contains_key(&n.id)),
            );
            for n in claims {
                if let Some(&vertex) = n.mesh_connections.iter().find(|&&v| v as usize >= vertices)
                {
                    return Err(UpdateError::Claim {
                        id: n.id,
                        vertex,
                        vertices,
                    });
                }
            }
        }

        let mut report = UpdateReport::default();
        if !deleted_edges.is_empty() || !deleted.is_empty() {
            let removed_pairs: FxHashSet<(u64, u64)> = deleted_edges
                .chunks_exact(2)
                .map(|p| pair(p[0], p[1]))
                .collect();
            report.edges_changed += self.remove_edges(&removed_pairs, &deleted);
            let before = self.nodes.len();
            self.nodes.retain(|n| !deleted.contains(&n.id));
            report.removed = before - self.nodes.len();
        }
        let index = if report.removed > 0 {
            self.node_index()
        } else {
            index
        };

        let DsgGraph {
            nodes,
            layers,
            mesh,
            labelspaces,
            ..
        } = part;
        for n in nodes {
            let parent = n.parent;
            match index.get(&n.id) {
                Some(&i) => {
                    let node = DsgNode {
                        parent: self.nodes[i].parent,
                        ..n
                    };
                    if node != self.nodes[i] || parent.is_some() {
                        report
                            .replaced
                            .push((i, std::mem::replace(&mut self.nodes[i], node)));
                    }
                }
                None => {
                    self.nodes.push(DsgNode { parent: None, ..n });
                    report.added += 1;
                }
            }
        }
        if !part_edges.is_empty() {
            report.edges_changed += self.add_edges(&part_edges);
        }
        for layer in layers {
            if self.layer(layer.key).is_none() {
                self.layers.push(layer);
                self.layers.sort_by_key(|l| l.key);
                report.rest_changed = true;
            }
        }
        if let Some(mesh) = mesh {
            self.mesh = Some(mesh);
            report.rest_changed = true;
        }
        for (key, labels) in labelspaces {
            let space = self.labelspaces.entry(key).or_default();
            for (id, name) in labels {
                if space.get(&id) != Some(&name) {
                    space.insert(id, name);
                    report.rest_changed = true;
                }
            }
        }
        // A replaced node whose value is its old one after all (a parent it already had).
        report.replaced.retain(|(i, old)| self.nodes[*i] != *old);
        Ok(report)
    }

    /// Removes the edges named in `pairs` and every edge touching a node of `nodes`
    /// (children of such a node lose their parent, or take their next parent edge);
    /// returns how many went.
    fn remove_edges(&mut self, pairs: &FxHashSet<(u64, u64)>, nodes: &FxHashSet<u64>) -> usize {
        let gone = |a: u64, b: u64| {
            pairs.contains(&pair(a, b)) || nodes.contains(&a) || nodes.contains(&b)
        };
        let mut removed = 0;
        for list in [&mut self.edges, &mut self.sibling_edges] {
            let before = list.len();
            list.retain(|e| !gone(e.source, e.target));
            removed += before - list.len();
        }
        let before = self.extra_parent_edges.len();
        self.extra_parent_edges.retain(|e| !gone(e.parent, e.child));
        removed += before - self.extra_parent_edges.len();
        for i in 0..self.nodes.len() {
            let n = &self.nodes[i];
            if let Some(p) = n.parent
                && gone(p, n.id)
            {
                let child = n.id;
                // The next inter-layer edge above the child becomes its parent, as the
                // importer would choose with the removed one absent.
                let next = self
                    .extra_parent_edges
                    .iter()
                    .position(|e| e.child == child);
                self.nodes[i].parent = next.map(|k| self.extra_parent_edges.remove(k).parent);
                removed += 1;
            }
        }
        removed
    }

    /// Adds the edges of `list` (from [`part_edge_list`]); returns how many were new or
    /// changed.
    fn add_edges(&mut self, list: &[(u64, u64, EdgeKind)]) -> usize {
        let index = self.node_index();
        let mut existing: FxHashMap<(u64, u64), (EdgeKind, usize)> = FxHashMap::default();
        for (k, e) in self.edges.iter().enumerate() {
            existing.insert(pair(e.source, e.target), (EdgeKind::Intra(e.weight), k));
        }
        for (k, e) in self.sibling_edges.iter().enumerate() {
            existing.insert(pair(e.source, e.target), (EdgeKind::Sibling(e.weight), k));
        }
        for (k, e) in self.extra_parent_edges.iter().enumerate() {
            existing.insert(pair(e.parent, e.child), (EdgeKind::Parent, k));
        }
        for n in &self.nodes {
            if let Some(p) = n.parent {
                existing.insert(pair(p, n.id), (EdgeKind::Parent, usize::MAX));
            }
        }
        let mut changed = 0;
        for &(a, b, kind) in list {
            match (existing.get(&pair(a, b)), kind) {
                (Some(&(EdgeKind::Intra(w), k)), EdgeKind::Intra(new)) => {
                    if w.map(f64::to_bits) != new.map(f64::to_bits) {
                        self.edges[k].weight = new;
                        changed += 1;
                    }
                }
                (Some(&(EdgeKind::Sibling(w), k)), EdgeKind::Sibling(new)) => {
                    if w.map(f64::to_bits) != new.map(f64::to_bits) {
                        self.sibling_edges[k].weight = new;
                        changed += 1;
                    }
                }
                (Some(_), _) => {}
                (None, kind) => {
                    changed += 1;
                    existing.insert(pair(a, b), (kind, usize::MAX));
                    match kind {
                        EdgeKind::Intra(weight) => self.edges.push(DsgEdge {
                            source: a,
                            target: b,
                            weight,
                        }),
                        EdgeKind::Sibling(weight) => self.sibling_edges.push(DsgEdge {
                            source: a,
                            target: b,
                            weight,
                        }),
                        EdgeKind::Parent => {
                            // (a, b) is (parent, child).
                            let child = &mut self.nodes[index[&b]];
                            if child.parent.is_none() {
                                child.parent = Some(a);
                            } else {
                                self.extra_parent_edges.push(DsgParentEdge {
                                    parent: a,
                                    child: b,
                                });
                            }
                        }
                    }
                }
            }
        }
        changed
    }
}

/// The kind of an edge, with its weight where it has one.
#[derive(Clone, Copy, Debug)]
enum EdgeKind {
    Intra(Option<f64>),
    Sibling(Option<f64>),
    /// (parent, child).
    Parent,
}

/// Every edge of a part: intra-layer, sibling, parent (as (parent, child)) and extra
/// parent edges.
fn part_edge_list(part: &DsgGraph) -> Vec<(u64, u64, EdgeKind)> {
    let mut out: Vec<(u64, u64, EdgeKind)> = Vec::new();
    out.extend(
        part.edges
            .iter()
            .map(|e| (e.source, e.target, EdgeKind::Intra(e.weight))),
    );
    out.extend(
        part.sibling_edges
            .iter()
            .map(|e| (e.source, e.target, EdgeKind::Sibling(e.weight))),
    );
    out.extend(
        part.nodes
            .iter()
            .filter_map(|n| n.parent.map(|p| (p, n.id, EdgeKind::Parent))),
    );
    out.extend(
        part.extra_parent_edges
            .iter()
            .map(|e| (e.parent, e.child, EdgeKind::Parent)),
    );
    out
}

/// An incremental update as [`DsgGraph::apply_update`] takes it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GraphUpdate {
    /// The nodes changed or added, the edges added and the nodes they join.
    pub part: DsgGraph,
    /// Nodes removed.
    pub deleted_nodes: Vec<u64>,
    /// Edges removed, as consecutive (source, target) pairs.
    pub deleted_edges: Vec<u64>,
}

impl GraphUpdate {
    /// Whether the update changes nothing.
    pub fn is_empty(&self) -> bool {
        self.part.nodes.is_empty()
            && self.part.mesh.is_none()
            && self.deleted_nodes.is_empty()
            && self.deleted_edges.is_empty()
    }
}

/// Every edge of a graph by unordered pair, with its kind.
fn edge_map(g: &DsgGraph) -> FxHashMap<(u64, u64), (u64, u64, EdgeKind)> {
    part_edge_list(g)
        .into_iter()
        .map(|(a, b, k)| (pair(a, b), (a, b, k)))
        .collect()
}

fn same_kind(a: EdgeKind, b: EdgeKind) -> bool {
    match (a, b) {
        (EdgeKind::Intra(x), EdgeKind::Intra(y)) | (EdgeKind::Sibling(x), EdgeKind::Sibling(y)) => {
            x.map(f64::to_bits) == y.map(f64::to_bits)
        }
        (EdgeKind::Parent, EdgeKind::Parent) => true,
        _ => false,
    }
}

/// The incremental update that takes `previous` to `next`: `apply_update` of it on
/// `previous` gives `next`'s nodes, edges, mesh and labelspaces (new nodes at the end).
/// The part holds each node that changed or is new, and each node an added edge joins.
///
/// # Examples
/// ```
/// use ygg_dsg::office::{generate, OfficeParams};
/// let before = generate(OfficeParams { seed: 1, scale: 0.01 });
/// let mut after = before.clone();
/// after.nodes[3].position[2] += 0.5;
/// let update = ygg_dsg::update_between(&before, &after);
/// assert_eq!(update.part.nodes.len(), 1);
/// let mut g = before.clone();
/// g.apply_update(update.part, &update.deleted_nodes, &update.deleted_edges)?;
/// assert_eq!(g, after);
/// # Ok::<(), ygg_dsg::UpdateError>(())
/// ```
pub fn update_between(previous: &DsgGraph, next: &DsgGraph) -> GraphUpdate {
    let before = previous.node_index();
    let after = next.node_index();
    let deleted_nodes: Vec<u64> = previous
        .nodes
        .iter()
        .filter(|n| !after.contains_key(&n.id))
        .map(|n| n.id)
        .collect();
    let (old_edges, new_edges) = (edge_map(previous), edge_map(next));
    let mut deleted_edges = Vec::new();
    for (p, &(a, b, kind)) in &old_edges {
        let survives = after.contains_key(&a) && after.contains_key(&b);
        let kept = new_edges
            .get(p)
            .is_some_and(|&(_, _, k)| same_kind(k, kind));
        if survives && !kept {
            deleted_edges.extend([a, b]);
        }
    }
    let added: Vec<(u64, u64, EdgeKind)> = new_edges
        .iter()
        .filter(|(p, (_, _, k))| !old_edges.get(*p).is_some_and(|&(_, _, o)| same_kind(o, *k)))
        .map(|(_, &e)| e)
        .collect();
    let mut in_part: FxHashSet<u64> = FxHashSet::default();
    for n in &next.nodes {
        let changed = before.get(&n.id).is_none_or(|&i| {
            let old = &previous.nodes[i];
            DsgNode {
                parent: n.parent,
                ..old.clone()
            } != *n
        });
        if changed {
            in_part.insert(n.id);
        }
    }
    for &(a, b, _) in &added {
        in_part.extend([a, b]);
    }
    let new_parent_edges: FxHashSet<(u64, u64)> = added
        .iter()
        .filter(|(_, _, k)| matches!(k, EdgeKind::Parent))
        .map(|&(a, b, _)| (a, b))
        .collect();
    let mut part = DsgGraph {
        source: next.source.clone(),
        version: next.version,
        layers: next.layers.clone(),
        labelspaces: next.labelspaces.clone(),
        mesh: (next.mesh != previous.mesh)
            .then(|| next.mesh.clone())
            .flatten(),
        ..DsgGraph::default()
    };
    // Part nodes in `next`'s order; a node's parent only when that edge is new.
    for n in next.nodes.iter().filter(|n| in_part.contains(&n.id)) {
        let parent = n.parent.filter(|&p| new_parent_edges.contains(&(p, n.id)));
        part.nodes.push(DsgNode {
            parent,
            ..n.clone()
        });
    }
    for (a, b, kind) in added {
        match kind {
            EdgeKind::Intra(weight) => part.edges.push(DsgEdge {
                source: a,
                target: b,
                weight,
            }),
            EdgeKind::Sibling(weight) => part.sibling_edges.push(DsgEdge {
                source: a,
                target: b,
                weight,
            }),
            EdgeKind::Parent if next.nodes[after[&b]].parent == Some(a) => {}
            EdgeKind::Parent => part.extra_parent_edges.push(DsgParentEdge {
                parent: a,
                child: b,
            }),
        }
    }
    GraphUpdate {
        part,
        deleted_nodes,
        deleted_edges,
    }
}
