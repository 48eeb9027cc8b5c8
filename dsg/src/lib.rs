//! Spark-DSG support for Yggdrasil: the Spark-DSG model, its files, the paper's layouts
//! and the object queries.
//!
//! * [`layout::build`] turns a Spark-DSG graph into a [`ygg_store::SceneGraph`] in one of
//!   the paper's layouts ([`layout::Layout`]). [`layout::LayerRole`] says what each
//!   layer of such a scene holds.
//! * [`objects::Objects`] answers the object-query contract of `ygg query` on any
//!   view of such a scene, live or archived.
//! * [`replay::SlamReplay`] drives a SLAM-like stream of mutations over a built scene.
//!
//! The generic store (`ygg-store`) knows nothing of Spark-DSG; everything Spark-DSG lives
//! here. The plain-data model:
//!
//! * [`parse_json`] / [`read_file`] import Spark-DSG JSON files: v1.1.x (with
//!   `SPARK_DSG_header`, `layer_keys`, partitions, optional mesh) and the legacy
//!   v1.0 encoding written by older Hydra (no header, `layer_ids`, agent partitions
//!   from the node-level `timestamp` and the id's prefix). `.json.gz` is handled.
//! * [`parse_binary`] / [`parse_binary_body`] import Spark-DSG's binary format
//!   (`.sparkdsg` files, and the header-less `to_binary()` buffers Hydra sends over
//!   ZMQ), 1.0.2 to 1.1.3, into the same [`DsgGraph`] through the same checks;
//!   [`write_binary`] / [`to_binary_bytes`] export it. [`read_file`] tells the formats
//!   apart by content.
//! * [`office::generate`] builds a uHumans2-like office with the paper's counts, so
//!   benchmarks need no external file.
//! * [`DsgGraph::counts`] and [`DsgGraph::claim_stats`] summarise a graph (node and
//!   edge counts; unclaimed / multiply claimed vertices and wrong object boxes).
//!
//! # How Spark-DSG maps to [`DsgGraph`]
//!
//! | Spark-DSG | `DsgGraph` |
//! |---|---|
//! | node `id` (u64 `NodeSymbol`) | [`DsgNode::id`], unchanged |
//! | `layer` + `partition` | [`DsgNode::layer`] ([`LayerKey`]) |
//! | `attributes.type` | [`DsgNode::kind`] ([`NodeKind`]) |
//! | edge between nodes of one layer key | [`DsgGraph::edges`] |
//! | edge between partitions of one layer id | [`DsgGraph::sibling_edges`] |
//! | edge between layer ids | [`DsgNode::parent`] of the lower node |
//! | a second inter-layer edge above one node | [`DsgGraph::extra_parent_edges`] |
//! | `mesh` | [`DsgGraph::mesh`] (points, faces, labels; colors and stamps dropped) |
//! | `metadata.labelspaces` | [`DsgGraph::labelspaces`], and [`DsgNode::label`] |
//!
//! **Several parents.** The store allows one parent per node. The importer keeps the
//! first inter-layer edge (in file order) above a node as its parent, and records
//! every later one in [`DsgGraph::extra_parent_edges`] rather than failing, so that a
//! Hydra graph with an ambiguous nesting still loads and the choice stays visible.
//!
//! # Invariants
//! See [`DsgGraph`]. The importer checks them all and returns a [`DsgImportError`]
//! naming the file, node and field otherwise; it never panics on any input.
//!
//! # Strict and lenient import
//! Import is strict by default: the first fault is an error. Real Hydra output written
//! by older versions holds faults Spark-DSG itself refuses (an edge to an absent node,
//! say). [`ImportOptions::LENIENT`] ([`read_file_with`], [`import_file`],
//! [`parse_json_with`], [`parse_binary_with`]; `ygg import --lenient`) imports
//! what can be imported: it drops the items of every [`DropClass`] and returns an
//! [`ImportReport`] with each class dropped, its count and its first example, so
//! nothing is lost silently. The resulting [`DsgGraph`] keeps every invariant.

#[cfg(not(target_endian = "little"))]
compile_error!("ygg-dsg builds scenes for ygg-store, which supports little-endian targets only");

mod binary;
mod diag;
mod error;
mod io;
mod json;
mod model;
mod progress;
mod raw;
mod report;
mod symbol;
mod update;

pub mod layout;
pub mod objects;
pub mod office;
pub mod replay;

#[doc(inline)]
pub use self::binary::{
    BodyStream, ChangedNodes, StreamStep, is_binary, parse_binary, parse_binary_body,
    parse_binary_with, parse_binary_with_progress, to_binary_body, to_binary_body_at,
    to_binary_bytes, to_binary_bytes_at, write_binary,
};
#[doc(inline)]
pub use self::error::DsgImportError;
#[doc(inline)]
pub use self::io::{import_file, read_file, read_file_with, read_file_with_progress};
#[doc(inline)]
pub use self::json::{DsgExportError, to_json_bytes, write_json, write_json_to};
#[doc(inline)]
pub use self::json::{parse_json, parse_json_with, parse_json_with_progress};
#[doc(inline)]
pub use self::model::{
    ClaimStats, DsgAabb, DsgCounts, DsgEdge, DsgGraph, DsgLayer, DsgMesh, DsgNode, DsgParentEdge,
    DsgVersion, LabelCount, LayerKey, NodeKind,
};
#[doc(inline)]
pub use self::progress::{ImportPhase, ImportProgress};
#[doc(inline)]
pub use self::report::{DropClass, DroppedItems, ImportOptions, ImportReport, Imported};
#[doc(inline)]
pub use self::symbol::NodeSymbol;
#[doc(inline)]
pub use self::update::{GraphUpdate, UpdateError, UpdateReport, update_between};
