//! [`SpatialIndex`]: the read interface of every spatial index, which the spatial
//! queries in [`crate::query`] are written against.

use crate::{NodeId, Point};

/// Read access to one spatial index: a multiset of points, each tagged with an item that
/// names the node it belongs to.
///
/// Implemented by [`super::LiveIndex`] (live graph), [`super::ArchivedIndex`] (snapshot) and
/// [`super::KdIndex`] (built by a reader). The spatial queries use only these methods, so they
/// run unchanged on every kind of index.
pub trait SpatialIndex {
    /// Number of indexed points.
    fn len(&self) -> usize;

    /// Whether the index holds no point.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The node an item belongs to (`None` only for an item no point carries).
    fn node_of(&self, item: u32) -> Option<NodeId>;

    /// A hint that [`SpatialIndex::node_of`] will soon be asked about `item`: starts
    /// loading its entry of the id table into the cache, so that the (in a large index,
    /// cold) loads of many items overlap the search that finds them. Changes no result;
    /// the default does nothing.
    fn prefetch_node(&self, _item: u32) {}

    /// Branch-and-bound search from `c`, nearer cells first: calls `f(distance², item)`
    /// for every point whose squared distance is at most the current bound, and skips
    /// every cell whose points are all strictly farther than it. `f` returns the new bound
    /// (it starts at `+∞` and may only shrink). Points *at* the bound are still reported,
    /// so a caller can break ties exactly.
    fn nearest_visit<F: FnMut(f32, u32) -> f32>(&self, c: &Point, f: F);

    /// Calls `f(distance², item, point)` for every point with `distance² <= r2`.
    fn points_within<F: FnMut(f32, u32, &Point)>(&self, c: &Point, r2: f32, f: F);

    /// Bytes of memory (or of archive) the index occupies.
    fn memory_bytes(&self) -> usize;
}

/// Starts loading the cache line holding `p` into the cache (a hint: `p` may be any
/// address, even a dangling or wild one).
#[inline]
pub(crate) fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code, reason = "a prefetch hint")]
    // SAFETY: `_mm_prefetch` only hints the cache hierarchy: it never faults, whatever
    // the address, and changes no memory the program can observe. It needs SSE, which
    // every x86_64 CPU has (part of the target's baseline features).
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(p.cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}
