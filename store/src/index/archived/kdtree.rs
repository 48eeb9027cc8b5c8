//! kiddo-backed indexes: [`ArchivedIndex`] (kiddo's archived `ImmutableKdTree` inside a
//! snapshot's layer segment, queried in place) and [`KdIndex`] (a tree a reader built,
//! kept in the same archived form).
//!
//! kiddo builds the trees (median splits, Eytzinger stems, leaf arenas) and answers
//! radius queries (`within`). Nearest-node search needs one branch-and-bound pass that
//! knows about nodes and ties (kiddo's `nearest_n(2)` costs 1.8× its `nearest_one` in
//! instructions, and neither breaks ties by node id), so the nearest walk
//! (`crate::index::walk`) reads the archived layout itself through [`ArchivedTreeAccess`]:
//! stems in Eytzinger order (root 1, children `2s` and `2s + 1`, split dimension
//! `level % 3`, above when `c[dim] >= pivot`), leaf `s - 2^levels` at the bottom, leaves
//! as tiles of x's, y's, z's and items. The layout is read through the checked mirror
//! of `super::layout`; the walk indexes only with bounds-checked slices.

#![allow(
    unsafe_code,
    reason = "re-deriving a reader-built tree from the bytes it was archived into"
)]

use super::layout::{ArchivedKdTree, KdTree, layout, tile_widths};
use super::patched_rows::RowPatch;
use crate::bytes::{SegmentBytes, archive};
use crate::index::spatial_index::{SpatialIndex, prefetch};
use crate::index::walk::{self, Cell, KdTreeAccessor, TileVisitor};
use crate::{NodeId, Point};
use kiddo::SquaredEuclidean;
use rkyv::primitive::ArchivedUsize;
use rkyv::tuple::ArchivedTuple2;

/// Radius queries on kiddo trees ask for this much more (relative) and filter exactly:
/// kiddo updates its pruning bound incrementally, which can round a few ulps high.
const WITHIN_MARGIN: f32 = 1e-4;

/// [`nearest_visit`] prefetches stems in trees with at least this many stem levels
/// (64 KiB of stems, from about 260k points); smaller stem arrays stay in cache.
const PREFETCH_MIN_LEVELS: u32 = 14;

/// Builds a [`KdTree`] over `(item, point)` entries.
pub(crate) fn build_tree(entries: &[(u32, Point)]) -> KdTree {
    KdTree::new_from_entries(entries).expect("u32 items are given, none is generated")
}

/// Points within `r2` of `c` through kiddo's `within` query (with a margin, filtered
/// exactly), reporting each point's coordinates.
fn within<F: FnMut(f32, u32, &Point)>(tree: &ArchivedKdTree, c: &Point, r2: f32, mut f: F) {
    if tree.size() == 0 {
        return;
    }
    let wide = r2 * (1.0 + WITHIN_MARGIN) + f32::MIN_POSITIVE;
    tree.query(c)
        .within::<SquaredEuclidean<f32>>(wide)
        .unsorted()
        .with_points()
        .visit(|r| {
            if r.distance <= r2 {
                f(r.distance, r.item, &r.point);
            }
        });
}

/// Read access to the stems and leaves of an archived tree that passed [`check_tree`],
/// for the nearest walk (see the module docs for the layout).
struct ArchivedTreeAccess<'a> {
    stems: &'a [f32],
    extents: &'a [ArchivedTuple2<ArchivedUsize, ArchivedUsize>],
    words: &'a [u32],
    levels: u32,
}

impl<'a> ArchivedTreeAccess<'a> {
    /// The tree's stems and leaves, or `None` for an empty tree (never walked).
    fn new(tree: &'a ArchivedKdTree) -> Option<Self> {
        let l = layout(tree);
        if l.size.to_native() == 0 {
            return None;
        }
        let bytes = l.leaves.leaf_bytes.get();
        // `check_tree` guarantees 128-byte alignment.
        let words = bytemuck::try_cast_slice::<u8, u32>(&bytes[..bytes.len() / 4 * 4]).ok()?;
        Some(ArchivedTreeAccess {
            stems: bytemuck::cast_slice(l.stems.get()),
            extents: l.leaves.leaf_extents.as_slice(),
            words,
            levels: (l.max_stem_level.to_native() + 1).max(0) as u32,
        })
    }
}

/// Nodes are `(stem index, level)`; at the bottom level, `(leaf index, level)`.
impl KdTreeAccessor for ArchivedTreeAccess<'_> {
    type Node = (usize, u32);

    #[inline]
    fn root(&self) -> Option<(usize, u32)> {
        Some((1, 0))
    }

    #[inline]
    fn cell(&self, (s, level): (usize, u32)) -> Cell<(usize, u32)> {
        if level >= self.levels {
            return Cell::Leaf((s - (1 << self.levels), level));
        }
        Cell::Inner {
            dim: (level % 3) as usize,
            split: self.stems[s],
            below: (2 * s, level + 1),
            above: (2 * s + 1, level + 1),
        }
    }

    /// Eytzinger order puts the children of `s` at `2s`, `2s + 1` and its 16
    /// descendants four levels down at `16s..16s + 16` (one cache line of stems): ask
    /// for both, as kiddo's own descent does, so that the loads of the levels below
    /// overlap this one's (at 10M points this took the walk from 1.3× to 1.0× kiddo's
    /// `nearest_one`). Small trees sit in cache, where the hints would only cost
    /// instructions.
    #[inline]
    fn descending_into(&self, (s, _): (usize, u32)) {
        if self.levels >= PREFETCH_MIN_LEVELS {
            let stems = self.stems.as_ptr();
            prefetch(stems.wrapping_add(s.wrapping_mul(2)));
            prefetch(stems.wrapping_add(s.wrapping_mul(16)));
        }
    }

    /// The leaf's tiles, widest first (see `tile_widths`).
    #[inline]
    fn visit_leaf<V: TileVisitor>(&self, (leaf, _): (usize, u32), visitor: &mut V) {
        let e = &self.extents[leaf];
        let (start, len) = (e.0.to_native() as usize / 4, e.1.to_native() as usize);
        let Some(mut rest) = self.words.get(start..start + 4 * len) else {
            return; // `check_tree` keeps every extent inside the arena
        };
        for w in tile_widths(len) {
            let (tile, tail) = rest.split_at(4 * w);
            match w {
                32 => visit_tile::<32, V>(tile, visitor),
                8 => visit_tile::<8, V>(tile, visitor),
                4 => visit_tile::<4, V>(tile, visitor),
                2 => visit_tile::<2, V>(tile, visitor),
                _ => visit_tile::<1, V>(tile, visitor),
            }
            rest = tail;
        }
    }
}

/// One tile of `W` points (`W` x's, `W` y's, `W` z's, `W` items) passed to `visitor`.
#[inline]
fn visit_tile<const W: usize, V: TileVisitor>(tile: &[u32], visitor: &mut V) {
    let coords: &[f32] = bytemuck::cast_slice(tile);
    let coord = |i: usize| -> Option<&[f32; W]> { coords.get(i * W..(i + 1) * W)?.try_into().ok() };
    let items = tile
        .get(3 * W..4 * W)
        .and_then(|s| <&[u32; W]>::try_from(s).ok());
    if let (Some(xs), Some(ys), Some(zs), Some(items)) = (coord(0), coord(1), coord(2), items) {
        visitor.tile(xs, ys, zs, items, W);
    }
}

/// A kd-tree index a reader built from any [`crate::SceneView`] (see
/// [`crate::index::build_layer_index`]): kiddo's tree, kept archived (the form snapshot indexes
/// have, so one search serves both), and the node of each item.
pub struct KdIndex {
    bytes: SegmentBytes,
    ids: Vec<NodeId>,
}

impl std::fmt::Debug for KdIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("KdIndex")
            .field("points", &self.len())
            .field("nodes", &self.ids.len())
            .field("bytes", &self.bytes.len())
            .finish()
    }
}

impl KdIndex {
    pub(crate) fn new(tree: &KdTree, ids: Vec<NodeId>) -> Self {
        KdIndex {
            bytes: archive(tree),
            ids,
        }
    }

    fn index(&self) -> ArchivedIndex<'_> {
        // SAFETY: `bytes` is exactly what rkyv wrote when serializing a `KdTree` in
        // `KdIndex::new`, with the root at the end, and is never modified afterwards; the
        // buffer is 128-byte aligned (`SegmentBytes`), as kiddo's archived leaves need.
        // Items are positions in `ids` by construction, which `ArchivedIndex` relies on.
        let tree = unsafe { rkyv::access_unchecked::<ArchivedKdTree>(&self.bytes) };
        ArchivedIndex::new(tree, bytemuck::cast_slice(&self.ids))
    }
}

impl SpatialIndex for KdIndex {
    fn len(&self) -> usize {
        self.index().len()
    }

    fn node_of(&self, item: u32) -> Option<NodeId> {
        self.ids.get(item as usize).copied()
    }

    fn prefetch_node(&self, item: u32) {
        prefetch(self.ids.as_ptr().wrapping_add(item as usize));
    }

    fn nearest_visit<F: FnMut(f32, u32) -> f32>(&self, c: &Point, f: F) {
        self.index().nearest_visit(c, f);
    }

    fn points_within<F: FnMut(f32, u32, &Point)>(&self, c: &Point, r2: f32, f: F) {
        self.index().points_within(c, r2, f);
    }

    fn memory_bytes(&self) -> usize {
        self.bytes.len() + self.ids.capacity() * 8
    }
}

/// A kd-tree index inside a validated snapshot, queried in place (zero-copy): kiddo's
/// archived tree and the node ids its items refer to. A layer index may carry a patch:
/// the rows changed since its tree was built.
#[derive(Clone, Copy)]
pub struct ArchivedIndex<'a> {
    tree: &'a ArchivedKdTree,
    ids: &'a [u64],
    patch: Option<RowPatch<'a>>,
}

impl<'a> ArchivedIndex<'a> {
    /// # Invariant
    /// `tree` passed [`check_tree`] with an item bound of at most `ids.len()`.
    pub(crate) fn new(tree: &'a ArchivedKdTree, ids: &'a [u64]) -> Self {
        ArchivedIndex {
            tree,
            ids,
            patch: None,
        }
    }

    /// A layer index: `tree` over rows as they were, patched by `patch`.
    ///
    /// # Invariant
    /// `tree` passed [`check_tree`] with the patch's base row count as item bound;
    /// `ids` are the layer's ids (one per row).
    pub(crate) fn patched(tree: &'a ArchivedKdTree, ids: &'a [u64], patch: RowPatch<'a>) -> Self {
        ArchivedIndex {
            tree,
            ids,
            patch: (!patch.is_clean()).then_some(patch),
        }
    }
}

impl std::fmt::Debug for ArchivedIndex<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ArchivedIndex")
            .field("points", &self.len())
            .field("nodes", &self.ids.len())
            .finish()
    }
}

impl SpatialIndex for ArchivedIndex<'_> {
    fn len(&self) -> usize {
        self.patch.map_or(self.tree.size(), |p| p.len())
    }

    fn node_of(&self, item: u32) -> Option<NodeId> {
        self.ids.get(item as usize).map(|&id| NodeId(id))
    }

    fn prefetch_node(&self, item: u32) {
        prefetch(self.ids.as_ptr().wrapping_add(item as usize));
    }

    /// The base tree's live entries, nearer cells first, then the patched rows' points.
    fn nearest_visit<F: FnMut(f32, u32) -> f32>(&self, c: &Point, mut f: F) {
        let access = ArchivedTreeAccess::new(self.tree);
        let Some(patch) = self.patch else {
            if let Some(access) = access {
                walk::nearest_visit(&access, c, f);
            }
            return;
        };
        let mut bound = f32::INFINITY;
        if let Some(access) = access {
            walk::nearest_visit(&access, c, |d2, item| {
                if !patch.is_dead(item) {
                    bound = f(d2, item);
                }
                bound
            });
        }
        patch.nearest_visit(c, bound, &mut f);
    }

    fn points_within<F: FnMut(f32, u32, &Point)>(&self, c: &Point, r2: f32, mut f: F) {
        match self.patch {
            None => within(self.tree, c, r2, f),
            Some(patch) => {
                within(self.tree, c, r2, |d2, item, p| {
                    if !patch.is_dead(item) {
                        f(d2, item, p);
                    }
                });
                patch.within(c, r2, &mut f);
            }
        }
    }

    fn memory_bytes(&self) -> usize {
        let l = layout(self.tree);
        std::mem::size_of::<ArchivedKdTree>()
            + l.stems.get().len() * 4
            + l.leaves.leaf_extents.len()
                * std::mem::size_of::<ArchivedTuple2<ArchivedUsize, ArchivedUsize>>()
            + l.leaves.leaf_bytes.get().len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distance_squared;
    use crate::index::check_tree;
    use rand::{Rng, SeedableRng};

    /// The nearest walk over an archived tree.
    fn nearest_visit(tree: &ArchivedKdTree, c: &Point, f: impl FnMut(f32, u32) -> f32) {
        if let Some(access) = ArchivedTreeAccess::new(tree) {
            walk::nearest_visit(&access, c, f);
        }
    }

    /// Every point with its squared distance, through `nearest_visit` with no pruning.
    fn visit_all(tree: &ArchivedKdTree, c: &Point) -> Vec<(u32, u32)> {
        let mut v = Vec::new();
        nearest_visit(tree, c, |d2, item| {
            v.push((item, d2.to_bits()));
            f32::INFINITY
        });
        v.sort_unstable();
        v
    }

    fn random_entries(n: usize, seed: u64) -> Vec<(u32, Point)> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        (0..n)
            .map(|i| {
                let p = [
                    rng.gen_range(-50.0..50.0),
                    rng.gen_range(-50.0..50.0),
                    rng.gen_range(-5.0..5.0),
                ];
                (i as u32, p)
            })
            .collect()
    }

    /// Decodes every leaf through the mirror, as `check_tree` reads it.
    fn decode(tree: &ArchivedKdTree) -> Vec<(u32, [u32; 3])> {
        let l = layout(tree);
        let bytes = l.leaves.leaf_bytes.get();
        let mut out = Vec::new();
        for e in l.leaves.leaf_extents.iter() {
            let (mut off, len) = (e.0.to_native() as usize, e.1.to_native() as usize);
            for w in tile_widths(len) {
                let word = |i: usize| {
                    u32::from_le_bytes(bytes[off + 4 * i..off + 4 * i + 4].try_into().unwrap())
                };
                for j in 0..w {
                    out.push((word(3 * w + j), [word(j), word(w + j), word(2 * w + j)]));
                }
                off += 16 * w;
            }
        }
        out.sort_unstable();
        out
    }

    #[test]
    fn layout_mirror_reads_what_kiddo_reads() {
        for n in [1, 2, 31, 32, 33, 100, 1000, 4097] {
            let tree = build_tree(&random_entries(n, n as u64));
            let bytes = archive(&tree);
            let archived = rkyv::access::<ArchivedKdTree, rkyv::rancor::Error>(&bytes).unwrap();
            let l = layout(archived);
            assert_eq!(l.size.to_native() as usize, archived.size());
            assert_eq!(l.max_stem_level.to_native(), archived.max_stem_level());
            assert_eq!(l.max_leaf_len.to_native() as usize, archived.max_leaf_len());
            assert_eq!(l.leaves.leaf_extents.len(), archived.leaf_count());
            assert_eq!(l.resolution.tag, 0);
            assert_eq!(
                l.resolution.leaf_count.to_native() as usize,
                archived.leaf_count()
            );
            let mut expected: Vec<(u32, [u32; 3])> = archived
                .iter()
                .map(|(item, p)| (item, p.map(f32::to_bits)))
                .collect();
            expected.sort_unstable();
            assert_eq!(decode(archived), expected);
            check_tree(archived, n).unwrap();
            assert!(
                check_tree(archived, n - 1).is_err(),
                "item bound is enforced"
            );
        }
    }

    #[test]
    fn walk_and_kiddo_within_report_distance_squared_bit_for_bit() {
        for n in [1, 7, 32, 33, 500, 5000] {
            let entries = random_entries(n, 9);
            let bytes = archive(&build_tree(&entries));
            let tree = rkyv::access::<ArchivedKdTree, rkyv::rancor::Error>(&bytes).unwrap();
            check_tree(tree, n).unwrap();
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(10);
            for _ in 0..50 {
                let c = [
                    rng.gen_range(-60.0..60.0),
                    rng.gen_range(-60.0..60.0),
                    rng.gen_range(-9.0..9.0),
                ];
                let mut all: Vec<(u32, u32)> = entries
                    .iter()
                    .map(|(i, p)| (*i, distance_squared(p, &c).to_bits()))
                    .collect();
                all.sort_unstable();
                assert_eq!(visit_all(tree, &c), all);
                // A pruned walk finds the nearest point (ties to the smaller item).
                let mut best = (f32::INFINITY, u32::MAX);
                nearest_visit(tree, &c, |d2, item| {
                    if (d2, item) < best {
                        best = (d2, item);
                    }
                    best.0
                });
                let want = entries
                    .iter()
                    .map(|(i, p)| (distance_squared(p, &c), *i))
                    .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
                    .unwrap();
                assert_eq!(best, want);
                let mut found = Vec::new();
                within(tree, &c, 30.0, |d, item, p| {
                    assert_eq!(*p, entries[item as usize].1);
                    found.push((item, d.to_bits()));
                });
                found.sort_unstable();
                let want: Vec<(u32, u32)> = all
                    .iter()
                    .copied()
                    .filter(|&(_, d)| f32::from_bits(d) <= 30.0)
                    .collect();
                assert_eq!(found, want);
            }
        }
    }

    #[test]
    fn corrupted_trees_are_rejected_or_safe() {
        let tree = build_tree(&random_entries(3000, 4));
        let clean = archive(&tree);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (mut rejected, mut queried) = (0, 0);
        for _ in 0..3000 {
            let mut bytes = clean.clone();
            for _ in 0..rng.gen_range(1..4) {
                let at = rng.gen_range(0..bytes.len());
                bytes[at] ^= 1 << rng.gen_range(0..8);
            }
            let Ok(archived) = rkyv::access::<ArchivedKdTree, rkyv::rancor::Error>(&bytes) else {
                rejected += 1;
                continue;
            };
            if check_tree(archived, 3000).is_err() {
                rejected += 1;
                continue;
            }
            queried += 1;
            nearest_visit(archived, &[0.0, 0.0, 0.0], |_, item| {
                assert!(item < 3000);
                f32::INFINITY
            });
            within(archived, &[1.0, 2.0, 0.0], 100.0, |_, item, _| {
                assert!(item < 3000)
            });
        }
        assert!(
            rejected > 0 && queried > 0,
            "{rejected} rejected, {queried} queried"
        );
    }
}
