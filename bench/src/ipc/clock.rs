//! The clocks latencies and CPU time are read from.

/// Nanoseconds since the Unix epoch: the clock shared by the writer and its readers.
pub(crate) use ygg_transport::protocol::unix_ns;

/// CPU time the calling thread has used, ns (`CLOCK_THREAD_CPUTIME_ID`): what one reader
/// spends, whatever else runs on the machine.
pub(crate) fn thread_cpu_ns() -> u64 {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::ThreadCPUTime);
    u64::try_from(t.tv_sec).unwrap_or(0) * 1_000_000_000 + u64::try_from(t.tv_nsec).unwrap_or(0)
}
