//! Recordings: a live scene's cuts kept on disk, each segment once, and any recorded cut
//! queried in place ([`Recording`]).
//!
//! A recording is a folder of numbered files (`00000001.ygr`, ...). A file is a header
//! and then records, each a 64-byte header (kind, length, five words, CRC-32) and a
//! payload starting 128-byte aligned, so that archived segments are queried where they
//! lie in the mapped file. A **segment** record holds one archived segment as a reader
//! received it; a **cut** record holds the cut's manifest and its segment list: every
//! segment (a checkpoint: the first cut of a file and every 256th) or the segments set and
//! removed since the previous cut. The cut record is written after the segments it names,
//! so a recording stopped at any point is readable up to its last complete cut. Each file
//! is self-contained (its first cut's segments are all in it): bounds drop whole old
//! files and rewrite nothing. Format and choices: `docs/DESIGN.md` §11.
//!
//! * `format`: the bytes of files, records and cut lists.
//! * `files`: the folder's file names.
//! * `append`: [`RecordingWriter`], which a recorder (a reader of the live scene) feeds.
//! * `open`: [`Recording`] and [`RecordedScene`].
//! * `changes`: [`Recording::changes`], what changed between two cuts.

mod append;
mod changes;
mod error;
mod files;
mod format;
mod open;

pub use append::{AppendReport, CutToRecord, RecordedSegment, RecordingOptions, RecordingWriter};
pub use changes::{NodeMove, Relabel, SceneChanges};
pub use error::RecordingError;
pub use format::{RECORDING_FILE_MAGIC, RECORDING_VERSION};
pub use open::{CutSummary, RawCut, RawSegment, RecordedScene, Recording};
