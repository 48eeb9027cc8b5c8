//! Object-level queries: the query contract of `ygg-reader query`, answered on a scene
//! built by [`crate::layout::build`] in any layout, live or archived.
//!
//! # Contract
//! * Answers are **object ids** (the Spark-DSG node ids the layouts keep), ascending.
//! * The spatial scope is the **whole scene**.
//! * An object's **geometry** is the set of mesh vertices it claims: the points of the
//!   mesh node(s) nested under it in an object-mesh layer
//!   ([`crate::layout::object_mesh_layers`]). A vertex claimed by several objects counts
//!   for each of them. An object without claimed vertices is never a spatial answer.
//! * [`Objects::nearest_object`]: the object with the closest vertex (distance as
//!   [`ygg_store::query::nearest_nodes`] defines it), ties to the smaller id.
//! * [`Objects::objects_within`]: every object with a vertex at distance `<= r`
//!   (exactly the test of [`ygg_store::query::nodes_within_radius`]).
//! * [`Objects::visible_objects`]: every object with a vertex `v` such that
//!   `|v - eye| <= range` and the angle between `v - eye` and `dir` is at most the
//!   half-angle (exactly the test of [`ygg_store::query::visible`] with a [`ConeView`]).
//! * [`Objects::objects_with_label`]: every object node carrying the label. Object
//!   nodes are the nodes of the object layers: `OBJECTS` in vanilla,
//!   `room:<id>/claimed-object` in the per-room layouts.
//!
//! The answers depend only on the imported graph, not on the layout: the same question
//! gets the same ids on vanilla, chocolate, mint and saffron (tested against brute force
//! over the imported graph).
//!
//! # How they run
//! Each query calls the store's spatial queries once per object-mesh layer and merges
//! the answers, so the layer indexes of mint and saffron (one per room's claimed-mesh
//! layer) serve nearest and radius queries; visibility runs [`ygg_store::query::visible`]
//! from each object whose box can reach the view, using the node indexes mint and
//! saffron keep on objects. Layouts without indexes (vanilla, chocolate) scan, with the
//! same answers.
//!
//! # Examples
//! ```
//! # use ygg_dsg::{self as dsg, layout::{self, Layout}, objects::Objects}; use ygg_store::NodeId;
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let office = dsg::office::generate(dsg::office::OfficeParams { seed: 7, scale: 0.02 });
//! let graph = layout::build(&office, Layout::Mint)?;
//! let objects = Objects::new(&graph);
//! let nearest = objects.nearest_object([5.0, 5.0, 1.0])?;
//! assert!(nearest.is_some());
//! let lights = objects.objects_with_label("light");
//! assert!(!lights.is_empty());
//! // The same answers on the archived snapshot.
//! let snapshot = graph.to_snapshot();
//! let view = snapshot.view();
//! let archived = Objects::new(&view);
//! assert_eq!(archived.nearest_object([5.0, 5.0, 1.0])?, nearest);
//! assert_eq!(archived.objects_with_label("light"), lights);
//! # Ok(()) }
//! ```

use crate::layout::object_mesh_layers;
use crate::{DsgLayer, LayerKey};
use rustc_hash::FxHashSet;
use std::sync::OnceLock;
use ygg_store::index::SpatialIndex;
use ygg_store::query::{self, ConeView, SpatialQueryError};
use ygg_store::{Aabb, LayerId, NodeId, Point, SceneView, Scope};

/// Why an object query refused its input. Object queries never panic on bad input.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum ObjectQueryError {
    /// A point, radius, direction or range the spatial queries reject.
    #[error(transparent)]
    Spatial(#[from] SpatialQueryError),
    /// A view half-angle outside `[0, 180]` degrees or not finite.
    #[error("half_angle_deg {0} is not in [0, 180] degrees")]
    InvalidHalfAngleDeg(f32),
}

/// One query of the contract, as `ygg-reader query` reads it from a JSON line
/// (`{"op":"nearest_object","point":[x,y,z]}`, ...): see [`ObjectQuery::from_json`].
/// Serializes to that same form.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "op", rename_all = "snake_case")]
pub enum ObjectQuery {
    /// [`Objects::nearest_object`].
    NearestObject {
        /// The query point.
        point: Point,
    },
    /// [`Objects::objects_within`].
    ObjectsWithin {
        /// The centre.
        point: Point,
        /// The radius, metres (inclusive).
        radius: f32,
    },
    /// [`Objects::visible_objects`].
    VisibleObjects {
        /// The apex of the view.
        eye: Point,
        /// The viewing direction (any finite non-zero vector).
        dir: Point,
        /// Half of the opening angle, degrees, in `[0, 180]`.
        half_angle_deg: f32,
        /// How far the view reaches, metres.
        range: f32,
    },
    /// [`Objects::objects_with_label`].
    ObjectsWithLabel {
        /// The label.
        label: String,
    },
}

impl ObjectQuery {
    /// The operations, as `"op"` names them.
    pub const OPS: [&'static str; 4] = [
        "nearest_object",
        "objects_within",
        "visible_objects",
        "objects_with_label",
    ];

    /// Reads a query from one JSON line.
    ///
    /// Numbers are read as `f64` and rounded to `f32`; one too large for `f32` is refused.
    ///
    /// # Errors
    /// A message naming what is wrong: malformed JSON, a missing or unknown `op`, a
    /// missing, unknown or mistyped field (`field "point": expected an array of 3
    /// numbers, got [1,2]`).
    ///
    /// # Examples
    /// ```
    /// # use ygg_dsg::objects::ObjectQuery;
    /// let q = ObjectQuery::from_json(r#"{"op":"objects_within","point":[1,2,0.5],"radius":2}"#);
    /// assert_eq!(q, Ok(ObjectQuery::ObjectsWithin { point: [1.0, 2.0, 0.5], radius: 2.0 }));
    /// let e = ObjectQuery::from_json(r#"{"op":"objects_within","point":[1,2],"radius":2}"#);
    /// assert!(e.unwrap_err().contains("field \"point\""));
    /// ```
    pub fn from_json(line: &str) -> Result<Self, String> {
        let v: serde_json::Value =
            serde_json::from_str(line).map_err(|e| format!("malformed JSON: {e}"))?;
        Self::from_value(&v)
    }

    /// Reads a query from a parsed JSON value (as [`ObjectQuery::from_json`]).
    ///
    /// # Errors
    /// As [`ObjectQuery::from_json`].
    pub fn from_value(v: &serde_json::Value) -> Result<Self, String> {
        use serde_json::Value;
        let ops = || Self::OPS.join(", ");
        let Some(obj) = v.as_object() else {
            return Err(format!(
                "expected a JSON object with an \"op\" ({}), got {}",
                ops(),
                brief(v)
            ));
        };
        let op = match obj.get("op") {
            Some(Value::String(op)) => op.as_str(),
            Some(other) => return Err(format!("\"op\" must be a string, got {}", brief(other))),
            None => return Err(format!("missing field \"op\" (one of {})", ops())),
        };
        let fields: &[&str] = match op {
            "nearest_object" => &["point"],
            "objects_within" => &["point", "radius"],
            "visible_objects" => &["eye", "dir", "half_angle_deg", "range"],
            "objects_with_label" => &["label"],
            _ => return Err(format!("unknown op {op:?} (expected one of {})", ops())),
        };
        if let Some(k) = obj
            .keys()
            .find(|k| *k != "op" && !fields.contains(&k.as_str()))
        {
            return Err(format!(
                "unknown field {k:?} for op {op} (it takes {})",
                fields.join(", ")
            ));
        }
        let get = |name: &str| {
            obj.get(name)
                .ok_or_else(|| format!("missing field {name:?} for op {op}"))
        };
        let to_f32 = |name: &str, x: f64| -> Result<f32, String> {
            let y = x as f32;
            if y.is_finite() {
                Ok(y)
            } else {
                Err(format!("field {name:?}: {x:?} is not a finite f32"))
            }
        };
        let number = |name: &str| -> Result<f32, String> {
            let v = get(name)?;
            let x = v
                .as_f64()
                .ok_or_else(|| format!("field {name:?}: expected a number, got {}", brief(v)))?;
            to_f32(name, x)
        };
        let point = |name: &str| -> Result<Point, String> {
            let v = get(name)?;
            let xyz: Option<Vec<f64>> = v
                .as_array()
                .filter(|a| a.len() == 3)
                .and_then(|a| a.iter().map(serde_json::Value::as_f64).collect());
            let xyz = xyz.ok_or_else(|| {
                format!(
                    "field {name:?}: expected an array of 3 numbers, got {}",
                    brief(v)
                )
            })?;
            Ok([
                to_f32(name, xyz[0])?,
                to_f32(name, xyz[1])?,
                to_f32(name, xyz[2])?,
            ])
        };
        Ok(match op {
            "nearest_object" => ObjectQuery::NearestObject {
                point: point("point")?,
            },
            "objects_within" => ObjectQuery::ObjectsWithin {
                point: point("point")?,
                radius: number("radius")?,
            },
            "visible_objects" => ObjectQuery::VisibleObjects {
                eye: point("eye")?,
                dir: point("dir")?,
                half_angle_deg: number("half_angle_deg")?,
                range: number("range")?,
            },
            _ => {
                let v = get("label")?;
                ObjectQuery::ObjectsWithLabel {
                    label: v
                        .as_str()
                        .ok_or_else(|| {
                            format!("field \"label\": expected a string, got {}", brief(v))
                        })?
                        .to_owned(),
                }
            }
        })
    }
}

/// A JSON value for a message, cut to a readable length.
fn brief(v: &serde_json::Value) -> String {
    let s = v.to_string();
    match s.char_indices().nth(60) {
        Some((at, _)) => format!("{}...", &s[..at]),
        None => s,
    }
}

/// An object with claimed geometry: its id, a box around that geometry (when known),
/// and its mesh nodes when there are few of them (see [`MAX_PART_CHILDREN`]).
#[derive(Clone, Debug)]
struct Claimant<R> {
    id: NodeId,
    bbox: Option<Aabb>,
    mesh: Vec<R>,
    /// Whether the object keeps a box and a node index and every node below it is one
    /// of its mesh nodes: its box then bounds exactly its claimed vertices, and
    /// [`ygg_store::query::nearest_in_subtree`] searches exactly them.
    indexed_mesh: bool,
}

/// Objects with more mesh children than this (saffron's one node per vertex) get no
/// part boxes when they keep a box of their own: finding their points would cost a
/// node lookup per vertex.
const MAX_PART_CHILDREN: usize = 8;

/// The points of `sets` split into the octants around the centre of `around` (a box
/// holding them all), as the boxes of the non-empty octants: each holds its points
/// exactly, so each holds at least one point and together they hold all.
fn octant_boxes(sets: &[&[Point]], around: &Aabb) -> Vec<Aabb> {
    let centre = [0, 1, 2].map(|a| around.min[a] + (around.max[a] - around.min[a]) / 2.0);
    let mut parts = [Aabb {
        min: [f32::INFINITY; 3],
        max: [f32::NEG_INFINITY; 3],
    }; 8];
    for p in sets.iter().flat_map(|s| s.iter()) {
        let octant = usize::from(p[0] > centre[0])
            | usize::from(p[1] > centre[1]) << 1
            | usize::from(p[2] > centre[2]) << 2;
        let b = &mut parts[octant];
        for ((lo, hi), &c) in b.min.iter_mut().zip(&mut b.max).zip(p) {
            if c < *lo {
                *lo = c;
            }
            if c > *hi {
                *hi = c;
            }
        }
    }
    parts.into_iter().filter(|b| b.min[0] <= b.max[0]).collect()
}

/// The object queries over one view of a scene built by [`crate::layout::build`].
///
/// [`Objects::new`] finds the object and object-mesh layers once (from layer names and
/// the layer DAG) and the objects that claim geometry; keep it for a batch of queries.
/// It borrows the view and holds no copy of the scene's geometry.
pub struct Objects<'a, V: SceneView> {
    view: &'a V,
    /// Layers holding object nodes, ascending.
    object_layers: Vec<LayerId>,
    /// Layers holding object geometry (mesh nodes nested under objects), ascending.
    mesh_layers: Vec<LayerId>,
    /// A box around every point of each mesh layer (same order; `None` when empty).
    layer_boxes: Vec<Option<Aabb>>,
    /// Objects with at least one mesh node, ascending by id.
    claimants: Vec<Claimant<V::NodeRef<'a>>>,
    /// Part boxes of each claimant (same order; empty when not kept), computed by the
    /// first visibility query.
    parts: OnceLock<Vec<Vec<Aabb>>>,
    /// The ids of `claimants`.
    claimant_ids: FxHashSet<NodeId>,
    /// With [`Objects::in_subtree`]: every object node kept (with geometry or not).
    kept: Option<FxHashSet<NodeId>>,
}

/// Whether `name` names an object layer: `OBJECTS` (vanilla) or
/// `room:<id>/claimed-object` (per-room layouts).
pub fn is_object_layer_name(name: &str) -> bool {
    name == DsgLayer::default_name(LayerKey::OBJECTS)
        || name
            .strip_prefix("room:")
            .and_then(|r| r.strip_suffix("/claimed-object"))
            .is_some_and(|id| id.parse::<u64>().is_ok())
}

impl<'a, V: SceneView> Objects<'a, V> {
    /// Finds the object layers, the object-mesh layers and the objects claiming geometry
    /// of `view`.
    ///
    /// # Complexity
    /// O(layers + objects + their children) for the object layers, and one pass over
    /// the mesh layers' nodes for a box around each layer (their boxes where the layout
    /// keeps them, their points otherwise).
    pub fn new(view: &'a V) -> Self {
        Self::build(view, false, |_| true)
    }

    /// Like [`Objects::new`], restricted to the objects in the sub-tree of `root` (a
    /// room, say): every query then answers among those objects only.
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
        Self::build(view, true, |n| {
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

    /// [`Objects::new`] over the object nodes `keep` accepts; `scoped`: keep only the
    /// mesh layers holding their geometry.
    fn build(view: &'a V, scoped: bool, keep: impl Fn(V::NodeRef<'a>) -> bool) -> Self {
        let mut mesh_layers: Vec<LayerId> = object_mesh_layers(view)
            .into_iter()
            .map(|(l, _)| l)
            .collect();
        mesh_layers.sort_unstable();
        mesh_layers.dedup();
        // Object layers by name, plus any DAG parent of an object-mesh layer (the layer
        // objects live in, whatever the source file called it).
        let mut object_layers: Vec<LayerId> = view
            .layers()
            .filter(|&l| view.layer_name(l).is_some_and(is_object_layer_name))
            .chain(mesh_layers.iter().flat_map(|&m| view.layer_parents(m)))
            .collect();
        object_layers.sort_unstable();
        object_layers.dedup();
        let mut claimants = Vec::new();
        // The mesh layers holding the kept objects' mesh nodes.
        let mut used_layers = Vec::new();
        let mut kept = FxHashSet::default();
        for &layer in &object_layers {
            for n in view.layer_nodes(layer).filter(|&n| keep(n)) {
                if scoped {
                    kept.insert(view.node_id(n));
                }
                // Every mesh child when there are few of them (one per object except in
                // saffron) or the object keeps no box; else the first, to know it has one.
                let children = view.children(n);
                let all = view.aabb(n).is_none() || children.len() <= MAX_PART_CHILDREN;
                let mut mesh: Vec<V::NodeRef<'a>> = Vec::new();
                let mut only_mesh = true;
                for &c in children {
                    let Some(c) = view.node(c) else {
                        only_mesh = false;
                        continue;
                    };
                    let l = view.node_layer(c);
                    if mesh_layers.binary_search(&l).is_err() {
                        only_mesh = false;
                        continue;
                    }
                    if all || mesh.is_empty() {
                        mesh.push(c);
                    }
                    if used_layers.last() != Some(&l) {
                        used_layers.push(l);
                    }
                    only_mesh &= view.children(c).is_empty();
                }
                if mesh.is_empty() {
                    continue;
                }
                let indexed_mesh = only_mesh
                    && view.aabb(n).is_some()
                    && view.node_index(view.node_id(n)).is_some();
                // The object's own box (mint, saffron) holds its whole sub-tree; else the
                // box around its mesh nodes' points.
                let bbox = view.aabb(n).or_else(|| {
                    mesh.iter()
                        .filter_map(|&m| Aabb::from_points(view.points(m)))
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
        if scoped {
            // Only the layers holding the kept objects' geometry.
            used_layers.sort_unstable();
            used_layers.dedup();
            mesh_layers = used_layers;
        }
        claimants.sort_unstable_by_key(|c| c.id);
        claimants.dedup_by_key(|c| c.id);
        let claimant_ids = claimants.iter().map(|c| c.id).collect();
        let layer_boxes = mesh_layers
            .iter()
            .map(|&l| {
                view.layer_nodes(l)
                    .filter_map(|n| view.aabb(n).or_else(|| Aabb::from_points(view.points(n))))
                    .reduce(|a, b| a.union(&b))
            })
            .collect();
        Objects {
            view,
            object_layers,
            mesh_layers,
            layer_boxes,
            claimants,
            parts: OnceLock::new(),
            claimant_ids,
            kept: scoped.then_some(kept),
        }
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
    fn is_kept(&self, id: NodeId) -> bool {
        self.kept.as_ref().is_none_or(|k| k.contains(&id))
    }

    /// The objects that claim at least one mesh vertex, ascending.
    pub fn objects_with_geometry(&self) -> impl Iterator<Item = NodeId> + '_ {
        self.claimants.iter().map(|c| c.id)
    }

    /// The object owning mesh node `mesh` (its parent, when that is an object with
    /// geometry).
    fn owner(&self, mesh: NodeId) -> Option<NodeId> {
        let parent = self.view.parent(self.view.node(mesh)?)?;
        self.claimant_ids.contains(&parent).then_some(parent)
    }

    /// The object with the vertex closest to `point`; ties go to the smaller id.
    /// `None` when no object claims a vertex.
    ///
    /// # Errors
    /// [`SpatialQueryError::NonFinitePoint`] (as [`ObjectQueryError::Spatial`]).
    ///
    /// # Complexity
    /// One [`ygg_store::query::nearest_nodes`] (`m = 1`) per object-mesh layer (a kd-tree
    /// search where the layer has an index; repeated with a larger `m` only while mesh
    /// nodes without an object come first), then one [`ygg_store::query::nodes_within_radius`]
    /// at the best distance on the layer(s) holding it, to resolve exact ties.
    pub fn nearest_object(&self, point: Point) -> Result<Option<NodeId>, ObjectQueryError> {
        check_point(&point)?;
        // The closest claimed mesh node of each layer, nearest layer boxes first; a layer
        // whose box is farther than the best distance so far cannot hold a closer node
        // (nor a tie).
        let mut order: Vec<(f64, LayerId)> = self
            .mesh_layers
            .iter()
            .zip(&self.layer_boxes)
            .filter_map(|(&l, b)| Some((lower_bound(b.as_ref()?, &point), l)))
            .collect();
        order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut best_d: Option<f32> = None;
        let mut closest: Vec<(LayerId, f32)> = Vec::with_capacity(order.len());
        for (bound, layer) in order {
            if best_d.is_some_and(|b| bound > f64::from(b)) {
                break;
            }
            let mut m = 1usize;
            let found = loop {
                let found = query::nearest_nodes(self.view, Scope::Layer(layer), point, m)?;
                let first = found.iter().find(|&&(mesh, _)| self.owner(mesh).is_some());
                match first {
                    Some(&(_, d)) => break Some(d),
                    // Only mesh nodes without an object so far (vanilla's unclaimed
                    // vertices): look further.
                    None if found.len() == m => m = m.saturating_mul(4),
                    None => break None,
                }
            };
            if let Some(d) = found {
                closest.push((layer, d));
                if best_d.is_none_or(|b| d < b) {
                    best_d = Some(d);
                }
            }
        }
        let Some(d0) = best_d else {
            return Ok(None);
        };
        // Every mesh node at exactly that distance ties (none is closer): the radius
        // query with radius d0 finds exactly them, and their smallest owner wins.
        let mut winner: Option<NodeId> = None;
        for &(layer, d) in &closest {
            if d != d0 {
                continue;
            }
            for mesh in query::nodes_within_radius(self.view, Scope::Layer(layer), point, d0)? {
                if let Some(owner) = self.owner(mesh)
                    && winner.is_none_or(|w| owner < w)
                {
                    winner = Some(owner);
                }
            }
        }
        Ok(winner)
    }

    /// Every object with a vertex at distance `<= radius` from `point`, ascending.
    ///
    /// # Errors
    /// [`SpatialQueryError::NonFinitePoint`], [`SpatialQueryError::InvalidRadius`] (as
    /// [`ObjectQueryError::Spatial`]).
    ///
    /// # Complexity
    /// Where every object keeps a box and a node index over exactly its vertices (mint,
    /// saffron): one box test per object, and for an object whose box straddles the
    /// ball a kd-tree search of its node index that stops at the first vertex within
    /// `radius`. Elsewhere: one [`ygg_store::query::nodes_within_radius`] per object-mesh
    /// layer (a kd-tree range search where the layer has an index), then one parent
    /// lookup per mesh node found.
    pub fn objects_within(
        &self,
        point: Point,
        radius: f32,
    ) -> Result<Vec<NodeId>, ObjectQueryError> {
        check_point(&point)?;
        if !(radius.is_finite() && radius >= 0.0) {
            return Err(SpatialQueryError::InvalidRadius(radius).into());
        }
        let mut out = Vec::new();
        if !self.claimants.is_empty() && self.claimants.iter().all(|c| c.indexed_mesh) {
            let r2 = query::radius_bound(radius);
            for c in &self.claimants {
                let Some(b) = c.bbox else { continue };
                // The box bounds the object's vertices: entirely beyond the ball, or
                // entirely inside it (and it holds at least one vertex).
                if b.distance_squared_to(&point) > r2 {
                    continue;
                }
                let within = farthest_distance2(&b, &point) <= r2
                    || match self.view.node_index(c.id) {
                        Some(index) => any_within(&index, &point, r2),
                        None => query::nearest_in_subtree(self.view, c.id, point, 1)?
                            .first()
                            .is_some_and(|&(_, d)| d <= radius),
                    };
                if within {
                    out.push(c.id); // claimants ascend by id
                }
            }
            return Ok(out);
        }
        for (&layer, b) in self.mesh_layers.iter().zip(&self.layer_boxes) {
            if b.is_none_or(|b| lower_bound(&b, &point) > f64::from(radius)) {
                continue;
            }
            let found = query::nodes_within_radius(self.view, Scope::Layer(layer), point, radius)?;
            out.extend(found.into_iter().filter_map(|m| self.owner(m)));
        }
        out.sort_unstable();
        out.dedup();
        Ok(out)
    }

    /// Every object with a vertex `v` such that `|v - eye| <= range` and the angle
    /// between `v - eye` and `dir` is at most `half_angle_deg` degrees, ascending.
    ///
    /// # Errors
    /// [`SpatialQueryError::NonFinitePoint`] (eye), [`SpatialQueryError::InvalidDirection`]
    /// (zero or non-finite `dir`), [`SpatialQueryError::InvalidRange`], and
    /// [`ObjectQueryError::InvalidHalfAngleDeg`] outside `[0, 180]`.
    ///
    /// # Complexity
    /// Classifies each object's box, then its up to eight part boxes (computed by the
    /// first call, one pass over the claimed vertices), against the cone with margins far above rounding: a box
    /// clearly outside rules its vertices out, a non-empty box clearly inside answers
    /// yes. Only an object that neither settles is searched: for an object of many mesh
    /// nodes whose node index holds exactly its vertices (saffron), one radius search of
    /// that index over a ball around the cone, testing points against the cone until the
    /// first one inside; otherwise [`ygg_store::query::visible`] from the object (a scan of
    /// its vertices that stops at the first visible one).
    pub fn visible_objects(
        &self,
        eye: Point,
        dir: Point,
        half_angle_deg: f32,
        range: f32,
    ) -> Result<Vec<NodeId>, ObjectQueryError> {
        let cone = cone_view(eye, dir, half_angle_deg, range)?;
        let reach = Reach::new(&cone);
        let parts = self.parts.get_or_init(|| {
            self.claimants
                .iter()
                .map(|c| match (&c.bbox, c.mesh.is_empty()) {
                    (Some(around), false) => {
                        let sets: Vec<&[Point]> =
                            c.mesh.iter().map(|&m| self.view.points(m)).collect();
                        octant_boxes(&sets, around)
                    }
                    _ => Vec::new(),
                })
                .collect()
        });
        let mut out = Vec::new();
        for (c, parts) in self.claimants.iter().zip(parts) {
            match c.bbox.map(|b| reach.classify(&b)) {
                Some(Sight::Outside) => continue,
                // The box holds the object's claimed vertices, and lies inside the cone.
                Some(Sight::Inside) => {
                    out.push(c.id);
                    continue;
                }
                Some(Sight::Maybe) | None => {}
            }
            // The same with the part boxes: one inside proves a visible vertex (each
            // holds one), all outside prove none.
            if !parts.is_empty() {
                let (mut inside, mut outside) = (false, true);
                for p in parts {
                    match reach.classify(p) {
                        Sight::Inside => {
                            inside = true;
                            break;
                        }
                        Sight::Maybe => outside = false,
                        Sight::Outside => {}
                    }
                }
                if inside {
                    out.push(c.id);
                }
                if inside || outside {
                    continue;
                }
            }
            // An object of many mesh nodes (no part boxes: saffron's one per vertex) whose
            // node index holds exactly its vertices: a yes or no from the index, without
            // a node lookup per vertex found.
            if c.indexed_mesh
                && c.mesh.is_empty()
                && let Some(index) = self.view.node_index(c.id)
            {
                if query::index_sees(&index, &cone)? {
                    out.push(c.id);
                }
                continue;
            }
            let seen = query::visible(self.view, c.id, &cone)?;
            if seen.iter().any(|&m| self.is_mesh_node(m)) {
                out.push(c.id);
            }
        }
        Ok(out)
    }

    /// Every object node carrying `label`, ascending (O(1) for a label no node has).
    pub fn objects_with_label(&self, label: &str) -> Vec<NodeId> {
        let mut out: Vec<NodeId> = self
            .view
            .layers_with_label(label)
            .filter(|l| self.object_layers.binary_search(l).is_ok())
            .flat_map(|l| {
                self.view
                    .nodes_with_label(l, label)
                    .map(|n| self.view.node_id(n))
            })
            .filter(|id| self.is_kept(*id))
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Answers one query of the contract: ids ascending (at most one for
    /// [`ObjectQuery::NearestObject`]).
    ///
    /// # Errors
    /// As the query's method.
    pub fn answer(&self, q: &ObjectQuery) -> Result<Vec<NodeId>, ObjectQueryError> {
        match q {
            ObjectQuery::NearestObject { point } => {
                Ok(self.nearest_object(*point)?.into_iter().collect())
            }
            ObjectQuery::ObjectsWithin { point, radius } => self.objects_within(*point, *radius),
            ObjectQuery::VisibleObjects {
                eye,
                dir,
                half_angle_deg,
                range,
            } => self.visible_objects(*eye, *dir, *half_angle_deg, *range),
            ObjectQuery::ObjectsWithLabel { label } => Ok(self.objects_with_label(label)),
        }
    }

    fn is_mesh_node(&self, id: NodeId) -> bool {
        self.view.node(id).is_some_and(|n| {
            self.mesh_layers
                .binary_search(&self.view.node_layer(n))
                .is_ok()
        })
    }
}

/// The store's view cone for a half-angle in degrees, checked.
///
/// The half-angle is converted with `f32::to_radians` (and clamped to `π`, which
/// 180° may round just above), so every caller builds the very same cone.
///
/// # Errors
/// As [`Objects::visible_objects`].
pub fn cone_view(
    eye: Point,
    dir: Point,
    half_angle_deg: f32,
    range: f32,
) -> Result<ConeView, ObjectQueryError> {
    if !(half_angle_deg.is_finite() && (0.0..=180.0).contains(&half_angle_deg)) {
        return Err(ObjectQueryError::InvalidHalfAngleDeg(half_angle_deg));
    }
    let cone = ConeView {
        eye,
        dir,
        half_angle: half_angle_deg.to_radians().min(std::f32::consts::PI),
        range,
    };
    cone.contains(&eye)?; // checks eye, direction, half-angle and range
    Ok(cone)
}

fn check_point(p: &Point) -> Result<(), SpatialQueryError> {
    if p.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(SpatialQueryError::NonFinitePoint(*p))
    }
}

/// Where a box lies with respect to a view cone.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Sight {
    /// Every point of the box is outside the cone.
    Outside,
    /// Every point of the box is inside the cone.
    Inside,
    /// Either may be true.
    Maybe,
}

/// Conservative tests of boxes against a view cone: [`Sight::Outside`] and
/// [`Sight::Inside`] only when provable with margins far above the rounding of the
/// cone's own test, so they never contradict [`ConeView::contains`] on any point.
struct Reach {
    eye: [f64; 3],
    /// Unit direction, normalised as the cone normalises it.
    dir: [f64; 3],
    range2: f64,
    /// `cos` and `sin` of the half-angle.
    cos_half: f64,
    sin_half: f64,
    /// `cos` of the half-angle less [`Reach::ANGLE_MARGIN`], when that narrower cone is
    /// convex and not degenerate (for [`Reach::holds`]).
    cos_narrow: Option<f64>,
    /// The squared range less a relative 1e-6 (for [`Reach::holds`]).
    range2_short: f64,
}

impl Reach {
    /// Margin (radians, and relative distance) far above the rounding of the cone's
    /// test and of these tests (about 1e-8 at worst), so that a box is classified only
    /// when it is clearly outside or inside.
    const ANGLE_MARGIN: f64 = 1e-5;

    fn new(cone: &ConeView) -> Self {
        let d = cone.dir.map(f64::from);
        let norm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let half = f64::from(cone.half_angle);
        let narrow = half - Self::ANGLE_MARGIN;
        let range2 = f64::from(cone.range) * f64::from(cone.range);
        Reach {
            eye: cone.eye.map(f64::from),
            dir: [d[0] / norm, d[1] / norm, d[2] / norm],
            range2,
            cos_half: half.cos(),
            sin_half: half.sin(),
            cos_narrow: (1e-4..=std::f64::consts::FRAC_PI_2 - 1e-4)
                .contains(&narrow)
                .then(|| narrow.cos()),
            range2_short: range2 * (1.0 - 1e-6) * (1.0 - 1e-6),
        }
    }

    fn classify(&self, b: &Aabb) -> Sight {
        if !self.may_see(b) {
            Sight::Outside
        } else if self.holds(b) {
            Sight::Inside
        } else {
            Sight::Maybe
        }
    }

    /// Whether every point of the box is inside the cone. For a half-angle of at most
    /// 90° the cone cut by the range ball is convex, so it holds the box when it holds
    /// its eight corners; the corners are tested against a cone narrower by
    /// [`Reach::ANGLE_MARGIN`] and shorter by a relative 1e-6.
    fn holds(&self, b: &Aabb) -> bool {
        let Some(cos_h) = self.cos_narrow else {
            return false;
        };
        (0..8u32).all(|corner| {
            let pick = |a: usize| {
                let c = if corner >> a & 1 == 1 {
                    b.max[a]
                } else {
                    b.min[a]
                };
                f64::from(c) - self.eye[a]
            };
            let v = [pick(0), pick(1), pick(2)];
            let d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            if d2 > self.range2_short {
                return false;
            }
            let dot = v[0] * self.dir[0] + v[1] * self.dir[1] + v[2] * self.dir[2];
            d2 == 0.0 || dot >= cos_h * d2.sqrt()
        })
    }

    /// Whether some point of the box may be inside the cone (false only when provably
    /// none is).
    fn may_see(&self, b: &Aabb) -> bool {
        // Range: the box's closest point is farther than the range.
        if box_distance2(b, &self.eye) > self.range2 {
            return false;
        }
        // Angle: the ball around the box (centre c, radius rho) against the cone. With
        // v = c - eye split into `axial` along the direction and `radial` across it,
        // every point outside the cone at angle theta > half from the axis lies at least
        // |v| sin(theta - half) = radial cos(half) - axial sin(half) from the cone, so a
        // ball whose centre is farther than rho (plus a margin) from it lies outside.
        let mut v = [0.0; 3];
        let mut rho2 = 0.0;
        for (a, va) in v.iter_mut().enumerate() {
            let (lo, hi) = (f64::from(b.min[a]), f64::from(b.max[a]));
            *va = (lo + hi) / 2.0 - self.eye[a];
            rho2 += (hi - lo) * (hi - lo) / 4.0;
        }
        let len2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        let axial = v[0] * self.dir[0] + v[1] * self.dir[1] + v[2] * self.dir[2];
        let radial = (len2 - axial * axial).max(0.0).sqrt();
        let gap = radial * self.cos_half - axial * self.sin_half;
        gap <= rho2.sqrt() * (1.0 + 1e-9) + Self::ANGLE_MARGIN * len2.sqrt()
    }
}

/// An upper bound of [`ygg_store::distance_squared`] from `c` to any point inside `b`: per
/// axis the farther face, evaluated in the same order (rounding is monotone, so no point
/// of the box is farther).
fn farthest_distance2(b: &Aabb, c: &Point) -> f32 {
    let v = [0, 1, 2].map(|a| {
        let (lo, hi) = (b.min[a] - c[a], b.max[a] - c[a]);
        (lo * lo).max(hi * hi)
    });
    v[0] + v[1] + v[2]
}

/// Whether `index` holds a point at squared distance `<= r2` from `c`: a nearest-point
/// search bounded by `r2` that drops its bound below zero at the first such point, so
/// that it prunes everything left.
fn any_within<I: SpatialIndex>(index: &I, c: &Point, r2: f32) -> bool {
    let mut hit = false;
    index.nearest_visit(c, |d2, _| {
        if d2 <= r2 {
            hit = true;
            -1.0
        } else {
            r2
        }
    });
    hit
}

/// A lower bound of the distance (as the spatial queries compute it in `f32`) from `c`
/// to any point inside `b`: the exact box distance less a relative margin far above
/// `f32` rounding.
fn lower_bound(b: &Aabb, c: &Point) -> f64 {
    box_distance2(b, &c.map(f64::from)).sqrt() * (1.0 - 1e-5)
}

/// Squared distance from `eye` to the box, evaluated like the cone's range test (per
/// axis differences exact in `f64`, squares summed in the same order), so that a box
/// farther than the range proves every point inside it farther too.
fn box_distance2(b: &Aabb, eye: &[f64; 3]) -> f64 {
    let v = [0, 1, 2].map(|a| {
        let (lo, hi) = (f64::from(b.min[a]), f64::from(b.max[a]));
        if eye[a] < lo {
            lo - eye[a]
        } else if eye[a] > hi {
            eye[a] - hi
        } else {
            0.0
        }
    });
    v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
}

/// [`Objects::nearest_object`] on `view` (builds an [`Objects`] for one query).
///
/// # Errors
/// As [`Objects::nearest_object`].
///
/// # Examples
/// ```
/// # use ygg_dsg::{office, layout::{self, Layout}, objects};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let g = layout::build(&office::generate(office::OfficeParams { seed: 7, scale: 0.02 }), Layout::Mint)?;
/// let id = objects::nearest_object(&g, [5.0, 5.0, 1.0])?.expect("the office has objects");
/// assert!(objects::objects_within(&g, [5.0, 5.0, 1.0], 100.0)?.contains(&id));
/// # Ok(()) }
/// ```
pub fn nearest_object<V: SceneView>(
    view: &V,
    point: Point,
) -> Result<Option<NodeId>, ObjectQueryError> {
    Objects::new(view).nearest_object(point)
}

/// [`Objects::objects_within`] on `view` (builds an [`Objects`] for one query).
///
/// # Errors
/// As [`Objects::objects_within`].
///
/// # Examples
/// ```
/// # use ygg_dsg::{office, layout::{self, Layout}, objects};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let g = layout::build(&office::generate(office::OfficeParams { seed: 7, scale: 0.02 }), Layout::Mint)?;
/// let all = objects::objects_within(&g, [20.0, 12.0, 1.5], 1000.0)?;
/// assert_eq!(all.len(), 34); // every object of the tiny office
/// assert!(objects::objects_within(&g, [500.0, 0.0, 0.0], 1.0)?.is_empty());
/// # Ok(()) }
/// ```
pub fn objects_within<V: SceneView>(
    view: &V,
    point: Point,
    radius: f32,
) -> Result<Vec<NodeId>, ObjectQueryError> {
    Objects::new(view).objects_within(point, radius)
}

/// [`Objects::visible_objects`] on `view` (builds an [`Objects`] for one query).
///
/// # Errors
/// As [`Objects::visible_objects`].
///
/// # Examples
/// ```
/// # use ygg_dsg::{office, layout::{self, Layout}, objects};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let g = layout::build(&office::generate(office::OfficeParams { seed: 7, scale: 0.02 }), Layout::Mint)?;
/// // A full sphere of view sees everything in range; a zero direction is an error.
/// let seen = objects::visible_objects(&g, [20.0, 12.0, 1.5], [1.0, 0.0, 0.0], 180.0, 1000.0)?;
/// assert_eq!(seen.len(), 34);
/// assert!(objects::visible_objects(&g, [0.0; 3], [0.0; 3], 30.0, 5.0).is_err());
/// # Ok(()) }
/// ```
pub fn visible_objects<V: SceneView>(
    view: &V,
    eye: Point,
    dir: Point,
    half_angle_deg: f32,
    range: f32,
) -> Result<Vec<NodeId>, ObjectQueryError> {
    Objects::new(view).visible_objects(eye, dir, half_angle_deg, range)
}

/// [`Objects::objects_with_label`] on `view` (builds an [`Objects`] for one query).
///
/// # Examples
/// ```
/// # use ygg_dsg::{office, layout::{self, Layout}, objects};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let g = layout::build(&office::generate(office::OfficeParams { seed: 7, scale: 0.02 }), Layout::Mint)?;
/// assert_eq!(objects::objects_with_label(&g, "light").len(), 4);
/// assert!(objects::objects_with_label(&g, "absent").is_empty());
/// # Ok(()) }
/// ```
pub fn objects_with_label<V: SceneView>(view: &V, label: &str) -> Vec<NodeId> {
    Objects::new(view).objects_with_label(label)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn queries_parse_from_json_lines() {
        let q = ObjectQuery::from_json(r#"{"op":"nearest_object","point":[1,2.5,-3]}"#);
        assert_eq!(
            q,
            Ok(ObjectQuery::NearestObject {
                point: [1.0, 2.5, -3.0]
            })
        );
        let q = ObjectQuery::from_json(
            r#"{"op":"visible_objects","eye":[0,0,1],"dir":[1,0,0],"half_angle_deg":30,"range":4}"#,
        );
        assert!(matches!(q, Ok(ObjectQuery::VisibleObjects { .. })));
        for (bad, says) in [
            (
                r#"{"op":"nearest_object","point":[1,2]}"#,
                "field \"point\"",
            ),
            (
                r#"{"op":"nearest_object","point":[1,2,3],"radius":1}"#,
                "\"radius\"",
            ),
            (r#"{"op":"teleport"}"#, "teleport"),
            (r#"{"point":[1,2,3]}"#, "missing field \"op\""),
            (r#"{"op":7}"#, "\"op\" must be a string"),
            (
                r#"{"op":"objects_with_label","label":7}"#,
                "field \"label\"",
            ),
            (r#"{"op":"objects_with_label"}"#, "missing field \"label\""),
            (
                r#"{"op":"objects_within","point":[0,0,0],"radius":"far"}"#,
                "\"far\"",
            ),
            (r#"[1,2,3]"#, "expected a JSON object"),
            (r#"{"op":"nearest_object""#, "malformed JSON"),
        ] {
            let e = ObjectQuery::from_json(bad).unwrap_err();
            assert!(e.contains(says), "{bad}: {e}");
        }
        // Serializing gives the same line back.
        let q = ObjectQuery::ObjectsWithLabel {
            label: "light".into(),
        };
        let line = serde_json::to_string(&q).unwrap();
        assert_eq!(line, r#"{"op":"objects_with_label","label":"light"}"#);
        assert_eq!(ObjectQuery::from_json(&line), Ok(q));
    }

    #[test]
    fn half_angles_in_degrees_are_checked() {
        let ok = |a: f32| cone_view([0.0; 3], [1.0, 0.0, 0.0], a, 1.0).is_ok();
        assert!(ok(0.0) && ok(45.0) && ok(180.0));
        assert!(!ok(-1.0) && !ok(180.5) && !ok(f32::NAN) && !ok(f32::INFINITY));
        assert!(cone_view([0.0; 3], [0.0; 3], 30.0, 1.0).is_err());
        assert!(cone_view([0.0; 3], [1.0, 0.0, 0.0], 30.0, -1.0).is_err());
    }

    #[test]
    fn reach_never_contradicts_the_cone_test() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let (mut skipped, mut inside) = (0, 0);
        for _ in 0..20_000 {
            let lo: Point = [0, 1, 2].map(|_| rng.gen_range(-5.0..5.0));
            let size: Point = [0, 1, 2].map(|_| rng.gen_range(0.0..2.0));
            let hi: Point = [0, 1, 2].map(|a| lo[a] + size[a]);
            let b = Aabb::from_points(&[lo, hi]).unwrap();
            let dir: Point = [0, 1, 2].map(|_| rng.gen_range(-1.0..1.0));
            let Ok(cone) = cone_view(
                [0, 1, 2].map(|_| rng.gen_range(-6.0..6.0)),
                dir,
                rng.gen_range(0.0..180.0),
                rng.gen_range(0.0..12.0),
            ) else {
                continue;
            };
            let reach = Reach::new(&cone);
            let sight = reach.classify(&b);
            let sees = sight != Sight::Outside;
            skipped += usize::from(!sees);
            inside += usize::from(sight == Sight::Inside);
            for i in 0..64 {
                let p: Point = if i < 8 {
                    [0, 1, 2].map(|a| if i >> a & 1 == 1 { hi[a] } else { lo[a] })
                } else {
                    [0, 1, 2].map(|a| rng.gen_range(lo[a]..=hi[a]))
                };
                let contains = cone.contains(&p).unwrap();
                if contains {
                    assert!(sees, "{cone:?} sees {p:?} in {b:?}");
                } else {
                    assert!(sight != Sight::Inside, "{cone:?} misses {p:?} in {b:?}");
                }
            }
        }
        assert!(
            skipped > 5_000,
            "the test should exercise skipping: {skipped}"
        );
        assert!(inside > 200, "the test should exercise accepting: {inside}");
    }

    #[test]
    fn box_distance_is_zero_inside() {
        let b = Aabb::from_points(&[[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]]).unwrap();
        assert_eq!(box_distance2(&b, &[0.5, 0.5, 0.5]), 0.0);
        assert_eq!(box_distance2(&b, &[3.0, 2.0, 3.0]), 4.0);
    }
}
