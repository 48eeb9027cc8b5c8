//! [`OverlaidTree`]: a [`LiveKdTree`] that absorbs a node moved wholesale (an object's
//! mesh translated, re-observed, replaced) in O(its points) instead of one kd-tree
//! removal and insertion per point.
//!
//! When most points of one item change at once, the tree keeps that item's old entries
//! in place, marks the item *moved* (its entries in the tree are dead: queries skip
//! them) and keeps the item's new points in a small overlay that queries scan linearly,
//! item by item, skipping an item whose box is beyond the query's bound. A moved item
//! that changes again only replaces its overlay points; one that returns to the points
//! the tree holds for it is simply live again. When the overlay grows past
//! [`OverlaidTree::overlay_budget`] (or holds [`MAX_MOVED`] items), it is merged: the
//! dead entries are removed and the overlay points inserted one by one, or the whole
//! tree is rebuilt when that is cheaper. So a burst of wholesale moves costs what it cost
//! before, and an item that moves again and again touches the tree once.
//!
//! # Invariants (checked by [`OverlaidTree::check`] in tests)
//! - For a moved item, the tree holds exactly the entries `(p, item)` for `p` in its
//!   `in_tree` points (all dead), and its live points are its overlay points (never
//!   empty). For any other item, its entries in the tree are its live points.
//! - `moved` is sorted by item, each item once; `overlay_len` and `dead_len` are the
//!   sums of its overlay and `in_tree` lengths.
//!
//! Queries are exact: live entries are reported as [`LiveKdTree`] reports them, and an
//! overlay item is skipped only when [`Aabb::distance_squared_to`] (a lower bound of
//! [`crate::distance_squared`] to any point in the box, evaluated in the same order)
//! exceeds the bound.

use super::kdtree::{Entry, LiveKdTree, Located};
use crate::graph::PointChange;
use crate::{Aabb, Point, distance_squared};
use std::sync::Arc;

/// Changed points (removed plus added, after trimming the common prefix and suffix) from
/// which an update of one item goes to the overlay instead of the tree.
pub(crate) const MOVE_MIN: usize = 16;
/// Most items in the overlay before it is merged into the tree.
pub(crate) const MAX_MOVED: usize = 16;
/// The overlay may hold this many points in any tree (more in large trees).
const OVERLAY_MIN: usize = 1024;

/// One item whose tree entries are dead.
#[derive(Clone, Debug)]
struct Moved {
    item: u32,
    /// The points of the item's (dead) entries in the tree.
    in_tree: Arc<[Point]>,
    /// The item's live points (not empty).
    points: Arc<[Point]>,
    /// A box around `points`.
    bbox: Aabb,
}

/// A [`LiveKdTree`] plus an overlay of items moved wholesale (see the module docs).
#[derive(Clone, Debug, Default)]
pub(crate) struct OverlaidTree {
    tree: LiveKdTree,
    moved: Vec<Moved>,
    overlay_len: usize,
    dead_len: usize,
}

/// Whether two point lists are equal bit for bit (one memory compare).
fn same_points(a: &[Point], b: &[Point]) -> bool {
    bytemuck::cast_slice::<Point, u32>(a) == bytemuck::cast_slice::<Point, u32>(b)
}

impl OverlaidTree {
    /// A balanced tree over `entries`, with an empty overlay.
    pub(crate) fn from_entries(entries: Vec<Entry>) -> Self {
        OverlaidTree {
            tree: LiveKdTree::from_entries(entries),
            ..OverlaidTree::default()
        }
    }

    /// Replaces every item `i` (in the tree and the overlay) by `map(i)`. `map` must not
    /// send two items to one.
    pub(crate) fn map_items(&mut self, mut map: impl FnMut(u32) -> u32) {
        self.tree.map_items(&mut map);
        for m in &mut self.moved {
            m.item = map(m.item);
        }
        self.moved.sort_unstable_by_key(|m| m.item);
    }

    /// Number of live entries.
    pub(crate) fn len(&self) -> usize {
        self.tree.len() - self.dead_len + self.overlay_len
    }

    /// Bytes held by the tree and the overlay (overlay points shared with another tree
    /// counted in each).
    pub(crate) fn memory_bytes(&self) -> usize {
        let points: usize = self
            .moved
            .iter()
            .map(|m| m.in_tree.len() + m.points.len())
            .sum();
        self.tree.memory_bytes()
            + self.moved.capacity() * std::mem::size_of::<Moved>()
            + points * std::mem::size_of::<Point>()
    }

    /// Whether `item`'s entries in the tree are dead.
    #[inline]
    fn is_moved(&self, item: u32) -> bool {
        self.moved.binary_search_by_key(&item, |m| m.item).is_ok()
    }

    /// The kd-tree under the overlay.
    pub(crate) fn tree(&self) -> &LiveKdTree {
        &self.tree
    }

    /// The live points of `item` change from `change.old` (exactly its live points) to
    /// `change.new`. `located` (if given) holds where each changed point descends to in
    /// the tree, removed ones first, as [`LiveKdTree::locate`] found them under its
    /// current shape; it is used when the change goes to the tree point by point.
    pub(crate) fn apply(
        &mut self,
        item: u32,
        change: &PointChange<'_>,
        located: Option<&[Located]>,
    ) {
        let (old, new) = (change.old_points(), change.new_points());
        match self.moved.binary_search_by_key(&item, |m| m.item) {
            Ok(at) => {
                let m = &mut self.moved[at];
                if new.is_empty() || same_points(new, &m.in_tree) {
                    // Gone (its handle may be reused: purge the dead entries), or back
                    // where the tree has it (the dead entries are live again).
                    let m = self.moved.remove(at);
                    self.overlay_len -= m.points.len();
                    self.dead_len -= m.in_tree.len();
                    if new.is_empty() {
                        for p in m.in_tree.iter() {
                            let found = self.tree.remove(*p, item);
                            debug_assert!(found, "dead entry {p:?} missing");
                        }
                    }
                    return;
                }
                self.overlay_len = self.overlay_len - m.points.len() + new.len();
                m.points = change.kept_new();
                m.bbox = change.new_box().expect("not empty");
            }
            Err(at) => {
                let (removed, added) = change.changed();
                if removed.len() + added.len() < MOVE_MIN || old.is_empty() || new.is_empty() {
                    let shape = self.tree.shape();
                    let at = |i: usize| located.and_then(|l| l.get(i)).copied();
                    for (i, p) in removed.iter().enumerate() {
                        let found = match at(i) {
                            Some(a) => self.tree.remove_located(*p, item, a, shape),
                            None => self.tree.remove(*p, item),
                        };
                        debug_assert!(found, "indexed point {p:?} missing");
                    }
                    for (i, p) in added.iter().enumerate() {
                        match at(removed.len() + i) {
                            Some(a) => self.tree.insert_located(*p, item, a, shape),
                            None => self.tree.insert(*p, item),
                        }
                    }
                    return;
                }
                self.moved.insert(
                    at,
                    Moved {
                        item,
                        in_tree: change.kept_old(),
                        points: change.kept_new(),
                        bbox: change.new_box().expect("not empty"),
                    },
                );
                self.overlay_len += new.len();
                self.dead_len += old.len();
            }
        }
        if self.moved.len() > MAX_MOVED || self.overlay_len > self.overlay_budget() {
            self.merge();
        }
    }

    /// How many overlay points the tree tolerates before merging: [`OVERLAY_MIN`], or an
    /// eighth of the tree when that is more.
    fn overlay_budget(&self) -> usize {
        OVERLAY_MIN.max(self.tree.len() / 8)
    }

    /// Moves the overlay into the tree: removes the dead entries and inserts the overlay
    /// points, one by one, or rebuilds the tree from its live entries when they change a
    /// quarter of it or more (a rebuild costs far less per entry than an update).
    fn merge(&mut self) {
        let moved = std::mem::take(&mut self.moved);
        if 4 * (self.dead_len + self.overlay_len) >= self.tree.len() {
            let mut entries: Vec<Entry> = self
                .tree
                .entries()
                .into_iter()
                .filter(|e| moved.binary_search_by_key(&e.item, |m| m.item).is_err())
                .collect();
            for m in &moved {
                entries.extend(m.points.iter().map(|&p| Entry { p, item: m.item }));
            }
            self.tree = LiveKdTree::from_entries(entries);
        } else {
            for m in &moved {
                for p in m.in_tree.iter() {
                    let found = self.tree.remove(*p, m.item);
                    debug_assert!(found, "dead entry {p:?} missing");
                }
                for p in m.points.iter() {
                    self.tree.insert(*p, m.item);
                }
            }
        }
        self.overlay_len = 0;
        self.dead_len = 0;
    }

    /// Every live entry (tree order, then the overlay).
    pub(crate) fn entries(&self) -> Vec<Entry> {
        let mut out = self.tree.entries();
        out.retain(|e| !self.is_moved(e.item));
        for m in &self.moved {
            out.extend(m.points.iter().map(|&p| Entry { p, item: m.item }));
        }
        out
    }

    /// Branch-and-bound nearest search over the live entries (see
    /// [`crate::index::SpatialIndex::nearest_visit`]): the tree, nearer cells first,
    /// then the overlay items within the bound.
    pub(crate) fn nearest_visit<F: FnMut(f32, u32) -> f32>(&self, c: &Point, mut f: F) {
        if self.moved.is_empty() {
            self.tree.nearest_visit(c, f);
            return;
        }
        let mut bound = f32::INFINITY;
        self.tree.nearest_visit(c, |d2, item| {
            if !self.is_moved(item) {
                bound = f(d2, item);
            }
            bound
        });
        for m in &self.moved {
            if m.bbox.distance_squared_to(c) > bound {
                continue;
            }
            for p in m.points.iter() {
                let d2 = distance_squared(p, c);
                if d2 <= bound {
                    bound = f(d2, m.item);
                }
            }
        }
    }

    /// Calls `f(distance², item, point)` for every live entry with `distance² <= r2`.
    pub(crate) fn within(&self, c: &Point, r2: f32, f: &mut impl FnMut(f32, u32, &Point)) {
        if self.moved.is_empty() {
            self.tree.within(c, r2, f);
            return;
        }
        self.tree.within(c, r2, &mut |d2, item, p| {
            if !self.is_moved(item) {
                f(d2, item, p);
            }
        });
        for m in &self.moved {
            if m.bbox.distance_squared_to(c) > r2 {
                continue;
            }
            for p in m.points.iter() {
                let d2 = distance_squared(p, c);
                if d2 <= r2 {
                    f(d2, m.item, p);
                }
            }
        }
    }

    /// Checks the invariants in the module docs; `Err` names the first broken one.
    #[cfg(test)]
    pub(crate) fn check(&self) -> Result<(), String> {
        self.tree.check()?;
        if !self.moved.windows(2).all(|w| w[0].item < w[1].item) {
            return Err("moved items not sorted".into());
        }
        let key = |e: &Entry| (e.item, e.p.map(f32::to_bits));
        for m in &self.moved {
            if m.points.is_empty() {
                return Err(format!("moved item {} without points", m.item));
            }
            if m.points
                .iter()
                .any(|p| m.bbox.distance_squared_to(p) != 0.0)
            {
                return Err(format!("box of moved item {} misses a point", m.item));
            }
            let mut dead: Vec<_> = self
                .tree
                .entries()
                .iter()
                .filter(|e| e.item == m.item)
                .map(key)
                .collect();
            let mut want: Vec<_> = m
                .in_tree
                .iter()
                .map(|&p| key(&Entry { p, item: m.item }))
                .collect();
            dead.sort_unstable();
            want.sort_unstable();
            if dead != want {
                return Err(format!("dead entries of item {} differ", m.item));
            }
        }
        let overlay: usize = self.moved.iter().map(|m| m.points.len()).sum();
        let dead: usize = self.moved.iter().map(|m| m.in_tree.len()).sum();
        if (overlay, dead) != (self.overlay_len, self.dead_len) {
            return Err("overlay counts differ".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// A model: each item's live points.
    type Model = Vec<Vec<Point>>;

    fn check_against(t: &OverlaidTree, model: &Model, rng: &mut impl Rng) {
        t.check().unwrap();
        let key = |e: &Entry| (e.item, e.p.map(f32::to_bits));
        let mut got: Vec<_> = t.entries().iter().map(key).collect();
        let mut want: Vec<_> = model
            .iter()
            .enumerate()
            .flat_map(|(i, ps)| ps.iter().map(move |&p| key(&Entry { p, item: i as u32 })))
            .collect();
        got.sort_unstable();
        want.sort_unstable();
        assert_eq!(got, want);
        assert_eq!(t.len(), want.len());
        for _ in 0..10 {
            let c: Point = [0, 1, 2].map(|_| rng.gen_range(-3.0..13.0));
            // Nearest: the best (distance, item) with ties to the smaller item, through
            // the visitor as the spatial queries use it.
            let mut best: Option<(f32, u32)> = None;
            t.nearest_visit(&c, |d2, item| {
                if best.is_none_or(|(bd, bi)| d2 < bd || (d2 == bd && item < bi)) {
                    best = Some((d2, item));
                }
                best.map_or(f32::INFINITY, |b| b.0)
            });
            let brute = model
                .iter()
                .enumerate()
                .flat_map(|(i, ps)| ps.iter().map(move |p| (distance_squared(p, &c), i as u32)))
                .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            assert_eq!(best, brute, "nearest to {c:?}");
            let r2 = rng.gen_range(0.0..16.0f32);
            let mut w = Vec::new();
            t.within(&c, r2, &mut |d2, item, p| {
                assert_eq!(d2, distance_squared(p, &c));
                w.push((item, p.map(f32::to_bits)));
            });
            let mut brute: Vec<_> = model
                .iter()
                .enumerate()
                .flat_map(|(i, ps)| ps.iter().map(move |p| (i as u32, *p)))
                .filter(|(_, p)| distance_squared(p, &c) <= r2)
                .map(|(i, p)| (i, p.map(f32::to_bits)))
                .collect();
            w.sort_unstable();
            brute.sort_unstable();
            assert_eq!(w, brute, "within {r2} of {c:?}");
        }
    }

    /// A cluster of `n` points around `at`, on a coarse grid (duplicates occur).
    fn cluster(rng: &mut impl Rng, at: Point, n: usize) -> Vec<Point> {
        (0..n)
            .map(|_| [0, 1, 2].map(|a| at[a] + rng.gen_range(0..8) as f32 * 0.125))
            .collect()
    }

    #[test]
    fn wholesale_moves_match_brute_force() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let items = 60;
        let mut model: Model = (0..items)
            .map(|_| {
                let at = [0, 1, 2].map(|_| rng.gen_range(0.0..10.0));
                let n = rng.gen_range(0..40);
                cluster(&mut rng, at, n)
            })
            .collect();
        let entries = model
            .iter()
            .enumerate()
            .flat_map(|(i, ps)| ps.iter().map(move |&p| Entry { p, item: i as u32 }))
            .collect();
        let mut t = OverlaidTree::from_entries(entries);
        let (mut overlaid, mut merged) = (0, 0);
        for step in 0..3000 {
            let i = rng.gen_range(0..items);
            let old = model[i].clone();
            let new = match rng.gen_range(0..6) {
                // A rigid move of every point.
                0 | 1 => {
                    let d: Point = [0, 1, 2].map(|_| rng.gen_range(-4..5) as f32 * 0.25);
                    old.iter().map(|p| [0, 1, 2].map(|a| p[a] + d[a])).collect()
                }
                // One point moves.
                2 if !old.is_empty() => {
                    let mut v = old.clone();
                    let k = rng.gen_range(0..v.len());
                    v[k][0] += 0.5;
                    v
                }
                // Back to what the tree holds, when moved.
                3 => t
                    .moved
                    .iter()
                    .find(|m| m.item == i as u32)
                    .map_or(old.clone(), |m| m.in_tree.to_vec()),
                // Gone.
                4 if rng.gen_bool(0.2) => Vec::new(),
                // Replaced by a new cluster.
                _ => {
                    let at = [0, 1, 2].map(|_| rng.gen_range(0.0..10.0));
                    let n = rng.gen_range(0..40);
                    cluster(&mut rng, at, n)
                }
            };
            let before = t.moved.len();
            t.apply(i as u32, &PointChange::new(&old, &new), None);
            overlaid += usize::from(t.moved.len() > before);
            merged += usize::from(t.moved.len() < before && t.moved.is_empty() && before > 1);
            model[i] = new;
            if step % 50 == 0 {
                check_against(&t, &model, &mut rng);
            }
        }
        check_against(&t, &model, &mut rng);
        assert!(
            overlaid > 300,
            "the test should exercise the overlay: {overlaid}"
        );
        assert!(merged > 5, "the test should exercise merging: {merged}");
    }

    #[test]
    fn a_moved_item_costs_no_tree_update_until_merged() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let points = cluster(&mut rng, [1.0, 1.0, 1.0], 190);
        let mut t =
            OverlaidTree::from_entries(points.iter().map(|&p| Entry { p, item: 3 }).collect());
        let mut cur = points.clone();
        for k in 1..=20 {
            let next: Vec<Point> = points
                .iter()
                .map(|p| [p[0] + k as f32, p[1], p[2]])
                .collect();
            t.apply(3, &PointChange::new(&cur, &next), None);
            cur = next;
            // The tree still holds the original entries, all dead; the overlay the rest.
            assert_eq!(t.tree.len(), 190);
            assert_eq!((t.moved.len(), t.dead_len, t.overlay_len), (1, 190, 190));
        }
        t.check().unwrap();
        // Back home: live again, nothing in the overlay.
        t.apply(3, &PointChange::new(&cur, &points), None);
        assert!(t.moved.is_empty());
        assert_eq!(t.len(), 190);
        // Gone: the dead entries are purged, so the item may be reused.
        t.apply(3, &PointChange::new(&points, &cur), None);
        t.apply(3, &PointChange::new(&cur, &[]), None);
        assert_eq!((t.len(), t.tree.len()), (0, 0));
        t.check().unwrap();
    }
}
