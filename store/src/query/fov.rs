//! Field of view: [`visible`] finds the nodes of a sub-tree with a point inside a view
//! cone ([`ConeView`]).

use super::spatial::{SpatialQueryError, check_point};
use crate::index::SpatialIndex;
use crate::{Aabb, NodeId, Point, SceneView, distance_squared};
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

/// A [`ConeView`] checked once ([`ConeView::checked`]) with its unit direction,
/// evaluated in `f64`: the exact point test [`CheckedCone::contains`] and the
/// conservative box test [`CheckedCone::classify`], for testing many points and boxes
/// against one cone.
#[derive(Clone, Debug)]
pub struct CheckedCone {
    eye: [f64; 3],
    dir: [f64; 3],
    cos_half: f64,
    sin_half: f64,
    range2: f64,
    /// `cos` of the half-angle less [`CheckedCone::ANGLE_MARGIN`], when that narrower
    /// cone is convex and not degenerate (for [`CheckedCone::holds`]).
    cos_narrow: Option<f64>,
    /// The squared range less a relative 1e-6 (for [`CheckedCone::holds`]).
    range2_short: f64,
    /// A ball containing the cone: centre and squared radius (`f32`, rounded outward).
    ball: (Point, f32),
}

/// Where a box lies with respect to a view cone ([`CheckedCone::classify`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoxSight {
    /// Every point of the box is outside the cone.
    Outside,
    /// Every point of the box is inside the cone.
    Inside,
    /// Either may be true.
    Maybe,
}

impl ConeView {
    /// The cone checked once, for many point and box tests.
    ///
    /// # Errors
    /// As [`visible`], for an invalid cone.
    pub fn checked(&self) -> Result<CheckedCone, SpatialQueryError> {
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
        let half = f64::from(self.half_angle);
        let cos_half = half.cos();
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
        let narrow = half - CheckedCone::ANGLE_MARGIN;
        let range2 = range * range;
        Ok(CheckedCone {
            eye,
            dir,
            cos_half,
            sin_half: half.sin(),
            range2,
            cos_narrow: (1e-4..=std::f64::consts::FRAC_PI_2 - 1e-4)
                .contains(&narrow)
                .then(|| narrow.cos()),
            range2_short: range2 * (1.0 - 1e-6) * (1.0 - 1e-6),
            ball,
        })
    }
}

/// Sub-trees with fewer points than this are walked even when they carry a node index.
const INDEX_MIN_POINTS: usize = 4096;
/// ... or with at least this many children.
const INDEX_MIN_CHILDREN: usize = 16;

impl CheckedCone {
    /// Margin (radians, and relative distance) far above the rounding of the point test
    /// and of the box tests (about 1e-8 at worst), so that a box is classified only
    /// when it is clearly outside or inside.
    const ANGLE_MARGIN: f64 = 1e-5;

    /// Whether `p` is inside the cone: the one test every path of [`visible`] applies.
    pub fn contains(&self, p: &Point) -> bool {
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

    /// Where box `b` lies with respect to the cone. Conservative: [`BoxSight::Outside`]
    /// and [`BoxSight::Inside`] only when provable with margins far above the rounding
    /// of [`CheckedCone::contains`], so they never contradict it on any point of the
    /// box; [`BoxSight::Maybe`] otherwise.
    ///
    /// # Complexity
    /// O(1): a few dozen floating-point operations (eight corner tests for `Inside`).
    ///
    /// # Examples
    /// ```
    /// # use ygg_store::{Aabb, query::{BoxSight, ConeView}};
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// let cone = ConeView { eye: [0.0; 3], dir: [1.0, 0.0, 0.0], half_angle: 0.5, range: 10.0 }.checked()?;
    /// let boxed = |lo, hi| Aabb::from_points(&[lo, hi]).expect("two points");
    /// assert_eq!(cone.classify(&boxed([4.0, -0.1, -0.1], [5.0, 0.1, 0.1])), BoxSight::Inside);
    /// assert_eq!(cone.classify(&boxed([-5.0, -1.0, -1.0], [-4.0, 1.0, 1.0])), BoxSight::Outside);
    /// assert_eq!(cone.classify(&boxed([9.0, -1.0, -1.0], [11.0, 1.0, 1.0])), BoxSight::Maybe);
    /// # Ok(()) }
    /// ```
    pub fn classify(&self, b: &Aabb) -> BoxSight {
        if !self.may_see(b) {
            BoxSight::Outside
        } else if self.holds(b) {
            BoxSight::Inside
        } else {
            BoxSight::Maybe
        }
    }

    /// Whether some point of box `b` may be inside the cone (false only when provably
    /// none is): the box misses the ball enclosing the cone, lies beyond the range, or
    /// its enclosing sphere lies wholly outside the cone's angle.
    fn may_see(&self, b: &Aabb) -> bool {
        let (centre, ball2) = self.ball;
        if b.distance_squared_to(&centre) > ball2 {
            return false;
        }
        // Range: the box's closest point is farther than the range.
        if box_distance2(b, &self.eye) > self.range2 {
            return false;
        }
        // Angle: the ball around the box (centre c, radius rho) against the cone. With
        // v = c - eye split into `axial` along the direction and `radial` across it,
        // every point outside the cone at angle theta > half from the axis lies at least
        // |v| sin(theta - half) = radial cos(half) - axial sin(half) from the cone, so a
        // ball whose centre is farther than rho (plus a margin) from it lies outside.
        let mut v = [0.0; 3];
        let mut rho2 = 0.0;
        for (a, va) in v.iter_mut().enumerate() {
            let (lo, hi) = (f64::from(b.min[a]), f64::from(b.max[a]));
            *va = (lo + hi) / 2.0 - self.eye[a];
            rho2 += (hi - lo) * (hi - lo) / 4.0;
        }
        let len2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        let axial = v[0] * self.dir[0] + v[1] * self.dir[1] + v[2] * self.dir[2];
        let radial = (len2 - axial * axial).max(0.0).sqrt();
        let gap = radial * self.cos_half - axial * self.sin_half;
        gap <= rho2.sqrt() * (1.0 + 1e-9) + Self::ANGLE_MARGIN * len2.sqrt()
    }

    /// Whether every point of box `b` is inside the cone. For a half-angle of at most
    /// 90° the cone cut by the range ball is convex, so it holds the box when it holds
    /// its eight corners; the corners are tested against a cone narrower by
    /// [`CheckedCone::ANGLE_MARGIN`] and shorter by a relative 1e-6.
    fn holds(&self, b: &Aabb) -> bool {
        let Some(cos_h) = self.cos_narrow else {
            return false;
        };
        (0..8u32).all(|corner| {
            let pick = |a: usize| {
                let c = if corner >> a & 1 == 1 {
                    b.max[a]
                } else {
                    b.min[a]
                };
                f64::from(c) - self.eye[a]
            };
            let v = [pick(0), pick(1), pick(2)];
            let d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            if d2 > self.range2_short {
                return false;
            }
            let dot = v[0] * self.dir[0] + v[1] * self.dir[1] + v[2] * self.dir[2];
            d2 == 0.0 || dot >= cos_h * d2.sqrt()
        })
    }
}

/// Squared distance from `eye` to box `b`, evaluated like the cone's range test (per
/// axis differences exact in `f64`, squares summed in the same order), so that a box
/// farther than the range proves every point inside it farther too.
fn box_distance2(b: &Aabb, eye: &[f64; 3]) -> f64 {
    let v = [0, 1, 2].map(|a| {
        let (lo, hi) = (f64::from(b.min[a]), f64::from(b.max[a]));
        if eye[a] < lo {
            lo - eye[a]
        } else if eye[a] > hi {
            eye[a] - hi
        } else {
            0.0
        }
    });
    v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
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
        if view.aabb(n).is_some_and(|b| !cone.may_see(&b)) {
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
        stack.extend(view.children(n).filter_map(|ch| view.node(ch)));
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

    #[test]
    fn box_classes_never_contradict_the_point_test() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let (mut outside, mut inside) = (0, 0);
        for _ in 0..20_000 {
            let lo: Point = [0, 1, 2].map(|_| rng.gen_range(-5.0..5.0));
            let size: Point = [0, 1, 2].map(|_| rng.gen_range(0.0..2.0));
            let hi: Point = [0, 1, 2].map(|a| lo[a] + size[a]);
            let b = Aabb::from_points(&[lo, hi]).unwrap();
            let view = ConeView {
                eye: [0, 1, 2].map(|_| rng.gen_range(-6.0..6.0)),
                dir: [0, 1, 2].map(|_| rng.gen_range(-1.0..1.0)),
                half_angle: rng
                    .gen_range(0.0f32..180.0)
                    .to_radians()
                    .min(std::f32::consts::PI),
                range: rng.gen_range(0.0..12.0),
            };
            let Ok(cone) = view.checked() else {
                continue;
            };
            let sight = cone.classify(&b);
            outside += usize::from(sight == BoxSight::Outside);
            inside += usize::from(sight == BoxSight::Inside);
            for i in 0..64 {
                let p: Point = if i < 8 {
                    [0, 1, 2].map(|a| if i >> a & 1 == 1 { hi[a] } else { lo[a] })
                } else {
                    [0, 1, 2].map(|a| rng.gen_range(lo[a]..=hi[a]))
                };
                if cone.contains(&p) {
                    assert!(sight != BoxSight::Outside, "{view:?} sees {p:?} in {b:?}");
                } else {
                    assert!(sight != BoxSight::Inside, "{view:?} misses {p:?} in {b:?}");
                }
            }
        }
        assert!(
            outside > 5_000,
            "the test should exercise Outside: {outside}"
        );
        assert!(inside > 200, "the test should exercise Inside: {inside}");
    }

    #[test]
    fn box_distance_is_zero_inside() {
        let b = Aabb::from_points(&[[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]]).unwrap();
        assert_eq!(box_distance2(&b, &[0.5, 0.5, 0.5]), 0.0);
        assert_eq!(box_distance2(&b, &[3.0, 2.0, 3.0]), 4.0);
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
