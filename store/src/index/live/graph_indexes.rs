//! The live graph's indexes: [`LiveIndexes`], the layer and node indexes a
//! [`crate::SceneGraph`] keeps with the handle table their items use, and [`LiveIndex`],
//! one of them as a [`SpatialIndex`].
//!
//! Handles are dense `u32`s naming nodes: a node keeps its handle (`u32::MAX` until it
//! has one) and `ids[handle]` is the node.

use super::overlay::OverlaidTree;
use crate::index::spatial_index::{SpatialIndex, prefetch};
use crate::{LayerId, NodeId, Point};
use rustc_hash::FxHashMap;
use std::collections::BTreeMap;

/// The live graph's index over one layer or one sub-tree, as [`crate::SceneView::layer_index`]
/// and [`crate::SceneView::node_index`] return it for a [`crate::SceneGraph`].
#[derive(Clone, Copy, Debug)]
pub struct LiveIndex<'a> {
    tree: &'a OverlaidTree,
    ids: &'a [NodeId],
}

impl<'a> LiveIndex<'a> {
    pub(crate) fn new(tree: &'a OverlaidTree, ids: &'a [NodeId]) -> Self {
        LiveIndex { tree, ids }
    }
}

impl SpatialIndex for LiveIndex<'_> {
    fn len(&self) -> usize {
        self.tree.len()
    }

    fn node_of(&self, item: u32) -> Option<NodeId> {
        self.ids
            .get(item as usize)
            .copied()
            .filter(|&id| id != NodeId::NONE)
    }

    fn nearest_visit<F: FnMut(f32, u32) -> f32>(&self, c: &Point, f: F) {
        self.tree.nearest_visit(c, f);
    }

    fn prefetch_node(&self, item: u32) {
        prefetch(self.ids.as_ptr().wrapping_add(item as usize));
    }

    fn points_within<F: FnMut(f32, u32, &Point)>(&self, c: &Point, r2: f32, mut f: F) {
        self.tree.within(c, r2, &mut f);
    }

    fn memory_bytes(&self) -> usize {
        self.tree.memory_bytes()
    }
}

/// `Node::index_handle` of a node without a handle.
pub(crate) const NO_HANDLE: u32 = u32::MAX;

/// The live indexes of a graph and the node handles their items use.
#[derive(Clone, Debug, Default)]
pub(crate) struct LiveIndexes {
    /// The node of each handle (`NodeId::NONE` for a free one).
    pub(crate) ids: Vec<NodeId>,
    /// Free handles.
    pub(crate) free: Vec<u32>,
    /// Layer indexes.
    pub(crate) layers: BTreeMap<LayerId, OverlaidTree>,
    /// Node indexes, by root.
    pub(crate) nodes: FxHashMap<NodeId, OverlaidTree>,
}

impl LiveIndexes {
    /// Whether no index is enabled.
    pub(crate) fn is_empty(&self) -> bool {
        self.layers.is_empty() && self.nodes.is_empty()
    }

    /// The handle of node `id`, whose stored handle is `slot`, allocated (and stored in
    /// `slot`) on first use.
    pub(crate) fn handle(&mut self, id: NodeId, slot: &mut u32) -> u32 {
        if *slot != NO_HANDLE {
            return *slot;
        }
        let h = match self.free.pop() {
            Some(h) => {
                self.ids[h as usize] = id;
                h
            }
            None => {
                if self.ids.len() == self.ids.capacity() {
                    // Grow by an eighth rather than double: the table costs 8 bytes per
                    // indexed node, and doubling would leave up to as much again unused.
                    self.ids.reserve_exact(self.ids.len() / 8 + 8);
                }
                self.ids.push(id);
                u32::try_from(self.ids.len() - 1).expect("fewer than 2^32 indexed nodes")
            }
        };
        *slot = h;
        h
    }

    /// Makes room for `n` more handles at once (exactly, so that enabling an index
    /// over many nodes leaves no slack in the table).
    pub(crate) fn reserve_handles(&mut self, n: usize) {
        self.ids.reserve_exact(n.saturating_sub(self.free.len()));
    }

    /// Frees `handle` (nothing for [`NO_HANDLE`]).
    pub(crate) fn release(&mut self, handle: u32) {
        if handle != NO_HANDLE {
            self.ids[handle as usize] = NodeId::NONE;
            self.free.push(handle);
        }
    }

    /// The index of `layer`, if enabled.
    pub(crate) fn layer(&self, layer: LayerId) -> Option<LiveIndex<'_>> {
        self.layers
            .get(&layer)
            .map(|t| LiveIndex::new(t, &self.ids))
    }

    /// The index of `node`'s sub-tree, if enabled.
    pub(crate) fn node(&self, node: NodeId) -> Option<LiveIndex<'_>> {
        if self.nodes.is_empty() {
            return None;
        }
        self.nodes.get(&node).map(|t| LiveIndex::new(t, &self.ids))
    }
}
