//! Errors of the reader: one enum per operation.

use crate::SetupError;
use crate::protocol::SegmentError;
use crate::service::ENV_IOX2_PREFIX;

/// Why [`SubscriberBuilder::open`](crate::SubscriberBuilder::open) failed.
#[derive(Debug, thiserror::Error)]
pub enum ReaderOpenError {
    /// The scene name or iceoryx2 prefix is invalid, or the iceoryx2 node, a service or a
    /// port could not be set up.
    #[error(transparent)]
    Setup(#[from] SetupError),
    /// No writer has published this scene (its services do not exist).
    #[error(
        "no writer publishes scene {scene:?} (is the writer running? writer and readers must \
         share {ENV_IOX2_PREFIX})"
    )]
    NoWriter {
        /// The scene.
        scene: String,
    },
    /// SIGINT or SIGTERM arrived while waiting for a writer (only with
    /// [`SubscriberBuilder::handle_termination_signals`](crate::SubscriberBuilder::handle_termination_signals)).
    #[error("termination requested by a signal while waiting for a writer")]
    Terminated,
}

/// Why receiving a snapshot failed. The last good snapshot stays available through
/// [`SegmentSubscriber::current`](crate::SegmentSubscriber::current).
#[derive(Debug, thiserror::Error)]
pub enum ReceiveError {
    /// The writer exited or died. Reported once per writer; the reader keeps the last snapshot
    /// and picks up a restarted writer by itself.
    #[error("the writer of scene {scene:?} is gone; keeping the last snapshot")]
    WriterGone {
        /// The scene.
        scene: String,
    },
    /// A segment broke the protocol (shared memory is untrusted input). It was dropped.
    #[error("invalid segment on {service:?}: {source}")]
    Corrupt {
        /// The service it arrived on.
        service: String,
        /// What is wrong with it.
        #[source]
        source: SegmentError,
    },
    /// The application holds so many old snapshots that no new sample can be received on
    /// this service. Drop old snapshots.
    #[error("too many samples of {service:?} are held by old snapshots; drop some")]
    BorrowLimit {
        /// The service.
        service: String,
    },
    /// A connection to the writer's shared memory failed.
    #[error("connection failure on {service:?}: {reason}")]
    Connection {
        /// The service.
        service: String,
        /// iceoryx2's description.
        reason: String,
    },
    /// Waiting for events failed.
    #[error("waiting for events failed: {reason}")]
    Wait {
        /// iceoryx2's description.
        reason: String,
    },
    /// SIGINT or SIGTERM arrived (only with
    /// [`SubscriberBuilder::handle_termination_signals`](crate::SubscriberBuilder::handle_termination_signals)).
    #[error("termination requested by a signal")]
    Terminated,
}
