//! The object catalog: [`Objects`] finds the object and object-mesh layers of a view
//! and the objects that claim geometry, once for a batch of queries.

use crate::layout::{LayerRole, layer_roles, layer_with_role};
use rustc_hash::{FxHashMap, FxHashSet};
use std::sync::OnceLock;
use ygg_store::{Aabb, LayerId, NodeId, SceneView};

/// An object with claimed geometry: its id, a box around that geometry (when known),
/// and its mesh nodes when there are few of them (see [`MAX_PART_CHILDREN`]).
#[derive(Clone, Debug)]
pub(super) struct Claimant<R> {
    pub(super) id: NodeId,
    pub(super) bbox: Option<Aabb>,
    pub(super) mesh: Vec<R>,
    /// Whether the object keeps a box and a node index and every node below it is one
    /// of its mesh nodes: its box then bounds exactly its claimed vertices, and
    /// [`ygg_store::query::nearest_in_subtree`] searches exactly them.
    pub(super) indexed_mesh: bool,
}

/// Objects with more mesh children than this (saffron's one node per vertex) get no
/// part boxes when they keep a box of their own: finding their points would cost a
/// node lookup per vertex.
const MAX_PART_CHILDREN: usize = 8;

/// The object queries over one view of a scene built by [`crate::layout::build`].
///
/// [`Objects::new`] finds the object and object-mesh layers once (from layer names and
/// the layer DAG) and the objects that claim geometry; keep it for a batch of queries.
/// It borrows the view and holds no copy of the scene's geometry.
pub struct Objects<'a, V: SceneView> {
    pub(super) view: &'a V,
    /// Layers holding object nodes, ascending.
    pub(super) object_layers: Vec<LayerId>,
    /// Layers holding object geometry (mesh nodes nested under objects), ascending.
    pub(super) mesh_layers: Vec<LayerId>,
    /// A box around every point of each mesh layer (same order; `None` when empty),
    /// computed by the first query that prunes layers by them.
    layer_boxes: OnceLock<Vec<Option<Aabb>>>,
    /// Objects with at least one mesh node, ascending by id, computed by the first query
    /// that needs them (radius and visibility, not nearest).
    claimants: OnceLock<Vec<Claimant<V::NodeRef<'a>>>>,
    /// Part boxes of each claimant (same order; empty when not kept), computed by the
    /// first visibility query.
    pub(super) parts: OnceLock<Vec<Vec<Aabb>>>,
    /// The kept objects carrying each label, ascending, indexed by the first label query.
    labelled: OnceLock<FxHashMap<String, Vec<NodeId>>>,
    /// With [`Objects::in_subtree`]: every object node kept (with geometry or not).
    pub(super) kept: Option<FxHashSet<NodeId>>,
    /// Whether every layer-DAG parent of every mesh layer is an object layer: then the
    /// parent of any mesh node is an object, and [`Objects::owner`] needs no lookup.
    mesh_parents_are_objects: bool,
}

/// Whether `name` names an object layer (one whose [`LayerRole::holds_objects`]):
/// `OBJECTS` (vanilla) or `room:<id>/claimed-object` (per-room layouts).
pub fn is_object_layer_name(name: &str) -> bool {
    LayerRole::of_name(name).is_some_and(|role| role.holds_objects())
}

impl<'a, V: SceneView> Objects<'a, V> {
    /// Finds the object layers, the object-mesh layers and the objects claiming geometry
    /// of `view`.
    ///
    /// # Complexity
    /// O(layers). The objects with geometry and the layer boxes are found by the first
    /// query that needs them ([`Objects::objects_within`], [`Objects::visible_objects`]).
    pub fn new(view: &'a V) -> Self {
        Self::build(view, None, |_| true)
    }

    /// Like [`Objects::new`], restricted to the objects in the sub-tree of `root` (a
    /// room, say): every query then answers among those objects only.
    ///
    /// # Complexity
    /// For a room of a per-room layout, O(1): its layers are found by role
    /// ([`LayerRole::ClaimedObjects`], [`LayerRole::ClaimedMesh`]). Otherwise
    /// O(objects in the layers below the root's layer × nesting depth).
    ///
    /// # Examples
    /// ```
    /// # use ygg_dsg::{self as dsg, layout::{self, Layout}, objects::Objects}; use ygg_store::SceneView;
    /// let office = dsg::office::generate(dsg::office::OfficeParams { seed: 7, scale: 0.02 });
    /// let graph = layout::build(&office, Layout::Mint).unwrap();
    /// let everywhere = Objects::new(&graph).objects_within([20.0, 12.0, 1.5], 1000.0).unwrap();
    /// let room = layout::object_mesh_layers(&graph)[0].1.expect("per-room layout");
    /// let here = Objects::in_subtree(&graph, room).objects_within([20.0, 12.0, 1.5], 1000.0).unwrap();
    /// assert!(!here.is_empty() && here.len() < everywhere.len());
    /// assert!(here.iter().all(|o| everywhere.contains(o)));
    /// ```
    pub fn in_subtree(view: &'a V, root: NodeId) -> Self {
        if let Some(room) = Self::room_layers(view, root) {
            return room;
        }
        Self::build(view, Some(root), |n| {
            let mut cur = view.parent(n);
            while let Some(p) = cur {
                if p == root {
                    return true;
                }
                cur = view.node(p).and_then(|x| view.parent(x));
            }
            false
        })
    }

    /// A room's objects in a per-room layout, found by role: its claimed-object layer
    /// holds exactly the objects nested under the room (the layouts put each object in
    /// its room's layer), and its claimed-mesh layer their geometry. `None` when `root`
    /// is no room of a per-room layout.
    fn room_layers(view: &'a V, root: NodeId) -> Option<Self> {
        let room = root;
        let objects = layer_with_role(view, LayerRole::ClaimedObjects { room })?;
        let mesh = layer_with_role(view, LayerRole::ClaimedMesh { room });
        Some(Self::assemble(
            view,
            vec![objects],
            mesh.into_iter().collect(),
            None,
        ))
    }

    /// [`Objects::new`] over the object nodes `keep` accepts; with a `root`, only the
    /// layers below the root's layer in the layer DAG (nesting follows DAG edges, so no
    /// other layer holds a node of its sub-tree), and only the mesh layers holding the
    /// kept objects' geometry.
    fn build(view: &'a V, root: Option<NodeId>, keep: impl Fn(V::NodeRef<'a>) -> bool) -> Self {
        let scoped = root.is_some();
        let below: Option<Vec<LayerId>> = root.map(|r| layers_below(view, r));
        let roles: Vec<(LayerId, LayerRole)> = match &below {
            None => layer_roles(view).collect(),
            Some(below) => below
                .iter()
                .filter_map(|&l| Some((l, LayerRole::of_name(view.layer_name(l)?)?)))
                .collect(),
        };
        let mut mesh_layers: Vec<LayerId> = roles
            .iter()
            .filter(|(_, role)| role.holds_object_mesh())
            .map(|&(l, _)| l)
            .collect();
        mesh_layers.sort_unstable();
        mesh_layers.dedup();
        // Object layers by role, plus any DAG parent of an object-mesh layer (the layer
        // objects live in, whatever the source file called it).
        let mut object_layers: Vec<LayerId> = roles
            .iter()
            .filter(|(_, role)| role.holds_objects())
            .map(|&(l, _)| l)
            .chain(mesh_layers.iter().flat_map(|&m| view.layer_parents(m)))
            .filter(|l| below.as_ref().is_none_or(|b| b.binary_search(l).is_ok()))
            .collect();
        object_layers.sort_unstable();
        object_layers.dedup();
        let mut kept = FxHashSet::default();
        if scoped {
            // The mesh layers holding the kept objects' geometry: an object's mesh nodes
            // lie in one layer in every layout, so its first mesh child names it.
            let mut used_layers = Vec::new();
            for &layer in &object_layers {
                for n in view.layer_nodes(layer).filter(|&n| keep(n)) {
                    kept.insert(view.node_id(n));
                    let first_mesh = view.children(n).find_map(|c| {
                        let l = view.node_layer(view.node(c)?);
                        mesh_layers.binary_search(&l).is_ok().then_some(l)
                    });
                    used_layers.extend(first_mesh);
                }
            }
            used_layers.sort_unstable();
            used_layers.dedup();
            mesh_layers = used_layers;
        }
        Self::assemble(view, object_layers, mesh_layers, scoped.then_some(kept))
    }

    /// The catalog over these layers (ascending) and kept objects.
    fn assemble(
        view: &'a V,
        object_layers: Vec<LayerId>,
        mesh_layers: Vec<LayerId>,
        kept: Option<FxHashSet<NodeId>>,
    ) -> Self {
        let mesh_parents_are_objects = mesh_layers.iter().all(|&m| {
            view.layer_parents(m)
                .iter()
                .all(|p| object_layers.binary_search(p).is_ok())
        });
        Objects {
            view,
            object_layers,
            mesh_layers,
            layer_boxes: OnceLock::new(),
            claimants: OnceLock::new(),
            parts: OnceLock::new(),
            labelled: OnceLock::new(),
            kept,
            mesh_parents_are_objects,
        }
    }

    /// The objects (among those kept) with at least one mesh node, ascending by id.
    ///
    /// # Complexity
    /// The first call visits every kept object's children: O(objects + their mesh
    /// nodes); later calls are free.
    pub(super) fn claimants(&self) -> &[Claimant<V::NodeRef<'a>>] {
        self.claimants.get_or_init(|| {
            let view = self.view;
            let mut claimants = Vec::new();
            for &layer in &self.object_layers {
                for n in view.layer_nodes(layer) {
                    if !self.is_kept(view.node_id(n)) {
                        continue;
                    }
                    // Every mesh child when there are few of them (one per object except
                    // in saffron) or the object keeps no box; else the first, to know it
                    // has one.
                    let children = view.children(n);
                    let all = view.aabb(n).is_none() || children.len() <= MAX_PART_CHILDREN;
                    let mut mesh: Vec<V::NodeRef<'a>> = Vec::new();
                    let mut only_mesh = true;
                    for c in children {
                        let Some(c) = view.node(c) else {
                            only_mesh = false;
                            continue;
                        };
                        if self.mesh_layers.binary_search(&view.node_layer(c)).is_err() {
                            only_mesh = false;
                            continue;
                        }
                        if all || mesh.is_empty() {
                            mesh.push(c);
                        }
                        only_mesh &= view.children(c).len() == 0;
                    }
                    if mesh.is_empty() {
                        continue;
                    }
                    let indexed_mesh = only_mesh
                        && view.aabb(n).is_some()
                        && view.node_index(view.node_id(n)).is_some();
                    // The object's own box (mint, saffron) holds its whole sub-tree; else
                    // the box around its mesh nodes' points.
                    let bbox = view.aabb(n).or_else(|| {
                        mesh.iter()
                            .filter_map(|&m| view.points(m).aabb())
                            .reduce(|a, b| a.union(&b))
                    });
                    claimants.push(Claimant {
                        id: view.node_id(n),
                        bbox,
                        mesh: if all { mesh } else { Vec::new() },
                        indexed_mesh,
                    });
                }
            }
            claimants.sort_unstable_by_key(|c| c.id);
            claimants.dedup_by_key(|c| c.id);
            claimants
        })
    }

    /// A box around every point of each mesh layer (in [`Objects::mesh_layers`] order;
    /// `None` for an empty layer).
    ///
    /// # Complexity
    /// The first call visits every node of the mesh layers (their boxes where the layout
    /// keeps them, their points otherwise); later calls are free.
    pub(super) fn layer_boxes(&self) -> &[Option<Aabb>] {
        self.layer_boxes.get_or_init(|| {
            self.mesh_layers
                .iter()
                .map(|&l| {
                    self.view
                        .layer_nodes(l)
                        .filter_map(|n| self.view.aabb(n).or_else(|| self.view.points(n).aabb()))
                        .reduce(|a, b| a.union(&b))
                })
                .collect()
        })
    }

    /// The view queried.
    pub fn view(&self) -> &'a V {
        self.view
    }

    /// The layers holding object nodes, ascending.
    pub fn object_layers(&self) -> &[LayerId] {
        &self.object_layers
    }

    /// The layers holding object geometry, ascending.
    pub fn mesh_layers(&self) -> &[LayerId] {
        &self.mesh_layers
    }

    /// Every object node, ascending.
    pub fn objects(&self) -> Vec<NodeId> {
        let mut ids: Vec<NodeId> = self
            .object_layers
            .iter()
            .flat_map(|&l| self.view.layer_nodes(l).map(|n| self.view.node_id(n)))
            .filter(|id| self.is_kept(*id))
            .collect();
        ids.sort_unstable();
        ids.dedup();
        ids
    }

    /// Whether object `id` is among those queried (always, unless scoped).
    pub(super) fn is_kept(&self, id: NodeId) -> bool {
        self.kept.as_ref().is_none_or(|k| k.contains(&id))
    }

    /// The objects that claim at least one mesh vertex, ascending.
    pub fn objects_with_geometry(&self) -> impl Iterator<Item = NodeId> + '_ {
        self.claimants().iter().map(|c| c.id)
    }

    /// The object owning mesh node `mesh`: its parent, when that is a kept object node
    /// (which then has geometry: `mesh`).
    pub(super) fn owner(&self, mesh: NodeId) -> Option<NodeId> {
        let parent = self.view.parent(self.view.node(mesh)?)?;
        if self.mesh_parents_are_objects && self.kept.is_none() {
            return Some(parent);
        }
        let parent = self.view.node(parent)?;
        let id = self.view.node_id(parent);
        (self
            .object_layers
            .binary_search(&self.view.node_layer(parent))
            .is_ok()
            && self.is_kept(id))
        .then_some(id)
    }

    /// Every object node carrying `label`, ascending.
    ///
    /// # Complexity
    /// The first call indexes the labels of every kept object (O(objects × labels));
    /// every call after it is one hash lookup and a copy of the answer.
    pub fn objects_with_label(&self, label: &str) -> Vec<NodeId> {
        self.labelled().get(label).cloned().unwrap_or_default()
    }

    /// The label index of [`Objects::objects_with_label`], built on first use.
    fn labelled(&self) -> &FxHashMap<String, Vec<NodeId>> {
        self.labelled.get_or_init(|| {
            let mut index: FxHashMap<String, Vec<NodeId>> = FxHashMap::default();
            for &layer in &self.object_layers {
                for n in self.view.layer_nodes(layer) {
                    let id = self.view.node_id(n);
                    if !self.is_kept(id) {
                        continue;
                    }
                    for label in self.view.labels(n) {
                        index.entry(label.to_owned()).or_default().push(id);
                    }
                }
            }
            for ids in index.values_mut() {
                ids.sort_unstable();
                ids.dedup();
            }
            index
        })
    }

    /// Whether node `id` lies in an object-mesh layer.
    pub(super) fn is_mesh_node(&self, id: NodeId) -> bool {
        self.view.node(id).is_some_and(|n| {
            self.mesh_layers
                .binary_search(&self.view.node_layer(n))
                .is_ok()
        })
    }
}

/// The layer of `root` and every layer below it in the layer DAG, ascending (empty when
/// `root` does not exist).
fn layers_below<V: SceneView>(view: &V, root: NodeId) -> Vec<LayerId> {
    let Some(start) = view.node(root).map(|n| view.node_layer(n)) else {
        return Vec::new();
    };
    let mut seen = vec![start];
    let mut next = vec![start];
    while let Some(l) = next.pop() {
        for c in view.layer_children(l) {
            if !seen.contains(&c) {
                seen.push(c);
                next.push(c);
            }
        }
    }
    seen.sort_unstable();
    seen
}
