//! Inserting and removing entries of a [`LiveKdTree`]: located updates, leaf chains,
//! scapegoat rebalancing and shrinking.

use super::{
    BALANCE, Entry, LEAF_BIT, LEAF_CAP, LiveKdTree, Located, NONE, depth_limit, is_leaf, leaf_index,
};
use crate::Point;

impl LiveKdTree {
    /// Points the reference to `old` held by `parent` (or the root) at `new`.
    pub(super) fn replace_child(&mut self, parent: Option<u32>, old: u32, new: u32) {
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

    pub(super) fn locate_batch(batch: &mut [(&LiveKdTree, u32, Point)], out: &mut [Located]) {
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

    /// The inner nodes from the root down to where `p` descends (in the tree's reused
    /// path buffer, to be given back), and the leaf reference reached.
    fn descend(&mut self, p: &Point) -> (Vec<u32>, u32) {
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
        (path, r)
    }

    /// Adds one entry.
    pub fn insert(&mut self, p: Point, item: u32) {
        let (path, r) = self.descend(&p);
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
    pub(super) fn chain_equals(&self, head: u32, p: &Point) -> bool {
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

    pub(super) fn chain_push(&mut self, head: u32, e: Entry) {
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
        let (mut path, r) = self.descend(&p);
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
    pub(super) fn shrink_if_halved(&mut self) {
        if self.len > 2 * LEAF_CAP && 2 * self.len < self.peak {
            let mut entries = self.entries();
            self.free_subtree(self.root);
            self.root = self.build(&mut entries);
            self.peak = self.len;
        }
    }

    /// Removes one `(p, item)` entry from a chain, keeping chained leaves packed.
    pub(super) fn chain_remove(&mut self, head: u32, p: &Point, item: u32) -> bool {
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
    pub(super) fn count(&self, r: u32) -> usize {
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
    pub(super) fn rebalance(&mut self, path: &[u32], bottom: u32) {
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
}
