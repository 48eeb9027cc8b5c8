//! How a layer is chunked, shared by the publishing writer and readers: chunk sizes,
//! which layers and trees travel as chunks, and the segment ids of chunks.
//!
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

use crate::LayerId;

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

#[cfg(test)]
mod tests {
    use super::*;

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
