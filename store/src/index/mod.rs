//! Spatial indexes: kd-trees over the points of one layer (a **layer index**) or of one
//! node's sub-tree (a **node index**), and the [`SpatialIndex`] trait that the spatial
//! queries in [`crate::query`] are written against.
//!
//! | index | type | kept by | items |
//! |---|---|---|---|
//! | live | [`LiveIndex`] over a [`LiveKdTree`] plus an overlay of nodes moved wholesale | [`crate::SceneGraph`], updated by every mutation | node handles |
//! | archived | [`ArchivedIndex`] over kiddo's archived `ImmutableKdTree` (a layer index: plus the rows patched since it was built, `archived/patched_rows.rs`) | the layer segment of a snapshot, queried zero-copy | rows / id-table positions |
//! | reader-built | [`KdIndex`]: kiddo's `ImmutableKdTree`, kept archived | a reader ([`build_layer_index`], [`build_subtree_index`], [`IndexCache`]) | id-table positions |
//!
//! kiddo builds the snapshot's and the readers' trees and answers their radius queries.
//! Nearest-node search is one branch-and-bound walk (see [`SpatialIndex::nearest_visit`]),
//! written once over read-only accessors that the live tree and kiddo's archived tree
//! both implement (`walk.rs`). The live graph uses its own dynamic tree, because
//! kiddo's `MutableKdTree` refuses inserts once a full bucket's points share the
//! coordinate it must split on (a wall, a floor, duplicates).
//!
//! Every index reports distances computed exactly as [`crate::distance_squared`]
//! computes them (the same expression in the same order; for kiddo's scalar kernel a
//! test pins this), so an indexed query returns what brute force returns, bit for bit.
//!
//! # Memory
//! An index stores each point's coordinates (12 bytes) and item (4 bytes). Measured
//! totals per point: 16.5–16.8 bytes archived (kiddo's leaves, extents and stems), about
//! 19.2 bytes live (leaves are bulk-built 7/8 full so that inserts rarely split one).
//! The live indexes of a graph share one handle table besides (item to node id: 8 bytes
//! per indexed node, grown by an eighth; [`crate::SceneGraph::index_handle_bytes`]).
//!
//! # Modules, bottom up
//! `spatial_index` (the trait), `walk` (the nearest walk over a kd-tree accessor),
//! `live/` (the live graph's indexes: `kdtree/`, the live kd-tree; `overlay`, moved nodes
//! over it; `graph_indexes`, one graph's indexes and their handle table), `archived/`
//! (kiddo's trees: `layout`, kiddo's archived layout, checked; `kdtree`, archived and
//! reader-built indexes; `patched_rows`, changed rows over an archived layer index),
//! `from_view` (indexes built from any view).

mod archived;
mod from_view;
mod live;
mod spatial_index;
mod walk;

pub use archived::{ArchivedIndex, ArchivedKdTree, KdIndex, KdTree, PartedIndex};
pub(crate) use archived::{RowPatch, build_tree, check_tree};
pub use from_view::{IndexCache, build_layer_index, build_subtree_index};
pub(crate) use live::{Entry, LiveIndexes, Located, NO_HANDLE, OverlaidTree};
pub use live::{LiveIndex, LiveKdTree};
pub use spatial_index::SpatialIndex;
