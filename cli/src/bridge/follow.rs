//! Bringing the bridge's live graph to each message's graph: decode (reusing the last
//! message's mesh when unchanged), then either patch the moved nodes ([`super::patch`])
//! or build the whole layout and sync to it.

use std::time::{Duration, Instant};

use bytes::Bytes;
use ygg_dsg::layout::{self, Layout};
use ygg_dsg::{BodyStream, DsgVersion};
use ygg_store::{SceneGraph, SyncReport};

use super::patch;

/// A message that could not become a graph.
#[derive(Debug, thiserror::Error)]
pub(super) enum FrameError {
    #[error("a message of {0} frames (Spark-DSG sends one)")]
    Frames(usize),
    #[error(transparent)]
    Decode(#[from] ygg_dsg::DsgImportError),
    #[error(transparent)]
    Layout(#[from] layout::LayoutError),
    #[error("could not apply the message: {0}")]
    Sync(#[from] ygg_store::GraphEditError),
    #[error(transparent)]
    Update(#[from] ygg_dsg::UpdateError),
}

/// An incremental update: a Spark-DSG body of the nodes changed or added (and the edges
/// added), and the nodes and edges removed ([`ygg_dsg::DsgGraph::apply_update`]).
pub struct Delta {
    /// The body of the changed part.
    pub contents: Bytes,
    /// Nodes removed.
    pub deleted_nodes: Vec<u64>,
    /// Edges removed, as consecutive (source, target) pairs.
    pub deleted_edges: Vec<u64>,
}

/// How a message reached the live graph.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Path {
    /// Byte for byte the last message: nothing to do.
    Unchanged,
    /// Only nodes moved: their mutations, without building the layout.
    Patch,
    /// The layout built in full and [`SceneGraph::sync_to`].
    Build,
}

impl Path {
    /// The name in the bridge's `update` lines.
    pub(super) fn name(self) -> &'static str {
        match self {
            Path::Unchanged => "unchanged",
            Path::Patch => "patch",
            Path::Build => "build",
        }
    }
}

/// What one message did.
pub(super) struct Applied {
    /// The path taken.
    pub path: Path,
    /// Whether the decoder reused the last message's mesh (its bytes were unchanged).
    pub mesh_reused: bool,
    /// The changes made to the live graph (empty when unchanged).
    pub report: SyncReport,
    /// Decoding the message, and building its layout on [`Path::Build`].
    pub decode: Duration,
    /// Syncing or patching the live graph.
    pub sync: Duration,
}

/// Follows a stream of full-state messages with a live graph.
pub(super) struct Follower {
    stream: BodyStream<Bytes>,
    layout: Layout,
}

impl Follower {
    /// A follower building `layout` from bodies encoded at `version`; the first message
    /// is decoded in full. `source` names the messages in errors (`zmq message`).
    pub(super) fn new(layout: Layout, source: &str, version: DsgVersion) -> Self {
        Self {
            stream: BodyStream::new(version, source),
            layout,
        }
    }

    /// The first good message's graph in the layout, to create the scene with; `None`
    /// when the message is byte for byte the last one.
    ///
    /// # Errors
    /// A message that does not decode or build; the follower then forgets it.
    pub(super) fn first(&mut self, frames: Vec<Bytes>) -> Result<Option<SceneGraph>, FrameError> {
        let frame = one_frame(frames)?;
        if self.stream.decode(frame)?.is_none() {
            return Ok(None);
        }
        let built = self.build();
        if built.is_err() {
            self.stream.forget();
        }
        built.map(Some)
    }

    /// Brings `live` (the layout of the last message this follower applied) to the
    /// message's graph.
    ///
    /// # Errors
    /// A message that does not decode, build or apply. `live` then keeps the last good
    /// graph, unless a mutation was refused mid-way (a bug), in which case it is partly
    /// synced; either way the next message is decoded and built in full.
    pub(super) fn apply(
        &mut self,
        frames: Vec<Bytes>,
        live: &mut SceneGraph,
    ) -> Result<Applied, FrameError> {
        let t0 = Instant::now();
        let frame = one_frame(frames)?;
        let Some(step) = self.stream.decode(frame)? else {
            return Ok(Applied {
                path: Path::Unchanged,
                mesh_reused: true,
                report: SyncReport::default(),
                decode: t0.elapsed(),
                sync: Duration::ZERO,
            });
        };
        let graph = self.stream.graph().expect("decoded above");
        let moves = match (&step.previous, &step.changed_nodes) {
            (Some(p), _) => patch::plan(p, graph, step.mesh_reused, self.layout),
            (None, Some(changed)) => patch::plan_changed(changed, graph, self.layout),
            (None, None) => None,
        };
        self.patch_or_build(moves, live, t0, step.mesh_reused)
    }

    /// Brings `live` to the stream's graph after applying the incremental update `delta`
    /// to it: the moves of the nodes it replaced when that is all it did, else the
    /// general path.
    ///
    /// # Errors
    /// As [`Follower::apply`], and an update that does not fit the graph (which then
    /// stays as it was).
    pub(super) fn apply_update(
        &mut self,
        delta: &Delta,
        live: &mut SceneGraph,
    ) -> Result<Applied, FrameError> {
        let t0 = Instant::now();
        let report = self.stream.apply_update(
            &delta.contents,
            &delta.deleted_nodes,
            &delta.deleted_edges,
        )?;
        let graph = self.stream.graph().expect("updated above");
        if report.nodes_only() && report.replaced.is_empty() {
            return Ok(Applied {
                path: Path::Unchanged,
                mesh_reused: true,
                report: SyncReport::default(),
                decode: t0.elapsed(),
                sync: Duration::ZERO,
            });
        }
        let moves = report.nodes_only().then(|| {
            let pairs = report
                .replaced
                .iter()
                .map(|(i, old)| (old, &graph.nodes[*i]));
            patch::node_moves(pairs, graph, self.layout)
        });
        self.patch_or_build(moves.flatten(), live, t0, !report.rest_changed)
    }

    /// Applies `moves` to `live` when there are some and `live` takes them, else builds
    /// the stream's graph and syncs `live` to it; `t0`: when the message arrived.
    fn patch_or_build(
        &mut self,
        moves: Option<Vec<patch::Move>>,
        live: &mut SceneGraph,
        t0: Instant,
        mesh_reused: bool,
    ) -> Result<Applied, FrameError> {
        if let Some(moves) = moves {
            let t1 = Instant::now();
            if let Ok(report) = patch::apply(live, &moves) {
                return Ok(Applied {
                    path: Path::Patch,
                    mesh_reused,
                    report,
                    decode: t1 - t0,
                    sync: t1.elapsed(),
                });
            }
            // A refused move means `live` is not what the plan assumed: sync in full.
        }
        let synced = self.build().and_then(|target| {
            let t1 = Instant::now();
            let report = live.sync_to_owned(target)?;
            Ok((report, t1))
        });
        match synced {
            Ok((report, t1)) => Ok(Applied {
                path: Path::Build,
                mesh_reused,
                report,
                decode: t1 - t0,
                sync: t1.elapsed(),
            }),
            Err(e) => {
                self.stream.forget();
                Err(e)
            }
        }
    }

    /// The layout of the stream's current graph.
    fn build(&self) -> Result<SceneGraph, FrameError> {
        let graph = self.stream.graph().expect("a decoded graph");
        Ok(layout::build(graph, self.layout)?)
    }
}

/// The one frame of a Spark-DSG message.
fn one_frame(frames: Vec<Bytes>) -> Result<Bytes, FrameError> {
    <[Bytes; 1]>::try_from(frames)
        .map(|[f]| f)
        .map_err(|f| FrameError::Frames(f.len()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use ygg_dsg::office::{OfficeParams, generate};
    use ygg_dsg::{DsgGraph, NodeKind, to_binary_body};

    /// One change between two messages.
    #[derive(Clone, Debug)]
    enum Edit {
        /// The `i`-th node of `kind` moves by `d` along `axis`.
        Move(NodeKind, usize, usize, f32),
        /// An object loses its parent (its room then follows from its position) and moves.
        Orphan(usize, f32),
        /// Mesh vertex `i` moves.
        MoveVertex(usize, f32),
        /// The last agent pose is dropped, with its edges.
        DropAgent,
        /// The message is sent again unchanged.
        Same,
        /// A truncated message (a bad frame).
        Truncate(usize),
    }

    fn edit() -> impl Strategy<Value = Edit> {
        let kind = prop_oneof![
            Just(NodeKind::Object),
            Just(NodeKind::Place),
            Just(NodeKind::Place2d),
            Just(NodeKind::Agent),
            Just(NodeKind::Room),
        ];
        prop_oneof![
            6 => (kind, any::<usize>(), 0..3usize, -0.5f32..0.5)
                .prop_map(|(k, i, a, d)| Edit::Move(k, i, a, d)),
            1 => (any::<usize>(), -0.5f32..0.5).prop_map(|(i, d)| Edit::Orphan(i, d)),
            1 => (any::<usize>(), -0.5f32..0.5).prop_map(|(i, d)| Edit::MoveVertex(i, d)),
            1 => Just(Edit::DropAgent),
            1 => Just(Edit::Same),
            1 => any::<usize>().prop_map(Edit::Truncate),
        ]
    }

    /// Applies `e` to `g`; returns the body to send.
    fn change(g: &mut DsgGraph, e: &Edit) -> Vec<u8> {
        let nth = |g: &DsgGraph, kind: NodeKind, i: usize| {
            let of: Vec<usize> = (0..g.nodes.len())
                .filter(|&k| g.nodes[k].kind == kind)
                .collect();
            (!of.is_empty()).then(|| of[i % of.len()])
        };
        match *e {
            Edit::Move(kind, i, axis, d) => {
                if let Some(k) = nth(g, kind, i) {
                    g.nodes[k].position[axis] += d;
                }
            }
            Edit::Orphan(i, d) => {
                if let Some(k) = nth(g, NodeKind::Object, i) {
                    g.nodes[k].parent = None;
                    g.nodes[k].position[0] += d;
                }
            }
            Edit::MoveVertex(i, d) => {
                if let Some(m) = g.mesh.as_mut() {
                    let k = i % m.points.len();
                    m.points[k][1] += d;
                }
            }
            Edit::DropAgent => {
                if let Some(k) = g.nodes.iter().rposition(|n| n.kind == NodeKind::Agent) {
                    let id = g.nodes.remove(k).id;
                    g.edges.retain(|x| x.source != id && x.target != id);
                    g.sibling_edges.retain(|x| x.source != id && x.target != id);
                    g.extra_parent_edges
                        .retain(|x| x.parent != id && x.child != id);
                    for n in &mut g.nodes {
                        if n.parent == Some(id) {
                            n.parent = None;
                        }
                    }
                }
            }
            Edit::Same | Edit::Truncate(_) => {}
        }
        let mut body = to_binary_body(g).expect("encode");
        if let Edit::Truncate(i) = *e {
            body.truncate(i % body.len());
        }
        body
    }

    /// Runs `edits` through a follower and, after each message, checks that its live
    /// graph equals the full path's (decode, build, nothing left to sync). Returns how
    /// many messages took each path.
    fn follow(layout: Layout, edits: &[Edit]) -> Result<[usize; 3], TestCaseError> {
        let mut g = generate(OfficeParams {
            seed: 5,
            scale: 0.03,
        });
        let mut follower = Follower::new(layout, "zmq message", DsgVersion::V1_1_3);
        let first = Bytes::from(to_binary_body(&g).expect("encode"));
        let mut live = follower.first(vec![first]).expect("first").expect("new");
        let mut paths = [0; 3];
        for e in edits {
            let before = g.clone();
            let body = change(&mut g, e);
            let full = ygg_dsg::parse_binary_body(&body, DsgVersion::V1_1_3, "zmq message");
            let applied = follower.apply(vec![Bytes::from(body)], &mut live);
            match (full, applied) {
                (Ok(dsg), Ok(a)) => {
                    paths[a.path as usize] += 1;
                    let target = layout::build(&dsg, layout).expect("build");
                    let rest = live.clone().sync_to(&target).expect("sync");
                    prop_assert!(rest.is_empty(), "{e:?} by {:?} left {rest:?}", a.path);
                }
                (Err(_), Err(_)) => g = before,
                (full, applied) => prop_assert!(
                    false,
                    "{e:?}: full path {:?}, follower {:?}",
                    full.err(),
                    applied.err()
                ),
            }
        }
        Ok(paths)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        /// The patch path and the build path both leave the live graph equal to the full
        /// path's on random edit sequences (moves of every kind, orphaned objects, mesh
        /// edits, removals, repeats and bad frames), in every layout.
        #[test]
        fn follower_equals_full_path(
            layout in prop_oneof![Just(Layout::Vanilla), Just(Layout::Mint), Just(Layout::Saffron)],
            edits in proptest::collection::vec(edit(), 1..10),
        ) {
            follow(layout, &edits)?;
        }
    }

    #[test]
    fn moves_take_the_patch_path_and_the_rest_builds() {
        let edits = [
            Edit::Move(NodeKind::Object, 0, 0, 0.05),
            Edit::Move(NodeKind::Place, 3, 2, -0.1),
            Edit::Move(NodeKind::Agent, 1, 1, 0.2),
            Edit::Same,
            Edit::Move(NodeKind::Room, 0, 0, 0.3),
            Edit::MoveVertex(7, 0.1),
            Edit::Truncate(1000),
            Edit::Move(NodeKind::Object, 2, 1, 0.05),
        ];
        let paths = follow(Layout::Mint, &edits).expect("equal to the full path");
        let [unchanged, patched, built] = paths;
        assert_eq!((unchanged, patched, built), (1, 4, 2));
    }
}
