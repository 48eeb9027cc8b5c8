//! Yggdrasil reader: attach to a scene published through shared memory and query its
//! snapshots in place, zero-copy.
//!
//! * See [`SceneReader`] (from [`SceneReader::builder`]):
//!   [`SceneReader::wait_next`] / [`SceneReader::latest`] hand out [`SceneSnapshot`]s whose
//!   [`SceneSnapshot::view`] every query of [`ygg_store::query`] runs on.
//! * The transport underneath is [`ygg_transport`]; each received segment is validated once
//!   against the archived layout of [`ygg_store::snapshot`] before any query touches it.
#![warn(missing_docs)]

mod scene;

#[doc(inline)]
pub use scene::{SceneReader, SceneReaderBuilder, SceneReceiveError, SceneSnapshot};
#[doc(inline)]
pub use ygg_transport::{ReaderOpenError, ReceiveError, WriterStatus};

// The transport starts every payload at `SEGMENT_ALIGN`; archives need `ARCHIVE_ALIGN`.
const _: () = assert!(
    ygg_transport::protocol::SEGMENT_ALIGN.is_multiple_of(ygg_store::snapshot::ARCHIVE_ALIGN),
    "the transport's payload alignment must satisfy the archived layout's"
);
