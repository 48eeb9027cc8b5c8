//! The Yggdrasil rungs: vanilla (brute force over the ported structure, as the paper
//! runs it) and chocolate, mint, saffron: Q1a is the store's nearest-node query scoped
//! to the room's claimed-mesh layer; Q1b and Q2 are the object queries of
//! [`ygg_dsg::objects`] over the room's objects ([`Objects::in_subtree`]). Mint and
//! saffron have live indexes and object boxes, chocolate scans.

use super::Answer;
use super::harness::Target;
use super::workload::Query;
use rustc_hash::FxHashMap;
use std::borrow::Cow;
use std::cell::OnceCell;
use ygg_dsg::layout::{self, Layout};
use ygg_dsg::objects::Objects;
use ygg_store::query::{self, ConeView};
use ygg_store::{LayerId, NodeId, SceneView, Scope};

/// The per-room query scopes of a scene, found once from layer names.
#[derive(Clone, Default)]
pub struct Scopes {
    /// Each room's claimed-mesh layer.
    rooms: FxHashMap<u64, LayerId>,
    mesh_layer: Option<LayerId>,
}

impl Scopes {
    /// Finds the scopes of a view built by [`layout::build`].
    pub fn new<V: SceneView>(view: &V) -> Self {
        let mut rooms = FxHashMap::default();
        let mut mesh_layer = None;
        for (layer, room) in layout::object_mesh_layers(view) {
            match room {
                None => mesh_layer = Some(layer),
                Some(room) => {
                    rooms.insert(room.0, layer);
                }
            }
        }
        Scopes { rooms, mesh_layer }
    }
}

/// One Yggdrasil rung over any view (the live graph or an archived snapshot).
pub struct YggTarget<'a, V: SceneView> {
    name: String,
    layout: Layout,
    view: &'a V,
    scopes: Cow<'a, Scopes>,
    /// The object queries of each room, built on first use.
    objects: OnceCell<FxHashMap<u64, Objects<'a, V>>>,
}

impl<'a, V: SceneView> YggTarget<'a, V> {
    /// Wraps a view built with `layout`.
    pub fn new(name: String, layout: Layout, view: &'a V) -> Self {
        YggTarget {
            name,
            layout,
            view,
            scopes: Cow::Owned(Scopes::new(view)),
            objects: OnceCell::new(),
        }
    }

    /// Wraps a view whose scopes are already known (they change only with the layers).
    pub fn with_scopes(name: String, layout: Layout, view: &'a V, scopes: &'a Scopes) -> Self {
        YggTarget {
            name,
            layout,
            view,
            scopes: Cow::Borrowed(scopes),
            objects: OnceCell::new(),
        }
    }

    /// The object queries over `room`'s objects.
    fn room_objects(&self, room: u64) -> Option<&Objects<'a, V>> {
        self.objects
            .get_or_init(|| {
                self.scopes
                    .rooms
                    .keys()
                    .map(|&r| (r, Objects::in_subtree(self.view, NodeId(r))))
                    .collect()
            })
            .get(&room)
    }

    /// The object owning a mesh node (its parent).
    fn owner(&self, mesh: NodeId) -> Option<u64> {
        self.view
            .node(mesh)
            .and_then(|n| self.view.parent(n))
            .map(|p| p.0)
    }

    /// Vanilla's room of an object: climb parents to a node of the rooms' layer.
    fn vanilla_room(&self, object: NodeId) -> Option<u64> {
        let mut cur = self.view.node(object)?;
        for _ in 0..8 {
            let p = self.view.parent(cur)?;
            cur = self.view.node(p)?;
            if self.view.layer_name(self.view.node_layer(cur)) == Some("ROOMS") {
                return Some(p.0);
            }
        }
        None
    }

    /// Vanilla brute force: every mesh node whose object is in `room`, with its points.
    fn vanilla_candidates(&self, room: u64, mut f: impl FnMut(u64, &[[f32; 3]])) {
        let Some(mesh) = self.scopes.mesh_layer else {
            return;
        };
        for n in self.view.layer_nodes(mesh) {
            let Some(object) = self.view.parent(n) else {
                continue;
            };
            if self.vanilla_room(object) == Some(room) {
                f(object.0, self.view.points(n));
            }
        }
    }

    fn owners(&self, ids: impl IntoIterator<Item = NodeId>) -> Answer {
        let mut out: Answer = ids.into_iter().filter_map(|m| self.owner(m)).collect();
        out.sort_unstable();
        out.dedup();
        out
    }
}

impl<V: SceneView> Target for YggTarget<'_, V> {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn answer(&self, q: &Query) -> Answer {
        if self.layout == Layout::Vanilla {
            return self.answer_vanilla(q);
        }
        let scope = |room: &u64| self.scopes.rooms.get(room).copied();
        match q {
            Query::Nearest { room, point } => {
                let Some(s) = scope(room) else {
                    return Vec::new();
                };
                let found =
                    query::nearest_nodes(self.view, Scope::Layer(s), *point, 1).unwrap_or_default();
                self.owners(found.into_iter().map(|(id, _)| id))
            }
            Query::Within {
                room,
                point,
                radius,
            } => self.room_objects(*room).map_or_else(Vec::new, |o| {
                let found = o.objects_within(*point, *radius).unwrap_or_default();
                found.into_iter().map(|n| n.0).collect()
            }),
            Query::Visible {
                room,
                eye,
                dir,
                half_angle_deg,
                range,
            } => self.room_objects(*room).map_or_else(Vec::new, |o| {
                let found = o
                    .visible_objects(*eye, *dir, *half_angle_deg, *range)
                    .unwrap_or_default();
                found.into_iter().map(|n| n.0).collect()
            }),
            Query::Label { label } => query::nodes_with_label(self.view, Scope::Graph, label)
                .into_iter()
                .map(|n| n.0)
                .collect(),
        }
    }
}

impl<V: SceneView> YggTarget<'_, V> {
    fn answer_vanilla(&self, q: &Query) -> Answer {
        match q {
            Query::Nearest { room, point } => {
                let mut best: Option<(f32, u64)> = None;
                self.vanilla_candidates(*room, |object, points| {
                    for p in points {
                        let d = ygg_store::distance_squared(p, point);
                        if best.is_none_or(|(bd, bid)| d < bd || (d == bd && object < bid)) {
                            best = Some((d, object));
                        }
                    }
                });
                best.map(|b| b.1).into_iter().collect()
            }
            Query::Within {
                room,
                point,
                radius,
            } => {
                let mut out = Vec::new();
                self.vanilla_candidates(*room, |object, points| {
                    if points
                        .iter()
                        .any(|p| query::within_radius(p, point, *radius))
                    {
                        out.push(object);
                    }
                });
                out.sort_unstable();
                out
            }
            Query::Visible {
                room,
                eye,
                dir,
                half_angle_deg,
                range,
            } => {
                let cone = cone_view(eye, dir, *half_angle_deg, *range);
                let mut out = Vec::new();
                self.vanilla_candidates(*room, |object, points| {
                    if points.iter().any(|p| cone.contains(p).unwrap_or(false)) {
                        out.push(object);
                    }
                });
                out.sort_unstable();
                out
            }
            Query::Label { label } => query::nodes_with_label(self.view, Scope::Graph, label)
                .into_iter()
                .map(|n| n.0)
                .collect(),
        }
    }
}

/// The workload's cone as the store's view cone.
pub fn cone_view(eye: &[f32; 3], dir: &[f32; 3], half_angle_deg: f32, range: f32) -> ConeView {
    ConeView {
        eye: *eye,
        dir: *dir,
        half_angle: half_angle_deg.to_radians(),
        range,
    }
}
