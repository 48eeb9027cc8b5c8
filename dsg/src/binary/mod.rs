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
mod writer;

pub use self::export::{to_binary_body, to_binary_bytes, write_binary};

use self::reader::DecodeError;
use crate::error::DsgImportError;
use crate::json::build_graph;
use crate::model::{DsgGraph, DsgVersion};
use crate::progress::{ImportPhase, ImportProgress};

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
    parse(body, header.len, header.version, source_name, progress)
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
    parse(bytes, 0, version, source_name, &mut |_| {})
}

fn parse(
    body: &[u8],
    base: usize,
    version: DsgVersion,
    source_name: &str,
    progress: &mut dyn FnMut(ImportProgress),
) -> Result<DsgGraph, DsgImportError> {
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
    let total = Some((base + body.len()) as u64);
    progress(ImportProgress::new(ImportPhase::Parse, 0, total));
    let raw =
        graph::read_body(body, base, version, progress).map_err(|e| e.into_import(source_name))?;
    let graph = build_graph(raw, source_name, progress)?;
    progress(ImportProgress::new(
        ImportPhase::Done,
        total.unwrap_or(0),
        total,
    ));
    Ok(graph)
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
