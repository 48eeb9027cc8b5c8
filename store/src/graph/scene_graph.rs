//! [`SceneGraph`] and [`Node`]: the live graph's storage (layers, nodes, strings, the
//! inverted label and key indexes) and its mutations. The invariants they keep are listed
//! in the [`crate::graph`] module docs.

use super::change_journal::{Change, LayerChanges};
use super::point_change::PointChange;
use super::touch_log::{TouchLog, TouchMark};
use crate::error::{EditResult, GraphEditError};
use crate::feature::{FeatureValue, Interner, StoredValue, Sym};
use crate::index::LiveIndexes;
use crate::{Aabb, LayerId, NodeId, Point};
use rustc_hash::{FxHashMap, FxHashSet};
use std::collections::BTreeMap;

/// One node of the live graph.
#[derive(Clone, Debug)]
pub struct Node {
    pub(crate) id: NodeId,
    pub(crate) layer: LayerId,
    /// Position in the layer's node list.
    pub(crate) slot: u32,
    pub(crate) points: Vec<Point>,
    pub(crate) parent: Option<NodeId>,
    pub(crate) children: Vec<NodeId>,
    pub(crate) out_edges: Vec<(NodeId, Sym)>,
    pub(crate) in_edges: Vec<(NodeId, Sym)>,
    pub(crate) labels: Vec<Sym>,
    pub(crate) features: Vec<(Sym, StoredValue)>,
    pub(crate) bbox_enabled: bool,
    pub(crate) aabb: Option<Aabb>,
    /// With the box enabled: how many sub-tree points lie on each face of `aabb`
    /// (min x, y, z, then max x, y, z). A face moves inward only when its count drops
    /// to zero, so most removals and moves cost O(1) per enabled ancestor.
    pub(crate) face_counts: [u32; 6],
    /// With the box enabled: how many points its sub-tree holds (when a change removes
    /// all of them, the new box is the added points' own).
    pub(crate) box_points: u64,
    /// The node's handle in the live spatial indexes (`u32::MAX` until it has one).
    pub(crate) index_handle: u32,
}

/// One layer of the live graph.
#[derive(Clone, Debug)]
pub(crate) struct Layer {
    pub(crate) name: String,
    pub(crate) parents: Vec<LayerId>,
    pub(crate) children: Vec<LayerId>,
    pub(crate) nodes: Vec<NodeId>,
    /// Incremented on every change to the layer's archived content.
    pub(crate) generation: u64,
    pub(crate) label_postings: FxHashMap<Sym, FxHashSet<NodeId>>,
    pub(crate) key_postings: FxHashMap<Sym, FxHashSet<NodeId>>,
    /// What changed in the layer since the generation the journal starts from.
    pub(crate) changes: LayerChanges,
    /// Unique within the graph for each layer ever added (layer ids may be reused).
    pub(crate) incarnation: u64,
}

impl Layer {
    /// The smallest and largest node id (`u64::MAX` and 0 when empty).
    pub(crate) fn id_bounds(&self) -> (u64, u64) {
        self.nodes
            .iter()
            .fold((u64::MAX, 0), |(lo, hi), n| (lo.min(n.0), hi.max(n.0)))
    }

    /// Records a change of the layer's archived content: bumps the generation and notes
    /// the change in the journal.
    pub(crate) fn touch(&mut self, change: Change) {
        self.generation += 1;
        self.changes.record(change, self.nodes.len());
    }
}

/// A layered 3D scene graph that can be edited: the writer's live graph.
///
/// Start with [`SceneGraph::new`], add layers with [`SceneGraph::add_layer`] and
/// [`SceneGraph::add_layer_edge`], then nodes, geometry, features, edges and nestings.
/// Query it through [`crate::SceneView`] (the same queries run on archived snapshots).
#[derive(Clone, Debug, Default)]
pub struct SceneGraph {
    pub(crate) strings: Interner,
    pub(crate) layers: BTreeMap<LayerId, Layer>,
    pub(crate) layer_names: FxHashMap<String, LayerId>,
    next_layer: u32,
    pub(crate) nodes: FxHashMap<NodeId, Node>,
    pub(crate) label_layers: FxHashMap<Sym, Vec<LayerId>>,
    pub(crate) key_layers: FxHashMap<Sym, Vec<LayerId>>,
    /// Incremented when the layer set or the DAG changes.
    pub(crate) structure_generation: u64,
    /// Incremented when `label_layers` or `key_layers` changes.
    pub(crate) terms_generation: u64,
    /// Live spatial indexes (layer and node indexes), kept exact by every mutation.
    pub(crate) indexes: LiveIndexes,
    /// Which layers changed when, for [`SceneGraph::layers_touched_since`].
    pub(crate) touches: TouchLog,
}

/// Which inverted index a posting belongs to.
#[derive(Clone, Copy)]
enum Postings {
    Label,
    Key,
}

impl SceneGraph {
    /// An empty graph.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of nodes in the whole graph.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Number of layers.
    pub fn layer_count(&self) -> usize {
        self.layers.len()
    }

    /// The generation of a layer: it increases whenever the layer's content changes.
    pub fn layer_generation(&self, layer: LayerId) -> Option<u64> {
        self.layers.get(&layer).map(|l| l.generation)
    }

    /// The generation of the layer set and DAG.
    pub fn structure_generation(&self) -> u64 {
        self.structure_generation
    }

    /// A point after every change made so far, for [`SceneGraph::layers_touched_since`].
    pub fn touch_mark(&self) -> TouchMark {
        self.touches.mark()
    }

    /// The layers whose generation changed after `mark` (or that were added after it),
    /// ascending; removed layers are not listed. O(changes since the mark, amortised),
    /// whatever the number of layers: how a publisher finds what to send. `None` when
    /// `mark` is not this graph's (a mark of another graph, or taken before a clone).
    pub fn layers_touched_since(&self, mark: TouchMark) -> Option<Vec<LayerId>> {
        self.touches.touched_since(mark)
    }

    fn layer(&self, id: LayerId) -> EditResult<&Layer> {
        self.layers.get(&id).ok_or(GraphEditError::UnknownLayer(id))
    }

    fn node(&self, id: NodeId) -> EditResult<&Node> {
        self.nodes.get(&id).ok_or(GraphEditError::UnknownNode(id))
    }

    pub(crate) fn touch_layer(&mut self, layer: LayerId, change: Change) {
        if let Some(l) = self.layers.get_mut(&layer) {
            l.touch(change);
            self.touches.touch(layer);
        }
    }

    /// The change journal of `layer` (which exists), replaced by an empty one starting
    /// at the layer's current generation.
    pub(crate) fn take_layer_changes(&mut self, layer: LayerId) -> LayerChanges {
        let l = self.layers.get_mut(&layer).expect("layer exists");
        std::mem::replace(&mut l.changes, LayerChanges::new(l.generation))
    }

    // ---- layers -------------------------------------------------------------------

    /// Adds an empty layer named `name` and returns its id.
    ///
    /// # Errors
    /// [`GraphEditError::DuplicateLayerName`] if the name is taken.
    pub fn add_layer(&mut self, name: &str) -> EditResult<LayerId> {
        if self.layer_names.contains_key(name) {
            return Err(GraphEditError::DuplicateLayerName(name.to_owned()));
        }
        let id = LayerId(self.next_layer);
        self.insert_layer_with_id(id, name);
        Ok(id)
    }

    /// Adds a layer under a given id (used when copying a scene's layers).
    pub(crate) fn insert_layer_with_id(&mut self, id: LayerId, name: &str) {
        self.layers.insert(
            id,
            Layer {
                name: name.to_owned(),
                parents: Vec::new(),
                children: Vec::new(),
                nodes: Vec::new(),
                generation: 1,
                label_postings: FxHashMap::default(),
                key_postings: FxHashMap::default(),
                changes: LayerChanges::new(1),
                incarnation: self.structure_generation,
            },
        );
        self.layer_names.insert(name.to_owned(), id);
        self.next_layer = self.next_layer.max(id.0 + 1);
        self.structure_generation += 1;
        self.touches.touch(id);
    }

    /// The id of the layer named `name`.
    pub fn layer_id(&self, name: &str) -> EditResult<LayerId> {
        self.layer_names
            .get(name)
            .copied()
            .ok_or_else(|| GraphEditError::UnknownLayerName(name.to_owned()))
    }

    /// Removes a layer with all its nodes (their edges and nestings go with them) and
    /// its DAG edges.
    pub fn remove_layer(&mut self, id: LayerId) -> EditResult {
        let layer = self.layer(id)?;
        let nodes = layer.nodes.clone();
        let parents = layer.parents.clone();
        let children = layer.children.clone();
        self.index_layer_removed(id);
        for n in nodes {
            self.remove_node(n)
                .expect("node listed in its layer exists");
        }
        for p in parents {
            self.layers
                .get_mut(&p)
                .expect("DAG parent exists")
                .children
                .retain(|&c| c != id);
        }
        for c in children {
            self.layers
                .get_mut(&c)
                .expect("DAG child exists")
                .parents
                .retain(|&p| p != id);
        }
        let layer = self.layers.remove(&id).expect("checked above");
        self.layer_names.remove(&layer.name);
        self.structure_generation += 1;
        self.touches.forget(id);
        Ok(())
    }

    /// Adds the DAG edge `parent -> child`: `parent` encompasses `child`, and nodes of
    /// `parent` may then nest nodes of `child`.
    ///
    /// # Errors
    /// Unknown layers, an existing edge, or a cycle ([`GraphEditError::WouldCreateCycle`]).
    pub fn add_layer_edge(&mut self, parent: LayerId, child: LayerId) -> EditResult {
        self.layer(parent)?;
        let c = self.layer(child)?;
        if c.parents.contains(&parent) {
            return Err(GraphEditError::DuplicateLayerEdge { parent, child });
        }
        if parent == child || self.layer_reaches(child, parent) {
            return Err(GraphEditError::WouldCreateCycle { parent, child });
        }
        self.layers
            .get_mut(&parent)
            .expect("checked")
            .children
            .push(child);
        self.layers
            .get_mut(&child)
            .expect("checked")
            .parents
            .push(parent);
        self.structure_generation += 1;
        Ok(())
    }

    /// Whether `to` is reachable from `from` along DAG edges.
    pub(crate) fn layer_reaches(&self, from: LayerId, to: LayerId) -> bool {
        let mut stack = vec![from];
        let mut seen = FxHashSet::default();
        while let Some(l) = stack.pop() {
            if l == to {
                return true;
            }
            if seen.insert(l) {
                stack.extend(self.layers[&l].children.iter().copied());
            }
        }
        false
    }

    /// Removes the DAG edge `parent -> child`.
    ///
    /// # Errors
    /// [`GraphEditError::LayerEdgeInUse`] while nodes are nested along it.
    pub fn remove_layer_edge(&mut self, parent: LayerId, child: LayerId) -> EditResult {
        self.layer(parent)?;
        let c = self.layer(child)?;
        if !c.parents.contains(&parent) {
            return Err(GraphEditError::UnknownLayerEdge { parent, child });
        }
        let count = c
            .nodes
            .iter()
            .filter(|n| {
                self.nodes[n]
                    .parent
                    .is_some_and(|p| self.nodes[&p].layer == parent)
            })
            .count();
        if count > 0 {
            return Err(GraphEditError::LayerEdgeInUse {
                parent,
                child,
                count,
            });
        }
        self.layers
            .get_mut(&parent)
            .expect("checked")
            .children
            .retain(|&c| c != child);
        self.layers
            .get_mut(&child)
            .expect("checked")
            .parents
            .retain(|&p| p != parent);
        self.structure_generation += 1;
        Ok(())
    }

    // ---- nodes --------------------------------------------------------------------

    /// Adds a node with no geometry, features or relations to `layer`.
    ///
    /// # Errors
    /// Unknown layer, an id already in use, or the reserved id `u64::MAX`.
    pub fn add_node(&mut self, id: NodeId, layer: LayerId) -> EditResult {
        if id == NodeId::NONE {
            return Err(GraphEditError::ReservedNodeId(id));
        }
        let l = self
            .layers
            .get_mut(&layer)
            .ok_or(GraphEditError::UnknownLayer(layer))?;
        let entry = match self.nodes.entry(id) {
            std::collections::hash_map::Entry::Occupied(_) => {
                return Err(GraphEditError::DuplicateNode(id));
            }
            std::collections::hash_map::Entry::Vacant(v) => v,
        };
        let slot = l.nodes.len() as u32;
        l.nodes.push(id);
        l.touch(Change::Node(id));
        self.touches.touch(layer);
        entry.insert(Node {
            id,
            layer,
            slot,
            points: Vec::new(),
            parent: None,
            children: Vec::new(),
            out_edges: Vec::new(),
            in_edges: Vec::new(),
            labels: Vec::new(),
            features: Vec::new(),
            bbox_enabled: false,
            aabb: None,
            face_counts: [0; 6],
            box_points: 0,
            index_handle: u32::MAX,
        });
        Ok(())
    }

    /// Removes a node, its edges (both directions) and its nesting. Its children stay,
    /// un-nested.
    pub fn remove_node(&mut self, id: NodeId) -> EditResult {
        let node = self.node(id)?;
        let children = node.children.clone();
        let out: Vec<NodeId> = node.out_edges.iter().map(|e| e.0).collect();
        let inc: Vec<NodeId> = node.in_edges.iter().map(|e| e.0).collect();
        for c in children {
            self.unnest(c).expect("child of an existing node");
        }
        if node_parent(self, id).is_some() {
            self.unnest(id).expect("nested node");
        }
        for t in out {
            self.remove_edge(id, t).expect("listed edge");
        }
        for s in inc {
            self.remove_edge(s, id).expect("listed edge");
        }
        let labels: Vec<Sym> = self.nodes[&id].labels.clone();
        let keys: Vec<Sym> = self.nodes[&id].features.iter().map(|f| f.0).collect();
        let node = self.nodes.remove(&id).expect("checked");
        for s in labels {
            self.unpost(node.layer, Postings::Label, s, id);
        }
        for s in keys {
            self.unpost(node.layer, Postings::Key, s, id);
        }
        let layer = self
            .layers
            .get_mut(&node.layer)
            .expect("node's layer exists");
        layer.nodes.swap_remove(node.slot as usize);
        if let Some(&moved) = layer.nodes.get(node.slot as usize) {
            self.nodes.get_mut(&moved).expect("listed").slot = node.slot;
        }
        layer.touch(Change::Removed {
            id,
            had_points: !node.points.is_empty(),
        });
        self.touches.touch(node.layer);
        self.index_node_removed(&node);
        Ok(())
    }

    /// Replaces a node's geometry (an empty vector removes it). This is how a node moves.
    /// Bounding boxes above it stay exact.
    ///
    /// # Errors
    /// Unknown node or a non-finite coordinate.
    pub fn set_geometry(&mut self, id: NodeId, points: Vec<Point>) -> EditResult {
        self.node(id)?;
        if let Some(index) = crate::id::first_non_finite(&points) {
            return Err(GraphEditError::NonFinitePoint { node: id, index });
        }
        let node = self.nodes.get_mut(&id).expect("checked");
        let old = std::mem::take(&mut node.points);
        let change = PointChange::new(&old, &points);
        let emptied = self.points_changing(id, &change);
        self.points_changed(id, points, emptied);
        Ok(())
    }

    /// Appends points to a node's geometry (a mesh growing): O(the appended points), where
    /// [`SceneGraph::set_geometry`] with the longer list compares it whole with the old
    /// one. Bounding boxes above the node stay exact.
    ///
    /// # Errors
    /// Unknown node or a non-finite coordinate (its index counts the node's points before
    /// it).
    pub fn append_points(&mut self, id: NodeId, points: &[Point]) -> EditResult {
        let had = self.node(id)?.points.len();
        if let Some(index) = crate::id::first_non_finite(points) {
            return Err(GraphEditError::NonFinitePoint {
                node: id,
                index: had + index,
            });
        }
        if points.is_empty() {
            return Ok(());
        }
        let node = self.nodes.get_mut(&id).expect("checked");
        let mut all = std::mem::take(&mut node.points);
        all.extend_from_slice(points);
        let change = PointChange::appended(&all, had);
        let emptied = self.points_changing(id, &change);
        self.points_changed(id, all, emptied);
        Ok(())
    }

    /// The boxes and indexes above `id` take `change` while the node holds no points
    /// (both read them from `change`); returns the boxes a face of which lost its last
    /// point, for [`Self::points_changed`].
    fn points_changing(&mut self, id: NodeId, change: &PointChange<'_>) -> Vec<NodeId> {
        let layer = self.nodes[&id].layer;
        self.touch_layer(
            layer,
            Change::Geometry {
                id,
                kept: change.kept(),
            },
        );
        let emptied = self.geometry_changed(id, change);
        self.index_geometry_changed(id, change);
        emptied
    }

    /// `id` takes its new points; then the boxes that lost a face's last point are
    /// recomputed from their sub-trees.
    fn points_changed(&mut self, id: NodeId, points: Vec<Point>, emptied: Vec<NodeId>) {
        self.nodes.get_mut(&id).expect("checked").points = points;
        self.recompute_boxes(emptied);
    }

    // ---- features and labels ------------------------------------------------------

    /// Sets feature `key` of a node (replacing an earlier value).
    ///
    /// # Errors
    /// Unknown node, or a NaN float.
    pub fn set_feature(&mut self, id: NodeId, key: &str, value: FeatureValue) -> EditResult {
        self.node(id)?;
        if matches!(value, FeatureValue::Float(v) if v.is_nan()) {
            return Err(GraphEditError::NanFeature {
                node: id,
                key: key.to_owned(),
            });
        }
        let k = self.strings.intern(key);
        let stored = match value {
            FeatureValue::Str(s) => StoredValue::Str(self.strings.intern(&s)),
            FeatureValue::Int(v) => StoredValue::Int(v),
            FeatureValue::Float(v) => StoredValue::Float(v),
            FeatureValue::Bool(v) => StoredValue::Bool(v),
        };
        let node = self.nodes.get_mut(&id).expect("checked");
        let layer = node.layer;
        match node.features.iter_mut().find(|f| f.0 == k) {
            Some(f) => f.1 = stored,
            None => {
                node.features.push((k, stored));
                self.post(layer, Postings::Key, k, id);
            }
        }
        self.touch_layer(layer, Change::Node(id));
        Ok(())
    }

    /// Removes feature `key` of a node.
    pub fn remove_feature(&mut self, id: NodeId, key: &str) -> EditResult {
        let missing = || GraphEditError::UnknownFeature {
            node: id,
            key: key.to_owned(),
        };
        let node = self.node(id)?;
        let k = self.strings.get(key).ok_or_else(missing)?;
        let at = node
            .features
            .iter()
            .position(|f| f.0 == k)
            .ok_or_else(missing)?;
        let node = self.nodes.get_mut(&id).expect("checked");
        node.features.remove(at);
        let layer = node.layer;
        self.unpost(layer, Postings::Key, k, id);
        self.touch_layer(layer, Change::Node(id));
        Ok(())
    }

    /// Adds a label to a node's label set (no effect if already there).
    pub fn add_label(&mut self, id: NodeId, label: &str) -> EditResult {
        self.node(id)?;
        let s = self.strings.intern(label);
        let node = self.nodes.get_mut(&id).expect("checked");
        if node.labels.contains(&s) {
            return Ok(());
        }
        node.labels.push(s);
        let layer = node.layer;
        self.post(layer, Postings::Label, s, id);
        self.touch_layer(layer, Change::Node(id));
        Ok(())
    }

    /// Removes a label from a node's label set.
    pub fn remove_label(&mut self, id: NodeId, label: &str) -> EditResult {
        let missing = || GraphEditError::UnknownLabel {
            node: id,
            label: label.to_owned(),
        };
        let node = self.node(id)?;
        let s = self.strings.get(label).ok_or_else(missing)?;
        let at = node
            .labels
            .iter()
            .position(|&l| l == s)
            .ok_or_else(missing)?;
        let node = self.nodes.get_mut(&id).expect("checked");
        node.labels.remove(at);
        let layer = node.layer;
        self.unpost(layer, Postings::Label, s, id);
        self.touch_layer(layer, Change::Node(id));
        Ok(())
    }

    fn post(&mut self, layer: LayerId, which: Postings, term: Sym, id: NodeId) {
        let l = self.layers.get_mut(&layer).expect("node's layer exists");
        let (map, graph_map) = match which {
            Postings::Label => (&mut l.label_postings, &mut self.label_layers),
            Postings::Key => (&mut l.key_postings, &mut self.key_layers),
        };
        let set = map.entry(term).or_default();
        if set.is_empty() {
            graph_map.entry(term).or_default().push(layer);
            self.terms_generation += 1;
        }
        set.insert(id);
    }

    fn unpost(&mut self, layer: LayerId, which: Postings, term: Sym, id: NodeId) {
        let l = self.layers.get_mut(&layer).expect("node's layer exists");
        let (map, graph_map) = match which {
            Postings::Label => (&mut l.label_postings, &mut self.label_layers),
            Postings::Key => (&mut l.key_postings, &mut self.key_layers),
        };
        let Some(set) = map.get_mut(&term) else {
            return;
        };
        set.remove(&id);
        if set.is_empty() {
            map.remove(&term);
            self.terms_generation += 1;
            if let Some(ls) = graph_map.get_mut(&term) {
                ls.retain(|&x| x != layer);
                if ls.is_empty() {
                    graph_map.remove(&term);
                }
            }
        }
    }

    // ---- edges --------------------------------------------------------------------

    /// Adds the directed edge `source -> target` with a description. Both ends must be
    /// in the same layer.
    pub fn add_edge(&mut self, source: NodeId, target: NodeId, description: &str) -> EditResult {
        let s = self.node(source)?;
        let t = self.node(target)?;
        if source == target {
            return Err(GraphEditError::SelfLoop(source));
        }
        if s.layer != t.layer {
            return Err(GraphEditError::CrossLayerEdge {
                from: source,
                to: target,
                from_layer: s.layer,
                to_layer: t.layer,
            });
        }
        let at = match s.out_edges.binary_search_by_key(&target, |e| e.0) {
            Ok(_) => {
                return Err(GraphEditError::DuplicateEdge {
                    from: source,
                    to: target,
                });
            }
            Err(at) => at,
        };
        let layer = s.layer;
        let d = self.strings.intern(description);
        self.nodes
            .get_mut(&source)
            .expect("checked")
            .out_edges
            .insert(at, (target, d));
        let t = self.nodes.get_mut(&target).expect("checked");
        let at = t
            .in_edges
            .binary_search_by_key(&source, |e| e.0)
            .unwrap_or_else(|e| e);
        t.in_edges.insert(at, (source, d));
        self.touch_layer(layer, Change::Node(source));
        self.touch_layer(layer, Change::Node(target));
        Ok(())
    }

    /// Removes the edge `source -> target`.
    pub fn remove_edge(&mut self, source: NodeId, target: NodeId) -> EditResult {
        let s = self.node(source)?;
        self.node(target)?;
        let at = s
            .out_edges
            .binary_search_by_key(&target, |e| e.0)
            .map_err(|_| GraphEditError::UnknownEdge {
                from: source,
                to: target,
            })?;
        let layer = s.layer;
        self.nodes
            .get_mut(&source)
            .expect("checked")
            .out_edges
            .remove(at);
        let t = self.nodes.get_mut(&target).expect("checked");
        let at = t
            .in_edges
            .binary_search_by_key(&source, |e| e.0)
            .expect("mirrored edge");
        t.in_edges.remove(at);
        self.touch_layer(layer, Change::Node(source));
        self.touch_layer(layer, Change::Node(target));
        Ok(())
    }

    // ---- nesting ------------------------------------------------------------------

    /// Nests `child` under `parent`. The parent's layer must have a DAG edge to the
    /// child's layer, and the child must not have a parent yet.
    pub fn nest(&mut self, parent: NodeId, child: NodeId) -> EditResult {
        let p = self.node(parent)?;
        let c = self.node(child)?;
        if let Some(existing) = c.parent {
            return Err(GraphEditError::AlreadyNested {
                parent: existing,
                child,
            });
        }
        if !self.layers[&p.layer].children.contains(&c.layer) {
            return Err(GraphEditError::NestingOffDag {
                parent,
                child,
                parent_layer: p.layer,
                child_layer: c.layer,
            });
        }
        let cl = c.layer;
        let p = self.nodes.get_mut(&parent).expect("checked");
        let at = p.children.binary_search(&child).unwrap_or_else(|e| e);
        p.children.insert(at, child);
        self.nodes.get_mut(&child).expect("checked").parent = Some(parent);
        // Archived nesting lives on the child's side only (`LayerSegment::by_parent`):
        // the parent's layer changes only if its box or a node index does (below).
        self.touch_layer(cl, Change::Node(child));
        self.subtree_joined(parent, child);
        self.index_nested(parent, child);
        Ok(())
    }

    /// Removes `child` from its parent.
    pub fn unnest(&mut self, child: NodeId) -> EditResult {
        let c = self.node(child)?;
        let parent = c.parent.ok_or(GraphEditError::NotNested(child))?;
        let cl = c.layer;
        self.nodes.get_mut(&child).expect("checked").parent = None;
        let p = self.nodes.get_mut(&parent).expect("parent exists");
        let at = p.children.binary_search(&child).expect("mirrored nesting");
        p.children.remove(at);
        self.touch_layer(cl, Change::Node(child));
        self.subtree_left(parent, child);
        self.index_unnested(parent, child);
        Ok(())
    }

    // ---- bounding boxes -----------------------------------------------------------

    /// Enables the node's bounding box: from now on it holds the exact AABB of its
    /// sub-tree.
    pub fn enable_bounding_box(&mut self, id: NodeId) -> EditResult {
        let node = self.node(id)?;
        if node.bbox_enabled {
            return Ok(());
        }
        self.nodes.get_mut(&id).expect("checked").bbox_enabled = true;
        self.recompute_box(id);
        Ok(())
    }

    /// Disables the node's bounding box.
    pub fn disable_bounding_box(&mut self, id: NodeId) -> EditResult {
        self.node(id)?;
        let node = self.nodes.get_mut(&id).expect("checked");
        if !node.bbox_enabled {
            return Ok(());
        }
        node.bbox_enabled = false;
        node.aabb = None;
        let layer = node.layer;
        self.touch_layer(layer, Change::Node(id));
        Ok(())
    }
}

fn node_parent(g: &SceneGraph, id: NodeId) -> Option<NodeId> {
    g.nodes[&id].parent
}
