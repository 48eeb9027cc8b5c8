//! Exact bounding boxes, kept exact on every insert, move and removal below them.
//!
//! An enabled box stores, besides the AABB, how many sub-tree points lie on each of its
//! six faces. Adding points grows the box (O(1) per point); removing a point that lies
//! on a face decrements that face's count, and only when a count reaches zero is the
//! box recomputed from the sub-tree. Floors, walls and ceilings put many points on one
//! face, so a count rarely reaches zero.

use crate::change::Change;
use crate::graph::{Node, SceneGraph};
use crate::{Aabb, NodeId, Point};

/// How many of `points` have coordinate `a` equal (`==`) to `v`.
fn count_on(points: &[Point], a: usize, v: f32) -> u32 {
    points.iter().map(|p| u32::from(p[a] == v)).sum()
}

/// Adds points (with `around`, their box) to an enabled box; returns whether the box
/// changed. Points strictly inside the box cost nothing beyond `around`; a face is
/// counted again only when `around` reaches it.
fn add_points(node: &mut Node, points: &[Point], around: Option<Aabb>) -> bool {
    let Some(pb) = around else {
        return false;
    };
    let before = node.aabb;
    let counts = &mut node.face_counts;
    match &mut node.aabb {
        None => {
            node.aabb = Some(pb);
            for a in 0..3 {
                counts[a] = count_on(points, a, pb.min[a]);
                counts[3 + a] = count_on(points, a, pb.max[a]);
            }
        }
        Some(b) => {
            for a in 0..3 {
                if pb.min[a] < b.min[a] {
                    b.min[a] = pb.min[a];
                    counts[a] = count_on(points, a, b.min[a]);
                } else if pb.min[a] == b.min[a] {
                    counts[a] += count_on(points, a, b.min[a]);
                }
                if pb.max[a] > b.max[a] {
                    b.max[a] = pb.max[a];
                    counts[3 + a] = count_on(points, a, b.max[a]);
                } else if pb.max[a] == b.max[a] {
                    counts[3 + a] += count_on(points, a, b.max[a]);
                }
            }
        }
    }
    node.aabb != before
}

/// Removes points (with `around`, their box) from an enabled box's counts; returns
/// whether a face lost its last point (the box must then be recomputed). Only the faces
/// `around` reaches are counted.
fn remove_points(node: &mut Node, points: &[Point], around: Option<Aabb>) -> bool {
    let (Some(b), Some(pb)) = (node.aabb, around) else {
        return false;
    };
    let mut emptied = false;
    for a in 0..3 {
        for (face, reaches, bound) in [
            (a, pb.min[a] <= b.min[a], b.min[a]),
            (3 + a, pb.max[a] >= b.max[a], b.max[a]),
        ] {
            if reaches {
                let k = count_on(points, a, bound);
                if k > 0 {
                    let c = &mut node.face_counts[face];
                    *c = c.saturating_sub(k);
                    emptied |= *c == 0;
                }
            }
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
        node.aabb = None;
        node.face_counts = [0; 6];
        add_points(node, &points, Aabb::from_points(&points));
        let layer = node.layer;
        self.touch_layer(layer, Change::Node(id));
    }

    /// Applies a change of sub-tree points (`removed` left, `added` joined) to every
    /// enabled box at or above `from`. The added points are counted first: a point that
    /// moves within a face (a translation along it) then never empties that face, so
    /// moving a node of many one-point children one child at a time (saffron) recomputes
    /// the box only when a face's last point really leaves it.
    fn update_boxes(&mut self, from: NodeId, removed: &[Point], added: &[Point]) {
        let (removed_box, added_box) = (Aabb::from_points(removed), Aabb::from_points(added));
        let mut cur = Some(from);
        while let Some(n) = cur {
            let node = self.nodes.get_mut(&n).expect("exists");
            cur = node.parent;
            if !node.bbox_enabled {
                continue;
            }
            let grew = add_points(node, added, added_box);
            if remove_points(node, removed, removed_box) {
                self.recompute_box(n);
            } else if grew {
                let layer = node.layer;
                self.touch_layer(layer, Change::Node(n));
            }
        }
    }

    /// Keeps boxes exact after `id`'s points changed from `old` to its current points.
    pub(crate) fn geometry_changed(&mut self, id: NodeId, old: &[Point]) {
        if self.any_box_at_or_above(id) {
            let (removed, added) = crate::id::changed_points(old, &self.nodes[&id].points);
            let (removed, added) = (removed.to_vec(), added.to_vec());
            self.update_boxes(id, &removed, &added);
        }
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
