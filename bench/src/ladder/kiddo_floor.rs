//! The floor for Q1a / Q1b: a bare kiddo `ImmutableKdTree` per room over the room's
//! claimed vertices, with no scene graph around it (no tie rule, no nesting).

use super::harness::Target;
use super::workload::{Answer, Query};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rustc_hash::FxHashMap;
use ygg_dsg::{DsgGraph, NodeKind};

/// Per room: the tree and the owner object of each point.
pub struct KiddoFloor {
    rooms: FxHashMap<u64, (ImmutableKdTree<f32, 3>, Vec<u64>)>,
}

impl KiddoFloor {
    /// Builds one tree per room from the claimed vertices of the room's objects.
    pub fn new(dsg: &DsgGraph, room_of: &FxHashMap<u64, u64>) -> Self {
        let mut points: FxHashMap<u64, (Vec<[f32; 3]>, Vec<u64>)> = FxHashMap::default();
        let mesh = dsg
            .mesh
            .as_ref()
            .map(|m| m.points.as_slice())
            .unwrap_or_default();
        for o in dsg.nodes.iter().filter(|n| n.kind == NodeKind::Object) {
            let Some(&room) = room_of.get(&o.id) else {
                continue;
            };
            let e = points.entry(room).or_default();
            let mut v = o.mesh_connections.clone();
            v.sort_unstable();
            v.dedup();
            for i in v {
                if let Some(p) = mesh.get(i as usize) {
                    e.0.push(*p);
                    e.1.push(o.id);
                }
            }
        }
        let rooms = points
            .into_iter()
            .filter(|(_, (p, _))| !p.is_empty())
            .filter_map(|(room, (p, owners))| {
                Some((room, (ImmutableKdTree::new_from_slice(&p).ok()?, owners)))
            })
            .collect();
        KiddoFloor { rooms }
    }
}

impl Target for KiddoFloor {
    fn name(&self) -> String {
        "kiddo".into()
    }

    fn answer(&self, q: &Query) -> Answer {
        match q {
            Query::Nearest { room, point } => {
                let Some((tree, owners)) = self.rooms.get(room) else {
                    return Vec::new();
                };
                let n = tree
                    .query(point)
                    .nearest_one::<SquaredEuclidean<f32>>()
                    .execute();
                vec![owners[n.item as usize]]
            }
            Query::Within {
                room,
                point,
                radius,
            } => {
                let Some((tree, owners)) = self.rooms.get(room) else {
                    return Vec::new();
                };
                let mut out: Answer = tree
                    .query(point)
                    .within::<SquaredEuclidean<f32>>(radius * radius)
                    .unsorted()
                    .execute()
                    .iter()
                    .map(|n| owners[n.item as usize])
                    .collect();
                out.sort_unstable();
                out.dedup();
                out
            }
            Query::Visible { .. } | Query::Label { .. } => Vec::new(),
        }
    }
}
