//! What `/proc` tells about a process: its CPU time and resident memory.

use super::spans::ProcSample;

/// CPU time and memory of process `pid` (`None`: this process). Zeros where `/proc` does
/// not say (another OS, a process that is gone).
pub fn sample(pid: Option<u32>) -> ProcSample {
    let dir = pid.map_or_else(|| "/proc/self".to_owned(), |p| format!("/proc/{p}"));
    let status = std::fs::read_to_string(format!("{dir}/status")).unwrap_or_default();
    ProcSample {
        cpu_ns: cpu_ns(&dir),
        rss: status_kb(&status, "VmRSS:") * 1024,
        rss_anon: status_kb(&status, "RssAnon:") * 1024,
    }
}

/// A `kB` field of `/proc/<pid>/status`.
fn status_kb(status: &str, key: &str) -> u64 {
    status
        .lines()
        .find_map(|l| l.strip_prefix(key))
        .and_then(|v| v.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .unwrap_or(0)
}

/// CPU time of every thread of the process, ns: the sum of each thread's
/// `schedstat` (ns), or `utime + stime` of `stat` (clock ticks of 10 ms) where the kernel
/// keeps no schedstat.
fn cpu_ns(dir: &str) -> u64 {
    let threads = std::fs::read_dir(format!("{dir}/task"))
        .map(|d| {
            d.filter_map(Result::ok)
                .filter_map(|t| std::fs::read_to_string(t.path().join("schedstat")).ok())
                .filter_map(|s| s.split_whitespace().next()?.parse::<u64>().ok())
                .collect::<Vec<u64>>()
        })
        .unwrap_or_default();
    if !threads.is_empty() {
        return threads.iter().sum();
    }
    let stat = std::fs::read_to_string(format!("{dir}/stat")).unwrap_or_default();
    // Fields after the command name (which may hold spaces), from field 3 on.
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let field = |i: usize| -> u64 {
        rest.split_whitespace()
            .nth(i)
            .and_then(|v| v.parse().ok())
            .unwrap_or(0)
    };
    // utime and stime are fields 14 and 15: 11 and 12 after the state (field 3).
    (field(11) + field(12)) * 10_000_000
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn this_process_has_memory_and_cpu_time() {
        let mut x = 0u64;
        for i in 0..2_000_000u64 {
            x = x.wrapping_mul(31).wrapping_add(std::hint::black_box(i));
        }
        std::hint::black_box(x);
        let s = sample(None);
        assert!(s.rss > 1_000_000, "{s:?}");
        assert!(s.rss_anon > 0 && s.rss_anon <= s.rss, "{s:?}");
        assert!(s.cpu_ns > 0, "{s:?}");
        assert_eq!(status_kb("VmRSS:\t  1234 kB\n", "VmRSS:"), 1234);
    }
}
