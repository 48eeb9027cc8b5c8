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
//! `walk::cell_distance_squared`), so queries are exact.
//!
//! The tree's jobs live in submodules: `build` (bulk builds and rebuilds), `update`
//! (inserts, removes, rebalancing), `query` (the nearest walk through the shared
//! kd-tree accessor, and the radius walk), `check` (invariants, for tests).

use crate::Point;

mod build;
#[cfg(test)]
mod check;
mod query;
#[cfg(test)]
mod tests;
mod update;

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

    /// Replaces every entry's item `i` by `map(i)`, keeping the tree's shape (the points
    /// decide it). `map` must not send two items to one.
    pub(crate) fn map_items(&mut self, mut map: impl FnMut(u32) -> u32) {
        for leaf in &mut self.leaves {
            for item in &mut leaf.items[..leaf.len as usize] {
                *item = map(*item);
            }
        }
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
}
