//! Patching a cached segment's layer index ([`LayerIndexSegment`]) instead of rebuilding
//! its kd-tree, for [`super::SegmentCache`].
//!
//! A row whose points changed since the base tree was built is listed as patched (its
//! base entries die, its points are read from the point column); rows removed from the
//! end die by the row count. The patch costs queries a scan of its points and the walk
//! the dead entries it skips, so past a budget it is **folded**: the tree is rebuilt
//! from the current rows and the patch emptied.
//!
//! # Policy
//! The patch's two costs are bounded apart. Its live points (every point of a patched
//! row) are scanned by every query, so the patch is folded once they exceed
//! `max(FOLD_MIN, base points / 8)`; the base entries it killed only cost the walks that
//! reach them, so it is folded once they exceed `max(FOLD_MIN, base points / 4)`. One
//! object moved (its mesh node's points all change: as many killed as live) stays a
//! patch up to `FOLD_MIN` points, whatever the layer's size; a row moved again and again
//! costs its points once, so a node that keeps moving never forces a fold. Worst case for
//! one publish: a fold, i.e. one full rebuild of the tree (what every change cost
//! before). Amortised: a fold follows at least `max(FOLD_MIN, n / 8)` changed points, so
//! a layer of `n` points pays at most 8 rebuilds' worth of `O(n log n) / n` per changed
//! point, and a query scans at most `max(FOLD_MIN, n / 8)` points beyond the tree.
//!
//! (Until 2026-12 the sum of the two was held to `max(1024, n / 8)`: an object of more
//! than 512 points, such as the office's median object in a room of under 8,192 mesh
//! points, folded, i.e. rebuilt its room's tree, on every move.)

use crate::snapshot::schema::{LayerIndexSegment, LayerSegment};
use crate::{LayerId, NodeId, SceneGraph};

/// Fewest changed points a layer index absorbs before it is folded.
const FOLD_MIN: usize = 1024;

/// Rows of a layer whose points changed in one build, found before the rows are
/// rewritten: `rows` (old rows whose points differ, and every appended row) and the
/// base entries those changes killed.
#[derive(Debug, Default)]
pub(super) struct PointChanges {
    rows: Vec<u32>,
    killed: usize,
}

impl PointChanges {
    /// Changes in `old`'s rows `dirty_rows` (their new content is the graph's node with
    /// the id at that row in `ids`) and rows `old.ids.len()..ids.len()` appended, after
    /// `cut_points` points were cut from `old`'s end ([`PointChanges::points_from`]).
    /// `old` still holds its previous rows and layer index.
    pub(super) fn find(
        graph: &SceneGraph,
        old: &LayerSegment,
        dirty_rows: &[usize],
        ids: &[u64],
        cut_points: usize,
    ) -> Self {
        let Some(index) = old.layer_index.as_ref() else {
            return PointChanges::default();
        };
        let mut c = PointChanges {
            rows: Vec::new(),
            killed: cut_points,
        };
        for &row in dirty_rows {
            let r = old.point_offsets[row] as usize..old.point_offsets[row + 1] as usize;
            let new = &graph.nodes[&NodeId(ids[row])].points;
            let same = old.points[r.clone()].len() == new.len()
                && old.points[r.clone()]
                    .iter()
                    .zip(new)
                    .all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits));
            if !same {
                c.note(index, row as u32, r.len());
            }
        }
        c.rows.extend(old.ids.len() as u32..ids.len() as u32);
        c
    }

    /// Points of `old`'s rows from `from` on, about to be cut (nodes removed from the
    /// end; their base entries die), when `old` has a layer index.
    pub(super) fn points_from(old: &LayerSegment, from: usize) -> usize {
        match old.layer_index.as_ref() {
            Some(_) => old.points.len() - old.point_offsets[from] as usize,
            None => 0,
        }
    }

    /// Row `row`, holding `old_points` points before, changed.
    fn note(&mut self, index: &LayerIndexSegment, row: u32, old_points: usize) {
        if row < index.base_rows && index.patched.binary_search(&row).is_err() {
            self.killed += old_points;
        }
        self.rows.push(row);
    }
}

/// Brings the layer index of `s` (rows up to date, index as it was) up to date after
/// `changes`, by patching it or, past the budget, folding it (see the module docs);
/// `killed` counts the base entries the patch killed so far and is reset by a fold.
/// Returns whether a new base tree was built.
pub(super) fn update_layer_index(
    graph: &SceneGraph,
    layer: LayerId,
    s: &mut LayerSegment,
    changes: PointChanges,
    killed: &mut usize,
) -> bool {
    let Some(mut index) = s.layer_index.take() else {
        s.layer_index = graph.archived_layer_index(layer, s);
        *killed = 0;
        return true;
    };
    let rows = s.ids.len() as u32;
    let offsets = &s.point_offsets;
    let has_points = |row: u32| offsets[row as usize] != offsets[row as usize + 1];
    index.patched.retain(|&r| r < rows);
    index.patched.extend(
        changes
            .rows
            .into_iter()
            .filter(|&r| r < index.base_rows || has_points(r)),
    );
    index.patched.sort_unstable();
    index.patched.dedup();
    *killed += changes.killed;
    let live: usize = index
        .patched
        .iter()
        .map(|&r| (offsets[r as usize + 1] - offsets[r as usize]) as usize)
        .sum();
    let base = index.base_points as usize;
    if live > FOLD_MIN.max(base / 8) || *killed > FOLD_MIN.max(base / 4) {
        s.layer_index = graph.archived_layer_index(layer, s);
        *killed = 0;
        true
    } else {
        s.layer_index = Some(index);
        false
    }
}
