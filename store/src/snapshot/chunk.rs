//! Chunked layers: the point column of a large layer is published as fixed-size
//! [`PointChunk`] segments beside its layer segment, so that a change republishes the
//! chunks it touches (appending to a mesh node sends the last chunk and the small layer
//! segment, not the whole column) and a reader keeps, and validated once, the rest.
//!
//! Kd-trees are published the same way, as [`TreeChunk`]s: a layer index's base tree is
//! sent when the base is built or folded, not with every patch of the index, and a node
//! index's tree when it is built anew, not with every change of its root's layer (moving
//! one object sends its own tree, not those of every object of its layer).
//!
//! A chunk travels as a segment of its own, under a segment id derived from its layer
//! and place ([`chunk_segment_id`], [`tree_chunk_segment_id`]): ids with the top bit
//! set, so that a cut's segments sorted by id list its layers first, then each layer's
//! point chunks in column order, then the tree chunks.

use super::schema::{
    ArchivedPointChunk, ArchivedTreeChunk, ArchivedTreeChunkRef, FORMAT_VERSION, PointChunk,
};
use crate::index::{KdTree, check_tree};
use crate::{LayerId, NodeId, Point, SnapshotError};
use rkyv::munge::munge;
use rkyv::rancor::Fallible;
use rkyv::ser::{Allocator, Writer};
use rkyv::vec::{ArchivedVec, VecResolver};
use rkyv::{Archive, Place, Serialize};
use std::collections::HashMap;

/// Points per chunk a publishing writer uses by default (384 KiB of coordinates); layers
/// of more points are published chunked.
pub const POINT_CHUNK_LEN: usize = 32_768;

/// Most points per chunk a layer segment may declare.
pub const MAX_POINT_CHUNK_LEN: usize = 1 << 16;

/// Top bit of a segment id: set for chunks, clear for layers.
const CHUNK_ID_BIT: u32 = 1 << 31;

/// Second bit of a chunk's segment id: set for tree chunks, clear for point chunks.
const TREE_CHUNK_BIT: u32 = 1 << 30;

/// Fewest points a kd-tree (a layer index's base tree or a node index's tree) has for a
/// publishing writer to send it as a [`TreeChunk`](super::TreeChunk) (about 20 KiB
/// archived). A smaller layer index tree stays in its layer segment; a smaller node
/// index tree over a few nodes ([`WITHHELD_TREE_MAX_MEMBERS`]) is withheld (readers walk
/// so small a sub-tree), so that moving one object does not resend the trees of every
/// object in its layer. Every segment of a cut costs
/// each reader a receive and a join per cut and a validation at attach: with a bound of
/// 64 points the office's 213 object trees became chunks and single-layer updates and
/// attach got slower by more than the bytes they saved (measured for issue 19).
pub const TREE_CHUNK_MIN_POINTS: usize = 1024;

/// Most nodes with points that a node index's sub-tree may hold for a publishing writer
/// to withhold its tree (with fewer than [`TREE_CHUNK_MIN_POINTS`] points): the walk that
/// replaces the tree visits each of them, so an object with one node per vertex (saffron)
/// keeps its tree however few points it has.
pub const WITHHELD_TREE_MAX_MEMBERS: usize = 16;

/// Whether a publishing writer withholds the tree of a node index over `points` points
/// in `members` nodes, sending trees of `min_points` or more as chunks.
pub(crate) fn withholds_node_tree(points: usize, members: usize, min_points: usize) -> bool {
    0 < points && points < min_points && members <= WITHHELD_TREE_MAX_MEMBERS
}

/// Bits of a chunk's segment id that hold its place in the column.
const CHUNK_INDEX_BITS: u32 = 11;

/// Most chunks one layer may be split into; a larger column is kept in one piece.
pub const MAX_CHUNKS_PER_LAYER: usize = 1 << CHUNK_INDEX_BITS;

/// Layer ids below this may be chunked (the layer id must fit the segment id's bits,
/// and no chunk may take the manifest's id `u32::MAX`).
const CHUNKABLE_LAYERS: u32 = (1 << (30 - CHUNK_INDEX_BITS)) - 1;

/// Largest layer id a snapshot may hold: segment ids at or above it name chunks.
pub const MAX_LAYER_ID: u32 = CHUNK_ID_BIT - 1;

/// The segment id of chunk `index` of `layer`'s point column, if that layer can be
/// chunked that far.
pub fn chunk_segment_id(layer: LayerId, index: usize) -> Option<u32> {
    (layer.0 < CHUNKABLE_LAYERS && index < MAX_CHUNKS_PER_LAYER)
        .then_some(CHUNK_ID_BIT | layer.0 << CHUNK_INDEX_BITS | index as u32)
}

/// The segment id of tree chunk `slot` of `layer` (0: its layer index's base tree), if
/// that layer's trees can be chunked.
pub fn tree_chunk_segment_id(layer: LayerId, slot: usize) -> Option<u32> {
    chunk_segment_id(layer, slot).map(|id| id | TREE_CHUNK_BIT)
}

/// Whether a segment id names a chunk (not a layer, not the manifest).
pub fn is_chunk_segment_id(id: u32) -> bool {
    id & CHUNK_ID_BIT != 0 && id != u32::MAX
}

/// Whether a segment id names a tree chunk (not a point chunk, a layer or the manifest).
pub fn is_tree_chunk_segment_id(id: u32) -> bool {
    is_chunk_segment_id(id) && id & TREE_CHUNK_BIT != 0
}

/// The layer whose point or tree chunk a segment id names (`None` for a layer's or the
/// manifest's id).
pub fn chunk_segment_layer(id: u32) -> Option<LayerId> {
    is_chunk_segment_id(id).then_some(LayerId(
        (id & !(CHUNK_ID_BIT | TREE_CHUNK_BIT)) >> CHUNK_INDEX_BITS,
    ))
}

/// Whether a layer with `points` points is published in chunks of `chunk_len`: when it
/// has more than one chunk's worth and its chunks fit the segment ids.
pub(crate) fn is_chunked(layer: LayerId, points: usize, chunk_len: usize) -> bool {
    points > chunk_len && chunk_segment_id(layer, chunk_count(points, chunk_len) - 1).is_some()
}

/// Whether tree `slot` of `layer` (0: its layer index's base tree, `1 + i`: the tree of
/// its node index `i`), of `points` points, is published as a tree chunk by a writer
/// that sends trees of `min_points` or more as chunks: when it is that large (and not
/// empty) and its segment id fits.
pub(crate) fn has_tree_chunk(
    layer: LayerId,
    slot: usize,
    points: usize,
    min_points: usize,
) -> bool {
    points >= min_points.max(1) && tree_chunk_segment_id(layer, slot).is_some()
}

/// Chunks of `chunk_len` a column of `points` points takes.
pub(crate) fn chunk_count(points: usize, chunk_len: usize) -> usize {
    points.div_ceil(chunk_len)
}

/// The column positions chunk `index` holds, in a column of `points` points.
pub(crate) fn chunk_range(index: usize, points: usize, chunk_len: usize) -> std::ops::Range<usize> {
    let start = index * chunk_len;
    start..points.min(start + chunk_len)
}

impl PointChunk {
    /// Chunk `index` of `layer`'s column `points`, at `generation` (an owned copy; a
    /// publishing writer archives [`PointChunkSource`] instead).
    pub fn new(layer: LayerId, index: usize, generation: u64, points: &[Point]) -> Self {
        PointChunk {
            version: FORMAT_VERSION,
            layer: layer.0,
            index: index as u32,
            generation,
            points: points.to_vec(),
        }
    }
}

/// A point chunk archived straight from the column it is part of: the same archive as
/// [`PointChunk`], without first copying its points (up to 384 KiB per chunk).
#[derive(Debug, Clone, Copy)]
pub struct PointChunkSource<'a> {
    layer: u32,
    index: u32,
    generation: u64,
    points: &'a [Point],
}

impl<'a> PointChunkSource<'a> {
    /// Chunk `index` of `layer`'s column, holding `points`, at `generation`.
    pub fn new(layer: LayerId, index: usize, generation: u64, points: &'a [Point]) -> Self {
        PointChunkSource {
            layer: layer.0,
            index: index as u32,
            generation,
            points,
        }
    }
}

impl Archive for PointChunkSource<'_> {
    type Archived = ArchivedPointChunk;
    type Resolver = VecResolver;

    fn resolve(&self, resolver: VecResolver, out: Place<ArchivedPointChunk>) {
        munge!(let ArchivedPointChunk { version, layer, index, generation, points } = out);
        FORMAT_VERSION.resolve((), version);
        self.layer.resolve((), layer);
        self.index.resolve((), index);
        self.generation.resolve((), generation);
        ArchivedVec::resolve_from_len(self.points.len(), resolver, points);
    }
}

impl<S: Fallible + Allocator + Writer + ?Sized> Serialize<S> for PointChunkSource<'_> {
    fn serialize(&self, serializer: &mut S) -> Result<VecResolver, S::Error> {
        ArchivedVec::serialize_from_slice(self.points, serializer)
    }
}

/// A layer's kd-tree archived as a [`TreeChunk`](super::TreeChunk) straight from the tree
/// it holds (no copy of the tree).
#[derive(Debug, Clone, Copy)]
pub struct TreeChunkSource<'a> {
    layer: u32,
    slot: u32,
    generation: u64,
    items: u32,
    tree: &'a KdTree,
}

impl<'a> TreeChunkSource<'a> {
    /// Tree chunk `slot` of `layer`, at `generation`, holding `tree` whose items are
    /// below `items`.
    pub fn new(layer: LayerId, slot: usize, generation: u64, items: u32, tree: &'a KdTree) -> Self {
        TreeChunkSource {
            layer: layer.0,
            slot: slot as u32,
            generation,
            items,
            tree,
        }
    }
}

impl Archive for TreeChunkSource<'_> {
    type Archived = ArchivedTreeChunk;
    type Resolver = <KdTree as Archive>::Resolver;

    fn resolve(&self, resolver: Self::Resolver, out: Place<ArchivedTreeChunk>) {
        munge!(let ArchivedTreeChunk { version, layer, slot, generation, items, tree } = out);
        FORMAT_VERSION.resolve((), version);
        self.layer.resolve((), layer);
        self.slot.resolve((), slot);
        self.generation.resolve((), generation);
        self.items.resolve((), items);
        self.tree.resolve(resolver, tree);
    }
}

impl<S> Serialize<S> for TreeChunkSource<'_>
where
    S: Fallible + Allocator + Writer + ?Sized,
    KdTree: Serialize<S>,
{
    fn serialize(&self, serializer: &mut S) -> Result<Self::Resolver, S::Error> {
        self.tree.serialize(serializer)
    }
}

/// Checks a tree chunk on its own: its tree passes [`check_tree`] with items below the
/// chunk's `items`. Whether it is the tree its layer names is checked when the cut is
/// joined ([`check_tree_chunk_matches`]).
pub(crate) fn check_tree_chunk(chunk: &ArchivedTreeChunk) -> Result<(), String> {
    check_tree(&chunk.tree, chunk.items.to_native() as usize)
}

/// Checks a tree chunk against the index that names it as tree `slot` of `layer`: same
/// layer and slot, the generation and point count of `r`, items within `items` (the
/// layer index's base rows, the node index's id table).
pub(crate) fn check_tree_chunk_matches(
    chunk: &ArchivedTreeChunk,
    layer: u32,
    slot: u32,
    items: u32,
    r: &ArchivedTreeChunkRef,
) -> Result<(), String> {
    if chunk.layer != layer
        || chunk.slot != slot
        || chunk.generation != r.generation
        || chunk.tree.size() != r.points.to_native() as usize
        || chunk.items.to_native() > items
    {
        return Err(format!(
            "tree chunk segment (layer {}, slot {}, generation {}, {} points, items below {}) where layer {layer} names tree {slot} at generation {} with {} points, items below {items}",
            chunk.layer,
            chunk.slot,
            chunk.generation,
            chunk.tree.size(),
            chunk.items,
            r.generation,
            r.points
        ));
    }
    Ok(())
}

/// Checks the chunk list of a layer segment: a chunk length that is a power of two up
/// to [`MAX_POINT_CHUNK_LEN`], every chunk but the last full, the last not empty, no more
/// than [`MAX_CHUNKS_PER_LAYER`]. Returns the points they hold.
pub(crate) fn check_chunk_refs(
    refs: &[super::schema::ArchivedPointChunkRef],
    chunk_len: u32,
) -> Result<usize, String> {
    let chunk_len = chunk_len as usize;
    if !chunk_len.is_power_of_two() || chunk_len > MAX_POINT_CHUNK_LEN {
        return Err(format!(
            "point chunks of {chunk_len} points (a power of two up to {MAX_POINT_CHUNK_LEN})"
        ));
    }
    if refs.len() > MAX_CHUNKS_PER_LAYER {
        return Err(format!(
            "{} point chunks, at most {MAX_CHUNKS_PER_LAYER}",
            refs.len()
        ));
    }
    let mut total = 0;
    for (i, r) in refs.iter().enumerate() {
        let len = r.len.to_native() as usize;
        let last = i + 1 == refs.len();
        if len > chunk_len || len == 0 || (!last && len != chunk_len) {
            return Err(format!(
                "point chunk {i} of {} holds {len} points (every chunk but the last holds {chunk_len}, the last 1 to {chunk_len})",
                refs.len()
            ));
        }
        total += len;
    }
    Ok(total)
}

/// Checks a chunk segment against the entry of its layer segment that names it.
pub(crate) fn check_chunk_matches(
    chunk: &ArchivedPointChunk,
    layer: u32,
    index: usize,
    r: &super::schema::ArchivedPointChunkRef,
) -> Result<(), String> {
    if chunk.layer != layer
        || chunk.index != index as u32
        || chunk.generation != r.generation
        || chunk.points.len() != r.len.to_native() as usize
    {
        return Err(format!(
            "point chunk segment (layer {}, chunk {}, generation {}, {} points) where layer {layer} names chunk {index} at generation {} with {} points",
            chunk.layer,
            chunk.index,
            chunk.generation,
            chunk.points.len(),
            r.generation,
            r.len
        ));
    }
    Ok(())
}

impl crate::SceneGraph {
    /// Segments a snapshot of this graph takes when published in point chunks of
    /// `chunk_len` ([`POINT_CHUNK_LEN`] by default): one per layer, plus the point chunks
    /// of each chunked layer and the tree chunks of its large indexes (for sizing a
    /// publisher's bound on segments per cut).
    pub fn snapshot_segments(&self, chunk_len: usize) -> usize {
        let mut node_trees: HashMap<LayerId, Vec<(NodeId, usize)>> = HashMap::new();
        for (root, tree) in &self.indexes.nodes {
            node_trees
                .entry(self.nodes[root].layer)
                .or_default()
                .push((*root, tree.len()));
        }
        self.layers
            .iter()
            .map(|(&id, l)| {
                let points = l.nodes.iter().map(|n| self.nodes[n].points.len()).sum();
                let point_chunks = if is_chunked(id, points, chunk_len) {
                    chunk_count(points, chunk_len)
                } else {
                    0
                };
                let layer_tree = self.indexes.layers.contains_key(&id)
                    && has_tree_chunk(id, 0, points, TREE_CHUNK_MIN_POINTS);
                let mut roots = node_trees.remove(&id).unwrap_or_default();
                roots.sort_unstable();
                let node_tree_chunks = roots
                    .iter()
                    .enumerate()
                    .filter(|(i, (_, points))| {
                        has_tree_chunk(id, 1 + i, *points, TREE_CHUNK_MIN_POINTS)
                    })
                    .count();
                1 + point_chunks + usize::from(layer_tree) + node_tree_chunks
            })
            .sum()
    }
}

/// A validated chunk's points.
pub(crate) fn chunk_points(chunk: &ArchivedPointChunk) -> &[Point] {
    bytemuck::cast_slice(chunk.points.as_slice())
}

/// Validation error for a chunk that is not one.
pub(crate) fn chunk_error(what: &str, reason: impl Into<String>) -> SnapshotError {
    SnapshotError::Validation {
        what: what.to_owned(),
        reason: reason.into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::snapshot::{TreeChunk, archive};

    #[test]
    fn a_chunk_archived_from_its_column_is_the_owned_chunks_archive() {
        let points: Vec<Point> = (0..1000).map(|i| [i as f32, -(i as f32), 0.5]).collect();
        for range in [0..1, 0..1000, 17..513] {
            let owned = PointChunk::new(LayerId(7), 3, 42, &points[range.clone()]);
            let source = PointChunkSource::new(LayerId(7), 3, 42, &points[range]);
            assert_eq!(source.archived_len(), owned.archived_len());
            assert_eq!(&archive(&source)[..], &archive(&owned)[..]);
        }
    }

    #[test]
    fn a_tree_chunk_archived_from_its_tree_is_the_owned_chunks_archive() {
        let entries: Vec<(u32, Point)> = (0..3000u32)
            .map(|i| (i / 3, [i as f32, (i % 7) as f32, 0.5]))
            .collect();
        let tree = crate::index::build_tree(&entries);
        let source = TreeChunkSource::new(LayerId(7), 0, 42, 1000, &tree);
        let owned = TreeChunk {
            version: FORMAT_VERSION,
            layer: 7,
            slot: 0,
            generation: 42,
            items: 1000,
            tree: crate::index::build_tree(&entries),
        };
        assert_eq!(source.archived_len(), owned.archived_len());
        assert_eq!(&archive(&source)[..], &archive(&owned)[..]);
        let bytes = archive(&source);
        let chunk = crate::snapshot::validate_tree_chunk(&bytes, "tree").unwrap();
        assert_eq!(chunk.tree.size(), 3000);
    }

    #[test]
    fn tree_chunk_ids_sort_after_every_point_chunk() {
        let last_point = chunk_segment_id(LayerId(CHUNKABLE_LAYERS - 1), MAX_CHUNKS_PER_LAYER - 1);
        let first_tree = tree_chunk_segment_id(LayerId(0), 0).unwrap();
        assert!(last_point.unwrap() < first_tree);
        assert!(is_tree_chunk_segment_id(first_tree) && is_chunk_segment_id(first_tree));
        assert!(!is_tree_chunk_segment_id(last_point.unwrap()));
        let last_tree = tree_chunk_segment_id(LayerId(CHUNKABLE_LAYERS - 1), 0).unwrap();
        assert!(last_tree != u32::MAX && is_tree_chunk_segment_id(last_tree));
        assert!(
            !is_tree_chunk_segment_id(u32::MAX),
            "the manifest's id is no chunk"
        );
    }

    #[test]
    fn chunk_ids_sort_after_layers_in_layer_and_column_order() {
        let a = chunk_segment_id(LayerId(0), 0).unwrap();
        let b = chunk_segment_id(LayerId(0), 1).unwrap();
        let c = chunk_segment_id(LayerId(1), 0).unwrap();
        assert!(MAX_LAYER_ID < a && a < b && b < c);
        assert!(is_chunk_segment_id(a) && !is_chunk_segment_id(MAX_LAYER_ID));
        assert!(
            !is_chunk_segment_id(u32::MAX),
            "the manifest's id is no chunk"
        );
        assert_eq!(chunk_segment_id(LayerId(0), MAX_CHUNKS_PER_LAYER), None);
        assert_eq!(chunk_segment_id(LayerId(CHUNKABLE_LAYERS), 0), None);
        let last = chunk_segment_id(LayerId(CHUNKABLE_LAYERS - 1), MAX_CHUNKS_PER_LAYER - 1);
        assert!(last.is_some_and(|id| id != u32::MAX));
    }

    #[test]
    fn a_chunk_segment_id_names_its_layer() {
        for layer in [0, 1, 77, CHUNKABLE_LAYERS - 1] {
            for place in [0, 5, MAX_CHUNKS_PER_LAYER - 1] {
                let point = chunk_segment_id(LayerId(layer), place).unwrap();
                let tree = tree_chunk_segment_id(LayerId(layer), place).unwrap();
                assert_eq!(chunk_segment_layer(point), Some(LayerId(layer)));
                assert_eq!(chunk_segment_layer(tree), Some(LayerId(layer)));
            }
        }
        assert_eq!(chunk_segment_layer(MAX_LAYER_ID), None);
        assert_eq!(chunk_segment_layer(u32::MAX), None);
    }
}
