//! The `dsg` rung: Spark-DSG's structure ported as is, in Rust, queried by brute force.
//! Nodes in a vector with their attributes, edges in one list (a node's parent is found
//! by scanning it, as in the paper's baseline), the mesh as a separate vertex array
//! that objects index into with `mesh_connections`.

use super::workload::{Answer, Query, Scan};
use ygg_dsg::{DsgGraph, NodeKind};
use ygg_store::Point;

/// One node, as Spark-DSG stores it.
struct FlatNode {
    id: u64,
    kind: NodeKind,
    label: Option<String>,
    mesh_connections: Vec<u32>,
}

/// The flat baseline.
pub struct FlatDsg {
    nodes: Vec<FlatNode>,
    /// `(parent, child)` for inter-layer edges, plus intra-layer edges (never parents).
    edges: Vec<(u64, u64, bool)>,
    mesh: Vec<Point>,
}

impl FlatDsg {
    /// Copies an imported graph into the flat structure.
    pub fn new(dsg: &DsgGraph) -> Self {
        let nodes = dsg
            .nodes
            .iter()
            .map(|n| FlatNode {
                id: n.id,
                kind: n.kind,
                label: n.label.clone(),
                mesh_connections: n.mesh_connections.clone(),
            })
            .collect();
        let mut edges: Vec<(u64, u64, bool)> = dsg
            .edges
            .iter()
            .map(|e| (e.source, e.target, false))
            .collect();
        edges.extend(
            dsg.nodes
                .iter()
                .filter_map(|n| n.parent.map(|p| (p, n.id, true))),
        );
        FlatDsg {
            nodes,
            edges,
            mesh: dsg
                .mesh
                .as_ref()
                .map(|m| m.points.clone())
                .unwrap_or_default(),
        }
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Approximate heap bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.nodes
            .iter()
            .map(|n| {
                std::mem::size_of::<FlatNode>()
                    + n.mesh_connections.len() * 4
                    + n.label.as_ref().map_or(0, |l| l.len())
            })
            .sum::<usize>()
            + self.edges.len() * std::mem::size_of::<(u64, u64, bool)>()
            + self.mesh.len() * 12
    }

    fn parent(&self, id: u64) -> Option<u64> {
        self.edges.iter().find(|e| e.2 && e.1 == id).map(|e| e.0)
    }

    fn room_of(&self, id: u64) -> Option<u64> {
        let mut cur = self.parent(id);
        for _ in 0..8 {
            let c = cur?;
            if self
                .nodes
                .iter()
                .any(|n| n.id == c && n.kind == NodeKind::Room)
            {
                return Some(c);
            }
            cur = self.parent(c);
        }
        None
    }

    /// Objects in `room` with their claimed vertices (brute force: every object's room
    /// is found through the edge list).
    fn room_objects(&self, room: u64) -> impl Iterator<Item = &FlatNode> + '_ {
        self.nodes
            .iter()
            .filter(move |n| n.kind == NodeKind::Object && self.room_of(n.id) == Some(room))
    }

    /// Answers one workload query by brute force.
    pub fn answer(&self, q: &Query) -> Answer {
        match q {
            Query::Nearest { room, .. }
            | Query::Within { room, .. }
            | Query::Visible { room, .. } => {
                let mut scan = Scan::new(q);
                for o in self.room_objects(*room) {
                    let points = o.mesh_connections.iter().map(|&v| &self.mesh[v as usize]);
                    scan.object(o.id, points);
                }
                scan.answer()
            }
            Query::Label { label } => {
                let mut out: Answer = self
                    .nodes
                    .iter()
                    .filter(|n| {
                        n.kind == NodeKind::Object && n.label.as_deref() == Some(label.as_str())
                    })
                    .map(|n| n.id)
                    .collect();
                out.sort_unstable();
                out
            }
        }
    }
}
