//! The files of a recording's folder: their names and order.

use super::error::RecordingError;
use std::path::{Path, PathBuf};

/// Extension of a recording's files.
const FILE_EXTENSION: &str = "ygr";

/// The name of file number `.0` of a recording: `00000001.ygr`, ...
pub(crate) struct RecordingFileName(pub u64);

impl std::fmt::Display for RecordingFileName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:08}.{FILE_EXTENSION}", self.0)
    }
}

/// A file of a recording's folder.
pub(crate) struct ListedFile {
    pub number: u64,
    pub path: PathBuf,
}

/// The recording files of `dir`, ascending by number. Other entries are refused, so that a
/// wrong folder is not mistaken for an empty recording.
pub(crate) fn list_files(dir: &Path) -> Result<Vec<ListedFile>, RecordingError> {
    let io = |source| RecordingError::Io {
        path: dir.display().to_string(),
        source,
    };
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io)? {
        let entry = entry.map_err(io)?;
        let path = entry.path();
        let name = entry.file_name();
        let name = name.to_string_lossy();
        let number = name
            .strip_suffix(&format!(".{FILE_EXTENSION}"))
            .filter(|n| n.len() == 8 && n.bytes().all(|b| b.is_ascii_digit()))
            .and_then(|n| n.parse::<u64>().ok());
        match number {
            Some(number) => files.push(ListedFile { number, path }),
            None => {
                return Err(RecordingError::Format {
                    path: path.display().to_string(),
                    reason: format!(
                        "not a file of a recording (expected NNNNNNNN.{FILE_EXTENSION}); \
                         is {} a recording folder?",
                        dir.display()
                    ),
                });
            }
        }
    }
    files.sort_by_key(|f| f.number);
    Ok(files)
}

/// Now, in nanoseconds since the Unix epoch.
pub(crate) fn unix_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as u64)
}
