//! Free-space check of the shared-memory file system.
//!
//! iceoryx2 sizes data segments with `ftruncate`, which on tmpfs reserves nothing: pages are
//! allocated when first written. Writing into a segment whose pages tmpfs cannot provide raises
//! SIGBUS, so the writer checks the free space before it writes pages that a loaned chunk does
//! not hold yet (`ports::send_segment`: a segment republished into a reused chunk needs none).

use std::path::Path;

use super::PublishError;

/// Extra room required beyond the segment itself, for iceoryx2's management data and the
/// pages of sample headers.
pub const SHM_HEADROOM: u64 = 1 << 20;

/// Bytes free for unprivileged users in the file system holding `path`.
///
/// # Errors
///
/// [`PublishError::SharedMemoryStat`] if `statvfs` fails.
pub fn free_bytes(path: &Path) -> Result<u64, PublishError> {
    let stat = rustix::fs::statvfs(path).map_err(|e| PublishError::SharedMemoryStat {
        path: path.to_owned(),
        source: e.into(),
    })?;
    Ok(stat.f_bavail.saturating_mul(stat.f_frsize))
}

/// Fails with [`PublishError::SharedMemoryFull`] unless `segment_bytes` plus
/// [`SHM_HEADROOM`] are free in `path`.
///
/// The check is conservative: a reused chunk whose pages already exist needs no new space,
/// but the writer cannot know which chunk iceoryx2 will hand out.
///
/// # Errors
///
/// [`PublishError::SharedMemoryFull`] or [`PublishError::SharedMemoryStat`].
pub fn ensure_free(path: &Path, segment_bytes: u64) -> Result<(), PublishError> {
    let available = free_bytes(path)?;
    let needed = segment_bytes.saturating_add(SHM_HEADROOM);
    if available < needed {
        return Err(PublishError::SharedMemoryFull {
            needed,
            available,
            path: path.to_owned(),
        });
    }
    Ok(())
}
