//! Yggdrasil reader: attaches to a scene published through iceoryx2 shared memory and hands
//! out consistent snapshots of its per-layer byte segments, zero-copy.
//!
//! * See [`ReaderBuilder`] to open a [`SegmentSubscriber`], then
//!   [`SegmentSubscriber::wait_next`] / [`SegmentSubscriber::latest`] for [`Snapshot`]s.
//! * [`protocol`] is the wire format shared with the writer crate.
//!
//! The transport treats segment bytes as opaque; validating the archives inside is the
//! caller's job (shared memory is untrusted input). The transport itself checks every header
//! and manifest prefix and reports [`ReceiveError::Corrupt`] instead of reading out of bounds.
#![warn(missing_docs)]

mod error;
pub mod limits;
pub mod protocol;
mod segment;
mod snapshot;
mod subscriber;
pub mod test_pattern;

#[doc(inline)]
pub use error::{ReaderOpenError, ReceiveError};
#[doc(inline)]
pub use protocol::ManifestEntry;
#[doc(inline)]
pub use snapshot::Snapshot;
#[doc(inline)]
pub use subscriber::{ReaderBuilder, SegmentSubscriber, WriterStatus};
mod scene;
#[doc(inline)]
pub use scene::{SceneReader, SceneReceiveError, SceneSnapshot};
