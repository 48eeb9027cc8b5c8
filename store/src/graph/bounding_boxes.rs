//! Exact bounding boxes, kept exact on every insert, move and removal below them.
//!
//! An enabled box stores, besides the AABB, how many sub-tree points lie on each of its
//! six faces. Adding points grows the box (O(1) per point); removing a point that lies
//! on a face decrements that face's count, and only when a count reaches zero is the
//! box recomputed from the sub-tree. Floors, walls and ceilings put many points on one
//! face, so a count rarely reaches zero.

use super::change_journal::Change;
use super::point_change::PointChange;
use super::scene_graph::{Node, SceneGraph};
use crate::{Aabb, NodeId, Point};

/// How many of `points` lie on each face of `b` (`==` on the face's coordinate; min x,
/// y, z, then max x, y, z), in one pass over the coordinates as a flat array, eight
/// points at a time with a counter per coordinate (as [`Aabb::from_points`] runs).
fn face_counts(points: &[Point], b: &Aabb) -> [u32; 6] {
    const LANES: usize = 24;
    let flat: &[f32] = bytemuck::cast_slice(points);
    let blocks = flat.chunks_exact(LANES);
    let rest = blocks.remainder();
    let lo: [f32; LANES] = std::array::from_fn(|i| b.min[i % 3]);
    let hi: [f32; LANES] = std::array::from_fn(|i| b.max[i % 3]);
    let (mut on_lo, mut on_hi) = ([0u32; LANES], [0u32; LANES]);
    for block in blocks {
        for i in 0..LANES {
            on_lo[i] += u32::from(block[i] == lo[i]);
            on_hi[i] += u32::from(block[i] == hi[i]);
        }
    }
    let mut counts = [0u32; 6];
    for i in 0..LANES {
        counts[i % 3] += on_lo[i];
        counts[3 + i % 3] += on_hi[i];
    }
    for p in rest.chunks_exact(3) {
        for a in 0..3 {
            counts[a] += u32::from(p[a] == b.min[a]);
            counts[3 + a] += u32::from(p[a] == b.max[a]);
        }
    }
    counts
}

/// Whether a box around some points (`around`) reaches a face of `b`: only then can a
/// point lie on it.
fn reaches_a_face(around: &Aabb, b: &Aabb) -> bool {
    (0..3).any(|a| around.min[a] <= b.min[a] || around.max[a] >= b.max[a])
}

/// Adds points (with `around`, their box) to an enabled box; returns whether the box
/// changed. Points strictly inside the box cost nothing beyond `around`; otherwise one
/// pass counts them on the faces of the grown box: a face that moved out is held by
/// them alone, one that stayed gains them.
fn add_points(node: &mut Node, points: &[Point], around: Option<Aabb>) -> bool {
    let Some(pb) = around else {
        return false;
    };
    let Some(b) = node.aabb else {
        node.aabb = Some(pb);
        node.face_counts = face_counts(points, &pb);
        return true;
    };
    if !reaches_a_face(&pb, &b) {
        return false;
    }
    let grown = b.union(&pb);
    let on = face_counts(points, &grown);
    for a in 0..3 {
        for (face, moved) in [
            (a, grown.min[a] < b.min[a]),
            (3 + a, grown.max[a] > b.max[a]),
        ] {
            let c = &mut node.face_counts[face];
            *c = if moved { on[face] } else { *c + on[face] };
        }
    }
    node.aabb = Some(grown);
    grown != b
}

/// Makes an enabled box exactly the box of `points` (with `around`, their box): its
/// bounds, face counts and point count.
fn set_box_to(node: &mut Node, points: &[Point], around: Option<Aabb>) {
    node.aabb = None;
    node.face_counts = [0; 6];
    node.box_points = points.len() as u64;
    add_points(node, points, around);
}

/// Removes points (with `around`, their box) from an enabled box's counts; returns
/// whether a face lost its last point (the box must then be recomputed). Points
/// strictly inside the box cost nothing beyond `around`.
fn remove_points(node: &mut Node, points: &[Point], around: Option<Aabb>) -> bool {
    let (Some(b), Some(pb)) = (node.aabb, around) else {
        return false;
    };
    if !reaches_a_face(&pb, &b) {
        return false;
    }
    let on = face_counts(points, &b);
    let mut emptied = false;
    for (c, k) in node.face_counts.iter_mut().zip(on) {
        if k > 0 {
            *c = c.saturating_sub(k);
            emptied |= *c == 0;
        }
    }
    emptied
}

impl SceneGraph {
    /// Every point in the sub-tree of `id`.
    fn all_subtree_points(&self, id: NodeId) -> Vec<Point> {
        let mut out = Vec::new();
        let mut stack = vec![id];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[&n];
            out.extend_from_slice(&node.points);
            stack.extend_from_slice(&node.children);
        }
        out
    }

    /// Whether `from` or any node above it has an enabled box.
    fn any_box_at_or_above(&self, from: NodeId) -> bool {
        let mut cur = Some(from);
        while let Some(n) = cur {
            let node = &self.nodes[&n];
            if node.bbox_enabled {
                return true;
            }
            cur = node.parent;
        }
        false
    }

    /// Recomputes an enabled box and its face counts from the whole sub-tree.
    pub(crate) fn recompute_box(&mut self, id: NodeId) {
        let points = self.all_subtree_points(id);
        let node = self.nodes.get_mut(&id).expect("exists");
        set_box_to(node, &points, Aabb::from_points(&points));
        let layer = node.layer;
        self.touch_layer(layer, Change::Node(id));
    }

    /// Applies a change of sub-tree points (`removed` left, `added` joined) to every
    /// enabled box at or above `from`, then recomputes the boxes a face of which lost its
    /// last point.
    fn update_boxes(&mut self, from: NodeId, removed: &[Point], added: &[Point]) {
        let emptied = self.adjust_boxes(from, removed, added, Aabb::from_points(added));
        self.recompute_boxes(emptied);
    }

    /// Recomputes each of `ids`' boxes from its sub-tree (the boxes
    /// [`SceneGraph::geometry_changed`] returns, once the node holds its new points).
    pub(crate) fn recompute_boxes(&mut self, ids: Vec<NodeId>) {
        for n in ids {
            self.recompute_box(n);
        }
    }

    /// Applies a change of sub-tree points (`added_box` is the added points' box) to every
    /// enabled box at or above `from`, as far as the change itself tells; returns the
    /// boxes a face of which lost its last point, to recompute from their sub-trees once
    /// these hold their new points.
    ///
    /// The added points are counted first: a point that moves within a face (a
    /// translation along it) then never empties that face, so moving a node of many
    /// one-point children one child at a time (saffron) recomputes the box only when a
    /// face's last point really leaves it. A box whose every point left is the added
    /// points' own box, with no removal to count; its old box is then the removed
    /// points' box, which the boxes above need.
    #[must_use]
    fn adjust_boxes(
        &mut self,
        from: NodeId,
        removed: &[Point],
        added: &[Point],
        added_box: Option<Aabb>,
    ) -> Vec<NodeId> {
        let mut removed_box: Option<Option<Aabb>> = None;
        let mut emptied = Vec::new();
        let mut cur = Some(from);
        while let Some(n) = cur {
            let node = self.nodes.get_mut(&n).expect("exists");
            cur = node.parent;
            if !node.bbox_enabled {
                continue;
            }
            let changed = if node.box_points == removed.len() as u64 {
                let before = node.aabb;
                removed_box.get_or_insert(before);
                set_box_to(node, added, added_box);
                node.aabb != before
            } else {
                let grew = add_points(node, added, added_box);
                node.box_points = node.box_points + added.len() as u64 - removed.len() as u64;
                let around = *removed_box.get_or_insert_with(|| Aabb::from_points(removed));
                if remove_points(node, removed, around) {
                    emptied.push(n);
                    continue;
                }
                grew
            };
            if changed {
                let layer = node.layer;
                self.touch_layer(layer, Change::Node(n));
            }
        }
        emptied
    }

    /// Keeps boxes exact as `id`'s points change (`change`); the node may not hold its
    /// new points yet. Returns the boxes to recompute ([`SceneGraph::recompute_boxes`])
    /// once it does.
    #[must_use]
    pub(crate) fn geometry_changed(&mut self, id: NodeId, change: &PointChange<'_>) -> Vec<NodeId> {
        if !self.any_box_at_or_above(id) {
            return Vec::new();
        }
        let (removed, added) = change.changed();
        let added_box = if added.len() == change.new_points().len() {
            change.new_box()
        } else {
            Aabb::from_points(added)
        };
        self.adjust_boxes(id, removed, added, added_box)
    }

    /// Keeps boxes exact after `child`'s sub-tree was nested under `parent`.
    pub(crate) fn subtree_joined(&mut self, parent: NodeId, child: NodeId) {
        if self.any_box_at_or_above(parent) {
            let points = self.all_subtree_points(child);
            self.update_boxes(parent, &[], &points);
        }
    }

    /// Keeps boxes exact after `child`'s sub-tree left `parent`.
    pub(crate) fn subtree_left(&mut self, parent: NodeId, child: NodeId) {
        if self.any_box_at_or_above(parent) {
            let points = self.all_subtree_points(child);
            self.update_boxes(parent, &points, &[]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SceneView;

    #[test]
    fn face_counts_equal_a_count_point_by_point() {
        for n in [1, 2, 7, 8, 9, 24, 25, 100] {
            let points: Vec<Point> = (0..n)
                .map(|i| [(i % 3) as f32, (i % 5) as f32 - 2.0, -((i % 2) as f32)])
                .collect();
            let b = Aabb::from_points(&points).expect("points");
            let mut want = [0u32; 6];
            for p in &points {
                for a in 0..3 {
                    want[a] += u32::from(p[a] == b.min[a]);
                    want[3 + a] += u32::from(p[a] == b.max[a]);
                }
            }
            assert_eq!(face_counts(&points, &b), want, "{n} points");
        }
    }

    /// A room box over two object boxes, each object's points in one mesh node. Moving
    /// one object's mesh whole (every point of its box leaves) replaces the object's box
    /// by the new points' box; the room's box follows, shrinking when the moved object
    /// held a face of it alone.
    #[test]
    fn a_box_whose_every_point_moves_is_the_new_points_box() {
        let mut g = SceneGraph::new();
        let rooms = g.add_layer("rooms").unwrap();
        let objects = g.add_layer("objects").unwrap();
        let mesh = g.add_layer("mesh").unwrap();
        g.add_layer_edge(rooms, objects).unwrap();
        g.add_layer_edge(objects, mesh).unwrap();
        g.add_node(NodeId(1), rooms).unwrap();
        g.enable_bounding_box(NodeId(1)).unwrap();
        let cube = |at: f32| -> Vec<Point> {
            (0..60)
                .map(|i| [at + (i % 4) as f32, (i % 3) as f32, (i % 5) as f32])
                .collect()
        };
        for (object, vertices, at) in [(10, 20, 0.0), (11, 21, 10.0)] {
            g.add_node(NodeId(object), objects).unwrap();
            g.nest(NodeId(1), NodeId(object)).unwrap();
            g.enable_bounding_box(NodeId(object)).unwrap();
            g.add_node(NodeId(vertices), mesh).unwrap();
            g.nest(NodeId(object), NodeId(vertices)).unwrap();
            g.set_geometry(NodeId(vertices), cube(at)).unwrap();
        }
        let aabb = |g: &SceneGraph, id: u64| g.node(NodeId(id)).and_then(|n| g.aabb(n));
        for at in [12.0, -3.0, 5.5, 0.0] {
            g.set_geometry(NodeId(21), cube(at)).unwrap();
            g.check_invariants().unwrap();
            assert_eq!(aabb(&g, 11), Aabb::from_points(&cube(at)));
            let both = [cube(0.0), cube(at)].concat();
            assert_eq!(aabb(&g, 1), Aabb::from_points(&both));
        }
        g.set_geometry(NodeId(21), Vec::new()).unwrap();
        g.check_invariants().unwrap();
        assert_eq!(aabb(&g, 11), None);
        assert_eq!(aabb(&g, 1), Aabb::from_points(&cube(0.0)));
    }
}
