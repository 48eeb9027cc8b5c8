//! [`LiveKdTree`]: the dynamic kd-tree behind the live graph's layer and node indexes.
//!
//! kiddo's `MutableKdTree` cannot hold more than a bucket of points that share a
//! coordinate on the dimension a full bucket must split on (an axis-aligned wall, or
//! duplicate points): its `add` then fails. This tree stores the same `(point, item)`
//! multiset but always splits a full leaf on its widest dimension, keeps points that are
//! identical in every dimension in a chain of leaves, and keeps depth logarithmic like a
//! scapegoat tree: an insert that lands deeper than [`depth_limit`] rebuilds the highest
//! unbalanced sub-tree on its path, and the whole tree is rebuilt when it has halved.
//! Every insert and remove succeeds; splits and rebuilds are amortised O(log n).
//!
//! # Invariants
//! - An entry lives in the leaf reached by descending with its point, going left at an
//!   inner node exactly when `point[dim] < split`.
//! - Every leaf but the root holds at least one entry; chained leaves (`next`) hold
//!   entries whose points are all equal.
//!
//! Distances are [`crate::distance_squared`] bit for bit, and pruning bounds are
//! computed so that they never exceed the distance of any entry they prune (see
//! [`cell_distance_squared`]), so queries are exact.

use crate::Point;
use std::cmp::Ordering;

/// Maximum entries in one leaf.
pub(crate) const LEAF_CAP: usize = 32;
/// Entries per leaf after a bulk build: room for a few inserts before a leaf splits.
const BULK_FILL: usize = 28;
const NONE: u32 = u32::MAX;
const LEAF_BIT: u32 = 1 << 31;
/// Scapegoat balance: when an insert lands deeper than [`depth_limit`], the highest
/// node on its path with more than 3/4 of its entries on one side is rebuilt.
const BALANCE: (u64, u64) = (3, 4);

/// A depth a tree of `n` entries with no unbalanced node cannot exceed:
/// `log_{4/3}(n) + 2` (2.5 × the bit length of `n` is at least `log_{4/3}(n)`).
fn depth_limit(n: usize) -> usize {
    (usize::BITS - n.max(1).leading_zeros()) as usize * 5 / 2 + 2
}

/// One `(point, item)` pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Entry {
    pub(crate) p: Point,
    pub(crate) item: u32,
}

#[derive(Clone, Debug)]
struct Leaf {
    len: u32,
    /// Next leaf of a chain of identical points, or the next free leaf.
    next: u32,
    xs: [f32; LEAF_CAP],
    ys: [f32; LEAF_CAP],
    zs: [f32; LEAF_CAP],
    items: [u32; LEAF_CAP],
}

impl Leaf {
    const EMPTY: Leaf = Leaf {
        len: 0,
        next: NONE,
        xs: [0.0; LEAF_CAP],
        ys: [0.0; LEAF_CAP],
        zs: [0.0; LEAF_CAP],
        items: [0; LEAF_CAP],
    };

    fn point(&self, i: usize) -> Point {
        [self.xs[i], self.ys[i], self.zs[i]]
    }

    fn push(&mut self, e: Entry) {
        let i = self.len as usize;
        self.xs[i] = e.p[0];
        self.ys[i] = e.p[1];
        self.zs[i] = e.p[2];
        self.items[i] = e.item;
        self.len += 1;
    }

    fn entry(&self, i: usize) -> Entry {
        Entry {
            p: self.point(i),
            item: self.items[i],
        }
    }

    fn set(&mut self, i: usize, e: Entry) {
        self.xs[i] = e.p[0];
        self.ys[i] = e.p[1];
        self.zs[i] = e.p[2];
        self.items[i] = e.item;
    }

    /// Squared distances from `c` to every slot (slots past `len` hold stale values).
    #[inline]
    fn distances(&self, c: &Point) -> [f32; LEAF_CAP] {
        let mut d = [0.0f32; LEAF_CAP];
        for (i, di) in d.iter_mut().enumerate() {
            let dx = self.xs[i] - c[0];
            let dy = self.ys[i] - c[1];
            let dz = self.zs[i] - c[2];
            *di = dx * dx + dy * dy + dz * dz;
        }
        d
    }
}

#[derive(Clone, Copy, Debug)]
struct Inner {
    split: f32,
    dim: u32,
    left: u32,
    right: u32,
}

/// A dynamic kd-tree over `(point, item)` entries (a multiset: duplicates allowed).
#[derive(Clone, Debug)]
pub struct LiveKdTree {
    leaves: Vec<Leaf>,
    inners: Vec<Inner>,
    free_leaves: u32,
    free_inners: Vec<u32>,
    root: u32,
    len: usize,
    /// The most entries since the last full rebuild (removals shrink sub-trees without
    /// making them deeper; the whole tree is rebuilt when it halves).
    peak: usize,
    path: Vec<u32>,
    /// Changes whenever a node is allocated, freed or relinked: a [`Located`] found
    /// under one `shape` stays exact while `shape` does.
    shape: u64,
}

/// Where a point descends to in a [`LiveKdTree`]: the head of its leaf chain and the
/// depth of that leaf. Exact only while the tree's `shape` is unchanged.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Located {
    leaf: u32,
    depth: u32,
}

impl Default for LiveKdTree {
    fn default() -> Self {
        LiveKdTree {
            leaves: vec![Leaf::EMPTY],
            inners: Vec::new(),
            free_leaves: NONE,
            free_inners: Vec::new(),
            root: LEAF_BIT,
            len: 0,
            peak: 0,
            path: Vec::new(),
            shape: 0,
        }
    }
}

fn is_leaf(r: u32) -> bool {
    r & LEAF_BIT != 0
}

fn leaf_index(r: u32) -> usize {
    (r & !LEAF_BIT) as usize
}

/// `((o0² + o1²) + o2²)`: evaluated like [`distance_squared`], so for any point whose
/// per-axis offsets from the query are at least `off` (a point in the cell), the result
/// is at most that point's distance (rounding is monotone).
#[inline]
pub(crate) fn cell_distance_squared(off: &[f32; 3]) -> f32 {
    off[0] * off[0] + off[1] * off[1] + off[2] * off[2]
}

/// Orders coordinates (`-0.0` before `0.0`, which `<` treats as equal: fine for
/// selection, since both land on the same side of a `<` split).
fn cmp_axis(a: f32, b: f32) -> Ordering {
    a.total_cmp(&b)
}

/// Moves entries satisfying `pred` to the front; returns how many there are.
fn partition(entries: &mut [Entry], pred: impl Fn(&Entry) -> bool) -> usize {
    let mut i = 0;
    for j in 0..entries.len() {
        if pred(&entries[j]) {
            entries.swap(i, j);
            i += 1;
        }
    }
    i
}

impl LiveKdTree {
    /// An empty tree.
    pub fn new() -> Self {
        Self::default()
    }

    /// A balanced tree over `entries`.
    pub(crate) fn from_entries(mut entries: Vec<Entry>) -> Self {
        let mut t = LiveKdTree {
            len: entries.len(),
            peak: entries.len(),
            ..LiveKdTree::default()
        };
        let leaves = entries.len().div_ceil(BULK_FILL);
        t.leaves.reserve_exact(leaves);
        t.inners.reserve_exact(leaves);
        t.free_leaf(0);
        t.root = t.build(&mut entries);
        t
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the tree holds no entry.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Bytes held by the tree's storage (leaves, inner nodes, free lists).
    pub fn memory_bytes(&self) -> usize {
        self.leaves.capacity() * std::mem::size_of::<Leaf>()
            + self.inners.capacity() * std::mem::size_of::<Inner>()
            + self.free_inners.capacity() * 4
            + self.path.capacity() * 4
    }

    // ---- allocation -------------------------------------------------------------------

    fn alloc_leaf(&mut self) -> u32 {
        self.shape = self.shape.wrapping_add(1);
        if self.free_leaves != NONE {
            let i = self.free_leaves;
            let l = &mut self.leaves[i as usize];
            self.free_leaves = l.next;
            l.len = 0;
            l.next = NONE;
            i
        } else {
            self.leaves.push(Leaf::EMPTY);
            u32::try_from(self.leaves.len() - 1).expect("fewer than 2^31 leaves")
        }
    }

    fn free_leaf(&mut self, i: u32) {
        self.shape = self.shape.wrapping_add(1);
        let l = &mut self.leaves[i as usize];
        l.len = 0;
        l.next = self.free_leaves;
        self.free_leaves = i;
    }

    fn alloc_inner(&mut self, n: Inner) -> u32 {
        self.shape = self.shape.wrapping_add(1);
        if let Some(i) = self.free_inners.pop() {
            self.inners[i as usize] = n;
            i
        } else {
            self.inners.push(n);
            u32::try_from(self.inners.len() - 1).expect("fewer than 2^31 inner nodes")
        }
    }

    // ---- building -----------------------------------------------------------------------

    /// Builds a sub-tree over `entries` and returns its reference.
    fn build(&mut self, entries: &mut [Entry]) -> u32 {
        if entries.len() <= LEAF_CAP {
            let l = self.alloc_leaf();
            for e in entries.iter() {
                self.leaves[l as usize].push(*e);
            }
            return l | LEAF_BIT;
        }
        let mut lo = entries[0].p;
        let mut hi = entries[0].p;
        for e in entries.iter() {
            for a in 0..3 {
                if e.p[a] < lo[a] {
                    lo[a] = e.p[a];
                }
                if e.p[a] > hi[a] {
                    hi[a] = e.p[a];
                }
            }
        }
        let dim = (0..3)
            .max_by(|&a, &b| cmp_axis(hi[a] - lo[a], hi[b] - lo[b]))
            .expect("three axes");
        if hi[dim] - lo[dim] <= 0.0 && (0..3).all(|a| lo[a] == hi[a]) {
            return self.build_chain(entries);
        }
        // Above two leaves, split at a multiple of `BULK_FILL` so that bulk-built leaves
        // hold `BULK_FILL` entries; a splitting leaf (33 entries) divides in halves.
        let n = entries.len();
        let mid = if n > 2 * LEAF_CAP {
            (n / 2 + BULK_FILL / 2) / BULK_FILL * BULK_FILL
        } else {
            n / 2
        };
        entries.select_nth_unstable_by(mid, |a, b| cmp_axis(a.p[dim], b.p[dim]));
        let mut split = entries[mid].p[dim];
        let mut nl = partition(&mut entries[..mid], |e| e.p[dim] < split);
        if nl == 0 {
            // Every entry left of the median equals the minimum: split just above it.
            nl = partition(entries, |e| e.p[dim] <= split);
            split = entries[nl..]
                .iter()
                .map(|e| e.p[dim])
                .min_by(|a, b| cmp_axis(*a, *b))
                .expect("spread > 0 leaves entries above the minimum");
        }
        let (left_entries, right_entries) = entries.split_at_mut(nl);
        let left = self.build(left_entries);
        let right = self.build(right_entries);
        self.alloc_inner(Inner {
            split,
            dim: dim as u32,
            left,
            right,
        })
    }

    /// A chain of leaves holding entries whose points are all equal.
    fn build_chain(&mut self, entries: &[Entry]) -> u32 {
        let head = self.alloc_leaf();
        let mut cur = head;
        for e in entries {
            if self.leaves[cur as usize].len as usize == LEAF_CAP {
                let next = self.alloc_leaf();
                self.leaves[cur as usize].next = next;
                cur = next;
            }
            self.leaves[cur as usize].push(*e);
        }
        head | LEAF_BIT
    }

    /// Appends every entry below `r` to `out`.
    fn collect(&self, r: u32, out: &mut Vec<Entry>) {
        if is_leaf(r) {
            let mut l = leaf_index(r) as u32;
            while l != NONE {
                let leaf = &self.leaves[l as usize];
                out.extend((0..leaf.len as usize).map(|i| leaf.entry(i)));
                l = leaf.next;
            }
        } else {
            let n = self.inners[r as usize];
            self.collect(n.left, out);
            self.collect(n.right, out);
        }
    }

    /// Frees every node below `r` (including `r`).
    fn free_subtree(&mut self, r: u32) {
        if is_leaf(r) {
            let mut l = leaf_index(r) as u32;
            while l != NONE {
                let next = self.leaves[l as usize].next;
                self.free_leaf(l);
                l = next;
            }
        } else {
            let n = self.inners[r as usize];
            self.free_subtree(n.left);
            self.free_subtree(n.right);
            self.free_inners.push(r);
        }
    }

    /// Every entry, in tree order.
    pub(crate) fn entries(&self) -> Vec<Entry> {
        let mut out = Vec::with_capacity(self.len);
        self.collect(self.root, &mut out);
        out
    }

    /// Points the reference to `old` held by `parent` (or the root) at `new`.
    fn replace_child(&mut self, parent: Option<u32>, old: u32, new: u32) {
        self.shape = self.shape.wrapping_add(1);
        match parent {
            None => self.root = new,
            Some(p) => {
                let n = &mut self.inners[p as usize];
                if n.left == old {
                    n.left = new;
                } else {
                    debug_assert_eq!(n.right, old);
                    n.right = new;
                }
            }
        }
    }

    // ---- updates ------------------------------------------------------------------------

    /// The current shape (see [`Located`]).
    pub(crate) fn shape(&self) -> u64 {
        self.shape
    }

    /// Finds, for every point of `points` in every tree of `trees`, where it descends
    /// to, and writes it to `out` (trees outer, points inner; `out` must have room):
    /// [`LiveKdTree::insert_located`] and [`LiveKdTree::remove_located`] then skip
    /// their own descent. Brings each leaf into cache as well. Changes nothing.
    ///
    /// The descents advance in lockstep, one level each per round, so their cache
    /// misses overlap instead of following one another: a move (a remove and an insert)
    /// in two indexes walks its four paths in about the time of one.
    pub(crate) fn locate(trees: &[&LiveKdTree], points: &[&[Point]], out: &mut [Located]) {
        const WIDTH: usize = 8;
        let Some(&first) = trees.first() else { return };
        let mut batch = [(first, LEAF_BIT, [0.0f32; 3]); WIDTH];
        let mut k = 0;
        let mut done = 0;
        for &t in trees {
            for p in points.iter().flat_map(|ps| ps.iter()) {
                batch[k] = (t, t.root, *p);
                k += 1;
                if k == WIDTH {
                    Self::locate_batch(&mut batch, &mut out[done..done + k]);
                    done += k;
                    k = 0;
                }
            }
        }
        Self::locate_batch(&mut batch[..k], &mut out[done..done + k]);
    }

    fn locate_batch(batch: &mut [(&LiveKdTree, u32, Point)], out: &mut [Located]) {
        out.fill(Located::default());
        let mut depth = 0;
        loop {
            let mut descending = false;
            for ((t, c, p), o) in batch.iter_mut().zip(out.iter_mut()) {
                if !is_leaf(*c) {
                    let n = &t.inners[*c as usize];
                    *c = if p[n.dim as usize] < n.split {
                        n.left
                    } else {
                        n.right
                    };
                    descending = true;
                    o.depth = depth + 1;
                }
            }
            if !descending {
                break;
            }
            depth += 1;
        }
        // One read per cache line of each leaf (independent reads, so they overlap
        // too); `black_box` keeps them.
        let mut sum = 0u32;
        for ((t, c, _), o) in batch.iter().zip(out.iter_mut()) {
            o.leaf = *c;
            let leaf = &t.leaves[leaf_index(*c)];
            sum = sum.wrapping_add(leaf.len);
            for i in (0..LEAF_CAP).step_by(8) {
                sum = sum
                    .wrapping_add(leaf.xs[i].to_bits())
                    .wrapping_add(leaf.ys[i].to_bits())
                    .wrapping_add(leaf.zs[i].to_bits())
                    .wrapping_add(leaf.items[i]);
            }
        }
        std::hint::black_box(sum);
    }

    /// [`LiveKdTree::insert`], given where `p` descends to (found by
    /// [`LiveKdTree::locate`] under the current shape): a leaf with room takes the entry
    /// without a descent; anything else (a full or chained leaf, a leaf too deep, a
    /// stale `at`) takes the ordinary path.
    pub(crate) fn insert_located(&mut self, p: Point, item: u32, at: Located, shape: u64) {
        let head = leaf_index(at.leaf);
        let leaf = &self.leaves[head];
        if shape == self.shape
            && leaf.next == NONE
            && (leaf.len as usize) < LEAF_CAP
            && at.depth as usize <= depth_limit(self.len + 1)
        {
            self.leaves[head].push(Entry { p, item });
            self.len += 1;
            self.peak = self.peak.max(self.len);
        } else {
            self.insert(p, item);
        }
    }

    /// [`LiveKdTree::remove`], given where `p` descends to (see
    /// [`LiveKdTree::insert_located`]): found in a single leaf that keeps other entries,
    /// the entry goes without a descent; anything else takes the ordinary path.
    pub(crate) fn remove_located(&mut self, p: Point, item: u32, at: Located, shape: u64) -> bool {
        let head = leaf_index(at.leaf);
        let leaf = &self.leaves[head];
        if shape == self.shape && leaf.next == NONE && leaf.len > 1 {
            if !self.chain_remove(head as u32, &p, item) {
                return false; // `p` descends to this leaf: nowhere else can hold it
            }
            self.len -= 1;
            self.shrink_if_halved();
            true
        } else {
            self.remove(p, item)
        }
    }

    /// Adds one entry.
    pub fn insert(&mut self, p: Point, item: u32) {
        let mut path = std::mem::take(&mut self.path);
        path.clear();
        let mut r = self.root;
        while !is_leaf(r) {
            path.push(r);
            let n = &self.inners[r as usize];
            r = if p[n.dim as usize] < n.split {
                n.left
            } else {
                n.right
            };
        }
        self.len += 1;
        let e = Entry { p, item };
        let head = leaf_index(r) as u32;
        let (len, next) = (
            self.leaves[head as usize].len as usize,
            self.leaves[head as usize].next,
        );
        // The reference now at the bottom of `path` (the leaf, or what replaced it).
        let mut bottom = r;
        if len < LEAF_CAP && next == NONE {
            self.leaves[head as usize].push(e);
        } else if len == LEAF_CAP && next == NONE && !self.chain_equals(head, &p) {
            // A full leaf with distinct points: split it (on the stack, no allocation).
            let leaf = &self.leaves[head as usize];
            let mut entries = [e; LEAF_CAP + 1];
            for (i, slot) in entries.iter_mut().take(LEAF_CAP).enumerate() {
                *slot = leaf.entry(i);
            }
            self.free_leaf(head);
            bottom = self.build(&mut entries);
            self.replace_child(path.last().copied(), r, bottom);
        } else if self.chain_equals(head, &p) {
            self.chain_push(head, e);
        } else {
            // A chain of identical points receives a different point: rebuild it.
            let mut entries = Vec::new();
            self.collect(r, &mut entries);
            entries.push(e);
            self.free_subtree(r);
            bottom = self.build(&mut entries);
            self.replace_child(path.last().copied(), r, bottom);
        }
        self.peak = self.peak.max(self.len);
        if path.len() > depth_limit(self.len) {
            self.rebalance(&path, bottom);
        }
        self.path = path;
    }

    /// Whether every entry of the leaf chain starting at `head` has point `p`.
    fn chain_equals(&self, head: u32, p: &Point) -> bool {
        let mut l = head;
        while l != NONE {
            let leaf = &self.leaves[l as usize];
            if !(0..leaf.len as usize).all(|i| leaf.point(i) == *p) {
                return false;
            }
            l = leaf.next;
        }
        true
    }

    fn chain_push(&mut self, head: u32, e: Entry) {
        let mut l = head;
        loop {
            let leaf = &self.leaves[l as usize];
            if (leaf.len as usize) < LEAF_CAP {
                self.leaves[l as usize].push(e);
                return;
            }
            if leaf.next == NONE {
                let next = self.alloc_leaf();
                self.leaves[l as usize].next = next;
                self.leaves[next as usize].push(e);
                return;
            }
            l = leaf.next;
        }
    }

    /// Removes one entry equal to `(p, item)` (coordinates compared bit for bit).
    /// Returns whether one was found.
    pub fn remove(&mut self, p: Point, item: u32) -> bool {
        let mut path = std::mem::take(&mut self.path);
        path.clear();
        let mut r = self.root;
        while !is_leaf(r) {
            path.push(r);
            let n = &self.inners[r as usize];
            r = if p[n.dim as usize] < n.split {
                n.left
            } else {
                n.right
            };
        }
        let head = leaf_index(r) as u32;
        let found = self.chain_remove(head, &p, item);
        if found {
            self.len -= 1;
            if self.leaves[head as usize].len == 0
                && let Some(parent) = path.pop()
            {
                // Unlink the empty leaf: its sibling takes the parent's place.
                let n = self.inners[parent as usize];
                let sibling = if n.left == r { n.right } else { n.left };
                self.replace_child(path.last().copied(), parent, sibling);
                self.free_leaf(head);
                self.free_inners.push(parent);
            }
            self.shrink_if_halved();
        }
        self.path = path;
        found
    }

    /// Rebuilds the whole tree once it holds half the entries it had at its peak.
    fn shrink_if_halved(&mut self) {
        if self.len > 2 * LEAF_CAP && 2 * self.len < self.peak {
            let mut entries = self.entries();
            self.free_subtree(self.root);
            self.root = self.build(&mut entries);
            self.peak = self.len;
        }
    }

    /// Removes one `(p, item)` entry from a chain, keeping chained leaves packed.
    fn chain_remove(&mut self, head: u32, p: &Point, item: u32) -> bool {
        let bits = p.map(f32::to_bits);
        let mut l = head;
        let mut at = None;
        let mut prev_of_last = NONE;
        let mut last = head;
        while l != NONE {
            let leaf = &self.leaves[l as usize];
            if at.is_none() {
                at = (0..leaf.len as usize)
                    .find(|&i| leaf.items[i] == item && leaf.point(i).map(f32::to_bits) == bits)
                    .map(|i| (l, i));
            }
            if leaf.next != NONE {
                prev_of_last = l;
            }
            last = l;
            l = leaf.next;
        }
        let Some((l, i)) = at else { return false };
        let tail = &mut self.leaves[last as usize];
        tail.len -= 1;
        let moved = tail.entry(tail.len as usize);
        if (l, i) != (last, tail.len as usize) {
            self.leaves[l as usize].set(i, moved);
        }
        if self.leaves[last as usize].len == 0 && last != head {
            self.leaves[prev_of_last as usize].next = NONE;
            self.free_leaf(last);
        }
        true
    }

    /// Entries below `r`.
    fn count(&self, r: u32) -> usize {
        if is_leaf(r) {
            let mut total = 0;
            let mut l = leaf_index(r) as u32;
            while l != NONE {
                total += self.leaves[l as usize].len as usize;
                l = self.leaves[l as usize].next;
            }
            total
        } else {
            let n = &self.inners[r as usize];
            self.count(n.left) + self.count(n.right)
        }
    }

    /// After an insert below `path` (root first) landed too deep: walks up from `bottom`,
    /// sizing sub-trees, and rebuilds the first ancestor with more than 3/4 of its entries
    /// on one side (one exists when the depth exceeds [`depth_limit`]). Sizing costs at
    /// most the rebuilt sub-tree's size, so rebuilds stay amortised O(log n).
    fn rebalance(&mut self, path: &[u32], bottom: u32) {
        let mut below = self.count(bottom) as u64;
        let mut child = bottom;
        for (i, &a) in path.iter().enumerate().rev() {
            let n = self.inners[a as usize];
            let sibling = if n.left == child { n.right } else { n.left };
            let other = self.count(sibling) as u64;
            let total = below + other;
            if below.max(other) * BALANCE.1 > total * BALANCE.0 {
                let mut entries = Vec::with_capacity(total as usize);
                self.collect(a, &mut entries);
                self.free_subtree(a);
                let new = self.build(&mut entries);
                let parent = if i == 0 { None } else { Some(path[i - 1]) };
                self.replace_child(parent, a, new);
                return;
            }
            below = total;
            child = a;
        }
    }

    // ---- queries ------------------------------------------------------------------------

    /// Branch-and-bound nearest search (see [`crate::index::SpatialIndex::nearest_visit`]):
    /// calls `f(distance², item)` for entries at most the current bound away, nearer
    /// cells first, and skips cells strictly farther than the bound `f` returns.
    pub fn nearest_visit<F: FnMut(f32, u32) -> f32>(&self, c: &Point, mut f: F) {
        if self.len > 0 {
            let mut bound = f32::INFINITY;
            self.nearest_in(self.root, c, [0.0; 3], &mut bound, &mut f);
        }
    }

    fn nearest_in<F: FnMut(f32, u32) -> f32>(
        &self,
        r: u32,
        c: &Point,
        off: [f32; 3],
        bound: &mut f32,
        f: &mut F,
    ) {
        if is_leaf(r) {
            let mut l = leaf_index(r) as u32;
            while l != NONE {
                let leaf = &self.leaves[l as usize];
                let d = leaf.distances(c);
                let b = *bound;
                // Slots past `len` may hold stale points: a false hit only costs the loop.
                if d.iter().fold(false, |hit, &x| hit | (x <= b)) {
                    for (i, &di) in d.iter().enumerate().take(leaf.len as usize) {
                        if di <= *bound {
                            *bound = f(di, leaf.items[i]);
                        }
                    }
                }
                l = leaf.next;
            }
            return;
        }
        let n = &self.inners[r as usize];
        let dim = n.dim as usize;
        let delta = c[dim] - n.split;
        let (near, far) = if delta < 0.0 {
            (n.left, n.right)
        } else {
            (n.right, n.left)
        };
        self.nearest_in(near, c, off, bound, f);
        let mut far_off = off;
        far_off[dim] = delta.abs();
        if cell_distance_squared(&far_off) <= *bound {
            self.nearest_in(far, c, far_off, bound, f);
        }
    }

    /// Calls `f(distance², item, point)` for every entry with `distance² <= r2`.
    pub fn within(&self, c: &Point, r2: f32, f: &mut impl FnMut(f32, u32, &Point)) {
        if self.len > 0 {
            self.within_in(self.root, c, [0.0; 3], r2, f);
        }
    }

    fn within_in(
        &self,
        r: u32,
        c: &Point,
        off: [f32; 3],
        r2: f32,
        f: &mut impl FnMut(f32, u32, &Point),
    ) {
        if is_leaf(r) {
            let mut l = leaf_index(r) as u32;
            while l != NONE {
                let leaf = &self.leaves[l as usize];
                let d = leaf.distances(c);
                for (i, &di) in d.iter().enumerate().take(leaf.len as usize) {
                    if di <= r2 {
                        f(di, leaf.items[i], &leaf.point(i));
                    }
                }
                l = leaf.next;
            }
            return;
        }
        let n = &self.inners[r as usize];
        let dim = n.dim as usize;
        let delta = c[dim] - n.split;
        let (near, far) = if delta < 0.0 {
            (n.left, n.right)
        } else {
            (n.right, n.left)
        };
        let mut far_off = off;
        far_off[dim] = delta.abs();
        let visit_far = cell_distance_squared(&far_off) <= r2;
        if visit_far {
            // The far side is walked after the near one: start loading its first node
            // (a whole leaf: 9 cache lines) now, so that the load overlaps that walk.
            if is_leaf(far) {
                let p = self
                    .leaves
                    .as_ptr()
                    .wrapping_add(leaf_index(far))
                    .cast::<u8>();
                for line in 0..std::mem::size_of::<Leaf>().div_ceil(64) {
                    super::prefetch(p.wrapping_add(64 * line));
                }
            } else {
                super::prefetch(self.inners.as_ptr().wrapping_add(far as usize));
            }
        }
        self.within_in(near, c, off, r2, f);
        if visit_far {
            self.within_in(far, c, far_off, r2, f);
        }
    }

    /// Checks the invariants in the module docs; `Err` names the first broken one.
    #[cfg(test)]
    pub(crate) fn check(&self) -> Result<(), String> {
        fn walk(
            t: &LiveKdTree,
            r: u32,
            lo: [f32; 3],
            hi: [f32; 3],
            is_root: bool,
            depth: usize,
        ) -> Result<(u32, usize), String> {
            if is_leaf(r) {
                let head = leaf_index(r) as u32;
                let mut l = head;
                let mut n = 0;
                let first =
                    (t.leaves[head as usize].len > 0).then(|| t.leaves[head as usize].point(0));
                while l != NONE {
                    let leaf = &t.leaves[l as usize];
                    for i in 0..leaf.len as usize {
                        let p = leaf.point(i);
                        if (0..3).any(|a| p[a] < lo[a] || p[a] >= hi[a]) {
                            return Err(format!("entry {p:?} outside its cell"));
                        }
                        if (leaf.next != NONE || l != head) && Some(p) != first {
                            return Err("chained leaf holds distinct points".into());
                        }
                    }
                    n += leaf.len;
                    l = leaf.next;
                }
                if n == 0 && !is_root {
                    return Err("empty non-root leaf".into());
                }
                return Ok((n, depth));
            }
            let node = t.inners[r as usize];
            let d = node.dim as usize;
            let mut lhi = hi;
            lhi[d] = lhi[d].min(node.split);
            let mut rlo = lo;
            rlo[d] = rlo[d].max(node.split);
            let (lc, ld) = walk(t, node.left, lo, lhi, false, depth + 1)?;
            let (rc, rd) = walk(t, node.right, rlo, hi, false, depth + 1)?;
            Ok((lc + rc, ld.max(rd)))
        }
        let (n, _) = walk(
            self,
            self.root,
            [f32::NEG_INFINITY; 3],
            [f32::INFINITY; 3],
            true,
            0,
        )?;
        if n as usize != self.len {
            return Err(format!("len {} != entries {n}", self.len));
        }
        Ok(())
    }

    /// Depth of the deepest leaf (the root leaf has depth 0).
    #[cfg(test)]
    pub(crate) fn depth(&self) -> usize {
        fn walk(t: &LiveKdTree, r: u32) -> usize {
            if is_leaf(r) {
                0
            } else {
                let n = t.inners[r as usize];
                1 + walk(t, n.left).max(walk(t, n.right))
            }
        }
        walk(self, self.root)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distance_squared;
    use rand::{Rng, SeedableRng};

    fn brute_nearest(entries: &[Entry], c: &Point, k: usize) -> Vec<f32> {
        let mut d: Vec<f32> = entries.iter().map(|e| distance_squared(&e.p, c)).collect();
        d.sort_by(|a, b| a.total_cmp(b));
        d.truncate(k);
        d
    }

    fn brute_within(entries: &[Entry], c: &Point, r2: f32) -> Vec<(u32, u32)> {
        let mut v: Vec<(u32, u32)> = entries
            .iter()
            .filter(|e| distance_squared(&e.p, c) <= r2)
            .map(|e| (e.item, distance_squared(&e.p, c).to_bits()))
            .collect();
        v.sort_unstable();
        v
    }

    fn check_queries(t: &LiveKdTree, model: &[Entry], rng: &mut impl Rng) {
        t.check().unwrap();
        assert_eq!(t.len(), model.len());
        for _ in 0..20 {
            let c = [
                rng.gen_range(-2.0..12.0),
                rng.gen_range(-2.0..12.0),
                rng.gen_range(-1.0..2.0),
            ];
            let k = rng.gen_range(1..12);
            // The k smallest distances, through the visitor with a k-best bound.
            let mut best: Vec<f32> = Vec::new();
            t.nearest_visit(&c, |d, item| {
                assert!(
                    model
                        .iter()
                        .any(|e| e.item == item && distance_squared(&e.p, &c) == d)
                );
                let at = best.partition_point(|&x| x <= d);
                best.insert(at, d);
                best.truncate(k);
                if best.len() == k {
                    best[k - 1]
                } else {
                    f32::INFINITY
                }
            });
            assert_eq!(best, brute_nearest(model, &c, k));
            let r2 = rng.gen_range(0.0..9.0f32);
            let mut w = Vec::new();
            t.within(&c, r2, &mut |d, item, _| w.push((item, d.to_bits())));
            w.sort_unstable();
            assert_eq!(w, brute_within(model, &c, r2));
        }
    }

    #[test]
    fn random_inserts_and_removes_match_brute_force() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut t = LiveKdTree::new();
        let mut model: Vec<Entry> = Vec::new();
        for step in 0..4000 {
            if model.is_empty() || rng.gen_bool(0.65) {
                // Points on a coarse grid so that duplicates and shared coordinates occur.
                let p = [
                    rng.gen_range(0..40) as f32 * 0.25,
                    rng.gen_range(0..40) as f32 * 0.25,
                    rng.gen_range(0..3) as f32 * 0.5,
                ];
                let e = Entry {
                    p,
                    item: rng.gen_range(0..50),
                };
                t.insert(e.p, e.item);
                model.push(e);
            } else {
                let i = rng.gen_range(0..model.len());
                let e = model.swap_remove(i);
                assert!(t.remove(e.p, e.item));
            }
            if step % 200 == 0 {
                check_queries(&t, &model, &mut rng);
            }
        }
        check_queries(&t, &model, &mut rng);
        assert!(!t.remove([99.0, 0.0, 0.0], 1));
    }

    #[test]
    fn many_identical_points_chain_and_unchain() {
        let mut t = LiveKdTree::new();
        for i in 0..200 {
            t.insert([1.0, 2.0, 3.0], i);
        }
        t.insert([1.0, 2.0, 4.0], 999);
        t.check().unwrap();
        assert_eq!(t.len(), 201);
        let mut seen = Vec::new();
        t.nearest_visit(&[1.0, 2.0, 3.0], |d, item| {
            seen.push((d, item));
            f32::INFINITY
        });
        seen.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        assert_eq!(seen.len(), 201);
        assert_eq!(seen[200], (1.0, 999));
        for i in 0..200 {
            assert!(t.remove([1.0, 2.0, 3.0], i));
            t.check().unwrap();
        }
        assert_eq!(
            t.entries(),
            vec![Entry {
                p: [1.0, 2.0, 4.0],
                item: 999
            }]
        );
    }

    #[test]
    fn a_wall_of_points_sharing_one_coordinate_is_indexed() {
        // kiddo's MutableKdTree fails here (a full bucket cannot split on x).
        let mut t = LiveKdTree::new();
        for i in 0..5000u32 {
            t.insert([1.0, (i % 71) as f32, (i / 71) as f32], i);
        }
        t.check().unwrap();
        assert_eq!(t.len(), 5000);
    }

    #[test]
    fn sequential_inserts_stay_balanced() {
        let mut t = LiveKdTree::new();
        for i in 0..100_000u32 {
            t.insert([i as f32, 0.0, 0.0], i);
        }
        t.check().unwrap();
        assert!(t.depth() <= depth_limit(t.len()) + 1, "depth {}", t.depth());
        for i in 0..99_000u32 {
            assert!(t.remove([i as f32, 0.0, 0.0], i));
        }
        t.check().unwrap();
        assert!(t.depth() <= depth_limit(t.len()), "depth {}", t.depth());
    }

    #[test]
    fn located_updates_match_plain_ones() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let empty = LiveKdTree::new();
        let point = |rng: &mut rand_chacha::ChaCha8Rng| {
            [
                rng.gen_range(0..60) as f32 * 0.25,
                rng.gen_range(0..60) as f32 * 0.25,
                rng.gen_range(0..2) as f32,
            ]
        };
        let entries: Vec<Entry> = (0..3000)
            .map(|i| Entry {
                p: point(&mut rng),
                item: i,
            })
            .collect();
        let mut t = LiveKdTree::from_entries(entries.clone());
        let mut plain = t.clone();
        let mut model = entries;
        for step in 0..6000 {
            // Move (remove one entry, add up to three) through located updates; the same
            // through plain ones.
            let e = model.swap_remove(rng.gen_range(0..model.len()));
            let added: Vec<Entry> = (0..rng.gen_range(0..4))
                .map(|_| Entry {
                    p: if rng.gen_bool(0.1) {
                        e.p
                    } else {
                        point(&mut rng)
                    },
                    item: e.item,
                })
                .collect();
            let ps: Vec<Point> = added.iter().map(|a| a.p).collect();
            let mut at = [Located::default(); 8];
            LiveKdTree::locate(&[&t, &empty], &[&[e.p], &ps], &mut at[..2 * (1 + ps.len())]);
            let shape = t.shape();
            assert!(t.remove_located(e.p, e.item, at[0], shape));
            assert!(plain.remove(e.p, e.item));
            for (a, l) in added.iter().zip(&at[1..]) {
                t.insert_located(a.p, a.item, *l, shape);
                plain.insert(a.p, a.item);
            }
            model.extend(added);
            if step % 500 == 0 {
                t.check().unwrap();
                let sorted = |t: &LiveKdTree| {
                    let mut v: Vec<_> = t
                        .entries()
                        .iter()
                        .map(|e| (e.item, e.p.map(f32::to_bits)))
                        .collect();
                    v.sort_unstable();
                    v
                };
                assert_eq!(sorted(&t), sorted(&plain));
                assert_eq!(t.len(), model.len());
            }
        }
        // A located leaf is the one a descent reaches, at the path's depth.
        let probe: Vec<Point> = (0..50).map(|_| point(&mut rng)).collect();
        let mut at = vec![Located::default(); 50];
        LiveKdTree::locate(&[&t], &[&probe], &mut at);
        for (p, a) in probe.iter().zip(&at) {
            let (mut r, mut depth) = (t.root, 0);
            while !is_leaf(r) {
                let n = &t.inners[r as usize];
                r = if p[n.dim as usize] < n.split {
                    n.left
                } else {
                    n.right
                };
                depth += 1;
            }
            assert_eq!((a.leaf, a.depth), (r, depth));
        }
        // A stale location (the shape changed since) takes the ordinary path.
        let old_shape = t.shape();
        for i in 0..200 {
            t.insert(point(&mut rng), 10_000 + i);
        }
        assert_ne!(t.shape(), old_shape);
        t.insert_located([1.0, 1.0, 0.0], 99_999, at[0], old_shape);
        assert!(t.remove_located([1.0, 1.0, 0.0], 99_999, at[1], old_shape));
        t.check().unwrap();
    }

    #[test]
    fn bulk_build_matches_brute_force() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let model: Vec<Entry> = (0..3000)
            .map(|i| Entry {
                p: [
                    rng.gen_range(0.0..10.0),
                    rng.gen_range(0.0..10.0),
                    rng.gen_range(0.0..1.0),
                ],
                item: i,
            })
            .collect();
        let t = LiveKdTree::from_entries(model.clone());
        check_queries(&t, &model, &mut rng);
        // Leaves 7/8 full after a bulk build: 18.6 bytes per point plus inner nodes.
        assert!(t.memory_bytes() < 20 * model.len(), "{}", t.memory_bytes());
    }
}
