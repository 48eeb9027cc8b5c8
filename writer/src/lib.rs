//! Yggdrasil writer: a live scene graph published through shared memory.
//!
//! * See [`SceneWriter`] (from [`SceneWriter::builder`]): it owns a
//!   [`ygg_store::SceneGraph`] and, on [`SceneWriter::publish`], archives each changed layer
//!   straight into shared memory, then a manifest that names the new consistent cut.
//! * [`RecordingPlayer`] publishes a recording's cuts as a live scene, with their
//!   recorded timing.
//! * The transport underneath is [`ygg_transport`]: wire format, iceoryx2 services and the
//!   segment publisher. The writer shares with readers only the archived layout
//!   ([`ygg_store::snapshot`]) and that wire format.
#![warn(missing_docs)]

mod replay;
mod scene;

#[doc(inline)]
pub use replay::{PlayOptions, RecordingPlayer, ReplayError};
#[doc(inline)]
pub use scene::{
    MIN_DEFAULT_MAX_LAYERS, PublishReport, SceneWriter, SceneWriterBuilder, default_max_layers,
};
#[doc(inline)]
pub use ygg_transport::{PublishError, WriterCreateError, WriterWaitError};

// The transport starts every payload at `SEGMENT_ALIGN`; archives need `ARCHIVE_ALIGN`.
const _: () = assert!(
    ygg_transport::protocol::SEGMENT_ALIGN.is_multiple_of(ygg_store::snapshot::ARCHIVE_ALIGN),
    "the transport's payload alignment must satisfy the archived layout's"
);
