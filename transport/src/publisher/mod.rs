//! The writer side: one scene's segment publisher.

mod error;
mod heap;
mod helper;
mod loan;
mod ports;
mod reader_watch;
mod retained;
mod segment_publisher;
mod shared_state;
pub mod shm;

pub use error::{PublishError, WriterCreateError, WriterWaitError};
pub use segment_publisher::{DEFAULT_INITIAL_SEGMENT_BYTES, PublisherBuilder, SegmentPublisher};
