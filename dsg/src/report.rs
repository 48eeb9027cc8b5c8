//! Import options and the import report: what a lenient import dropped.

use std::fmt;

use super::error::{DsgImportError, LENIENT_HINT};
use super::model::DsgGraph;

/// How to import a Spark-DSG file ([`import_file`](crate::import_file),
/// [`read_file_with`](crate::read_file_with), [`parse_json_with`](crate::parse_json_with),
/// [`parse_binary_with`](crate::parse_binary_with)).
///
/// The default is strict: the first fault is a [`DsgImportError`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct ImportOptions {
    /// Import what can be imported: drop the items of every [`DropClass`] instead of
    /// failing, and list them in the [`ImportReport`]. Faults outside those classes
    /// (malformed JSON or binary, non-finite coordinates, a binary attribute layout
    /// this crate does not know, ...) still fail: a binary attribute block has no
    /// length prefix, so an unknown layout cannot be skipped, leniently or not.
    pub lenient: bool,
}

impl ImportOptions {
    /// Strict import (the default).
    pub const STRICT: Self = Self { lenient: false };
    /// Lenient import.
    pub const LENIENT: Self = Self { lenient: true };
}

/// A kind of fault a lenient import drops (and a strict import refuses).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[non_exhaustive]
pub enum DropClass {
    /// A node whose `attributes.type` this crate does not model (in binary files: a
    /// spark_dsg layout it decodes but does not model, such as
    /// `KhronosObjectAttributes`). [`DsgImportError::UnknownNodeType`] when strict.
    NodeOfUnknownType,
    /// A node of a layer (or partition) the file does not declare.
    /// [`DsgImportError::UnknownLayer`] when strict.
    NodeOfUnknownLayer,
    /// A node repeating an earlier node's id; the first is kept.
    /// [`DsgImportError::DuplicateNode`] when strict.
    DuplicateNode,
    /// A `mesh_connections` entry naming no vertex of the saved mesh (one entry each).
    /// [`DsgImportError::MeshConnectionOutOfRange`] when strict.
    ClaimOfAbsentVertex,
    /// An edge from a node to itself. [`DsgImportError::SelfEdge`] when strict.
    SelfEdge,
    /// An edge to a node the file does not have. [`DsgImportError::DanglingEdge`] when
    /// strict.
    EdgeToAbsentNode,
    /// An edge to a node this import dropped (of an unknown type or layer).
    EdgeToDroppedNode,
    /// An edge repeating the node pair of an earlier edge; the first is kept.
    /// [`DsgImportError::DuplicateEdge`] when strict.
    DuplicateEdge,
}

impl DropClass {
    /// The class a strict error belongs to, if a lenient import tolerates it.
    pub(crate) fn of(e: &DsgImportError) -> Option<Self> {
        Some(match e {
            DsgImportError::UnknownNodeType { .. } => Self::NodeOfUnknownType,
            DsgImportError::UnknownLayer { .. } => Self::NodeOfUnknownLayer,
            DsgImportError::DuplicateNode { .. } => Self::DuplicateNode,
            DsgImportError::MeshConnectionOutOfRange { .. } => Self::ClaimOfAbsentVertex,
            DsgImportError::SelfEdge { .. } => Self::SelfEdge,
            DsgImportError::DanglingEdge { .. } => Self::EdgeToAbsentNode,
            DsgImportError::DuplicateEdge { .. } => Self::DuplicateEdge,
            _ => return None,
        })
    }

    /// A short description, plural (`edges to absent nodes`).
    pub fn description(self) -> &'static str {
        match self {
            Self::NodeOfUnknownType => "nodes of unknown attribute types",
            Self::NodeOfUnknownLayer => "nodes of undeclared layers",
            Self::DuplicateNode => "nodes repeating an id (the first kept)",
            Self::ClaimOfAbsentVertex => "mesh_connections entries naming no mesh vertex",
            Self::SelfEdge => "self edges",
            Self::EdgeToAbsentNode => "edges to absent nodes",
            Self::EdgeToDroppedNode => "edges to dropped nodes",
            Self::DuplicateEdge => "duplicate edges (the first kept)",
        }
    }
}

impl fmt::Display for DropClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.description())
    }
}

/// The items of one [`DropClass`] an import dropped.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DroppedItems {
    /// What was dropped.
    pub class: DropClass,
    /// How many items.
    pub count: usize,
    /// The first one, described as the strict import's error describes it (file,
    /// list index, node ids).
    pub first: String,
}

/// What an import dropped: empty for a strict import, and for a lenient import of a
/// clean file. Nothing is dropped silently.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ImportReport {
    /// One entry per class with at least one dropped item, in [`DropClass`] order.
    pub dropped: Vec<DroppedItems>,
}

impl ImportReport {
    /// Whether nothing was dropped.
    pub fn is_empty(&self) -> bool {
        self.dropped.is_empty()
    }

    /// How many items of `class` were dropped.
    pub fn count(&self, class: DropClass) -> usize {
        self.dropped
            .iter()
            .find(|d| d.class == class)
            .map_or(0, |d| d.count)
    }

    /// Records one dropped item, described by `first` when it is the first of its class.
    pub(crate) fn record(&mut self, class: DropClass, first: impl FnOnce() -> String) {
        match self.dropped.binary_search_by(|d| d.class.cmp(&class)) {
            Ok(i) => self.dropped[i].count += 1,
            Err(i) => self.dropped.insert(
                i,
                DroppedItems {
                    class,
                    count: 1,
                    first: first(),
                },
            ),
        }
    }

    /// Records the fault `e` when `lenient` and a lenient import tolerates it;
    /// otherwise returns it.
    pub(crate) fn tolerate(
        &mut self,
        lenient: bool,
        e: DsgImportError,
    ) -> Result<(), DsgImportError> {
        match DropClass::of(&e) {
            Some(class) if lenient => {
                self.record(class, || {
                    let msg = e.to_string();
                    msg.strip_suffix(LENIENT_HINT).unwrap_or(&msg).to_owned()
                });
                Ok(())
            }
            _ => Err(e),
        }
    }
}

impl fmt::Display for ImportReport {
    /// One line per class: `dropped 3 edges to absent nodes (first: ...)`; `nothing
    /// dropped` when empty.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.dropped.is_empty() {
            return f.write_str("nothing dropped");
        }
        for (i, d) in self.dropped.iter().enumerate() {
            if i > 0 {
                f.write_str("\n")?;
            }
            write!(f, "dropped {} {} (first: {})", d.count, d.class, d.first)?;
        }
        Ok(())
    }
}

/// An imported graph with the report of what the import dropped.
#[derive(Clone, Debug, PartialEq)]
pub struct Imported {
    /// The graph: every invariant of [`DsgGraph`] holds, as after a strict import.
    pub graph: DsgGraph,
    /// What was dropped to get there (empty for a strict import).
    pub report: ImportReport,
}
