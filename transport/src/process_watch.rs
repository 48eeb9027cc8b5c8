//! A cheap check, between iceoryx2's own, that a node's process still runs.
//!
//! iceoryx2's liveness check of one node ([`Node::state_of`](iceoryx2::prelude::Node)) lists
//! every node of the system and reads and parses each one's details file (TOML holding a
//! whole iceoryx2 config) until it finds the node: about half a millisecond with a handful
//! of processes, in every reader at every liveness interval. Measured with a bridge and four
//! readers (`ygg-bench hydra`), that was most of an idle reader's CPU.
//!
//! A reader watches its writer's node, a writer's helper thread each reader's. After
//! iceoryx2 has found a node alive once, a [`ProcessWatch`] opens a pidfd
//! on the node's process (Linux 5.3 or later) and later checks only that: a poll that does
//! not wait tells whether the process has exited. iceoryx2 stays the authority: a process
//! that exited, a different node, and every [`CONFIRM_INTERVAL`] go through its check again.
//! The pidfd is kept only when the process's executable matches the node's details, so a
//! node of another pid namespace (whose pid means another process here) gets none (unless
//! that process runs the same program, which the periodic confirmation settles) and is
//! checked the iceoryx2 way.

use std::os::fd::{AsFd as _, BorrowedFd, OwnedFd};
use std::time::{Duration, Instant};

use iceoryx2::config::Config;
use iceoryx2::identifiers::UniqueNodeId;
use iceoryx2::node::{NodeDetails, NodeView as _};
use iceoryx2::prelude::{Node, NodeState, SemanticString as _};
use rustix::event::{PollFd, PollFlags, Timespec, poll};
use rustix::process::{Pid, PidfdFlags, pidfd_open};

use crate::service::Ipc;

/// How long a pidfd's answer stands before iceoryx2's check confirms the node again.
const CONFIRM_INTERVAL: Duration = Duration::from_secs(5);

/// A node's process, watched through a pidfd.
#[derive(Debug, Default)]
pub(crate) struct ProcessWatch {
    watched: Option<Watched>,
}

#[derive(Debug)]
struct Watched {
    node: UniqueNodeId,
    pidfd: OwnedFd,
    confirmed: Instant,
    /// The pidfd has polled readable: the process has exited.
    exited: bool,
}

/// What [`ProcessWatch::check`] found out about a node.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Liveness {
    /// Its process runs (the pidfd says so, or iceoryx2 found the node alive).
    Alive,
    /// The node is dead (its resources are now removed) or no longer exists.
    Gone,
    /// iceoryx2 could not tell now; ask again later.
    Unknown,
}

impl ProcessWatch {
    /// Whether `node` lives: the pidfd answers while it can ([`ProcessWatch::runs`]),
    /// iceoryx2 otherwise. A node found alive is watched from then on. A dead one is
    /// forgotten and the resources it left are removed: the ports holding samples of a
    /// writer's pool, the publisher slot a restarted writer claims (another process may be
    /// removing them at the same time, which is fine).
    pub(crate) fn check(&mut self, node: UniqueNodeId, config: &Config) -> Liveness {
        if self.runs(node) {
            return Liveness::Alive;
        }
        match Node::<Ipc>::state_of(config, node) {
            Ok(Some(NodeState::Alive(view))) => {
                self.confirmed(node, view.details().as_ref());
                Liveness::Alive
            }
            Ok(Some(NodeState::Dead(view))) => {
                self.forget();
                let _ = view.try_remove_stale_resources();
                Liveness::Gone
            }
            Ok(None) => {
                self.forget();
                Liveness::Gone
            }
            Ok(Some(_)) | Err(_) => Liveness::Unknown,
        }
    }

    /// Whether `node`'s process is known to run without asking iceoryx2: it is the node
    /// watched, its process has not exited, and iceoryx2 confirmed it alive less than
    /// [`CONFIRM_INTERVAL`] ago. `false` means "ask iceoryx2", not "dead".
    fn runs(&mut self, node: UniqueNodeId) -> bool {
        let Some(w) = &mut self.watched else {
            return false;
        };
        if w.node != node || w.exited || w.confirmed.elapsed() >= CONFIRM_INTERVAL {
            return false;
        }
        let mut fds = [PollFd::new(&w.pidfd, PollFlags::IN)];
        // A pidfd polls readable once its process has exited.
        w.exited = !matches!(poll(&mut fds, Some(&Timespec::default())), Ok(0));
        !w.exited
    }

    /// The pidfd to wait on beside the writer's events: it polls readable when the
    /// watched process exits. `None` when nothing is watched or the process is known to
    /// have exited (waiting on it would return at once).
    pub(crate) fn exit_fd(&self) -> Option<BorrowedFd<'_>> {
        self.watched
            .as_ref()
            .filter(|w| !w.exited)
            .map(|w| w.pidfd.as_fd())
    }

    /// When iceoryx2 must confirm the watched node again; `None` when nothing is watched.
    pub(crate) fn confirm_due(&self) -> Option<Instant> {
        self.watched
            .as_ref()
            .map(|w| w.confirmed + CONFIRM_INTERVAL)
    }

    /// iceoryx2 found `node` alive, with these details: watch its process from now on.
    fn confirmed(&mut self, node: UniqueNodeId, details: Option<&NodeDetails>) {
        if let Some(w) = &mut self.watched
            && w.node == node
        {
            w.confirmed = Instant::now();
            return;
        }
        self.watched = details.and_then(|d| {
            let pidfd = open_matching(d)?;
            Some(Watched {
                node,
                pidfd,
                confirmed: Instant::now(),
                exited: false,
            })
        });
    }

    /// Forgets the watched process (iceoryx2 found its node dead or gone).
    fn forget(&mut self) {
        self.watched = None;
    }
}

/// A pidfd on the process `details` names, if a process with that pid runs here from the
/// executable the details give (iceoryx2 records the file name of `/proc/self/exe`).
fn open_matching(details: &NodeDetails) -> Option<OwnedFd> {
    let pid = Pid::from_raw(details.process_id().value())?;
    let pidfd = pidfd_open(pid, PidfdFlags::empty()).ok()?;
    // Read after the pidfd is open: if the pid was reused in between, the executable read
    // is the new process's, and a match then means the same program under the same pid,
    // which the periodic confirmation settles.
    let exe = std::fs::read_link(format!("/proc/{}/exe", pid.as_raw_nonzero())).ok()?;
    let same = exe
        .file_name()
        .is_some_and(|name| name.as_encoded_bytes() == details.executable().as_bytes());
    same.then_some(pidfd)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::test_prefix::TestPrefix;

    /// A node of this process under an iceoryx2 prefix of its own (`tag` and the pid),
    /// its details as iceoryx2 reads them back, and the prefix (its files go with it).
    pub(crate) fn own_node(tag: &str) -> (Node<Ipc>, Option<NodeDetails>, TestPrefix) {
        let prefix = TestPrefix::new(&format!("pw_{tag}"));
        let node = prefix.node();
        let details = match Node::<Ipc>::state_of(node.config(), *node.id()) {
            Ok(Some(NodeState::Alive(view))) => view.details().clone(),
            other => panic!("own node not alive: {other:?}"),
        };
        (node, details, prefix)
    }

    #[test]
    fn a_confirmed_node_of_a_running_process_is_watched_and_no_other() {
        let (node, details, _prefix) = own_node("a");
        let id = *node.id();
        let mut watch = ProcessWatch::default();
        assert!(!watch.runs(id), "nothing watched yet");
        assert!(open_matching(details.as_ref().expect("details")).is_some());
        watch.confirmed(id, details.as_ref());
        assert!(watch.runs(id), "this process runs");
        let (other, _, _other_prefix) = own_node("b");
        assert!(
            !watch.runs(*other.id()),
            "another node is not the one watched"
        );
        watch.forget();
        assert!(!watch.runs(id), "forgotten");
        watch.confirmed(id, None);
        assert!(!watch.runs(id), "no details, nothing to watch");
    }

    #[test]
    fn an_exited_process_no_longer_runs() {
        let (node, _, _prefix) = own_node("c");
        let id = *node.id();
        let mut child = std::process::Command::new("sleep")
            .arg("30")
            .spawn()
            .expect("sleep");
        let pid = Pid::from_raw(child.id().cast_signed()).expect("pid");
        let mut watch = ProcessWatch {
            watched: Some(Watched {
                node: id,
                pidfd: pidfd_open(pid, PidfdFlags::empty()).expect("pidfd"),
                confirmed: Instant::now(),
                exited: false,
            }),
        };
        assert!(watch.runs(id), "the child runs");
        assert!(watch.exit_fd().is_some(), "its exit can be waited for");
        child.kill().expect("kill");
        child.wait().expect("reap");
        assert!(!watch.runs(id), "the child exited");
        assert!(
            watch.exit_fd().is_none(),
            "an exit already seen is not waited for"
        );
        watch.confirmed(id, None);
        assert!(
            !watch.runs(id),
            "a confirmation does not revive an exited process"
        );
    }

    #[test]
    fn an_answer_older_than_the_confirm_interval_is_asked_again() {
        let (node, details, _prefix) = own_node("d");
        let id = *node.id();
        let mut watch = ProcessWatch::default();
        watch.confirmed(id, details.as_ref());
        let w = watch.watched.as_mut().expect("watched");
        w.confirmed = Instant::now() - CONFIRM_INTERVAL;
        assert!(!watch.runs(id), "stale: iceoryx2 must confirm");
        watch.confirmed(id, details.as_ref());
        assert!(watch.runs(id), "confirmed again");
    }
}
