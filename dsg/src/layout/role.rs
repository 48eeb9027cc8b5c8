//! [`LayerRole`]: what each layer of a scene built by [`super::build`] holds, and the
//! one place where layer names are written and read.

use crate::{DsgLayer, LayerKey};
use std::cell::RefCell;
use ygg_store::{LayerId, NodeId, SceneView};

/// What a layer of a scene built by [`super::build`] holds, with the room it serves in
/// the per-room layouts.
///
/// A layer's name says its role: [`LayerRole::name`] writes it, [`LayerRole::of_name`]
/// reads it back, so readers of a snapshot find their layers from names alone.
///
/// | role | name |
/// |---|---|
/// | [`LayerRole::Objects`], [`LayerRole::Agents`], [`LayerRole::Places`], [`LayerRole::MeshPlaces`], [`LayerRole::Rooms`], [`LayerRole::Buildings`] | Spark-DSG's conventional names ([`DsgLayer::default_name`]): `OBJECTS`, `AGENTS`, `PLACES`, `MESH_PLACES`, `ROOMS`, `BUILDINGS` |
/// | [`LayerRole::Mesh`] | `MESH` |
/// | [`LayerRole::RoomGroups`] | `room:<id>` |
/// | [`LayerRole::ClaimedObjects`] | `room:<id>/claimed-object` |
/// | [`LayerRole::ClaimedMesh`] | `room:<id>/claimed-mesh` |
/// | [`LayerRole::UnclaimedMesh`] | `room:<id>/unclaimed-mesh` |
///
/// `<id>` is the room's node id in decimal, without leading zeros. A layer a source file names otherwise has
/// no role.
///
/// # Examples
/// ```
/// # use ygg_dsg::layout::LayerRole; use ygg_store::NodeId;
/// let role = LayerRole::ClaimedMesh { room: NodeId(42) };
/// assert_eq!(role.name(), "room:42/claimed-mesh");
/// assert_eq!(LayerRole::of_name("room:42/claimed-mesh"), Some(role));
/// assert_eq!(LayerRole::of_name("ROOMS"), Some(LayerRole::Rooms));
/// assert_eq!(LayerRole::of_name("room:x/claimed-mesh"), None);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum LayerRole {
    /// Spark-DSG's objects; empty in the per-room layouts, which move objects to
    /// [`LayerRole::ClaimedObjects`].
    Objects,
    /// Spark-DSG's agent poses.
    Agents,
    /// Spark-DSG's places.
    Places,
    /// Spark-DSG's mesh places.
    MeshPlaces,
    /// Spark-DSG's rooms (each keeps an exact box).
    Rooms,
    /// Spark-DSG's buildings.
    Buildings,
    /// Vanilla's mesh: one node per object holding its claimed vertices, and one node
    /// holding the unclaimed ones.
    Mesh,
    /// A room's two group nodes (claimed and unclaimed, in that order by id), nested
    /// under the room.
    RoomGroups {
        /// The room.
        room: NodeId,
    },
    /// A room's objects, nested under its claimed group node.
    ClaimedObjects {
        /// The room.
        room: NodeId,
    },
    /// The mesh nodes of a room's objects, each nested under its object.
    ClaimedMesh {
        /// The room.
        room: NodeId,
    },
    /// A room's unclaimed vertices, nested under its unclaimed group node.
    UnclaimedMesh {
        /// The room.
        room: NodeId,
    },
}

/// The roles named after a Spark-DSG layer key, with that key.
const SPARK_DSG_ROLES: [(LayerRole, LayerKey); 6] = [
    (LayerRole::Objects, LayerKey::OBJECTS),
    (LayerRole::Agents, LayerKey::AGENTS),
    (LayerRole::Places, LayerKey::PLACES),
    (LayerRole::MeshPlaces, LayerKey::MESH_PLACES),
    (LayerRole::Rooms, LayerKey::ROOMS),
    (LayerRole::Buildings, LayerKey::BUILDINGS),
];

const MESH_NAME: &str = "MESH";
const ROOM_PREFIX: &str = "room:";
const CLAIMED_OBJECT_SUFFIX: &str = "/claimed-object";
const CLAIMED_MESH_SUFFIX: &str = "/claimed-mesh";
const UNCLAIMED_MESH_SUFFIX: &str = "/unclaimed-mesh";

impl LayerRole {
    /// The name of the layer holding this role.
    pub fn name(&self) -> String {
        let mut name = String::new();
        self.write_name(&mut name);
        name
    }

    /// Appends the name of the layer holding this role to `out` (no allocation beyond
    /// `out`'s growth).
    pub fn write_name(&self, out: &mut String) {
        let (room, suffix) = match *self {
            LayerRole::Mesh => return out.push_str(MESH_NAME),
            LayerRole::RoomGroups { room } => (room, ""),
            LayerRole::ClaimedObjects { room } => (room, CLAIMED_OBJECT_SUFFIX),
            LayerRole::ClaimedMesh { room } => (room, CLAIMED_MESH_SUFFIX),
            LayerRole::UnclaimedMesh { room } => (room, UNCLAIMED_MESH_SUFFIX),
            spark_dsg => {
                let key = SPARK_DSG_ROLES
                    .iter()
                    .find(|(r, _)| *r == spark_dsg)
                    .map(|&(_, key)| key)
                    .expect("every other role is named after a Spark-DSG layer key");
                return out.push_str(&DsgLayer::default_name(key));
            }
        };
        out.push_str(ROOM_PREFIX);
        out.push_str(itoa::Buffer::new().format(room.0));
        out.push_str(suffix);
    }

    /// The role of the layer called `name`: the inverse of [`LayerRole::name`]. `None`
    /// for any other name (a room id must be a decimal `u64`).
    pub fn of_name(name: &str) -> Option<LayerRole> {
        if let Some(rest) = name.strip_prefix(ROOM_PREFIX) {
            let (id, make): (&str, fn(NodeId) -> LayerRole) =
                match rest.split_once('/').map(|(id, _)| id) {
                    None => (rest, |room| LayerRole::RoomGroups { room }),
                    Some(id) => match &rest[id.len()..] {
                        CLAIMED_OBJECT_SUFFIX => (id, |room| LayerRole::ClaimedObjects { room }),
                        CLAIMED_MESH_SUFFIX => (id, |room| LayerRole::ClaimedMesh { room }),
                        UNCLAIMED_MESH_SUFFIX => (id, |room| LayerRole::UnclaimedMesh { room }),
                        _ => return None,
                    },
                };
            // Only what `name` writes: `u64::from_str` also takes a leading `+` or `0`.
            if !id.bytes().all(|b| b.is_ascii_digit()) || (id.len() > 1 && id.starts_with('0')) {
                return None;
            }
            return Some(make(NodeId(id.parse().ok()?)));
        }
        if name == MESH_NAME {
            return Some(LayerRole::Mesh);
        }
        SPARK_DSG_ROLES
            .iter()
            .find(|&&(_, key)| DsgLayer::default_name(key) == name)
            .map(|&(role, _)| role)
    }

    /// The room this role serves, for the per-room roles.
    pub fn room(&self) -> Option<NodeId> {
        match *self {
            LayerRole::RoomGroups { room }
            | LayerRole::ClaimedObjects { room }
            | LayerRole::ClaimedMesh { room }
            | LayerRole::UnclaimedMesh { room } => Some(room),
            _ => None,
        }
    }

    /// Whether the layer holds object nodes: [`LayerRole::Objects`] or
    /// [`LayerRole::ClaimedObjects`].
    pub fn holds_objects(&self) -> bool {
        matches!(self, LayerRole::Objects | LayerRole::ClaimedObjects { .. })
    }

    /// Whether the layer holds object geometry (mesh nodes nested under objects):
    /// [`LayerRole::Mesh`] or [`LayerRole::ClaimedMesh`].
    pub fn holds_object_mesh(&self) -> bool {
        matches!(self, LayerRole::Mesh | LayerRole::ClaimedMesh { .. })
    }
}

impl std::fmt::Display for LayerRole {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.name())
    }
}

/// Every layer of `view` that has a role, ascending by layer id, with its role.
///
/// # Examples
/// ```
/// # use ygg_dsg::{office, layout::{self, Layout, LayerRole}};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let office = office::generate(office::OfficeParams { seed: 7, scale: 0.02 });
/// let g = layout::build(&office, Layout::Chocolate)?;
/// let claimed_meshes = layout::layer_roles(&g)
///     .filter(|(_, role)| matches!(role, LayerRole::ClaimedMesh { .. }))
///     .count();
/// assert_eq!(claimed_meshes, 9); // one per room
/// # Ok(()) }
/// ```
pub fn layer_roles<V: SceneView>(view: &V) -> impl Iterator<Item = (LayerId, LayerRole)> + '_ {
    view.layers()
        .filter_map(|l| Some((l, LayerRole::of_name(view.layer_name(l)?)?)))
}

/// The layer of `view` holding `role`, if there is one.
pub fn layer_with_role<V: SceneView>(view: &V, role: LayerRole) -> Option<LayerId> {
    thread_local! {
        /// The name looked up, written again for every lookup (no allocation per lookup:
        /// object queries look a room's layers up each time they are built).
        static NAME: RefCell<String> = const { RefCell::new(String::new()) };
    }
    NAME.with_borrow_mut(|name| {
        name.clear();
        role.write_name(name);
        view.layer_by_name(name)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn every_role() -> Vec<LayerRole> {
        let mut roles: Vec<LayerRole> = SPARK_DSG_ROLES.iter().map(|&(r, _)| r).collect();
        roles.push(LayerRole::Mesh);
        for room in [0, 7, u64::MAX] {
            let room = NodeId(room);
            roles.extend([
                LayerRole::RoomGroups { room },
                LayerRole::ClaimedObjects { room },
                LayerRole::ClaimedMesh { room },
                LayerRole::UnclaimedMesh { room },
            ]);
        }
        roles
    }

    #[test]
    fn every_role_reads_back_from_its_name() {
        let roles = every_role();
        for role in &roles {
            assert_eq!(LayerRole::of_name(&role.name()), Some(*role), "{role:?}");
        }
        let mut names: Vec<String> = roles.iter().map(LayerRole::name).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), roles.len(), "names are distinct");
    }

    #[test]
    fn roles_are_named_as_the_layouts_name_them() {
        let room = NodeId(5);
        for (role, name) in [
            (LayerRole::Objects, "OBJECTS"),
            (LayerRole::Agents, "AGENTS"),
            (LayerRole::Places, "PLACES"),
            (LayerRole::MeshPlaces, "MESH_PLACES"),
            (LayerRole::Rooms, "ROOMS"),
            (LayerRole::Buildings, "BUILDINGS"),
            (LayerRole::Mesh, "MESH"),
            (LayerRole::RoomGroups { room }, "room:5"),
            (LayerRole::ClaimedObjects { room }, "room:5/claimed-object"),
            (LayerRole::ClaimedMesh { room }, "room:5/claimed-mesh"),
            (LayerRole::UnclaimedMesh { room }, "room:5/unclaimed-mesh"),
        ] {
            assert_eq!(role.name(), name);
            assert_eq!(role.to_string(), name);
        }
    }

    #[test]
    fn other_names_have_no_role() {
        for name in [
            "",
            "objects",
            "MESH_",
            "AGENTS_b",
            "room:",
            "room:+5",
            "room:05",
            "room:-5",
            "room:5/",
            "room:5/claimed",
            "room:5/claimed-mesh/",
            "room:5/claimed-mesh/x",
            "room:18446744073709551616",
            "room:5x/claimed-mesh",
        ] {
            assert_eq!(LayerRole::of_name(name), None, "{name:?}");
        }
    }
}
