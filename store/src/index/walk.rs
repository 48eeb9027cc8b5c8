//! The one nearest-neighbour walk, written once over [`KdTreeAccessor`]: read-only
//! access to the cells and leaves of a kd-tree, implemented by the live tree
//! ([`super::LiveKdTree`]) and by kiddo's archived tree ([`super::ArchivedKdTree`]), as
//! kiddo v6 writes its queries over `KdTreeAccessor`.
//!
//! Distances are computed exactly as [`crate::distance_squared`] computes them (the same
//! expression in the same order), and a cell is skipped only when
//! [`cell_distance_squared`] of its offsets, a lower bound of every point's distance in
//! it, exceeds the bound: an indexed query returns what brute force returns, bit for bit.

use crate::Point;

/// One node of a kd-tree as [`KdTreeAccessor::cell`] reports it.
pub(crate) enum Cell<N> {
    /// An inner node: points with `point[dim] < split` lie `below`, the others `above`.
    Inner {
        /// The split dimension (0, 1 or 2).
        dim: usize,
        /// The split coordinate.
        split: f32,
        /// The child holding points below the split.
        below: N,
        /// The child holding points at or above the split.
        above: N,
    },
    /// A leaf: its points are read through [`KdTreeAccessor::visit_leaf`].
    Leaf(N),
}

/// Receives the points of a leaf, a tile at a time.
pub(crate) trait TileVisitor {
    /// One tile of `W` slots, of which the first `len` hold points (the others may hold
    /// stale values, never reported): x's, y's, z's and items.
    fn tile<const W: usize>(
        &mut self,
        xs: &[f32; W],
        ys: &[f32; W],
        zs: &[f32; W],
        items: &[u32; W],
        len: usize,
    );
}

/// Read-only query access over live and archived kd-tree storage.
pub(crate) trait KdTreeAccessor {
    /// A handle to one node of the tree.
    type Node: Copy;

    /// The root, or `None` for an empty tree.
    fn root(&self) -> Option<Self::Node>;

    /// What `node` is: an inner node with its split, or a leaf.
    fn cell(&self, node: Self::Node) -> Cell<Self::Node>;

    /// Passes every point of the leaf `leaf` to `visitor`, in tiles.
    fn visit_leaf<V: TileVisitor>(&self, leaf: Self::Node, visitor: &mut V);

    /// A hint that the walk descends into `node` next (to start loading what lies below
    /// it); the default does nothing.
    #[inline]
    fn descending_into(&self, _node: Self::Node) {}
}

/// `((o0² + o1²) + o2²)`: evaluated like [`crate::distance_squared`], so for any point
/// whose per-axis offsets from the query are at least `off` (a point in the cell), the
/// result is at most that point's distance (rounding is monotone).
#[inline]
pub(crate) fn cell_distance_squared(off: &[f32; 3]) -> f32 {
    off[0] * off[0] + off[1] * off[1] + off[2] * off[2]
}

/// Squared distances from `c` to every slot of a tile: the same expression as
/// [`crate::distance_squared`], for the whole tile (fixed width, so the loop
/// vectorises).
#[inline]
pub(crate) fn tile_distances<const W: usize>(
    xs: &[f32; W],
    ys: &[f32; W],
    zs: &[f32; W],
    c: &Point,
) -> [f32; W] {
    let mut d = [0.0f32; W];
    for (i, di) in d.iter_mut().enumerate() {
        let dx = xs[i] - c[0];
        let dy = ys[i] - c[1];
        let dz = zs[i] - c[2];
        *di = dx * dx + dy * dy + dz * dz;
    }
    d
}

/// Branch-and-bound search from `c`, nearer cells first (see
/// [`super::SpatialIndex::nearest_visit`]): calls `f(distance², item)` for every point
/// at most the current bound away, and skips every cell whose points are all strictly
/// farther than it; `f` returns the new bound.
pub(crate) fn nearest_visit<T: KdTreeAccessor, F: FnMut(f32, u32) -> f32>(
    tree: &T,
    c: &Point,
    f: F,
) {
    let Some(root) = tree.root() else { return };
    let mut walk = NearestWalk {
        tree,
        c,
        bound: f32::INFINITY,
        f,
    };
    walk.descend(root, [0.0; 3]);
}

struct NearestWalk<'a, T, F> {
    tree: &'a T,
    c: &'a Point,
    bound: f32,
    f: F,
}

impl<T: KdTreeAccessor, F: FnMut(f32, u32) -> f32> NearestWalk<'_, T, F> {
    /// Depth-first from `node` (cell offsets `off` from the query), nearer child first;
    /// the farther child only if its cell is within the bound by then. Recursion costs
    /// less than an explicit stack here: no far cell is stored that the bound later
    /// prunes (archived trees are at most 31 levels deep, live ones logarithmic).
    fn descend(&mut self, node: T::Node, off: [f32; 3]) {
        let tree = self.tree;
        match tree.cell(node) {
            Cell::Leaf(leaf) => tree.visit_leaf(leaf, self),
            Cell::Inner {
                dim,
                split,
                below,
                above,
            } => {
                let delta = self.c[dim] - split;
                let (near, far) = if delta < 0.0 {
                    (below, above)
                } else {
                    (above, below)
                };
                tree.descending_into(near);
                self.descend(near, off);
                let mut far_off = off;
                far_off[dim] = delta.abs();
                if cell_distance_squared(&far_off) <= self.bound {
                    self.descend(far, far_off);
                }
            }
        }
    }
}

impl<T, F: FnMut(f32, u32) -> f32> TileVisitor for NearestWalk<'_, T, F> {
    #[inline]
    fn tile<const W: usize>(
        &mut self,
        xs: &[f32; W],
        ys: &[f32; W],
        zs: &[f32; W],
        items: &[u32; W],
        len: usize,
    ) {
        let d = tile_distances(xs, ys, zs, self.c);
        let bound = self.bound;
        // Slots past `len` may hold stale points: a false hit only costs the loop.
        if d.iter().fold(false, |hit, &x| hit | (x <= bound)) {
            for (&di, &item) in d.iter().zip(items).take(len) {
                if di <= self.bound {
                    self.bound = (self.f)(di, item);
                }
            }
        }
    }
}
