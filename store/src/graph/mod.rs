//! The live scene graph: [`SceneGraph`] and every concern of `impl SceneGraph`.
//!
//! | file | what |
//! |---|---|
//! | `scene_graph.rs` | [`SceneGraph`], [`Node`] and the mutations |
//! | `bounding_boxes.rs` | exact bounding boxes, kept on every change below them |
//! | `spatial_indexes.rs` | enabling the live layer and node indexes, and the hooks that keep them exact |
//! | `point_change.rs` | one node's points before and after a change, as boxes and indexes take it |
//! | `change_journal.rs` | what changed in a layer since a generation, for the publishing writer |
//! | `touch_log.rs` | which layers changed after a [`TouchMark`] |
//! | `sync.rs` | [`SceneGraph::sync_to`]: equal another graph with the fewest mutations |
//! | `invariants.rs` | [`SceneGraph::check_invariants`]: every invariant below, recounted |
//! | `scene_view.rs` | the [`crate::SceneView`] of the live graph |
//!
//! # Invariants (checked by [`SceneGraph::check_invariants`])
//! - Layers form a DAG; layer names are unique.
//! - Every node belongs to exactly one layer and appears once in that layer's node list.
//! - Edges join two distinct nodes of the same layer; `out_edges` and `in_edges` mirror
//!   each other and are sorted by the other end's id.
//! - A node has at most one parent; the parent's layer has a DAG edge to the child's
//!   layer; `children` lists mirror parent pointers and are sorted by id.
//! - A node with its bounding box enabled holds the exact AABB of every point in its
//!   sub-tree (or none when the sub-tree has no point).
//! - The inverted label and key indexes hold exactly the nodes carrying each term.
//!
//! Every mutation validates first and changes nothing when it returns an error.

mod bounding_boxes;
mod change_journal;
mod invariants;
mod point_change;
mod scene_graph;
mod scene_view;
mod spatial_indexes;
mod sync;
mod touch_log;

pub(crate) use change_journal::LayerChanges;
pub(crate) use point_change::PointChange;
pub(crate) use scene_graph::Layer;
pub use scene_graph::{Node, SceneGraph};
pub use sync::SyncReport;
pub use touch_log::TouchMark;
