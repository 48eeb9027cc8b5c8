//! [`Watchdog`]: kills a test's children when the test runs past its deadline.

use std::sync::{Arc, Condvar, Mutex, PoisonError};
use std::time::Duration;

use rustix::process::Signal;

use crate::signal::send_signal;

/// Kills registered children when a test runs past its deadline, so no test hangs forever.
#[derive(Debug)]
pub struct Watchdog {
    pids: Arc<Mutex<Vec<u32>>>,
    done: Arc<(Mutex<bool>, Condvar)>,
}

impl Watchdog {
    /// Starts a watchdog that SIGKILLs every registered child after `limit`.
    pub fn new(limit: Duration) -> Self {
        let watchdog = Self {
            pids: Arc::new(Mutex::new(Vec::new())),
            done: Arc::new((Mutex::new(false), Condvar::new())),
        };
        let pids = Arc::clone(&watchdog.pids);
        let done = Arc::clone(&watchdog.done);
        std::thread::spawn(move || {
            let (lock, cvar) = &*done;
            let guard = lock.lock().unwrap_or_else(PoisonError::into_inner);
            let (guard, timeout) = cvar
                .wait_timeout_while(guard, limit, |finished| !*finished)
                .unwrap_or_else(PoisonError::into_inner);
            drop(guard);
            if timeout.timed_out() {
                eprintln!("watchdog: test exceeded {limit:?}, killing its children");
                for pid in pids.lock().unwrap_or_else(PoisonError::into_inner).iter() {
                    send_signal(*pid, Signal::KILL);
                }
            }
        });
        watchdog
    }

    /// Adds a child to kill at the deadline ([`crate::Proc::spawn`] does this).
    pub fn register(&self, pid: u32) {
        self.pids
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(pid);
    }
}

impl Drop for Watchdog {
    fn drop(&mut self) {
        let (lock, cvar) = &*self.done;
        *lock.lock().unwrap_or_else(PoisonError::into_inner) = true;
        cvar.notify_all();
    }
}
