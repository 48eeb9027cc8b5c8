//! [`RowPatch`]: the rows of an archived layer index changed since its base tree was
//! built (see [`crate::snapshot::LayerIndexSegment`]), as a query reads them.
//!
//! A patched row's base entries are dead (the walk skips them), as are the entries of
//! rows at or past the layer's row count (removed since the base); a patched row's live
//! points are read from the layer's point column and scanned linearly. The writer keeps
//! the patch small (see `SegmentCache`), so the scan costs a bounded number of
//! [`crate::distance_squared`] per query, computed as brute force computes them.

use crate::points::{PointColumn, Points};
use crate::{Point, distance_squared};

/// The patch over an archived layer index's base tree, read from a checked segment.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RowPatch<'a> {
    /// Rows of the layer: base entries of rows at or past it are dead.
    rows: u32,
    /// Rows whose base entries are dead, ascending.
    patched: &'a [u32],
    /// The layer's point offsets (rows + 1 entries) and points.
    point_offsets: &'a [u32],
    points: PointColumn<'a>,
    /// Whether the base tree is the whole index (nothing patched, no row removed).
    clean: bool,
}

impl<'a> RowPatch<'a> {
    /// The patch of a layer with `point_offsets` and `points` (rows + 1 offsets), whose
    /// base tree was built over `base_rows` rows.
    pub(crate) fn new(
        base_rows: u32,
        patched: &'a [u32],
        point_offsets: &'a [u32],
        points: PointColumn<'a>,
    ) -> Self {
        let rows = point_offsets.len().saturating_sub(1) as u32;
        RowPatch {
            rows,
            patched,
            point_offsets,
            points,
            clean: patched.is_empty() && base_rows == rows,
        }
    }

    /// Whether the base tree alone answers (no entry of it is dead, none is added).
    #[inline]
    pub(crate) fn is_clean(&self) -> bool {
        self.clean
    }

    /// Whether the base tree's entries for `row` are dead.
    #[inline]
    pub(crate) fn is_dead(&self, row: u32) -> bool {
        row >= self.rows || self.patched.binary_search(&row).is_ok()
    }

    /// Number of live points: every point of the layer.
    pub(crate) fn len(&self) -> usize {
        self.points.len()
    }

    /// Each patched row with its live points (rows the checks let through are in range;
    /// a row out of range yields no points).
    fn rows(&self) -> impl Iterator<Item = (u32, Points<'a>)> + '_ {
        self.patched.iter().map(|&row| {
            let r = row as usize;
            let points = match (self.point_offsets.get(r), self.point_offsets.get(r + 1)) {
                (Some(&a), Some(&b)) => self.points.range(a as usize..b as usize),
                _ => Points::default(),
            };
            (row, points)
        })
    }

    /// Reports every patched point within the current bound (see
    /// [`crate::index::SpatialIndex::nearest_visit`]), starting from `bound`.
    pub(crate) fn nearest_visit<F: FnMut(f32, u32) -> f32>(
        &self,
        c: &Point,
        mut bound: f32,
        f: &mut F,
    ) {
        for (row, points) in self.rows() {
            for p in points {
                let d2 = distance_squared(p, c);
                if d2 <= bound {
                    bound = f(d2, row);
                }
            }
        }
    }

    /// Calls `f(distance², row, point)` for every patched point within `r2` of `c`.
    pub(crate) fn within<F: FnMut(f32, u32, &Point)>(&self, c: &Point, r2: f32, f: &mut F) {
        for (row, points) in self.rows() {
            for p in points {
                let d2 = distance_squared(p, c);
                if d2 <= r2 {
                    f(d2, row, p);
                }
            }
        }
    }
}
