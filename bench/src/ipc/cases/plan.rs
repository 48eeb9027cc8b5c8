//! [`Plan`]: how many samples and how long each case of a run takes, quick or full.

use std::time::Duration;

/// Sample counts and durations.
pub(super) struct Plan {
    pub(super) quick: bool,
    /// (label, bytes, samples)
    pub(super) sizes: Vec<(&'static str, usize, usize)>,
    pub(super) small_samples: usize,
    pub(super) office_samples: usize,
    pub(super) full_samples: usize,
    pub(super) attach_samples: usize,
    pub(super) shm40_samples: usize,
    pub(super) socket_samples: usize,
    pub(super) qps_secs: f64,
    pub(super) throughput_secs: f64,
    pub(super) throughput_reps: usize,
    /// Pause between publishes (at least; twice the last publish's duration for big ones),
    /// so that readers are back to waiting and every publish is seen.
    pub(super) gap: Duration,
}

impl Plan {
    pub(super) fn new(quick: bool) -> Plan {
        if quick {
            Plan {
                quick,
                sizes: vec![
                    ("1KB", 1_000, 100),
                    ("10KB", 10_000, 100),
                    ("100KB", 100_000, 100),
                    ("1MB", 1_000_000, 60),
                    ("10MB", 10_000_000, 20),
                    ("40MB", 40_000_000, 10),
                ],
                small_samples: 150,
                office_samples: 150,
                full_samples: 20,
                attach_samples: 5,
                shm40_samples: 8,
                socket_samples: 6,
                qps_secs: 1.5,
                throughput_secs: 1.0,
                throughput_reps: 2,
                gap: Duration::from_millis(3),
            }
        } else {
            Plan {
                quick,
                sizes: vec![
                    ("1KB", 1_000, 500),
                    ("10KB", 10_000, 500),
                    ("100KB", 100_000, 400),
                    ("1MB", 1_000_000, 200),
                    ("10MB", 10_000_000, 60),
                    ("40MB", 40_000_000, 30),
                    ("100MB", 100_000_000, 15),
                    ("200MB", 200_000_000, 12),
                ],
                small_samples: 600,
                office_samples: 600,
                full_samples: 60,
                attach_samples: 15,
                shm40_samples: 25,
                socket_samples: 15,
                qps_secs: 5.0,
                throughput_secs: 3.0,
                throughput_reps: 3,
                gap: Duration::from_millis(4),
            }
        }
    }
}
