//! Queries on a [`LiveKdTree`]: the nearest walk through its [`KdTreeAccessor`], and
//! the radius walk.

use super::{Leaf, LiveKdTree, NONE, is_leaf, leaf_index};
use crate::Point;
use crate::index::spatial_index::prefetch;
use crate::index::walk::{self, Cell, KdTreeAccessor, TileVisitor, cell_distance_squared};

impl LiveKdTree {
    /// Branch-and-bound nearest search (see [`crate::index::SpatialIndex::nearest_visit`]):
    /// calls `f(distance², item)` for entries at most the current bound away, nearer
    /// cells first, and skips cells strictly farther than the bound `f` returns.
    pub fn nearest_visit<F: FnMut(f32, u32) -> f32>(&self, c: &Point, f: F) {
        walk::nearest_visit(self, c, f);
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
                let d = walk::tile_distances(&leaf.xs, &leaf.ys, &leaf.zs, c);
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
                    prefetch(p.wrapping_add(64 * line));
                }
            } else {
                prefetch(self.inners.as_ptr().wrapping_add(far as usize));
            }
        }
        self.within_in(near, c, off, r2, f);
        if visit_far {
            self.within_in(far, c, far_off, r2, f);
        }
    }
}

/// Nodes are references: an inner node's index, or a leaf chain's head with
/// [`LEAF_BIT`] set.
impl KdTreeAccessor for LiveKdTree {
    type Node = u32;

    #[inline]
    fn root(&self) -> Option<u32> {
        (self.len > 0).then_some(self.root)
    }

    #[inline]
    fn cell(&self, r: u32) -> Cell<u32> {
        if is_leaf(r) {
            return Cell::Leaf(r);
        }
        let n = &self.inners[r as usize];
        Cell::Inner {
            dim: n.dim as usize,
            split: n.split,
            below: n.left,
            above: n.right,
        }
    }

    /// Every leaf of the chain, one full-width tile each.
    #[inline]
    fn visit_leaf<V: TileVisitor>(&self, r: u32, visitor: &mut V) {
        let mut l = leaf_index(r) as u32;
        while l != NONE {
            let leaf: &Leaf = &self.leaves[l as usize];
            visitor.tile(&leaf.xs, &leaf.ys, &leaf.zs, &leaf.items, leaf.len as usize);
            l = leaf.next;
        }
    }
}
