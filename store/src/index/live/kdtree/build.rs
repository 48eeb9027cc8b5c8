//! Building [`LiveKdTree`] sub-trees from entries (bulk builds, splits, rebuilds), and
//! collecting and freeing them.

use super::{BULK_FILL, Entry, Inner, LEAF_BIT, LEAF_CAP, LiveKdTree, NONE, is_leaf, leaf_index};
use std::cmp::Ordering;

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
    /// Builds a sub-tree over `entries` and returns its reference.
    pub(super) fn build(&mut self, entries: &mut [Entry]) -> u32 {
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
    pub(super) fn build_chain(&mut self, entries: &[Entry]) -> u32 {
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
    pub(super) fn collect(&self, r: u32, out: &mut Vec<Entry>) {
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
    pub(super) fn free_subtree(&mut self, r: u32) {
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
}
