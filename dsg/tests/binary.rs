//! scratch
use std::path::{Path, PathBuf};
fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}
#[test]
fn scratch() {
    for f in ["office_tiny.sparkdsg", "apartment_dsg.sparkdsg"] {
        let b = std::fs::read(fixture(f)).unwrap();
        let t = std::time::Instant::now();
        for _ in 0..10 {
            ygg_dsg::parse_binary(&b, f).unwrap();
        }
        eprintln!("{f}: {:?} per parse", t.elapsed() / 10);
    }
    for f in ["/tmp/bt/a.bin", "/tmp/bt/b.bin"] {
        let b = std::fs::read(f).unwrap();
        match ygg_dsg::parse_binary_body(&b, ygg_dsg::DsgVersion::V1_1_3, f) {
            Ok(g) => eprintln!("{f}: ok {:?}", g.counts()),
            Err(e) => eprintln!("{f}: {e}"),
        }
    }
}
