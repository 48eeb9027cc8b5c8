//! Import progress reporting.

/// A step of an import, in the order they happen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ImportPhase {
    /// Reading the file; `done` / `total` count file bytes.
    Read,
    /// Decompressing gzip; `done` counts decompressed bytes, `total` is the size the
    /// gzip trailer announces (a hint: it is stored modulo 2^32).
    Decompress,
    /// Parsing the JSON or decoding the binary file; reported at its start
    /// (`done = 0`) and end (`done = total` = bytes). serde_json gives no position
    /// while it runs, so a CLI should show a spinner for this phase; the binary
    /// decoder also reports the byte offset after each section (nodes, edges, mesh).
    Parse,
    /// Checking and converting nodes, mesh and edges; `done` / `total` count nodes
    /// plus edges.
    Validate,
    /// Finished successfully.
    Done,
}

/// One progress report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImportProgress {
    /// The current phase.
    pub phase: ImportPhase,
    /// Units done in this phase (see [`ImportPhase`] for the unit).
    pub done: u64,
    /// Units in this phase, when known.
    pub total: Option<u64>,
}

impl ImportProgress {
    /// A report.
    pub fn new(phase: ImportPhase, done: u64, total: Option<u64>) -> Self {
        Self { phase, done, total }
    }
}
