//! Yggdrasil reader: attach to a scene published through shared memory and query its
//! snapshots in place, zero-copy.
//!
//! * See [`SceneReader`] (from [`SceneReader::builder`]):
//!   [`SceneReader::wait_next`] / [`SceneReader::latest`] hand out [`SceneSnapshot`]s whose
//!   [`SceneSnapshot::view`] every query of [`ygg_store::query`] runs on.
//! * [`SceneRecorder`] records the cuts a reader receives into a
//!   [`ygg_store::recording::RecordingWriter`].
//! * The transport underneath is [`ygg_transport`]; each received segment is validated once
//!   against the archived layout of [`ygg_store::snapshot`] before any query touches it.
//!
//! # Trust model
//! * **Who can write the segments.** iceoryx2 0.10 creates every segment file with mode
//!   0600 once initialised, so only processes of the writer's user can open it. A reader
//!   maps the payload read-only. The writer keeps its read-write mapping, and any process
//!   of the same user can open a segment file read-write.
//! * **What validation guarantees.** Every manifest and every newly received segment (a
//!   layer's part, a point or tree chunk, the structure) passes rkyv's bytecheck and the
//!   store's consistency pass before any query touches it (a segment the reader accepted
//!   before, the very same bytes, is not checked again):
//!   whatever bytes were in shared memory at that moment, queries stay in bounds and
//!   answer on a consistent cut. A corrupt or hostile segment is rejected with
//!   [`SceneReceiveError::Invalid`]; the previous snapshot stays current.
//! * **What it does not guarantee.** Validation happens once. In the default zero-copy
//!   mode a process that rewrites a sample after the reader validated it (the writer, or
//!   any process of that user) changes what the reader's queries read, and can make them
//!   misbehave. The writer in this workspace never rewrites a published sample.
//! * **A writer that is not trusted**: [`SceneReaderBuilder::copy_segments`] copies each
//!   newly received segment into the reader's private memory and validates and queries
//!   the copy; unchanged layers keep their copy. Nothing another process does afterwards
//!   reaches the reader. The cost is one memcpy of each changed layer per snapshot, measured
//!   in `bench/results/store.md`.
#![warn(missing_docs)]

mod join_memo;
mod recorder;
mod scene;

#[doc(inline)]
pub use recorder::{RecordError, SceneRecorder};
#[doc(inline)]
pub use scene::{SceneReader, SceneReaderBuilder, SceneReceiveError, SceneSnapshot};
#[doc(inline)]
pub use ygg_transport::{ReaderOpenError, ReceiveError, WriterStatus};

// The transport starts every payload at `SEGMENT_ALIGN`; archives need `ARCHIVE_ALIGN`.
const _: () = assert!(
    ygg_transport::protocol::SEGMENT_ALIGN.is_multiple_of(ygg_store::snapshot::ARCHIVE_ALIGN),
    "the transport's payload alignment must satisfy the archived layout's"
);
