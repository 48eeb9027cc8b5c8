//! Exact bounding boxes, kept exact on every insert, move and removal below them.
//!
//! An enabled box stores, besides the AABB, how many sub-tree points lie on each of its
//! six faces. Adding points grows the box (O(1) per point); removing a point that lies
//! on a face decrements that face's count, and only when a count reaches zero is the
//! box recomputed from the sub-tree. Floors, walls and ceilings put many points on one
//! face, so a count rarely reaches zero.

use crate::graph::{Change, Node, SceneGraph};
use crate::{Aabb, NodeId, Point};

/// Adds points to an enabled box; returns whether the box changed.
fn add_points(node: &mut Node, points: &[Point]) -> bool {
    let before = node.aabb;
    for p in points {
        match &mut node.aabb {
            None => {
                node.aabb = Some(Aabb::from_point(*p));
                node.face_counts = [1; 6];
            }
            Some(b) => {
                for (a, &c) in p.iter().enumerate() {
                    if c < b.min[a] {
                        b.min[a] = c;
                        node.face_counts[a] = 1;
                    } else if c == b.min[a] {
                        node.face_counts[a] += 1;
                    }
                    if c > b.max[a] {
                        b.max[a] = c;
                        node.face_counts[3 + a] = 1;
                    } else if c == b.max[a] {
                        node.face_counts[3 + a] += 1;
                    }
                }
            }
        }
    }
    node.aabb != before
}

/// Removes points from an enabled box's counts; returns whether a face lost its last
/// point (the box must then be recomputed).
fn remove_points(node: &mut Node, points: &[Point]) -> bool {
    let Some(b) = node.aabb else {
        return false;
    };
    let mut emptied = false;
    for p in points {
        for (a, &c) in p.iter().enumerate() {
            for (face, bound) in [(a, b.min[a]), (3 + a, b.max[a])] {
                if c == bound {
                    let c = &mut node.face_counts[face];
                    *c = c.saturating_sub(1);
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
        add_points(node, &points);
        let layer = node.layer;
        self.touch_layer(layer, Change::Node(id));
    }

    /// Applies a change of sub-tree points (`removed` left, `added` joined) to every
    /// enabled box at or above `from`.
    fn update_boxes(&mut self, from: NodeId, removed: &[Point], added: &[Point]) {
        let mut cur = Some(from);
        while let Some(n) = cur {
            let node = self.nodes.get_mut(&n).expect("exists");
            cur = node.parent;
            if !node.bbox_enabled {
                continue;
            }
            if remove_points(node, removed) {
                self.recompute_box(n);
            } else if add_points(node, added) {
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
