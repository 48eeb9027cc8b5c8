//! The way back: the Spark-DSG graph a scene built by [`super::build`] holds, for sending
//! a live scene to Spark-DSG consumers (`ygg export ros2`).
//!
//! Every node of a layer with a Spark-DSG role (objects, in the per-room layouts the
//! `room:<id>/claimed-object` layers; agents, places, mesh places, rooms, buildings)
//! becomes a node with its id, layer key and kind from the role, its position (an object's
//! `position_x/y/z` features, any other node's geometry), and its `name`,
//! `semantic_label`, `timestamp_ns` and stored box features. A node's parent is its
//! parent in the scene when that is such a node; in the per-room layouts an object's is
//! its room. Edges between two such nodes come back as intra-layer or sibling edges.
//!
//! What a layout does not keep does not come back: the mesh (and so `mesh_connections`),
//! edge weights, labelspaces, in the per-room layouts an object's Spark-DSG parent other
//! than its room. In [`Layout::Vanilla`](super::Layout::Vanilla) the graph of a mesh-less
//! file builds to the same scene again.

use std::collections::BTreeSet;

use rustc_hash::FxHashMap;
use ygg_store::{FeatureRef, NodeId, SceneView};

use super::{LayerRole, STORED_BOX_FEATURES, layer_roles};
use crate::model::{DsgAabb, DsgEdge, DsgGraph, DsgLayer, DsgNode, DsgVersion, LayerKey, NodeKind};

/// The Spark-DSG layer key and node kind of a role's nodes, for the roles that hold
/// Spark-DSG nodes.
fn spark_dsg_node(role: LayerRole) -> Option<(LayerKey, NodeKind)> {
    Some(match role {
        LayerRole::Objects | LayerRole::ClaimedObjects { .. } => {
            (LayerKey::OBJECTS, NodeKind::Object)
        }
        LayerRole::Agents => (LayerKey::AGENTS, NodeKind::Agent),
        LayerRole::Places => (LayerKey::PLACES, NodeKind::Place),
        LayerRole::MeshPlaces => (LayerKey::MESH_PLACES, NodeKind::Place2d),
        LayerRole::Rooms => (LayerKey::ROOMS, NodeKind::Room),
        LayerRole::Buildings => (LayerKey::BUILDINGS, NodeKind::Building),
        LayerRole::Mesh
        | LayerRole::RoomGroups { .. }
        | LayerRole::ClaimedMesh { .. }
        | LayerRole::UnclaimedMesh { .. } => return None,
    })
}

fn float(f: Option<FeatureRef<'_>>) -> Option<f32> {
    match f? {
        FeatureRef::Float(v) => Some(v as f32),
        FeatureRef::Int(v) => Some(v as f32),
        _ => None,
    }
}

fn int(f: Option<FeatureRef<'_>>) -> Option<i64> {
    match f? {
        FeatureRef::Int(v) => Some(v),
        _ => None,
    }
}

/// The Spark-DSG graph `view` (a scene built by [`super::build`]) holds; see the module
/// docs for what comes back. `source` becomes [`DsgGraph::source`]. Nodes are in layer
/// key order, then id order, as spark_dsg writes them.
///
/// # Examples
/// ```
/// use ygg_dsg::layout::{self, Layout};
/// let mut office = ygg_dsg::office::generate(ygg_dsg::office::OfficeParams { seed: 1, scale: 0.01 });
/// office.mesh = None;
/// let scene = layout::build(&office, Layout::Vanilla)?;
/// let back = layout::to_dsg(&scene, "scene");
/// assert_eq!(back.nodes.len(), office.nodes.len());
/// # Ok::<(), layout::LayoutError>(())
/// ```
pub fn to_dsg<V: SceneView>(view: &V, source: &str) -> DsgGraph {
    let mut nodes: Vec<DsgNode> = Vec::new();
    let mut layers: BTreeSet<LayerKey> = BTreeSet::new();
    let mut groups: FxHashMap<NodeId, NodeId> = FxHashMap::default();
    for (layer, role) in layer_roles(view) {
        if let LayerRole::RoomGroups { room } = role {
            for n in view.layer_nodes(layer) {
                groups.insert(view.node_id(n), room);
            }
        }
        let Some((key, kind)) = spark_dsg_node(role) else {
            continue;
        };
        layers.insert(key);
        for n in view.layer_nodes(layer) {
            let feature = |k: &str| view.feature(n, k);
            let position = if kind == NodeKind::Object {
                ["position_x", "position_y", "position_z"]
                    .map(|k| float(feature(k)).unwrap_or_default())
            } else {
                view.points(n).first().copied().unwrap_or_default()
            };
            let corners: Vec<f32> = STORED_BOX_FEATURES
                .iter()
                .filter_map(|k| float(feature(k)))
                .collect();
            let bbox = (corners.len() == 6).then(|| DsgAabb {
                min: [corners[0], corners[1], corners[2]],
                max: [corners[3], corners[4], corners[5]],
            });
            let name = match feature("name") {
                Some(FeatureRef::Str(s)) => Some(s.to_owned()),
                _ => None,
            };
            nodes.push(DsgNode {
                id: view.node_id(n).0,
                layer: key,
                kind,
                position,
                label: name.clone(),
                name,
                semantic_label: int(feature("semantic_label")).and_then(|v| u32::try_from(v).ok()),
                bbox,
                mesh_connections: Vec::new(),
                timestamp_ns: int(feature("timestamp_ns")).map(|v| v as u64),
                parent: view.parent(n).map(|p| p.0),
            });
        }
    }
    nodes.sort_by_key(|n| (n.layer, n.id));
    let index: FxHashMap<u64, usize> = nodes.iter().enumerate().map(|(i, n)| (n.id, i)).collect();
    let keys: Vec<LayerKey> = nodes.iter().map(|n| n.layer).collect();
    // Parents: a Spark-DSG node above (a room group stands for its room).
    for (i, n) in nodes.iter_mut().enumerate() {
        let parent = n
            .parent
            .map(|p| groups.get(&NodeId(p)).map_or(p, |room| room.0));
        n.parent = parent.filter(|p| index.get(p).is_some_and(|&k| keys[k].is_parent_of(keys[i])));
    }
    let mut edges = Vec::new();
    let mut sibling_edges = Vec::new();
    let mut seen: BTreeSet<(u64, u64)> = BTreeSet::new();
    for (layer, role) in layer_roles(view) {
        if spark_dsg_node(role).is_none() {
            continue;
        }
        for n in view.layer_nodes(layer) {
            for e in view.out_edges(n) {
                let (a, b) = (e.source.0, e.target.0);
                let (Some(&i), Some(&k)) = (index.get(&a), index.get(&b)) else {
                    continue;
                };
                if a == b || !seen.insert((a.min(b), a.max(b))) {
                    continue;
                }
                let edge = DsgEdge {
                    source: a,
                    target: b,
                    weight: None,
                };
                if keys[i] == keys[k] {
                    edges.push(edge);
                } else if keys[i].layer == keys[k].layer {
                    sibling_edges.push(edge);
                }
            }
        }
    }
    DsgGraph {
        source: source.to_owned(),
        version: DsgVersion::V1_1_3,
        layers: layers
            .into_iter()
            .map(|key| DsgLayer {
                key,
                name: DsgLayer::default_name(key),
                aliases: Vec::new(),
            })
            .collect(),
        nodes,
        edges,
        sibling_edges,
        extra_parent_edges: Vec::new(),
        mesh: None,
        labelspaces: Default::default(),
    }
}
