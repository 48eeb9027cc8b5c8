//! Identifiers and small geometric value types shared by the live graph and snapshots.

use bytemuck::{Pod, Zeroable};

/// A node's identifier: stable for the node's whole life, unique in the scene.
///
/// Imported Spark-DSG ids are kept as they are. `u64::MAX` is reserved (it marks
/// "no node" in archived columns) and is rejected by [`crate::SceneGraph::add_node`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Pod, Zeroable)]
#[repr(transparent)]
pub struct NodeId(pub u64);

impl NodeId {
    /// The reserved value that never names a node.
    pub const NONE: NodeId = NodeId(u64::MAX);
}

impl std::fmt::Display for NodeId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// A layer's identifier: dense, assigned by [`crate::SceneGraph::add_layer`], never reused
/// within one graph.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Pod, Zeroable)]
#[repr(transparent)]
pub struct LayerId(pub u32);

impl std::fmt::Display for LayerId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "L{}", self.0)
    }
}

/// A point in the scene's world frame, metres.
pub type Point = [f32; 3];

/// Squared Euclidean distance between two points, accumulated in `f32`.
#[inline]
pub fn distance_squared(a: &Point, b: &Point) -> f32 {
    let dx = a[0] - b[0];
    let dy = a[1] - b[1];
    let dz = a[2] - b[2];
    dx * dx + dy * dy + dz * dz
}

/// An axis-aligned bounding box, inclusive on both ends.
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Point,
    /// Largest corner.
    pub max: Point,
}

impl Aabb {
    /// The box holding exactly one point.
    pub fn from_point(p: Point) -> Self {
        Aabb { min: p, max: p }
    }

    /// The smallest box holding every point, or `None` for no points.
    ///
    /// Runs over the coordinates as one flat array in blocks of eight points, each
    /// coordinate of a block with its own running bound, so the bounds do not wait on
    /// one another (several times faster than growing one box point by point). The
    /// bounds of a block are plain comparisons (`<`, `>`), which compile to the
    /// processor's min and max; like [`f32::min`], they skip a NaN coordinate.
    pub fn from_points(points: &[Point]) -> Option<Self> {
        const LANES: usize = 24;
        let first = *points.first()?;
        let flat: &[f32] = bytemuck::cast_slice(points);
        let blocks = flat.chunks_exact(LANES);
        let rest = blocks.remainder();
        let mut lo = [f32::INFINITY; LANES];
        let mut hi = [f32::NEG_INFINITY; LANES];
        for block in blocks {
            for i in 0..LANES {
                lo[i] = if block[i] < lo[i] { block[i] } else { lo[i] };
                hi[i] = if block[i] > hi[i] { block[i] } else { hi[i] };
            }
        }
        let mut b = Aabb::from_point(first);
        for i in 0..LANES {
            b.min[i % 3] = b.min[i % 3].min(lo[i]);
            b.max[i % 3] = b.max[i % 3].max(hi[i]);
        }
        for p in rest.chunks_exact(3) {
            b.grow(&[p[0], p[1], p[2]]);
        }
        Some(b)
    }

    /// Grows the box to hold `p`.
    pub fn grow(&mut self, p: &Point) {
        for ((lo, hi), c) in self.min.iter_mut().zip(&mut self.max).zip(p) {
            *lo = lo.min(*c);
            *hi = hi.max(*c);
        }
    }

    /// The smallest box holding both boxes.
    pub fn union(&self, other: &Aabb) -> Aabb {
        let mut b = *self;
        b.grow(&other.min);
        b.grow(&other.max);
        b
    }

    /// Whether `p` lies inside the box (bounds inclusive).
    pub fn contains(&self, p: &Point) -> bool {
        (0..3).all(|a| self.min[a] <= p[a] && p[a] <= self.max[a])
    }

    /// Squared distance from `p` to the closest point of the box (0 inside).
    pub fn distance_squared_to(&self, p: &Point) -> f32 {
        let mut d = 0.0;
        for ((lo, hi), c) in self.min.iter().zip(&self.max).zip(p) {
            let v = (lo - c).max(c - hi).max(0.0);
            d += v * v;
        }
        d
    }

    /// The box as the six numbers `[min.x, min.y, min.z, max.x, max.y, max.z]`.
    pub fn to_array(&self) -> [f32; 6] {
        [
            self.min[0],
            self.min[1],
            self.min[2],
            self.max[0],
            self.max[1],
            self.max[2],
        ]
    }

    /// The box from `[min.x, min.y, min.z, max.x, max.y, max.z]`.
    pub fn from_array(a: [f32; 6]) -> Self {
        Aabb {
            min: [a[0], a[1], a[2]],
            max: [a[3], a[4], a[5]],
        }
    }
}

/// The index of the first point with a non-finite coordinate, if any: a flat pass over
/// the coordinates the compiler vectorises, the position only when it fails.
pub(crate) fn first_non_finite(points: &[Point]) -> Option<usize> {
    let flat: &[f32] = bytemuck::cast_slice(points);
    if flat.iter().fold(true, |ok, c| ok & c.is_finite()) {
        return None;
    }
    points.iter().position(|p| !p.iter().all(|c| c.is_finite()))
}

/// The parts of two point lists that differ: the length of their common prefix, then
/// `old` and `new` without their common prefix and suffix (points compared bit for bit).
/// Moving one point of a node, or appending points to it, then costs index and box
/// updates for those points only.
pub(crate) fn point_difference<'o, 'n>(
    old: &'o [Point],
    new: &'n [Point],
) -> (usize, &'o [Point], &'n [Point]) {
    let (a, b): (&[[u32; 3]], &[[u32; 3]]) = (bytemuck::cast_slice(old), bytemuck::cast_slice(new));
    let prefix = prefix_len(a, b);
    let suffix = suffix_len(&a[prefix..], &b[prefix..]);
    (
        prefix,
        &old[prefix..old.len() - suffix],
        &new[prefix..new.len() - suffix],
    )
}

/// Points compared at once by [`prefix_len`] and [`suffix_len`] (a slice comparison of
/// plain integers, which compiles to a memory compare).
const SAME_BLOCK: usize = 32;

/// How many leading points of `a` and `b` are equal.
fn prefix_len(a: &[[u32; 3]], b: &[[u32; 3]]) -> usize {
    let n = a.len().min(b.len());
    let mut k = 0;
    while k + SAME_BLOCK <= n && a[k..k + SAME_BLOCK] == b[k..k + SAME_BLOCK] {
        k += SAME_BLOCK;
    }
    k + a[k..n]
        .iter()
        .zip(&b[k..n])
        .take_while(|(x, y)| x == y)
        .count()
}

/// How many trailing points of `a` and `b` are equal.
fn suffix_len(a: &[[u32; 3]], b: &[[u32; 3]]) -> usize {
    let n = a.len().min(b.len());
    let (ea, eb) = (a.len(), b.len());
    let mut k = 0;
    while k + SAME_BLOCK <= n && a[ea - k - SAME_BLOCK..ea - k] == b[eb - k - SAME_BLOCK..eb - k] {
        k += SAME_BLOCK;
    }
    k + a[..ea - k]
        .iter()
        .rev()
        .zip(b[..eb - k].iter().rev())
        .take_while(|(x, y)| x == y)
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_from_points_equals_growing_one_point_at_a_time() {
        assert_eq!(Aabb::from_points(&[]), None);
        for n in [1, 2, 7, 8, 9, 16, 23, 100] {
            let points: Vec<Point> = (0..n)
                .map(|i| {
                    let t = i as f32;
                    [(t * 7.3).sin() * 5.0, (t * 1.7).cos() - t, t * 0.5 - 3.0]
                })
                .collect();
            let mut want = Aabb::from_point(points[0]);
            for p in &points {
                want.grow(p);
            }
            assert_eq!(Aabb::from_points(&points), Some(want), "{n} points");
        }
    }

    #[test]
    fn point_difference_trims_common_prefix_and_suffix() {
        let a = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        let moved = [[0.0, 0.0, 0.0], [1.5, 0.0, 0.0], [2.0, 0.0, 0.0]];
        assert_eq!(point_difference(&a, &moved), (1, &a[1..2], &moved[1..2]));
        let appended = [a[0], a[1], a[2], [3.0, 0.0, 0.0]];
        let (kept, r, n) = point_difference(&a, &appended);
        assert!(r.is_empty());
        assert_eq!((kept, n), (3, &appended[3..]));
        let (kept, r, n) = point_difference(&a, &a);
        assert!(kept == 3 && r.is_empty() && n.is_empty());
        let (kept, r, n) = point_difference(&a, &[]);
        assert_eq!((kept, r.len(), n.len()), (0, 3, 0));
        // Long lists: one point changed anywhere, compared block by block.
        let long: Vec<Point> = (0..200).map(|i| [i as f32, 0.0, 1.0]).collect();
        for at in [0, 31, 32, 33, 100, 167, 168, 199] {
            let mut moved = long.clone();
            moved[at][2] = 2.0;
            assert_eq!(
                point_difference(&long, &moved),
                (at, &long[at..=at], &moved[at..=at])
            );
        }
        assert_eq!(point_difference(&long, &long[..150]).1, &long[150..]);
        assert_eq!(point_difference(&long[50..], &long).2, &long[..50]);
        // -0.0 and 0.0 differ bit for bit: both are updated.
        let signed = [[-0.0, 0.0, 0.0], a[1], a[2]];
        assert_eq!(point_difference(&a, &signed).1.len(), 1);
    }
}
