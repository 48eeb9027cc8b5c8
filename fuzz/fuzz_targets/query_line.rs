//! A line of `ygg query` input: parsing never panics, and a parsed query answers
//! (or errors) on a small office without panicking.
#![no_main]

use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use ygg_dsg::layout::{self, Layout};
use ygg_dsg::objects::{ObjectQuery, Objects};
use ygg_dsg::office::{OfficeParams, generate};
use ygg_store::SceneGraph;

fn office() -> &'static SceneGraph {
    static OFFICE: OnceLock<SceneGraph> = OnceLock::new();
    OFFICE.get_or_init(|| {
        layout::build(&generate(OfficeParams { seed: 7, scale: 0.02 }), Layout::Mint)
            .expect("office")
    })
}

fuzz_target!(|data: &[u8]| {
    let Ok(line) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(query) = ObjectQuery::from_json(line) {
        let _ = Objects::new(office()).answer(&query);
    }
});
