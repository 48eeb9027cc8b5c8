//! A ROS 2 `hydra_msgs/msg/DsgUpdate` sample as `ygg bridge ros2` receives it: the first
//! byte picks the encapsulation (plain CDR or XCDR2, either byte order), the rest is the
//! payload. Decoding never panics; a full update builds a scene, an incremental one is
//! applied to the small office (everything checked before anything changes) and what
//! it leaves builds a scene.
#![no_main]

use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use ygg_dsg::layout::{self, Layout};
use ygg_dsg::office::{OfficeParams, generate};
use ygg_dsg::{DsgGraph, DsgVersion};
use ygg_ros2::{DsgUpdate, Encoding};

/// The graph incremental updates apply to (the seeds' base).
fn base() -> &'static DsgGraph {
    static BASE: OnceLock<DsgGraph> = OnceLock::new();
    BASE.get_or_init(|| {
        let mut office = generate(OfficeParams {
            seed: 7,
            scale: 0.01,
        });
        office.mesh = None;
        office
    })
}

fuzz_target!(|data: &[u8]| {
    let Some((&pick, payload)) = data.split_first() else {
        return;
    };
    let identifier = [0x0000, 0x0001, 0x0006, 0x0007, 0x0008, 0x0009][usize::from(pick % 6)];
    let Ok(encoding) = Encoding::from_identifier(identifier) else {
        return;
    };
    let Ok(update) = DsgUpdate::from_cdr(payload, encoding) else {
        return;
    };
    let Ok(part) = ygg_dsg::parse_binary_body(&update.layer_contents, DsgVersion::V1_1_3, "fuzz")
    else {
        return;
    };
    let graph = if update.full_update {
        part
    } else {
        let mut graph = base().clone();
        if graph
            .apply_update(part, &update.deleted_nodes, &update.deleted_edges)
            .is_err()
        {
            assert_eq!(&graph, base(), "a refused update changed the graph");
            return;
        }
        graph
    };
    let _ = layout::build(&graph, Layout::Mint);
});
