//! The per-layer change journal: what mutations changed in a layer since a given layer
//! generation, for the incremental segment builder ([`crate::snapshot::SegmentCache`]).
//!
//! The journal is bounded: past about as many entries as the layer has nodes (a full
//! rebuild costs as much as following them), or after a change that may shift rows (an
//! index enabled or disabled), it records only that everything changed.

use crate::NodeId;

/// Fewest entries a journal holds before it overflows, whatever the layer's size.
const MIN_BOUND: usize = 64;

/// What a mutation changed in a layer.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Change {
    /// Anything: rows may have shifted (an index enabled or disabled).
    All,
    /// This node's row (edges, nesting, labels, features, box; or a new node).
    Node(NodeId),
    /// This node's points (its row and the layer index), of which the first `kept` stay
    /// as they were.
    Geometry {
        /// The node.
        id: NodeId,
        /// How many of its leading points the change kept.
        kept: usize,
    },
    /// The node index rooted at this node.
    IndexRoot(NodeId),
    /// This node was removed (whether it had points: the layer index changes then).
    Removed {
        /// The node.
        id: NodeId,
        /// Whether it had points.
        had_points: bool,
    },
}

/// What changed in one layer since layer generation [`LayerChanges::since`].
#[derive(Clone, Debug)]
pub(crate) struct LayerChanges {
    /// The layer generation the journal starts from.
    pub(crate) since: u64,
    /// Everything may have changed (the journal overflowed, or rows shifted).
    pub(crate) everything: bool,
    /// Some node's points changed (the layer index must be rebuilt).
    pub(crate) geometry: bool,
    /// Nodes whose rows changed, or new nodes (may repeat).
    pub(crate) nodes: Vec<NodeId>,
    /// Roots of node indexes in this layer whose sub-tree changed (may repeat).
    pub(crate) index_roots: Vec<NodeId>,
    /// Nodes removed from the layer (may repeat).
    pub(crate) removed: Vec<NodeId>,
    /// Nodes whose points changed, each with how many of its leading points the change
    /// kept (may repeat: what stays of a node's points since [`LayerChanges::since`] is
    /// at least its least entry). A node of `nodes` not listed here kept its points.
    pub(crate) points_kept: Vec<(NodeId, usize)>,
}

impl LayerChanges {
    /// An empty journal starting at layer generation `since`.
    pub(crate) fn new(since: u64) -> Self {
        LayerChanges {
            since,
            everything: false,
            geometry: false,
            nodes: Vec::new(),
            index_roots: Vec::new(),
            removed: Vec::new(),
            points_kept: Vec::new(),
        }
    }

    /// Notes `change` in a layer of `layer_nodes` nodes (which bounds the journal).
    pub(crate) fn record(&mut self, change: Change, layer_nodes: usize) {
        if self.everything {
            return;
        }
        let (list, id) = match change {
            Change::All => return self.overflow(),
            Change::Node(id) => (&mut self.nodes, id),
            Change::Geometry { id, kept } => {
                self.geometry = true;
                self.points_kept.push((id, kept));
                (&mut self.nodes, id)
            }
            Change::IndexRoot(id) => (&mut self.index_roots, id),
            Change::Removed { id, had_points } => {
                self.geometry |= had_points;
                (&mut self.removed, id)
            }
        };
        if list.last() != Some(&id) {
            list.push(id);
        }
        if self.nodes.len() + self.index_roots.len() + self.removed.len() + self.points_kept.len()
            > layer_nodes.max(MIN_BOUND)
        {
            self.overflow();
        }
    }

    /// Forgets the entries: everything changed.
    fn overflow(&mut self) {
        *self = LayerChanges {
            everything: true,
            ..LayerChanges::new(self.since)
        };
    }
}
