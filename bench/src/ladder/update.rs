//! The workload's update applied to a graph: [`object_rooms`] finds the room of every
//! object (the moved one's among them) and [`move_object`] is the mutation both
//! after-update rows time (`after_update_local` in process, [`super::after_ipc`] across
//! processes).

use super::workload::Workload;
use ygg_dsg::{DsgGraph, NodeKind};
use ygg_store::{NodeId, SceneGraph};

/// The room of every object (its ancestor room).
pub(crate) fn object_rooms(dsg: &DsgGraph) -> rustc_hash::FxHashMap<u64, u64> {
    let index = dsg.node_index();
    dsg.nodes
        .iter()
        .filter(|n| n.kind == NodeKind::Object)
        .filter_map(|o| {
            let mut cur = o.parent;
            for _ in 0..8 {
                let n = &dsg.nodes[*index.get(&cur?)?];
                if n.kind == NodeKind::Room {
                    return Some((o.id, n.id));
                }
                cur = n.parent;
            }
            None
        })
        .collect()
}

/// The after-update mutation, sample `i`: the object's mesh nodes (`mesh`: id and
/// original points) translated by the workload's translation on even samples and put
/// back on odd ones, so the graph ends bit-for-bit as it started.
pub(crate) fn move_object(
    g: &mut SceneGraph,
    mesh: &[(NodeId, Vec<[f32; 3]>)],
    w: &Workload,
    i: usize,
) -> ygg_store::EditResult {
    for (m, original) in mesh {
        let points: Vec<[f32; 3]> = if i.is_multiple_of(2) {
            original
                .iter()
                .map(|p| [0, 1, 2].map(|a| p[a] + w.update_translation[a]))
                .collect()
        } else {
            original.clone()
        };
        g.set_geometry(*m, points)?;
    }
    Ok(())
}
