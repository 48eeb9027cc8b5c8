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
use iceoryx2::prelude::{CallbackProgression, Node, NodeState};

use super::segment_publisher::{Inner, lock};
use crate::protocol::{EVENT_READER_HELLO, EVENT_SNAPSHOT_PUBLISHED, Ipc};

/// How often the helper thread removes resources of dead readers.
const CLEANUP_INTERVAL: Duration = Duration::from_secs(1);

/// What the helper thread owns.
pub(crate) struct Helper {
    pub(crate) listener: Listener<Ipc>,
    pub(crate) shm_dir: PathBuf,
    pub(crate) interval: Duration,
    pub(crate) config: Config,
}

impl Helper {
    /// Answers reader announcements, removes resources of dead readers and drops connections
    /// of departed ones until `stop` is set.
    pub(crate) fn run(self, inner: &Mutex<Inner>, stop: &AtomicBool) {
        let mut last_cleanup = Instant::now();
        let mut readers_before = lock(inner).reader_count();
        while !stop.load(Ordering::SeqCst) {
            let mut hello = false;
            let waited = self.listener.timed_wait(
                |activation| hello |= activation.id == EVENT_READER_HELLO,
                self.interval,
            );
            if stop.load(Ordering::SeqCst) {
                break;
            }
            if waited.is_err() {
                // Interrupted by a signal or a broken listener: do not spin.
                std::thread::sleep(self.interval.min(Duration::from_millis(50)));
            }
            if hello {
                self.catch_up(inner);
            }
            if last_cleanup.elapsed() >= CLEANUP_INTERVAL {
                cleanup_dead_nodes(&self.config);
                // Drops the connections (shared-memory files and descriptors) of readers
                // that left or died; they would otherwise stay until the next send.
                let readers = {
                    let inner = lock(inner);
                    inner.update_connections();
                    inner.reader_count()
                };
                // A reader left or died (and whoever noticed first, a reader or this thread,
                // removed its resources): give the heap that freed back.
                if readers < readers_before {
                    super::heap::release_free_heap();
                }
                readers_before = readers;
                last_cleanup = Instant::now();
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

/// Removes the resources of dead processes (readers killed without cleanup), freeing their
/// subscriber slots and the samples they held.
fn cleanup_dead_nodes(config: &Config) {
    let _ = Node::<Ipc>::list(config, |state| {
        if let NodeState::Dead(view) = state {
            // Another process may be cleaning up the same node; that is fine.
            let _ = view.try_remove_stale_resources();
        }
        CallbackProgression::Continue
    });
}
