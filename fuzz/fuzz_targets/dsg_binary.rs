//! A Spark-DSG binary file (`.sparkdsg`) or a header-less `to_binary()` body: decoding
//! never panics, never allocates from an unchecked length; what decodes builds a scene.
#![no_main]

use libfuzzer_sys::fuzz_target;
use ygg_dsg::DsgVersion;
use ygg_dsg::layout::{self, Layout};

fuzz_target!(|data: &[u8]| {
    let decoded = if ygg_dsg::is_binary(data) {
        ygg_dsg::parse_binary(data, "fuzz.sparkdsg")
    } else {
        ygg_dsg::parse_binary_body(data, DsgVersion::V1_1_3, "fuzz body")
    };
    if let Ok(graph) = decoded {
        let _ = layout::build(&graph, Layout::Mint);
    }
});
