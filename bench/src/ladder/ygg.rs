//! The Yggdrasil rungs: vanilla (brute force over the ported structure, as the paper
//! runs it) and chocolate, mint, saffron: Q1a, Q1b and Q2 are the object queries of
//! [`ygg_dsg::objects`] over the room's objects ([`Objects::in_subtree`]); Q3 is
//! [`Objects::objects_with_label`] over the whole scene on every rung. Mint and saffron have live indexes and
//! object boxes, chocolate scans.

use super::harness::Target;
use super::workload::{Answer, Query, Scan};
use rustc_hash::FxHashMap;
use std::borrow::Cow;
use std::cell::OnceCell;
use ygg_dsg::layout::{self, LayerRole, Layout};
use ygg_dsg::objects::Objects;
use ygg_store::{LayerId, NodeId, SceneView};

/// The query scopes of a scene, found once from its layer roles.
#[derive(Clone, Default)]
pub struct Scopes {
    /// The rooms with a claimed-mesh layer (per-room layouts).
    rooms: Vec<u64>,
    /// Vanilla's mesh layer.
    mesh_layer: Option<LayerId>,
    /// The rooms' layer.
    rooms_layer: Option<LayerId>,
}

impl Scopes {
    /// Finds the scopes of a view built by [`layout::build`].
    pub fn new<V: SceneView>(view: &V) -> Self {
        let mut scopes = Scopes::default();
        for (layer, role) in layout::layer_roles(view) {
            match role {
                LayerRole::Mesh => scopes.mesh_layer = Some(layer),
                LayerRole::Rooms => scopes.rooms_layer = Some(layer),
                LayerRole::ClaimedMesh { room } => scopes.rooms.push(room.0),
                _ => {}
            }
        }
        scopes
    }
}

/// One Yggdrasil rung over any view (the live graph or an archived snapshot).
pub struct YggTarget<'a, V: SceneView> {
    name: String,
    layout: Layout,
    view: &'a V,
    scopes: Cow<'a, Scopes>,
    /// The object queries of each room, each built on first use.
    room_objects: FxHashMap<u64, OnceCell<Objects<'a, V>>>,
    /// The object queries over the whole scene, built on first use.
    scene_objects: OnceCell<Objects<'a, V>>,
}

impl<'a, V: SceneView> YggTarget<'a, V> {
    /// Wraps a view built with `layout`.
    pub fn new(name: String, layout: Layout, view: &'a V) -> Self {
        Self::with_cow_scopes(name, layout, view, Cow::Owned(Scopes::new(view)))
    }

    /// Wraps a view whose scopes are already known (they change only with the layers).
    pub fn with_scopes(name: String, layout: Layout, view: &'a V, scopes: &'a Scopes) -> Self {
        Self::with_cow_scopes(name, layout, view, Cow::Borrowed(scopes))
    }

    fn with_cow_scopes(name: String, layout: Layout, view: &'a V, scopes: Cow<'a, Scopes>) -> Self {
        YggTarget {
            name,
            layout,
            view,
            room_objects: scopes.rooms.iter().map(|&r| (r, OnceCell::new())).collect(),
            scopes,
            scene_objects: OnceCell::new(),
        }
    }

    /// The object queries over `room`'s objects (`None` for a room without a
    /// claimed-mesh layer).
    fn room_objects(&self, room: u64) -> Option<&Objects<'a, V>> {
        let cell = self.room_objects.get(&room)?;
        Some(cell.get_or_init(|| Objects::in_subtree(self.view, NodeId(room))))
    }

    /// Vanilla's room of an object: climb parents to a node of the rooms' layer.
    fn vanilla_room(&self, object: NodeId) -> Option<u64> {
        let rooms = self.scopes.rooms_layer?;
        let mut cur = self.view.node(object)?;
        for _ in 0..8 {
            let p = self.view.parent(cur)?;
            cur = self.view.node(p)?;
            if self.view.node_layer(cur) == rooms {
                return Some(p.0);
            }
        }
        None
    }

    /// Vanilla brute force: every mesh node whose object is in `room`, with its points.
    fn answer_vanilla(&self, q: &Query, room: u64) -> Answer {
        let mut scan = Scan::new(q);
        if let Some(mesh) = self.scopes.mesh_layer {
            for n in self.view.layer_nodes(mesh) {
                let Some(object) = self.view.parent(n) else {
                    continue;
                };
                if self.vanilla_room(object) == Some(room) {
                    scan.object(object.0, self.view.points(n));
                }
            }
        }
        scan.answer()
    }
}

impl<V: SceneView> Target for YggTarget<'_, V> {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn answer(&self, q: &Query) -> Answer {
        let objects = match q.room() {
            None => self.scene_objects.get_or_init(|| Objects::new(self.view)),
            Some(room) if self.layout == Layout::Vanilla => return self.answer_vanilla(q, room),
            Some(room) => match self.room_objects(room) {
                Some(objects) => objects,
                None => return Vec::new(),
            },
        };
        let found = match q {
            // The same call `answer` makes, without building an owned query per call.
            Query::Label { label } => objects.objects_with_label(label),
            _ => objects.answer(&q.to_object_query()).unwrap_or_default(),
        };
        found.into_iter().map(|n| n.0).collect()
    }
}
