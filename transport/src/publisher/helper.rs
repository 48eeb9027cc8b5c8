//! The writer's helper thread: catch-up bursts for readers that ask, and housekeeping.
//!
//! A reader announces itself ([`EVENT_READER_HELLO`]) when it connects and whenever it finds
//! a hole in the segment stream (a segment its newest manifest names was overflowed away). The
//! helper answers with one catch-up burst on the stream: a copy of every segment of the
//! current snapshot ([`FLAG_CATCH_UP`]), then its manifest, and wakes the readers.
//! Announcements that arrive together are answered by one burst. The lock the publishing
//! thread takes is held for one segment's copy at a time, so a burst delays a publish by at
//! most the copy of one segment.

use std::path::PathBuf;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use iceoryx2::config::Config;
use iceoryx2::port::listener::Listener;

use super::reader_watch::ReaderWatch;
use super::shared_state::{Inner, lock};
use crate::protocol::{EVENT_READER_HELLO, EVENT_SNAPSHOT_PUBLISHED};
use crate::service::Ipc;
use crate::wake;

/// How long the helper sleeps when no reader is connected (a new one announces itself).
const NO_READER_CHECK: Duration = Duration::from_secs(5);

/// What the helper thread owns.
pub(crate) struct Helper {
    pub(crate) listener: Listener<Ipc>,
    pub(crate) shm_dir: PathBuf,
    /// How often readers whose process cannot be watched are checked.
    pub(crate) interval: Duration,
    pub(crate) config: Config,
}

impl Helper {
    /// Answers reader announcements, removes resources of dead readers and drops connections
    /// of departed ones until `stop` is set. Sleeps until an announcement, a reader's
    /// process exits, or a check of the readers is due ([`ReaderWatch`]).
    pub(crate) fn run(self, inner: &Mutex<Inner>, stop: &AtomicBool) {
        let mut readers = ReaderWatch::default();
        let mut next_check = Instant::now();
        let mut readers_before = lock(inner).reader_count();
        while !stop.load(Ordering::SeqCst) {
            let mut hello = false;
            let waited = wake::wait(
                &self.listener,
                &readers.exit_fds(),
                next_check.saturating_duration_since(Instant::now()),
                |id| hello |= id == EVENT_READER_HELLO,
            );
            if stop.load(Ordering::SeqCst) {
                break;
            }
            let exited = waited.as_ref().is_ok_and(|&exited| exited);
            if waited.is_err() {
                // A broken listener: do not spin.
                std::thread::sleep(Duration::from_millis(50));
            }
            if hello {
                self.catch_up(inner);
            }
            let now = Instant::now();
            if hello || exited || now >= next_check {
                readers.check(&lock(inner).reader_nodes(), &self.config);
                // Drops the connections (shared-memory files and descriptors) of readers
                // that left or died; they would otherwise stay until the next send.
                let count = {
                    let inner = lock(inner);
                    inner.update_connections();
                    inner.reader_count()
                };
                // A reader left or died (and whoever noticed first, a reader or this thread,
                // removed its resources): give the heap that freed back.
                if count < readers_before {
                    super::heap::release_free_heap();
                }
                readers_before = count;
                next_check = readers
                    .next_check(now, self.interval)
                    .unwrap_or(now + NO_READER_CHECK);
            }
        }
    }

    /// Connects new readers and sends them (and whoever else listens) the current snapshot.
    fn catch_up(&self, inner: &Mutex<Inner>) {
        let burst = {
            let inner = lock(inner);
            inner.update_connections();
            inner.current_snapshot()
        };
        for sample in &burst {
            // Out of shared memory or loans, or closing: the reader asks again after a while.
            if lock(inner).send_copy(sample, &self.shm_dir).is_err() {
                break;
            }
        }
        lock(inner).notify(EVENT_SNAPSHOT_PUBLISHED);
    }
}
