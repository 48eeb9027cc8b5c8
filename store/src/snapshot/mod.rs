//! Archived snapshots: the packed, column-oriented rkyv layout, `.ygg` files, and
//! [`ArchivedScene`], the [`crate::SceneView`] over validated archived bytes.
//!
//! A snapshot is one **manifest** segment (per-cut values: each layer's generation, node
//! count, id bounds) plus a **structure** segment (layer names, DAG, part lists, term
//! indexes; resent only when it changes) plus one or more **part** segments per layer
//! (row chunks over id ranges), and for a part of many points its point column in
//! **chunk** segments (`chunk`). A layer
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
//! # Modules: what a reader runs apart from what only a publishing writer runs
//! Shared: `schema` (the archived types both sides agree on), `chunking` (chunk sizes,
//! which layers and trees travel as chunks, chunk segment ids).
//!
//! `read/`, what a reader runs on untrusted bytes: `validate` (bytecheck and the
//! consistency pass), `chunk_check` (chunks on their own and against their layer), `cut`
//! (joining and checking a cut: [`ArchivedScene`]), `rejoin` (what a reader need not
//! check again in its next cut), `scene_view` (the [`crate::SceneView`] of an
//! [`ArchivedScene`]), `file` (`.ygg` files: [`SnapshotFile`]; `SceneGraph::save`).
//!
//! `publish/`, what only a publishing writer runs on its live graph: `archive`
//! (archiving a layer or the whole graph), `by_parent` (the rows-by-parent column),
//! `chunk_source` (chunks archived from the live columns), `chunk_state` (which chunks a
//! patch touched), `layer_index_update` (patching or folding a layer index), and
//! `segment_cache` ([`SegmentCache`], incremental segments per publish).

mod chunking;
mod publish;
mod read;
mod schema;

pub use crate::bytes::{ARCHIVE_ALIGN, SegmentBytes, archive};
pub use chunking::{
    MANIFEST_SEGMENT_ID, MAX_CHUNKS_PER_LAYER, MAX_LAYER_ID, MAX_PART_ROWS, MAX_PARTS_PER_LAYER,
    MAX_POINT_CHUNK_LEN, PART_ITEM_ROW_BITS, PART_ROWS, POINT_CHUNK_LEN, STRUCTURE_SEGMENT_ID,
    TREE_CHUNK_MIN_POINTS, WITHHELD_TREE_MAX_MEMBERS, chunk_segment_id, is_chunk_segment_id,
    is_part_segment_id, is_structure_segment_id, is_tree_chunk_segment_id, part_segment_id,
    segment_layer_part, tree_chunk_segment_id,
};
pub use publish::{
    ArchivedGraph, CutBytes, PointChunkSource, PublishedLayer, PublishedParts, SegmentCache,
    TreeChunkSource,
};
pub use read::{
    ArchivedNodeRef, ArchivedScene, FILE_MAGIC, KnownParts, SnapshotFile, check_layer,
    chunk_unchecked, layer_unchecked, manifest_unchecked, structure_unchecked,
    tree_chunk_unchecked, validate_chunk, validate_layer, validate_manifest, validate_structure,
    validate_tree_chunk,
};
pub use schema::{
    ArchivedLayerIndexSegment, ArchivedLayerSegment, ArchivedManifest, ArchivedManifestLayer,
    ArchivedNodeIndexSegment, ArchivedPointChunk, ArchivedPointChunkRef, ArchivedStructure,
    ArchivedStructureLayer, ArchivedTreeChunk, ArchivedTreeChunkRef, FORMAT_VERSION,
    LayerIndexSegment, LayerSegment, Manifest, ManifestLayer, NodeIndexSegment, PointChunk,
    PointChunkRef, Structure, StructureLayer, TreeChunk, TreeChunkRef,
};
