//! A reader's checks of chunk segments: each chunk on its own, and against the layer
//! segment that names it when a cut is joined; and a validated point chunk's points.

use crate::index::check_tree;
use crate::snapshot::chunking::{MAX_CHUNKS_PER_LAYER, MAX_POINT_CHUNK_LEN};
use crate::snapshot::schema::{
    ArchivedPointChunk, ArchivedPointChunkRef, ArchivedTreeChunk, ArchivedTreeChunkRef,
};
use crate::{Point, SnapshotError};

/// Checks a tree chunk on its own: its tree passes [`check_tree`] with items below the
/// chunk's `items`. Whether it is the tree its layer names is checked when the cut is
/// joined ([`check_tree_chunk_matches`]).
pub(crate) fn check_tree_chunk(chunk: &ArchivedTreeChunk) -> Result<(), String> {
    check_tree(&chunk.tree, chunk.items.to_native() as usize)
}

/// Checks a tree chunk against the index that names it as tree `slot` of part `part` of
/// `layer`: same layer, part and slot, the generation and point count of `r`, items
/// within `items` (the layer index's base rows, the node index's id table).
pub(crate) fn check_tree_chunk_matches(
    chunk: &ArchivedTreeChunk,
    layer: u32,
    part: u32,
    slot: u32,
    items: u32,
    r: &ArchivedTreeChunkRef,
) -> Result<(), String> {
    if chunk.layer != layer
        || chunk.part != part
        || chunk.slot != slot
        || chunk.generation != r.generation
        || chunk.tree.size() != r.points.to_native() as usize
        || chunk.items.to_native() > items
    {
        return Err(format!(
            "tree chunk segment (layer {}, part {}, slot {}, generation {}, {} points, items below {}) where layer {layer} part {part} names tree {slot} at generation {} with {} points, items below {items}",
            chunk.layer,
            chunk.part,
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
    refs: &[ArchivedPointChunkRef],
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

/// Checks a chunk segment against the entry of its part segment that names it.
pub(crate) fn check_chunk_matches(
    chunk: &ArchivedPointChunk,
    layer: u32,
    part: u32,
    index: usize,
    r: &ArchivedPointChunkRef,
) -> Result<(), String> {
    if chunk.layer != layer
        || chunk.part != part
        || chunk.index != index as u32
        || chunk.generation != r.generation
        || chunk.points.len() != r.len.to_native() as usize
    {
        return Err(format!(
            "point chunk segment (layer {}, part {}, chunk {}, generation {}, {} points) where layer {layer} part {part} names chunk {index} at generation {} with {} points",
            chunk.layer,
            chunk.part,
            chunk.index,
            chunk.generation,
            chunk.points.len(),
            r.generation,
            r.len
        ));
    }
    Ok(())
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
