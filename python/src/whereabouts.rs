//! `yggdrasil.AgentPose` and `yggdrasil.RoomScope`: where the agent is, as
//! `Scene.newest_pose()` and `Scene.room_scope(room)` answer it (`ygg_dsg::layout`).

use pyo3::prelude::*;
use ygg_store::{ArchivedScene, Point, SceneView};

type Xyz = (f32, f32, f32);

fn xyz(p: Point) -> Xyz {
    (p[0], p[1], p[2])
}

/// The newest agent pose of a scene (`Scene.newest_pose()`).
#[pyclass(frozen, get_all, module = "yggdrasil", name = "AgentPose")]
pub struct AgentPose {
    /// The pose node: the largest id of the `AGENTS` layer with a point.
    node: u64,
    /// Its position `(x, y, z)`.
    position: Xyz,
    /// The previous pose's position (1 m behind along -x when there is a single pose).
    previous: Xyz,
    /// The unit direction of travel, from `previous` to `position` (+x when they coincide).
    heading: Xyz,
}

impl From<ygg_dsg::layout::AgentPose> for AgentPose {
    fn from(pose: ygg_dsg::layout::AgentPose) -> Self {
        AgentPose {
            node: pose.node.0,
            position: xyz(pose.position),
            previous: xyz(pose.previous),
            heading: xyz(pose.heading()),
        }
    }
}

#[pymethods]
impl AgentPose {
    fn __repr__(&self) -> String {
        let (x, y, z) = self.position;
        format!(
            "<yggdrasil.AgentPose node={} at=({x}, {y}, {z})>",
            self.node
        )
    }
}

/// Where a room's objects live in a per-room layout (`Scene.room_scope(room)`).
#[pyclass(frozen, get_all, module = "yggdrasil", name = "RoomScope")]
pub struct RoomScope {
    /// The name of the room's claimed-mesh layer (its objects' mesh nodes).
    mesh_layer: String,
    /// The room's claimed group node: `scene.objects_in(claimed)` answers over the room's
    /// objects.
    claimed: u64,
}

impl RoomScope {
    /// The scope of `view`, with its layer named.
    pub fn new(view: &ArchivedScene<'_>, scope: ygg_dsg::layout::RoomScope) -> Self {
        RoomScope {
            mesh_layer: view
                .layer_name(scope.mesh_layer)
                .unwrap_or_default()
                .to_owned(),
            claimed: scope.claimed.0,
        }
    }
}

#[pymethods]
impl RoomScope {
    fn __repr__(&self) -> String {
        format!(
            "<yggdrasil.RoomScope mesh_layer={:?} claimed={}>",
            self.mesh_layer, self.claimed
        )
    }
}
