//! Yggdrasil's shared-memory transport: per-layer byte segments between one writer and
//! its readers, through iceoryx2.
//!
//! * See [`SegmentPublisher`] (from [`PublisherBuilder`]) for the writer side:
//!   [`SegmentPublisher::publish_layer`] and [`SegmentPublisher::publish_manifest`] carry out
//!   the consistent-cut protocol of DESIGN.md §5.
//! * See [`SegmentSubscriber`] (from [`SubscriberBuilder`]) for the reader side:
//!   [`SegmentSubscriber::wait_next`] / [`SegmentSubscriber::latest`] hand out [`Snapshot`]s,
//!   zero-copy.
//! * [`protocol`] is the wire format both sides share: service names, the segment header, the
//!   manifest prefix, events and quality of service.
//!
//! The transport knows bytes, not graphs: segment payloads are opaque here, and validating
//! the archives inside is the caller's job (shared memory is untrusted input). The transport
//! itself checks every header and manifest prefix and reports [`ReceiveError::Corrupt`]
//! instead of reading out of bounds. Publishing never blocks on readers (safe overflow,
//! bounded borrows), checks the free space of `/dev/shm` before writing
//! ([`PublishError::SharedMemoryFull`]), and a writer restarted after a crash takes over the
//! scene's services ([`WriterCreateError::AlreadyRunning`] only while the previous writer
//! lives).
#![warn(missing_docs)]

pub mod limits;
pub mod protocol;
mod publisher;
pub use publisher::shm;
mod service;
pub use service::{SetupError, init_iceoryx_logging};
mod subscriber;
pub mod test_pattern;

#[doc(inline)]
pub use protocol::ManifestEntry;
#[doc(inline)]
pub use publisher::{
    DEFAULT_INITIAL_SEGMENT_BYTES, PublishError, PublisherBuilder, SegmentPublisher,
    WriterCreateError, WriterWaitError,
};
#[doc(inline)]
pub use subscriber::{
    ReaderOpenError, ReceiveError, SegmentSubscriber, Snapshot, SubscriberBuilder, WriterStatus,
};
