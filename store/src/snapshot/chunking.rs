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
//! A layer's rows may be split into **parts** (row chunks over disjoint id ranges, each a
//! [`LayerSegment`](super::LayerSegment) of its own; see `publish/parts.rs`), and each
//! part's point column and trees into chunks. Every one travels as a segment of its own,
//! under a `u64` segment id derived from its kind, layer, part and place
//! ([`part_segment_id`], [`chunk_segment_id`], [`tree_chunk_segment_id`]): a cut's
//! segments sorted by id list every part first (by layer, then part number), then the
//! point chunks (by layer, part, place), then the tree chunks.

use crate::LayerId;

/// Points per chunk a publishing writer uses by default (384 KiB of coordinates); layers
/// of more points are published chunked.
pub const POINT_CHUNK_LEN: usize = 32_768;

/// Most points per chunk a layer segment may declare.
pub const MAX_POINT_CHUNK_LEN: usize = 1 << 16;

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

/// Rows of the newest part of a layer a publishing writer lets grow before it seals the
/// part and starts another (`SegmentCache::with_part_rows`): appending a row resends at
/// most this many rows.
pub const PART_ROWS: usize = 128;

/// Most rows one part of a layer split into parts may hold: sealed parts merge up to it
/// (so a layer of n rows has O(log n + n / MAX_PART_ROWS) parts), a part past it is
/// split. An edit of a row resends its part: at most this many rows.
pub const MAX_PART_ROWS: usize = 2048;

/// Bits of a spatial index item that hold a row of a layer split into parts: the rest
/// hold the part's place in the layer (a multi-part layer index's item is
/// `place << PART_ITEM_ROW_BITS | row`).
pub const PART_ITEM_ROW_BITS: u32 = 18;

/// Bits of a segment id that hold a chunk's place in its part's column or its tree
/// slot.
const INDEX_BITS: u32 = 15;

/// Bits of a segment id that hold a part's number within its layer.
const PART_BITS: u32 = 15;

/// Where a segment id's layer id starts.
const LAYER_SHIFT: u32 = INDEX_BITS + PART_BITS;

/// Where a segment id's kind starts (two bits: part, point chunk, tree chunk).
const KIND_SHIFT: u32 = 62;

/// Kind of a layer part's segment id.
const KIND_PART: u64 = 0;

/// Kind of a point chunk's segment id.
const KIND_POINT_CHUNK: u64 = 1;

/// Kind of a tree chunk's segment id.
const KIND_TREE_CHUNK: u64 = 2;

/// The manifest's segment id: of no kind a part or chunk has.
pub const MANIFEST_SEGMENT_ID: u64 = u64::MAX;

/// The structure's segment id ([`Structure`](super::Structure)): of no kind a part or
/// chunk has, sorted after every chunk.
pub const STRUCTURE_SEGMENT_ID: u64 = 3 << KIND_SHIFT;

/// Whether a segment id names the structure.
pub fn is_structure_segment_id(id: u64) -> bool {
    id == STRUCTURE_SEGMENT_ID
}

/// Most chunks one part's point column may be split into; a larger column is kept in
/// one piece.
pub const MAX_CHUNKS_PER_LAYER: usize = 1 << INDEX_BITS;

/// Most parts one layer may be split into at once (part numbers are reused).
pub const MAX_PARTS_PER_LAYER: usize = 1 << PART_BITS;

/// Largest layer id a snapshot may hold: every `u32` but the largest.
pub const MAX_LAYER_ID: u32 = u32::MAX - 1;

fn segment_id(kind: u64, layer: LayerId, part: u32, index: usize) -> Option<u64> {
    (layer.0 <= MAX_LAYER_ID
        && (part as usize) < MAX_PARTS_PER_LAYER
        && index < MAX_CHUNKS_PER_LAYER)
        .then_some(
            kind << KIND_SHIFT
                | u64::from(layer.0) << LAYER_SHIFT
                | u64::from(part) << INDEX_BITS
                | index as u64,
        )
}

/// The segment id of part `part` of `layer` (a layer published in one piece is its part
/// 0), if the numbers fit.
pub fn part_segment_id(layer: LayerId, part: u32) -> Option<u64> {
    segment_id(KIND_PART, layer, part, 0)
}

/// The segment id of chunk `index` of the point column of part `part` of `layer`, if
/// the numbers fit.
pub fn chunk_segment_id(layer: LayerId, part: u32, index: usize) -> Option<u64> {
    segment_id(KIND_POINT_CHUNK, layer, part, index)
}

/// The segment id of tree chunk `slot` of part `part` of `layer` (slot 0: the part's
/// layer index base tree), if the numbers fit.
pub fn tree_chunk_segment_id(layer: LayerId, part: u32, slot: usize) -> Option<u64> {
    segment_id(KIND_TREE_CHUNK, layer, part, slot)
}

/// Whether a segment id names a layer part (not a chunk, not the manifest).
pub fn is_part_segment_id(id: u64) -> bool {
    id >> KIND_SHIFT == KIND_PART
}

/// Whether a segment id names a point or tree chunk (not a part, not the manifest).
pub fn is_chunk_segment_id(id: u64) -> bool {
    matches!(id >> KIND_SHIFT, KIND_POINT_CHUNK | KIND_TREE_CHUNK) && id != MANIFEST_SEGMENT_ID
}

/// Whether a segment id names a tree chunk (not a point chunk, a part or the manifest).
pub fn is_tree_chunk_segment_id(id: u64) -> bool {
    id >> KIND_SHIFT == KIND_TREE_CHUNK
}

/// The layer and part a part's or chunk's segment id names (`None` for the manifest's).
pub fn segment_layer_part(id: u64) -> Option<(LayerId, u32)> {
    (id != MANIFEST_SEGMENT_ID && id >> KIND_SHIFT != 3).then_some((
        LayerId((id >> LAYER_SHIFT) as u32),
        ((id >> INDEX_BITS) & ((1 << PART_BITS) - 1)) as u32,
    ))
}

/// Whether a layer with `points` points is published in chunks of `chunk_len`: when it
/// has more than one chunk's worth and its chunks fit the segment ids.
pub(crate) fn is_chunked(points: usize, chunk_len: usize) -> bool {
    points > chunk_len && chunk_count(points, chunk_len) <= MAX_CHUNKS_PER_LAYER
}

/// Whether tree `slot` of `layer` (0: its layer index's base tree, `1 + i`: the tree of
/// its node index `i`), of `points` points, is published as a tree chunk by a writer
/// that sends trees of `min_points` or more as chunks: when it is that large (and not
/// empty) and its segment id fits.
pub(crate) fn has_tree_chunk(slot: usize, points: usize, min_points: usize) -> bool {
    points >= min_points.max(1) && slot < MAX_CHUNKS_PER_LAYER
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
    fn segment_ids_sort_parts_then_point_chunks_then_tree_chunks() {
        let last_part = part_segment_id(LayerId(MAX_LAYER_ID), MAX_PARTS_PER_LAYER as u32 - 1);
        let first_point = chunk_segment_id(LayerId(0), 0, 0).unwrap();
        let last_point = chunk_segment_id(
            LayerId(MAX_LAYER_ID),
            MAX_PARTS_PER_LAYER as u32 - 1,
            MAX_CHUNKS_PER_LAYER - 1,
        );
        let first_tree = tree_chunk_segment_id(LayerId(0), 0, 0).unwrap();
        let last_tree = tree_chunk_segment_id(
            LayerId(MAX_LAYER_ID),
            MAX_PARTS_PER_LAYER as u32 - 1,
            MAX_CHUNKS_PER_LAYER - 1,
        )
        .unwrap();
        assert!(last_part.unwrap() < first_point);
        assert!(last_point.unwrap() < first_tree);
        assert!(last_tree < MANIFEST_SEGMENT_ID);
        assert!(is_part_segment_id(last_part.unwrap()) && !is_chunk_segment_id(last_part.unwrap()));
        assert!(is_chunk_segment_id(first_point) && !is_tree_chunk_segment_id(first_point));
        assert!(is_tree_chunk_segment_id(last_tree) && is_chunk_segment_id(last_tree));
        assert!(!is_chunk_segment_id(MANIFEST_SEGMENT_ID));
        assert!(!is_part_segment_id(MANIFEST_SEGMENT_ID));
        assert_eq!(segment_layer_part(MANIFEST_SEGMENT_ID), None);
    }

    #[test]
    fn ids_sort_by_layer_then_part_then_place() {
        let a = chunk_segment_id(LayerId(0), 0, 1).unwrap();
        let b = chunk_segment_id(LayerId(0), 1, 0).unwrap();
        let c = chunk_segment_id(LayerId(1), 0, 0).unwrap();
        assert!(a < b && b < c);
        assert!(part_segment_id(LayerId(3), 2).unwrap() < part_segment_id(LayerId(3), 5).unwrap());
        assert_eq!(chunk_segment_id(LayerId(0), 0, MAX_CHUNKS_PER_LAYER), None);
        assert_eq!(
            part_segment_id(LayerId(0), MAX_PARTS_PER_LAYER as u32),
            None
        );
        assert_eq!(part_segment_id(LayerId(u32::MAX), 0), None);
    }

    #[test]
    fn a_segment_id_names_its_layer_and_part() {
        for layer in [0, 1, 77, MAX_LAYER_ID] {
            for part in [0, 3, MAX_PARTS_PER_LAYER as u32 - 1] {
                for place in [0, 5, MAX_CHUNKS_PER_LAYER - 1] {
                    let point = chunk_segment_id(LayerId(layer), part, place).unwrap();
                    let tree = tree_chunk_segment_id(LayerId(layer), part, place).unwrap();
                    assert!(is_chunk_segment_id(point));
                    assert_eq!(segment_layer_part(point), Some((LayerId(layer), part)));
                    assert_eq!(segment_layer_part(tree), Some((LayerId(layer), part)));
                }
                let id = part_segment_id(LayerId(layer), part).unwrap();
                assert_eq!(segment_layer_part(id), Some((LayerId(layer), part)));
                assert!(!is_chunk_segment_id(id));
            }
        }
    }
}
