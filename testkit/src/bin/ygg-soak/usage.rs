//! What a process holds, read from `/proc/<pid>`: resident memory and open file
//! descriptors; and the scene's files in `/dev/shm`.

use serde::Serialize;
use std::path::Path;
use ygg_testkit::{SHM_DIR, TestScene};

/// Resident memory (from `/proc/<pid>/status`) and open file descriptors
/// (`/proc/<pid>/fd`) of one process at one moment.
///
/// Descriptors on iceoryx2 data segments (`*.data` in `/dev/shm`) are counted apart: a reader
/// maps each pool segment of the writer it follows, and a writer's pool has one to a few of
/// them depending on when its segments grew (iceoryx2 grows a pool in power-of-two steps and
/// keeps an older one while samples in it are held), so their number is compared within one
/// writer's life only. A descriptor on a data segment that was removed is a leak at any time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Usage {
    /// `VmRSS`: all resident memory, kB.
    pub rss_kb: u64,
    /// `RssAnon`: resident private memory (heap, stacks), kB.
    pub anon_kb: u64,
    /// `RssShmem`: resident shared memory (the scene's segments it touched), kB.
    pub shmem_kb: u64,
    /// Open file descriptors.
    pub fds: usize,
    /// Of `fds`, those on iceoryx2 data segments (`*.data`).
    pub pool_fds: usize,
    /// Of `pool_fds`, those on a data segment that was removed (a gone writer's pool).
    pub removed_pool_fds: usize,
}

impl Usage {
    /// Reads the usage of process `pid`.
    ///
    /// # Errors
    /// If `/proc/<pid>` cannot be read (the process is gone, or there is no procfs).
    pub fn of(pid: u32) -> std::io::Result<Self> {
        let dir = Path::new("/proc").join(pid.to_string());
        let status = std::fs::read_to_string(dir.join("status"))?;
        // A descriptor closed between the listing and its readlink has no target: skipped.
        let targets: Vec<String> = std::fs::read_dir(dir.join("fd"))?
            .filter_map(|e| std::fs::read_link(e.ok()?.path()).ok())
            .map(|t| t.to_string_lossy().into_owned())
            .collect();
        Ok(Self::parse(&status, &targets))
    }

    /// The usage described by the text of a `/proc/<pid>/status` file and the targets of
    /// the open descriptors; a field that is missing reads as 0.
    fn parse(status: &str, fd_targets: &[String]) -> Self {
        let kb = |key: &str| {
            status
                .lines()
                .find_map(|l| l.strip_prefix(key)?.strip_prefix(':'))
                .and_then(|v| v.split_whitespace().next()?.parse().ok())
                .unwrap_or(0)
        };
        let removed = |t: &&String| t.ends_with(" (deleted)");
        let pool = |t: &&String| {
            t.starts_with(SHM_DIR) && t.trim_end_matches(" (deleted)").ends_with(".data")
        };
        Self {
            rss_kb: kb("VmRSS"),
            anon_kb: kb("RssAnon"),
            shmem_kb: kb("RssShmem"),
            fds: fd_targets.len(),
            pool_fds: fd_targets.iter().filter(pool).count(),
            removed_pool_fds: fd_targets.iter().filter(pool).filter(removed).count(),
        }
    }
}

/// Number of shared-memory objects of `scene`'s iceoryx2 prefix: the files directly in
/// `/dev/shm`, not iceoryx2's node and service files below it (those come and go with every
/// reader process).
pub fn shm_files(scene: &TestScene) -> usize {
    scene
        .files()
        .iter()
        .filter(|p| p.parent() == Some(std::path::Path::new(SHM_DIR)))
        .count()
}

/// Growth from `from` to `to`, percent of `from` (0 when `from` is 0).
pub fn growth_pct(from: u64, to: u64) -> f64 {
    if from == 0 {
        return 0.0;
    }
    (to as f64 - from as f64) / from as f64 * 100.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_fields_are_read_in_kilobytes_and_missing_ones_are_zero() {
        let status = "Name:\tygg\nVmRSS:\t  123456 kB\nRssAnon:\t   100000 kB\n\
                      RssFile:\t    3456 kB\nRssShmem:\t   20000 kB\n";
        let fds = [
            "/dev/null",
            "/dev/shm/p_1f_42__0.data",
            "/dev/shm/p_1f_42__mgmt.data",
            "/dev/shm/p_1f_41__4.data (deleted)",
            "/dev/shm/p_9a_7.event_mgmt (deleted)",
            "/tmp/x.data",
        ]
        .map(String::from);
        let u = Usage::parse(status, &fds);
        assert_eq!(
            u,
            Usage {
                rss_kb: 123_456,
                anon_kb: 100_000,
                shmem_kb: 20_000,
                fds: 6,
                pool_fds: 3,
                removed_pool_fds: 1,
            }
        );
        assert_eq!(Usage::parse("Name:\tx\n", &[]), Usage::default());
    }

    #[test]
    fn this_process_has_memory_and_descriptors() {
        let u = Usage::of(std::process::id()).expect("procfs");
        assert!(u.rss_kb > 0 && u.anon_kb > 0 && u.fds >= 3, "{u:?}");
    }

    #[test]
    fn growth_is_relative_to_the_first_value() {
        assert_eq!(growth_pct(200, 210), 5.0);
        assert_eq!(growth_pct(200, 190), -5.0);
        assert_eq!(growth_pct(0, 10), 0.0);
    }
}
