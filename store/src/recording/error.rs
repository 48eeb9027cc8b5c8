//! [`RecordingError`]: what can go wrong writing or reading a recording.

use crate::SnapshotError;

/// Why a recording could not be written, opened or queried.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// Reading or writing a file of the recording failed (a full disk says "No space left
    /// on device"); what was written before stays readable.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// A file of the recording is not one, or a record in it is damaged.
    #[error("{path}: {reason}")]
    Format {
        /// The file, with the offset of the record where one is known.
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// The recording holds no complete cut.
    #[error("{path}: the recording holds no complete cut")]
    Empty {
        /// The recording's folder.
        path: String,
    },
    /// No cut matches what was asked.
    #[error("{0}")]
    NoSuchCut(String),
    /// A recorded segment or cut failed validation.
    #[error(transparent)]
    Snapshot(#[from] SnapshotError),
}
