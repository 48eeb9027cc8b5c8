//! [`PointChange`]: one node's points before and after a change, as the exact boxes and
//! the spatial indexes above the node take it.

use crate::{Aabb, Point};
use std::cell::OnceCell;
use std::sync::Arc;

/// One node's points before and after a change, handed to the boxes above the node and to
/// every index tree the change goes to (its layer's index, the node indexes above it).
/// What more than one of them needs is made once, on first use: the new points' box, and
/// the copies an index overlay keeps (shared by the trees that keep them).
pub(crate) struct PointChange<'a> {
    old: &'a [Point],
    new: &'a [Point],
    /// `old` and `new` without their common prefix and suffix.
    removed: &'a [Point],
    added: &'a [Point],
    /// How many leading points the change keeps as they were.
    kept: usize,
    new_box: OnceCell<Option<Aabb>>,
    kept_old: OnceCell<Arc<[Point]>>,
    kept_new: OnceCell<Arc<[Point]>>,
}

impl<'a> PointChange<'a> {
    /// The change from `old` to `new` (compared once, point by point, for the parts that
    /// differ).
    pub(crate) fn new(old: &'a [Point], new: &'a [Point]) -> Self {
        let (kept, removed, added) = crate::id::point_difference(old, new);
        Self::with_parts(old, new, removed, added, kept)
    }

    /// The change that appends `points[appended_from..]` to `points[..appended_from]`
    /// (nothing compared).
    pub(crate) fn appended(points: &'a [Point], appended_from: usize) -> Self {
        let (old, added) = points.split_at(appended_from);
        Self::with_parts(old, points, &[], added, appended_from)
    }

    fn with_parts(
        old: &'a [Point],
        new: &'a [Point],
        removed: &'a [Point],
        added: &'a [Point],
        kept: usize,
    ) -> Self {
        PointChange {
            old,
            new,
            removed,
            added,
            kept,
            new_box: OnceCell::new(),
            kept_old: OnceCell::new(),
            kept_new: OnceCell::new(),
        }
    }

    /// How many leading points the change keeps as they were (bit for bit).
    pub(crate) fn kept(&self) -> usize {
        self.kept
    }

    /// The points before the change.
    pub(crate) fn old_points(&self) -> &'a [Point] {
        self.old
    }

    /// The points after the change.
    pub(crate) fn new_points(&self) -> &'a [Point] {
        self.new
    }

    /// The parts that differ: the old and new points without their common prefix and
    /// suffix (see [`crate::id::changed_points`]).
    pub(crate) fn changed(&self) -> (&'a [Point], &'a [Point]) {
        (self.removed, self.added)
    }

    /// The box of the new points (`None` for none).
    pub(crate) fn new_box(&self) -> Option<Aabb> {
        *self.new_box.get_or_init(|| Aabb::from_points(self.new))
    }

    /// The old points, as an index overlay keeps them.
    pub(crate) fn kept_old(&self) -> Arc<[Point]> {
        Arc::clone(self.kept_old.get_or_init(|| Arc::from(self.old)))
    }

    /// The new points, as an index overlay keeps them.
    pub(crate) fn kept_new(&self) -> Arc<[Point]> {
        Arc::clone(self.kept_new.get_or_init(|| Arc::from(self.new)))
    }
}
