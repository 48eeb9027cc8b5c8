//! Errors of the Spark-DSG importer.

use super::model::{DsgVersion, LayerKey};
use super::symbol::describe_id;

/// The appendix of the strict errors a lenient import would tolerate.
pub(crate) const LENIENT_HINT: &str = " (strict import; a lenient import, `ygg import \
     --lenient` or `ImportOptions::LENIENT`, drops such items and reports them)";

/// Why a Spark-DSG file could not be imported.
///
/// Every variant names the file; variants about one node name its id (shown as
/// `O(3) [5692549928996306947]`), and field paths look like
/// `attributes.position[1]` or `mesh.points[12]`. Errors found while parsing carry
/// the JSON line and column (binary files: the byte offset); errors found by the
/// checks after parsing (dangling edges, duplicates, ranges) name the list index
/// instead. The faults a lenient import drops ([`crate::DropClass`]) say so in their
/// message.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DsgImportError {
    /// The file could not be read.
    #[error("{file}: cannot read: {source}")]
    Io {
        /// File name.
        file: String,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The file starts like gzip but does not decompress.
    #[error("{file}: invalid gzip data: {source}")]
    Gzip {
        /// File name.
        file: String,
        /// The decoder error.
        #[source]
        source: std::io::Error,
    },
    /// The bytes are not well-formed JSON (or end too early).
    #[error("{file}: malformed JSON at line {line} column {column}: {message}")]
    Syntax {
        /// File name.
        file: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What the JSON parser expected.
        message: String,
    },
    /// Well-formed JSON, but a field has the wrong type or shape, or is missing.
    #[error("{file}: {}{field}: {message} (line {line} column {column})", at_node(.node))]
    InvalidField {
        /// File name.
        file: String,
        /// The node the field belongs to, when the field is inside a node.
        node: Option<u64>,
        /// Path of the field, e.g. `nodes[4].attributes.position` or `mesh.faces[7]`.
        field: String,
        /// What was wrong.
        message: String,
        /// 1-based line where the parser stopped.
        line: usize,
        /// 1-based column where the parser stopped.
        column: usize,
    },
    /// A required field is absent (found by the checks after parsing).
    #[error("{file}: {}missing field `{field}`", at_node(.node))]
    MissingField {
        /// File name.
        file: String,
        /// The node, when the field belongs to one.
        node: Option<u64>,
        /// Field path.
        field: String,
    },
    /// The header names a version this importer does not read.
    #[error("{file}: unsupported Spark-DSG version {version} (this importer reads 1.x)")]
    UnsupportedVersion {
        /// File name.
        file: String,
        /// The version in the header.
        version: DsgVersion,
    },
    /// `attributes.type` is not one of the supported node attribute types.
    #[error("{file}: {}unknown node attribute type `{type_name}`{}", at_node(&Some(*.node)), LENIENT_HINT)]
    UnknownNodeType {
        /// File name.
        file: String,
        /// Node id.
        node: u64,
        /// The type found.
        type_name: String,
    },
    /// A node's layer (or layer and partition) is not declared in the header fields
    /// `layer_keys` / `layer_ids`.
    #[error("{file}: {}unknown {layer} (not declared in the file){}", at_node(&Some(*.node)), LENIENT_HINT)]
    UnknownLayer {
        /// File name.
        file: String,
        /// Node id.
        node: u64,
        /// The undeclared layer key.
        layer: LayerKey,
    },
    /// Two nodes share an id.
    #[error("{file}: {}duplicate node id (nodes[{first}] and nodes[{second}]){}", at_node(&Some(*.node)), LENIENT_HINT)]
    DuplicateNode {
        /// File name.
        file: String,
        /// The repeated id.
        node: u64,
        /// Index of the first occurrence in `nodes`.
        first: usize,
        /// Index of the repeated occurrence in `nodes`.
        second: usize,
    },
    /// An edge names a node that does not exist.
    #[error("{file}: edges[{edge}] {} -> {}: node {} does not exist{}", describe_id(*.from), describe_id(*.to), describe_id(*.missing), LENIENT_HINT)]
    DanglingEdge {
        /// File name.
        file: String,
        /// Index in `edges`.
        edge: usize,
        /// Edge source (`source` in the file).
        from: u64,
        /// Edge target (`target` in the file).
        to: u64,
        /// The end that is missing.
        missing: u64,
    },
    /// An edge joins a node to itself.
    #[error("{file}: edges[{edge}]: {}self edge{}", at_node(&Some(*.node)), LENIENT_HINT)]
    SelfEdge {
        /// File name.
        file: String,
        /// Index in `edges`.
        edge: usize,
        /// The node.
        node: u64,
    },
    /// The same unordered node pair appears in two edges.
    #[error("{file}: edges[{edge}] {} -> {}: duplicate edge{}", describe_id(*.from), describe_id(*.to), LENIENT_HINT)]
    DuplicateEdge {
        /// File name.
        file: String,
        /// Index in `edges` of the repeated edge.
        edge: usize,
        /// Edge source (`source` in the file).
        from: u64,
        /// Edge target (`target` in the file).
        to: u64,
    },
    /// A coordinate is NaN, infinite (`null` in nlohmann JSON), or outside the f32
    /// range.
    #[error("{file}: {}{field}: non-finite value {value}", at_node(.node))]
    NonFinite {
        /// File name.
        file: String,
        /// The node, when the value belongs to one.
        node: Option<u64>,
        /// Field path, e.g. `attributes.position[2]` or `mesh.points[5][0]`.
        field: String,
        /// The value after conversion to f32.
        value: f32,
    },
    /// An object's `mesh_connections` entry is not a vertex of the mesh.
    #[error("{file}: {}attributes.mesh_connections[{index}] = {vertex} but the mesh has {vertex_count} vertices{}", at_node(&Some(*.node)), LENIENT_HINT)]
    MeshConnectionOutOfRange {
        /// File name.
        file: String,
        /// Object node id.
        node: u64,
        /// Position in the list.
        index: usize,
        /// The vertex index found.
        vertex: u32,
        /// Number of mesh vertices.
        vertex_count: usize,
    },
    /// A mesh face names a vertex that does not exist.
    #[error(
        "{file}: mesh.faces[{face}] uses vertex {vertex} but the mesh has {vertex_count} vertices"
    )]
    FaceOutOfRange {
        /// File name.
        file: String,
        /// Face index.
        face: usize,
        /// The vertex index found.
        vertex: u32,
        /// Number of mesh vertices.
        vertex_count: usize,
    },
    /// Spark-DSG binary data that does not fit the format: a wrong tag, a length past
    /// the end, an impossible value, an unknown attribute type (attribute blocks have
    /// no length prefix, so it cannot be skipped), trailing bytes, or an encoding
    /// Spark-DSG does not read (no header, older than 1.0.2).
    #[error("{file}: byte {offset}: {}{field}: {message}", at_node(.node))]
    Binary {
        /// File name.
        file: String,
        /// Byte offset of the bad value in the file (in the buffer, for a header-less
        /// body).
        offset: usize,
        /// The node being decoded, when known.
        node: Option<u64>,
        /// Field path, e.g. `nodes[3].attributes.bounding_box` or `mesh.faces[7]`.
        field: String,
        /// What was wrong.
        message: String,
    },
    /// `mesh.labels` does not have one entry per vertex.
    #[error("{file}: mesh.labels has {labels} entries for {vertex_count} vertices")]
    MeshLabelCount {
        /// File name.
        file: String,
        /// Number of labels.
        labels: usize,
        /// Number of vertices.
        vertex_count: usize,
    },
}

impl DsgImportError {
    /// The file the error is about.
    pub fn file(&self) -> &str {
        match self {
            Self::Io { file, .. }
            | Self::Gzip { file, .. }
            | Self::Syntax { file, .. }
            | Self::InvalidField { file, .. }
            | Self::MissingField { file, .. }
            | Self::UnsupportedVersion { file, .. }
            | Self::UnknownNodeType { file, .. }
            | Self::UnknownLayer { file, .. }
            | Self::DuplicateNode { file, .. }
            | Self::DanglingEdge { file, .. }
            | Self::SelfEdge { file, .. }
            | Self::DuplicateEdge { file, .. }
            | Self::NonFinite { file, .. }
            | Self::MeshConnectionOutOfRange { file, .. }
            | Self::FaceOutOfRange { file, .. }
            | Self::MeshLabelCount { file, .. }
            | Self::Binary { file, .. } => file,
        }
    }

    /// The node the error is about, if it is about one node.
    pub fn node(&self) -> Option<u64> {
        match self {
            Self::InvalidField { node, .. }
            | Self::MissingField { node, .. }
            | Self::NonFinite { node, .. }
            | Self::Binary { node, .. } => *node,
            Self::UnknownNodeType { node, .. }
            | Self::UnknownLayer { node, .. }
            | Self::DuplicateNode { node, .. }
            | Self::SelfEdge { node, .. }
            | Self::MeshConnectionOutOfRange { node, .. } => Some(*node),
            Self::DanglingEdge { missing, .. } => Some(*missing),
            _ => None,
        }
    }

    /// The field path, for errors about one field.
    pub fn field(&self) -> Option<&str> {
        match self {
            Self::InvalidField { field, .. }
            | Self::MissingField { field, .. }
            | Self::NonFinite { field, .. }
            | Self::Binary { field, .. } => Some(field),
            Self::MeshConnectionOutOfRange { .. } => Some("attributes.mesh_connections"),
            _ => None,
        }
    }

    /// Byte offset, for errors found while decoding binary data.
    pub fn byte_offset(&self) -> Option<usize> {
        match self {
            Self::Binary { offset, .. } => Some(*offset),
            _ => None,
        }
    }

    /// JSON line and column, for errors found while parsing.
    pub fn line_column(&self) -> Option<(usize, usize)> {
        match self {
            Self::Syntax { line, column, .. } | Self::InvalidField { line, column, .. } => {
                Some((*line, *column))
            }
            _ => None,
        }
    }
}

fn at_node(node: &Option<u64>) -> String {
    match node {
        Some(id) => format!("node {}: ", describe_id(*id)),
        None => String::new(),
    }
}
