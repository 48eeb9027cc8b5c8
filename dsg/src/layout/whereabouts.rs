//! Where the agent is in a scene built by [`super::build`]: its newest pose, the room
//! holding a point, the layers that hold a room's objects, and the objects owning mesh
//! nodes. The one implementation the demo's readers, the examples, the C API and the
//! Python package call (each used to find the `AGENTS` layer by name on its own).

use super::{LayerRole, layer_with_role};
use ygg_store::{LayerId, NodeId, Point, SceneView, query};

/// The newest agent pose of a scene and the pose before it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AgentPose {
    /// The pose node: the largest id of the `AGENTS` layer.
    pub node: NodeId,
    /// Its position (the node's first point).
    pub position: Point,
    /// The previous pose's position (the next largest id), or 1 m behind `position`
    /// along -x when there is a single pose; the direction of travel is
    /// `position - previous`.
    pub previous: Point,
}

impl AgentPose {
    /// The unit direction of travel (from `previous` to `position`), or +x when the two
    /// coincide.
    pub fn heading(&self) -> Point {
        let d = [
            self.position[0] - self.previous[0],
            self.position[1] - self.previous[1],
            self.position[2] - self.previous[2],
        ];
        let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        if n > f32::EPSILON && n.is_finite() {
            [d[0] / n, d[1] / n, d[2] / n]
        } else {
            [1.0, 0.0, 0.0]
        }
    }
}

/// The newest agent pose of `view` (the `AGENTS` layer's largest id with a point), or
/// `None` when there is no such layer or no pose with a point yet.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let agents = g.add_layer("AGENTS")?;
/// for (id, y) in [(1, 0.0), (2, 2.0)] {
///     g.add_node(NodeId(id), agents)?;
///     g.set_geometry(NodeId(id), vec![[0.0, y, 0.0]])?;
/// }
/// let pose = ygg_dsg::layout::newest_pose(&g).unwrap();
/// assert_eq!((pose.node, pose.position, pose.previous), (NodeId(2), [0.0, 2.0, 0.0], [0.0, 0.0, 0.0]));
/// assert_eq!(pose.heading(), [0.0, 1.0, 0.0]);
/// # Ok(()) }
/// ```
pub fn newest_pose<V: SceneView>(view: &V) -> Option<AgentPose> {
    let agents = layer_with_role(view, LayerRole::Agents)?;
    // The two largest ids with a point, in one pass (the layer holds every pose of the run).
    let mut newest: Option<(NodeId, Point)> = None;
    let mut before: Option<(NodeId, Point)> = None;
    for n in view.layer_nodes(agents) {
        let id = view.node_id(n);
        let Some(&p) = view.points(n).first() else {
            continue;
        };
        match newest {
            Some((top, _)) if id < top => {
                if before.is_none_or(|(b, _)| id > b) {
                    before = Some((id, p));
                }
            }
            _ => {
                before = newest;
                newest = Some((id, p));
            }
        }
    }
    let (node, position) = newest?;
    let previous = before.map_or([position[0] - 1.0, position[1], position[2]], |(_, p)| p);
    Some(AgentPose {
        node,
        position,
        previous,
    })
}

/// The room (a node of the `ROOMS` layer) whose box holds `p` in x and y, the smallest
/// id when several do; `None` when no room's box holds it.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let rooms = g.add_layer("ROOMS")?;
/// g.add_node(NodeId(7), rooms)?;
/// g.set_geometry(NodeId(7), vec![[0.0, 0.0, 0.0], [4.0, 3.0, 0.0]])?;
/// g.enable_bounding_box(NodeId(7))?; // a room's box: its sub-tree's points
/// assert_eq!(ygg_dsg::layout::room_of(&g, &[1.0, 1.0, 5.0]), Some(NodeId(7)));
/// assert_eq!(ygg_dsg::layout::room_of(&g, &[5.0, 1.0, 0.0]), None);
/// # Ok(()) }
/// ```
pub fn room_of<V: SceneView>(view: &V, p: &Point) -> Option<NodeId> {
    let rooms = layer_with_role(view, LayerRole::Rooms)?;
    view.layer_nodes(rooms)
        .filter(|&n| {
            view.aabb(n)
                .is_some_and(|b| (0..2).all(|a| b.min[a] <= p[a] && p[a] <= b.max[a]))
        })
        .map(|n| view.node_id(n))
        .min()
}

/// Where a room's objects live in the per-room layouts (chocolate, mint, saffron).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RoomScope {
    /// The room's claimed-mesh layer: its objects' mesh nodes.
    pub mesh_layer: LayerId,
    /// The room's claimed group node: every object of the room nests under it, so
    /// [`crate::objects::Objects::in_subtree`] on it answers over the room's objects.
    pub claimed: NodeId,
}

/// The layers and group node holding `room`'s objects, or `None` when the scene is not
/// in a per-room layout or has no such room.
pub fn room_scope<V: SceneView>(view: &V, room: NodeId) -> Option<RoomScope> {
    let mesh_layer = layer_with_role(view, LayerRole::ClaimedMesh { room })?;
    let group = layer_with_role(view, LayerRole::RoomGroups { room })?;
    // The claimed group node is the smaller id of the room's two group nodes.
    let claimed = view.layer_nodes(group).map(|n| view.node_id(n)).min()?;
    Some(RoomScope {
        mesh_layer,
        claimed,
    })
}

/// The distinct parents of `nodes` (the objects owning mesh nodes), ascending; nodes
/// without a parent or unknown to `view` are left out.
pub fn owners<V: SceneView>(view: &V, nodes: impl IntoIterator<Item = NodeId>) -> Vec<NodeId> {
    let mut out: Vec<NodeId> = nodes
        .into_iter()
        .filter_map(|m| query::parent(view, m))
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}
