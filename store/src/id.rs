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
    pub fn from_points(points: &[Point]) -> Option<Self> {
        let (first, rest) = points.split_first()?;
        let mut b = Aabb::from_point(*first);
        for p in rest {
            b.grow(p);
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

/// The parts of two point lists that differ: `old` and `new` without their common
/// prefix and suffix (points compared bit for bit). Moving one point of a node, or
/// appending points to it, then costs index and box updates for those points only.
pub(crate) fn changed_points<'a>(old: &'a [Point], new: &'a [Point]) -> (&'a [Point], &'a [Point]) {
    let same = |a: &Point, b: &Point| a.map(f32::to_bits) == b.map(f32::to_bits);
    let prefix = old.iter().zip(new).take_while(|(a, b)| same(a, b)).count();
    let (old, new) = (&old[prefix..], &new[prefix..]);
    let suffix = old
        .iter()
        .rev()
        .zip(new.iter().rev())
        .take_while(|(a, b)| same(a, b))
        .count();
    (&old[..old.len() - suffix], &new[..new.len() - suffix])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn changed_points_trims_common_prefix_and_suffix() {
        let a = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        let moved = [[0.0, 0.0, 0.0], [1.5, 0.0, 0.0], [2.0, 0.0, 0.0]];
        assert_eq!(changed_points(&a, &moved), (&a[1..2], &moved[1..2]));
        let appended = [a[0], a[1], a[2], [3.0, 0.0, 0.0]];
        let (r, n) = changed_points(&a, &appended);
        assert!(r.is_empty());
        assert_eq!(n, &appended[3..]);
        let (r, n) = changed_points(&a, &a);
        assert!(r.is_empty() && n.is_empty());
        let (r, n) = changed_points(&a, &[]);
        assert_eq!((r.len(), n.len()), (3, 0));
        // -0.0 and 0.0 differ bit for bit: both are updated.
        let signed = [[-0.0, 0.0, 0.0], a[1], a[2]];
        assert_eq!(changed_points(&a, &signed).0.len(), 1);
    }
}
