//! Field of view: [`visible`] finds the nodes of a sub-tree with a point inside a view
//! cone ([`ConeView`]).

use super::spatial::{SpatialQueryError, check_point};
use crate::index::SpatialIndex;
use crate::{NodeId, Point, SceneView, distance_squared};
use rustc_hash::FxHashSet;

/// A view volume: the points within `range` of `eye` whose direction from `eye` makes an
/// angle of at most `half_angle` with `dir`. Both bounds are inclusive.
///
/// A point exactly at `eye` is inside (its direction is undefined). A `half_angle` of
/// `π` sees the whole ball; a `range` of 0 sees only `eye` itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConeView {
    /// The apex (the observer's position).
    pub eye: Point,
    /// The viewing direction: a unit vector (any finite non-zero vector is normalised).
    pub dir: Point,
    /// Half of the opening angle, radians, in `[0, π]`.
    pub half_angle: f32,
    /// How far the view reaches, metres, `>= 0`.
    pub range: f32,
}

/// A checked cone with a unit direction, evaluated in `f64`.
struct Cone {
    eye: [f64; 3],
    dir: [f64; 3],
    cos_half: f64,
    range2: f64,
    /// A ball containing the cone: centre and squared radius (`f32`, rounded outward).
    ball: (Point, f32),
}

impl ConeView {
    fn checked(&self) -> Result<Cone, SpatialQueryError> {
        check_point(&self.eye)?;
        let d = self.dir.map(f64::from);
        let norm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        if !(norm.is_finite() && norm > 0.0) {
            return Err(SpatialQueryError::InvalidDirection(self.dir));
        }
        let dir = d.map(|v| v / norm);
        if !(self.half_angle.is_finite() && (0.0..=std::f32::consts::PI).contains(&self.half_angle))
        {
            return Err(SpatialQueryError::InvalidHalfAngle(self.half_angle));
        }
        if !(self.range.is_finite() && self.range >= 0.0) {
            return Err(SpatialQueryError::InvalidRange(self.range));
        }
        let eye = self.eye.map(f64::from);
        let cos_half = f64::from(self.half_angle).cos();
        let range = f64::from(self.range);
        // A cone narrower than 60° fits in the ball through its apex and rim, centred
        // on the axis at range / (2 cos θ); a wider one in the ball of radius range.
        let (centre, radius) = if cos_half > 0.5 {
            let t = range / (2.0 * cos_half);
            ([0, 1, 2].map(|a| eye[a] + dir[a] * t), t)
        } else {
            (eye, range)
        };
        let extent = centre.iter().fold(radius, |m, v| m.max(v.abs()));
        let radius = radius * (1.0 + 1e-4) + extent * 1e-5 + 1e-30;
        let ball = (
            centre.map(|v| v as f32),
            (radius * radius) as f32 * (1.0 + 1e-4),
        );
        Ok(Cone {
            eye,
            dir,
            cos_half,
            range2: range * range,
            ball,
        })
    }
}

/// Sub-trees with fewer points than this are walked even when they carry a node index.
const INDEX_MIN_POINTS: usize = 4096;
/// ... or with at least this many children.
const INDEX_MIN_CHILDREN: usize = 16;

impl Cone {
    /// Whether some point of box `b` may lie inside the cone: false only when none can.
    /// Two conservative tests: the box misses the ball enclosing the cone, or the
    /// sphere around the box lies wholly outside the cone's angle (the angle between
    /// the axis and any direction into the sphere is at least the angle to the sphere's
    /// centre less the sphere's angular radius).
    fn may_hit(&self, b: &crate::Aabb) -> bool {
        let (centre, ball2) = self.ball;
        if b.distance_squared_to(&centre) > ball2 {
            return false;
        }
        let c = [0, 1, 2].map(|a| (f64::from(b.min[a]) + f64::from(b.max[a])) / 2.0);
        let half = [0, 1, 2].map(|a| (f64::from(b.max[a]) - f64::from(b.min[a])) / 2.0);
        let radius = (half[0] * half[0] + half[1] * half[1] + half[2] * half[2]).sqrt()
            * (1.0 + 1e-9)
            + 1e-9;
        let v = [0, 1, 2].map(|a| c[a] - self.eye[a]);
        let d = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if d <= radius {
            return true;
        }
        let cos_axis =
            ((v[0] * self.dir[0] + v[1] * self.dir[1] + v[2] * self.dir[2]) / d).clamp(-1.0, 1.0);
        let to_centre = cos_axis.acos();
        let spread = (radius / d).asin();
        to_centre - spread <= self.cos_half.acos() + 1e-9
    }

    /// Whether `p` is inside the cone (the one test every path uses).
    fn contains(&self, p: &Point) -> bool {
        let v = [0, 1, 2].map(|a| f64::from(p[a]) - self.eye[a]);
        let d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        if d2 > self.range2 {
            return false;
        }
        if d2 == 0.0 {
            return true;
        }
        let dot = v[0] * self.dir[0] + v[1] * self.dir[1] + v[2] * self.dir[2];
        dot >= self.cos_half * d2.sqrt()
    }
}

/// Nodes of `root`'s sub-tree (`root` included) with at least one point inside the view
/// cone `view`.
///
/// # Arguments
/// * `view` – a live graph or an archived snapshot (the scene view, not the cone).
/// * `root` – the sub-tree's root, e.g. the room the observer is in (an unknown root
///   gives an empty answer).
/// * `cone` – eye, unit direction, half-angle and range; bounds inclusive.
///
/// # Returns
/// Node ids, ascending.
///
/// # Errors
/// [`SpatialQueryError::NonFinitePoint`] (eye), [`SpatialQueryError::InvalidDirection`]
/// (zero or non-finite direction), [`SpatialQueryError::InvalidHalfAngle`],
/// [`SpatialQueryError::InvalidRange`].
///
/// # Complexity
/// With a node index on `root` (or on nodes below it): a kd-tree range search over a
/// ball enclosing the cone, then the exact cone test on the points found. Otherwise a
/// walk of the sub-tree that skips sub-trees whose bounding box misses that ball.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, query::{visible, ConeView}};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let (rooms, objects) = (g.add_layer("rooms")?, g.add_layer("objects")?);
/// g.add_layer_edge(rooms, objects)?;
/// g.add_node(NodeId(1), rooms)?;
/// for (id, p) in [(10, [2.0, 0.0, 0.0]), (11, [0.0, 2.0, 0.0]), (12, [9.0, 0.0, 0.0])] {
///     g.add_node(NodeId(id), objects)?;
///     g.set_geometry(NodeId(id), vec![p])?;
///     g.nest(NodeId(1), NodeId(id))?;
/// }
/// g.enable_node_index(NodeId(1))?;
/// let cone = ConeView { eye: [0.0; 3], dir: [1.0, 0.0, 0.0], half_angle: 0.5, range: 5.0 };
/// assert_eq!(visible(&g, NodeId(1), &cone)?, vec![NodeId(10)]);
/// assert_eq!(visible(&g.to_snapshot().view(), NodeId(1), &cone)?, vec![NodeId(10)]);
/// # Ok(()) }
/// ```
pub fn visible<V: SceneView>(
    view: &V,
    root: NodeId,
    cone: &ConeView,
) -> Result<Vec<NodeId>, SpatialQueryError> {
    let cone = cone.checked()?;
    let Some(r) = view.node(root) else {
        return Ok(Vec::new());
    };
    let (centre, ball2) = cone.ball;
    let mut out = Vec::new();
    let mut stack = vec![r];
    let mut seen = FxHashSet::default();
    while let Some(n) = stack.pop() {
        let id = view.node_id(n);
        if !seen.insert(id) {
            continue; // only a damaged snapshot can nest a node twice
        }
        if view.aabb(n).is_some_and(|b| !cone.may_hit(&b)) {
            continue;
        }
        // A kd-tree pays off for sub-trees with many points or many nodes; a small one is
        // cheaper to walk, and the walk stops at a node's first visible point.
        let worth_it = |i: &_| {
            view.children(n).len() >= INDEX_MIN_CHILDREN || SpatialIndex::len(i) >= INDEX_MIN_POINTS
        };
        if let Some(index) = view.node_index(id).filter(worth_it) {
            let mut items = Vec::new();
            let prefetch = super::spatial::prefetches_ids(&index);
            index.points_within(&centre, ball2, |_, item, p| {
                if cone.contains(p) {
                    if prefetch {
                        index.prefetch_node(item);
                    }
                    items.push(item);
                }
            });
            items.sort_unstable();
            items.dedup();
            out.extend(items.into_iter().filter_map(|i| index.node_of(i)));
            continue;
        }
        if view
            .points(n)
            .iter()
            .any(|p| distance_squared(p, &centre) <= ball2 && cone.contains(p))
        {
            out.push(id);
        }
        stack.extend(view.children(n).iter().filter_map(|&ch| view.node(ch)));
    }
    out.sort_unstable();
    out.dedup();
    Ok(out)
}

/// Whether `index` holds a point inside the cone (the test of [`visible`]): one radius
/// search over the ball around the cone, testing points against the cone only until
/// the first one inside.
///
/// # Errors
/// As [`visible`].
pub fn index_sees<I: SpatialIndex>(index: &I, cone: &ConeView) -> Result<bool, SpatialQueryError> {
    let cone = cone.checked()?;
    let (centre, ball2) = cone.ball;
    let mut hit = false;
    index.points_within(&centre, ball2, |_, _, p| {
        hit = hit || cone.contains(p);
    });
    Ok(hit)
}

impl ConeView {
    /// Whether `p` is inside the cone: exactly the test [`visible`] applies to every
    /// point.
    ///
    /// # Errors
    /// As [`visible`], for an invalid cone.
    pub fn contains(&self, p: &Point) -> Result<bool, SpatialQueryError> {
        Ok(self.checked()?.contains(p))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cone(dir: Point, half_angle: f32, range: f32) -> ConeView {
        ConeView {
            eye: [1.0, 2.0, 3.0],
            dir,
            half_angle,
            range,
        }
    }

    #[test]
    fn invalid_views_are_errors() {
        let bad = [
            cone([0.0; 3], 0.5, 1.0),
            cone([f32::NAN, 0.0, 0.0], 0.5, 1.0),
            cone([f32::INFINITY, 1.0, 0.0], 0.5, 1.0),
            cone([1.0, 0.0, 0.0], -0.1, 1.0),
            cone([1.0, 0.0, 0.0], 3.5, 1.0),
            cone([1.0, 0.0, 0.0], f32::INFINITY, 1.0),
            cone([1.0, 0.0, 0.0], 0.5, -1.0),
            cone([1.0, 0.0, 0.0], 0.5, f32::NAN),
            ConeView {
                eye: [f32::INFINITY, 0.0, 0.0],
                ..cone([1.0, 0.0, 0.0], 0.5, 1.0)
            },
        ];
        for c in bad {
            assert!(c.checked().is_err(), "{c:?}");
        }
        // A tiny direction is still a direction (normalised in f64, where 1e-30² is not 0).
        let tiny = cone([1e-30, 0.0, 0.0], 0.5, 1.0).checked().unwrap();
        assert_eq!(tiny.dir, [1.0, 0.0, 0.0]);
    }

    #[test]
    fn the_bounding_ball_contains_the_cone() {
        let views = [
            cone([1.0, 0.0, 0.0], 0.1, 5.0),
            cone([1.0, 1.0, 0.0], 1.0, 3.0),
            cone([0.0, 0.0, -1.0], 1.5, 2.0),
            cone([0.3, -0.2, 0.9], 3.0, 7.0),
        ];
        for v in views {
            let c = v.checked().unwrap();
            for i in 0..2000 {
                // Points along rays inside the cone at several depths.
                let t = i as f32 / 2000.0;
                let a = t * v.half_angle;
                let b = t * 37.0;
                let (u, w) = perpendiculars(&c.dir);
                let dir = [0, 1, 2].map(|k| {
                    (c.dir[k] * f64::from(a).cos()
                        + (u[k] * f64::from(b).cos() + w[k] * f64::from(b).sin())
                            * f64::from(a).sin()) as f32
                });
                let p = [0, 1, 2].map(|k| v.eye[k] + dir[k] * v.range * (i % 7) as f32 / 6.0);
                if c.contains(&p) {
                    assert!(distance_squared(&p, &c.ball.0) <= c.ball.1, "{v:?} {p:?}");
                }
            }
        }
    }

    fn perpendiculars(d: &[f64; 3]) -> ([f64; 3], [f64; 3]) {
        let a = if d[0].abs() < 0.9 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 1.0, 0.0]
        };
        let u = [
            d[1] * a[2] - d[2] * a[1],
            d[2] * a[0] - d[0] * a[2],
            d[0] * a[1] - d[1] * a[0],
        ];
        let n = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
        let u = u.map(|v| v / n);
        let w = [
            d[1] * u[2] - d[2] * u[1],
            d[2] * u[0] - d[0] * u[2],
            d[0] * u[1] - d[1] * u[0],
        ];
        (u, w)
    }
}
