//! SIGINT and SIGTERM: taken over so that an interrupted run stops its children and
//! removes its shared memory before exiting.

use super::error::Res;
use std::sync::atomic::{AtomicBool, Ordering};

/// Whether SIGINT or SIGTERM arrived since [`install_signal_handler`] (sticky).
fn interrupted() -> bool {
    static SEEN: AtomicBool = AtomicBool::new(false);
    if iceoryx2_bb_posix::signal::SignalHandler::termination_requested() {
        SEEN.store(true, Ordering::SeqCst);
    }
    SEEN.load(Ordering::SeqCst)
}

/// Takes over SIGINT and SIGTERM (iceoryx2's handler), so that an interrupted run stops
/// its children and removes its shared memory before exiting; see [`interrupted`].
pub(crate) fn install_signal_handler() {
    let _ = interrupted();
}

/// An error unless the run was interrupted.
pub(crate) fn check_interrupted() -> Res<()> {
    if interrupted() {
        Err("interrupted (SIGINT/SIGTERM): children stopped, shared memory removed".into())
    } else {
        Ok(())
    }
}
