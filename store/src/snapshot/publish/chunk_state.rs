//! What a publishing writer's [`super::SegmentCache`] keeps per chunked layer: which
//! column positions changed since the last publish ([`ChangedPoints`]) and each chunk's
//! generation ([`ChunkState`]), so that a publish resends only the chunks whose points
//! changed, and a tree (the layer index's base tree, a node index's tree) only when it
//! was built anew; and [`PublishedLayer`], a layer as it is published.

use super::chunk_source::{PointChunkSource, TreeChunkSource};
use crate::index::{KdTree, build_tree};
use crate::snapshot::chunking::{
    WITHHELD_TREE_MAX_MEMBERS, chunk_count, chunk_range, chunk_segment_id, has_tree_chunk,
    is_chunked, part_segment_id, tree_chunk_segment_id, withholds_node_tree,
};
use crate::snapshot::schema::{LayerSegment, NodeIndexSegment, PointChunkRef, TreeChunkRef};
use crate::{LayerId, NodeId, Point, SceneGraph};
use std::ops::Range;

/// Column positions whose points may differ from the last publish's.
#[derive(Debug, Clone)]
pub(super) enum ChangedPoints {
    /// Any position (a fresh build).
    All,
    /// These ranges (an open end is `usize::MAX`), unordered, possibly overlapping.
    Ranges(Vec<Range<usize>>),
}

impl Default for ChangedPoints {
    fn default() -> Self {
        ChangedPoints::Ranges(Vec::new())
    }
}

impl ChangedPoints {
    /// Records that positions `range` may have changed.
    pub(super) fn add(&mut self, range: Range<usize>) {
        if let ChangedPoints::Ranges(ranges) = self
            && range.start < range.end
        {
            ranges.push(range);
        }
    }

    /// Records the changes a row-by-row patch of `old` makes: rows `dirty_rows` take the
    /// points of the graph's node with the id at that row in `ids`, rows past `old`'s are
    /// appended. `old` still holds its previous rows (after any cut from its end).
    /// `points_kept` is the journal's: per node whose points changed, how many leading
    /// points a change kept (a node not listed kept them all), so that only the points
    /// past that are compared (a mesh growing by appends compares nothing).
    /// Returns, per dirty row, how many of its leading points stay as they were (the
    /// patch rewrites only the rest).
    pub(super) fn note_patch(
        &mut self,
        graph: &SceneGraph,
        old: &LayerSegment,
        dirty_rows: &[usize],
        ids: &[u64],
        mut points_kept: Vec<(NodeId, usize)>,
    ) -> Vec<usize> {
        points_kept.sort_unstable();
        let mut kept = Vec::with_capacity(dirty_rows.len());
        for &row in dirty_rows {
            let (a, b) = (
                old.point_offsets[row] as usize,
                old.point_offsets[row + 1] as usize,
            );
            let id = NodeId(ids[row]);
            let new = &graph.nodes[&id].points;
            // The least `kept` of the node's entries (sorted by id, then `kept`), if any.
            let known = match points_kept.binary_search(&(id, 0)) {
                Ok(at) | Err(at) => points_kept.get(at).filter(|(n, _)| *n == id),
            };
            let same = match known {
                Some(&(_, k)) => {
                    let k = k.min(b - a).min(new.len());
                    k + common_prefix(&old.points[a + k..b], &new[k..])
                }
                // Not listed: the node kept its points (checked cheaply, in case).
                None if b - a == new.len() => b - a,
                None => common_prefix(&old.points[a..b], new),
            };
            kept.push(same);
            if new.len() == b - a {
                self.add(a + same..b);
            } else {
                // The row changes length: every later position shifts.
                self.add(a + same..usize::MAX);
            }
        }
        if ids.len() > old.ids.len() {
            self.add(old.points.len()..usize::MAX);
        }
        kept
    }

    fn touches(&self, range: &Range<usize>) -> bool {
        match self {
            ChangedPoints::All => true,
            ChangedPoints::Ranges(ranges) => ranges
                .iter()
                .any(|r| r.start < range.end && range.start < r.end),
        }
    }
}

/// How many leading points `a` and `b` share bit for bit: blocks compared with `memcmp`,
/// then the first differing block point by point (a mesh node of 50,000 points is
/// compared in microseconds).
fn common_prefix(a: &[Point], b: &[Point]) -> usize {
    fn bytes(p: &[Point]) -> &[u8] {
        bytemuck::cast_slice(p)
    }
    const BLOCK: usize = 256;
    let n = a.len().min(b.len());
    let mut at = 0;
    while at + BLOCK <= n && bytes(&a[at..at + BLOCK]) == bytes(&b[at..at + BLOCK]) {
        at += BLOCK;
    }
    at + a[at..n]
        .iter()
        .zip(&b[at..n])
        .take_while(|(p, q)| bytes(std::slice::from_ref(*p)) == bytes(std::slice::from_ref(*q)))
        .count()
}

/// A chunked layer's chunks as last published.
#[derive(Debug, Default)]
pub(super) struct ChunkState {
    /// Each chunk's reference (generation, length) in the last published layer segment;
    /// empty when the layer was published in one piece (or not yet).
    refs: Vec<PointChunkRef>,
    /// The column, moved out of the segment while it is in published form.
    aside: Vec<Point>,
    /// Positions changed since the last publish.
    pub(super) changed: ChangedPoints,
    /// Points per chunk of `refs`.
    chunk_len: usize,
    /// The tree chunk of the layer index's base tree last published (`None` when the
    /// tree went inline, or not yet).
    tree_ref: Option<TreeChunkRef>,
    /// The base tree, moved out of the segment while it is in published form.
    tree_aside: Option<KdTree>,
    /// Whether the base tree was built anew since the last publish.
    pub(super) tree_rebuilt: bool,
    /// Per node index of the last published segment, by position: its root and its
    /// tree chunk (`None` for a tree kept inline).
    node_refs: Vec<(u64, Option<TreeChunkRef>)>,
    /// The node indexes' trees that travel as chunks or are withheld, by position, moved
    /// out of the segment while it is in published form.
    node_trees_aside: Vec<(usize, KdTree)>,
    /// Roots whose node index tree was built anew since the last publish, among those
    /// whose tree the last publish sent as a chunk.
    node_trees_rebuilt: Vec<u64>,
    /// Roots of node indexes whose sub-tree changed and whose tree is not built yet
    /// (empty in the segment): built when the segment is asked for inline, or when a
    /// publish would not withhold the tree (see [`ChunkState::build_stale_node_trees`]).
    node_trees_stale: Vec<u64>,
    /// Empty trees that stand in for the trees moved aside, kept for reuse: building
    /// one costs about a microsecond, a publish moves a tree per chunked index.
    empty_trees: Vec<KdTree>,
}

impl ChunkState {
    /// The state of a layer built afresh: every chunk changed.
    pub(super) fn fresh() -> Self {
        ChunkState {
            changed: ChangedPoints::All,
            tree_rebuilt: true,
            ..ChunkState::default()
        }
    }

    /// Puts the column and the trees back into `segment` (the form the cache patches).
    pub(super) fn restore(&mut self, segment: &mut LayerSegment) {
        if let Some(tree) = self.tree_aside.take()
            && let Some(index) = segment.layer_index.as_mut()
        {
            self.empty_trees
                .push(std::mem::replace(&mut index.tree, tree));
            index.tree_chunk = None;
        }
        for (position, tree) in self.node_trees_aside.drain(..) {
            let index = &mut segment.node_indexes[position];
            self.empty_trees
                .push(std::mem::replace(&mut index.tree, tree));
            index.tree_chunk = None;
        }
        if !segment.point_chunks.is_empty() {
            segment.points = std::mem::take(&mut self.aside);
            segment.point_chunks.clear();
        }
        segment.point_chunk_len = 0;
    }

    /// Notes that the tree of the node index rooted at `root` was built anew: if the last
    /// publish sent it as a chunk, the next one sends it again. (Nothing is noted for a
    /// cache that never publishes, whose segments keep their trees inline.)
    pub(super) fn node_tree_rebuilt(&mut self, root: u64) {
        if self
            .node_refs
            .iter()
            .any(|&(r, chunk)| r == root && chunk.is_some())
        {
            self.node_trees_rebuilt.push(root);
        }
    }

    /// Empties the node index `index`, whose sub-tree changed: its tree is built by
    /// [`ChunkState::build_stale_node_trees`] when needed, so a tree a publish would
    /// withhold is not built at all.
    pub(super) fn node_tree_stale(&mut self, index: &mut NodeIndexSegment) {
        self.node_tree_rebuilt(index.root);
        let empty = self.empty_trees.pop().unwrap_or_else(|| build_tree(&[]));
        index.tree = empty;
        index.ids.clear();
        index.tree_chunk = None;
        self.node_trees_stale.push(index.root);
    }

    /// Builds the trees of the stale node indexes of `segment` that a publish would not
    /// withhold, its larger trees going out as chunks of `min_points` points or more
    /// (every one for 0); the others stay stale. Roots no longer indexed are forgotten.
    pub(super) fn build_stale_node_trees(
        &mut self,
        graph: &SceneGraph,
        segment: &mut LayerSegment,
        min_points: usize,
    ) {
        self.node_trees_stale.sort_unstable();
        self.node_trees_stale.dedup();
        self.node_trees_stale.retain(|&root| {
            let Ok(at) = segment
                .node_indexes
                .binary_search_by_key(&root, |index| index.root)
            else {
                return false;
            };
            let points = graph.indexed_points(NodeId(root));
            let members = graph.indexed_member_count(NodeId(root), WITHHELD_TREE_MAX_MEMBERS + 1);
            if withholds_node_tree(points, members, min_points) {
                return true;
            }
            segment.node_indexes[at] = graph.archived_node_index(NodeId(root));
            false
        });
    }

    /// Brings the chunks up to date with `segment` and puts it in published form: for a
    /// layer of more than `chunk_len` points its points move aside and `point_chunks`
    /// lists the chunks, each at the generation it last changed (the segment's
    /// generation if it changed since the last publish). A layer index's base tree of
    /// `tree_min_points` or more moves aside too, named by its tree chunk, which keeps
    /// its generation until the tree is built anew; so do node indexes' trees of
    /// `tree_min_points` or more, and smaller node index trees are withheld.
    pub(super) fn publish_form(
        &mut self,
        segment: &mut LayerSegment,
        chunk_len: usize,
        tree_min_points: usize,
    ) {
        self.tree_publish_form(segment, tree_min_points);
        self.node_trees_publish_form(segment, tree_min_points);
        let total = segment.points.len();
        let changed = std::mem::take(&mut self.changed);
        if !is_chunked(total, chunk_len) {
            self.refs.clear();
            return;
        }
        if self.chunk_len != chunk_len {
            self.refs.clear();
            self.chunk_len = chunk_len;
        }
        let refs = (0..chunk_count(total, chunk_len))
            .map(|i| {
                let range = chunk_range(i, total, chunk_len);
                let len = range.len() as u32;
                match self.refs.get(i) {
                    Some(old) if old.len == len && !changed.touches(&range) => *old,
                    _ => PointChunkRef {
                        generation: segment.generation,
                        len,
                    },
                }
            })
            .collect();
        self.refs = refs;
        segment.point_chunks.clone_from(&self.refs);
        segment.point_chunk_len = chunk_len as u32;
        self.aside = std::mem::take(&mut segment.points);
    }

    /// The base tree's part of [`ChunkState::publish_form`].
    fn tree_publish_form(&mut self, segment: &mut LayerSegment, min_points: usize) {
        let rebuilt = std::mem::take(&mut self.tree_rebuilt);
        let Some(index) = segment
            .layer_index
            .as_mut()
            .filter(|i| has_tree_chunk(0, i.base_points as usize, min_points))
        else {
            self.tree_ref = None;
            return;
        };
        let generation = match self.tree_ref {
            Some(old) if !rebuilt && old.points == index.base_points => old.generation,
            _ => segment.generation,
        };
        let r = TreeChunkRef {
            generation,
            points: index.base_points,
        };
        self.tree_ref = Some(r);
        index.tree_chunk = Some(r);
        let empty = self.empty_trees.pop().unwrap_or_else(|| build_tree(&[]));
        self.tree_aside = Some(std::mem::replace(&mut index.tree, empty));
    }

    /// The node indexes' part of [`ChunkState::publish_form`]: the tree of node index
    /// `i` travels as tree chunk `1 + i` when it is large enough, and keeps its
    /// generation while the same root holds the slot and its tree is not built anew; a
    /// smaller tree is withheld (moved aside, not sent).
    fn node_trees_publish_form(&mut self, segment: &mut LayerSegment, min_points: usize) {
        let mut rebuilt = std::mem::take(&mut self.node_trees_rebuilt);
        rebuilt.sort_unstable();
        let old_refs = std::mem::take(&mut self.node_refs);
        for (i, index) in segment.node_indexes.iter_mut().enumerate() {
            let points = index.tree.size();
            if !has_tree_chunk(1 + i, points, min_points) {
                self.node_refs.push((index.root, None));
                if withholds_node_tree(points, index.ids.len(), min_points) {
                    // Withheld: readers walk a sub-tree this small (`SceneView::node_index`
                    // gives no index), so moving one object does not resend every
                    // object tree of its layer.
                    let empty = self.empty_trees.pop().unwrap_or_else(|| build_tree(&[]));
                    let tree = std::mem::replace(&mut index.tree, empty);
                    self.node_trees_aside.push((i, tree));
                }
                continue;
            }
            let generation = match old_refs.get(i) {
                Some(&(root, Some(old)))
                    if root == index.root
                        && old.points as usize == points
                        && rebuilt.binary_search(&root).is_err() =>
                {
                    old.generation
                }
                _ => segment.generation,
            };
            let r = TreeChunkRef {
                generation,
                points: points as u32,
            };
            self.node_refs.push((index.root, Some(r)));
            index.tree_chunk = Some(r);
            let empty = self.empty_trees.pop().unwrap_or_else(|| build_tree(&[]));
            let tree = std::mem::replace(&mut index.tree, empty);
            self.node_trees_aside.push((i, tree));
        }
    }
}

/// A layer as a publishing writer sends it: the layer segment (points moved to chunks
/// when the layer is chunked, large trees moved to tree chunks), its point chunks and
/// its tree chunks, each with its segment id and generation
/// ([`super::SegmentCache::published_layer`]).
#[derive(Debug, Clone, Copy)]
pub struct PublishedLayer<'c> {
    /// The layer segment.
    pub segment: &'c LayerSegment,
    points: &'c [Point],
    tree: Option<&'c KdTree>,
    node_trees: &'c [(usize, KdTree)],
}

impl<'c> PublishedLayer<'c> {
    pub(super) fn new(segment: &'c LayerSegment, state: &'c ChunkState) -> Self {
        let points = if segment.point_chunks.is_empty() {
            &[][..]
        } else {
            &state.aside[..]
        };
        let tree = segment
            .layer_index
            .as_ref()
            .and_then(|i| i.tree_chunk)
            .and(state.tree_aside.as_ref());
        PublishedLayer {
            segment,
            points,
            tree,
            node_trees: &state.node_trees_aside,
        }
    }

    /// The segment id of this part.
    pub fn segment_id(&self) -> u64 {
        part_segment_id(LayerId(self.segment.layer), self.segment.part)
            .expect("a part's number fits its segment id")
    }

    /// The trees that travel as tree chunks, ascending by slot (the layer index's base
    /// tree first, then node indexes' trees): each one's segment id, generation, and the
    /// chunk ready to archive (the tree is not copied).
    pub fn tree_chunks(&self) -> impl Iterator<Item = (u64, u64, TreeChunkSource<'c>)> + 'c {
        let (layer, part) = (LayerId(self.segment.layer), self.segment.part);
        let segment = self.segment;
        let base = self.tree.and_then(|tree| {
            let index = segment.layer_index.as_ref()?;
            let r = index.tree_chunk?;
            Some((0, r, index.base_rows, tree))
        });
        let nodes = self.node_trees.iter().filter_map(move |(i, tree)| {
            let index = &segment.node_indexes[*i];
            let r = index.tree_chunk?;
            Some((1 + i, r, index.ids.len() as u32, tree))
        });
        base.into_iter()
            .chain(nodes)
            .map(move |(slot, r, items, tree)| {
                let id = tree_chunk_segment_id(layer, part, slot).expect("a tree chunk's id fits");
                (
                    id,
                    r.generation,
                    TreeChunkSource::new(layer, part, slot, r.generation, items, tree),
                )
            })
    }

    /// How many chunk segments the part publishes beside its segment.
    pub fn chunk_segments(&self) -> usize {
        self.segment.point_chunks.len() + self.tree_chunks().count()
    }

    /// The layer's point chunks: `(segment id, generation)` each, in column order (none
    /// for a layer published in one piece).
    pub fn chunks(&self) -> impl Iterator<Item = (u64, u64)> + 'c {
        let (layer, part) = (LayerId(self.segment.layer), self.segment.part);
        self.segment
            .point_chunks
            .iter()
            .enumerate()
            .map(move |(i, r)| {
                let id = chunk_segment_id(layer, part, i).expect("a chunked layer's ids fit");
                (id, r.generation)
            })
    }

    /// Chunk `index` of the column, ready to archive (its points are not copied).
    ///
    /// # Panics
    /// If the layer has no chunk `index`.
    pub fn chunk(&self, index: usize) -> PointChunkSource<'c> {
        let r = self.segment.point_chunks[index];
        let chunk_len = self.segment.point_chunk_len as usize;
        let range = chunk_range(index, self.points.len(), chunk_len);
        PointChunkSource::new(
            LayerId(self.segment.layer),
            self.segment.part,
            index,
            r.generation,
            &self.points[range],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::common_prefix;

    #[test]
    fn the_common_prefix_is_counted_bit_for_bit_across_blocks() {
        let a: Vec<[f32; 3]> = (0..1000).map(|i| [i as f32, 0.0, 1.0]).collect();
        for cut in [0, 1, 255, 256, 257, 999] {
            let mut b = a.clone();
            b[cut][2] = -1.0;
            assert_eq!(common_prefix(&a, &b), cut);
            assert_eq!(common_prefix(&a, &b[..cut]), cut);
        }
        assert_eq!(common_prefix(&a, &a), 1000);
        // -0.0 and 0.0 differ in bits: a changed point, though equal as numbers.
        let mut b = a.clone();
        b[700][1] = -0.0;
        assert_eq!(common_prefix(&a, &b), 700);
    }
}
