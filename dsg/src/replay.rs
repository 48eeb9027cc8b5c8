//! [`SlamReplay`]: a SLAM-like stream of updates for a served office: agent poses
//! appended at the tick rate, objects moving and appearing, the mesh growing room by
//! room. It drives `ygg serve --rate`, `ygg demo` and `ygg-bench mission`; [`window`]
//! keeps only the newest of what it adds.

pub mod window;

use crate::NodeSymbol;
use crate::layout::{self, LayerRole};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use ygg_store::query::{self, children};
use ygg_store::{
    EditResult, FeatureValue, LayerId, NodeId, Point, SceneGraph, SceneView, distance_squared,
};

/// What one [`SlamReplay::step`] changed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepReport {
    /// Agent poses appended.
    pub poses: u32,
    /// Objects moved.
    pub objects_moved: u32,
    /// Objects added.
    pub objects_added: u32,
    /// Mesh points added.
    pub mesh_points: u32,
}

/// One mutation of the stream, as [`SlamReplay::step_recorded`] reports it: the stream
/// can then be replayed elsewhere (through the C API, say) exactly as it was applied.
#[derive(Clone, Debug, PartialEq)]
pub enum Edit {
    /// [`SceneGraph::add_node`].
    AddNode {
        /// The new node.
        node: NodeId,
        /// Its layer.
        layer: LayerId,
    },
    /// [`SceneGraph::set_geometry`].
    SetGeometry {
        /// The node.
        node: NodeId,
        /// Its new points.
        points: Vec<Point>,
    },
    /// [`SceneGraph::append_points`].
    AppendPoints {
        /// The node.
        node: NodeId,
        /// The points appended to its geometry.
        points: Vec<Point>,
    },
    /// [`SceneGraph::set_feature`].
    SetFeature {
        /// The node.
        node: NodeId,
        /// The key.
        key: &'static str,
        /// The value.
        value: FeatureValue,
    },
    /// [`SceneGraph::add_label`].
    AddLabel {
        /// The node.
        node: NodeId,
        /// The label.
        label: &'static str,
    },
    /// [`SceneGraph::add_edge`].
    AddEdge {
        /// Source node.
        source: NodeId,
        /// Target node.
        target: NodeId,
        /// The description.
        description: &'static str,
    },
    /// [`SceneGraph::nest`].
    Nest {
        /// The parent.
        parent: NodeId,
        /// The child.
        child: NodeId,
    },
}

impl Edit {
    /// Applies the mutation to `g` (copying the points of a [`Edit::SetGeometry`]).
    ///
    /// # Errors
    /// The mutation's own error; `g` is then unchanged.
    pub fn apply(&self, g: &mut SceneGraph) -> EditResult {
        match self {
            Edit::AddNode { node, layer } => g.add_node(*node, *layer),
            Edit::SetGeometry { node, points } => g.set_geometry(*node, points.clone()),
            Edit::AppendPoints { node, points } => g.append_points(*node, points),
            Edit::SetFeature { node, key, value } => g.set_feature(*node, key, value.clone()),
            Edit::AddLabel { node, label } => g.add_label(*node, label),
            Edit::AddEdge {
                source,
                target,
                description,
            } => g.add_edge(*source, *target, description),
            Edit::Nest { parent, child } => g.nest(*parent, *child),
        }
    }

    /// Applies the mutation to `g`, moving its points.
    fn apply_owned(self, g: &mut SceneGraph) -> EditResult {
        match self {
            Edit::SetGeometry { node, points } => g.set_geometry(node, points),
            other => other.apply(g),
        }
    }
}

/// Where a step's edits are applied: to the graph alone, or also recorded.
struct Sink<'a> {
    graph: &'a mut SceneGraph,
    log: Option<&'a mut Vec<Edit>>,
}

impl Sink<'_> {
    /// Applies `edit` and records it if it succeeded.
    fn apply(&mut self, edit: Edit) -> EditResult {
        match self.log.as_deref_mut() {
            Some(log) => {
                edit.apply(self.graph)?;
                log.push(edit);
                Ok(())
            }
            None => edit.apply_owned(self.graph),
        }
    }
}

/// A deterministic SLAM-like update stream over a scene built by
/// [`crate::layout::build`] (any layout; pieces a scene lacks are skipped).
pub struct SlamReplay {
    rng: ChaCha8Rng,
    tick: u64,
    agents: Option<LayerId>,
    places: Option<PlaceMap>,
    last_pose: Option<NodeId>,
    next_pose: u64,
    position: Point,
    waypoint: Point,
    rooms: Vec<(NodeId, [f32; 6])>,
    objects: Vec<NodeId>,
    next_object: u64,
}

/// The places a pose may nest under, as the replay's own map (a SLAM front end keeps its
/// place graph itself; it does not search the published scene for it): every point of every
/// node of the places layer, read when the replay starts and again whenever the layer's node
/// count changed or the place found is gone. The nearest place is then a scan of a flat
/// array (about 1 µs for the office's 1,130 places) instead of a walk over the live graph's
/// nodes (about 150 µs per tick, most of what a tick cost). It answers what
/// [`query::nearest_nodes`] answers on the places as they were read: the same distances,
/// ties to the smaller id.
struct PlaceMap {
    layer: LayerId,
    /// Node count of the layer when `points` was read.
    nodes: usize,
    /// `(point, place)` for every point of every place.
    points: Vec<(Point, NodeId)>,
}

impl PlaceMap {
    fn new(g: &SceneGraph, layer: LayerId) -> Self {
        let mut map = PlaceMap {
            layer,
            nodes: 0,
            points: Vec::new(),
        };
        map.read(g);
        map
    }

    fn read(&mut self, g: &SceneGraph) {
        self.nodes = g.layer_len(self.layer);
        self.points.clear();
        for n in g.layer_nodes(self.layer) {
            let id = g.node_id(n);
            self.points.extend(g.points(n).iter().map(|&p| (p, id)));
        }
    }

    /// The place nearest to `c` (ties to the smaller id), if the layer holds a point.
    fn nearest(&mut self, g: &SceneGraph, c: &Point) -> Option<NodeId> {
        if g.layer_len(self.layer) != self.nodes {
            self.read(g);
        }
        let found = self.scan(c)?;
        if g.node(found).is_some_and(|n| g.node_layer(n) == self.layer) {
            return Some(found);
        }
        self.read(g);
        self.scan(c)
    }

    fn scan(&self, c: &Point) -> Option<NodeId> {
        self.points
            .iter()
            .map(|(p, id)| (distance_squared(p, c), *id))
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
            .map(|(_, id)| id)
    }
}

/// Ticks between object moves, mesh patches and new objects (at 30 Hz: 1 s, 0.5 s, 5 s).
const MOVE_EVERY: u64 = 30;
const MESH_EVERY: u64 = 15;
const NEW_OBJECT_EVERY: u64 = 150;
/// Metres an agent moves per tick.
const STEP: f32 = 0.05;

impl SlamReplay {
    /// A stream over `g` from a fixed seed.
    pub fn new(g: &SceneGraph, seed: u64) -> Self {
        let agents = layout::layer_with_role(g, LayerRole::Agents);
        let places = layout::layer_with_role(g, LayerRole::Places).map(|l| PlaceMap::new(g, l));
        let last_pose = agents.and_then(|l| g.layer_nodes(l).map(|n| g.node_id(n)).max());
        let next_pose = last_pose.map_or(0, |p| NodeSymbol(p.0).index() + 1);
        let position = last_pose
            .and_then(|p| g.node(p))
            .and_then(|n| g.points(n).first().copied())
            .unwrap_or([1.0, 12.5, 1.0]);
        let rooms: Vec<(NodeId, [f32; 6])> = layout::layer_with_role(g, LayerRole::Rooms)
            .map(|l| {
                g.layer_nodes(l)
                    .filter_map(|n| Some((g.node_id(n), g.aabb(n)?.to_array())))
                    .collect()
            })
            .unwrap_or_default();
        let mut objects: Vec<NodeId> = layout::object_mesh_layers(g)
            .into_iter()
            .flat_map(|(l, _)| {
                g.layer_nodes(l)
                    .filter_map(|m| g.parent(m))
                    .collect::<Vec<_>>()
            })
            .collect();
        objects.sort_unstable();
        objects.dedup();
        SlamReplay {
            rng: ChaCha8Rng::seed_from_u64(seed),
            tick: 0,
            agents,
            places,
            last_pose,
            next_pose,
            position,
            waypoint: position,
            rooms,
            objects,
            next_object: 100_000,
        }
    }

    /// The newest agent pose and its position.
    pub fn pose(&self) -> Option<(NodeId, Point)> {
        self.last_pose.map(|p| (p, self.position))
    }

    /// Applies one tick of updates.
    ///
    /// # Errors
    /// A refused mutation (which would mean the scene broke the layout's conventions);
    /// the graph is left as the failing mutation found it.
    pub fn step(&mut self, g: &mut SceneGraph) -> EditResult<StepReport> {
        self.step_into(&mut Sink {
            graph: g,
            log: None,
        })
    }

    /// [`SlamReplay::step`] that also appends each mutation it applied to `log`, in
    /// order, so the same stream can be applied to another graph (or through another
    /// API) with [`Edit::apply`].
    ///
    /// # Errors
    /// As [`SlamReplay::step`]; `log` then holds the mutations applied before the error.
    pub fn step_recorded(
        &mut self,
        g: &mut SceneGraph,
        log: &mut Vec<Edit>,
    ) -> EditResult<StepReport> {
        self.step_into(&mut Sink {
            graph: g,
            log: Some(log),
        })
    }

    fn step_into(&mut self, s: &mut Sink<'_>) -> EditResult<StepReport> {
        self.tick += 1;
        let mut report = StepReport::default();
        if let Some(agents) = self.agents {
            self.append_pose(s, agents)?;
            report.poses = 1;
        }
        if self.tick.is_multiple_of(MOVE_EVERY) && !self.objects.is_empty() {
            let o = self.objects[self.rng.gen_range(0..self.objects.len())];
            let d = [
                self.rng.gen_range(-0.02..0.02),
                self.rng.gen_range(-0.02..0.02),
                0.0,
            ];
            for m in children(&*s.graph, o) {
                let moved: Vec<Point> = s
                    .graph
                    .node(m)
                    .map(|n| {
                        s.graph
                            .points(n)
                            .iter()
                            .map(|p| [p[0] + d[0], p[1] + d[1], p[2] + d[2]])
                            .collect()
                    })
                    .unwrap_or_default();
                s.apply(Edit::SetGeometry {
                    node: m,
                    points: moved,
                })?;
            }
            report.objects_moved = 1;
        }
        if self.tick.is_multiple_of(MESH_EVERY) {
            report.mesh_points = self.grow_mesh(s)?;
        }
        if self.tick.is_multiple_of(NEW_OBJECT_EVERY) {
            report.objects_added = self.add_object(s)?;
        }
        Ok(report)
    }

    fn append_pose(&mut self, s: &mut Sink<'_>, agents: LayerId) -> EditResult {
        let to = [
            self.waypoint[0] - self.position[0],
            self.waypoint[1] - self.position[1],
        ];
        let dist = (to[0] * to[0] + to[1] * to[1]).sqrt();
        if dist < STEP {
            if let Some(&(_, b)) = self
                .rooms
                .get(self.rng.gen_range(0..self.rooms.len().max(1)))
            {
                self.waypoint = [
                    self.rng.gen_range(b[0]..=b[3]),
                    self.rng.gen_range(b[1]..=b[4]),
                    1.0,
                ];
            }
        } else {
            self.position = [
                self.position[0] + to[0] / dist * STEP,
                self.position[1] + to[1] / dist * STEP,
                1.0,
            ];
        }
        let id = NodeId(NodeSymbol::new(b'a', self.next_pose).0);
        self.next_pose += 1;
        s.apply(Edit::AddNode {
            node: id,
            layer: agents,
        })?;
        s.apply(Edit::SetGeometry {
            node: id,
            points: vec![self.position],
        })?;
        s.apply(Edit::SetFeature {
            node: id,
            key: "timestamp_ns",
            value: FeatureValue::Int((self.tick * 33_333_333) as i64),
        })?;
        if let Some(prev) = self.last_pose.filter(|p| s.graph.node(*p).is_some()) {
            s.apply(Edit::AddEdge {
                source: prev,
                target: id,
                description: "odometry",
            })?;
        }
        let position = self.position;
        if let Some(place) = self
            .places
            .as_mut()
            .and_then(|places| places.nearest(s.graph, &position))
        {
            // Nesting needs a places -> agents layer edge; scenes without one skip it.
            let _ = s.apply(Edit::Nest {
                parent: place,
                child: id,
            });
        }
        self.last_pose = Some(id);
        Ok(())
    }

    /// Appends a patch of mesh points to one room's unclaimed mesh (rooms in turn).
    fn grow_mesh(&mut self, s: &mut Sink<'_>) -> EditResult<u32> {
        if self.rooms.is_empty() {
            return Ok(0);
        }
        let (room, b) = self.rooms[(self.tick / MESH_EVERY) as usize % self.rooms.len()];
        let g = &*s.graph;
        let target = layout::layer_with_role(g, LayerRole::UnclaimedMesh { room })
            .and_then(|l| g.layer_nodes(l).map(|n| g.node_id(n)).min());
        let Some(target) = target else { return Ok(0) };
        let n = 64;
        let points = (0..n)
            .map(|_| {
                [
                    self.rng.gen_range(b[0]..=b[3]),
                    self.rng.gen_range(b[1]..=b[4]),
                    self.rng.gen_range(0.0..3.0),
                ]
            })
            .collect();
        s.apply(Edit::AppendPoints {
            node: target,
            points,
        })?;
        Ok(n)
    }

    /// Adds an object with a small mesh in a random room (per-room layouts only).
    fn add_object(&mut self, s: &mut Sink<'_>) -> EditResult<u32> {
        if self.rooms.is_empty() {
            return Ok(0);
        }
        let (room, b) = self.rooms[self.rng.gen_range(0..self.rooms.len())];
        let g = &*s.graph;
        let (Some(objects), Some(mesh)) = (
            layout::layer_with_role(g, LayerRole::ClaimedObjects { room }),
            layout::layer_with_role(g, LayerRole::ClaimedMesh { room }),
        ) else {
            return Ok(0);
        };
        let claimed = layout::layer_with_role(g, LayerRole::RoomGroups { room })
            .and_then(|l| g.layer_nodes(l).map(|n| g.node_id(n)).min());
        let Some(claimed) = claimed else { return Ok(0) };
        let object = NodeId(NodeSymbol::new(b'O', self.next_object).0);
        let mesh_node = NodeId(0xF5 << 56 | self.next_object);
        self.next_object += 1;
        let centre = [
            self.rng.gen_range(b[0]..=b[3]),
            self.rng.gen_range(b[1]..=b[4]),
            self.rng.gen_range(0.3..2.0),
        ];
        let points: Vec<Point> = (0..48)
            .map(|_| [0, 1, 2].map(|a| centre[a] + self.rng.gen_range(-0.15f32..0.15)))
            .collect();
        let label = ["chair", "plant", "box", "person"][self.rng.gen_range(0..4)];
        for edit in [
            Edit::AddNode {
                node: object,
                layer: objects,
            },
            Edit::AddLabel {
                node: object,
                label,
            },
            Edit::Nest {
                parent: claimed,
                child: object,
            },
            Edit::AddNode {
                node: mesh_node,
                layer: mesh,
            },
            Edit::SetGeometry {
                node: mesh_node,
                points,
            },
            Edit::Nest {
                parent: object,
                child: mesh_node,
            },
        ] {
            s.apply(edit)?;
        }
        if query::parent(&*s.graph, object).is_some() {
            self.objects.push(object);
        }
        Ok(1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::Layout;
    use crate::office::{self, OfficeParams};

    #[test]
    fn poses_nest_under_the_place_nearest_by_brute_force() {
        use ygg_store::{Scope, query::nearest_nodes};
        let office = office::generate(OfficeParams {
            seed: 7,
            scale: 0.1,
        });
        let mut g = layout::build(&office, Layout::Mint).expect("layout");
        let places = layout::layer_with_role(&g, LayerRole::Places).expect("places");
        let mut replay = SlamReplay::new(&g, 5);
        for tick in 0..300 {
            replay.step(&mut g).expect("step");
            let (pose, at) = replay.pose().expect("pose");
            let near = nearest_nodes(&g, Scope::Layer(places), at, 1).expect("query");
            assert_eq!(query::parent(&g, pose), Some(near[0].0), "tick {tick}");
            if tick == 100 {
                // A place removed behind the replay's back is never chosen again.
                g.remove_node(near[0].0).expect("remove place");
            }
        }
    }

    #[test]
    fn a_recorded_stream_applied_to_a_copy_gives_the_same_graph() {
        let office = office::generate(OfficeParams {
            seed: 7,
            scale: 0.02,
        });
        let mut live = layout::build(&office, Layout::Mint).expect("layout");
        let mut copy = live.clone();
        let mut replay = SlamReplay::new(&live, 3);
        let mut log = Vec::new();
        for _ in 0..320 {
            replay.step_recorded(&mut live, &mut log).expect("step");
        }
        assert!(
            log.iter().any(|e| matches!(e, Edit::AddLabel { .. })),
            "no object added"
        );
        for edit in &log {
            edit.apply(&mut copy).expect("replayed edit");
        }
        assert_eq!(copy.node_count(), live.node_count());
        for layer in live.layers() {
            for n in live.layer_nodes(layer) {
                let id = live.node_id(n);
                let m = copy.node(id).expect("node in the copy");
                assert_eq!(copy.points(m), live.points(n), "points of {id}");
                assert_eq!(copy.parent(m), live.parent(n), "parent of {id}");
                assert_eq!(copy.aabb(m), live.aabb(n), "box of {id}");
            }
        }
    }
}
