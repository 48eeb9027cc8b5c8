//! Object-level queries: the query contract of `ygg query`, answered on a scene
//! built by [`crate::layout::build`] in any layout, live or archived.
//!
//! # Contract
//! * Answers are **object ids** (the Spark-DSG node ids the layouts keep), ascending.
//! * The spatial scope is the **whole scene**.
//! * An object's **geometry** is the set of mesh vertices it claims: the points of the
//!   mesh node(s) nested under it in an object-mesh layer
//!   (the layers whose [`LayerRole::holds_object_mesh`]). A vertex claimed by several objects counts
//!   for each of them.
//! * An object that claims **no mesh vertex present in the file** (the file saves no
//!   mesh, as real Hydra output often does, or its `mesh_connections` is empty) is
//!   located by its position: its geometry is its `attributes.position`, one point, held
//!   by the one mesh node [`crate::layout::build`] nests under it on every layout. Its
//!   stored Spark-DSG `bounding_box` is not its geometry; it is kept as the object
//!   node's features [`STORED_BOX_FEATURES`] (min x, y, z, max x, y, z; the store's own
//!   box of an object, in mint and saffron, is the exact box of its geometry). The nodes
//!   of the other layers (places, rooms, agents, ...) have their position as geometry.
//! * [`Objects::nearest_object`]: the object with the closest vertex (distance as
//!   [`ygg_store::query::nearest_nodes`] defines it), ties to the smaller id.
//! * [`Objects::objects_within`]: every object with a vertex at distance `<= r`
//!   (exactly the test of [`ygg_store::query::nodes_within_radius`]).
//! * [`Objects::visible_objects`]: every object with a vertex `v` such that
//!   `|v - eye| <= range` and the angle between `v - eye` and `dir` is at most the
//!   half-angle (exactly the test of [`ygg_store::query::visible`] with a [`ygg_store::query::ConeView`]).
//! * [`Objects::objects_with_label`]: every object node carrying the label. An object
//!   carries its labelspace name (from the file's `metadata.labelspaces`; without one,
//!   its `name` unless that only spells its symbol) and always its decimal
//!   `semantic_label` (`"5"`): see [`crate::DsgNode::labels`]. Object
//!   nodes are the nodes of the object layers (those whose
//!   [`LayerRole::holds_objects`]): `OBJECTS` in vanilla, `room:<id>/claimed-object` in
//!   the per-room layouts.
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

//!
//! # Where things are
//! The query lines ([`ObjectQuery`]) in `query_line.rs`; the catalog of object and
//! object-mesh layers ([`Objects::new`]) in `catalog.rs`; nearest and radius queries in
//! `distance.rs`; visibility and the contract's cone ([`cone_view`]) in `visibility.rs`;
//! the one-query shortcuts ([`nearest_object`], ...) in `one_shot.rs`.
//!
//! [`LayerRole::holds_object_mesh`]: crate::layout::LayerRole::holds_object_mesh
//! [`LayerRole::holds_objects`]: crate::layout::LayerRole::holds_objects
//! [`STORED_BOX_FEATURES`]: crate::layout::STORED_BOX_FEATURES

mod catalog;
mod distance;
mod one_shot;
mod query_line;
mod visibility;

#[doc(inline)]
pub use self::catalog::{Objects, is_object_layer_name};
#[doc(inline)]
pub use self::one_shot::{nearest_object, objects_with_label, objects_within, visible_objects};
#[doc(inline)]
pub use self::query_line::ObjectQuery;
#[doc(inline)]
pub use self::visibility::cone_view;

use ygg_store::Point;
use ygg_store::query::SpatialQueryError;

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

fn check_point(p: &Point) -> Result<(), SpatialQueryError> {
    if p.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(SpatialQueryError::NonFinitePoint(*p))
    }
}
