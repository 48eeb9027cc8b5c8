//! Decoding a stream of full-state bodies (Spark-DSG's ZMQ messages: every message is
//! the whole graph) without decoding again what the previous message already held.
//!
//! The mesh is most of a message (28 of the office's 31 MB) and rarely changes from one
//! message to the next. [`BodyStream`] keeps the last good body and its graph; for a new
//! body it compares bytes, structure-aware:
//! * a body equal to the last one byte for byte is not decoded at all;
//! * otherwise the nodes and edges are decoded, and the mesh section (everything from the
//!   mesh flag to the end) is compared with the last body's: when equal, the last graph's
//!   mesh is moved into the new graph instead of being decoded, after the one check that
//!   ties nodes to the mesh (every `mesh_connections` entry names a vertex). When that
//!   check fails, the body is decoded in full, which reports the error exactly as
//!   [`parse_binary_body`](super::parse_binary_body) does.
//!
//! Invariant: the graph [`BodyStream::decode`] yields equals
//! `parse_binary_body(body, version, source_name)` for every body, and a body that does
//! not decode leaves the stream as it was.

use std::ops::Range;

use super::graph;
use super::reader::Cursor;
use crate::error::DsgImportError;
use crate::json::build_graph;
use crate::model::{DsgGraph, DsgVersion};
use crate::report::ImportOptions;

/// A decoder for successive header-less bodies of one stream (Spark-DSG's ZMQ messages,
/// each the whole graph), reusing what the last good body already decoded: a body equal
/// to it byte for byte is not decoded at all, and when only the nodes or edges differ,
/// the mesh section (mesh flag to end: most of a message) is compared instead of
/// decoded and the last graph's mesh moves to the new one. The graph it yields always
/// equals [`parse_binary_body`](crate::parse_binary_body)'s for the same body, and a body
/// that does not decode leaves the stream as it was.
///
/// `B` is the buffer type the bodies arrive in (`Vec<u8>`, `bytes::Bytes`, ...): the
/// stream keeps the last good body to compare the next one with, without copying it.
///
/// # Examples
/// ```
/// use ygg_dsg::{self as dsg, BodyStream, office::{generate, OfficeParams}};
/// let mut g = generate(OfficeParams { seed: 1, scale: 0.01 });
/// let mut stream = BodyStream::new(dsg::DsgVersion::V1_1_3, "zmq");
/// let step = stream.decode(dsg::to_binary_body(&g)?)?.expect("a first body is new");
/// assert!(step.previous.is_none());
/// g.nodes[0].position[0] += 1.0;
/// let step = stream.decode(dsg::to_binary_body(&g)?)?.expect("a node moved");
/// assert!(step.mesh_reused);
/// assert_eq!(stream.graph().map(|s| &s.nodes), Some(&g.nodes));
/// // The same body again: nothing to decode.
/// assert!(stream.decode(dsg::to_binary_body(&g)?)?.is_none());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct BodyStream<B> {
    version: DsgVersion,
    source_name: String,
    last: Option<Last<B>>,
}

/// The last good body, where its mesh section starts, and its graph.
struct Last<B> {
    body: B,
    tail: Range<usize>,
    graph: DsgGraph,
}

/// What [`BodyStream::decode`] did with a body that differs from the last one.
#[derive(Debug)]
pub struct StreamStep {
    /// The stream's graph before this body (`None` for the first body, or after
    /// [`BodyStream::forget`]). When `mesh_reused`, its mesh has moved to the new graph
    /// and this one's is `None`.
    pub previous: Option<DsgGraph>,
    /// Whether the mesh section (mesh flag, mesh, end of buffer) was byte for byte the
    /// previous body's, so that its decoded mesh was reused: the two graphs have the
    /// same mesh (or both none).
    pub mesh_reused: bool,
}

impl<B: AsRef<[u8]>> BodyStream<B> {
    /// A stream of bodies encoded at `version` ([`DsgVersion::V1_1_3`] for what spark_dsg
    /// 1.1.3 sends); `source_name` names them in errors and [`DsgGraph::source`].
    pub fn new(version: DsgVersion, source_name: impl Into<String>) -> Self {
        Self {
            version,
            source_name: source_name.into(),
            last: None,
        }
    }

    /// The graph of the last body decoded without error.
    pub fn graph(&self) -> Option<&DsgGraph> {
        self.last.as_ref().map(|l| &l.graph)
    }

    /// Forgets the last body: the next one is decoded in full and has no `previous`
    /// (for a consumer that could not apply the last graph).
    pub fn forget(&mut self) {
        self.last = None;
    }

    /// Decodes `body`, reusing the last body's mesh when the mesh section is unchanged.
    /// Returns `None`, and keeps the last graph, when `body` equals the last body byte
    /// for byte; otherwise the new graph is [`BodyStream::graph`].
    ///
    /// # Errors
    /// As [`parse_binary_body`](super::parse_binary_body); the stream then keeps its
    /// last graph.
    pub fn decode(&mut self, body: B) -> Result<Option<StreamStep>, DsgImportError> {
        if self
            .last
            .as_ref()
            .is_some_and(|l| l.body.as_ref() == body.as_ref())
        {
            return Ok(None);
        }
        let bytes = body.as_ref();
        let c = &mut Cursor::new(bytes, 0);
        let err = |e: super::reader::DecodeError| e.into_import(&self.source_name);
        super::check_version(self.version, &self.source_name)?;
        let raw = graph::read_graph(c, self.version, &mut |_| {}).map_err(err)?;
        let tail = c.position()..bytes.len();
        let same_tail = self
            .last
            .as_ref()
            .is_some_and(|l| l.body.as_ref()[l.tail.clone()] == bytes[tail.clone()]);
        let build = |raw| build_graph(raw, &self.source_name, ImportOptions::STRICT, &mut |_| {});
        let (graph, mesh_reused) = if same_tail {
            let mut graph = build(raw)?.graph;
            let last_mesh = self.last.as_ref().and_then(|l| l.graph.mesh.as_ref());
            let vertices = last_mesh.map_or(0, |m| m.points.len());
            let connected = last_mesh.is_none()
                || graph
                    .nodes
                    .iter()
                    .all(|n| n.mesh_connections.iter().all(|&v| (v as usize) < vertices));
            if connected {
                graph.mesh = self.last.as_mut().and_then(|l| l.graph.mesh.take());
                (graph, true)
            } else {
                // The full decode reports the out-of-range connection, as without a stream.
                let graph = super::parse_binary_body(bytes, self.version, &self.source_name)?;
                (graph, false)
            }
        } else {
            let mut raw = raw;
            raw.mesh = graph::read_tail(c).map_err(err)?;
            (build(raw)?.graph, false)
        };
        let previous = self
            .last
            .replace(Last { body, tail, graph })
            .map(|l| l.graph);
        Ok(Some(StreamStep {
            previous,
            mesh_reused,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::binary::{parse_binary_body, to_binary_body};
    use crate::office::{OfficeParams, generate};
    use proptest::prelude::*;

    /// One change between two messages of a stream.
    #[derive(Clone, Debug)]
    enum Edit {
        /// Node `i % n` moves by `dx`.
        Move(usize, f32),
        /// Mesh vertex `i % n` moves by `dx`.
        MoveVertex(usize, f32),
        /// Object `i % n` claims one vertex past the end of the mesh (a bad body).
        BadConnection(usize),
        /// The mesh is dropped or given back.
        ToggleMesh,
        /// The same body is sent again.
        Same,
        /// The body is cut short (a bad body).
        Truncate(usize),
    }

    fn edit() -> impl Strategy<Value = Edit> {
        prop_oneof![
            4 => (any::<usize>(), -1.0f32..1.0).prop_map(|(i, d)| Edit::Move(i, d)),
            2 => (any::<usize>(), -1.0f32..1.0).prop_map(|(i, d)| Edit::MoveVertex(i, d)),
            1 => any::<usize>().prop_map(Edit::BadConnection),
            1 => Just(Edit::ToggleMesh),
            1 => Just(Edit::Same),
            1 => any::<usize>().prop_map(Edit::Truncate),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// After every body, the stream's graph is what a full decode gives, bodies that
        /// do not decode fail as a full decode does and leave the last graph, and the
        /// mesh is reused exactly when its section is unchanged.
        #[test]
        fn stream_equals_full_decode(edits in proptest::collection::vec(edit(), 1..12)) {
            let mut g = generate(OfficeParams { seed: 3, scale: 0.02 });
            let mesh = g.mesh.clone();
            let mut stream = BodyStream::new(DsgVersion::V1_1_3, "s");
            let first = to_binary_body(&g).unwrap();
            prop_assert!(stream.decode(first).unwrap().is_some());
            for e in edits {
                let mut sent = g.clone();
                let mut body_cut = None;
                match e {
                    Edit::Move(i, d) => {
                        let k = i % g.nodes.len();
                        g.nodes[k].position[0] += d;
                        sent = g.clone();
                    }
                    Edit::MoveVertex(i, d) => {
                        if let Some(m) = g.mesh.as_mut() {
                            let k = i % m.points.len();
                            m.points[k][2] += d;
                        }
                        sent = g.clone();
                    }
                    Edit::BadConnection(i) => {
                        let objects: Vec<usize> = (0..sent.nodes.len())
                            .filter(|&k| !sent.nodes[k].mesh_connections.is_empty())
                            .collect();
                        if let (Some(m), false) = (&sent.mesh, objects.is_empty()) {
                            let k = objects[i % objects.len()];
                            sent.nodes[k].mesh_connections.push(m.points.len() as u32);
                        }
                    }
                    Edit::ToggleMesh => {
                        g.mesh = if g.mesh.is_some() { None } else { mesh.clone() };
                        sent = g.clone();
                    }
                    Edit::Same => {}
                    Edit::Truncate(i) => body_cut = Some(i),
                }
                let mut body = to_binary_body(&sent).unwrap();
                if let Some(i) = body_cut {
                    body.truncate(i % body.len());
                }
                let before = stream.graph().cloned();
                let last_tail = stream.last.as_ref().map(|l| l.body[l.tail.clone()].to_vec());
                let full = parse_binary_body(&body, DsgVersion::V1_1_3, "s");
                let same = stream.last.as_ref().is_some_and(|l| l.body == body);
                match (stream.decode(body.clone()), full) {
                    (Ok(None), Ok(f)) => {
                        prop_assert!(same);
                        prop_assert_eq!(stream.graph(), Some(&f));
                    }
                    (Ok(Some(step)), Ok(f)) => {
                        prop_assert_eq!(stream.graph(), Some(&f));
                        let tail = stream.last.as_ref().map(|l| body[l.tail.clone()].to_vec());
                        prop_assert_eq!(step.mesh_reused, last_tail == tail);
                        let mut previous = step.previous.expect("not the first body");
                        if step.mesh_reused {
                            prop_assert!(previous.mesh.is_none());
                            previous.mesh = f.mesh.clone();
                        }
                        prop_assert_eq!(Some(previous), before);
                    }
                    (Err(s), Err(f)) => {
                        prop_assert_eq!(s.to_string(), f.to_string());
                        prop_assert_eq!(stream.graph().cloned(), before);
                    }
                    (s, f) => prop_assert!(false, "stream {s:?}, full decode {f:?}"),
                }
            }
        }
    }
}
