//! A Spark-DSG JSON file: import never panics; what imports builds a scene in every layout.
#![no_main]

use libfuzzer_sys::fuzz_target;
use ygg_dsg::layout::{self, Layout};

fuzz_target!(|data: &[u8]| {
    let Ok(graph) = ygg_dsg::parse_json(data, "fuzz.json") else {
        return;
    };
    for l in Layout::ALL {
        let _ = layout::build(&graph, l);
    }
});
