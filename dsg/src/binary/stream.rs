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
//! * when the bytes that differ all lie within node records, and re-decoding just those
//!   records (from the last body's record offsets) ends exactly where the unchanged rest
//!   resumes, only those records are decoded: the graph is the last one with those nodes
//!   replaced, provided each keeps its id and layer (so the edges, parents, layers and
//!   mesh, byte for byte the same, mean the same) and claims only vertices of the mesh.
//!   Finding them costs a comparison from each end of the two bodies.
//!
//! Invariant: the graph [`BodyStream::decode`] yields equals
//! `parse_binary_body(body, version, source_name)` for every body, and a body that does
//! not decode leaves the stream as it was.

use std::ops::Range;

use super::graph::{self, NodeRecords};
use super::reader::Cursor;
use crate::error::DsgImportError;
use crate::json::{build_graph, build_node_in_layer};
use crate::model::{DsgGraph, DsgMesh, DsgNode, DsgVersion};
use crate::report::ImportOptions;
use crate::update::{UpdateError, UpdateReport};

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

/// The last good body, where its mesh section starts and its node records lie, and its
/// graph.
struct Last<B> {
    body: B,
    tail: Range<usize>,
    /// `None` for versions before 1.1.0.
    records: Option<NodeRecords>,
    graph: DsgGraph,
    /// Whether `graph` is still `body`'s: false once an incremental update changed it.
    graph_is_body: bool,
    /// Whether `graph`'s mesh is still the one of `body`'s mesh section.
    mesh_is_body: bool,
}

/// The nodes that alone differ from the previous graph, when only their records changed.
#[derive(Debug)]
pub struct ChangedNodes {
    /// The index in [`DsgGraph::nodes`] of the first.
    pub first: usize,
    /// Their values in the previous graph, in order (the new ones follow `first`).
    pub previous: Vec<DsgNode>,
}

/// Node records decoded again, ready to replace the last graph's.
struct Redecoded {
    first: usize,
    nodes: Vec<DsgNode>,
    /// Offsets of the records after the first one decoded (the new body's).
    starts: Vec<usize>,
    /// New body length minus the last one's.
    delta: isize,
}

/// What [`BodyStream::decode`] did with a body that differs from the last one.
#[derive(Debug)]
pub struct StreamStep {
    /// The stream's graph before this body (`None` for the first body, after
    /// [`BodyStream::forget`], or when `changed_nodes` says what changed). When
    /// `mesh_reused`, its mesh has moved to the new graph and this one's is `None`.
    pub previous: Option<DsgGraph>,
    /// When only some node records differed and only those were decoded: which nodes
    /// changed, with their previous values; everything else is the previous graph's.
    pub changed_nodes: Option<ChangedNodes>,
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

    /// Applies an incremental update to the stream's graph
    /// ([`DsgGraph::apply_update`]): `part` is a body (encoded at the stream's version)
    /// holding the nodes changed or added and the edges added. The next full body is then
    /// decoded against the updated graph: its `previous` is that graph, and its mesh is
    /// still reused when neither the update nor the body changed it.
    ///
    /// # Errors
    /// [`UpdateError::NoGraph`] before a first good body, the part's decoding error, or
    /// what [`DsgGraph::apply_update`] refuses; the stream then keeps its graph.
    pub fn apply_update(
        &mut self,
        part: &[u8],
        deleted_nodes: &[u64],
        deleted_edges: &[u64],
    ) -> Result<UpdateReport, UpdateError> {
        let version = self.version;
        let part = super::parse_binary_body(part, version, &self.source_name)?;
        let last = self.last.as_mut().ok_or(UpdateError::NoGraph)?;
        let mesh_sent = part.mesh.is_some();
        let report = last
            .graph
            .apply_update(part, deleted_nodes, deleted_edges)?;
        last.graph_is_body = false;
        last.mesh_is_body &= !mesh_sent;
        Ok(report)
    }

    /// Decodes `body`, reusing the last body's mesh when the mesh section is unchanged,
    /// and the last graph's nodes when only some node records changed.
    /// Returns `None`, and keeps the last graph, when `body` equals the last body byte
    /// for byte; otherwise the new graph is [`BodyStream::graph`].
    ///
    /// # Errors
    /// As [`parse_binary_body`](super::parse_binary_body); the stream then keeps its
    /// last graph.
    pub fn decode(&mut self, body: B) -> Result<Option<StreamStep>, DsgImportError> {
        // One comparison from each end of the two bodies serves every reuse below.
        let overlap = self
            .last
            .as_ref()
            .map(|l| Overlap::of(l.body.as_ref(), body.as_ref()));
        if let (Some(l), Some(o)) = (&self.last, overlap)
            && l.graph_is_body
            && o.is_whole(l.body.as_ref(), body.as_ref())
        {
            return Ok(None);
        }
        super::check_version(self.version, &self.source_name)?;
        let body = match overlap {
            Some(o) => match self.replace_changed_records(body, o) {
                Ok(step) => return Ok(Some(step)),
                Err(body) => body,
            },
            None => body,
        };
        let bytes = body.as_ref();
        let c = &mut Cursor::new(bytes, 0);
        let err = |e: super::reader::DecodeError| e.into_import(&self.source_name);
        let (raw, records) =
            graph::read_graph_indexed(c, self.version, &mut |_| {}).map_err(err)?;
        let tail = c.position()..bytes.len();
        // The tails are equal when they have one length and the common suffix covers it
        // (the suffix stops short of the common prefix only inside a differing tail).
        let same_tail = self.last.as_ref().zip(overlap).is_some_and(|(l, o)| {
            l.mesh_is_body && l.tail.len() == tail.len() && o.suffix >= tail.len()
        });
        let build = |raw| build_graph(raw, &self.source_name, ImportOptions::STRICT, &mut |_| {});
        let (graph, mesh_reused) = if same_tail {
            let mut graph = build(raw)?.graph;
            let last_mesh = self.last.as_ref().and_then(|l| l.graph.mesh.as_ref());
            if graph.nodes.iter().all(|n| claims_within(n, last_mesh)) {
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
            .replace(Last {
                body,
                tail,
                records,
                graph,
                graph_is_body: true,
                mesh_is_body: true,
            })
            .map(|l| l.graph);
        Ok(Some(StreamStep {
            previous,
            mesh_reused,
            changed_nodes: None,
        }))
    }

    /// The step for `body` when only node records changed (see the module docs), applied
    /// to the last graph; `Err(body)` when that does not hold and the body must be
    /// decoded in full.
    fn replace_changed_records(&mut self, body: B, overlap: Overlap) -> Result<StreamStep, B> {
        let Some(r) = self.redecode_changed_records(body.as_ref(), overlap) else {
            return Err(body);
        };
        let last = self.last.as_mut().expect("a last body was compared");
        let records = last.records.as_mut().expect("records were compared");
        let end = r.first + r.nodes.len();
        let mut previous = Vec::with_capacity(r.nodes.len());
        for (old, mut node) in last.graph.nodes[r.first..end].iter_mut().zip(r.nodes) {
            // Parents come from the edges, which did not change.
            node.parent = old.parent;
            previous.push(std::mem::replace(old, node));
        }
        let shift = |b: usize| b.checked_add_signed(r.delta).expect("within the new body");
        records.bounds[r.first + 1..end].copy_from_slice(&r.starts);
        for b in &mut records.bounds[end..] {
            *b = shift(*b);
        }
        last.tail = shift(last.tail.start)..body.as_ref().len();
        last.body = body;
        Ok(StreamStep {
            previous: None,
            mesh_reused: true,
            changed_nodes: Some(ChangedNodes {
                first: r.first,
                previous,
            }),
        })
    }

    /// Decodes again the node records of `new` that differ from the last body's, when
    /// nothing else differs and each keeps its node's id and layer; `None` otherwise.
    fn redecode_changed_records(&self, new: &[u8], overlap: Overlap) -> Option<Redecoded> {
        let last = self.last.as_ref().filter(|l| l.graph_is_body)?;
        let records = last.records.as_ref()?;
        let old = last.body.as_ref();
        let bounds = &records.bounds;
        let n = bounds.len().checked_sub(1).filter(|&n| n > 0)?;
        if last.graph.nodes.len() != n {
            return None;
        }
        let Overlap { prefix, suffix } = overlap;
        if prefix < bounds[0] || old.len() - suffix > bounds[n] {
            return None;
        }
        // The record holding the first byte that differs.
        let first = (bounds.partition_point(|&b| b <= prefix) - 1).min(n - 1);
        let delta = isize::try_from(new.len()).ok()? - isize::try_from(old.len()).ok()?;
        let unchanged_from = new.len() - suffix;
        let mut c = Cursor::new(new.get(bounds[first]..)?, bounds[first]);
        let (mut nodes, mut starts) = (Vec::new(), Vec::new());
        let mesh = last.graph.mesh.as_ref();
        let mut k = first;
        while k == first || c.offset() < unchanged_from {
            let old_node = last.graph.nodes.get(k)?;
            if k > first {
                starts.push(c.offset());
            }
            let raw = graph::read_node_record(&mut c, records, self.version).ok()?;
            let node = build_node_in_layer(
                raw,
                old_node.layer,
                &last.graph.labelspaces,
                &self.source_name,
            )?;
            if node.id != old_node.id || !claims_within(&node, mesh) {
                return None;
            }
            nodes.push(node);
            k += 1;
        }
        // The records decoded must end where the unchanged rest resumes.
        (c.offset().checked_add_signed(-delta)? == bounds[k]).then_some(Redecoded {
            first,
            nodes,
            starts,
            delta,
        })
    }
}

/// Whether every vertex `node` claims is one of `mesh`'s (any claim, without a mesh: the
/// full decode checks claims only against a mesh).
fn claims_within(node: &DsgNode, mesh: Option<&DsgMesh>) -> bool {
    mesh.is_none_or(|m| {
        node.mesh_connections
            .iter()
            .all(|&v| (v as usize) < m.points.len())
    })
}

/// How two bodies agree: the length of their common prefix, and of their common suffix
/// short of it.
#[derive(Clone, Copy)]
struct Overlap {
    prefix: usize,
    suffix: usize,
}

impl Overlap {
    fn of(old: &[u8], new: &[u8]) -> Self {
        let prefix = common_prefix(old, new);
        let suffix = common_suffix(old, new, old.len().min(new.len()) - prefix);
        Self { prefix, suffix }
    }

    /// Whether `old` and `new` are the same bytes.
    fn is_whole(self, old: &[u8], new: &[u8]) -> bool {
        self.prefix == old.len() && self.prefix == new.len()
    }
}

/// Comparison block: long enough for `memcmp` to run at full speed.
const BLOCK: usize = 4096;

/// The length of the longest common prefix of `a` and `b`.
fn common_prefix(a: &[u8], b: &[u8]) -> usize {
    let n = a.len().min(b.len());
    let mut i = 0;
    while i + BLOCK <= n && a[i..i + BLOCK] == b[i..i + BLOCK] {
        i += BLOCK;
    }
    i + a[i..n]
        .iter()
        .zip(&b[i..n])
        .take_while(|(x, y)| x == y)
        .count()
}

/// The length of the longest common suffix of `a` and `b`, at most `max`.
fn common_suffix(a: &[u8], b: &[u8], max: usize) -> usize {
    let n = a.len().min(b.len()).min(max);
    let (a, b) = (&a[a.len() - n..], &b[b.len() - n..]);
    let mut i = 0;
    while i + BLOCK <= n && a[n - i - BLOCK..n - i] == b[n - i - BLOCK..n - i] {
        i += BLOCK;
    }
    i + a[..n - i]
        .iter()
        .rev()
        .zip(b[..n - i].iter().rev())
        .take_while(|(x, y)| x == y)
        .count()
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
        /// Node `i % n` gets a name of `len` letters (its record changes length).
        Rename(usize, usize),
        /// Node `i % n` is dropped, with its edges.
        Drop(usize),
        /// A copy of node `i % n` under a new id is appended.
        Copy(usize),
    }

    fn edit() -> impl Strategy<Value = Edit> {
        prop_oneof![
            4 => (any::<usize>(), -1.0f32..1.0).prop_map(|(i, d)| Edit::Move(i, d)),
            2 => (any::<usize>(), -1.0f32..1.0).prop_map(|(i, d)| Edit::MoveVertex(i, d)),
            1 => any::<usize>().prop_map(Edit::BadConnection),
            1 => Just(Edit::ToggleMesh),
            1 => Just(Edit::Same),
            1 => any::<usize>().prop_map(Edit::Truncate),
            2 => (any::<usize>(), 0..40usize).prop_map(|(i, n)| Edit::Rename(i, n)),
            1 => any::<usize>().prop_map(Edit::Drop),
            1 => any::<usize>().prop_map(Edit::Copy),
        ]
    }

    /// Applies an edit that changes the graph itself.
    fn change(g: &mut DsgGraph, e: &Edit) {
        let n = g.nodes.len();
        match *e {
            Edit::Move(i, d) => g.nodes[i % n].position[0] += d,
            Edit::Rename(i, len) => {
                g.nodes[i % n].name = (len > 0).then(|| "r".repeat(len));
            }
            Edit::Drop(i) if n > 1 => {
                let id = g.nodes.remove(i % n).id;
                g.edges.retain(|x| x.source != id && x.target != id);
                g.sibling_edges.retain(|x| x.source != id && x.target != id);
                g.extra_parent_edges
                    .retain(|x| x.parent != id && x.child != id);
                for node in &mut g.nodes {
                    if node.parent == Some(id) {
                        node.parent = None;
                    }
                }
            }
            Edit::Copy(i) => {
                let mut copy = g.nodes[i % n].clone();
                copy.id = g.nodes.iter().map(|x| x.id).max().unwrap_or(0) + 1;
                copy.parent = None;
                g.nodes.push(copy);
            }
            _ => {}
        }
    }

    /// The graph before a step, from the graph after it and the step.
    fn previous_graph(step: StreamStep, after: &DsgGraph) -> Option<DsgGraph> {
        if let Some(changed) = step.changed_nodes {
            let mut g = after.clone();
            let end = changed.first + changed.previous.len();
            g.nodes.splice(changed.first..end, changed.previous);
            return Some(g);
        }
        let mut previous = step.previous?;
        if step.mesh_reused {
            previous.mesh = after.mesh.clone();
        }
        Some(previous)
    }

    #[test]
    fn moves_and_renames_decode_only_the_changed_records() {
        let mut g = generate(OfficeParams {
            seed: 4,
            scale: 0.02,
        });
        let mut stream = BodyStream::new(DsgVersion::V1_1_3, "s");
        stream.decode(to_binary_body(&g).unwrap()).unwrap();
        let n = g.nodes.len();
        for e in [
            Edit::Move(3, 0.5),
            Edit::Rename(n / 2, 12),
            Edit::Move(n / 2 + 1, -0.25),
            Edit::Rename(n / 2, 0),
            Edit::Move(n - 1, 1.0),
            Edit::Move(0, 1.0),
        ] {
            change(&mut g, &e);
            let body = to_binary_body(&g).unwrap();
            let full = parse_binary_body(&body, DsgVersion::V1_1_3, "s").unwrap();
            let step = stream.decode(body).unwrap();
            let changed = step.and_then(|s| s.changed_nodes).expect("records decoded");
            assert_eq!(changed.previous.len(), 1, "{e:?}");
            assert!(stream.graph() == Some(&full), "{e:?}: not the full decode");
        }
        // A node added or dropped changes the record count: decoded in full.
        for e in [Edit::Copy(2), Edit::Drop(5)] {
            change(&mut g, &e);
            let body = to_binary_body(&g).unwrap();
            let full = parse_binary_body(&body, DsgVersion::V1_1_3, "s").unwrap();
            let step = stream.decode(body).unwrap();
            assert!(step.expect("changed").changed_nodes.is_none(), "{e:?}");
            assert!(stream.graph() == Some(&full), "{e:?}: not the full decode");
        }
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
                    Edit::Move(..) | Edit::Rename(..) | Edit::Drop(_) | Edit::Copy(_) => {
                        change(&mut g, &e);
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
                        if step.mesh_reused && let Some(p) = &step.previous {
                            prop_assert!(p.mesh.is_none());
                        }
                        prop_assert_eq!(previous_graph(step, &f), before);
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
