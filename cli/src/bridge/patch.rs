//! Applying a message in which nodes only moved, without building the layout again.
//!
//! Spark-DSG sends the whole graph in every message, so the bridge's general path builds
//! the whole layout from each message and brings its live graph to equal it
//! ([`SceneGraph::sync_to`]). For the most frequent change of a live stream, nodes that
//! moved and nothing else, the layout's answer is known node by node (`ygg_dsg::layout`
//! module docs): an object keeps its `position_x/y/z` features and its geometry is the
//! mesh vertices it claims; every other node's geometry is its position. So such a
//! message becomes a few mutations of the moved nodes.
//!
//! [`plan`] is a structure-aware comparison of the two decoded graphs, never a guess:
//! it answers only when the layout of the new graph provably differs from the live one
//! in the moved nodes' positions alone, that is when
//! * the mesh is the same (the stream reused it: its bytes did not change), and so are
//!   the layers, edges, labelspaces and the node list (same ids, in the same order);
//! * each node that differs differs in its position only (floats compared bit for bit);
//! * no moved node is a room (rooms place objects and mesh vertices), and every moved
//!   object claims at least one mesh vertex (else its geometry is its position, held by
//!   a mesh node the layout derives) and, in the per-room layouts, has a room among its
//!   ancestors (else its room, hence its layer, follows from its position).
//!
//! Otherwise it returns `None` and the bridge takes the general path. The bridge's
//! tests check on random edit sequences that both paths give the same graph.

use std::collections::HashMap;
use std::hash::BuildHasher;

use ygg_dsg::layout::Layout;
use ygg_dsg::{ChangedNodes, DsgGraph, DsgNode, NodeKind};
use ygg_store::{EditResult, FeatureValue, NodeId, SceneGraph, SceneView, SyncReport};

/// Parent hops the layout follows from an object to find its room.
const ROOM_HOPS: usize = 16;

/// The object features holding its position, in axis order.
const POSITION_FEATURES: [&str; 3] = ["position_x", "position_y", "position_z"];

/// One mutation of a moved node.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Move {
    /// An object's position features (its geometry is its claimed vertices).
    Object {
        id: NodeId,
        from: [f32; 3],
        to: [f32; 3],
    },
    /// Any other node, whose geometry is its position.
    Point { id: NodeId, to: [f32; 3] },
}

/// The mutations that take a live graph built (in `layout`) from `previous` to the
/// layout of `next`, when they are node moves alone (see the module docs); `None` when
/// the general path must build `next`. `mesh_same`: the two graphs have the same mesh
/// (their mesh sections were equal byte for byte); `previous.mesh` is then not read.
pub(super) fn plan(
    previous: &DsgGraph,
    next: &DsgGraph,
    mesh_same: bool,
    layout: Layout,
) -> Option<Vec<Move>> {
    let same_rest = mesh_same
        && previous.version == next.version
        && previous.layers == next.layers
        && previous.edges == next.edges
        && previous.sibling_edges == next.sibling_edges
        && previous.extra_parent_edges == next.extra_parent_edges
        && previous.labelspaces == next.labelspaces
        && previous.nodes.len() == next.nodes.len();
    if !same_rest {
        return None;
    }
    node_moves(previous.nodes.iter().zip(&next.nodes), next, layout)
}

/// [`plan`] for a message in which only the nodes `changed` names differ from the
/// previous graph (the stream decoded only their records: the mesh, layers, edges and
/// every other node are byte for byte the previous message's).
pub(super) fn plan_changed(
    changed: &ChangedNodes,
    next: &DsgGraph,
    layout: Layout,
) -> Option<Vec<Move>> {
    let now = next
        .nodes
        .get(changed.first..changed.first + changed.previous.len())?;
    node_moves(changed.previous.iter().zip(now), next, layout)
}

/// The moves taking each node of `pairs` (previous, next) to its new value, when every
/// difference is a move the layout answers node by node (the module docs); `None` else.
pub(super) fn node_moves<'a>(
    pairs: impl Iterator<Item = (&'a DsgNode, &'a DsgNode)>,
    next: &DsgGraph,
    layout: Layout,
) -> Option<Vec<Move>> {
    let vertices = next.mesh.as_ref().map_or(0, |m| m.points.len());
    let mut index = None;
    let mut moves = Vec::new();
    for (a, b) in pairs {
        if same_node(a, b) {
            continue;
        }
        if !moved_only(a, b) {
            return None;
        }
        let id = NodeId(b.id);
        match b.kind {
            NodeKind::Room => return None,
            NodeKind::Object => {
                let claims = b.mesh_connections.iter().any(|&v| (v as usize) < vertices);
                let index = index.get_or_insert_with(|| next.node_index());
                if !claims || (layout != Layout::Vanilla && !has_room_ancestor(next, index, b)) {
                    return None;
                }
                moves.push(Move::Object {
                    id,
                    from: a.position,
                    to: b.position,
                });
            }
            _ => moves.push(Move::Point { id, to: b.position }),
        }
    }
    Some(moves)
}

/// Applies `moves` to `live`; reports what changed as [`SceneGraph::sync_to`] would.
///
/// # Errors
/// A refused mutation (a node missing from `live`, which would mean `live` was not
/// built from the plan's `previous`); `live` may then be partly patched.
pub(super) fn apply(live: &mut SceneGraph, moves: &[Move]) -> EditResult<SyncReport> {
    let before: Vec<_> = live
        .layers()
        .map(|l| (l, live.layer_generation(l)))
        .collect();
    for m in moves {
        match *m {
            Move::Object { id, from, to } => {
                for (k, name) in POSITION_FEATURES.iter().enumerate() {
                    if from[k].to_bits() != to[k].to_bits() {
                        live.set_feature(id, name, FeatureValue::Float(f64::from(to[k])))?;
                    }
                }
            }
            Move::Point { id, to } => live.set_geometry(id, vec![to])?,
        }
    }
    let mut changed_layers: Vec<String> = before
        .into_iter()
        .filter(|&(l, g)| live.layer_generation(l) != g)
        .filter_map(|(l, _)| live.layer_name(l).map(str::to_owned))
        .collect();
    changed_layers.sort_unstable();
    Ok(SyncReport {
        nodes_changed: moves.len(),
        changed_layers,
        ..SyncReport::default()
    })
}

/// Whether two nodes are equal, floats bit for bit.
fn same_node(a: &DsgNode, b: &DsgNode) -> bool {
    a == b && bits(a.position) == bits(b.position) && same_box(a, b)
}

/// Whether two nodes are equal but for their positions, floats bit for bit.
fn moved_only(a: &DsgNode, b: &DsgNode) -> bool {
    let moved = DsgNode {
        position: b.position,
        ..a.clone()
    };
    moved == *b && same_box(a, b)
}

fn same_box(a: &DsgNode, b: &DsgNode) -> bool {
    let corners = |n: &DsgNode| n.bbox.map(|x| (bits(x.min), bits(x.max)));
    corners(a) == corners(b)
}

fn bits(p: [f32; 3]) -> [u32; 3] {
    p.map(f32::to_bits)
}

/// Whether the layout finds `object`'s room through its parents (as it does: at most
/// [`ROOM_HOPS`] hops up).
fn has_room_ancestor(
    g: &DsgGraph,
    index: &HashMap<u64, usize, impl BuildHasher>,
    object: &DsgNode,
) -> bool {
    let mut cur = object.parent;
    for _ in 0..ROOM_HOPS {
        let Some(n) = cur.and_then(|p| index.get(&p)).map(|&i| &g.nodes[i]) else {
            return false;
        };
        if n.kind == NodeKind::Room {
            return true;
        }
        cur = n.parent;
    }
    false
}
