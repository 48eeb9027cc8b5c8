//! Binary export: a [`DsgGraph`] as spark_dsg 1.1.3 writes it (`saveDsgBinary`,
//! `writeGraph`), the inverse of the binary import for what the model holds.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::Write;
use std::path::Path;

use super::attributes::{self, EDGE_ATTRIBUTES, NodeLayout, NodeOut};
use super::graph::IDENTIFIER;
use super::mesh;
use super::writer::Writer;
use crate::json::{DsgExportError, box_axis, layer_keys, layer_names, name_to_write};
use crate::model::{DsgEdge, DsgGraph, DsgVersion, NodeKind};

/// Writes `graph` as a spark_dsg 1.1.3 binary file (`.sparkdsg`: header, then the
/// body) at `path` (created or truncated).
///
/// The layout choices are those of [`write_json`](crate::write_json): the same layer
/// keys and names, `metadata` holding only `labelspaces`, nodes in
/// [`DsgGraph::nodes`] order, edges as intra-layer, sibling, parent (child first)
/// then extra parent edges, boxes as centre and dimensions with an identity
/// rotation, and spark_dsg's defaults for every field the model does not keep
/// (black colors, identity orientations, no features, a mesh without colors or
/// stamps). Positions are written as f64 and boxes and mesh points as f32, so they
/// read back exactly.
///
/// Importing the output with [`parse_binary`](crate::parse_binary) gives back an
/// equal graph, except for [`DsgGraph::source`], a version other than 1.1.3, the
/// corner cases listed at [`write_json`](crate::write_json), and what the binary
/// layouts have no field for: the name, label and box of an agent pose, the
/// timestamp of a node that is not an agent pose, and the `mesh_connections` of a
/// node that is not an object.
///
/// # Errors
/// [`DsgExportError::Io`] if the file cannot be written, and
/// [`DsgExportError::Unrepresentable`] as for [`to_binary_bytes`].
pub fn write_binary(graph: &DsgGraph, path: impl AsRef<Path>) -> Result<(), DsgExportError> {
    let path = path.as_ref();
    let bytes = to_binary_bytes(graph)?;
    let io_err = |source| DsgExportError::Io {
        file: path.display().to_string(),
        source,
    };
    let mut file = File::create(path).map_err(io_err)?;
    file.write_all(&bytes).map_err(io_err)?;
    file.sync_all().map_err(io_err)
}

/// The bytes of a spark_dsg 1.1.3 binary file of `graph`: header v1.1.3, then
/// [`to_binary_body`] (see [`write_binary`]).
///
/// # Errors
/// [`DsgExportError::Unrepresentable`] when a value does not fit the format: more
/// than 2^32 - 1 elements in one array, or an agent timestamp above `i64::MAX`.
///
/// # Examples
/// ```
/// use ygg_dsg::{self as dsg, office::{generate, OfficeParams}};
/// let g = generate(OfficeParams { seed: 7, scale: 0.02 });
/// let bytes = dsg::to_binary_bytes(&g)?;
/// let back = dsg::parse_binary(&bytes, "office.sparkdsg")?;
/// assert_eq!(back.nodes, g.nodes);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn to_binary_bytes(graph: &DsgGraph) -> Result<Vec<u8>, DsgExportError> {
    to_binary_bytes_at(graph, DsgVersion::V1_1_3)
}

/// [`to_binary_bytes`] in the encoding of `version`: 1.1.3, or 1.1.4 (spark_dsg's
/// `develop` branch: only `Place2dNodeAttributes` differ), with that version in the
/// header.
///
/// # Errors
/// As [`to_binary_bytes`], and [`DsgExportError::Unrepresentable`] for another version.
///
/// # Examples
/// ```
/// use ygg_dsg::{self as dsg, office::{generate, OfficeParams}};
/// let g = generate(OfficeParams { seed: 7, scale: 0.02 });
/// let bytes = dsg::to_binary_bytes_at(&g, dsg::DsgVersion::V1_1_4)?;
/// let back = dsg::parse_binary(&bytes, "office.sparkdsg")?;
/// assert_eq!(back.version, dsg::DsgVersion::V1_1_4);
/// assert_eq!(back.nodes, g.nodes);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn to_binary_bytes_at(
    graph: &DsgGraph,
    version: DsgVersion,
) -> Result<Vec<u8>, DsgExportError> {
    let mut w = Writer::with_capacity(estimate_len(graph));
    w.str(IDENTIFIER);
    w.str("main");
    for part in [version.major, version.minor, version.patch] {
        w.u8(u8::try_from(part).map_err(|_| unwritable(version))?);
    }
    body(graph, &mut w, writes_1_1_4(version)?)?;
    w.finish().map_err(too_long)
}

/// Whether `version` is written in 1.1.4's layout; an error for versions the writer
/// does not write.
fn writes_1_1_4(version: DsgVersion) -> Result<bool, DsgExportError> {
    match version {
        DsgVersion::V1_1_3 => Ok(false),
        DsgVersion::V1_1_4 => Ok(true),
        other => Err(unwritable(other)),
    }
}

fn unwritable(version: DsgVersion) -> DsgExportError {
    DsgExportError::Unrepresentable {
        what: format!("Spark-DSG binary version {version} (the writer writes 1.1.3 and 1.1.4)"),
    }
}

/// The body alone, as spark_dsg's `to_binary()` gives it (what Hydra sends over ZMQ
/// and in `DsgUpdate` messages); read it with
/// [`parse_binary_body`](crate::parse_binary_body) at version 1.1.3.
///
/// # Errors
/// As [`to_binary_bytes`].
pub fn to_binary_body(graph: &DsgGraph) -> Result<Vec<u8>, DsgExportError> {
    to_binary_body_at(graph, DsgVersion::V1_1_3)
}

/// [`to_binary_body`] in the encoding of `version` (1.1.3 or 1.1.4, as
/// [`to_binary_bytes_at`]); read it with [`parse_binary_body`](crate::parse_binary_body)
/// at the same version.
///
/// # Errors
/// As [`to_binary_bytes_at`].
pub fn to_binary_body_at(graph: &DsgGraph, version: DsgVersion) -> Result<Vec<u8>, DsgExportError> {
    let mut w = Writer::with_capacity(estimate_len(graph));
    body(graph, &mut w, writes_1_1_4(version)?)?;
    w.finish().map_err(too_long)
}

fn too_long(n: usize) -> DsgExportError {
    DsgExportError::Unrepresentable {
        what: format!("an array of {n} elements (the binary format holds at most 2^32 - 1)"),
    }
}

/// A rough output size.
fn estimate_len(g: &DsgGraph) -> usize {
    let claims: usize = g.nodes.iter().map(|n| n.mesh_connections.len()).sum();
    let edges = g.edges.len() + g.sibling_edges.len() + g.nodes.len() + g.extra_parent_edges.len();
    let mesh = g
        .mesh
        .as_ref()
        .map_or(0, |m| m.points.len() * 20 + m.faces.len() * 32);
    4096 + g.nodes.len() * 400 + edges * 50 + claims * 9 + mesh
}

fn body(g: &DsgGraph, w: &mut Writer, place2d_1_1_4: bool) -> Result<(), DsgExportError> {
    let keys = layer_keys(g);
    w.array(keys.len());
    for k in &keys {
        layer_key(w, k.layer, k.partition);
    }
    w.array(NodeLayout::ALL.len());
    for l in NodeLayout::ALL {
        w.str(l.name());
    }
    w.array(1);
    w.str(EDGE_ATTRIBUTES);
    let names = layer_names(g);
    w.array(names.len());
    for (name, k) in &names {
        w.str(name);
        layer_key(w, k.layer, k.partition);
    }
    w.str(&metadata(g));

    w.dyn_start();
    for n in &g.nodes {
        w.array(4);
        w.i64(i64::from(n.layer.layer));
        w.u64(n.id);
        w.u32(n.layer.partition);
        let timestamp = n.timestamp_ns.unwrap_or(0);
        let agent = n.kind == NodeKind::Agent;
        let out = NodeOut {
            kind: n.kind,
            position: n.position,
            last_update_time_ns: if agent { timestamp } else { 0 },
            name: name_to_write(g, n).unwrap_or(""),
            bbox: n.bbox.map(|b| {
                let mut dims = [0f32; 3];
                let mut center = [0f32; 3];
                for k in 0..3 {
                    let (c, h) = box_axis(b.min[k], b.max[k]);
                    center[k] = c;
                    dims[k] = h * 2.0;
                }
                (dims, center)
            }),
            semantic_label: n.semantic_label.unwrap_or(u32::MAX),
            mesh_connections: &n.mesh_connections,
            timestamp: i64::try_from(timestamp).map_err(|_| DsgExportError::Unrepresentable {
                what: format!(
                    "the timestamp {timestamp} of node {} (above i64::MAX)",
                    n.id
                ),
            })?,
            external_key: n.id,
            centroid: n.position.map(f64::from),
            place2d_1_1_4,
        };
        attributes::write_node(w, &out);
    }
    w.dyn_end();

    w.dyn_start();
    let parents = g.nodes.iter().filter_map(|n| {
        n.parent.map(|p| DsgEdge {
            source: n.id,
            target: p,
            weight: None,
        })
    });
    let extra = g.extra_parent_edges.iter().map(|e| DsgEdge {
        source: e.child,
        target: e.parent,
        weight: None,
    });
    for e in g
        .edges
        .iter()
        .chain(&g.sibling_edges)
        .copied()
        .chain(parents)
        .chain(extra)
    {
        w.array(3);
        w.u64(e.source);
        w.u64(e.target);
        attributes::write_edge(w, e.weight);
    }
    w.dyn_end();

    match &g.mesh {
        Some(m) => {
            w.bool(true);
            mesh::write(w, m);
        }
        None => w.bool(false),
    }
    Ok(())
}

fn layer_key(w: &mut Writer, layer: u32, partition: u32) {
    w.array(2);
    w.i64(i64::from(layer));
    w.u32(partition);
}

/// The graph metadata: `{"labelspaces": {key: [[id, name], ...]}}`, as the JSON export
/// writes it.
fn metadata(g: &DsgGraph) -> String {
    let spaces: BTreeMap<&str, Vec<(u32, &str)>> = g
        .labelspaces
        .iter()
        .map(|(k, v)| {
            (
                k.as_str(),
                v.iter().map(|(&i, n)| (i, n.as_str())).collect(),
            )
        })
        .collect();
    let mut m = BTreeMap::new();
    m.insert("labelspaces", spaces);
    serde_json::to_string(&m).unwrap_or_else(|_| "{}".to_owned())
}
