//! The paper's layouts of a Spark-DSG scene graph (DESIGN.md §7): how an imported
//! [`DsgGraph`] becomes a [`SceneGraph`].
//!
//! | layout | structure |
//! |---|---|
//! | [`Layout::Vanilla`] | Spark-DSG's layers as they are; each object nests one node in a `MESH` layer holding its claimed vertices; the unclaimed vertices form one more `MESH` node |
//! | [`Layout::Chocolate`] | per room four layers: `room:<id>` (a *claimed* and an *unclaimed* node nested under the room), `room:<id>/claimed-object`, `room:<id>/claimed-mesh`, `room:<id>/unclaimed-mesh` |
//! | [`Layout::Mint`] | chocolate with exact boxes on objects, a node index on each object and a layer index on each room's claimed-mesh layer |
//! | [`Layout::Saffron`] | mint with one node per mesh point (a vertex claimed by several objects gets one node per claimant) |
//!
//! In every layout an object keeps its Spark-DSG id, carries its labels
//! ([`crate::DsgNode::labels`]), and nests the node(s) holding the vertices it claims;
//! object geometry is those vertices. An object that claims no vertex present in the
//! file (no mesh saved, as in real Hydra output, or empty `mesh_connections`) nests one
//! node of the same kind holding its `attributes.position` instead, so it is located by
//! its position. Every other node's geometry is its position. Mesh node ids are ordered
//! like their objects' ids, so "ties go to the smaller node id" on mesh nodes means
//! "ties go to the smaller object id". Derived ids (mesh and group nodes) come from
//! their object's or room's own id, not from its rank, so that they stay the same from
//! one message of a live stream to the next (`ygg bridge zmq`).
//!
//! Features: objects keep `position_x/y/z`; every node keeps `name`, `semantic_label`
//! and `timestamp_ns` when the file gives them, and its stored Spark-DSG bounding box as
//! the six [`STORED_BOX_FEATURES`].
//!
//! [`LayerRole`] says what each layer of a built scene holds: it writes the layer names
//! above ([`LayerRole::name`]) and reads them back ([`LayerRole::of_name`],
//! [`layer_roles`]).

mod role;
mod unbuild;
mod whereabouts;

#[doc(inline)]
pub use self::role::{LayerRole, layer_roles, layer_with_role};
#[doc(inline)]
pub use self::unbuild::to_dsg;
#[doc(inline)]
pub use self::whereabouts::{AgentPose, RoomScope, newest_pose, owners, room_of, room_scope};

use crate::{DsgGraph, NodeKind};
use rustc_hash::FxHashMap;
use std::collections::BTreeMap;
use ygg_store::{FeatureValue, GraphEditError, LayerId, NodeId, Point, SceneGraph, SceneView};

/// Which of the paper's layouts to build.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Layout {
    /// Spark-DSG's structure, ported as is.
    Vanilla,
    /// Per-room layer stacks.
    Chocolate,
    /// Chocolate plus live indexes and exact object boxes.
    Mint,
    /// Mint with one node per mesh point.
    Saffron,
}

impl Layout {
    /// Every layout, in ladder order.
    pub const ALL: [Layout; 4] = [
        Layout::Vanilla,
        Layout::Chocolate,
        Layout::Mint,
        Layout::Saffron,
    ];

    /// The layout's lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Layout::Vanilla => "vanilla",
            Layout::Chocolate => "chocolate",
            Layout::Mint => "mint",
            Layout::Saffron => "saffron",
        }
    }

    fn per_room(self) -> bool {
        self != Layout::Vanilla
    }
}

impl std::str::FromStr for Layout {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Layout::ALL
            .into_iter()
            .find(|l| l.name() == s)
            .ok_or_else(|| {
                format!("unknown layout {s:?} (expected vanilla, chocolate, mint or saffron)")
            })
    }
}

impl std::fmt::Display for Layout {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Why a layout could not be built.
#[derive(Debug, thiserror::Error)]
pub enum LayoutError {
    /// Per-room layouts need at least one room node.
    #[error("{source_name}: layout {layout} needs room nodes, and the graph has none")]
    NoRooms {
        /// The graph's source.
        source_name: String,
        /// The layout asked for.
        layout: Layout,
    },
    /// The imported graph broke an invariant of the store.
    #[error("{source_name}: {error}")]
    Edit {
        /// The graph's source.
        source_name: String,
        /// The refused mutation.
        error: GraphEditError,
    },
}

/// Id prefixes (top byte) of nodes the layouts create; above every ASCII prefix that
/// Spark-DSG uses, below the reserved `u64::MAX`.
const MESH_GROUP: u64 = 0xF0;
const UNCLAIMED_GROUP: u64 = 0xF1;
const ROOM_GROUP: u64 = 0xF2;
const CLAIMED_POINT: u64 = 0xF3;
const UNCLAIMED_POINT: u64 = 0xF4;

/// The features holding a node's stored Spark-DSG `bounding_box` ([`crate::DsgNode::bbox`]):
/// min x, y, z, then max x, y, z. The store's own box of a node (rooms; objects in mint
/// and saffron) is exact and computed from geometry, so it is not the stored one.
pub const STORED_BOX_FEATURES: [&str; 6] = [
    "bbox_min_x",
    "bbox_min_y",
    "bbox_min_z",
    "bbox_max_x",
    "bbox_max_y",
    "bbox_max_z",
];

fn prefixed(prefix: u64, index: u64) -> NodeId {
    NodeId(prefix << 56 | index)
}

/// Keys for the ids of nodes a layout derives from source nodes (an object's mesh node,
/// a room's group nodes), by source id: the source id's low 56 bits when all `ids`
/// share their top byte (Spark-DSG's symbol character) and fit in `bits` bits, else
/// the rank of the id. Ascending with the source ids either way; and in the first case
/// stable as the source graph grows and shrinks, so that the unchanged parts of a live
/// stream keep their ids (and their layers are not resent).
fn derived_keys(ids: impl IntoIterator<Item = u64>, bits: u32) -> FxHashMap<u64, u64> {
    let mut ids: Vec<u64> = ids.into_iter().collect();
    ids.sort_unstable();
    ids.dedup();
    let low = |id: u64| id & ((1u64 << 56) - 1);
    let stable = ids.windows(2).all(|w| w[0] >> 56 == w[1] >> 56)
        && ids.iter().all(|&id| low(id) < 1u64 << bits);
    ids.iter()
        .enumerate()
        .map(|(rank, &id)| (id, if stable { low(id) } else { rank as u64 }))
        .collect()
}

/// The layers holding object geometry in a scene built by [`build`] (those whose
/// [`LayerRole::holds_object_mesh`]), ascending, with the room each serves (`None` for
/// vanilla's single mesh layer). Works on any view, so readers of a snapshot find them
/// from layer names alone.
pub fn object_mesh_layers<V: SceneView>(view: &V) -> Vec<(LayerId, Option<NodeId>)> {
    layer_roles(view)
        .filter(|(_, role)| role.holds_object_mesh())
        .map(|(l, role)| (l, role.room()))
        .collect()
}

struct Builder<'a> {
    dsg: &'a DsgGraph,
    g: SceneGraph,
    layers: FxHashMap<String, LayerId>,
}

impl Builder<'_> {
    fn err(&self, error: GraphEditError) -> LayoutError {
        LayoutError::Edit {
            source_name: self.dsg.source.clone(),
            error,
        }
    }

    /// The layer called `name`, added on first use.
    fn layer(&mut self, name: &str) -> Result<LayerId, LayoutError> {
        if let Some(&l) = self.layers.get(name) {
            return Ok(l);
        }
        let l = self.g.add_layer(name).map_err(|e| self.err(e))?;
        self.layers.insert(name.to_owned(), l);
        Ok(l)
    }

    /// The layer holding `role`, added on first use.
    fn role_layer(&mut self, role: LayerRole) -> Result<LayerId, LayoutError> {
        self.layer(&role.name())
    }

    fn dag(&mut self, parent: LayerId, child: LayerId) -> Result<(), LayoutError> {
        match self.g.add_layer_edge(parent, child) {
            Ok(()) | Err(GraphEditError::DuplicateLayerEdge { .. }) => Ok(()),
            Err(e) => Err(self.err(e)),
        }
    }

    fn edit(&mut self, r: Result<(), GraphEditError>) -> Result<(), LayoutError> {
        r.map_err(|e| self.err(e))
    }
}

/// Builds `layout` from an imported Spark-DSG graph.
///
/// # Errors
/// [`LayoutError::NoRooms`] for a per-room layout of a graph without rooms, and
/// [`LayoutError::Edit`] if the graph breaks a store invariant (a node in two layers'
/// nesting, say).
pub fn build(dsg: &DsgGraph, layout: Layout) -> Result<SceneGraph, LayoutError> {
    let mut b = Builder {
        dsg,
        g: SceneGraph::new(),
        layers: FxHashMap::default(),
    };
    let index = dsg.node_index();
    let rooms: Vec<&crate::DsgNode> = dsg
        .nodes
        .iter()
        .filter(|n| n.kind == NodeKind::Room)
        .collect();
    if layout.per_room() && rooms.is_empty() {
        return Err(LayoutError::NoRooms {
            source_name: dsg.source.clone(),
            layout,
        });
    }
    let room_of_point = |p: &Point| -> Option<u64> {
        let inside = rooms.iter().find(|r| {
            r.bbox
                .is_some_and(|bb| (0..2).all(|a| bb.min[a] <= p[a] && p[a] <= bb.max[a]))
        });
        let chosen = inside.or_else(|| {
            rooms.iter().min_by(|a, c| {
                let d = |r: &crate::DsgNode| {
                    let q = r.position;
                    (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)
                };
                d(a).total_cmp(&d(c)).then(a.id.cmp(&c.id))
            })
        });
        chosen.map(|r| r.id)
    };
    // The room of every object: its ancestor room, else the room containing it.
    let room_of_object = |o: &crate::DsgNode| -> Option<u64> {
        let mut cur = o.parent;
        let mut hops = 0;
        while let (Some(p), true) = (cur, hops < 16) {
            let n = &dsg.nodes[*index.get(&p)?];
            if n.kind == NodeKind::Room {
                return Some(n.id);
            }
            cur = n.parent;
            hops += 1;
        }
        room_of_point(&o.position)
    };

    // Layers of the source graph (objects move to per-room layers when per_room).
    for l in &dsg.layers {
        let name = l.name.clone();
        b.layer(&name)?;
    }
    let layer_name: FxHashMap<crate::LayerKey, String> =
        dsg.layers.iter().map(|l| (l.key, l.name.clone())).collect();

    let mut sorted_objects: Vec<&crate::DsgNode> = dsg
        .nodes
        .iter()
        .filter(|n| n.kind == NodeKind::Object)
        .collect();
    sorted_objects.sort_by_key(|n| n.id);
    let object_room: FxHashMap<u64, Option<u64>> = sorted_objects
        .iter()
        .map(|o| (o.id, room_of_object(o)))
        .collect();

    // Nodes.
    for n in &dsg.nodes {
        let id = NodeId(n.id);
        let layer = if layout.per_room() && n.kind == NodeKind::Object {
            let room = object_room[&n.id].expect("per-room layouts have rooms");
            b.role_layer(LayerRole::ClaimedObjects { room: NodeId(room) })?
        } else {
            b.layers[&layer_name[&n.layer]]
        };
        let r = b.g.add_node(id, layer);
        b.edit(r)?;
        if n.kind == NodeKind::Object {
            for (k, v) in ["position_x", "position_y", "position_z"]
                .iter()
                .zip(n.position)
            {
                let r = b.g.set_feature(id, k, FeatureValue::Float(f64::from(v)));
                b.edit(r)?;
            }
        } else {
            let r = b.g.set_geometry(id, vec![n.position]);
            b.edit(r)?;
        }
        for label in n.labels() {
            let r = b.g.add_label(id, &label);
            b.edit(r)?;
        }
        if let Some(bb) = &n.bbox {
            for (k, v) in STORED_BOX_FEATURES.iter().zip(bb.min.iter().chain(&bb.max)) {
                let r = b.g.set_feature(id, k, FeatureValue::Float(f64::from(*v)));
                b.edit(r)?;
            }
        }
        if let Some(name) = &n.name {
            let r = b.g.set_feature(id, "name", FeatureValue::Str(name.clone()));
            b.edit(r)?;
        }
        if let Some(s) = n.semantic_label {
            let r =
                b.g.set_feature(id, "semantic_label", FeatureValue::Int(i64::from(s)));
            b.edit(r)?;
        }
        if let Some(t) = n.timestamp_ns {
            let r =
                b.g.set_feature(id, "timestamp_ns", FeatureValue::Int(t as i64));
            b.edit(r)?;
        }
    }
    // Intra-layer edges.
    for e in &dsg.edges {
        match b.g.add_edge(NodeId(e.source), NodeId(e.target), "") {
            Ok(()) | Err(GraphEditError::DuplicateEdge { .. }) => {}
            Err(GraphEditError::CrossLayerEdge { .. }) if layout.per_room() => {
                // Two objects of different rooms: per-room layouts keep rooms apart.
            }
            Err(e) => return Err(b.err(e)),
        }
    }
    // Per-room group layers and nodes.
    let mut room_groups: BTreeMap<u64, (NodeId, NodeId)> = BTreeMap::new();
    if layout.per_room() {
        let rooms_layer =
            b.g.node(NodeId(rooms[0].id))
                .map(|n| b.g.node_layer(n))
                .expect("room added");
        let room_keys = derived_keys(rooms.iter().map(|r| r.id), 55);
        for r in &rooms {
            let room = NodeId(r.id);
            let group_layer = b.role_layer(LayerRole::RoomGroups { room })?;
            let objects = b.role_layer(LayerRole::ClaimedObjects { room })?;
            let claimed_mesh = b.role_layer(LayerRole::ClaimedMesh { room })?;
            let unclaimed_mesh = b.role_layer(LayerRole::UnclaimedMesh { room })?;
            b.dag(rooms_layer, group_layer)?;
            b.dag(group_layer, objects)?;
            b.dag(objects, claimed_mesh)?;
            b.dag(group_layer, unclaimed_mesh)?;
            let claimed = prefixed(ROOM_GROUP, 2 * room_keys[&r.id]);
            let unclaimed = prefixed(ROOM_GROUP, 2 * room_keys[&r.id] + 1);
            for g in [claimed, unclaimed] {
                let r = b.g.add_node(g, group_layer);
                b.edit(r)?;
                let r = b.g.nest(room, g);
                b.edit(r)?;
            }
            room_groups.insert(r.id, (claimed, unclaimed));
        }
    }
    // Nesting from the source graph's parent relation.
    for n in &dsg.nodes {
        let Some(p) = n.parent else { continue };
        if layout.per_room() && n.kind == NodeKind::Object {
            continue; // nested under its room's claimed node below
        }
        let (Some(pl), Some(cl)) = (
            b.g.node(NodeId(p)).map(|x| b.g.node_layer(x)),
            b.g.node(NodeId(n.id)).map(|x| b.g.node_layer(x)),
        ) else {
            continue;
        };
        b.dag(pl, cl)?;
        let r = b.g.nest(NodeId(p), NodeId(n.id));
        b.edit(r)?;
    }
    if layout.per_room() {
        for o in &sorted_objects {
            let room = object_room[&o.id].expect("per-room layouts have rooms");
            let claimed = room_groups[&room].0;
            let r = b.g.nest(claimed, NodeId(o.id));
            b.edit(r)?;
        }
    }
    // Rooms keep exact boxes in every layout.
    for r in &rooms {
        let res = b.g.enable_bounding_box(NodeId(r.id));
        b.edit(res)?;
    }
    // Object geometry: the claimed vertices as object mesh nodes, or the object's
    // position when it claims no vertex present in the file.
    let no_mesh = crate::DsgMesh::default();
    let mesh = dsg.mesh.as_ref().unwrap_or(&no_mesh);
    let mut claimed = vec![false; mesh.points.len()];
    let vanilla_mesh = if layout.per_room() || (dsg.mesh.is_none() && sorted_objects.is_empty()) {
        None
    } else {
        Some(b.role_layer(LayerRole::Mesh)?)
    };
    let object_keys = derived_keys(
        sorted_objects.iter().map(|o| o.id),
        if layout == Layout::Saffron { 28 } else { 56 },
    );
    for o in &sorted_objects {
        let key = object_keys[&o.id];
        let mut vertices: Vec<u32> = o.mesh_connections.clone();
        vertices.sort_unstable();
        vertices.dedup();
        let mut points: Vec<Point> = vertices
            .iter()
            .filter_map(|&v| mesh.points.get(v as usize).copied())
            .collect();
        for &v in &vertices {
            if let Some(c) = claimed.get_mut(v as usize) {
                *c = true;
            }
        }
        if points.is_empty() {
            points.push(o.position);
        }
        let object = NodeId(o.id);
        let layer = match vanilla_mesh {
            Some(l) => l,
            None => b.role_layer(LayerRole::ClaimedMesh {
                room: NodeId(object_room[&o.id].expect("rooms")),
            })?,
        };
        let object_layer =
            b.g.node(object)
                .map(|n| b.g.node_layer(n))
                .expect("object added");
        b.dag(object_layer, layer)?;
        if layout == Layout::Saffron {
            for (k, p) in points.into_iter().enumerate() {
                let id = prefixed(CLAIMED_POINT, key << 28 | k as u64);
                let r =
                    b.g.add_node(id, layer)
                        .and_then(|()| b.g.set_geometry(id, vec![p]))
                        .and_then(|()| b.g.nest(object, id));
                b.edit(r)?;
            }
        } else {
            let id = prefixed(MESH_GROUP, key);
            let r =
                b.g.add_node(id, layer)
                    .and_then(|()| b.g.set_geometry(id, points))
                    .and_then(|()| b.g.nest(object, id));
            b.edit(r)?;
        }
    }
    if let Some(mesh) = &dsg.mesh {
        // Unclaimed vertices.
        let mut per_room: BTreeMap<Option<u64>, Vec<(usize, Point)>> = BTreeMap::new();
        for (v, p) in mesh.points.iter().enumerate() {
            if !claimed[v] {
                let room = if layout.per_room() {
                    room_of_point(p)
                } else {
                    None
                };
                per_room.entry(room).or_default().push((v, *p));
            }
        }
        let room_keys = derived_keys(rooms.iter().map(|r| r.id), 55);
        for (room, points) in per_room {
            // Vanilla's one group is 0; a room's is its key + 1.
            let group = room.map_or(0, |r| room_keys[&r] + 1);
            let (layer, parent) = match room {
                Some(r) => (
                    b.role_layer(LayerRole::UnclaimedMesh { room: NodeId(r) })?,
                    Some(room_groups[&r].1),
                ),
                None => (vanilla_mesh.expect("vanilla has a mesh layer"), None),
            };
            if layout == Layout::Saffron {
                for (v, p) in points {
                    let id = prefixed(UNCLAIMED_POINT, v as u64);
                    let r =
                        b.g.add_node(id, layer)
                            .and_then(|()| b.g.set_geometry(id, vec![p]));
                    b.edit(r)?;
                    if let Some(parent) = parent {
                        let r = b.g.nest(parent, id);
                        b.edit(r)?;
                    }
                }
            } else {
                let id = prefixed(UNCLAIMED_GROUP, group);
                let r = b.g.add_node(id, layer).and_then(|()| {
                    b.g.set_geometry(id, points.into_iter().map(|(_, p)| p).collect())
                });
                b.edit(r)?;
                if let Some(parent) = parent {
                    let r = b.g.nest(parent, id);
                    b.edit(r)?;
                }
            }
        }
    }
    if matches!(layout, Layout::Mint | Layout::Saffron) {
        for o in &sorted_objects {
            let r =
                b.g.enable_bounding_box(NodeId(o.id))
                    .and_then(|()| b.g.enable_node_index(NodeId(o.id)));
            b.edit(r)?;
        }
        for r in &rooms {
            let layer = b.role_layer(LayerRole::ClaimedMesh { room: NodeId(r.id) })?;
            let res = b.g.enable_layer_index(layer);
            b.edit(res)?;
        }
    }
    Ok(b.g)
}
