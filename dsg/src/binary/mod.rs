//! Spark-DSG's binary format: `.sparkdsg` files and header-less `to_binary()` buffers.
//!
//! Read from the spark_dsg 1.1.3 sources (`binary_serialization.{h,cpp}`,
//! `graph_binary_serialization.cpp`, `mesh_serialization.cpp`, `versioning.cpp`,
//! `binary_conversions.cpp`, `node_attributes.cpp`, `edge_attributes.cpp`). It is a
//! msgpack-like tagged encoding, **not msgpack**: values are in host byte order
//! (little-endian), strings are `ARR32` (`0xdd`) + u32 length + bytes (`STR32` `0xdb`
//! accepted on read), `0x00` / `0x01` open and close a dynamic array, and colors are
//! four tagged UINT8.
//!
//! * A file is a header (`dd 09000000 "SPARK_DSG"`, the project name, three UINT8
//!   version parts) then the body. Without the header Spark-DSG assumes the legacy
//!   1.0.0 encoding, which it (and this crate) does not read in binary.
//! * A `to_binary()` buffer (ZMQ, hydra_ros `DsgUpdate.layer_contents`) is the body
//!   alone; the reader reads it as its own version ([`DsgVersion::V1_1_3`]).
//! * Bodies from 1.0.2 to 1.1.3 are read, with every version branch of spark_dsg
//!   1.1.3's reader, and every node and edge attribute layout it registers.
//!
//! # Invariants
//! * The decoder never panics, never loops without consuming input, and never
//!   allocates for a length before checking that the bytes left can hold it.
//! * Decoding yields the same raw form the JSON parser yields, and the one shared
//!   builder checks and converts it: a graph imports to the same [`DsgGraph`] from
//!   its JSON and its binary file, with the same errors for the same faults
//!   (dangling or duplicate edges, unknown layers, non-finite values, ...).
//! * Errors of the decoding itself are [`DsgImportError::Binary`], with the byte
//!   offset (in the whole file), and the node and field when known.

mod attributes;
mod export;
mod graph;
mod mesh;
mod reader;
mod stream;
mod writer;

pub use self::export::{
    to_binary_body, to_binary_body_at, to_binary_bytes, to_binary_bytes_at, write_binary,
};
pub use self::stream::{BodyStream, ChangedNodes, StreamStep};

use self::reader::DecodeError;
use crate::error::DsgImportError;
use crate::json::build_graph;
use crate::model::{DsgGraph, DsgVersion};
use crate::progress::{ImportPhase, ImportProgress};
use crate::report::{ImportOptions, Imported};

/// Whether `head` starts with a Spark-DSG binary file header
/// (`dd 09000000 "SPARK_DSG"`, or `db` for the tag).
///
/// # Examples
/// ```
/// assert!(ygg_dsg::is_binary(b"\xdd\x09\x00\x00\x00SPARK_DSG\xdd\x04\x00\x00\x00main"));
/// assert!(!ygg_dsg::is_binary(b"{\"nodes\": []}"));
/// ```
pub fn is_binary(head: &[u8]) -> bool {
    graph::has_identifier(head)
}

/// Parses a Spark-DSG binary file (`.sparkdsg`: header, then body) into a
/// [`DsgGraph`], mapped exactly as [`parse_json`](crate::parse_json) maps the same graph.
///
/// `source_name` is used in errors and stored as [`DsgGraph::source`]. Attributes the
/// model does not hold are decoded (to get past them: blocks have no length prefix)
/// and dropped.
///
/// # Errors
/// [`DsgImportError::Binary`] for bytes that do not fit the format (with the byte
/// offset, node and field), or a file without header or older than 1.0.2 (which
/// Spark-DSG does not read either); [`DsgImportError::UnsupportedVersion`] for a
/// major version other than 1; and every check of [`parse_json`](crate::parse_json)
/// after decoding (unknown node types, dangling edges, ...). Never panics.
///
/// # Examples
/// ```
/// use ygg_dsg::{self as dsg, office::{generate, OfficeParams}};
/// let bytes = dsg::to_binary_bytes(&generate(OfficeParams { seed: 1, scale: 0.01 }))?;
/// let g = dsg::parse_binary(&bytes, "office.sparkdsg")?;
/// assert_eq!(g.version, dsg::DsgVersion::V1_1_3);
/// assert!(dsg::parse_binary(&bytes[..bytes.len() / 2], "cut.sparkdsg").is_err());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn parse_binary(bytes: &[u8], source_name: &str) -> Result<DsgGraph, DsgImportError> {
    parse_binary_with_progress(bytes, source_name, &mut |_| {})
}

/// [`parse_binary`] that reports its phases to `progress`: [`ImportPhase::Parse`]
/// (with the byte offset reached, after each section), then
/// [`ImportPhase::Validate`] and [`ImportPhase::Done`] as for JSON.
///
/// # Errors
/// As [`parse_binary`].
pub fn parse_binary_with_progress(
    bytes: &[u8],
    source_name: &str,
    progress: &mut dyn FnMut(ImportProgress),
) -> Result<DsgGraph, DsgImportError> {
    parse_binary_impl(bytes, source_name, ImportOptions::STRICT, progress).map(|i| i.graph)
}

/// [`parse_binary`] with [`ImportOptions`]: with `lenient`, the faults of every
/// [`DropClass`](crate::DropClass) are dropped and listed in [`Imported::report`]
/// instead of failing. Nodes of spark_dsg layouts the model does not hold
/// (`KhronosObjectAttributes`, `TraversabilityNodeAttributes`, plain
/// `NodeAttributes`) are decoded and dropped; an attribute type name spark_dsg 1.1.3
/// does not register stays an error even then: binary attribute blocks have no length
/// prefix, so there is no way past one.
///
/// # Errors
/// As [`parse_binary`], less the faults a lenient import drops.
pub fn parse_binary_with(
    bytes: &[u8],
    source_name: &str,
    options: ImportOptions,
) -> Result<Imported, DsgImportError> {
    parse_binary_impl(bytes, source_name, options, &mut |_| {})
}

/// The general binary file import: options and progress.
pub(crate) fn parse_binary_impl(
    bytes: &[u8],
    source_name: &str,
    options: ImportOptions,
    progress: &mut dyn FnMut(ImportProgress),
) -> Result<Imported, DsgImportError> {
    let err = |e: DecodeError| e.into_import(source_name);
    let Some(header) = graph::read_header(bytes).map_err(err)? else {
        return Err(DecodeError::new(
            0,
            "header",
            "no SPARK_DSG header: a legacy (1.0.0) binary file, which Spark-DSG does not \
             read either; convert it to JSON with an older Spark-DSG",
        )
        .into_import(source_name));
    };
    let body = bytes.get(header.len..).unwrap_or_default();
    parse(
        body,
        header.len,
        header.version,
        source_name,
        options,
        progress,
    )
}

/// Parses a header-less body, as spark_dsg's `to_binary()` writes it (ZMQ messages,
/// hydra_ros `DsgUpdate.layer_contents`), encoded at `version`: pass
/// [`DsgVersion::V1_1_3`] for what spark_dsg 1.1.3 sends (its reader reads bodies as
/// its own version). Error offsets count from the start of `bytes`.
///
/// # Errors
/// As [`parse_binary`]; a `version` before 1.0.2 is [`DsgImportError::Binary`].
///
/// # Examples
/// ```
/// use ygg_dsg::{self as dsg, office::{generate, OfficeParams}};
/// let g = generate(OfficeParams { seed: 1, scale: 0.01 });
/// let body = dsg::to_binary_body(&g)?;
/// let back = dsg::parse_binary_body(&body, dsg::DsgVersion::V1_1_3, "zmq")?;
/// assert_eq!(back.nodes, g.nodes);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn parse_binary_body(
    bytes: &[u8],
    version: DsgVersion,
    source_name: &str,
) -> Result<DsgGraph, DsgImportError> {
    parse(
        bytes,
        0,
        version,
        source_name,
        ImportOptions::STRICT,
        &mut |_| {},
    )
    .map(|i| i.graph)
}

fn parse(
    body: &[u8],
    base: usize,
    version: DsgVersion,
    source_name: &str,
    options: ImportOptions,
    progress: &mut dyn FnMut(ImportProgress),
) -> Result<Imported, DsgImportError> {
    check_version(version, source_name)?;
    let len = (base + body.len()) as u64;
    progress(ImportProgress::new(ImportPhase::Parse, 0, Some(len)));
    let raw =
        graph::read_body(body, base, version, progress).map_err(|e| e.into_import(source_name))?;
    let imported = build_graph(raw, source_name, options, progress)?;
    progress(ImportProgress::new(ImportPhase::Done, len, Some(len)));
    Ok(imported)
}

/// Whether bodies encoded at `version` can be read: major version 1, from 1.0.2.
fn check_version(version: DsgVersion, source_name: &str) -> Result<(), DsgImportError> {
    if version.major != 1 {
        return Err(DsgImportError::UnsupportedVersion {
            file: source_name.to_owned(),
            version,
        });
    }
    if version < DsgVersion::new(1, 0, 2) {
        return Err(DecodeError::new(
            0,
            "header.version",
            format!(
                "binary encoding {version} is older than 1.0.2, which Spark-DSG does not \
                 read either; convert the file to JSON with an older Spark-DSG"
            ),
        )
        .into_import(source_name));
    }
    Ok(())
}

impl DecodeError {
    fn into_import(self, file: &str) -> DsgImportError {
        DsgImportError::Binary {
            file: file.to_owned(),
            offset: self.offset,
            node: self.node,
            field: self.field,
            message: self.message,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::attributes::NodeLayout;
    use super::writer::Writer;
    use super::*;
    use crate::model::{LayerKey, NodeKind};
    use crate::symbol::NodeSymbol;

    /// A small body as spark_dsg `v` writes it: object O(1) named "desk" with label 3,
    /// place p(0), agent a(0) stamped 5, room R(0) (in the second node array before
    /// 1.1), O(1) nested in R(0) and an O(1) - a(0) sibling edge.
    fn body(v: DsgVersion) -> Vec<u8> {
        let at = |minor, patch| v >= DsgVersion::new(1, minor, patch);
        let mut w = Writer::with_capacity(4096);
        if at(1, 2) {
            w.array(4);
            for (l, p) in [(2, 0), (2, 97), (3, 0), (4, 0)] {
                w.array(2);
                w.i64(l);
                w.u32(p);
            }
        } else {
            w.array(3);
            [2, 3, 4].into_iter().for_each(|l| w.i64(l));
        }
        w.array(NodeLayout::ALL.len());
        NodeLayout::ALL.into_iter().for_each(|l| w.str(l.name()));
        w.array(1);
        w.str("EdgeAttributes");
        if at(1, 1) {
            w.array(1);
            w.str("OBJECTS");
            w.array(2);
            w.i64(2);
            w.u32(0);
        } else if at(1, 0) {
            w.array(1);
            w.str("OBJECTS");
            w.i64(2);
        }
        if at(0, 6) {
            w.str(r#"{"labelspaces":{"_l2p0":[[3,"chair"]]}}"#);
        }
        let head = |w: &mut Writer, layer: i64, id: u64, partition: u32, stamp: Option<i64>| {
            w.array(4);
            w.i64(layer);
            w.u64(id);
            if at(1, 0) {
                w.u32(partition);
            } else {
                match stamp {
                    Some(t) => w.i64(t),
                    None => w.nil(),
                }
            }
        };
        let base = |w: &mut Writer, layout: NodeLayout| {
            w.u8(layout.index());
            if at(0, 6) {
                w.str("{}");
            }
            w.vec3_f64([1.0, 2.0, 3.0]);
            w.u64(0);
            w.bool(false);
            if at(0, 4) {
                w.bool(false);
            }
        };
        let semantic = |w: &mut Writer, name: &str| {
            w.str(name);
            for _ in 0..if at(0, 3) { 4 } else { 3 } {
                w.u8(7);
            }
            if at(0, 3) {
                w.array(4);
                w.i32(1);
                w.vec3_f32([2.0; 3]);
            } else {
                w.array(5);
                w.i32(1);
                w.vec3_f32([0.0; 3]);
                w.vec3_f32([2.0; 3]);
            }
            w.vec3_f32([1.0; 3]);
            w.matrix_header(3, 3);
            for k in 0..9 {
                w.f32(if k % 4 == 0 { 1.0 } else { 0.0 });
            }
            w.u32(3);
            w.matrix_header(1, 2);
            for x in [0.5, 0.25] {
                if at(0, 5) {
                    w.f32(x)
                } else {
                    w.f64(f64::from(x))
                }
            }
        };
        let object = NodeSymbol::new(b'O', 1).id();
        let agent = NodeSymbol::new(b'a', 0).id();
        let place = NodeSymbol::new(b'p', 0).id();
        let room = NodeSymbol::new(b'R', 0).id();
        w.dyn_start();
        head(&mut w, 2, object, 0, None);
        base(&mut w, NodeLayout::Object);
        semantic(&mut w, "desk");
        w.array(1);
        w.u64(0);
        w.bool(true);
        w.quaternion([1.0, 0.0, 0.0, 0.0]);
        head(&mut w, 3, place, 0, None);
        base(&mut w, NodeLayout::Place);
        semantic(&mut w, "p(0)");
        w.f64(0.5);
        w.u32(2);
        (0..4).for_each(|_| w.array(0));
        w.bool(true);
        w.bool(false);
        w.vec3_f64([0.0; 3]);
        w.quaternion([1.0, 0.0, 0.0, 0.0]);
        w.bool(false);
        w.u64(0);
        if at(1, 3) {
            w.bool(true);
        }
        head(&mut w, 2, agent, 97, Some(5));
        base(&mut w, NodeLayout::Agent);
        if at(1, 0) {
            w.i64(5);
        }
        w.quaternion([1.0, 0.0, 0.0, 0.0]);
        w.u64(agent);
        w.matrix_header(0, 1);
        w.matrix_header(0, 1);
        if !at(1, 0) {
            w.dyn_end();
            w.dyn_start();
        }
        head(&mut w, 4, room, 0, None);
        base(&mut w, NodeLayout::Room);
        semantic(&mut w, "R(0)");
        w.array(1);
        w.str("kitchen");
        w.f64(1.0);
        w.dyn_end();
        w.dyn_start();
        for (s, t) in [(object, room), (agent, object)] {
            w.array(3);
            w.u64(s);
            w.u64(t);
            w.u8(0);
            if at(0, 6) {
                w.str("{}");
            }
            w.bool(false);
            w.f64(1.0);
        }
        w.dyn_end();
        w.bool(false);
        w.finish().unwrap_or_default()
    }

    #[test]
    fn every_version_branch_from_1_0_2_reads() {
        for (minor, patch) in [
            (0, 2),
            (0, 3),
            (0, 4),
            (0, 5),
            (0, 6),
            (1, 0),
            (1, 1),
            (1, 2),
            (1, 3),
        ] {
            let v = DsgVersion::new(1, minor, patch);
            let g = parse_binary_body(&body(v), v, "v").unwrap_or_else(|e| panic!("{v}: {e}"));
            assert_eq!(g.version, v);
            let c = g.counts();
            assert_eq!(c.nodes, 4, "{v}");
            assert_eq!((c.parent_edges, c.sibling_edges), (1, 1), "{v}");
            let o = &g.nodes[0];
            assert_eq!(
                (o.kind, o.position),
                (NodeKind::Object, [1.0, 2.0, 3.0]),
                "{v}"
            );
            assert_eq!(o.mesh_connections, vec![0], "{v}");
            let label = if v >= DsgVersion::new(1, 0, 6) {
                "chair"
            } else {
                "desk"
            };
            assert_eq!(o.label.as_deref(), Some(label), "{v}");
            let b = o.bbox.unwrap_or_else(|| panic!("{v}: no box"));
            assert_eq!((b.min, b.max), ([0.0; 3], [2.0; 3]), "{v}");
            let a = g.nodes.iter().find(|n| n.kind == NodeKind::Agent);
            let a = a.unwrap_or_else(|| panic!("{v}: no agent"));
            assert_eq!(
                (a.layer, a.timestamp_ns),
                (LayerKey::AGENTS, Some(5)),
                "{v}"
            );
            assert_eq!(g.nodes[3].kind, NodeKind::Room, "{v}");
            assert_eq!(o.parent, Some(g.nodes[3].id), "{v}");
            let names: Vec<&str> = g.layers.iter().map(|l| l.name.as_str()).collect();
            assert_eq!(names, ["OBJECTS", "AGENTS", "PLACES", "ROOMS"], "{v}");
            // One version off shifts the layout, and the decoder says where.
            if patch == 6 {
                let e = parse_binary_body(&body(v), DsgVersion::new(1, 0, 5), "v").unwrap_err();
                assert!(matches!(e, DsgImportError::Binary { .. }), "{e}");
            }
        }
    }
}
