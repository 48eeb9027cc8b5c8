//! The archived types: one [`LayerSegment`] per layer and a [`Manifest`] per cut, as
//! rkyv archives them.

use crate::index::KdTree;
use rkyv::vec::ArchivedVec;
use rkyv::{Archive, Serialize};
use std::collections::HashMap;

/// Version of the archived layout; bumped on every incompatible change.
pub const FORMAT_VERSION: u32 = 10;

/// Marks "no parent" in the parent column.
pub(crate) const NO_PARENT: u64 = u64::MAX;

/// One layer, or one part of a layer split into parts (its rows over a range of ids), as
/// archived: columns indexed by row (rank of the node id in the part).
#[derive(Archive, Serialize, Debug, Default)]
pub struct LayerSegment {
    /// [`FORMAT_VERSION`] of the writer.
    pub version: u32,
    /// The layer's id.
    pub layer: u32,
    /// The part's number within its layer (0 for a layer in one piece); the manifest
    /// lists a layer's part numbers in id order.
    pub part: u32,
    /// The generation of the part: the layer generation at which its rows last changed.
    pub generation: u64,
    /// The layer's name.
    pub name: String,
    /// Strings used by this layer (labels, keys, string values, edge descriptions).
    pub strings: Vec<String>,
    /// Node ids, strictly ascending.
    pub ids: Vec<u64>,
    /// CSR offsets into `points` (rows + 1 entries).
    pub point_offsets: Vec<u32>,
    /// Every point of every node of the layer, unless the layer is chunked: then empty,
    /// and the points lie in the [`PointChunk`] segments `point_chunks` lists.
    pub points: Vec<[f32; 3]>,
    /// For a chunked layer, its point column's chunks in order (each but the last holds
    /// `point_chunk_len` points); empty for a layer kept in one piece.
    pub point_chunks: Vec<PointChunkRef>,
    /// Points per chunk of a chunked layer (a power of two up to
    /// [`MAX_POINT_CHUNK_LEN`](super::MAX_POINT_CHUNK_LEN)); 0 for a layer in one piece.
    pub point_chunk_len: u32,
    /// Parent id of each row (`u64::MAX` for none).
    pub parents: Vec<u64>,
    /// Every row that has a parent, ascending by (parent id, row): the children a node
    /// has in this layer are one run of it. Nesting is kept on the child's side only, so
    /// nesting a node republishes the child's layer, not the parent's.
    pub by_parent: Vec<u32>,
    /// CSR offsets into `out_targets` / `out_descriptions`.
    pub out_offsets: Vec<u32>,
    /// Target node ids of out-edges, ascending per row (edges stay within the layer,
    /// but may cross parts).
    pub out_targets: Vec<u64>,
    /// Description (string index) of each out-edge.
    pub out_descriptions: Vec<u32>,
    /// CSR offsets into `in_sources` / `in_descriptions`.
    pub in_offsets: Vec<u32>,
    /// Source node ids of in-edges, ascending per row.
    pub in_sources: Vec<u64>,
    /// Description (string index) of each in-edge.
    pub in_descriptions: Vec<u32>,
    /// CSR offsets into `labels`.
    pub label_offsets: Vec<u32>,
    /// Labels (string indexes).
    pub labels: Vec<u32>,
    /// CSR offsets into the feature columns.
    pub feature_offsets: Vec<u32>,
    /// Feature keys (string indexes).
    pub feature_keys: Vec<u32>,
    /// Feature kinds (string, int, float, bool).
    pub feature_kinds: Vec<u8>,
    /// Feature values: string index, i64 bits, f64 bits or 0/1.
    pub feature_bits: Vec<u64>,
    /// Rows whose bounding box is enabled and non-empty, ascending.
    pub aabb_rows: Vec<u32>,
    /// Their boxes, `[min, max]` flattened.
    pub aabbs: Vec<[f32; 6]>,
    /// Label -> `[start, end)` range of `label_postings`.
    pub label_index: HashMap<String, [u32; 2]>,
    /// Rows per label, ascending.
    pub label_postings: Vec<u32>,
    /// Feature key -> `[start, end)` range of `key_postings`.
    pub key_index: HashMap<String, [u32; 2]>,
    /// Rows per feature key, ascending.
    pub key_postings: Vec<u32>,
    /// The layer index, if enabled: a kd-tree over the layer's points whose items are
    /// rows, patched by the rows changed since it was built.
    pub layer_index: Option<LayerIndexSegment>,
    /// The node indexes rooted at nodes of this layer, ascending by root.
    pub node_indexes: Vec<NodeIndexSegment>,
}

/// A chunk of a chunked layer's point column, as its layer segment names it.
#[derive(Archive, Serialize, Debug, Clone, Copy, PartialEq, Eq)]
pub struct PointChunkRef {
    /// The generation of the chunk segment: the layer generation at which the chunk's
    /// points last changed.
    pub generation: u64,
    /// Points in the chunk.
    pub len: u32,
}

/// One chunk of a chunked layer's point column: a segment of its own, republished only
/// when its points change (appending to a mesh republishes the last chunk).
#[derive(Archive, Serialize, Debug, Default)]
pub struct PointChunk {
    /// [`FORMAT_VERSION`] of the writer.
    pub version: u32,
    /// The layer whose column this is part of.
    pub layer: u32,
    /// The layer's part whose column this is part of.
    pub part: u32,
    /// The chunk's place in the column.
    pub index: u32,
    /// The chunk's generation (see [`PointChunkRef::generation`]).
    pub generation: u64,
    /// The points at column positions `index * point_chunk_len ..` of the layer.
    pub points: Vec<[f32; 3]>,
}

/// A kd-tree published as a segment of its own, as its layer segment names it.
#[derive(Archive, Serialize, Debug, Clone, Copy, PartialEq, Eq)]
pub struct TreeChunkRef {
    /// The generation of the tree chunk segment: the layer generation at which the tree
    /// was built.
    pub generation: u64,
    /// Points in the tree.
    pub points: u32,
}

/// A kd-tree of a layer (its layer index's base tree or the tree of one of its node
/// indexes) published as a segment of its own ([`TreeChunkRef`]), so that it is sent
/// once per build rather than with every change of its layer.
#[derive(Archive, Serialize, Debug)]
pub struct TreeChunk {
    /// [`FORMAT_VERSION`] of the writer.
    pub version: u32,
    /// The layer whose tree this is.
    pub layer: u32,
    /// The layer's part whose tree this is.
    pub part: u32,
    /// The tree's place among its layer's tree chunks (0: the layer index's base tree;
    /// `1 + i`: the tree of node index `i` of the layer segment).
    pub slot: u32,
    /// The chunk's generation (see [`TreeChunkRef::generation`]).
    pub generation: u64,
    /// Every item of `tree` is below this (the base rows of a layer index, the id table's
    /// length of a node index).
    pub items: u32,
    /// The tree.
    pub tree: KdTree,
}

/// A layer index as archived: a base kd-tree plus the rows patched since it was built,
/// so that a small change republishes the rows, not a rebuilt tree.
///
/// The index's entries are the base tree's entries whose row is neither patched nor at
/// or past the layer's row count, plus every point of every patched row, read from the
/// layer's `points` column (a patched row's base entries are dead). A publishing writer
/// folds the patch into a new base past a budget (`SegmentCache`); a fresh build has an
/// empty patch.
#[derive(Archive, Serialize, Debug)]
pub struct LayerIndexSegment {
    /// Rows of the layer when `tree` was built: every item of `tree` is below it.
    pub base_rows: u32,
    /// Points in `tree`.
    pub base_points: u32,
    /// The kd-tree over the points the rows had when it was built; items are rows.
    /// Empty when the tree travels as a [`TreeChunk`] (`tree_chunk`).
    pub tree: KdTree,
    /// The base tree's chunk, when it is published as a segment of its own (a large
    /// tree, by a publishing writer): sent again only when the base is rebuilt, not
    /// with every patch.
    pub tree_chunk: Option<TreeChunkRef>,
    /// Rows whose points may differ from their base entries, ascending, each below the
    /// layer's row count; every row at or past `base_rows` with points is listed.
    pub patched: Vec<u32>,
}

/// A node index as archived in its root's layer segment.
#[derive(Archive, Serialize, Debug)]
pub struct NodeIndexSegment {
    /// The root node.
    pub root: u64,
    /// Ids of the nodes with points in the root's sub-tree, ascending; an item is a
    /// position in this table.
    pub ids: Vec<u64>,
    /// A kd-tree over every point in the sub-tree. Empty when the tree travels as a
    /// [`TreeChunk`] (`tree_chunk`), and when a publishing writer withheld a tree of
    /// fewer than [`TREE_CHUNK_MIN_POINTS`](super::TREE_CHUNK_MIN_POINTS) points in at
    /// most [`WITHHELD_TREE_MAX_MEMBERS`](super::WITHHELD_TREE_MAX_MEMBERS) nodes: readers
    /// then walk the sub-tree, as for a node without an index (an empty tree without a
    /// chunk gives no index).
    pub tree: KdTree,
    /// The tree's chunk, when it is published as a segment of its own (by a publishing
    /// writer, for a tree of [`TREE_CHUNK_MIN_POINTS`](super::TREE_CHUNK_MIN_POINTS)
    /// points or more): its slot among its layer's tree chunks is 1 + the index's
    /// position in `node_indexes`. Sent again only when the tree is built anew (its
    /// sub-tree's points changed) or its slot holds another root.
    pub tree_chunk: Option<TreeChunkRef>,
}

/// A layer's entry in a snapshot's [`Structure`].
#[derive(Archive, Serialize, Debug, Default, Clone)]
pub struct StructureLayer {
    /// The layer's id.
    pub id: u32,
    /// The layer's name.
    pub name: String,
    /// DAG parents, ascending.
    pub parents: Vec<u32>,
    /// DAG children, ascending.
    pub children: Vec<u32>,
    /// The numbers of the layer's parts, in ascending order of their ids (`[0]` for a
    /// layer in one piece): each part's rows lie below the next part's.
    pub parts: Vec<u32>,
}

/// What of a snapshot changes only when its structure does: its layers (names, DAG,
/// parts) and the graph-level inverted indexes. A segment of its own, sent when it
/// changes; each cut's [`Manifest`] names its generation.
#[derive(Archive, Serialize, Debug, Default)]
pub struct Structure {
    /// [`FORMAT_VERSION`] of the writer.
    pub version: u32,
    /// The structure's generation (the [`Manifest::structure`] of the cuts it belongs to).
    pub generation: u64,
    /// Layers, ascending by id.
    pub layers: Vec<StructureLayer>,
    /// Label -> layers holding it, ascending.
    pub label_layers: HashMap<String, Vec<u32>>,
    /// Feature key -> layers holding it, ascending.
    pub key_layers: HashMap<String, Vec<u32>>,
}

/// A layer's entry in the manifest: its per-cut values.
#[derive(Archive, Serialize, Debug, Default, Clone, Copy)]
pub struct ManifestLayer {
    /// The layer's id.
    pub id: u32,
    /// The layer's generation in this cut (each part's generation is at most it).
    pub generation: u64,
    /// Number of nodes.
    pub node_count: u64,
    /// Smallest node id (`u64::MAX` when empty).
    pub min_id: u64,
    /// Largest node id (0 when empty).
    pub max_id: u64,
}

/// The manifest: which layers at which generations form one consistent cut, and which
/// [`Structure`] they have. Fixed-size entries, one per layer: everything else travels
/// in the structure, sent only when it changes.
#[derive(Archive, Serialize, Debug, Default)]
pub struct Manifest {
    /// [`FORMAT_VERSION`] of the writer.
    pub version: u32,
    /// Generation of the whole cut (increases with every publish).
    pub generation: u64,
    /// The generation of the cut's [`Structure`].
    pub structure: u64,
    /// Layers, ascending by id (the structure's layers, in the same order).
    pub layers: Vec<ManifestLayer>,
}

/// An archived `u32` column as native values.
pub(crate) fn u32s(v: &ArchivedVec<rkyv::rend::u32_le>) -> &[u32] {
    bytemuck::cast_slice(v.as_slice())
}

/// An archived `u64` column as native values.
pub(crate) fn u64s(v: &ArchivedVec<rkyv::rend::u64_le>) -> &[u64] {
    bytemuck::cast_slice(v.as_slice())
}

/// Offsets in an archived manifest's bytes (starting at `base`) of its per-cut fields:
/// the cut's generation, and per layer (in manifest order) its generation, node count
/// and smallest and largest node id.
pub(crate) fn cut_field_offsets(
    manifest: &ArchivedManifest,
    base: usize,
) -> (usize, Vec<[usize; 4]>) {
    let at = |field: &rkyv::rend::u64_le| std::ptr::from_ref(field).addr() - base;
    let layers = manifest
        .layers
        .iter()
        .map(|l| {
            [
                at(&l.generation),
                at(&l.node_count),
                at(&l.min_id),
                at(&l.max_id),
            ]
        })
        .collect();
    (at(&manifest.generation), layers)
}
