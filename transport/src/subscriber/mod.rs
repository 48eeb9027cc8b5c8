//! The reader side: attaching to a scene and assembling consistent snapshots of its
//! segments.

mod assembly;
mod error;
mod segment;
pub(crate) use segment::HeldSegment;
mod segment_subscriber;
mod snapshot;

pub use error::{ReaderOpenError, ReceiveError};
pub use segment_subscriber::{SegmentSubscriber, SubscriberBuilder, WriterStatus};
pub use snapshot::Snapshot;
