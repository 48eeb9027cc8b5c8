//! Yggdrasil's shared-memory transport: a scene's byte segments between one writer and its
//! readers, through iceoryx2, over a fixed set of services whatever the number of segments.
//!
//! * See [`SegmentPublisher`] (from [`PublisherBuilder`]) for the writer side:
//!   [`SegmentPublisher::publish_layer`] and [`SegmentPublisher::publish_manifest`] carry out
//!   the consistent-cut protocol of DESIGN.md §5.
//! * See [`SegmentSubscriber`] (from [`SubscriberBuilder`]) for the reader side:
//!   [`SegmentSubscriber::wait_next`] / [`SegmentSubscriber::latest`] hand out [`Snapshot`]s,
//!   zero-copy.
//! * [`protocol`] is the wire format both sides share: the segment header, payload blocks,
//!   the manifest prefix and event ids. [`service`] names a scene's services and holds
//!   their iceoryx2 configuration and quality of service. [`run_files`] finds and removes
//!   the `/dev/shm` files of a run's iceoryx2 prefix (the demo's and the tests' clean-up).
//!
//! The transport knows bytes, not graphs: segment payloads are opaque here (a segment id is a
//! layer or a chunk of one, the transport does not care), and validating the archives inside
//! is the caller's job (shared memory is untrusted input). The transport itself checks every
//! header and manifest prefix and reports [`ReceiveError::Corrupt`] instead of reading out of
//! bounds. Publishing never blocks on readers (safe overflow, bounded borrows), checks the
//! free space of `/dev/shm` before writing ([`PublishError::SharedMemoryFull`]), and a writer
//! restarted after a crash takes over the scene's services
//! ([`WriterCreateError::AlreadyRunning`] only while the previous writer lives).
//!
//! # Design: one stream per scene
//!
//! Three iceoryx2 services per scene ([`service::SceneServices`]): the segment stream (publish-subscribe),
//! an event service to wake readers and one for readers to ask for a catch-up. Every segment
//! and every manifest goes over the one stream, in publish order: a cut's changed segments,
//! then the manifest naming the generation of every segment of the snapshot. A reader files
//! each sample as it receives it; at a manifest, the segments it names are the newest of their
//! ids received before it, or those of the current snapshot, so the reader assembles the cut
//! with a lookup per segment and no waiting ("consistent cuts", DESIGN.md §5). A segment is
//! validated by the reader once per identity, as before: its bytes stay in the sample the
//! snapshot holds, at the same address in every snapshot that names it.
//!
//! iceoryx2 forgets a sample once it is sent and cannot send it again, so a stream has no
//! "newest sample per key" for late joiners. The writer therefore subscribes to its own
//! stream and keeps the current snapshot's samples (and the newest unnamed one per id);
//! a reader that connects, or that finds at a manifest that a named segment was lost to
//! overflow, announces itself, and the writer's helper thread answers with a *catch-up
//! burst* on the stream: a copy of every segment of the current snapshot
//! ([`protocol::FLAG_CATCH_UP`]), then its manifest. Readers that hold those segments drop the
//! copies on arrival (a receive and a header check each); the one that asked assembles the
//! burst, also when live cuts interleave with it.
//!
//! # Costs and worst cases
//!
//! * Descriptors and files: constant per process (about 40 descriptors for a reader, 30 for
//!   the writer, 12-14 files in `/dev/shm` per scene; measured 42 and 418 layers alike,
//!   `bench/results/ipc.md`), against about six per layer with a service per layer.
//! * Address space: the stream's pool has `(max_readers + 1) * (3 * max_segments + 18) + 1`
//!   chunks, each as large as the largest segment published so far (rounded up to a power of
//!   two; iceoryx2 reallocates the pool when a larger segment comes). Only pages written are
//!   backed by tmpfs, and chunks are reused last-in first-out, so memory follows the samples in
//!   use, but the files are large sparse files. Each connection costs iceoryx2 a byte per chunk
//!   and per possible reallocation (256), initialised when a reader attaches: ~3.6 MB per
//!   connection with the defaults, a few ms of the attach.
//! * A stream buffer of `max_segments + 2` samples per reader: a cut that republishes every
//!   segment, or a catch-up burst, never overflows a reader that is waiting; a reader that does
//!   not receive for longer than that many samples loses the oldest, notices the hole at the
//!   next manifest and asks for a catch-up (after 100 ms without an answer it asks again).
//! * A catch-up burst costs the writer's helper thread a copy of the current snapshot (the
//!   office: 7.4 MB, a few ms) and every other reader a receive per segment. The publishing
//!   thread waits for the helper for at most one segment's copy. A reader that overflows all
//!   the time makes the writer copy the scene ten times a second at most.
//! * A snapshot names at most `max_segments` segments ([`PublisherBuilder::max_segments`],
//!   default [`service::DEFAULT_MAX_SEGMENTS`]).
#![warn(missing_docs)]

pub mod limits;
mod process_watch;
pub mod protocol;
mod publisher;
pub mod run_files;
pub use publisher::shm;
pub mod service;
pub use service::{
    ENV_YGG_LOG, SetupError, UnknownLogLevelError, init_binding_logging, init_iceoryx_logging,
    set_iceoryx_log_level,
};
mod subscriber;
#[cfg(test)]
mod test_prefix;
mod wake;

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
