//! [`Window`]: a sliding window over what the SLAM-like stream ([`SlamReplay`]) adds
//! (agent poses, new objects, mesh points), so a long run serves a scene whose size stops
//! growing: the `--keep-*` options of `ygg serve` (the workload of `ygg-soak`, where any
//! memory that keeps growing is a leak, not the scene) and of `ygg-bench mission`.

use super::{SlamReplay, StepReport};
use crate::layout::{self, LayerRole};
use std::collections::{HashSet, VecDeque};
use ygg_store::query::children;
use ygg_store::{EditResult, LayerId, NodeId, SceneGraph, SceneView};

/// How much of what the stream added to keep (`None`: all of it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Keep {
    /// Agent poses the stream appended to keep (a sliding-window trajectory: the oldest
    /// is removed as each new one arrives).
    pub poses: Option<usize>,
    /// Objects the stream added to keep (the oldest is removed with its mesh).
    pub objects: Option<usize>,
    /// Mesh points the stream appended to each room's unclaimed mesh node to keep (the
    /// oldest go first).
    pub mesh_points: Option<usize>,
}

/// The window's state over one scene.
pub struct Window {
    keep: Keep,
    /// Poses the stream appended, oldest first.
    poses: VecDeque<NodeId>,
    /// Objects the stream added, oldest first.
    objects: VecDeque<NodeId>,
    /// The layers holding objects, and every object the scene had before the stream.
    object_layers: Vec<LayerId>,
    known_objects: HashSet<NodeId>,
    /// Unclaimed mesh nodes and the number of points each had before the stream.
    meshes: Vec<(NodeId, usize)>,
}

impl Window {
    /// A window over the stream on `g`, which holds the scene before its first step.
    pub fn new(g: &SceneGraph, keep: Keep) -> Self {
        let roles: Vec<(LayerId, LayerRole)> = layout::layer_roles(g).collect();
        let nodes = |want: fn(&LayerRole) -> bool| -> Vec<NodeId> {
            roles
                .iter()
                .filter(|(_, r)| want(r))
                .flat_map(|(l, _)| g.layer_nodes(*l).map(|n| g.node_id(n)))
                .collect()
        };
        let meshes = nodes(|r| matches!(r, LayerRole::UnclaimedMesh { .. }))
            .into_iter()
            .map(|id| (id, g.node(id).map_or(0, |n| g.points(n).len())))
            .collect();
        Self {
            keep,
            poses: VecDeque::new(),
            objects: VecDeque::new(),
            object_layers: roles
                .iter()
                .filter(|(_, r)| r.holds_objects())
                .map(|(l, _)| *l)
                .collect(),
            known_objects: nodes(LayerRole::holds_objects).into_iter().collect(),
            meshes,
        }
    }

    /// Removes what fell out of the window after one step of `replay` that did `report`.
    ///
    /// # Errors
    /// A refused mutation (the graph is left as the failing mutation found it).
    pub fn trim(
        &mut self,
        g: &mut SceneGraph,
        replay: &SlamReplay,
        report: StepReport,
    ) -> EditResult {
        if let Some(keep) = self.keep.poses {
            if let Some((pose, _)) = replay.pose().filter(|_| report.poses > 0) {
                self.poses.push_back(pose);
            }
            while self.poses.len() > keep {
                let oldest = self.poses.pop_front().expect("longer than keep");
                g.remove_node(oldest)?;
            }
        }
        if let Some(keep) = self.keep.objects {
            if report.objects_added > 0 {
                let new: Vec<NodeId> = self
                    .object_layers
                    .iter()
                    .flat_map(|l| g.layer_nodes(*l).map(|n| g.node_id(n)))
                    .filter(|id| !self.known_objects.contains(id))
                    .collect();
                self.known_objects.extend(&new);
                self.objects.extend(new);
            }
            while self.objects.len() > keep {
                let oldest = self.objects.pop_front().expect("longer than keep");
                self.known_objects.remove(&oldest);
                for mesh in children(&*g, oldest) {
                    g.remove_node(mesh)?;
                }
                g.remove_node(oldest)?;
            }
        }
        if let Some(keep) = self.keep.mesh_points
            && report.mesh_points > 0
        {
            for &(id, base) in &self.meshes {
                let Some(points) = g.node(id).map(|n| g.points(n)) else {
                    continue;
                };
                if points.len() > base + keep {
                    let mut kept: Vec<_> = points.iter().take(base).copied().collect();
                    kept.extend(points.iter().skip(points.len() - keep).copied());
                    g.set_geometry(id, kept)?;
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::office::{OfficeParams, generate};

    #[test]
    fn the_scene_stops_growing_once_the_window_is_full() {
        let mut g = layout::build(
            &generate(OfficeParams {
                seed: 7,
                scale: 0.05,
            }),
            layout::Layout::Mint,
        )
        .expect("office");
        let keep = Keep {
            poses: Some(20),
            objects: Some(2),
            mesh_points: Some(128),
        };
        let mut replay = SlamReplay::new(&g, 7);
        let mut window = Window::new(&g, keep);
        let points = |g: &SceneGraph| -> usize {
            g.layers()
                .flat_map(|l| {
                    g.layer_nodes(l)
                        .map(|n| g.points(n).len())
                        .collect::<Vec<_>>()
                })
                .sum()
        };
        let mut sizes = Vec::new();
        for tick in 1..=1500 {
            let report = replay.step(&mut g).expect("step");
            window.trim(&mut g, &replay, report).expect("trim");
            if tick % 300 == 0 {
                sizes.push((g.node_count(), points(&g)));
            }
        }
        g.check_invariants().expect("a consistent graph");
        // Full after 2 new objects (300 ticks) and 2 mesh patches per room: from then on
        // the node count is constant and the points vary only with the objects' meshes.
        assert!(
            sizes.windows(2).skip(1).all(|w| w[0].0 == w[1].0),
            "{sizes:?}"
        );
        let (min, max) = sizes[1..]
            .iter()
            .fold((usize::MAX, 0), |(a, b), s| (a.min(s.1), b.max(s.1)));
        assert!(max - min <= 2 * 48, "points {sizes:?}");
        assert!(replay.pose().is_some_and(|(p, _)| g.node(p).is_some()));
    }
}
