//! [`send_signal`]: a signal to a process by pid, for [`crate::Proc`] and [`crate::Watchdog`].

use rustix::process::{Pid, Signal, kill_process};

/// Sends `signal` to `pid` (errors ignored: the process may be gone).
pub(crate) fn send_signal(pid: u32, signal: Signal) {
    if let Some(pid) = i32::try_from(pid).ok().and_then(Pid::from_raw) {
        let _ = kill_process(pid, signal);
    }
}
