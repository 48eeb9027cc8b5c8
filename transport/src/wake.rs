//! One wait for an iceoryx2 listener's events and, beside them, the exit of processes.
//!
//! iceoryx2's `Listener::timed_wait` can only wait for events, so a reader that must also
//! notice a killed writer (which sends none), and a writer that must clean up after killed
//! readers, used to wake every liveness interval to ask iceoryx2. Polling the listener's
//! socket together with pidfds of those processes ([`ProcessWatch`]) wakes the thread
//! when either has something, and otherwise not at all: idle readers and writers no
//! longer spend CPU on periodic wake-ups, and a killed process is noticed at once.
//!
//! [`ProcessWatch`]: crate::process_watch::ProcessWatch

#![allow(
    unsafe_code,
    reason = "the listener's descriptor is only reachable through iceoryx2's unsafe accessor"
)]

use std::os::fd::BorrowedFd;
use std::time::Duration;

use iceoryx2::port::listener::Listener;
use iceoryx2::prelude::EventId;
use iceoryx2_bb_posix::file_descriptor::FileDescriptorBased as _;
use rustix::event::{PollFd, PollFlags, Timespec, poll};
use rustix::io::Errno;

use crate::service::Ipc;

/// Waiting failed: the poll or iceoryx2's collection of the events.
#[derive(Debug, thiserror::Error)]
#[error("waiting for events failed: {0}")]
pub(crate) struct WaitFailed(String);

impl WaitFailed {
    /// What failed.
    pub(crate) fn reason(self) -> String {
        self.0
    }
}

/// Waits up to `timeout` until `listener` has events, a process behind one of `exit_fds`
/// (pidfds) exits, or a signal arrives; then hands every event that arrived to `on_event`
/// without blocking. Returns whether a process behind `exit_fds` has exited.
///
/// # Errors
/// [`WaitFailed`] when the poll or collecting the events fails.
pub(crate) fn wait(
    listener: &Listener<Ipc>,
    exit_fds: &[BorrowedFd<'_>],
    timeout: Duration,
    on_event: impl FnMut(EventId),
) -> Result<bool, WaitFailed> {
    let mut fds = Vec::with_capacity(1 + exit_fds.len());
    fds.push(PollFd::from_borrowed_fd(
        descriptor(listener),
        PollFlags::IN,
    ));
    fds.extend(
        exit_fds
            .iter()
            .map(|&fd| PollFd::from_borrowed_fd(fd, PollFlags::IN)),
    );
    let timeout = Timespec {
        tv_sec: i64::try_from(timeout.as_secs()).unwrap_or(i64::MAX),
        tv_nsec: i64::from(timeout.subsec_nanos()),
    };
    let exited = match poll(&mut fds, Some(&timeout)) {
        Ok(_) => fds[1..].iter().any(|fd| !fd.revents().is_empty()),
        // A signal: the caller looks at what it asks for.
        Err(Errno::INTR) => false,
        Err(e) => return Err(WaitFailed(format!("poll of the event socket: {e}"))),
    };
    let mut on_event = on_event;
    listener
        .try_wait(|activation| on_event(activation.id))
        .map_err(|e| WaitFailed(e.to_string()))?;
    Ok(exited)
}

/// The descriptor of `listener`'s event socket, borrowed for as long as the listener.
fn descriptor(listener: &Listener<Ipc>) -> BorrowedFd<'_> {
    // SAFETY: `native_handle` asks that the value is neither kept beyond the descriptor's
    // life nor closed. The descriptor belongs to the listener's socket, which is open for
    // the listener's whole life (iceoryx2: "the file descriptor and its reference never
    // change during the lifetime of the listener port"); the `BorrowedFd` is tied to the
    // borrow of `listener`, and nothing here closes it.
    unsafe { BorrowedFd::borrow_raw(listener.file_descriptor().native_handle()) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_prefix::TestPrefix;
    use iceoryx2::prelude::*;
    use rustix::process::{Pid, PidfdFlags, pidfd_open};
    use std::os::fd::AsFd as _;
    use std::time::Instant;

    /// A node under a prefix of its own (its files go with the prefix).
    fn node(tag: &str) -> (Node<Ipc>, TestPrefix) {
        let prefix = TestPrefix::new(&format!("wk_{tag}"));
        (prefix.node(), prefix)
    }

    #[test]
    fn wakes_for_an_event_for_an_exit_and_otherwise_times_out() {
        let (node, _prefix) = node("a");
        let service = node
            .service_builder(&"ygg_wk_events".try_into().expect("name"))
            .event()
            .open_or_create()
            .expect("event service");
        let listener = service.listener_builder().create().expect("listener");
        let notifier = service.notifier_builder().create().expect("notifier");

        let start = Instant::now();
        let exited = wait(&listener, &[], Duration::from_millis(50), |_| {}).expect("wait");
        assert!(!exited);
        assert!(
            start.elapsed() >= Duration::from_millis(45),
            "timed out early"
        );

        notifier
            .notify_with_custom_event_id(EventId::new(3))
            .expect("notify");
        let mut ids = Vec::new();
        let exited =
            wait(&listener, &[], Duration::from_secs(10), |id| ids.push(id)).expect("wait");
        assert!(!exited);
        assert_eq!(ids, [EventId::new(3)]);

        let mut child = std::process::Command::new("sleep")
            .arg("0.2")
            .spawn()
            .expect("sleep");
        let pid = Pid::from_raw(child.id().cast_signed()).expect("pid");
        let pidfd = pidfd_open(pid, PidfdFlags::empty()).expect("pidfd");
        let start = Instant::now();
        let exited =
            wait(&listener, &[pidfd.as_fd()], Duration::from_secs(10), |_| {}).expect("wait");
        assert!(exited, "the child's exit ends the wait");
        assert!(start.elapsed() < Duration::from_secs(5));
        child.wait().expect("reap");
    }
}
