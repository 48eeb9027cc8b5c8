//! Nearest-neighbour and radius queries: [`nearest_nodes`], [`nodes_within_radius`] and
//! [`nearest_in_subtree`] over a view, and [`nearest_in_index`] / [`within_index`] over
//! one [`SpatialIndex`] (for example one a reader built with
//! [`crate::index::build_layer_index`]).
//!
//! # Semantics
//! - A node's squared distance to `c` is the smallest [`distance_squared`]`(p, c)` over
//!   its points `p` (in `f32`); its **distance** is the square root of that. Nodes
//!   without points are never returned.
//! - A node is **within** `r` of `c` when it has a point `p` with
//!   [`within_radius`]`(p, c, r)`, i.e. `distance_squared(p, c).sqrt() <= r`.
//! - Ranked results ascend by squared distance; nodes at exactly the same squared
//!   distance go to the smaller [`NodeId`].
//!
//! Indexed and scanning paths compute distances with the same expression
//! ([`crate::distance_squared`]), so they agree bit for bit; a brute-force baseline built
//! on these definitions gets the same answers.

use crate::index::SpatialIndex;
use crate::{NodeId, Point, Points, SceneView, Scope, distance_squared};
use rustc_hash::{FxHashMap, FxHashSet};

/// Why a spatial query refused its input. Queries never panic on bad input.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum SpatialQueryError {
    /// A query point (or view eye) has a NaN or infinite coordinate.
    #[error("point {0:?} has a non-finite coordinate")]
    NonFinitePoint(Point),
    /// A radius is negative, NaN or infinite.
    #[error("radius {0} is negative or not finite")]
    InvalidRadius(f32),
    /// A view direction is zero, too small to normalise, or not finite.
    #[error("view direction {0:?} is zero or not finite")]
    InvalidDirection(Point),
    /// A view half-angle is outside `[0, π]` or not finite.
    #[error("half-angle {0} is not in [0, π] radians")]
    InvalidHalfAngle(f32),
    /// A view range is negative, NaN or infinite.
    #[error("range {0} is negative or not finite")]
    InvalidRange(f32),
}

pub(crate) fn check_point(c: &Point) -> Result<(), SpatialQueryError> {
    if c.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(SpatialQueryError::NonFinitePoint(*c))
    }
}

/// Whether `p` lies within distance `r` of `c`: exactly the test
/// [`nodes_within_radius`] applies to every point (false for an invalid radius).
pub fn within_radius(p: &Point, c: &Point, r: f32) -> bool {
    r.is_finite() && r >= 0.0 && distance_squared(p, c) <= radius_bound(r)
}

/// The largest squared distance `d2` with `d2.sqrt() <= r`, so that [`within_radius`]
/// is exactly "`distance_squared <= radius_bound(r)`" (`sqrt` is monotone).
pub fn radius_bound(r: f32) -> f32 {
    let mut x = r * r;
    if !x.is_finite() {
        return f32::MAX;
    }
    while x > 0.0 && x.sqrt() > r {
        x = x.next_down();
    }
    while x < f32::MAX && x.next_up().sqrt() <= r {
        x = x.next_up();
    }
    x
}

/// Up to this many entries, [`Best`] keeps a sorted vector; beyond, a map of every key
/// offered with a lazily refreshed bound.
const SMALL_M: usize = 64;

/// The best `m` keys seen so far, by squared distance and then by `before` (the order
/// of keys at equal distance). A key may be offered several times (once per point); it
/// counts with its smallest squared distance.
pub(crate) struct Best<K, T> {
    m: usize,
    /// `m <= SMALL_M`: the best keys, ascending, each once.
    small: Vec<(f32, K)>,
    /// `m > SMALL_M`: every key offered, with its smallest squared distance.
    all: FxHashMap<K, f32>,
    /// `m > SMALL_M`: the `m`-th smallest value of `all` when last refreshed (it can only
    /// have dropped since, so it stays an upper bound of the current `m`-th smallest).
    bound: f32,
    refresh_at: usize,
    before: T,
}

/// The best `m` nodes; equal distances go to the smaller id.
pub(crate) type TopNodes = Best<NodeId, fn(NodeId, NodeId) -> bool>;

pub(crate) fn top_nodes(m: usize) -> TopNodes {
    Best::new(m, |a, b| a < b)
}

impl<K: Copy + Eq + std::hash::Hash, T: Fn(K, K) -> bool> Best<K, T> {
    pub(crate) fn new(m: usize, before: T) -> Self {
        Best {
            m,
            small: Vec::with_capacity(if m <= SMALL_M { m + 1 } else { 0 }),
            all: FxHashMap::default(),
            bound: f32::INFINITY,
            refresh_at: m,
            before,
        }
    }

    fn less(&self, a: &(f32, K), b: &(f32, K)) -> bool {
        match a.0.total_cmp(&b.0) {
            std::cmp::Ordering::Less => true,
            std::cmp::Ordering::Greater => false,
            std::cmp::Ordering::Equal => (self.before)(a.1, b.1),
        }
    }

    pub(crate) fn offer(&mut self, d2: f32, key: K) {
        if self.m == 0 {
            return;
        }
        if self.m > SMALL_M {
            let e = self.all.entry(key).or_insert(f32::INFINITY);
            if d2 < *e {
                *e = d2;
            }
            if self.all.len() >= self.refresh_at {
                let mut v: Vec<f32> = self.all.values().copied().collect();
                let (_, kth, _) = v.select_nth_unstable_by(self.m - 1, f32::total_cmp);
                self.bound = *kth;
                self.refresh_at = self.all.len() * 2;
            }
            return;
        }
        let e = (d2, key);
        if let Some(i) = self.small.iter().position(|x| x.1 == key) {
            if d2 >= self.small[i].0 {
                return;
            }
            self.small.remove(i);
        } else if self.small.len() == self.m && !self.less(&e, &self.small[self.m - 1]) {
            return;
        }
        let at = self.small.partition_point(|x| self.less(x, &e));
        self.small.insert(at, e);
        self.small.truncate(self.m);
    }

    /// A squared distance beyond which nothing can enter any more (`+∞` until `m` keys
    /// were seen).
    pub(crate) fn bound(&self) -> f32 {
        if self.m > SMALL_M {
            self.bound
        } else if self.small.len() == self.m {
            self.small[self.m - 1].0
        } else {
            f32::INFINITY
        }
    }

    /// Whether nothing at squared distance `>= min_d2` can still enter.
    pub(crate) fn prunes(&self, min_d2: f32) -> bool {
        self.m == 0 || min_d2 > self.bound()
    }

    /// The best `m` `(squared distance, key)` pairs, ascending.
    pub(crate) fn into_sorted(mut self) -> Vec<(f32, K)> {
        if self.m > SMALL_M {
            let mut all: Vec<(f32, K)> = self.all.drain().map(|(k, d2)| (d2, k)).collect();
            all.sort_unstable_by(|a, b| {
                if self.less(a, b) {
                    std::cmp::Ordering::Less
                } else if self.less(b, a) {
                    std::cmp::Ordering::Greater
                } else {
                    std::cmp::Ordering::Equal
                }
            });
            all.truncate(self.m);
            return all;
        }
        self.small
    }
}

impl TopNodes {
    /// `(node, distance)` pairs, ascending.
    pub(crate) fn into_vec(self) -> Vec<(NodeId, f32)> {
        self.into_sorted()
            .into_iter()
            .map(|(d2, id)| (id, d2.sqrt()))
            .collect()
    }
}

/// Offers the best `top.m` nodes of `index` near `c` to `top`: one branch-and-bound
/// pass over items (which name nodes one to one), bounded by the current `m`-th best;
/// an item's node is looked up only to break an exact tie and for the final `m`.
pub(crate) fn index_nearest<I: SpatialIndex>(index: &I, c: &Point, top: &mut TopNodes) {
    if top.m == 0 {
        return;
    }
    if top.m == 1 {
        if let Some((d2, id)) = index_nearest_one(index, c) {
            top.offer(d2, id);
        }
        return;
    }
    let mut items = Best::new(top.m, |a: u32, b: u32| index.node_of(a) < index.node_of(b));
    index.nearest_visit(c, |d2, item| {
        items.offer(d2, item);
        items.bound()
    });
    for (d2, item) in items.into_sorted() {
        if let Some(id) = index.node_of(item) {
            top.offer(d2, id);
        }
    }
}

/// The node of `index` nearest to `c` with its squared distance (ties to the smaller
/// id): [`index_nearest`] for `m = 1`, without the bookkeeping of [`Best`].
fn index_nearest_one<I: SpatialIndex>(index: &I, c: &Point) -> Option<(f32, NodeId)> {
    let mut best: Option<(f32, u32)> = None;
    index.nearest_visit(c, |d2, item| {
        let better = best.is_none_or(|(bd, bi)| {
            d2 < bd || (d2 == bd && item != bi && index.node_of(item) < index.node_of(bi))
        });
        if better {
            best = Some((d2, item));
        }
        best.map_or(f32::INFINITY, |b| b.0)
    });
    let (d2, item) = best?;
    Some((d2, index.node_of(item)?))
}

/// The node of `scope` nearest to `c` with its squared distance (ties to the smaller
/// id): exactly what [`nearest_nodes`] answers for `m = 1`, without allocating a
/// [`Best`].
fn nearest_node<V: SceneView>(view: &V, scope: Scope, c: &Point) -> Option<(f32, NodeId)> {
    let mut best: Option<(f32, NodeId)> = None;
    let offer = |best: &mut Option<(f32, NodeId)>, d2: f32, id: NodeId| {
        if best.is_none_or(|(bd, bid)| d2.total_cmp(&bd).then(id.cmp(&bid)).is_lt()) {
            *best = Some((d2, id));
        }
    };
    for layer in view.layers().filter(|&l| scope.contains(l)) {
        if let Some(index) = view.layer_index(layer) {
            if let Some((d2, id)) = index_nearest_one(&index, c) {
                offer(&mut best, d2, id);
            }
            continue;
        }
        for n in view.layer_nodes(layer) {
            let pruned = |b: crate::Aabb| best.is_some_and(|(bd, _)| b.distance_squared_to(c) > bd);
            if view.aabb(n).is_some_and(pruned) {
                continue;
            }
            // The id is read only for a node that can win (ties go to the smaller id).
            if let Some(d2) = node_distance2(view, n, c)
                && best.is_none_or(|(bd, _)| d2.total_cmp(&bd).is_le())
            {
                offer(&mut best, d2, view.node_id(n));
            }
        }
    }
    best
}

/// Whether a search of `index` that maps many items to nodes should prefetch their
/// id-table entries as it finds them ([`SpatialIndex::prefetch_node`]): in indexes of
/// 2^16 points and more, where the table no longer sits in cache (large radius queries
/// at 1M points: archived 1.33–1.38× → 1.10–1.28× bare kiddo; live 1.06–1.18× →
/// 0.81–0.88×, together with the live tree's prefetching of far cells).
pub(crate) fn prefetches_ids<I: SpatialIndex>(index: &I) -> bool {
    index.len() >= 1 << 16
}

/// Pushes the node of every point of `index` with `distance_squared <= r2`.
fn index_within<I: SpatialIndex>(index: &I, c: &Point, r2: f32, out: &mut Vec<NodeId>) {
    let mut items = Vec::new();
    let prefetch = prefetches_ids(index);
    index.points_within(c, r2, |_, item, _| {
        if prefetch {
            index.prefetch_node(item);
        }
        items.push(item);
    });
    items.sort_unstable();
    items.dedup();
    out.extend(items.into_iter().filter_map(|i| index.node_of(i)));
}

/// A node's squared distance to `c` (`None` without points).
fn node_distance2<'a, V: SceneView>(view: &'a V, n: V::NodeRef<'a>, c: &Point) -> Option<f32> {
    points_distance2(view.points(n), c)
}

/// The smallest squared distance from `points` to `c` (`None` for no points): a plain
/// loop over each contiguous run.
#[inline]
fn points_distance2(points: Points<'_>, c: &Point) -> Option<f32> {
    let nearest = |run: &[Point]| {
        run.iter()
            .map(|p| distance_squared(p, c))
            .min_by(f32::total_cmp)
    };
    match points.unchunked() {
        Some(run) => nearest(run),
        None => points.runs().filter_map(nearest).min_by(f32::total_cmp),
    }
}

/// Whether a point of `points` lies within squared distance `r2` of `c`.
fn points_within(points: Points<'_>, c: &Point, r2: f32) -> bool {
    let any = |run: &[Point]| run.iter().any(|p| distance_squared(p, c) <= r2);
    match points.unchunked() {
        Some(run) => any(run),
        None => points.runs().any(any),
    }
}

/// At most `m` nodes in `scope` closest to `c`, with their distances.
///
/// # Arguments
/// * `view` – a live graph or an archived snapshot.
/// * `scope` – the whole graph or one layer.
/// * `c` – the query point.
/// * `m` – how many nodes at most (`m` larger than the number of nodes with points
///   returns them all; 0 returns none).
///
/// # Returns
/// `(node, distance)` pairs, ascending by distance; nodes at the same squared distance go
/// to the smaller id (see the module docs for the exact semantics).
///
/// # Errors
/// [`SpatialQueryError::NonFinitePoint`] if `c` has a NaN or infinite coordinate.
///
/// # Complexity
/// Per layer with a layer index: a kd-tree k-nearest search, O(log n + m) for nodes
/// with one point. Per layer without: a scan of its nodes, skipping nodes whose bounding
/// box is already farther than the `m`-th best.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, Scope, query::nearest_nodes};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let places = g.add_layer("places")?;
/// for (id, x) in [(1, 3.0), (2, 1.0), (3, -1.0)] {
///     g.add_node(NodeId(id), places)?;
///     g.set_geometry(NodeId(id), vec![[x, 0.0, 0.0]])?;
/// }
/// g.enable_layer_index(places)?;
/// let want = vec![(NodeId(2), 1.0), (NodeId(3), 1.0)]; // a tie: smaller id first
/// assert_eq!(nearest_nodes(&g, Scope::Layer(places), [0.0, 0.0, 0.0], 2)?, want);
/// let snapshot = g.to_snapshot();
/// assert_eq!(nearest_nodes(&snapshot.view(), Scope::Graph, [0.0, 0.0, 0.0], 2)?, want);
/// # Ok(()) }
/// ```
pub fn nearest_nodes<V: SceneView>(
    view: &V,
    scope: Scope,
    c: Point,
    m: usize,
) -> Result<Vec<(NodeId, f32)>, SpatialQueryError> {
    check_point(&c)?;
    if m == 1 {
        return Ok(nearest_node(view, scope, &c)
            .map(|(d2, id)| vec![(id, d2.sqrt())])
            .unwrap_or_default());
    }
    let mut top = top_nodes(m);
    if m == 0 {
        return Ok(Vec::new());
    }
    for layer in scope.iter(view) {
        if let Some(index) = view.layer_index(layer) {
            index_nearest(&index, &c, &mut top);
            continue;
        }
        for n in view.layer_nodes(layer) {
            if view
                .aabb(n)
                .is_some_and(|b| top.prunes(b.distance_squared_to(&c)))
            {
                continue;
            }
            if let Some(d2) = node_distance2(view, n, &c) {
                top.offer(d2, view.node_id(n));
            }
        }
    }
    Ok(top.into_vec())
}

/// Nodes in `scope` with a point at distance `<= r` from `c`.
///
/// # Arguments
/// * `view` – a live graph or an archived snapshot.
/// * `scope` – the whole graph or one layer.
/// * `c` – the centre.
/// * `r` – the radius (inclusive; 0 finds nodes with a point exactly at `c`).
///
/// # Returns
/// Node ids, ascending.
///
/// # Errors
/// [`SpatialQueryError::NonFinitePoint`] for a non-finite `c`,
/// [`SpatialQueryError::InvalidRadius`] for a negative or non-finite `r`.
///
/// # Complexity
/// Per layer with a layer index: a kd-tree range search, O(log n + k log k) for k points
/// found. Per layer without: a scan of its nodes, skipping nodes whose bounding box lies
/// outside the ball.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, Scope, query::nodes_within_radius};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let objects = g.add_layer("objects")?;
/// g.add_node(NodeId(7), objects)?;
/// g.set_geometry(NodeId(7), vec![[5.0, 0.0, 0.0], [0.5, 0.0, 0.0]])?; // two points
/// g.add_node(NodeId(8), objects)?;
/// g.set_geometry(NodeId(8), vec![[2.0, 0.0, 0.0]])?;
/// g.enable_layer_index(objects)?;
/// assert_eq!(nodes_within_radius(&g, Scope::Graph, [0.0, 0.0, 0.0], 1.0)?, vec![NodeId(7)]);
/// let snapshot = g.to_snapshot();
/// let found = nodes_within_radius(&snapshot.view(), Scope::Layer(objects), [0.0, 0.0, 0.0], 2.0)?;
/// assert_eq!(found, vec![NodeId(7), NodeId(8)]);
/// # Ok(()) }
/// ```
pub fn nodes_within_radius<V: SceneView>(
    view: &V,
    scope: Scope,
    c: Point,
    r: f32,
) -> Result<Vec<NodeId>, SpatialQueryError> {
    check_point(&c)?;
    if !(r.is_finite() && r >= 0.0) {
        return Err(SpatialQueryError::InvalidRadius(r));
    }
    let r2 = radius_bound(r);
    let mut out = Vec::new();
    for layer in scope.iter(view) {
        if let Some(index) = view.layer_index(layer) {
            index_within(&index, &c, r2, &mut out);
            continue;
        }
        for n in view.layer_nodes(layer) {
            if view.aabb(n).is_some_and(|b| b.distance_squared_to(&c) > r2) {
                continue;
            }
            if points_within(view.points(n), &c, r2) {
                out.push(view.node_id(n));
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    Ok(out)
}

/// At most `m` nodes of `root`'s sub-tree (`root` included) closest to `c`, with their
/// distances. Runs over the whole graph: the sub-tree spans layers.
///
/// # Arguments
/// * `view` – a live graph or an archived snapshot.
/// * `root` – the sub-tree's root (an unknown root gives an empty answer).
/// * `c` – the query point.
/// * `m` – how many nodes at most.
///
/// # Returns
/// `(node, distance)` pairs, ascending by distance; nodes at the same squared distance go
/// to the smaller id.
///
/// # Errors
/// [`SpatialQueryError::NonFinitePoint`] if `c` has a NaN or infinite coordinate.
///
/// # Complexity
/// With a node index on `root`: a kd-tree k-nearest search. Otherwise a walk of the
/// sub-tree that uses the node index of any node below it for that node's sub-tree and
/// skips sub-trees whose bounding box is farther than the `m`-th best.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, query::nearest_in_subtree};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let (rooms, objects) = (g.add_layer("rooms")?, g.add_layer("objects")?);
/// g.add_layer_edge(rooms, objects)?;
/// for room in [1, 2] { g.add_node(NodeId(room), rooms)?; }
/// for (id, room, x) in [(10, 1, 4.0), (11, 1, 2.0), (20, 2, 0.5)] {
///     g.add_node(NodeId(id), objects)?;
///     g.set_geometry(NodeId(id), vec![[x, 0.0, 0.0]])?;
///     g.nest(NodeId(room), NodeId(id))?;
/// }
/// g.enable_node_index(NodeId(1))?;
/// let want = vec![(NodeId(11), 2.0)]; // object 20 is closer but in another room
/// assert_eq!(nearest_in_subtree(&g, NodeId(1), [0.0, 0.0, 0.0], 1)?, want);
/// assert_eq!(nearest_in_subtree(&g.to_snapshot().view(), NodeId(1), [0.0, 0.0, 0.0], 1)?, want);
/// # Ok(()) }
/// ```
pub fn nearest_in_subtree<V: SceneView>(
    view: &V,
    root: NodeId,
    c: Point,
    m: usize,
) -> Result<Vec<(NodeId, f32)>, SpatialQueryError> {
    check_point(&c)?;
    let mut top = top_nodes(m);
    let Some(r) = view.node(root) else {
        return Ok(Vec::new());
    };
    if m == 0 {
        return Ok(Vec::new());
    }
    let mut stack = vec![r];
    let mut seen = FxHashSet::default();
    while let Some(n) = stack.pop() {
        let id = view.node_id(n);
        if !seen.insert(id) {
            continue; // only a damaged snapshot can nest a node twice
        }
        if let Some(index) = view.node_index(id) {
            index_nearest(&index, &c, &mut top);
            continue;
        }
        if view
            .aabb(n)
            .is_some_and(|b| top.prunes(b.distance_squared_to(&c)))
        {
            continue;
        }
        if let Some(d2) = node_distance2(view, n, &c) {
            top.offer(d2, id);
        }
        stack.extend(view.children(n).filter_map(|ch| view.node(ch)));
    }
    Ok(top.into_vec())
}

/// At most `m` nodes of one index closest to `c` (the same semantics as
/// [`nearest_nodes`]); for indexes a reader built itself.
///
/// # Errors
/// [`SpatialQueryError::NonFinitePoint`] if `c` has a NaN or infinite coordinate.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, index::build_layer_index, query::nearest_in_index};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let mesh = g.add_layer("mesh")?;
/// g.add_node(NodeId(4), mesh)?;
/// g.set_geometry(NodeId(4), vec![[0.0, 3.0, 4.0]])?;
/// let index = build_layer_index(&g, mesh);
/// assert_eq!(nearest_in_index(&index, [0.0; 3], 5)?, vec![(NodeId(4), 5.0)]);
/// let index = build_layer_index(&g.to_snapshot().view(), mesh);
/// assert_eq!(nearest_in_index(&index, [0.0; 3], 5)?, vec![(NodeId(4), 5.0)]);
/// # Ok(()) }
/// ```
pub fn nearest_in_index<I: SpatialIndex>(
    index: &I,
    c: Point,
    m: usize,
) -> Result<Vec<(NodeId, f32)>, SpatialQueryError> {
    check_point(&c)?;
    let mut top = top_nodes(m);
    index_nearest(index, &c, &mut top);
    Ok(top.into_vec())
}

/// Nodes of one index with a point at distance `<= r` from `c`, ascending (the same
/// semantics as [`nodes_within_radius`]).
///
/// # Errors
/// As [`nodes_within_radius`].
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, index::build_layer_index, query::within_index};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let mesh = g.add_layer("mesh")?;
/// g.add_node(NodeId(4), mesh)?;
/// g.set_geometry(NodeId(4), vec![[0.0, 3.0, 4.0]])?;
/// let index = build_layer_index(&g.to_snapshot().view(), mesh);
/// assert_eq!(within_index(&index, [0.0; 3], 5.0)?, vec![NodeId(4)]);
/// assert!(within_index(&index, [0.0; 3], 4.9)?.is_empty());
/// assert_eq!(within_index(&build_layer_index(&g, mesh), [0.0; 3], 5.0)?, vec![NodeId(4)]);
/// # Ok(()) }
/// ```
pub fn within_index<I: SpatialIndex>(
    index: &I,
    c: Point,
    r: f32,
) -> Result<Vec<NodeId>, SpatialQueryError> {
    check_point(&c)?;
    if !(r.is_finite() && r >= 0.0) {
        return Err(SpatialQueryError::InvalidRadius(r));
    }
    let mut out = Vec::new();
    index_within(index, &c, radius_bound(r), &mut out);
    out.sort_unstable();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radius_bound_is_the_largest_square_with_root_within_r() {
        for r in [
            0.0f32,
            1e-30,
            1e-20,
            0.1,
            0.5,
            1.0,
            3.3,
            1234.5,
            1e18,
            1e19,
            2e19,
            f32::MAX,
        ] {
            let b = radius_bound(r);
            assert!(b.sqrt() <= r, "{r}: {b}");
            if b < f32::MAX {
                assert!(b.next_up().sqrt() > r, "{r}: {b}");
            }
        }
    }

    #[test]
    fn top_nodes_keeps_each_node_once_with_its_smallest_distance() {
        for m in [2, 40] {
            let mut t = top_nodes(m);
            t.offer(4.0, NodeId(1));
            t.offer(1.0, NodeId(1));
            t.offer(9.0, NodeId(1));
            t.offer(1.0, NodeId(2));
            assert_eq!(t.into_vec(), vec![(NodeId(1), 1.0), (NodeId(2), 1.0)]);
        }
    }

    #[test]
    fn top_nodes_orders_by_distance_then_id() {
        let mut t = top_nodes(2);
        t.offer(1.0, NodeId(5));
        t.offer(1.0, NodeId(3));
        t.offer(1.0, NodeId(4));
        t.offer(0.25, NodeId(9));
        assert_eq!(t.into_vec(), vec![(NodeId(9), 0.5), (NodeId(3), 1.0)]);
    }
}
