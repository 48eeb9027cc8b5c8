//! A layer split into **parts** for a publishing writer ([`super::SegmentCache`]): row
//! chunks over disjoint, ascending ranges of node ids, each a [`LayerSegment`] of its own
//! (with its own postings, `by_parent`, layer index and the node indexes rooted in it),
//! sent only when its rows change. Appending a row, or changing `k` rows, resends the
//! parts that hold them, not the layer.
//!
//! # Policy
//! - The newest part (the *tail*, which covers every id above the others) takes appended
//!   rows until it holds `tail` rows ([`PART_ROWS`](crate::snapshot::PART_ROWS)); the
//!   next append starts a new tail, so the sealed part is not sent again. An agent pose
//!   per tick costs the tail's rows (at most `tail`), whatever the trajectory's length.
//! - Sealed parts whose rows no change touched for [`COLD_UPDATES`] updates of their
//!   layer merge with their right neighbour when it is at least as large and the two
//!   hold at most `max` rows ([`MAX_PART_ROWS`](crate::snapshot::MAX_PART_ROWS)): like a
//!   binary counter, each row is resent O(log(max / tail)) times by merges over its life,
//!   and a merge sends at most `max` rows once.
//! - Parts untouched for [`FROZEN_UPDATES`] updates go on merging up to
//!   [`FROZEN_GROWTH`] times `max` ([`PartRows::frozen_max`]), so a layer of `n` rows
//!   keeps O(log(n / tail) + n / frozen_max) parts plus those changed lately.
//! - A part that lost rows (the front of a sliding window) is split into pieces of
//!   `tail` (of `max / 2` first when it holds more than `max`); a part that changed and
//!   holds more than `max` (inserts in the middle, an edit of a frozen part), or any
//!   part past `frozen_max` (a bulk load), into pieces of `max / 2`. An empty part is
//!   dropped (a layer keeps at least one).
//! - Part numbers (in segment ids) are reused once freed, so they stay below the most
//!   parts a layer had at once.
//!
//! Worst cases: an edit of any row resends its part once (at most `frozen_max` rows),
//! split so that the next edits there resend at most `max / 2`; a merge rebuilds and
//! resends at most `frozen_max` rows.

use super::chunk_state::PublishedLayer;
use super::part_patch::{Cached, patched};
use crate::graph::LayerChanges;
use crate::{LayerId, NodeId, SceneGraph};

/// How a publishing writer splits layers into parts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct PartRows {
    /// Rows the tail takes before a new tail starts.
    pub(super) tail: usize,
    /// Most rows of a part: merges stop below it, a larger part is split.
    pub(super) max: usize,
}

/// Updates of its layer a sealed part must go untouched before it may merge.
const COLD_UPDATES: u64 = 16;

/// Updates of its layer a sealed part must go untouched before it may merge past `max`
/// rows, up to [`FROZEN_GROWTH`] times `max` (about 34 s of a 30 Hz stream).
const FROZEN_UPDATES: u64 = 1024;

/// How many times `max` rows a part that stays untouched for [`FROZEN_UPDATES`] may grow
/// to by merges: a long history keeps `FROZEN_GROWTH` times fewer parts.
const FROZEN_GROWTH: usize = 16;

impl PartRows {
    /// Most rows of a part merged from parts untouched for [`FROZEN_UPDATES`] updates
    /// (and within what a part's index items can address).
    fn frozen_max(&self) -> usize {
        let addressable = (1 << crate::snapshot::PART_ITEM_ROW_BITS) - 1;
        self.max
            .saturating_mul(FROZEN_GROWTH)
            .min(addressable)
            .max(self.max)
    }
}

/// One part of a layer.
pub(super) struct Part {
    /// The part's number (in its segment id).
    number: u32,
    /// Smallest id the part covers (the first part covers every id below the second's
    /// lower bound whatever its own).
    low: u64,
    pub(super) cached: Box<Cached>,
    /// The layer's update count when the part last changed (its segment is new).
    touched: u64,
    /// The layer's update count when a row of the part last changed (a merge keeps the
    /// later of its parts'): how long the part has been cold.
    edited: u64,
    /// The layer's update count when the part, or the part it was split from, last lost
    /// rows (a sliding window's front); `None` if never. Such parts do not merge for
    /// [`FROZEN_UPDATES`] updates, so that the pieces ahead of a window's front are not
    /// merged again before the front reaches them.
    lost_at: Option<u64>,
    /// Whether the part is in published form (`ChunkState::publish_form`); only a part
    /// that changed is put back inline and published again.
    published: bool,
    /// The ids of the chunk segments the part last published beside its own.
    chunk_ids: Vec<u64>,
}

impl Part {
    /// Segments the part publishes: its own and its chunks (as last published).
    fn segments(&self) -> usize {
        1 + self.chunk_ids.len()
    }
}

/// A layer's parts, ascending by id range.
pub(super) struct LayerParts {
    /// The layer's incarnation (a removed layer's id may come back).
    pub(super) incarnation: u64,
    /// The layer generation the parts are current with (the layer's change journal
    /// starts there).
    pub(super) generation: u64,
    pub(super) parts: Vec<Part>,
    /// Part numbers freed, for reuse.
    free: Vec<u32>,
    /// The next part number never used.
    next: u32,
    /// Updates of the layer so far.
    updates: u64,
    /// Whether the last update or publish form changed the layer's segments (parts added,
    /// merged, split or dropped, or a part's chunks): the cut's entries are rebuilt.
    pub(super) reshaped: bool,
}

impl LayerParts {
    /// The layer built afresh: its rows in parts of at most `rows.max` (one part when
    /// `rows` is `None`).
    pub(super) fn full(graph: &SceneGraph, layer: LayerId, rows: Option<PartRows>) -> Box<Self> {
        let l = &graph.layers[&layer];
        let mut ids: Vec<u64> = l.nodes.iter().map(|n| n.0).collect();
        ids.sort_unstable();
        let mut parts = Box::new(LayerParts {
            incarnation: l.incarnation,
            generation: l.generation,
            parts: Vec::new(),
            free: Vec::new(),
            next: 0,
            updates: 0,
            reshaped: true,
        });
        let piece = rows.map_or(usize::MAX, |r| r.max);
        if ids.len() <= piece {
            parts.push_built(graph, layer, 0, ids);
        } else {
            for chunk in ids.chunks(piece) {
                let low = if parts.parts.is_empty() { 0 } else { chunk[0] };
                parts.push_built(graph, layer, low, chunk.to_vec());
            }
        }
        parts
    }

    /// Appends a part built afresh from `ids`, covering ids from `low`.
    fn push_built(&mut self, graph: &SceneGraph, layer: LayerId, low: u64, ids: Vec<u64>) {
        let number = self.allocate();
        self.parts.push(Part {
            number,
            low,
            cached: Cached::build(graph, layer, number, ids),
            touched: self.updates,
            edited: self.updates,
            lost_at: None,
            published: false,
            chunk_ids: Vec::new(),
        });
        self.reshaped = true;
    }

    /// Segments the layer publishes (parts and their chunks, as last published).
    pub(super) fn segment_count(&self) -> usize {
        self.parts.iter().map(Part::segments).sum()
    }

    /// Puts every part that changed since the last publish (or that is inline) in published
    /// form, building the node index trees it does not withhold; notes whether its chunk
    /// segments changed.
    pub(super) fn publish_form(&mut self, graph: &SceneGraph, chunk_len: usize, tree_min: usize) {
        for part in self.parts.iter_mut().filter(|p| !p.published) {
            let cached = &mut *part.cached;
            cached
                .chunks
                .build_stale_node_trees(graph, &mut cached.segment, tree_min);
            cached
                .chunks
                .publish_form(&mut cached.segment, chunk_len, tree_min);
            part.published = true;
            let published = PublishedLayer::new(&cached.segment, &cached.chunks);
            let ids: Vec<u64> = published
                .chunks()
                .map(|(id, _)| id)
                .chain(published.tree_chunks().map(|(id, _, _)| id))
                .collect();
            if ids != part.chunk_ids {
                self.reshaped = true;
                part.chunk_ids = ids;
            }
        }
    }

    /// The first part inline (what `SegmentCache::layer_segment` hands out for a layer in
    /// one piece).
    pub(super) fn first_inline(&mut self) -> &mut Cached {
        let part = &mut self.parts[0];
        if part.published {
            part.cached.chunks.restore(&mut part.cached.segment);
            part.published = false;
        }
        &mut part.cached
    }

    fn allocate(&mut self) -> u32 {
        self.free.pop().unwrap_or_else(|| {
            self.next += 1;
            self.next - 1
        })
    }

    /// The part numbers in id order (what the manifest lists).
    pub(super) fn numbers(&self) -> Vec<u32> {
        self.parts.iter().map(|p| p.number).collect()
    }

    /// The smallest and largest id of the layer `l` from the parts, when they are current
    /// with it.
    pub(super) fn current_id_bounds(&self, l: &crate::graph::Layer) -> Option<(u64, u64)> {
        if self.generation != l.generation || self.incarnation != l.incarnation {
            return None;
        }
        fn ids(p: &Part) -> &[u64] {
            &p.cached.segment.ids
        }
        let min = self.parts.iter().find_map(|p| ids(p).first().copied());
        let max = self.parts.iter().rev().find_map(|p| ids(p).last().copied());
        Some((min.unwrap_or(u64::MAX), max.unwrap_or(0)))
    }

    /// The part holding (or that would hold) node `id`.
    fn route(&self, id: u64) -> usize {
        self.parts
            .partition_point(|p| p.low <= id)
            .saturating_sub(1)
    }

    /// The parts brought up to date with the layer's journal `changes`, each changed part
    /// patched row by row (or rebuilt, when its rows moved), then sealed, split, merged
    /// or dropped by the policy; `None` when the journal cannot say what changed (a full
    /// build is needed).
    pub(super) fn patched(
        mut self: Box<Self>,
        graph: &SceneGraph,
        layer: LayerId,
        changes: LayerChanges,
        rows: Option<PartRows>,
    ) -> Option<Box<Self>> {
        let l = &graph.layers[&layer];
        if changes.everything || changes.since != self.generation {
            return None;
        }
        self.updates += 1;
        self.reshaped = false;
        let in_layer = |id: &NodeId| graph.nodes.get(id).is_some_and(|n| n.layer == layer);
        if let Some(rows) = rows {
            self.seal_tail(&changes.nodes, rows, in_layer, graph, layer);
        }
        let mut routed: Vec<LayerChanges> = self
            .parts
            .iter()
            .map(|p| LayerChanges::new(p.cached.segment.generation))
            .collect();
        for id in changes.nodes {
            routed[self.route(id.0)].nodes.push(id);
        }
        for id in changes.removed {
            routed[self.route(id.0)].removed.push(id);
        }
        for id in changes.index_roots {
            routed[self.route(id.0)].index_roots.push(id);
        }
        for (id, kept) in changes.points_kept {
            routed[self.route(id.0)].points_kept.push((id, kept));
        }
        let single = self.parts.len() == 1;
        let parts = std::mem::take(&mut self.parts);
        for (mut part, mut c) in parts.into_iter().zip(routed) {
            if c.nodes.is_empty() && c.removed.is_empty() && c.index_roots.is_empty() {
                self.parts.push(part);
                continue;
            }
            c.geometry = changes.geometry;
            if !c.removed.is_empty() {
                part.lost_at = Some(self.updates);
            }
            if part.published {
                part.cached.chunks.restore(&mut part.cached.segment);
                part.published = false;
            }
            let old_ids = part.cached.segment.ids.clone();
            let expected = single.then_some(l.nodes.len());
            let number = part.number;
            let nodes = c.nodes.clone();
            part.cached = match patched(graph, layer, *part.cached, c, expected) {
                Some(cached) => cached,
                None => {
                    let mut ids: Vec<u64> = old_ids
                        .into_iter()
                        .filter(|&id| in_layer(&NodeId(id)))
                        .chain(nodes.iter().filter(|id| in_layer(id)).map(|id| id.0))
                        .collect();
                    ids.sort_unstable();
                    ids.dedup();
                    Cached::build(graph, layer, number, ids)
                }
            };
            part.touched = self.updates;
            part.edited = self.updates;
            self.parts.push(part);
        }
        let total: usize = self.parts.iter().map(|p| p.cached.segment.ids.len()).sum();
        if total != l.nodes.len() {
            return None;
        }
        if let Some(rows) = rows {
            self.split(graph, layer, rows);
            self.drop_empty();
            self.merge_cold(graph, layer, rows);
        }
        self.generation = l.generation;
        Some(self)
    }

    /// Starts a new tail for the nodes appended above the tail's rows when the tail holds
    /// `rows.tail` rows or more.
    fn seal_tail(
        &mut self,
        changed: &[NodeId],
        rows: PartRows,
        in_layer: impl Fn(&NodeId) -> bool,
        graph: &SceneGraph,
        layer: LayerId,
    ) {
        let tail = &self.parts[self.parts.len() - 1].cached.segment;
        let Some(&max) = tail.ids.last() else {
            return;
        };
        if tail.ids.len() < rows.tail {
            return;
        }
        let first_new = changed
            .iter()
            .filter(|id| id.0 > max && in_layer(id))
            .map(|id| id.0)
            .min();
        if let Some(low) = first_new {
            self.push_built(graph, layer, low, Vec::new());
        }
    }

    /// Splits the parts the policy keeps smaller: one that lost rows in this update into
    /// pieces of `rows.tail` (of `rows.max / 2` first if it holds more than `rows.max`:
    /// the front of a sliding window then resends about a tail's rows per removal, not
    /// its whole part), one that changed past `rows.max` rows (an
    /// insert in the middle, or an edit of a frozen part) and any part past
    /// [`PartRows::frozen_max`] (a bulk load) into pieces of `rows.max / 2`.
    fn split(&mut self, graph: &SceneGraph, layer: LayerId, rows: PartRows) {
        let now = self.updates;
        let half = (rows.max / 2).max(1);
        let piece = |p: &Part| {
            let len = p.cached.segment.ids.len();
            if p.lost_at == Some(now) && len > rows.tail {
                // A frozen part first into pieces of `max / 2`, then its front.
                Some(if len <= rows.max { rows.tail } else { half })
            } else if (p.touched == now && len > rows.max) || len > rows.frozen_max() {
                Some(half)
            } else {
                None
            }
        };
        if self.parts.iter().all(|p| piece(p).is_none()) {
            return;
        }
        let parts = std::mem::take(&mut self.parts);
        for part in parts {
            let Some(piece) = piece(&part) else {
                self.parts.push(part);
                continue;
            };
            let pieces: Vec<Vec<u64>> = part
                .cached
                .segment
                .ids
                .chunks(piece)
                .map(<[u64]>::to_vec)
                .collect();
            self.free.push(part.number);
            self.reshaped = true;
            for (i, ids) in pieces.into_iter().enumerate() {
                let low = if i == 0 { part.low } else { ids[0] };
                self.push_built(graph, layer, low, ids);
                if let Some(piece) = self.parts.last_mut() {
                    piece.lost_at = part.lost_at;
                }
            }
        }
    }

    /// Drops the empty parts, keeping at least one (the first part then covers the ids
    /// below its neighbour's).
    fn drop_empty(&mut self) {
        let mut at = 0;
        while at < self.parts.len() && self.parts.len() > 1 {
            if self.parts[at].cached.segment.ids.is_empty() {
                let gone = self.parts.remove(at);
                self.free.push(gone.number);
                self.reshaped = true;
                if at == 0 {
                    self.parts[0].low = 0;
                }
            } else {
                at += 1;
            }
        }
    }

    /// Merges sealed parts whose rows no change touched for [`COLD_UPDATES`] updates
    /// (merges do not count) into their right neighbour when it is at least as large and
    /// the two fit `rows.max` (parts untouched for [`FROZEN_UPDATES`]:
    /// [`PartRows::frozen_max`]); parts that lost rows lately do not merge.
    fn merge_cold(&mut self, graph: &SceneGraph, layer: LayerId, rows: PartRows) {
        let idle = |p: &Part, now: u64| now - p.edited;
        let lost_lately = |p: &Part, now: u64| p.lost_at.is_some_and(|t| now - t < FROZEN_UPDATES);
        let len = |p: &Part| p.cached.segment.ids.len();
        // The tail (last part) never merges.
        let mut at = self.parts.len().saturating_sub(2);
        while at > 0 {
            let (left, right) = (&self.parts[at - 1], &self.parts[at]);
            let idle = idle(left, self.updates).min(idle(right, self.updates));
            let limit = if idle >= FROZEN_UPDATES {
                rows.frozen_max()
            } else {
                rows.max
            };
            if idle >= COLD_UPDATES
                && !lost_lately(left, self.updates)
                && !lost_lately(right, self.updates)
                && len(left) <= len(right)
                && len(left) + len(right) <= limit
            {
                let right = self.parts.remove(at);
                let left = &self.parts[at - 1];
                let mut ids = left.cached.segment.ids.clone();
                ids.extend_from_slice(&right.cached.segment.ids);
                let number = left.number;
                let edited = left.edited.max(right.edited);
                let lost_at = left.lost_at.max(right.lost_at);
                self.free.push(right.number);
                let merged = &mut self.parts[at - 1];
                merged.cached = Cached::build(graph, layer, number, ids);
                merged.touched = self.updates;
                merged.edited = edited;
                merged.lost_at = lost_at;
                merged.published = false;
                self.reshaped = true;
            }
            at -= 1;
        }
    }
}

/// A layer as a publishing writer sends it: its parts in id order
/// ([`super::SegmentCache::published_layer`]), each a [`PublishedLayer`].
#[derive(Debug, Clone)]
pub struct PublishedParts<'c> {
    parts: Vec<PublishedLayer<'c>>,
    /// Per part, whether it changed in the layer's last update.
    changed: Vec<bool>,
    reshaped: bool,
}

impl<'c> PublishedParts<'c> {
    pub(super) fn new(parts: &'c LayerParts) -> Self {
        PublishedParts {
            parts: parts
                .parts
                .iter()
                .map(|p| PublishedLayer::new(&p.cached.segment, &p.cached.chunks))
                .collect(),
            changed: parts
                .parts
                .iter()
                .map(|p| p.touched == parts.updates)
                .collect(),
            reshaped: parts.reshaped,
        }
    }

    /// The parts, in id order.
    pub fn parts(&self) -> &[PublishedLayer<'c>] {
        &self.parts
    }

    /// The parts that changed in the layer's last update (every part of a layer built
    /// afresh): the others are as the publish before sent them.
    pub fn changed_parts(&self) -> impl Iterator<Item = &PublishedLayer<'c>> {
        self.parts
            .iter()
            .zip(&self.changed)
            .filter_map(|(p, &changed)| changed.then_some(p))
    }

    /// Whether the layer's segments (their ids) changed in its last update: parts added,
    /// merged, split or dropped, or a part's chunks.
    pub fn reshaped(&self) -> bool {
        self.reshaped
    }

    /// Every segment the layer publishes (parts, point chunks, tree chunks) as `(segment
    /// id, generation)`, ascending by id.
    pub fn segments(&self) -> Vec<(u64, u64)> {
        let mut all: Vec<(u64, u64)> = Vec::new();
        for p in &self.parts {
            all.push((p.segment_id(), p.segment.generation));
            all.extend(p.chunks());
            all.extend(p.tree_chunks().map(|(id, generation, _)| (id, generation)));
        }
        all.sort_unstable();
        all
    }
}
