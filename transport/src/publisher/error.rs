//! Errors of the writer: one enum per operation.

use std::path::PathBuf;

use crate::SetupError;

/// Why [`PublisherBuilder::create`](crate::PublisherBuilder::create) failed.
#[derive(Debug, thiserror::Error)]
pub enum WriterCreateError {
    /// The scene name or iceoryx2 prefix is invalid, or the iceoryx2 node, a service or a
    /// port could not be set up.
    #[error(transparent)]
    Setup(#[from] SetupError),
    /// Another live writer already publishes this scene.
    #[error(
        "scene {scene:?} already has a live writer (one writer per scene); stop it first, \
         or pick another scene name"
    )]
    AlreadyRunning {
        /// The scene.
        scene: String,
    },
    /// The helper thread that answers new readers could not be started.
    #[error("cannot start the writer's helper thread: {0}")]
    Thread(#[source] std::io::Error),
}

/// Why a publish failed. Nothing was sent; the previous snapshot stays current.
#[derive(Debug, thiserror::Error)]
pub enum PublishError {
    /// `/dev/shm` lacks room for the segment; writing it would kill the process with SIGBUS.
    #[error(
        "shared memory is full: the segment needs {needed} bytes but only {available} are \
         free in {path}"
    )]
    SharedMemoryFull {
        /// Bytes the segment (plus a safety margin) needs.
        needed: u64,
        /// Bytes free in the shared-memory file system.
        available: u64,
        /// The shared-memory file system checked.
        path: PathBuf,
    },
    /// The free space of the shared-memory file system could not be queried.
    #[error("cannot query free space of {path}: {source}")]
    SharedMemoryStat {
        /// The shared-memory file system.
        path: PathBuf,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// The segment id is reserved for manifests.
    #[error("layer id {0} is reserved")]
    ReservedLayerId(u64),
    /// A manifest names more segments than the writer was built for
    /// ([`PublisherBuilder::max_segments`](crate::PublisherBuilder::max_segments)).
    #[error(
        "a snapshot may name at most {max} segments (layers), this one names {count}: create the writer with a higher max_segments (max_layers, --max-layers)"
    )]
    TooManyLayers {
        /// Layers named.
        count: usize,
        /// The limit.
        max: usize,
    },
    /// The manifest's layer ids are not strictly increasing.
    #[error("manifest entries must be sorted by layer id without duplicates (at layer {layer_id})")]
    UnsortedManifest {
        /// The first layer out of order.
        layer_id: u64,
    },
    /// A manifest names a layer generation that is not the last one published for that layer,
    /// so no reader could find it.
    #[error(
        "manifest names layer {layer_id} generation {generation}, but the last published \
         generation of that layer is {published:?}"
    )]
    UnknownLayerGeneration {
        /// The layer.
        layer_id: u64,
        /// The generation the manifest names.
        generation: u64,
        /// The last generation published for the layer, if any.
        published: Option<u64>,
    },
    /// The segment is too large for this platform.
    #[error("segment of {len} bytes is too large")]
    TooLarge {
        /// The requested length.
        len: usize,
    },
    /// iceoryx2 could not loan a sample.
    #[error("cannot loan a sample on {service:?}: {source}")]
    Loan {
        /// The service.
        service: String,
        /// iceoryx2's error.
        #[source]
        source: iceoryx2::port::LoanError,
    },
    /// iceoryx2 could not send the sample.
    #[error("cannot send the sample on {service:?}: {source}")]
    Send {
        /// The service.
        service: String,
        /// iceoryx2's error.
        #[source]
        source: iceoryx2::port::SendError,
    },
    /// The writer is shutting down.
    #[error("the writer is closed")]
    Closed,
    /// The fill closure reported an error.
    #[error("filling the segment failed: {0}")]
    Fill(#[source] Box<dyn std::error::Error + Send + Sync>),
}

/// Why [`SegmentPublisher::wait`](crate::SegmentPublisher::wait) returned early.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum WriterWaitError {
    /// SIGINT (Ctrl+C) arrived.
    #[error("interrupted (SIGINT)")]
    Interrupt,
    /// SIGTERM arrived.
    #[error("termination requested (SIGTERM)")]
    TerminationRequest,
}
