//! Bringing a live graph to equal another one with the fewest mutations:
//! [`SceneGraph::sync_to`].
//!
//! A source that sends the whole graph every time (Spark-DSG's ZMQ stream, a file that
//! is saved again) is turned into the few mutations that tell its versions apart, so
//! that the change journal names only what changed and a publish resends only the
//! layers touched.
//!
//! Layers are matched by name (their ids may differ between the two graphs), nodes by
//! id. A node whose content is the same in both graphs is never touched, so its layer
//! keeps its generation unless another node of the layer changes.

use super::scene_graph::Node;
use super::spatial_indexes::{AdoptedTrees, IndexScope};
use crate::feature::StoredValue;
use crate::index::{LiveIndexes, OverlaidTree};
use crate::{EditResult, FeatureValue, LayerId, NodeId, SceneGraph};
use rustc_hash::{FxHashMap, FxHashSet};

/// What [`SceneGraph::sync_to`] changed.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SyncReport {
    /// Layers added (by name).
    pub layers_added: usize,
    /// Layers removed (with the nodes left in them).
    pub layers_removed: usize,
    /// DAG edges added.
    pub layer_edges_added: usize,
    /// DAG edges removed.
    pub layer_edges_removed: usize,
    /// Nodes added.
    pub nodes_added: usize,
    /// Nodes removed.
    pub nodes_removed: usize,
    /// Nodes moved to another layer (removed, then added to their new layer).
    pub nodes_moved: usize,
    /// Nodes present before and after whose geometry, features, labels, edges, nesting
    /// or bounding-box flag changed.
    pub nodes_changed: usize,
    /// Layer and node indexes enabled or disabled.
    pub indexes_changed: usize,
    /// Names of the layers whose content changed (new layers included), sorted: the
    /// layers the next publish resends.
    pub changed_layers: Vec<String>,
}

impl SyncReport {
    /// Whether the graph already equalled the target.
    pub fn is_empty(&self) -> bool {
        self.changed_layers.is_empty()
            && self.layers_removed == 0
            && self.layer_edges_added == 0
            && self.layer_edges_removed == 0
    }
}

impl SceneGraph {
    /// Whether node `id` has its bounding box enabled (`None` for an unknown node).
    pub fn bounding_box_enabled(&self, id: NodeId) -> Option<bool> {
        self.nodes.get(&id).map(|n| n.bbox_enabled)
    }

    /// Applies to this graph the mutations that make it equal `target`: the same layers
    /// (by name) and DAG edges, the same nodes (by id) in the same layers, with the same
    /// geometry, features, labels, edges, nesting and bounding-box flags, and the same
    /// layer and node indexes enabled. Only what differs is changed: a node equal in
    /// both graphs is not touched, and a layer none of whose nodes changed keeps its
    /// generation (so [`crate::snapshot::SegmentCache`] and the writer do not resend it).
    /// A node that moves to another layer is removed and added again, so the rows that
    /// name it (its parent's and children's) are rewritten even where their content reads
    /// the same.
    ///
    /// Label sets and feature maps are compared as sets; floats are compared bit for bit.
    /// Layer ids are this graph's: a layer new to it gets a fresh id.
    ///
    /// Cost: one pass over both graphs' nodes (comparing each node's content), plus the
    /// mutations themselves.
    ///
    /// # Errors
    /// None for a `target` that holds the store's invariants (every `SceneGraph` does);
    /// an error would mean a bug, and leaves this graph partly synced (still valid).
    pub fn sync_to(&mut self, target: &SceneGraph) -> EditResult<SyncReport> {
        self.sync(target, &IndexSet::of(&target.indexes), None)
    }

    /// [`Self::sync_to`], taking `target`: an index whose points change much here (a
    /// quarter of them or more) or that is new here takes over the target's tree
    /// (remapping its items, O(points)) instead of being built again (O(points log
    /// points)). For a caller that builds a graph only to sync to it (the bridge does,
    /// per message).
    ///
    /// # Errors
    /// As [`Self::sync_to`].
    pub fn sync_to_owned(&mut self, mut target: SceneGraph) -> EditResult<SyncReport> {
        let indexes = std::mem::take(&mut target.indexes);
        let wanted = IndexSet::of(&indexes);
        self.sync(&target, &wanted, Some(AdoptedTrees::new(indexes)))
    }

    /// [`Self::sync_to`] with the indexes the target has (`wanted`), and its trees to
    /// adopt, if given.
    fn sync(
        &mut self,
        target: &SceneGraph,
        wanted: &IndexSet,
        mut adopted: Option<AdoptedTrees>,
    ) -> EditResult<SyncReport> {
        let mut report = SyncReport::default();
        let before: FxHashMap<LayerId, (u64, u64)> = self
            .layers
            .iter()
            .map(|(&id, l)| (id, (l.incarnation, l.generation)))
            .collect();

        // 1. Layers new to this graph.
        for tl in target.layers.values() {
            if !self.layer_names.contains_key(&tl.name) {
                self.add_layer(&tl.name)?;
                report.layers_added += 1;
            }
        }
        let map: FxHashMap<LayerId, LayerId> = target
            .layers
            .iter()
            .map(|(&tid, tl)| (tid, self.layer_names[&tl.name]))
            .collect();
        let target_layer_of = |name: &str| target.layer_names.get(name).copied();

        // 2. Indexes the target does not have (disabled first: no upkeep during the edits).
        let layer_indexes: Vec<LayerId> = self.indexes.layers.keys().copied().collect();
        for l in layer_indexes {
            let keep = target_layer_of(&self.layers[&l].name)
                .is_some_and(|tl| wanted.layers.contains(&tl));
            if !keep {
                self.disable_layer_index(l)?;
                report.indexes_changed += 1;
            }
        }
        let node_indexes: Vec<NodeId> = self.indexes.nodes.keys().copied().collect();
        for n in node_indexes {
            if !wanted.roots.contains(&n) {
                self.disable_node_index(n)?;
                report.indexes_changed += 1;
            }
        }

        // 3. Nodes the target lacks, or has in another layer.
        let mut moved = FxHashSet::default();
        let stale: Vec<NodeId> = self
            .nodes
            .values()
            .filter_map(|n| match target.nodes.get(&n.id) {
                None => Some(n.id),
                Some(t) if map[&t.layer] != n.layer => {
                    moved.insert(n.id);
                    Some(n.id)
                }
                Some(_) => None,
            })
            .collect();
        report.nodes_moved = moved.len();
        report.nodes_removed = stale.len() - moved.len();
        for id in stale {
            self.remove_node(id)?;
        }

        // 4. Layers the target lacks (empty by now, but for their DAG edges).
        let gone: Vec<LayerId> = self
            .layers
            .iter()
            .filter(|(_, l)| !target.layer_names.contains_key(&l.name))
            .map(|(&id, _)| id)
            .collect();
        for l in gone {
            self.remove_layer(l)?;
            report.layers_removed += 1;
        }

        // 5. Nestings and edges the target lacks (before the DAG edges they may use).
        let mut changed: FxHashSet<NodeId> = FxHashSet::default();
        let kept: FxHashSet<NodeId> = self.nodes.keys().copied().collect();
        for &id in &kept {
            let (node, t) = (&self.nodes[&id], &target.nodes[&id]);
            if node.parent.is_some() && node.parent != t.parent {
                self.unnest(id)?;
                changed.insert(id);
            }
            let node = &self.nodes[&id];
            let stale_edges: Vec<NodeId> = node
                .out_edges
                .iter()
                .filter(|&&(to, d)| {
                    t.out_edges
                        .binary_search_by_key(&to, |e| e.0)
                        .ok()
                        .is_none_or(|i| {
                            target.strings.resolve(t.out_edges[i].1) != self.strings.resolve(d)
                        })
                })
                .map(|e| e.0)
                .collect();
            for to in stale_edges {
                self.remove_edge(id, to)?;
                changed.insert(id);
            }
        }

        // 6. DAG edges: remove the target's missing ones, then add its new ones (a subset
        // of the target's DAG stays acyclic).
        let mut want: FxHashSet<(LayerId, LayerId)> = FxHashSet::default();
        for (&tid, tl) in &target.layers {
            for c in &tl.children {
                want.insert((map[&tid], map[c]));
            }
        }
        let have: Vec<(LayerId, LayerId)> = self
            .layers
            .iter()
            .flat_map(|(&p, l)| l.children.iter().map(move |&c| (p, c)))
            .collect();
        for &(p, c) in &have {
            if !want.contains(&(p, c)) {
                self.remove_layer_edge(p, c)?;
                report.layer_edges_removed += 1;
            }
        }
        let have: FxHashSet<(LayerId, LayerId)> = have.into_iter().collect();
        for (&tid, tl) in &target.layers {
            for c in &tl.children {
                let edge = (map[&tid], map[c]);
                if !have.contains(&edge) {
                    self.add_layer_edge(edge.0, edge.1)?;
                    report.layer_edges_added += 1;
                }
            }
        }

        // 7. Nodes new to this graph (moved ones included), in the target's layer order.
        for (&tid, tl) in &target.layers {
            for &id in &tl.nodes {
                if !self.nodes.contains_key(&id) {
                    self.add_node(id, map[&tid])?;
                    if !moved.contains(&id) {
                        report.nodes_added += 1;
                    }
                }
            }
        }

        // 8. Content: geometry, features, labels, edges, nesting, boxes; the indexes that
        // are new, or that it changes by a quarter or more, are out of upkeep meanwhile.
        let replaced = self.indexes_to_replace(target, wanted, &map);
        self.suspend_indexes(replaced.iter().map(|r| r.index));
        for tl in target.layers.values() {
            for &id in &tl.nodes {
                if self.sync_node(target, &target.nodes[&id])? {
                    changed.insert(id);
                }
            }
        }

        // 9. The indexes replaced: the target's trees adopted, else built here.
        for r in replaced {
            let tree = adopted
                .as_mut()
                .and_then(|a| Some((a.take(r.in_target)?, a)));
            self.restore_index(r.index, r.new, tree);
            report.indexes_changed += usize::from(r.new);
        }

        // Nodes added in step 7 are counted there, not as changed.
        report.nodes_changed = changed.iter().filter(|id| kept.contains(id)).count();
        let mut names: Vec<String> = self
            .layers
            .iter()
            .filter(|(id, l)| before.get(id) != Some(&(l.incarnation, l.generation)))
            .map(|(_, l)| l.name.clone())
            .collect();
        names.sort_unstable();
        report.changed_layers = names;
        Ok(report)
    }

    /// The indexes step 8 of [`Self::sync`] leaves out of upkeep and step 9 puts back:
    /// those of `wanted` (the target's) that this graph lacks, and those of this graph
    /// whose points the step changes by at least a quarter of their entries (points
    /// that move, and the points of sub-trees nested under an indexed node), where
    /// one build costs less than patching point by point. `map`: target layer ids to
    /// this graph's. Called once every target node is here, in its layer, with no
    /// nesting the target lacks.
    fn indexes_to_replace(
        &self,
        target: &SceneGraph,
        wanted: &IndexSet,
        map: &FxHashMap<LayerId, LayerId>,
    ) -> Vec<ReplacedIndex> {
        let mut in_layers: FxHashMap<LayerId, usize> = FxHashMap::default();
        let mut in_roots: FxHashMap<NodeId, usize> = FxHashMap::default();
        for tl in target.layers.values() {
            for &id in &tl.nodes {
                let (t, node) = (&target.nodes[&id], &self.nodes[&id]);
                if !same_points(&node.points, &t.points) {
                    let n = node.points.len() + t.points.len();
                    if self.indexes.layers.contains_key(&node.layer) {
                        *in_layers.entry(node.layer).or_default() += n;
                    }
                    for r in self.indexed_ancestors(id) {
                        *in_roots.entry(r).or_default() += n;
                    }
                }
                if let Some(p) = t.parent
                    && node.parent.is_none()
                {
                    let roots = self.indexed_ancestors(p);
                    if !roots.is_empty() {
                        let n = self.subtree_point_count(id);
                        for r in roots {
                            *in_roots.entry(r).or_default() += n;
                        }
                    }
                }
            }
        }
        let heavy = |tree: Option<&OverlaidTree>, changes: usize| {
            tree.is_some_and(|t| changes > 0 && 4 * changes >= t.len())
        };
        let mut replaced: Vec<ReplacedIndex> = wanted
            .layers
            .iter()
            .filter_map(|tl| {
                let l = map[tl];
                let tree = self.indexes.layers.get(&l);
                let changes = in_layers.get(&l).copied().unwrap_or(0);
                (tree.is_none() || heavy(tree, changes)).then_some(ReplacedIndex {
                    index: IndexScope::Layer(l),
                    in_target: IndexScope::Layer(*tl),
                    new: tree.is_none(),
                })
            })
            .collect();
        replaced.extend(wanted.roots.iter().filter_map(|&n| {
            let tree = self.indexes.nodes.get(&n);
            let changes = in_roots.get(&n).copied().unwrap_or(0);
            (tree.is_none() || heavy(tree, changes)).then_some(ReplacedIndex {
                index: IndexScope::Root(n),
                in_target: IndexScope::Root(n),
                new: tree.is_none(),
            })
        }));
        replaced.sort_unstable_by_key(|r| r.index);
        replaced
    }

    /// Points in `root`'s sub-tree (`root` included).
    fn subtree_point_count(&self, root: NodeId) -> usize {
        let mut count = 0;
        let mut stack = vec![root];
        while let Some(id) = stack.pop() {
            let n = &self.nodes[&id];
            count += n.points.len();
            stack.extend(n.children.iter().copied());
        }
        count
    }

    /// Makes the content of node `t.id` (which exists, in the right layer, with no
    /// nesting or edge the target lacks) equal `t`'s. Returns whether anything changed.
    fn sync_node(&mut self, target: &SceneGraph, t: &Node) -> EditResult<bool> {
        let id = t.id;
        let mut changed = false;
        let node = &self.nodes[&id];
        if !same_points(&node.points, &t.points) {
            self.set_geometry(id, t.points.clone())?;
            changed = true;
        }
        // Features: remove the target's missing keys, set the differing values.
        let node = &self.nodes[&id];
        let stale: Vec<String> = node
            .features
            .iter()
            .map(|(k, _)| self.strings.resolve(*k))
            .filter(|k| {
                target
                    .strings
                    .get(k)
                    .is_none_or(|tk| !t.features.iter().any(|f| f.0 == tk))
            })
            .map(str::to_owned)
            .collect();
        for k in &stale {
            self.remove_feature(id, k)?;
            changed = true;
        }
        for (tk, tv) in &t.features {
            let key = target.strings.resolve(*tk);
            let node = &self.nodes[&id];
            let same = self.strings.get(key).is_some_and(|k| {
                node.features
                    .iter()
                    .find(|f| f.0 == k)
                    .is_some_and(|f| same_value(self, &f.1, target, tv))
            });
            if !same {
                let value = match *tv {
                    StoredValue::Str(s) => FeatureValue::Str(target.strings.resolve(s).to_owned()),
                    StoredValue::Int(v) => FeatureValue::Int(v),
                    StoredValue::Float(v) => FeatureValue::Float(v),
                    StoredValue::Bool(v) => FeatureValue::Bool(v),
                };
                self.set_feature(id, key, value)?;
                changed = true;
            }
        }
        // Labels, as sets.
        let node = &self.nodes[&id];
        let stale: Vec<String> = node
            .labels
            .iter()
            .map(|&s| self.strings.resolve(s))
            .filter(|s| {
                target
                    .strings
                    .get(s)
                    .is_none_or(|ts| !t.labels.contains(&ts))
            })
            .map(str::to_owned)
            .collect();
        for s in &stale {
            self.remove_label(id, s)?;
            changed = true;
        }
        for &ts in &t.labels {
            let label = target.strings.resolve(ts);
            let node = &self.nodes[&id];
            if !self
                .strings
                .get(label)
                .is_some_and(|s| node.labels.contains(&s))
            {
                self.add_label(id, label)?;
                changed = true;
            }
        }
        // Edges the target has (the stale ones are gone; every node exists by now).
        for &(to, d) in &t.out_edges {
            let node = &self.nodes[&id];
            if node.out_edges.binary_search_by_key(&to, |e| e.0).is_err() {
                self.add_edge(id, to, target.strings.resolve(d))?;
                changed = true;
            }
        }
        // Nesting (a differing parent was undone already).
        if let Some(p) = t.parent
            && self.nodes[&id].parent.is_none()
        {
            self.nest(p, id)?;
            changed = true;
        }
        let enabled = self.nodes[&id].bbox_enabled;
        if t.bbox_enabled != enabled {
            if t.bbox_enabled {
                self.enable_bounding_box(id)?;
            } else {
                self.disable_bounding_box(id)?;
            }
            changed = true;
        }
        Ok(changed)
    }
}

/// Which indexes a graph has: its layer indexes (by layer) and node indexes (by root).
struct IndexSet {
    layers: FxHashSet<LayerId>,
    roots: FxHashSet<NodeId>,
}

impl IndexSet {
    /// The indexes of `indexes`.
    fn of(indexes: &LiveIndexes) -> Self {
        IndexSet {
            layers: indexes.layers.keys().copied().collect(),
            roots: indexes.nodes.keys().copied().collect(),
        }
    }
}

/// An index [`SceneGraph::sync`] replaces rather than patches.
struct ReplacedIndex {
    /// The index here.
    index: IndexScope,
    /// The same index in the target (its layer id may differ).
    in_target: IndexScope,
    /// Whether this graph lacks it.
    new: bool,
}

/// Whether two point lists are equal bit for bit.
fn same_points(a: &[crate::Point], b: &[crate::Point]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(p, q)| (0..3).all(|i| p[i].to_bits() == q[i].to_bits()))
}

/// Whether feature value `av` of graph `a` equals `bv` of graph `b` (strings resolved,
/// floats bit for bit).
fn same_value(a: &SceneGraph, av: &StoredValue, b: &SceneGraph, bv: &StoredValue) -> bool {
    match (av, bv) {
        (StoredValue::Str(x), StoredValue::Str(y)) => {
            a.strings.resolve(*x) == b.strings.resolve(*y)
        }
        (StoredValue::Int(x), StoredValue::Int(y)) => x == y,
        (StoredValue::Float(x), StoredValue::Float(y)) => x.to_bits() == y.to_bits(),
        (StoredValue::Bool(x), StoredValue::Bool(y)) => x == y,
        _ => false,
    }
}
