//! Dev-only harness for Yggdrasil's multi-process tests and benches, and the test drivers.
//!
//! * [`binary`] and [`example`] find (and if needed build) the workspace's executables.
//! * [`TestScene`] gives each test or run a unique scene name and iceoryx2 prefix, so
//!   tests can run in parallel and each one can check that it left nothing in `/dev/shm`
//!   ([`TestScene::assert_no_leftovers`], [`TestScene::clean_up`]); [`remove_stale`]
//!   removes what killed runs left.
//! * [`Proc`] is a spawned child whose stdout lines can be awaited (and whose stdin can
//!   carry commands); it is killed and reaped when dropped and when the test's
//!   [`Watchdog`] fires. A child that links this crate calls [`die_with_parent`] to get
//!   SIGTERM when its parent dies.
//! * [`wait_until`] polls, with a deadline, a condition that has no event to wait on.
//! * [`stats`] is the one median / p99 (nearest rank) everything reports.
//! * [`fingerprint`] gives canonical forms of archived segments, to compare incremental
//!   builds with fresh ones.
//! * [`VethLink`] makes two hosts on one machine (network namespaces joined by a veth
//!   pair) for what crosses a network.
//! * [`test_pattern`] is the synthetic segment content of the transport tests.
//!
//! Binaries (test drivers, never part of the product): `ygg-test-writer` publishes
//! synthetic segments ([`test_pattern`]) and `ygg-test-reader` watches or dumps a scene at
//! the transport level, checking them; `ygg-soak` runs the demo's writer and readers for
//! minutes under churn (`cargo run --release -p ygg-testkit --bin ygg-soak -- --minutes 2`).

mod binary;
pub mod fingerprint;
mod poll;
mod proc;
mod scene;
mod signal;
pub mod stats;
pub mod test_pattern;
mod veth;
mod watchdog;

pub use binary::{ENV_BIN_DIR, binary, example, run, text};
pub use poll::{POLL_INTERVAL, poll_until, wait_until};
pub use proc::{
    DROP_GRACE, ENV_PARENT_PID, Input, LineError, Proc, catches_signal, die_with_parent, field,
};
pub use scene::{PREFIX_TAG, SHM_DIR, TestScene, remove_stale};
pub use veth::{ENV_SKIP_NETNS_TESTS, VethLink};
pub use watchdog::Watchdog;
