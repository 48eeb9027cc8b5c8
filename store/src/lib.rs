//! Yggdrasil scene graph store: a layered 3D scene graph for robots.
//!
//! * See [`SceneGraph`] for the live, editable graph and its mutations.
//! * See [`SceneView`] for the one read interface, implemented by the live graph and by
//!   [`ArchivedScene`] (validated rkyv bytes from a `.ygg` file or shared memory).
//! * See [`query`] for the queries, written once over [`SceneView`].
//! * See [`index`] for the spatial indexes (live, archived, reader-built) behind the
//!   spatial queries.
//! * See [`SceneGraph::sync_to`] for making a graph equal another with the fewest
//!   mutations (a source that resends its whole graph).
//! * See [`snapshot`] for archiving a graph and opening a `.ygg` file, and
//!   [`snapshot::SegmentCache`] for publishing a changing graph incrementally.

#[cfg(not(target_endian = "little"))]
compile_error!("ygg-store reads archived columns in place and supports little-endian targets only");

mod bbox;
mod bytes;
mod change;
mod error;
mod feature;
mod graph;
mod graph_indexes;
mod id;
pub mod index;
mod invariants;
mod live_view;
mod point_change;
mod points;
pub mod query;
pub mod snapshot;
mod sync;
mod touch_log;
mod view;

pub use error::{EditResult, GraphEditError, SnapshotError};
pub use feature::{FeatureRef, FeatureValue};
pub use graph::{Node, SceneGraph};
pub use id::{Aabb, LayerId, NodeId, Point, distance_squared};
pub use points::{Points, PointsIter};
pub use query::Scope;
pub use snapshot::{ArchivedScene, SnapshotFile};
pub use sync::SyncReport;
pub use touch_log::TouchMark;
pub use view::{EdgeRef, SceneView};
