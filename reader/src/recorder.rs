//! [`SceneRecorder`]: follows a live scene as a reader and appends each cut it receives
//! to a recording, each segment once per recording file.

use crate::{SceneReader, SceneReceiveError, SceneSnapshot};
use std::time::Duration;
use ygg_store::recording::{
    AppendReport, CutToRecord, RecordedSegment, RecordingError, RecordingWriter,
};

/// Why a cut was not recorded.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// No valid cut could be received (the writer is gone, a cut was refused, ...).
    #[error(transparent)]
    Receive(#[from] SceneReceiveError),
    /// The recording could not be appended to (a full disk, ...); what was recorded
    /// before stays readable.
    #[error(transparent)]
    Recording(#[from] RecordingError),
}

/// A reader that records: every cut [`SceneRecorder::record_next`] receives (validated,
/// as any reader's) is appended to a [`RecordingWriter`]. The recorder is a reader like
/// any other: it never slows the writer, and if it falls behind it records the newest
/// cut and skips the ones in between.
pub struct SceneRecorder {
    reader: SceneReader,
    recording: RecordingWriter,
    cuts: u64,
    bytes: u64,
}

impl SceneRecorder {
    /// Records what `reader` receives into `recording`.
    pub fn new(reader: SceneReader, recording: RecordingWriter) -> Self {
        SceneRecorder {
            reader,
            recording,
            cuts: 0,
            bytes: 0,
        }
    }

    /// Waits up to `timeout` for a cut newer than the last recorded and appends it;
    /// `Ok(None)` when none came. The first call records the scene's current cut.
    ///
    /// # Errors
    /// [`RecordError::Receive`] from the reader, [`RecordError::Recording`] when the
    /// append failed (the recording stays readable up to its last complete cut).
    pub fn record_next(&mut self, timeout: Duration) -> Result<Option<AppendReport>, RecordError> {
        let snapshot = if self.cuts == 0 {
            match self.reader.latest()? {
                Some(s) => Some(s),
                None => self.reader.wait_next(timeout)?,
            }
        } else {
            self.reader.wait_next(timeout)?
        };
        match snapshot {
            Some(s) => Ok(Some(self.record(&s)?)),
            None => Ok(None),
        }
    }

    /// Appends `snapshot` (a cut this recorder's reader accepted).
    ///
    /// # Errors
    /// As [`RecordingWriter::append_cut`].
    pub fn record(&mut self, snapshot: &SceneSnapshot) -> Result<AppendReport, RecordingError> {
        let raw = snapshot.raw();
        let cut = CutToRecord {
            generation: raw.generation(),
            session: raw.session(),
            writer_unix_ns: raw.published_unix_ns(),
            manifest: raw.manifest_bytes(),
            segments: raw
                .layers()
                .map(|(entry, bytes)| RecordedSegment {
                    id: entry.layer_id,
                    generation: entry.generation,
                    bytes,
                })
                .collect(),
        };
        let report = self.recording.append_cut(&cut)?;
        self.cuts += 1;
        self.bytes += report.bytes_written;
        Ok(report)
    }

    /// The reader the recorder follows the scene with.
    pub fn reader(&self) -> &SceneReader {
        &self.reader
    }

    /// The recording being written.
    pub fn recording(&self) -> &RecordingWriter {
        &self.recording
    }

    /// Cuts recorded so far.
    pub fn cuts_recorded(&self) -> u64 {
        self.cuts
    }

    /// Bytes appended so far (records, headers and padding).
    pub fn bytes_recorded(&self) -> u64 {
        self.bytes
    }
}
