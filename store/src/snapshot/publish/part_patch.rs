//! Patching one part's cached segment (`Cached`) row by row from its change journal,
//! for [`super::SegmentCache`].
//!
//! When the journal starts at the generation of the cached segment and the rows kept their
//! places since — nodes removed only from the end (the largest ids), new nodes only with
//! ids above every remaining one, no index enabled or disabled — the next build looks up
//! only the changed nodes: each changed row is overwritten in place where it keeps the
//! length of a column (a node moved, a value changed) and spliced in where it does not (an
//! edge or a label added), and new rows are appended; when many rows change length, fresh
//! columns are built instead, copying each run of unchanged rows from the previous ones in
//! one go. Label and key postings are rebuilt (a counting sort of the rows by term) only
//! when labels or keys changed or rows were added or removed; the rows whose parent changed
//! are re-filed in `by_parent`. The layer index is patched with the rows whose points
//! changed and folded into a new tree past a budget (`layer_index_update`), a node index is
//! rebuilt only when its sub-tree changed. Otherwise (the journal overflowed, or starts
//! elsewhere: another consumer took it) the caller builds the part from scratch. Strings
//! no longer used stay until the next full build (one is forced once the table doubled).

use super::archive::StringTable;
use super::chunk_state::ChunkState;
use super::layer_index_update::{PointChanges, update_layer_index};
use crate::graph::LayerChanges;
use crate::snapshot::schema::{LayerSegment, NO_PARENT};
use crate::{LayerId, NodeId, SceneGraph};
use std::ops::Range;

/// One part's cached segment.
pub(super) struct Cached {
    pub(super) segment: LayerSegment,
    strings: StringTable,
    /// The layer's incarnation (a removed layer's id may come back).
    incarnation: u64,
    /// Length of the string table after the last full build.
    strings_at_full_build: usize,
    /// Base entries of the layer index that its patch killed (`index_patch`).
    index_killed: usize,
    /// The point chunks last published, if the part is chunked (`chunk_state`).
    pub(super) chunks: ChunkState,
}

impl Cached {
    /// Part `part` of `layer` built afresh from the nodes `ids` (ascending).
    pub(super) fn build(
        graph: &SceneGraph,
        layer: LayerId,
        part: u32,
        ids: Vec<u64>,
    ) -> Box<Cached> {
        let (segment, strings) = graph.build_part_segment(layer, part, ids);
        Box::new(Cached {
            incarnation: graph.layers[&layer].incarnation,
            strings_at_full_build: segment.strings.len(),
            segment,
            strings,
            index_killed: 0,
            chunks: ChunkState::fresh(),
        })
    }
}

/// The cached segment brought up to date row by row, or `None` when rows moved (a
/// full build is needed).
///
/// `expected_rows`, if given, is the row count the segment must have after the patch
/// (the layer's node count for a layer in one piece): a journal that disagrees means a
/// full build.
pub(super) fn patched(
    graph: &SceneGraph,
    layer: LayerId,
    cache: Cached,
    changes: LayerChanges,
    expected_rows: Option<usize>,
) -> Option<Box<Cached>> {
    let Cached {
        segment: mut old,
        strings: mut table,
        strings_at_full_build,
        incarnation,
        mut index_killed,
        mut chunks,
    } = cache;
    if changes.everything
        || changes.since != old.generation
        || old.strings.len() > 2 * strings_at_full_build + 64
    {
        return None;
    }
    let l = &graph.layers[&layer];
    let mut changed: Vec<NodeId> = changes.nodes;
    changed.sort_unstable();
    changed.dedup();
    let mut removed = changes.removed;
    removed.sort_unstable();
    removed.dedup();
    let mut cut_points = 0;
    if !removed.is_empty() {
        // Only the last rows, gone for good, keep the other rows in place.
        let kept = old.ids.len().checked_sub(removed.len())?;
        if !old.ids[kept..].iter().eq(removed.iter().map(|id| &id.0))
            || removed.iter().any(|id| graph.nodes.contains_key(id))
        {
            return None;
        }
        cut_points = PointChanges::points_from(&old, kept);
        old.truncate_rows(kept);
        changed.retain(|id| removed.binary_search(id).is_err());
    }
    let old_rows = old.ids.len();
    let mut dirty_rows = Vec::with_capacity(changed.len());
    let mut appended = Vec::new();
    for id in changed {
        if graph.nodes.get(&id).is_none_or(|n| n.layer != layer) {
            return None;
        }
        match old.ids.binary_search(&id.0) {
            Ok(row) => dirty_rows.push(row),
            Err(at) if at == old_rows => appended.push(id.0),
            Err(_) => return None,
        }
    }
    if expected_rows.is_some_and(|rows| old_rows + appended.len() != rows) {
        return None;
    }
    let mut ids = Vec::with_capacity(l.nodes.len());
    ids.extend_from_slice(&old.ids);
    ids.extend_from_slice(&appended);
    // Each rewritten or appended row with the parent it had, to re-file `by_parent`.
    let rewritten: Vec<(u32, u64)> = dirty_rows
        .iter()
        .map(|&row| (row as u32, old.parents[row]))
        .chain((old_rows..ids.len()).map(|row| (row as u32, NO_PARENT)))
        .collect();
    let point_changes = PointChanges::find(graph, &old, &dirty_rows, &ids, cut_points);
    let points_kept =
        chunks
            .changed
            .note_patch(graph, &old, &dirty_rows, &ids, changes.points_kept);

    let mut s = match rows_in_place(graph, &mut old, &mut table, &dirty_rows, &points_kept, &ids) {
        Some(terms_changed) => {
            for (row, &id) in ids.iter().enumerate().skip(old_rows) {
                graph.push_row(&mut old, &mut table, &graph.nodes[&NodeId(id)], row as u32);
            }
            old.ids = ids;
            old.generation = l.generation;
            if terms_changed || old_rows < old.ids.len() || !removed.is_empty() {
                old.rebuild_postings();
            }
            old
        }
        None => {
            let mut s = LayerSegment::empty(layer, l.generation, &l.name, ids.len());
            s.part = old.part;
            s.strings = std::mem::take(&mut old.strings);
            let mut aabb_cursor = 0;
            let mut clean_from = 0;
            for row in dirty_rows.into_iter().chain(old_rows..ids.len()) {
                copy_rows(
                    &old,
                    &mut s,
                    clean_from..row.min(old_rows),
                    &mut aabb_cursor,
                );
                let node = &graph.nodes[&NodeId(ids[row])];
                graph.push_row(&mut s, &mut table, node, row as u32);
                clean_from = row + 1;
            }
            copy_rows(&old, &mut s, clean_from..old_rows, &mut aabb_cursor);
            s.ids = ids;
            s.rebuild_postings();
            s.by_parent = std::mem::take(&mut old.by_parent);
            s.layer_index = old.layer_index.take();
            s.node_indexes = std::mem::take(&mut old.node_indexes);
            s
        }
    };

    s.refile_by_parent(&rewritten);
    if changes.geometry || s.layer_index.is_some() {
        chunks.tree_rebuilt |=
            update_layer_index(graph, layer, &mut s, point_changes, &mut index_killed);
    }
    let mut roots = changes.index_roots;
    roots.sort_unstable();
    roots.dedup();
    s.node_indexes
        .retain(|index| removed.binary_search(&NodeId(index.root)).is_err());
    for index in &mut s.node_indexes {
        if roots.binary_search(&NodeId(index.root)).is_ok() {
            // Built when the segment is next asked for, if it is sent at all.
            chunks.node_tree_stale(index);
        }
    }
    Some(Box::new(Cached {
        segment: s,
        strings: table,
        incarnation,
        strings_at_full_build,
        index_killed,
        chunks,
    }))
}

/// Most rows whose column lengths change (an edge or a label added) that one
/// build splices into the columns in place; each splice moves the tails of the columns
/// it changes and shifts the later offsets. Past it, fresh columns are built.
const MAX_SPLICED: usize = 32;

/// Rewrites the changed rows `dirty_rows` of `seg` in place: each row's entries are
/// overwritten where they keep their length (a node moved, a value changed) and
/// spliced in where they do not (an edge or label added: the odometry edge to the
/// previous pose). Returns whether the postings must be
/// rebuilt (labels or keys changed), or `None`, changing no row, when more than
/// [`MAX_SPLICED`] rows change length. `ids` are the new sorted ids; `points_kept`, per
/// dirty row, how many of its leading points are unchanged.
///
/// The new content of every dirty row is first built into one scratch segment (row `k`
/// of it is `dirty_rows[k]`), so a build allocates its columns once, not per row.
fn rows_in_place(
    graph: &SceneGraph,
    seg: &mut LayerSegment,
    table: &mut StringTable,
    dirty_rows: &[usize],
    points_kept: &[usize],
    ids: &[u64],
) -> Option<bool> {
    let mut fresh = LayerSegment::empty(LayerId(seg.layer), 0, "", dirty_rows.len());
    // New strings go to the segment's own table.
    fresh.strings = std::mem::take(&mut seg.strings);
    for &row in dirty_rows {
        let node = &graph.nodes[&NodeId(ids[row])];
        // The points go from the node to the column directly (a mesh node may hold many).
        graph.push_row_except_points(&mut fresh, table, node, row as u32);
        let end = fresh.point_offsets.last().copied().unwrap_or(0) + node.points.len() as u32;
        fresh.point_offsets.push(end);
    }
    seg.strings = std::mem::take(&mut fresh.strings);
    let reshaped = dirty_rows
        .iter()
        .enumerate()
        .filter(|&(k, &row)| {
            [
                (&seg.point_offsets, &fresh.point_offsets),
                (&seg.out_offsets, &fresh.out_offsets),
                (&seg.in_offsets, &fresh.in_offsets),
                (&seg.label_offsets, &fresh.label_offsets),
                (&seg.feature_offsets, &fresh.feature_offsets),
            ]
            .iter()
            .any(|(old, new)| row_range(old, row).len() != row_range(new, k).len())
        })
        .count();
    if reshaped > MAX_SPLICED {
        return None;
    }
    let mut terms_changed = false;
    for (k, (&row, &kept)) in dirty_rows.iter().zip(points_kept).enumerate() {
        let points = &graph.nodes[&NodeId(ids[row])].points;
        let new = row_range(&fresh.label_offsets, k);
        let r = row_range(&seg.label_offsets, row);
        terms_changed |= seg.labels[r.clone()] != fresh.labels[new.clone()];
        splice(&mut seg.labels, r.clone(), &fresh.labels[new.clone()]);
        shift_offsets(&mut seg.label_offsets, row, r.len(), new.len());
        let new = row_range(&fresh.feature_offsets, k);
        let r = row_range(&seg.feature_offsets, row);
        terms_changed |= seg.feature_keys[r.clone()] != fresh.feature_keys[new.clone()];
        splice(
            &mut seg.feature_keys,
            r.clone(),
            &fresh.feature_keys[new.clone()],
        );
        splice(
            &mut seg.feature_kinds,
            r.clone(),
            &fresh.feature_kinds[new.clone()],
        );
        splice(
            &mut seg.feature_bits,
            r.clone(),
            &fresh.feature_bits[new.clone()],
        );
        shift_offsets(&mut seg.feature_offsets, row, r.len(), new.len());
        // The leading points that stayed as they were are not rewritten (a mesh node
        // growing at its end).
        let r = row_range(&seg.point_offsets, row);
        splice(&mut seg.points, r.start + kept..r.end, &points[kept..]);
        shift_offsets(&mut seg.point_offsets, row, r.len(), points.len());
        let new = row_range(&fresh.out_offsets, k);
        let r = row_range(&seg.out_offsets, row);
        splice(
            &mut seg.out_targets,
            r.clone(),
            &fresh.out_targets[new.clone()],
        );
        splice(
            &mut seg.out_descriptions,
            r.clone(),
            &fresh.out_descriptions[new.clone()],
        );
        shift_offsets(&mut seg.out_offsets, row, r.len(), new.len());
        let new = row_range(&fresh.in_offsets, k);
        let r = row_range(&seg.in_offsets, row);
        splice(
            &mut seg.in_sources,
            r.clone(),
            &fresh.in_sources[new.clone()],
        );
        splice(
            &mut seg.in_descriptions,
            r.clone(),
            &fresh.in_descriptions[new.clone()],
        );
        shift_offsets(&mut seg.in_offsets, row, r.len(), new.len());
        seg.parents[row] = fresh.parents[k];
        // The scratch segment's boxes carry their real row numbers, ascending.
        let new_box = fresh
            .aabb_rows
            .binary_search(&(row as u32))
            .ok()
            .map(|i| fresh.aabbs[i]);
        match (seg.aabb_rows.binary_search(&(row as u32)), new_box) {
            (Ok(i), Some(b)) => seg.aabbs[i] = b,
            (Ok(i), None) => {
                seg.aabb_rows.remove(i);
                seg.aabbs.remove(i);
            }
            (Err(i), Some(b)) => {
                seg.aabb_rows.insert(i, row as u32);
                seg.aabbs.insert(i, b);
            }
            (Err(_), None) => {}
        }
    }
    Some(terms_changed)
}

/// The entries of row `row` of a CSR column with `offsets`.
fn row_range(offsets: &[u32], row: usize) -> Range<usize> {
    offsets[row] as usize..offsets[row + 1] as usize
}

/// Replaces `values[range]` by `new`: the common prefix is overwritten, and the rest
/// inserted or removed (moving the tail once).
fn splice<T: Copy>(values: &mut Vec<T>, range: Range<usize>, new: &[T]) {
    let common = range.len().min(new.len());
    values[range.start..range.start + common].copy_from_slice(&new[..common]);
    if new.len() > common {
        values.splice(range.end..range.end, new[common..].iter().copied());
    } else if range.len() > common {
        values.drain(range.start + common..range.end);
    }
}

/// Shifts the offsets after row `row` of a CSR column whose row went from `old_len` to
/// `new_len` entries.
fn shift_offsets(offsets: &mut [u32], row: usize, old_len: usize, new_len: usize) {
    if old_len != new_len {
        for o in &mut offsets[row + 1..] {
            *o = (*o as usize + new_len - old_len) as u32;
        }
    }
}

impl LayerSegment {
    /// Drops every row from `rows` on (not the postings or the spatial indexes).
    fn truncate_rows(&mut self, rows: usize) {
        fn cut<T>(offsets: &mut Vec<u32>, rows: usize, values: &mut Vec<T>) -> usize {
            let end = offsets[rows] as usize;
            offsets.truncate(rows + 1);
            values.truncate(end);
            end
        }
        cut(&mut self.point_offsets, rows, &mut self.points);
        let end = cut(&mut self.out_offsets, rows, &mut self.out_targets);
        self.out_descriptions.truncate(end);
        let end = cut(&mut self.in_offsets, rows, &mut self.in_sources);
        self.in_descriptions.truncate(end);
        cut(&mut self.label_offsets, rows, &mut self.labels);
        let end = cut(&mut self.feature_offsets, rows, &mut self.feature_keys);
        self.feature_kinds.truncate(end);
        self.feature_bits.truncate(end);
        self.parents.truncate(rows);
        self.by_parent.retain(|&row| (row as usize) < rows);
        self.ids.truncate(rows);
        let boxes = self.aabb_rows.partition_point(|&r| (r as usize) < rows);
        self.aabb_rows.truncate(boxes);
        self.aabbs.truncate(boxes);
    }
}

/// Appends rows `rows` of `old` to `new` unchanged (they keep their row numbers, so
/// edge rows stay valid), advancing `aabb_cursor` through `old`'s sparse boxes.
fn copy_rows(
    old: &LayerSegment,
    new: &mut LayerSegment,
    rows: Range<usize>,
    aabb_cursor: &mut usize,
) {
    let (a, b) = (rows.start, rows.end);
    if a < b {
        let r = copy_offsets(&mut new.point_offsets, &old.point_offsets, a, b);
        new.points.extend_from_slice(&old.points[r]);
        let r = copy_offsets(&mut new.out_offsets, &old.out_offsets, a, b);
        new.out_targets
            .extend_from_slice(&old.out_targets[r.clone()]);
        new.out_descriptions
            .extend_from_slice(&old.out_descriptions[r]);
        let r = copy_offsets(&mut new.in_offsets, &old.in_offsets, a, b);
        new.in_sources.extend_from_slice(&old.in_sources[r.clone()]);
        new.in_descriptions
            .extend_from_slice(&old.in_descriptions[r]);
        let r = copy_offsets(&mut new.label_offsets, &old.label_offsets, a, b);
        new.labels.extend_from_slice(&old.labels[r]);
        let r = copy_offsets(&mut new.feature_offsets, &old.feature_offsets, a, b);
        new.feature_keys
            .extend_from_slice(&old.feature_keys[r.clone()]);
        new.feature_kinds
            .extend_from_slice(&old.feature_kinds[r.clone()]);
        new.feature_bits.extend_from_slice(&old.feature_bits[r]);
        new.parents.extend_from_slice(&old.parents[a..b]);
    }
    // Boxes of rows before `b`: those in `a..b` are copied, the rest (rebuilt rows) are
    // skipped.
    while let Some(&row) = old.aabb_rows.get(*aabb_cursor) {
        if row as usize >= b {
            break;
        }
        if row as usize >= a {
            new.aabb_rows.push(row);
            new.aabbs.push(old.aabbs[*aabb_cursor]);
        }
        *aabb_cursor += 1;
    }
}

/// Appends `old`'s offsets of rows `a..b`, shifted to continue `new`; returns the range
/// of those rows' entries in `old`'s value columns.
fn copy_offsets(new: &mut Vec<u32>, old: &[u32], a: usize, b: usize) -> Range<usize> {
    let base = *new.last().expect("offset columns start with 0");
    let start = old[a];
    new.extend(old[a + 1..=b].iter().map(|&o| o - start + base));
    start as usize..old[b] as usize
}
