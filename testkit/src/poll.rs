//! [`wait_until`] and [`poll_until`]: a bounded poll of a condition the OS gives no event
//! for (a file gone from `/dev/shm`, a process's signal mask, a reader slot freed).
//!
//! Wait on the event where there is one (a line: [`crate::Proc::expect_line`]; a process
//! exit: [`crate::Proc::wait_exit`]); poll only the real condition, never a duration.

use std::time::{Duration, Instant};

/// How often [`poll_until`] checks its condition.
pub const POLL_INTERVAL: Duration = Duration::from_millis(10);

/// Checks `condition` every [`POLL_INTERVAL`] until it holds or `timeout` passes; how long
/// it took, or `None` if it never held.
pub fn poll_until(timeout: Duration, mut condition: impl FnMut() -> bool) -> Option<Duration> {
    let start = Instant::now();
    loop {
        if condition() {
            return Some(start.elapsed());
        }
        let remaining = timeout.checked_sub(start.elapsed())?;
        std::thread::sleep(POLL_INTERVAL.min(remaining));
    }
}

/// [`poll_until`], failing the test when `condition` does not hold in time.
///
/// # Panics
///
/// With `what` (the condition, in words) if it does not hold within `timeout`.
pub fn wait_until(timeout: Duration, what: &str, condition: impl FnMut() -> bool) -> Duration {
    poll_until(timeout, condition).unwrap_or_else(|| panic!("not within {timeout:?}: {what}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_condition_that_holds_later_is_seen_and_one_that_never_holds_times_out() {
        let start = Instant::now();
        let waited = poll_until(Duration::from_secs(10), || {
            start.elapsed() >= Duration::from_millis(30)
        })
        .expect("holds after 30 ms");
        assert!(waited >= Duration::from_millis(30));
        assert_eq!(poll_until(Duration::from_millis(30), || false), None);
    }

    #[test]
    #[should_panic(expected = "not within 20ms: the impossible")]
    fn wait_until_names_the_condition_that_did_not_hold() {
        wait_until(Duration::from_millis(20), "the impossible", || false);
    }
}
