//! kiddo-backed indexes: [`ArchivedIndex`] (kiddo's archived `ImmutableKdTree` inside a
//! snapshot's layer segment, queried in place) and [`KdIndex`] (a tree a reader built,
//! kept in the same archived form), plus [`check_tree`], the checks that make an
//! archived tree from untrusted bytes safe to query.
//!
//! kiddo builds the trees (median splits, Eytzinger stems, leaf arenas) and answers
//! radius queries (`within`). Nearest-node search needs one branch-and-bound pass that
//! knows about nodes and ties (kiddo's `nearest_n(2)` costs 1.8× its `nearest_one` in
//! instructions, and neither breaks ties by node id), so [`nearest_visit`] walks the
//! archived layout itself: stems in Eytzinger order (root 1, children `2s` and
//! `2s + 1`, split dimension `level % 3`, right when `c[dim] >= pivot`), leaf
//! `s - 2^levels` at the bottom, leaves as tiles of x's, y's, z's and items.
//!
//! # Safety of archived trees
//! rkyv's bytecheck validates an archived kiddo tree's *structure*: every relative
//! pointer and length stays inside the buffer, buffers are 128-byte aligned, the
//! stem/leaf resolution enum has a known tag. kiddo's queries also rely on facts that
//! bytecheck cannot see: the stem array covers every level the traversal descends, each
//! leaf extent lies inside the leaf arena (leaves are read through raw pointers), the
//! arithmetic leaf index stays below the leaf count (kiddo panics otherwise), and no
//! distance is NaN (kiddo sorts results with a comparator that treats NaN as equal,
//! which a sort may reject with a panic). [`check_tree`] reads those fields through
//! `TreeLayout`, a `#[repr(C)]` mirror of kiddo 6.3's archived layout (pinned by a size
//! assertion and by `layout_mirror_reads_what_kiddo_reads`), and checks them once per
//! segment; it also checks that every item is in range. The pass reads the leaf arena
//! once (16 bytes per point). [`nearest_visit`] indexes only with bounds-checked slices.

#![allow(
    unsafe_code,
    reason = "reading the fields of a validated archived kiddo tree through a layout mirror"
)]

use super::SpatialIndex;
use crate::snapshot::SegmentBytes;
use crate::{NodeId, Point};
use kiddo::leaf_strategy::VecOfArenas;
use kiddo::{Eytzinger, ImmutableKdTree, SquaredEuclidean};
use rkyv::boxed::ArchivedBox;
use rkyv::primitive::{ArchivedI32, ArchivedUsize};
use rkyv::rend::f32_le;
use rkyv::tuple::ArchivedTuple2;
use rkyv::vec::ArchivedVec;

/// The kd-tree of archived and reader-built indexes: kiddo's `ImmutableKdTree` over
/// `f32` points in 3-D with `u32` items.
pub type KdTree = ImmutableKdTree<f32, 3>;

/// kiddo's archived form of [`KdTree`], queried in place.
pub type ArchivedKdTree =
    kiddo::kd_tree::ArchivedKdTree<f32, u32, Eytzinger, VecOfArenas<f32, u32, 3, 32>, 3, 32>;

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

/// Branch-and-bound nearest search over a tree that passed [`check_tree`] (see
/// [`SpatialIndex::nearest_visit`]): nearer cells first, cells farther than the bound
/// skipped, pruning bounds evaluated like [`distance_squared`] so that they never
/// exceed the distance of a point they prune.
pub(crate) fn nearest_visit<F: FnMut(f32, u32) -> f32>(tree: &ArchivedKdTree, c: &Point, f: F) {
    let l = layout(tree);
    if l.size.to_native() == 0 {
        return;
    }
    let bytes = l.leaves.leaf_bytes.get();
    let Ok(words) = bytemuck::try_cast_slice::<u8, u32>(&bytes[..bytes.len() / 4 * 4]) else {
        return; // `check_tree` guarantees 128-byte alignment
    };
    let mut walk = Walk {
        stems: bytemuck::cast_slice(l.stems.get()),
        extents: l.leaves.leaf_extents.as_slice(),
        words,
        levels: (l.max_stem_level.to_native() + 1).max(0) as u32,
        c,
        bound: f32::INFINITY,
        f,
    };
    walk.descend(1, 0, [0.0; 3]);
}

struct Walk<'a, F> {
    stems: &'a [f32],
    extents: &'a [ArchivedTuple2<ArchivedUsize, ArchivedUsize>],
    words: &'a [u32],
    levels: u32,
    c: &'a Point,
    bound: f32,
    f: F,
}

impl<F: FnMut(f32, u32) -> f32> Walk<'_, F> {
    /// Depth-first from stem `s` at `level` (cell offsets `off` from the query), nearer
    /// child first; the farther child only if its cell is within the bound by then.
    /// Recursion (at most 31 deep: `check_tree` bounds the levels by 30) costs less than
    /// an explicit stack here: no far cell is stored that the bound later prunes.
    fn descend(&mut self, s: usize, level: u32, off: [f32; 3]) {
        if level >= self.levels {
            self.leaf(s - (1 << self.levels));
            return;
        }
        let dim = (level % 3) as usize;
        let delta = self.c[dim] - self.stems[s];
        let right = usize::from(delta >= 0.0);
        let near = 2 * s + right;
        // Eytzinger order puts the children of `near` at `2 near`, `2 near + 1` and its 16
        // descendants four levels down at `16 near..16 near + 16` (one cache line of
        // stems): ask for both now, as kiddo's own descent does, so that the loads of the
        // levels below overlap this one's (at 10M points this took the walk from 1.3× to
        // 1.0× kiddo's `nearest_one`). Small trees sit in cache, where the hints would
        // only cost instructions.
        if self.levels >= PREFETCH_MIN_LEVELS {
            let stems = self.stems.as_ptr();
            super::prefetch(stems.wrapping_add(near.wrapping_mul(2)));
            super::prefetch(stems.wrapping_add(near.wrapping_mul(16)));
        }
        self.descend(near, level + 1, off);
        let mut far_off = off;
        far_off[dim] = delta.abs();
        if super::live::cell_distance_squared(&far_off) <= self.bound {
            self.descend(near ^ 1, level + 1, far_off);
        }
    }

    fn leaf(&mut self, leaf: usize) {
        let e = &self.extents[leaf];
        let (start, len) = (e.0.to_native() as usize / 4, e.1.to_native() as usize);
        let Some(mut rest) = self.words.get(start..start + 4 * len) else {
            return; // `check_tree` keeps every extent inside the arena
        };
        let mut remaining = len;
        while remaining > 0 {
            let w = TILE_WIDTHS
                .into_iter()
                .find(|&w| remaining >= w)
                .expect("width 1 fits any remaining > 0");
            let (tile, tail) = rest.split_at(4 * w);
            match w {
                32 => self.tile::<32>(tile),
                8 => self.tile::<8>(tile),
                4 => self.tile::<4>(tile),
                2 => self.tile::<2>(tile),
                _ => self.tile::<1>(tile),
            }
            rest = tail;
            remaining -= w;
        }
    }

    /// One tile of `W` points: `W` x's, `W` y's, `W` z's, `W` items (fixed width, so the
    /// distance loop vectorises).
    #[inline]
    fn tile<const W: usize>(&mut self, tile: &[u32]) {
        let word =
            |i: usize| -> Option<&[u32; W]> { tile.get(i * W..(i + 1) * W)?.try_into().ok() };
        let (Some(xs), Some(ys), Some(zs), Some(items)) = (word(0), word(1), word(2), word(3))
        else {
            return;
        };
        let c = *self.c;
        // The same expression as `distance_squared`, for the whole tile.
        let mut d = [0.0f32; W];
        for i in 0..W {
            let dx = f32::from_bits(xs[i]) - c[0];
            let dy = f32::from_bits(ys[i]) - c[1];
            let dz = f32::from_bits(zs[i]) - c[2];
            d[i] = dx * dx + dy * dy + dz * dz;
        }
        let bound = self.bound;
        if d.iter().fold(false, |hit, &x| hit | (x <= bound)) {
            for i in 0..W {
                if d[i] <= self.bound {
                    self.bound = (self.f)(d[i], items[i]);
                }
            }
        }
    }
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

/// A kd-tree index a reader built from any [`crate::SceneView`] (see
/// [`super::build_layer_index`]): kiddo's tree, kept archived (the form snapshot indexes
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
        let bytes =
            rkyv::api::high::to_bytes_in::<_, rkyv::rancor::Error>(tree, SegmentBytes::new())
                .expect("serializing a kd-tree into memory cannot fail");
        KdIndex { bytes, ids }
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
        super::prefetch(self.ids.as_ptr().wrapping_add(item as usize));
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
/// archived tree and the node ids its items refer to.
#[derive(Clone, Copy)]
pub struct ArchivedIndex<'a> {
    tree: &'a ArchivedKdTree,
    ids: &'a [u64],
}

impl<'a> ArchivedIndex<'a> {
    /// # Invariant
    /// `tree` passed [`check_tree`] with an item bound of at most `ids.len()`.
    pub(crate) fn new(tree: &'a ArchivedKdTree, ids: &'a [u64]) -> Self {
        ArchivedIndex { tree, ids }
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
        self.tree.size()
    }

    fn node_of(&self, item: u32) -> Option<NodeId> {
        self.ids.get(item as usize).map(|&id| NodeId(id))
    }

    fn prefetch_node(&self, item: u32) {
        super::prefetch(self.ids.as_ptr().wrapping_add(item as usize));
    }

    fn nearest_visit<F: FnMut(f32, u32) -> f32>(&self, c: &Point, f: F) {
        nearest_visit(self.tree, c, f);
    }

    fn points_within<F: FnMut(f32, u32, &Point)>(&self, c: &Point, r2: f32, f: F) {
        within(self.tree, c, r2, f);
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

// ---- validation ----------------------------------------------------------------------

/// kiddo 6.3's archived `VecOfArenas<f32, u32, 3, 32>`, field for field.
#[repr(C)]
struct ArenasLayout {
    leaf_extents: ArchivedVec<ArchivedTuple2<ArchivedUsize, ArchivedUsize>>,
    leaf_bytes: ArchivedBox<[u8]>,
    size: ArchivedUsize,
}

/// kiddo 6.3's archived `OwnedStemLeafResolution`: a `repr(u8)` enum, laid out as a tag
/// followed by the variant's fields. Tag 0 is `Arithmetic { stems_depth, leaf_count }`;
/// the largest variant, `Mapped { usize, Vec<usize> }`, sets the size.
#[repr(C)]
struct ResolutionLayout {
    tag: u8,
    stems_depth: ArchivedUsize,
    leaf_count: ArchivedUsize,
    _mapped_tail: ArchivedUsize,
}

/// kiddo 6.3's archived `KdTree<f32, u32, Eytzinger, VecOfArenas<..>, 3, 32>`, field for
/// field (`AlignedArchiveSlice<[T]>` has the layout and metadata of `[T]`).
#[repr(C)]
struct TreeLayout {
    stems: ArchivedBox<[f32_le]>,
    leaves: ArenasLayout,
    resolution: ResolutionLayout,
    size: ArchivedUsize,
    max_stem_level: ArchivedI32,
    max_leaf_len: ArchivedUsize,
}

const _: () = assert!(
    std::mem::size_of::<TreeLayout>() == std::mem::size_of::<ArchivedKdTree>()
        && std::mem::align_of::<TreeLayout>() == std::mem::align_of::<ArchivedKdTree>()
);

/// The archived tree's fields, read through the layout mirror.
fn layout(tree: &ArchivedKdTree) -> &TreeLayout {
    // SAFETY: `TreeLayout` declares the fields of kiddo 6.3's archived tree in order,
    // with the same archived field types (rkyv derives `#[repr(C)]` archived structs,
    // and a `repr(u8)` enum is a tag followed by the variant's `repr(C)` fields); sizes
    // and alignments are asserted equal above, and `layout_mirror_reads_what_kiddo_reads`
    // checks the fields read here against kiddo's own accessors. Every `ArchivedKdTree`
    // reference we hold points into bytes that bytecheck validated, so each mirrored
    // field holds a valid value (relative pointers in bounds, initialised integers).
    unsafe { &*(tree as *const ArchivedKdTree).cast::<TreeLayout>() }
}

/// Leaf tiles, widest first, as kiddo's `VecOfArenas` encodes a leaf: each tile of width
/// `w` holds `w` x's, `w` y's, `w` z's, then `w` items (16 bytes per point).
const TILE_WIDTHS: [usize; 5] = [32, 8, 4, 2, 1];

/// Checks what kiddo's queries rely on and bytecheck does not verify (see the module
/// docs), and that every item is below `items`. Linear in the number of points.
///
/// # Errors
/// A description of the first problem.
pub(crate) fn check_tree(tree: &ArchivedKdTree, items: usize) -> Result<(), String> {
    let l = layout(tree);
    let size = l.size.to_native() as usize;
    if size == 0 {
        return Ok(()); // never queried: every query returns at once on an empty tree
    }
    if l.resolution.tag != 0 {
        return Err("kd-tree leaf resolution is not arithmetic".into());
    }
    let depth = l.resolution.stems_depth.to_native() as usize;
    let leaf_count = l.resolution.leaf_count.to_native() as usize;
    let extents = l.leaves.leaf_extents.as_slice();
    if depth > 30
        || leaf_count != 1 << depth
        || extents.len() != leaf_count
        || !(-1..depth as i32).contains(&l.max_stem_level.to_native())
    {
        return Err(format!(
            "kd-tree shape: depth {depth}, {leaf_count} leaves, {} extents, max stem level {}",
            extents.len(),
            l.max_stem_level.to_native()
        ));
    }
    // Levels 0..=max_stem_level are read, at stem indices below 2^(max_stem_level + 1).
    let stem_levels = (l.max_stem_level.to_native() + 1) as u32;
    let stems = l.stems.get();
    let bytes = l.leaves.leaf_bytes.get();
    let misaligned = |len: usize, ptr: usize| len > 0 && !ptr.is_multiple_of(128);
    if stems.len() < (1usize << stem_levels) - usize::from(stem_levels == 0)
        || misaligned(stems.len(), stems.as_ptr() as usize)
        || misaligned(bytes.len(), bytes.as_ptr() as usize)
    {
        return Err("kd-tree stems too short or buffers misaligned".into());
    }
    if l.leaves.size.to_native() as usize != size {
        return Err("kd-tree leaf size differs from tree size".into());
    }
    let max_leaf = l.max_leaf_len.to_native() as usize;
    let mut total = 0usize;
    for e in extents {
        let (off, len) = (e.0.to_native() as usize, e.1.to_native() as usize);
        let end = len.checked_mul(16).and_then(|n| n.checked_add(off));
        if off % 4 != 0 || len > max_leaf || end.is_none_or(|end| end > bytes.len()) {
            return Err(format!("kd-tree leaf extent {off}+{len} out of bounds"));
        }
        total += len;
        check_leaf(&bytes[off..off + 16 * len], len, items)?;
    }
    if total != size {
        return Err(format!(
            "kd-tree leaves hold {total} points, size says {size}"
        ));
    }
    Ok(())
}

fn check_leaf(mut bytes: &[u8], len: usize, items: usize) -> Result<(), String> {
    let mut remaining = len;
    while remaining > 0 {
        let w = TILE_WIDTHS
            .into_iter()
            .find(|&w| remaining >= w)
            .expect("width 1 fits any remaining > 0");
        let (coords, rest) = bytes.split_at(12 * w);
        let (item_bytes, rest) = rest.split_at(4 * w);
        if coords
            .chunks_exact(4)
            .any(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]).is_nan())
        {
            return Err("kd-tree leaf holds a NaN coordinate".into());
        }
        if item_bytes
            .chunks_exact(4)
            .any(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as usize >= items)
        {
            return Err(format!(
                "kd-tree leaf holds an item out of range (< {items})"
            ));
        }
        bytes = rest;
        remaining -= w;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distance_squared;
    use rand::{Rng, SeedableRng};

    fn archive(tree: &KdTree) -> SegmentBytes {
        rkyv::api::high::to_bytes_in::<_, rkyv::rancor::Error>(tree, SegmentBytes::new()).unwrap()
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
            let (mut off, mut remaining) = (e.0.to_native() as usize, e.1.to_native() as usize);
            while remaining > 0 {
                let w = TILE_WIDTHS.into_iter().find(|&w| remaining >= w).unwrap();
                let word = |i: usize| {
                    u32::from_le_bytes(bytes[off + 4 * i..off + 4 * i + 4].try_into().unwrap())
                };
                for j in 0..w {
                    out.push((word(3 * w + j), [word(j), word(w + j), word(2 * w + j)]));
                }
                off += 16 * w;
                remaining -= w;
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
