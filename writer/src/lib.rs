//! Yggdrasil writer: publishes a scene as per-layer byte segments through iceoryx2 shared
//! memory.
//!
//! * See [`WriterBuilder`] to create a [`SegmentPublisher`] for a scene, and
//!   [`SegmentPublisher::publish_layer`] / [`SegmentPublisher::publish_manifest`] for the
//!   consistent-cut protocol of DESIGN.md §5.
//! * The wire format is [`ygg_reader::protocol`]; the transport treats segment bytes as opaque.
//!
//! Publishing never blocks on readers (safe overflow, bounded borrows), checks the free space
//! of `/dev/shm` before writing ([`PublishError::SharedMemoryFull`]), and a writer restarted
//! after a crash takes over the scene's services ([`WriterCreateError::AlreadyRunning`] only
//! while the previous writer lives).
#![warn(missing_docs)]

mod error;
mod loan;
mod publisher;
pub mod shm;

#[doc(inline)]
pub use error::{PublishError, WriterCreateError, WriterWaitError};
#[doc(inline)]
pub use publisher::{DEFAULT_INITIAL_SEGMENT_BYTES, SegmentPublisher, WriterBuilder};
#[doc(inline)]
pub use ygg_reader::protocol::ManifestEntry;
mod scene;
#[doc(inline)]
pub use scene::{PublishReport, SceneWriter, unix_ns};
pub mod replay;
