//! [`Points`]: a node's points as a view hands them out, contiguous or split across the
//! fixed-size chunks of a chunked layer (see [`crate::snapshot::POINT_CHUNK_LEN`]).

use crate::{Aabb, Point};
use std::ops::Range;

/// A layer's point column as it lies in memory: one slice, or chunks of
/// [`crate::snapshot::POINT_CHUNK_LEN`] points each (the last may be shorter).
#[derive(Clone, Copy, Debug)]
pub(crate) enum PointColumn<'a> {
    /// The whole column in one slice.
    Inline(&'a [Point]),
    /// The column in chunks; position `p` lies in chunk `p / chunk_len`.
    Chunked {
        /// The chunks in order.
        chunks: &'a [&'a [Point]],
        /// Points per chunk (every chunk but the last holds exactly this many).
        chunk_len: usize,
    },
}

impl<'a> PointColumn<'a> {
    /// Points in the column.
    pub(crate) fn len(self) -> usize {
        match self {
            PointColumn::Inline(points) => points.len(),
            PointColumn::Chunked { chunks, chunk_len } => match chunks.split_last() {
                Some((last, rest)) => rest.len() * chunk_len + last.len(),
                None => 0,
            },
        }
    }

    /// The points at positions `range`, or none when the range is not in the column
    /// (checks let only in-range offsets through; this keeps accessors total anyway).
    pub(crate) fn range(self, range: Range<usize>) -> Points<'a> {
        if range.start > range.end || range.end > self.len() {
            return Points::default();
        }
        Points {
            column: self,
            start: range.start,
            len: range.end - range.start,
        }
    }
}

/// A node's points: one slice for a node of the live graph or of a layer kept in one
/// piece, possibly several for a node of a chunked layer whose points cross a chunk
/// boundary. Iterate it, or take [`Points::as_slice`] when it is one piece.
#[derive(Clone, Copy)]
pub struct Points<'a> {
    column: PointColumn<'a>,
    start: usize,
    len: usize,
}

impl Default for Points<'_> {
    fn default() -> Self {
        Points::from(&[][..])
    }
}

impl<'a> From<&'a [Point]> for Points<'a> {
    fn from(points: &'a [Point]) -> Self {
        Points {
            column: PointColumn::Inline(points),
            start: 0,
            len: points.len(),
        }
    }
}

impl<'a> Points<'a> {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The contiguous pieces, in order (one unless the points cross chunk boundaries).
    pub fn runs(&self) -> impl Iterator<Item = &'a [Point]> + use<'a> {
        let (start, end) = (self.start, self.start + self.len);
        let (inline, chunked) = match self.column {
            PointColumn::Inline(points) => (Some(&points[start..end]), None),
            PointColumn::Chunked { chunks, chunk_len } if self.len > 0 => {
                let first = start / chunk_len;
                let last = (end - 1) / chunk_len;
                let runs = chunks[first..=last].iter().enumerate().map(move |(k, c)| {
                    let base = (first + k) * chunk_len;
                    let a = start.max(base) - base;
                    let b = end.min(base + c.len()) - base;
                    &c[a..b]
                });
                (None, Some(runs))
            }
            PointColumn::Chunked { .. } => (None, None),
        };
        inline.into_iter().chain(chunked.into_iter().flatten())
    }

    /// The points as one slice when their column is not chunked: the quick test a scan
    /// makes before falling back to [`Points::runs`].
    #[inline]
    pub(crate) fn unchunked(&self) -> Option<&'a [Point]> {
        match self.column {
            PointColumn::Inline(points) => points.get(self.start..self.start + self.len),
            PointColumn::Chunked { .. } => None,
        }
    }

    /// The points as one slice, if they lie in one piece.
    pub fn as_slice(&self) -> Option<&'a [Point]> {
        let mut runs = self.runs();
        match (runs.next(), runs.next()) {
            (Some(one), None) => Some(one),
            (None, _) => Some(&[]),
            _ => None,
        }
    }

    /// Every point, in order.
    pub fn iter(&self) -> PointsIter<'a> {
        PointsIter {
            current: [].iter(),
            column: self.column,
            next: self.start,
            end: self.start + self.len,
        }
    }

    /// The `i`-th point.
    pub fn get(&self, i: usize) -> Option<&'a Point> {
        if i >= self.len {
            return None;
        }
        let p = self.start + i;
        match self.column {
            PointColumn::Inline(points) => points.get(p),
            PointColumn::Chunked { chunks, chunk_len } => {
                chunks.get(p / chunk_len)?.get(p % chunk_len)
            }
        }
    }

    /// The first point.
    pub fn first(&self) -> Option<&'a Point> {
        self.get(0)
    }

    /// The smallest box holding every point (`None` when there are none).
    pub fn aabb(&self) -> Option<Aabb> {
        self.runs()
            .filter_map(Aabb::from_points)
            .reduce(|a, b| a.union(&b))
    }

    /// The points copied into a vector.
    pub fn to_vec(&self) -> Vec<Point> {
        let mut v = Vec::with_capacity(self.len);
        for run in self.runs() {
            v.extend_from_slice(run);
        }
        v
    }
}

impl<'a> IntoIterator for Points<'a> {
    type Item = &'a Point;
    type IntoIter = PointsIter<'a>;

    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

/// Iterator over [`Points`]: a slice iterator per contiguous piece.
#[derive(Clone, Debug)]
pub struct PointsIter<'a> {
    current: std::slice::Iter<'a, Point>,
    column: PointColumn<'a>,
    /// Column position of the first point after `current`.
    next: usize,
    end: usize,
}

impl<'a> Iterator for PointsIter<'a> {
    type Item = &'a Point;

    #[inline]
    fn next(&mut self) -> Option<&'a Point> {
        loop {
            if let Some(p) = self.current.next() {
                return Some(p);
            }
            if self.next >= self.end {
                return None;
            }
            let (piece, base) = match self.column {
                PointColumn::Inline(points) => (points, 0),
                PointColumn::Chunked { chunks, chunk_len } => {
                    let k = self.next / chunk_len;
                    (chunks[k], k * chunk_len)
                }
            };
            let stop = self.end.min(base + piece.len());
            if stop <= self.next {
                // A chunk shorter than its place (a cut no check accepted): stop.
                self.next = self.end;
                return None;
            }
            self.current = piece[self.next - base..stop - base].iter();
            self.next = stop;
        }
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = self.current.len() + (self.end - self.next);
        (n, Some(n))
    }
}

impl ExactSizeIterator for PointsIter<'_> {}

impl std::fmt::Debug for Points<'_> {
    /// The points, as a list (however they are split).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

impl PartialEq for Points<'_> {
    fn eq(&self, other: &Self) -> bool {
        self.len == other.len && self.iter().eq(other.iter())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_range_across_chunks_reads_the_same_points_as_one_slice() {
        let all: Vec<Point> = (0..10).map(|i| [i as f32, 0.0, 0.0]).collect();
        let chunks: Vec<&[Point]> = all.chunks(4).collect();
        let column = PointColumn::Chunked {
            chunks: &chunks,
            chunk_len: 4,
        };
        assert_eq!(column.len(), 10);
        for a in 0..=10 {
            for b in a..=10 {
                let points = column.range(a..b);
                assert_eq!(points.to_vec(), all[a..b]);
                assert_eq!(points.len(), b - a);
                assert_eq!(points.get(0), all[a..b].first());
                let pieces = points.runs().count();
                assert_eq!(points.as_slice().is_some(), pieces <= 1, "{a}..{b}");
            }
        }
        assert!(column.range(3..11).is_empty());
    }
}
