//! What changed between two cuts of a recording, found from the segments that differ.

use super::error::RecordingError;
use super::open::Recording;
use crate::snapshot::{ArchivedScene, segment_layer_part};
use crate::{NodeId, Point, SceneView};
use std::collections::BTreeSet;

/// A node whose position moved by more than the tolerance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeMove {
    /// The node.
    pub id: NodeId,
    /// Its position at the first cut (the center of its points' box, or of its bounding
    /// box when it has no points).
    pub from: Point,
    /// Its position at the second cut.
    pub to: Point,
}

/// A node whose labels changed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Relabel {
    /// The node.
    pub id: NodeId,
    /// Its labels at the first cut, sorted.
    pub from: Vec<String>,
    /// Its labels at the second cut, sorted.
    pub to: Vec<String>,
}

/// What changed from one cut of a recording to another ([`Recording::changes`]). Every
/// list is ascending by node id (edges by source, then target).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SceneChanges {
    /// Nodes in the second cut only.
    pub nodes_added: Vec<NodeId>,
    /// Nodes in the first cut only.
    pub nodes_removed: Vec<NodeId>,
    /// Nodes in both whose position moved by more than the tolerance.
    pub nodes_moved: Vec<NodeMove>,
    /// Nodes in both whose labels differ.
    pub nodes_relabelled: Vec<Relabel>,
    /// Intra-layer edges `(source, target)` in the second cut only.
    pub edges_added: Vec<(NodeId, NodeId)>,
    /// Intra-layer edges in the first cut only.
    pub edges_removed: Vec<(NodeId, NodeId)>,
    /// Segments that differ between the two cuts: the only ones whose nodes were compared.
    pub segments_compared: usize,
}

impl Recording {
    /// What changed from cut `from` to cut `to` (indexes into [`Recording::cuts`]):
    /// nodes added, removed, moved by more than `tolerance` (meters) and relabelled, and
    /// edges added and removed. Only the nodes of the segments that differ between the
    /// two cuts are compared: segments both cuts name are the same bytes.
    ///
    /// # Errors
    /// As [`Recording::scene`].
    pub fn changes(
        &self,
        from: usize,
        to: usize,
        tolerance: f32,
    ) -> Result<SceneChanges, RecordingError> {
        let (a, b) = (self.scene(from)?, self.scene(to)?);
        let same_session = self.cuts()[from].session == self.cuts()[to].session;
        let (sa, sb) = (self.segments(from)?, self.segments(to)?);
        let differing: Vec<u64> = if same_session {
            let sa_set: BTreeSet<_> = sa.iter().collect();
            let sb_set: BTreeSet<_> = sb.iter().collect();
            sa_set
                .symmetric_difference(&sb_set)
                .map(|(id, _)| *id)
                .collect()
        } else {
            sa.iter().chain(&sb).map(|(id, _)| *id).collect()
        };
        let parts: BTreeSet<_> = differing
            .iter()
            .filter_map(|&id| segment_layer_part(id))
            .collect();
        let (va, vb) = (a.view(), b.view());
        let mut candidates = BTreeSet::new();
        for &(layer, part) in &parts {
            for view in [va, vb] {
                candidates.extend(view.part_nodes(layer, part).map(|n| view.node_id(n)));
            }
        }
        let mut changes = SceneChanges {
            segments_compared: differing.len(),
            ..SceneChanges::default()
        };
        for id in candidates {
            compare_node(va, vb, id, tolerance, &mut changes);
        }
        Ok(changes)
    }
}

/// Adds what changed of node `id` from `a` to `b` to `changes`.
fn compare_node(
    a: &ArchivedScene<'_>,
    b: &ArchivedScene<'_>,
    id: NodeId,
    tolerance: f32,
    changes: &mut SceneChanges,
) {
    let edges = |v: &ArchivedScene<'_>, n| -> BTreeSet<(NodeId, NodeId)> {
        v.out_edges(n).map(|e| (e.source, e.target)).collect()
    };
    match (a.node(id), b.node(id)) {
        (None, None) => {}
        (None, Some(nb)) => {
            changes.nodes_added.push(id);
            changes.edges_added.extend(edges(b, nb));
        }
        (Some(na), None) => {
            changes.nodes_removed.push(id);
            changes.edges_removed.extend(edges(a, na));
        }
        (Some(na), Some(nb)) => {
            if let (Some(from), Some(to)) = (position(a, na), position(b, nb))
                && crate::distance_squared(&from, &to) > tolerance * tolerance
            {
                changes.nodes_moved.push(NodeMove { id, from, to });
            }
            let labels = |v: &ArchivedScene<'_>, n| {
                let mut l: Vec<String> = v.labels(n).map(str::to_owned).collect();
                l.sort_unstable();
                l
            };
            let (la, lb) = (labels(a, na), labels(b, nb));
            if la != lb {
                changes.nodes_relabelled.push(Relabel {
                    id,
                    from: la,
                    to: lb,
                });
            }
            let (ea, eb) = (edges(a, na), edges(b, nb));
            changes.edges_added.extend(eb.difference(&ea));
            changes.edges_removed.extend(ea.difference(&eb));
        }
    }
}

/// A node's position: the center of its points' box, else of its bounding box.
fn position(v: &ArchivedScene<'_>, n: crate::snapshot::ArchivedNodeRef) -> Option<Point> {
    let aabb = v.points(n).aabb().or_else(|| v.aabb(n))?;
    Some(std::array::from_fn(|i| (aabb.min[i] + aabb.max[i]) / 2.0))
}
