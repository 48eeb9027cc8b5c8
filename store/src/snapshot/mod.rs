//! Archived snapshots: the packed, column-oriented rkyv layout, `.ygg` files, and
//! [`ArchivedScene`], the [`crate::SceneView`] over validated archived bytes.
//!
//! A snapshot is one **manifest** segment plus one **layer** segment per layer, and
//! for a layer of many points its point column in **chunk** segments (`chunk`). A layer
//! segment is a struct of arrays: sorted node ids, points with CSR offsets, parent ids
//! and the rows ordered by parent (a node's children are found in its layer's DAG
//! children, on the child's side), out- and in-edges in CSR form (rows within the layer), labels,
//! features, sparse bounding boxes and the inverted label/key indexes, plus the layer's
//! spatial indexes: its layer index and the node indexes rooted at its nodes, as kiddo's
//! archived kd-trees (queried in place; their leaves are 128-byte aligned inside the
//! 128-byte aligned segment). The same segments travel through shared memory; a `.ygg`
//! file stores them back to back.
//!
//! # Validation
//! Bytes are untrusted. [`validate_layer`] and [`validate_manifest`] run rkyv's
//! bytecheck and then [`check_layer`]'s consistency pass (offsets monotonic and in
//! range, rows in range, ids sorted, string indexes in range, kd-tree shapes, extents and
//! items in range), so that every accessor of [`ArchivedScene`] is total: no index it
//! computes can be out of bounds. Only after that do we re-derive references with
//! `access_unchecked`.
//!
//! # Row indexes
//! Inside a layer segment nodes are addressed by a dense `u32` row (their rank by id).
//! A row is valid only within that layer generation.
//!
//! # Modules
//! `schema` (the archived types), `archive` (archiving the live graph), `by_parent`
//! (the rows-by-parent column), `cache` (incremental segments for a publishing writer), `index_patch` (its patched layer
//! indexes), `file` (`.ygg` files), `validate`
//! (checking untrusted bytes), `rejoin` (what a reader need not check again in its next
//! cut), `view` ([`ArchivedScene`]).

mod archive;
mod by_parent;
mod cache;
mod chunk;
mod chunk_state;
mod file;
mod index_patch;
mod rejoin;
mod schema;
mod validate;
mod view;

pub use crate::bytes::{ARCHIVE_ALIGN, SegmentBytes, archive};
pub use cache::SegmentCache;
pub use chunk::{
    MAX_CHUNKS_PER_LAYER, MAX_LAYER_ID, MAX_POINT_CHUNK_LEN, POINT_CHUNK_LEN, PointChunkSource,
    TREE_CHUNK_MIN_POINTS, TreeChunkSource, WITHHELD_TREE_MAX_MEMBERS, chunk_segment_id,
    chunk_segment_layer, is_chunk_segment_id, is_tree_chunk_segment_id, tree_chunk_segment_id,
};
pub use chunk_state::{ChunkShape, PublishedLayer};
pub use file::{FILE_MAGIC, SnapshotFile};
pub use rejoin::{CheckedManifest, KnownParts};
pub use schema::{
    ArchivedLayerIndexSegment, ArchivedLayerSegment, ArchivedManifest, ArchivedManifestLayer,
    ArchivedNodeIndexSegment, ArchivedPointChunk, ArchivedPointChunkRef, ArchivedTreeChunk,
    ArchivedTreeChunkRef, FORMAT_VERSION, LayerIndexSegment, LayerSegment, Manifest, ManifestLayer,
    NodeIndexSegment, PointChunk, PointChunkRef, TreeChunk, TreeChunkRef,
};
pub use validate::{
    check_layer, chunk_unchecked, layer_unchecked, manifest_unchecked, tree_chunk_unchecked,
    validate_chunk, validate_layer, validate_manifest, validate_tree_chunk,
};
pub use view::{ArchivedNodeRef, ArchivedScene};
