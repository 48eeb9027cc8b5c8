//! [`TestPrefix`]: a unit test's own iceoryx2 file-name prefix, whose files in
//! `/dev/shm` (iceoryx2's per-prefix `global_mgmt` counter stays after every node is
//! gone) are removed when it is dropped.

use crate::service::{Ipc, iceoryx_config};
use iceoryx2::prelude::*;

/// A unit test's iceoryx2 prefix: `ygg_<tag>_<pid>_`.
pub(crate) struct TestPrefix(String);

impl TestPrefix {
    /// The prefix for `tag` in this process.
    pub(crate) fn new(tag: &str) -> Self {
        TestPrefix(format!("ygg_{tag}_{}_", std::process::id()))
    }

    /// A node of this process under this prefix.
    pub(crate) fn node(&self) -> Node<Ipc> {
        let config = iceoryx_config(Some(&self.0)).expect("config");
        NodeBuilder::new()
            .config(&config)
            .create::<Ipc>()
            .expect("node")
    }
}

impl Drop for TestPrefix {
    fn drop(&mut self) {
        let Ok(entries) = std::fs::read_dir("/dev/shm") else {
            return;
        };
        for entry in entries.flatten() {
            if entry.file_name().to_string_lossy().starts_with(&self.0) {
                let _ = std::fs::remove_file(entry.path());
            }
        }
    }
}
