//! The file header and the graph body (`graph_binary_serialization.cpp`,
//! `versioning.cpp`), decoded into the JSON importer's raw form so that both formats
//! go through one set of checks (`crate::json::build_graph`).
//!
//! Body, in order, with the reader's version branches:
//! - layer keys `ARR32(n)` of `[ARR32(2), INT64 layer, UINT32 partition]` (from 1.1.2;
//!   before, layer ids `ARR32(n)` of INT64);
//! - node and edge attribute type names (`ARR32` of strings each);
//! - layer names: from 1.1.1 `ARR32(n)` of (string, layer key); 1.1.0 (string, INT64
//!   layer); before 1.1.0 none (spark_dsg's fixed names);
//! - graph metadata as a JSON string (from 1.0.6);
//! - nodes in a dynamic array, each `ARR32(4)` `[INT64 layer, UINT64 id, UINT32
//!   partition, attributes]` (before 1.1.0 the third is an optional INT64 timestamp,
//!   and a second dynamic array of nodes follows);
//! - edges in a dynamic array, each `ARR32(3)` `[UINT64 source, UINT64 target,
//!   attributes]`;
//! - a bool, and the mesh when it is true (a buffer may also end before it).
//!
//! Invariants: the decoder reads the buffer once, front to back, and fails at the first
//! byte that does not fit the layout, with its offset; it accepts no trailing bytes.

use std::collections::BTreeMap;

use super::attributes::{self, EDGE_ATTRIBUTES, NodeLayout, TypeTable, Ver};
use super::mesh;
use super::reader::{Cursor, DecodeError, Decoded, Tag};
use crate::model::DsgVersion;
use crate::progress::{ImportPhase, ImportProgress};
use crate::raw::{
    RawEdge, RawFile, RawHeader, RawLayerRef, RawMesh, RawMetadata, RawNode, RawVersion,
};

/// The identifier string a header starts with.
pub(super) const IDENTIFIER: &str = "SPARK_DSG";

/// A decoded file header.
pub(super) struct Header {
    pub version: DsgVersion,
    /// Header length in bytes (where the body starts).
    pub len: usize,
}

/// Whether `bytes` start with a header identifier (`ARR32` or `STR32`, length 9,
/// `SPARK_DSG`).
pub(super) fn has_identifier(bytes: &[u8]) -> bool {
    matches!(bytes.first(), Some(&b) if b == Tag::Arr32 as u8 || b == Tag::Str32 as u8)
        && bytes.get(1..5) == Some(&[9, 0, 0, 0][..])
        && bytes.get(5..14) == Some(IDENTIFIER.as_bytes())
}

/// Reads the header: the identifier, the project name and three UINT8 version parts.
/// `None` when the buffer does not start with the identifier (Spark-DSG then treats
/// the whole buffer as a legacy 1.0.0 body).
pub(super) fn read_header(bytes: &[u8]) -> Decoded<Option<Header>> {
    if !has_identifier(bytes) {
        return Ok(None);
    }
    let mut c = Cursor::new(bytes, 0);
    c.bytes("header.identifier")?;
    c.bytes("header.project_name")?;
    let major = c.u8("header.version.major")?;
    let minor = c.u8("header.version.minor")?;
    let patch = c.u8("header.version.patch")?;
    Ok(Some(Header {
        version: DsgVersion::new(major.into(), minor.into(), patch.into()),
        len: c.offset(),
    }))
}

/// Decodes a body encoded at `version`; `base` is its offset in the file (for error
/// offsets). Reports [`ImportPhase::Parse`] with byte offsets to `progress`.
pub(super) fn read_body<'a>(
    body: &'a [u8],
    base: usize,
    version: DsgVersion,
    progress: &mut dyn FnMut(ImportProgress),
) -> Decoded<RawFile<'a>> {
    let c = &mut Cursor::new(body, base);
    let mut raw = read_graph(c, version, progress)?;
    raw.mesh = read_tail(c)?;
    progress(ImportProgress::new(
        ImportPhase::Parse,
        c.offset() as u64,
        Some((base + body.len()) as u64),
    ));
    Ok(raw)
}

/// Decodes what follows the edges: the mesh flag and mesh, then the end of the buffer.
pub(super) fn read_tail(c: &mut Cursor<'_>) -> Decoded<Option<RawMesh>> {
    let mesh = graph_mesh(c)?;
    if !c.at_end() {
        return Err(c.error(
            "",
            format!("{} bytes after the end of the graph", c.remaining()),
        ));
    }
    Ok(mesh)
}

/// Decodes a body up to the end of its edges (the cursor is then at the mesh flag),
/// with no mesh in the result.
pub(super) fn read_graph<'a>(
    c: &mut Cursor<'a>,
    version: DsgVersion,
    progress: &mut dyn FnMut(ImportProgress),
) -> Decoded<RawFile<'a>> {
    read_graph_indexed(c, version, progress).map(|(raw, _)| raw)
}

/// Where a body's node records lie, and what decoding one of them again needs.
pub(super) struct NodeRecords {
    /// The body's node attribute types.
    pub types: TypeTable<NodeLayout>,
    /// The cursor offset of each node record, then the offset just past the last one.
    pub bounds: Vec<usize>,
}

/// [`read_graph`], also giving where the node records lie (`None` before Spark-DSG 1.1.0,
/// whose nodes come in two arrays).
pub(super) fn read_graph_indexed<'a>(
    c: &mut Cursor<'a>,
    version: DsgVersion,
    progress: &mut dyn FnMut(ImportProgress),
) -> Decoded<(RawFile<'a>, Option<NodeRecords>)> {
    let total = Some(c.total_len() as u64);
    let report = |c: &Cursor<'_>, progress: &mut dyn FnMut(ImportProgress)| {
        progress(ImportProgress::new(
            ImportPhase::Parse,
            c.offset() as u64,
            total,
        ));
    };
    let v = Ver(version);
    let (layer_keys, layer_ids) = if v.before(1, 1, 2) {
        let n = c.array_len(9, "layer_ids")?;
        let mut ids = Vec::with_capacity(n);
        for i in 0..n {
            let layer = layer_id(c).map_err(|e| e.within(format!("layer_ids[{i}]")))?;
            ids.push(RawLayerRef {
                layer,
                partition: 0,
            });
        }
        (None, Some(ids))
    } else {
        let n = c.array_len(5 + 9 + 5, "layer_keys")?;
        let mut keys = Vec::with_capacity(n);
        for i in 0..n {
            keys.push(layer_key(c).map_err(|e| e.within(format!("layer_keys[{i}]")))?);
        }
        (Some(keys), None)
    };
    let node_types = type_table(c, "node_types", NodeLayout::from_name)?;
    let edge_types = type_table(c, "edge_types", |n| {
        (n == EDGE_ATTRIBUTES.as_bytes()).then_some(EDGE_ATTRIBUTES)
    })?;
    let layer_names = if v.before(1, 1, 0) {
        None
    } else {
        let n = c.array_len(6, "layer_names")?;
        let mut names = BTreeMap::new();
        for i in 0..n {
            let name = c
                .string("")
                .map_err(|e| e.within(format!("layer_names[{i}]")))?;
            let key = if v.before(1, 1, 1) {
                layer_id(c).map(|layer| RawLayerRef {
                    layer,
                    partition: 0,
                })
            } else {
                layer_key(c)
            }
            .map_err(|e| e.within(format!("layer_names[{i}]")))?;
            names.insert(name.into_owned(), key);
        }
        Some(names)
    };
    let metadata = if v.before(1, 0, 6) {
        None
    } else {
        graph_metadata(c)?
    };
    report(c, progress);

    let mut nodes = Vec::new();
    let mut bounds = Vec::new();
    let arrays = if v.before(1, 1, 0) { 2 } else { 1 };
    let mut records_end = c.offset();
    for _ in 0..arrays {
        c.dyn_start("nodes")?;
        records_end = c.offset();
        while !c.dyn_end("nodes")? {
            let i = nodes.len();
            bounds.push(c.offset());
            nodes.push(node(c, &node_types, v).map_err(|e| e.within(format!("nodes[{i}]")))?);
            records_end = c.offset();
        }
    }
    bounds.push(records_end);
    report(c, progress);

    let mut edges = Vec::new();
    c.dyn_start("edges")?;
    while !c.dyn_end("edges")? {
        let i = edges.len();
        edges.push(edge(c, &edge_types, v).map_err(|e| e.within(format!("edges[{i}]")))?);
    }
    report(c, progress);
    let records = (arrays == 1).then_some(NodeRecords {
        types: node_types,
        bounds,
    });
    let raw = RawFile {
        header: Some(RawHeader {
            version: RawVersion {
                major: version.major,
                minor: version.minor,
                patch: version.patch,
            },
        }),
        layer_keys,
        layer_ids,
        layer_names,
        nodes: Some(nodes),
        edges: Some(edges),
        mesh: None,
        metadata,
    };
    Ok((raw, records))
}

/// Decodes the node record at `c`, as the body `records` came from does.
pub(super) fn read_node_record<'a>(
    c: &mut Cursor<'a>,
    records: &NodeRecords,
    version: DsgVersion,
) -> Decoded<RawNode<'a>> {
    node(c, &records.types, Ver(version))
}

/// An INT64 layer id, which the model holds as u32.
fn layer_id(c: &mut Cursor<'_>) -> Decoded<u32> {
    let at = c.offset();
    let l = c.i64("layer")?;
    u32::try_from(l)
        .map_err(|_| DecodeError::new(at, "layer", format!("layer id {l} out of range")))
}

/// `LayerKey`: `[ARR32(2), INT64 layer, UINT32 partition]`.
fn layer_key(c: &mut Cursor<'_>) -> Decoded<RawLayerRef> {
    c.fixed(2, "")?;
    let layer = layer_id(c)?;
    let partition = c.u32("partition")?;
    Ok(RawLayerRef { layer, partition })
}

/// A list of attribute type names, mapped to the layouts this crate knows.
fn type_table<T>(
    c: &mut Cursor<'_>,
    field: &str,
    layout: impl Fn(&[u8]) -> Option<T>,
) -> Decoded<TypeTable<T>> {
    let n = c.array_len(5, field)?;
    let mut names = Vec::with_capacity(n);
    let mut layouts = Vec::with_capacity(n);
    for i in 0..n {
        let name = c.bytes("").map_err(|e| e.within(format!("{field}[{i}]")))?;
        layouts.push(layout(name));
        names.push(String::from_utf8_lossy(name).into_owned());
    }
    Ok(TypeTable { names, layouts })
}

/// The graph metadata JSON. Text that is not JSON is dropped, as spark_dsg does (it
/// logs a warning); JSON whose `labelspaces` has the wrong shape is an error, as in the
/// JSON importer.
fn graph_metadata(c: &mut Cursor<'_>) -> Decoded<Option<RawMetadata>> {
    let at = c.offset();
    let text = c.bytes("metadata")?;
    match serde_json::from_slice::<Option<RawMetadata>>(text) {
        Ok(m) => Ok(m),
        Err(e) if e.is_data() => Err(DecodeError::new(at, "metadata", e.to_string())),
        Err(_) => Ok(None),
    }
}

/// One node: `ARR32(4)` of layer, id, partition (or legacy timestamp), attributes.
fn node<'a>(c: &mut Cursor<'a>, types: &TypeTable<NodeLayout>, v: Ver) -> Decoded<RawNode<'a>> {
    c.fixed(4, "")?;
    let layer = layer_id(c)?;
    let id = c.u64("id")?;
    let (partition, timestamp) = if v.before(1, 1, 0) {
        // Spark-DSG < 1.1 gives timestamped nodes (agent poses) the partition of their
        // prefix character; the shared builder does the same for legacy JSON.
        let at = c.offset();
        let stamp = c.opt_i64("timestamp").map_err(|e| e.at_node(id))?;
        let stamp = stamp
            .map(|t| {
                u64::try_from(t).map_err(|_| {
                    DecodeError::new(at, "timestamp", format!("negative timestamp {t}")).at_node(id)
                })
            })
            .transpose()?;
        (None, stamp)
    } else {
        (Some(c.u32("partition").map_err(|e| e.at_node(id))?), None)
    };
    let attributes = attributes::read_node(c, types, v).map_err(|e| e.at_node(id))?;
    Ok(RawNode {
        id,
        layer,
        partition,
        timestamp,
        attributes,
    })
}

/// One edge: `ARR32(3)` of source, target, attributes.
fn edge(c: &mut Cursor<'_>, types: &TypeTable<&'static str>, v: Ver) -> Decoded<RawEdge> {
    c.fixed(3, "")?;
    let source = c.u64("source")?;
    let target = c.u64("target")?;
    let info = attributes::read_edge(c, types, v)?;
    Ok(RawEdge {
        source,
        target,
        info: Some(info),
    })
}

/// The trailing mesh flag and mesh. A buffer that ends here has no mesh (spark_dsg's
/// `checkIfTrue` reads the end as false).
fn graph_mesh(c: &mut Cursor<'_>) -> Decoded<Option<RawMesh>> {
    if c.at_end() {
        return Ok(None);
    }
    if !c.bool("has_mesh")? {
        return Ok(None);
    }
    mesh::read(c).map(Some).map_err(|e| e.within("mesh"))
}
