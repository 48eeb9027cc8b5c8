//! The live spatial indexes of a [`SceneGraph`]: enabling and disabling them, and the
//! hooks every mutation calls to keep them exact.
//!
//! # Invariants (checked by [`SceneGraph::check_indexes`])
//! - A layer index holds exactly one live entry `(point, handle(node))` per point of
//!   every node of its layer.
//! - A node index holds exactly one such entry per point of every node in its root's
//!   sub-tree (the root included).
//! - Live entries are those of the kd-tree less the dead ones of nodes moved wholesale,
//!   plus those nodes' points in the overlay (see `OverlaidTree`).
//! - Handles are dense `u32`s naming nodes: a node's handle is stored in the node
//!   (`Node::index_handle`) and `ids[handle]` is the node.
//!
//! A node index changes when any node below its root changes, so the hooks touch the
//! root's layer: a node index is republished with its root's layer.

use super::change_journal::Change;
use super::point_change::PointChange;
use super::scene_graph::Node;
use crate::error::{EditResult, GraphEditError};
use crate::index::{Entry, LiveIndexes, LiveKdTree, Located, NO_HANDLE, OverlaidTree};
use crate::{LayerId, NodeId, Point, SceneGraph};

/// The index trees of another graph that this one takes over (see
/// [`SceneGraph::sync_to_owned`]): the trees, the nodes their handles name, and the
/// handles of those nodes here, found as the trees are adopted.
pub(crate) struct AdoptedTrees {
    /// The other graph's trees (taken out one by one).
    trees: LiveIndexes,
    /// `trees.ids`, the node of each of the other graph's handles.
    ids: Vec<NodeId>,
    /// This graph's handle for each of the other graph's handles (`NO_HANDLE`: not yet).
    mapped: Vec<u32>,
}

/// One index of a graph: a layer's, or the one rooted at a node.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum IndexScope {
    /// The layer index of this layer.
    Layer(LayerId),
    /// The node index rooted at this node.
    Root(NodeId),
}

impl AdoptedTrees {
    /// The other graph's tree of `index` (named by that graph's ids), taken out.
    pub(crate) fn take(&mut self, index: IndexScope) -> Option<OverlaidTree> {
        match index {
            IndexScope::Layer(l) => self.trees.layers.remove(&l),
            IndexScope::Root(r) => self.trees.nodes.remove(&r),
        }
    }

    /// Takes over the index trees of another graph.
    pub(crate) fn new(mut trees: LiveIndexes) -> Self {
        let ids = std::mem::take(&mut trees.ids);
        AdoptedTrees {
            trees,
            ids,
            mapped: Vec::new(),
        }
    }
}

/// An update that walks between 2 and this many tree paths locates them first, all at
/// once (see [`LiveKdTree::locate`]), if its trees hold at least
/// [`WARM_MIN_ENTRIES`] entries together. Larger updates are bulk edits that gain
/// little; smaller trees mostly sit in cache, where a separate walk only adds work
/// (measured on a move, walking alone: +30% in one 10k-point index, −5 to −12% in one
/// 1M-point index, −19 to −29% in two; the located inserts and removes that skip their
/// own descent took another 13% and 19% off at 1M points).
const WARM_LIMIT: usize = 32;
/// See [`WARM_LIMIT`]: 2^17 entries are 2.5 MB of leaves, well past a 512 KiB L2 cache.
const WARM_MIN_ENTRIES: usize = 1 << 17;

impl SceneGraph {
    /// Enables the layer index of `layer`: a kd-tree over every point of the layer, kept
    /// exact by every later mutation. [`crate::query::nearest_nodes`] and
    /// [`crate::query::nodes_within_radius`] use it at layer and graph scope, and
    /// snapshots carry it. Enabling an enabled index does nothing.
    ///
    /// Cost: building is O(n log n) for the layer's n points; afterwards every change of
    /// a point in the layer costs one kd-tree update.
    ///
    /// # Errors
    /// [`GraphEditError::UnknownLayer`].
    pub fn enable_layer_index(&mut self, layer: LayerId) -> EditResult {
        if !self.layers.contains_key(&layer) {
            return Err(GraphEditError::UnknownLayer(layer));
        }
        if self.indexes.layers.contains_key(&layer) {
            return Ok(());
        }
        let tree = self.layer_tree(layer);
        self.indexes.layers.insert(layer, tree);
        self.touch_layer(layer, Change::All);
        Ok(())
    }

    /// A tree over every point of `layer` (which exists), handles allocated as needed.
    fn layer_tree(&mut self, layer: LayerId) -> OverlaidTree {
        let l = &self.layers[&layer];
        let unhandled = l
            .nodes
            .iter()
            .filter(|id| {
                let n = &self.nodes[id];
                !n.points.is_empty() && n.index_handle == NO_HANDLE
            })
            .count();
        self.indexes.reserve_handles(unhandled);
        let mut entries = Vec::new();
        for id in &l.nodes {
            let node = self.nodes.get_mut(id).expect("listed");
            if !node.points.is_empty() {
                let h = self.indexes.handle(node.id, &mut node.index_handle);
                entries.extend(node.points.iter().map(|&p| Entry { p, item: h }));
            }
        }
        OverlaidTree::from_entries(entries)
    }

    /// Bytes held by the handle table of the live indexes: the map from the items
    /// their kd-trees store (`u32` handles) to node ids, one entry per node that has
    /// had points in an enabled index, shared by all live indexes of the graph. Not
    /// included in [`crate::index::SpatialIndex::memory_bytes`] of a live index.
    pub fn index_handle_bytes(&self) -> usize {
        self.indexes.ids.capacity() * std::mem::size_of::<NodeId>()
            + self.indexes.free.capacity() * std::mem::size_of::<u32>()
    }

    /// Disables the layer index of `layer` (nothing happens if it is not enabled).
    ///
    /// # Errors
    /// [`GraphEditError::UnknownLayer`].
    pub fn disable_layer_index(&mut self, layer: LayerId) -> EditResult {
        if !self.layers.contains_key(&layer) {
            return Err(GraphEditError::UnknownLayer(layer));
        }
        if self.indexes.layers.remove(&layer).is_some() {
            self.touch_layer(layer, Change::All);
        }
        Ok(())
    }

    /// Enables the node index of `node`: a kd-tree over every point in its sub-tree,
    /// kept exact as geometry changes below it and as nodes are nested under it or taken
    /// out. [`crate::query::nearest_in_subtree`] and [`crate::query::visible`] use it,
    /// and snapshots carry it in the segment of `node`'s layer (a publishing writer
    /// withholds the tree of a sub-tree of fewer than
    /// [`TREE_CHUNK_MIN_POINTS`](crate::snapshot::TREE_CHUNK_MIN_POINTS) points in a few
    /// nodes: readers walk it). Enabling an enabled index does nothing.
    ///
    /// # Errors
    /// [`GraphEditError::UnknownNode`].
    pub fn enable_node_index(&mut self, node: NodeId) -> EditResult {
        let layer = self
            .nodes
            .get(&node)
            .ok_or(GraphEditError::UnknownNode(node))?
            .layer;
        if self.indexes.nodes.contains_key(&node) {
            return Ok(());
        }
        let tree = self.node_tree(node);
        self.indexes.nodes.insert(node, tree);
        self.touch_layer(layer, Change::All);
        Ok(())
    }

    /// A tree over every point in `root`'s sub-tree (`root` exists), handles allocated as
    /// needed.
    fn node_tree(&mut self, root: NodeId) -> OverlaidTree {
        let members = self.indexed_members(root);
        let unhandled = members
            .iter()
            .filter(|(id, _)| self.nodes[id].index_handle == NO_HANDLE)
            .count();
        self.indexes.reserve_handles(unhandled);
        let mut entries = Vec::new();
        for (id, points) in members {
            let h = self.index_handle_of(id);
            entries.extend(points.into_iter().map(|p| Entry { p, item: h }));
        }
        OverlaidTree::from_entries(entries)
    }

    /// Takes `indexes` out of upkeep, for an edit that changes much of them: mutations
    /// skip them until [`Self::restore_index`] puts them back (built again, or adopted).
    /// Nothing is journaled: the edits journal their own changes.
    pub(crate) fn suspend_indexes(&mut self, indexes: impl IntoIterator<Item = IndexScope>) {
        for index in indexes {
            match index {
                IndexScope::Layer(l) => self.indexes.layers.remove(&l),
                IndexScope::Root(r) => self.indexes.nodes.remove(&r),
            };
        }
    }

    /// Puts back `index` (whose layer or root exists), suspended or new: `adopted` (a tree
    /// over exactly its points from another graph, see [`AdoptedTrees`]), else a tree
    /// built here. A new index is journaled as enabling it journals it; a suspended layer
    /// index needs nothing more (the point changes are journaled), a suspended node index
    /// its root's change.
    pub(crate) fn restore_index(
        &mut self,
        index: IndexScope,
        new: bool,
        adopted: Option<(OverlaidTree, &mut AdoptedTrees)>,
    ) {
        let tree = match (adopted, index) {
            (Some((tree, from)), _) => self.adopt(tree, from),
            (None, IndexScope::Layer(l)) => self.layer_tree(l),
            (None, IndexScope::Root(r)) => self.node_tree(r),
        };
        let (layer, change) = match index {
            IndexScope::Layer(l) => {
                self.indexes.layers.insert(l, tree);
                (l, new.then_some(Change::All))
            }
            IndexScope::Root(r) => {
                self.indexes.nodes.insert(r, tree);
                let change = if new {
                    Change::All
                } else {
                    Change::IndexRoot(r)
                };
                (self.nodes[&r].layer, Some(change))
            }
        };
        if let Some(change) = change {
            self.touch_layer(layer, change);
        }
    }

    /// `tree`, built by another graph, with its items remapped to this graph's handles
    /// of the same nodes (which all exist here).
    fn adopt(&mut self, mut tree: OverlaidTree, from: &mut AdoptedTrees) -> OverlaidTree {
        let (nodes, indexes) = (&mut self.nodes, &mut self.indexes);
        from.mapped.resize(from.ids.len(), NO_HANDLE);
        tree.map_items(|h| {
            let mapped = &mut from.mapped[h as usize];
            if *mapped == NO_HANDLE {
                let id = from.ids[h as usize];
                let node = nodes
                    .get_mut(&id)
                    .expect("the other graph's nodes exist here");
                *mapped = indexes.handle(id, &mut node.index_handle);
            }
            *mapped
        });
        tree
    }

    /// Disables the node index of `node` (nothing happens if it is not enabled).
    ///
    /// # Errors
    /// [`GraphEditError::UnknownNode`].
    pub fn disable_node_index(&mut self, node: NodeId) -> EditResult {
        let layer = self
            .nodes
            .get(&node)
            .ok_or(GraphEditError::UnknownNode(node))?
            .layer;
        if self.indexes.nodes.remove(&node).is_some() {
            self.touch_layer(layer, Change::All);
        }
        Ok(())
    }

    /// The index handle of node `id` (which exists), allocated on first use.
    fn index_handle_of(&mut self, id: NodeId) -> u32 {
        let node = self.nodes.get_mut(&id).expect("indexed node exists");
        self.indexes.handle(id, &mut node.index_handle)
    }

    /// Points in the node index rooted at `root` (0 if there is none), in O(1).
    pub(crate) fn indexed_points(&self, root: NodeId) -> usize {
        self.indexes.nodes.get(&root).map_or(0, |tree| tree.len())
    }

    /// How many nodes with points `root`'s sub-tree holds, counting no further than
    /// `cap`.
    pub(crate) fn indexed_member_count(&self, root: NodeId, cap: usize) -> usize {
        let mut count = 0;
        let mut stack = vec![root];
        while let Some(id) = stack.pop() {
            let n = &self.nodes[&id];
            count += usize::from(!n.points.is_empty());
            if count >= cap {
                break;
            }
            stack.extend(n.children.iter().copied());
        }
        count
    }

    /// The nodes with points in `root`'s sub-tree, with their points.
    pub(crate) fn indexed_members(&self, root: NodeId) -> Vec<(NodeId, Vec<Point>)> {
        let mut out = Vec::new();
        let mut stack = vec![root];
        while let Some(id) = stack.pop() {
            let n = &self.nodes[&id];
            if !n.points.is_empty() {
                out.push((id, n.points.clone()));
            }
            stack.extend(n.children.iter().copied());
        }
        out
    }

    /// Roots of node indexes on the path from `from` to the top (`from` included).
    pub(crate) fn indexed_ancestors(&self, from: NodeId) -> Vec<NodeId> {
        let mut roots = Vec::new();
        if self.indexes.nodes.is_empty() {
            return roots;
        }
        let mut cur = Some(from);
        while let Some(n) = cur {
            if self.indexes.nodes.contains_key(&n) {
                roots.push(n);
            }
            cur = self.nodes[&n].parent;
        }
        roots
    }

    /// Hook: `id`'s points change as `change` says (the node may not hold its new points
    /// yet: they are read from `change`).
    pub(crate) fn index_geometry_changed(&mut self, id: NodeId, change: &PointChange<'_>) {
        if self.indexes.is_empty() {
            return;
        }
        let layer = self.nodes[&id].layer;
        let roots = self.indexed_ancestors(id);
        let has_layer = self.indexes.layers.contains_key(&layer);
        if roots.is_empty() && !has_layer {
            return;
        }
        let h = self.index_handle_of(id);
        let (removed, added) = change.changed();
        let per_tree = removed.len() + added.len();
        let paths = per_tree * (roots.len() + usize::from(has_layer));
        let mut located = [Located::default(); WARM_LIMIT];
        let mut is_located = false;
        if (2..=WARM_LIMIT).contains(&paths) {
            let trees: Vec<&LiveKdTree> = self
                .indexes
                .layers
                .get(&layer)
                .map(OverlaidTree::tree)
                .into_iter()
                .chain(roots.iter().map(|r| self.indexes.nodes[r].tree()))
                .collect();
            if trees.iter().map(|t| t.len()).sum::<usize>() >= WARM_MIN_ENTRIES {
                LiveKdTree::locate(&trees, &[removed, added], &mut located[..paths]);
                is_located = true;
            }
        }
        // Tree `k` (the layer index first, then the node indexes of `roots`, as located).
        let located_in = |k: usize| is_located.then(|| &located[k * per_tree..(k + 1) * per_tree]);
        let mut k = 0;
        if let Some(t) = self.indexes.layers.get_mut(&layer) {
            t.apply(h, change, located_in(k));
            k += 1;
        }
        for &r in &roots {
            let t = self.indexes.nodes.get_mut(&r).expect("listed");
            t.apply(h, change, located_in(k));
            k += 1;
        }
        for r in roots {
            let rl = self.nodes[&r].layer;
            self.touch_layer(rl, Change::IndexRoot(r));
        }
    }

    /// Hook: `child`'s sub-tree was nested under `parent`.
    pub(crate) fn index_nested(&mut self, parent: NodeId, child: NodeId) {
        self.index_subtree_moved(parent, child, true);
    }

    /// Hook: `child`'s sub-tree was taken out from under `old_parent`.
    pub(crate) fn index_unnested(&mut self, old_parent: NodeId, child: NodeId) {
        self.index_subtree_moved(old_parent, child, false);
    }

    fn index_subtree_moved(&mut self, parent: NodeId, child: NodeId, added: bool) {
        let roots = self.indexed_ancestors(parent);
        if roots.is_empty() {
            return;
        }
        let moved: Vec<(u32, Vec<Point>)> = self
            .indexed_members(child)
            .into_iter()
            .map(|(id, points)| {
                let h = self.index_handle_of(id);
                (h, points)
            })
            .collect();
        let changes: Vec<(u32, PointChange)> = moved
            .iter()
            .map(|(h, points)| {
                let change = if added {
                    PointChange::new(&[], points)
                } else {
                    PointChange::new(points, &[])
                };
                (*h, change)
            })
            .collect();
        for r in roots {
            let t = self.indexes.nodes.get_mut(&r).expect("listed");
            for (h, change) in &changes {
                t.apply(*h, change, None);
            }
            let rl = self.nodes[&r].layer;
            self.touch_layer(rl, Change::IndexRoot(r));
        }
    }

    /// Hook: `node` was removed (its nestings were undone first, through the hooks).
    pub(crate) fn index_node_removed(&mut self, node: &Node) {
        if self.indexes.is_empty() {
            return;
        }
        self.indexes.nodes.remove(&node.id);
        if node.index_handle != NO_HANDLE
            && let Some(t) = self.indexes.layers.get_mut(&node.layer)
        {
            t.apply(
                node.index_handle,
                &PointChange::new(&node.points, &[]),
                None,
            );
        }
        self.indexes.release(node.index_handle);
    }

    /// Hook: `layer` is being removed (before its nodes are).
    pub(crate) fn index_layer_removed(&mut self, layer: LayerId) {
        self.indexes.layers.remove(&layer);
    }

    /// Checks the invariants in the module docs: every live index holds exactly the
    /// points it covers. Meant for tests; it scans every indexed point.
    ///
    /// # Errors
    /// A description of the first index that differs from its scope.
    pub fn check_indexes(&self) -> Result<(), String> {
        let expect = |members: Vec<(NodeId, Vec<Point>)>| {
            let mut v: Vec<(u64, [u32; 3])> = members
                .into_iter()
                .flat_map(|(id, ps)| ps.into_iter().map(move |p| (id.0, p.map(f32::to_bits))))
                .collect();
            v.sort_unstable();
            v
        };
        let actual = |t: &OverlaidTree| -> Result<Vec<(u64, [u32; 3])>, String> {
            let mut v = Vec::with_capacity(t.len());
            for e in t.entries() {
                let id = self.indexes.ids.get(e.item as usize).copied();
                match id {
                    Some(id) if self.nodes.get(&id).map(|n| n.index_handle) == Some(e.item) => {
                        v.push((id.0, e.p.map(f32::to_bits)));
                    }
                    _ => return Err(format!("entry with stale handle {}", e.item)),
                }
            }
            v.sort_unstable();
            Ok(v)
        };
        for (&layer, t) in &self.indexes.layers {
            let l = self
                .layers
                .get(&layer)
                .ok_or(format!("index of missing layer {layer}"))?;
            let members = l
                .nodes
                .iter()
                .map(|id| (*id, self.nodes[id].points.clone()))
                .collect();
            if actual(t)? != expect(members) {
                return Err(format!("layer index of {layer} differs from its points"));
            }
        }
        for (&root, t) in &self.indexes.nodes {
            if !self.nodes.contains_key(&root) {
                return Err(format!("index of missing node {root}"));
            }
            if actual(t)? != expect(self.indexed_members(root)) {
                return Err(format!("node index of {root} differs from its sub-tree"));
            }
        }
        Ok(())
    }
}
