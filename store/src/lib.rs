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
//! * See [`recording`] for recording a live scene's cuts and querying any of them in
//!   place.
//! * See [`snapshot`] for archiving a graph and opening a `.ygg` file, and
//!   [`snapshot::SegmentCache`] for publishing a changing graph incrementally.
//!
//! # Where things are
//! | folder or file | what |
//! |---|---|
//! | `graph/` | the live graph: [`SceneGraph`] and every concern of `impl SceneGraph` (mutations, bounding boxes, live indexes, change journal, touch log, sync, invariants, its [`SceneView`]) |
//! | `view.rs` | [`SceneView`]: twelve required methods, the rest provided |
//! | `snapshot/` | the archived layout: `schema.rs` and `chunking.rs` shared, `read/` what readers run (validate, join a cut, rejoin, the archived [`SceneView`], `.ygg` files), `publish/` what only a publishing writer runs (archiving, segment cache, chunk state, layer index patches) |
//! | `index/` | spatial indexes: `live/` (the live kd-tree, its overlay, a graph's indexes), `archived/` (kiddo's trees in a snapshot or built by a reader), the shared nearest walk |
//! | `query/` | the queries: `pattern`, `spatial`, `fov`, `traverse` |
//! | `recording/` | recordings: the file format, [`recording::RecordingWriter`], [`recording::Recording`], what changed between two cuts |
//! | `id.rs`, `feature.rs`, `points.rs`, `bytes.rs`, `error.rs` | ids and boxes, feature values, point columns, aligned archive bytes, errors |

#[cfg(not(target_endian = "little"))]
compile_error!("ygg-store reads archived columns in place and supports little-endian targets only");

mod bytes;
mod error;
mod feature;
mod graph;
mod id;
pub mod index;
mod points;
pub mod query;
pub mod recording;
pub mod snapshot;
mod view;

pub use error::{EditResult, GraphEditError, SnapshotError};
pub use feature::{FeatureRef, FeatureValue};
pub use graph::{Node, SceneGraph, SyncReport, TouchMark};
pub use id::{Aabb, LayerId, NodeId, Point, distance_squared};
pub use points::{Points, PointsIter};
pub use query::Scope;
pub use snapshot::{ArchivedScene, SnapshotFile};
pub use view::{EdgeRef, SceneView};
