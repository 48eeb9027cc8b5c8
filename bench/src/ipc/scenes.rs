//! The graphs the benchmark publishes and the mutations it applies between publishes.

use super::error::Res;
use ygg_dsg::DsgGraph;
use ygg_dsg::layout::{self, Layout};
use ygg_dsg::office::{OfficeParams, generate};
use ygg_store::{LayerId, NodeId, Point, SceneGraph, SceneView};

/// Rooms of the many-layer office: the built-in office split into 103 rooms (418 layers in
/// mint), a realistic large building.
pub const MANY_ROOMS: usize = 103;

/// The built-in office at `scale` (seed 7), as imported Spark-DSG data.
pub fn office_dsg(scale: f64) -> DsgGraph {
    generate(OfficeParams { seed: 7, scale })
}

/// The office in `layout`.
pub fn office(dsg: &DsgGraph, layout: Layout) -> Res<SceneGraph> {
    Ok(layout::build(dsg, layout)?)
}

/// Bytes of the archived segment of the office's `AGENTS` layer.
pub fn agents_segment_bytes(g: &SceneGraph) -> Res<usize> {
    let agents = layout::layer_with_role(g, layout::LayerRole::Agents)
        .ok_or("the office has no AGENTS layer")?;
    let index = g
        .layers()
        .position(|l| l == agents)
        .ok_or("AGENTS is not among the layers")?;
    Ok(g.to_segments().layers[index].len())
}

/// Bytes of the whole archived graph (manifest and every layer).
pub fn archived_bytes(g: &SceneGraph) -> usize {
    g.to_segments().len()
}

/// Moves agent poses of the `AGENTS` layer round robin, a few centimetres each time:
/// a single-layer update (only `AGENTS` changes).
pub struct AgentMover {
    agents: Vec<(NodeId, Point)>,
    step: u64,
}

impl AgentMover {
    /// The agent poses of `g` (nodes of layer `AGENTS` with one point).
    pub fn new(g: &SceneGraph) -> Res<Self> {
        let layer = ygg_dsg::layout::layer_with_role(g, ygg_dsg::layout::LayerRole::Agents)
            .ok_or("the office has no AGENTS layer")?;
        let agents: Vec<(NodeId, Point)> = g
            .layer_nodes(layer)
            .filter_map(|n| g.points(n).first().map(|p| (g.node_id(n), *p)))
            .collect();
        if agents.is_empty() {
            return Err("the office has no agent poses".into());
        }
        Ok(AgentMover { agents, step: 0 })
    }

    /// Moves the next agent pose.
    pub fn step(&mut self, g: &mut SceneGraph) -> Res<()> {
        let (id, base) = self.agents[(self.step % self.agents.len() as u64) as usize];
        let offset = 0.01 * (self.step % 97) as f32;
        g.set_geometry(id, vec![[base[0] + offset, base[1], base[2]]])?;
        self.step += 1;
        Ok(())
    }
}

/// Grows and shrinks the office's largest unclaimed-mesh node at its end, as SLAM
/// extends a mesh: 64 new vertices on even ticks, the same 64 taken off on odd ones (so
/// that the layer keeps its size over a long run). Only the node's layer changes, and
/// only at the end of its point column.
pub struct MeshGrower {
    node: NodeId,
    base: Vec<Point>,
}

/// Vertices [`MeshGrower`] appends per tick (what the SLAM stream adds per mesh patch).
pub const MESH_PATCH: usize = 64;

impl MeshGrower {
    /// The largest node of `g`'s unclaimed-mesh layers.
    pub fn new(g: &SceneGraph) -> Res<Self> {
        let (node, base) = g
            .layers()
            .filter(|&l| {
                g.layer_name(l)
                    .is_some_and(|n| n.ends_with("unclaimed-mesh"))
            })
            .flat_map(|l| g.layer_nodes(l))
            .max_by_key(|&n| g.points(n).len())
            .map(|n| (g.node_id(n), g.points(n).to_vec()))
            .ok_or("the office has no unclaimed mesh")?;
        Ok(MeshGrower { node, base })
    }

    /// Points of the node before the first tick.
    pub fn base_points(&self) -> usize {
        self.base.len()
    }

    /// Appends (even `tick`) or removes (odd) the last [`MESH_PATCH`] vertices.
    pub fn step(&mut self, g: &mut SceneGraph, tick: u64) -> Res<()> {
        let mut points = self.base.clone();
        if tick.is_multiple_of(2) {
            let z = 0.001 * (tick % 1000) as f32;
            points.extend((0..MESH_PATCH).map(|k| {
                let p = self.base[k % self.base.len()];
                [p[0], p[1], p[2] + z]
            }));
        }
        g.set_geometry(self.node, points)?;
        Ok(())
    }
}

/// Changes every layer: adds (even `tick`) or removes (odd) one geometry-less node per
/// layer, so that every layer is republished.
pub fn touch_all_layers(g: &mut SceneGraph, tick: u64) -> Res<()> {
    let layers: Vec<LayerId> = g.layers().collect();
    for l in layers {
        let id = NodeId(0xFE << 56 | u64::from(l.0));
        if tick.is_multiple_of(2) {
            g.add_node(id, l)?;
        } else {
            g.remove_node(id)?;
        }
    }
    Ok(())
}

/// Points per node of [`sized_layer`]: point-set nodes, as mesh layers hold them.
const POINTS_PER_NODE: usize = 4096;

/// A graph with one layer whose archived segment is about `target` bytes: nodes holding
/// point sets (flat columns, as mesh layers are). Returns it with the node to move.
pub fn sized_layer(target: usize) -> Res<(SceneGraph, NodeId)> {
    // About 600 bytes of fixed overhead, 12 per point and ~40 per node.
    let budget = target.saturating_sub(600).max(12);
    let nodes = (budget / 12).div_ceil(POINTS_PER_NODE).max(1);
    let points = (budget.saturating_sub(40 * nodes) / 12).max(1);
    let mut g = SceneGraph::new();
    let layer = g.add_layer("blob")?;
    let mut seed = 0x9E37_79B9_7F4A_7C15u64;
    let mut coordinate = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 40) as f32 / 1e5
    };
    let mut left = points;
    for i in 0..nodes as u64 {
        let k = left.div_ceil(nodes - i as usize);
        left -= k;
        g.add_node(NodeId(i), layer)?;
        let pts: Vec<Point> = (0..k)
            .map(|_| [coordinate(), coordinate(), coordinate()])
            .collect();
        g.set_geometry(NodeId(i), pts)?;
    }
    Ok((g, NodeId(0)))
}

/// A small scene: one layer of 16 single-point nodes (a segment of about 2 KB).
pub fn small() -> Res<(SceneGraph, NodeId)> {
    let mut g = SceneGraph::new();
    let layer = g.add_layer("small")?;
    for i in 0..16u64 {
        g.add_node(NodeId(i), layer)?;
        g.set_geometry(NodeId(i), vec![[i as f32, 0.0, 1.0]])?;
    }
    Ok((g, NodeId(0)))
}

/// Moves the first point of `id` a little (its layer is republished).
pub fn nudge(g: &mut SceneGraph, id: NodeId, tick: u64) -> Res<()> {
    let node = g.node(id).ok_or("node to move is missing")?;
    let mut points = g.points(node).to_vec();
    if let Some(p) = points.first_mut() {
        p[2] = (tick % 1000) as f32 * 1e-3;
    }
    g.set_geometry(id, points)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sized_layers_come_close_to_their_target() {
        for target in [1_000usize, 100_000, 1_000_000] {
            let (g, _) = sized_layer(target).unwrap();
            let bytes = archived_bytes(&g) as f64;
            let off = (bytes - target as f64).abs() / target as f64;
            // The manifest (a few hundred bytes) is included: loose for the smallest.
            assert!(
                off < if target < 10_000 { 0.8 } else { 0.05 },
                "{target}: {bytes}"
            );
        }
    }

    #[test]
    fn an_agent_move_changes_one_layer_and_a_touch_all_of_them() {
        let mut g = office(&office_dsg(0.05), Layout::Mint).unwrap();
        let generations = |g: &SceneGraph| -> Vec<Option<u64>> {
            g.layers().map(|l| g.layer_generation(l)).collect()
        };
        let changed =
            |a: &[Option<u64>], b: &[Option<u64>]| a.iter().zip(b).filter(|(x, y)| x != y).count();
        let before = generations(&g);
        let mut mover = AgentMover::new(&g).unwrap();
        mover.step(&mut g).unwrap();
        let after = generations(&g);
        assert_eq!(changed(&before, &after), 1);
        for tick in 0..2 {
            let before = generations(&g);
            touch_all_layers(&mut g, tick).unwrap();
            assert_eq!(changed(&before, &generations(&g)), before.len());
        }
    }
}
