//! Error types of the store.

use crate::{LayerId, NodeId};

/// Why a mutation of a [`crate::SceneGraph`] was refused. The graph is unchanged.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GraphEditError {
    /// No layer has this id.
    #[error("unknown layer {0}")]
    UnknownLayer(LayerId),
    /// No layer has this name.
    #[error("unknown layer name {0:?}")]
    UnknownLayerName(String),
    /// A layer with this name already exists.
    #[error("a layer named {0:?} already exists")]
    DuplicateLayerName(String),
    /// No node has this id.
    #[error("unknown node {0}")]
    UnknownNode(NodeId),
    /// A node with this id already exists.
    #[error("node {0} already exists")]
    DuplicateNode(NodeId),
    /// The reserved id `u64::MAX` was given for a new node.
    #[error("node id {0} is reserved")]
    ReservedNodeId(NodeId),
    /// The DAG edge would close a cycle among layers (a self-loop included).
    #[error("layer edge {parent} -> {child} would create a cycle")]
    WouldCreateCycle {
        /// Encompassing layer.
        parent: LayerId,
        /// Encompassed layer.
        child: LayerId,
    },
    /// The DAG edge already exists.
    #[error("layer edge {parent} -> {child} already exists")]
    DuplicateLayerEdge {
        /// Encompassing layer.
        parent: LayerId,
        /// Encompassed layer.
        child: LayerId,
    },
    /// The DAG edge does not exist.
    #[error("layer edge {parent} -> {child} does not exist")]
    UnknownLayerEdge {
        /// Encompassing layer.
        parent: LayerId,
        /// Encompassed layer.
        child: LayerId,
    },
    /// Nodes are still nested along this DAG edge.
    #[error("layer edge {parent} -> {child} is still used by {count} nestings")]
    LayerEdgeInUse {
        /// Encompassing layer.
        parent: LayerId,
        /// Encompassed layer.
        child: LayerId,
        /// How many nestings use it.
        count: usize,
    },
    /// An edge must join two nodes of the same layer.
    #[error("edge {from} -> {to} crosses layers {from_layer} and {to_layer}")]
    CrossLayerEdge {
        /// Edge source.
        from: NodeId,
        /// Edge target.
        to: NodeId,
        /// Source's layer.
        from_layer: LayerId,
        /// Target's layer.
        to_layer: LayerId,
    },
    /// An edge from a node to itself.
    #[error("edge {0} -> {0} is a self-loop")]
    SelfLoop(NodeId),
    /// The edge already exists.
    #[error("edge {from} -> {to} already exists")]
    DuplicateEdge {
        /// Edge source.
        from: NodeId,
        /// Edge target.
        to: NodeId,
    },
    /// The edge does not exist.
    #[error("edge {from} -> {to} does not exist")]
    UnknownEdge {
        /// Edge source.
        from: NodeId,
        /// Edge target.
        to: NodeId,
    },
    /// Nesting is allowed only along a DAG edge from the parent's layer to the child's.
    #[error(
        "cannot nest {child} (layer {child_layer}) under {parent} (layer {parent_layer}): no layer edge {parent_layer} -> {child_layer}"
    )]
    NestingOffDag {
        /// Would-be parent.
        parent: NodeId,
        /// Would-be child.
        child: NodeId,
        /// Parent's layer.
        parent_layer: LayerId,
        /// Child's layer.
        child_layer: LayerId,
    },
    /// The child already has a parent; unnest it first.
    #[error("node {child} is already nested under {parent}")]
    AlreadyNested {
        /// The existing parent.
        parent: NodeId,
        /// The child.
        child: NodeId,
    },
    /// The node has no parent.
    #[error("node {0} is not nested")]
    NotNested(NodeId),
    /// A coordinate is NaN or infinite.
    #[error("node {node}: point {index} has a non-finite coordinate")]
    NonFinitePoint {
        /// The node.
        node: NodeId,
        /// Index of the point in the geometry.
        index: usize,
    },
    /// A float feature is NaN (it could never be matched).
    #[error("node {node}: feature {key:?} is NaN")]
    NanFeature {
        /// The node.
        node: NodeId,
        /// The feature key.
        key: String,
    },
    /// The node has no such feature.
    #[error("node {node} has no feature {key:?}")]
    UnknownFeature {
        /// The node.
        node: NodeId,
        /// The key.
        key: String,
    },
    /// The node has no such label.
    #[error("node {node} has no label {label:?}")]
    UnknownLabel {
        /// The node.
        node: NodeId,
        /// The label.
        label: String,
    },
}

/// Result of a graph mutation.
pub type EditResult<T = ()> = Result<T, GraphEditError>;

/// Why a snapshot could not be written, opened or accessed.
#[derive(Debug, thiserror::Error)]
pub enum SnapshotError {
    /// Reading or writing the file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The bytes do not start with the snapshot magic.
    #[error("{0}: not a Yggdrasil snapshot (bad magic)")]
    BadMagic(String),
    /// The snapshot was written by an incompatible format version.
    #[error("{what}: format version {found}, this build reads {expected}")]
    SchemaVersion {
        /// Which snapshot or segment.
        what: String,
        /// Version found.
        found: u32,
        /// Version this build reads.
        expected: u32,
    },
    /// The segment table or a segment lies outside the bytes, or is misaligned.
    #[error("{what}: {reason}")]
    Layout {
        /// Which snapshot or segment.
        what: String,
        /// What is wrong.
        reason: String,
    },
    /// rkyv validation (bytecheck) refused the bytes.
    #[error("{what}: archived bytes failed validation: {reason}")]
    Validation {
        /// Which snapshot or segment.
        what: String,
        /// The validator's message.
        reason: String,
    },
    /// The archived data is well-formed but inconsistent (a row index out of range, ...).
    #[error("{what}: inconsistent archive: {reason}")]
    Inconsistent {
        /// Which snapshot or segment.
        what: String,
        /// What is wrong.
        reason: String,
    },
}
