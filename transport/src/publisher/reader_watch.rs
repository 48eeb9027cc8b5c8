//! The processes of a writer's readers, watched so that the helper thread cleans up after
//! a killed reader at once and otherwise sleeps.
//!
//! A killed reader leaves its ports behind, holding samples of the writer's pool and a
//! subscriber slot, until some process removes its node's resources. The helper used to
//! look for dead nodes every second with iceoryx2's `Node::list`, which reads and parses
//! every node's details file (about a millisecond, most of an idle writer's CPU). Now it
//! watches each reader node's process ([`ProcessWatch`]): it waits on their pidfds beside
//! its listener, asks iceoryx2 about a node only when its process exited or the
//! confirmation is due, and every liveness interval for a reader whose process it cannot
//! watch (another pid namespace).

use std::os::fd::BorrowedFd;
use std::time::{Duration, Instant};

use iceoryx2::config::Config;
use iceoryx2::identifiers::UniqueNodeId;

use crate::process_watch::{Liveness, ProcessWatch};

/// The reader nodes of one writer and their processes.
#[derive(Debug, Default)]
pub(crate) struct ReaderWatch {
    readers: Vec<(UniqueNodeId, ProcessWatch)>,
}

impl ReaderWatch {
    /// Watches exactly the nodes `readers` (the stream's subscribers now) and removes the
    /// resources of those whose process died. Returns whether one was found dead or gone.
    pub(crate) fn check(&mut self, readers: &[UniqueNodeId], config: &Config) -> bool {
        self.readers.retain(|(id, _)| readers.contains(id));
        for &id in readers {
            if !self.readers.iter().any(|(known, _)| *known == id) {
                self.readers.push((id, ProcessWatch::default()));
            }
        }
        let mut gone = false;
        for (id, watch) in &mut self.readers {
            gone |= watch.check(*id, config) == Liveness::Gone;
        }
        gone
    }

    /// The pidfds to wait on: each polls readable when its reader's process exits.
    pub(crate) fn exit_fds(&self) -> Vec<BorrowedFd<'_>> {
        self.readers
            .iter()
            .filter_map(|(_, w)| w.exit_fd())
            .collect()
    }

    /// When the next [`ReaderWatch::check`] is due without a wake-up: the earliest
    /// confirmation of a watched reader, or `unwatched` from `now` when some reader is not
    /// watched; `None` without readers.
    pub(crate) fn next_check(&self, now: Instant, unwatched: Duration) -> Option<Instant> {
        self.readers
            .iter()
            .map(|(_, w)| match (w.exit_fd(), w.confirm_due()) {
                (Some(_), Some(due)) => due,
                _ => now + unwatched,
            })
            .min()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::process_watch::tests::own_node;

    #[test]
    fn readers_are_watched_and_forgotten_with_the_stream_subscribers() {
        let (node, _, _prefix) = own_node("rw");
        let config = node.config().clone();
        let id = *node.id();
        let mut watch = ReaderWatch::default();
        let now = Instant::now();
        assert!(!watch.check(&[id], &config), "a live node is not gone");
        assert_eq!(watch.exit_fds().len(), 1, "this process is watched");
        let second = Duration::from_secs(1);
        let due = watch.next_check(now, second).expect("a reader");
        assert!(
            due > now + second,
            "a watched reader waits for its confirmation"
        );
        assert!(!watch.check(&[], &config));
        assert!(
            watch.exit_fds().is_empty(),
            "a departed reader is not watched"
        );
        assert_eq!(watch.next_check(now, second), None);
        drop(node);
        assert!(
            watch.check(&[id], &config),
            "a node that no longer exists is gone"
        );
    }
}
