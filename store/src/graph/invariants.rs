//! The graph's invariant checker: [`SceneGraph::check_invariants`] recounts, from
//! scratch, what every mutation keeps up to date (the invariants listed in the docs of
//! the graph module).

use super::scene_graph::SceneGraph;
use crate::{Aabb, LayerId, NodeId, Point};

impl SceneGraph {
    /// Checks every invariant listed in the module docs; `Err` names the first broken one.
    /// Meant for tests and debugging: it scans the whole graph.
    pub fn check_invariants(&self) -> Result<(), String> {
        for (&lid, layer) in &self.layers {
            if self.layer_names.get(&layer.name) != Some(&lid) {
                return Err(format!("layer {lid} name {:?} not indexed", layer.name));
            }
            if self.layer_reaches_strictly(lid) {
                return Err(format!("layer {lid} is on a cycle"));
            }
            for c in &layer.children {
                if !self.layers[c].parents.contains(&lid) {
                    return Err(format!("DAG edge {lid}->{c} not mirrored"));
                }
            }
            for (slot, n) in layer.nodes.iter().enumerate() {
                let node = self
                    .nodes
                    .get(n)
                    .ok_or(format!("layer {lid} lists missing {n}"))?;
                if node.layer != lid || node.slot as usize != slot {
                    return Err(format!("node {n} layer/slot mismatch"));
                }
            }
            for (which, map, graph_map) in [
                ("label", &layer.label_postings, &self.label_layers),
                ("key", &layer.key_postings, &self.key_layers),
            ] {
                for (term, set) in map {
                    if set.is_empty() || !graph_map.get(term).is_some_and(|ls| ls.contains(&lid)) {
                        return Err(format!("{which} posting {term} of {lid} not in graph map"));
                    }
                    for n in set {
                        let node = self
                            .nodes
                            .get(n)
                            .ok_or(format!("{which} posting of missing {n}"))?;
                        let has = match which {
                            "label" => node.labels.contains(term),
                            _ => node.features.iter().any(|f| f.0 == *term),
                        };
                        if !has || node.layer != lid {
                            return Err(format!("{which} posting {term} wrongly lists {n}"));
                        }
                    }
                }
            }
        }
        if self.layer_names.len() != self.layers.len() {
            return Err("layer name index has stale entries".into());
        }
        let listed: usize = self.layers.values().map(|l| l.nodes.len()).sum();
        if listed != self.nodes.len() {
            return Err("node count differs from layer lists".into());
        }
        for (term, ls) in self.label_layers.iter().chain(self.key_layers.iter()) {
            if ls.is_empty() {
                return Err(format!("graph posting {term} empty"));
            }
        }
        for (&id, node) in &self.nodes {
            if node.id != id {
                return Err(format!("node {id} stored under wrong key"));
            }
            if node.points.iter().any(|p| !p.iter().all(|c| c.is_finite())) {
                return Err(format!("node {id} has a non-finite point"));
            }
            for s in &node.labels {
                if !self.layers[&node.layer]
                    .label_postings
                    .get(s)
                    .is_some_and(|p| p.contains(&id))
                {
                    return Err(format!("node {id} label not posted"));
                }
            }
            for (k, _) in &node.features {
                if !self.layers[&node.layer]
                    .key_postings
                    .get(k)
                    .is_some_and(|p| p.contains(&id))
                {
                    return Err(format!("node {id} feature key not posted"));
                }
            }
            if let Some(p) = node.parent {
                let pn = self
                    .nodes
                    .get(&p)
                    .ok_or(format!("node {id} has missing parent {p}"))?;
                if pn.children.binary_search(&id).is_err() {
                    return Err(format!("node {id} not among its parent's children"));
                }
                if !self.layers[&pn.layer].children.contains(&node.layer) {
                    return Err(format!("node {id} nested off the DAG"));
                }
            }
            if !node.children.is_sorted()
                || !node.out_edges.is_sorted_by_key(|e| e.0)
                || !node.in_edges.is_sorted_by_key(|e| e.0)
            {
                return Err(format!("node {id} relation lists not sorted"));
            }
            for c in &node.children {
                if self.nodes.get(c).and_then(|c| c.parent) != Some(id) {
                    return Err(format!("child {c} of {id} does not point back"));
                }
            }
            for &(t, d) in &node.out_edges {
                let tn = self
                    .nodes
                    .get(&t)
                    .ok_or(format!("edge {id}->{t} dangles"))?;
                if tn.layer != node.layer || t == id {
                    return Err(format!("edge {id}->{t} crosses layers or loops"));
                }
                if tn.in_edges.binary_search(&(id, d)).is_err() {
                    return Err(format!("edge {id}->{t} not mirrored"));
                }
            }
            for &(s, _) in &node.in_edges {
                let mirrored = self
                    .nodes
                    .get(&s)
                    .is_some_and(|sn| sn.out_edges.binary_search_by_key(&id, |e| e.0).is_ok());
                if !mirrored {
                    return Err(format!("in-edge {s}->{id} not mirrored"));
                }
            }
            if node.bbox_enabled {
                let exact = self.brute_subtree_box(id);
                let points = self.brute_subtree_points(id);
                if let Some(b) = exact {
                    let mut counts = [0u32; 6];
                    for p in &points {
                        for a in 0..3 {
                            counts[a] += u32::from(p[a] == b.min[a]);
                            counts[3 + a] += u32::from(p[a] == b.max[a]);
                        }
                    }
                    if counts != node.face_counts {
                        return Err(format!(
                            "node {id} face counts {:?} != {counts:?}",
                            node.face_counts
                        ));
                    }
                }
                if node.box_points != points.len() as u64 {
                    return Err(format!(
                        "node {id} box counts {} points, its sub-tree holds {}",
                        node.box_points,
                        points.len()
                    ));
                }
                if node.aabb != exact {
                    return Err(format!(
                        "node {id} box {:?} != exact {:?}",
                        node.aabb, exact
                    ));
                }
            } else if node.aabb.is_some() {
                return Err(format!("node {id} has a box while disabled"));
            }
        }
        self.check_indexes()
    }

    fn layer_reaches_strictly(&self, l: LayerId) -> bool {
        self.layers[&l]
            .children
            .iter()
            .any(|&c| self.layer_reaches(c, l))
    }

    fn brute_subtree_points(&self, id: NodeId) -> Vec<Point> {
        let node = &self.nodes[&id];
        let mut out = node.points.clone();
        for c in &node.children {
            out.extend(self.brute_subtree_points(*c));
        }
        out
    }

    fn brute_subtree_box(&self, id: NodeId) -> Option<Aabb> {
        let node = &self.nodes[&id];
        let mut acc = Aabb::from_points(&node.points);
        for c in &node.children {
            if let Some(b) = self.brute_subtree_box(*c) {
                acc = Some(acc.map_or(b, |a| a.union(&b)));
            }
        }
        acc
    }
}
