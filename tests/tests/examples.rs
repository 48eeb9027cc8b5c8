//! End-to-end tests of the examples: each writer/reader pair in `examples/` runs as real
//! processes on a scene of its own; the reader must see snapshots and answer with real
//! ids, and the writer must stop cleanly on SIGTERM and leave nothing in `/dev/shm`.

use std::time::Duration;

use rustix::process::Signal;
use ygg_testkit::{Proc, TestScene, Watchdog, example, field};

/// Generous bound for any single step (debug builds on a busy 2-core machine).
const STEP: Duration = Duration::from_secs(60);
/// Per-test watchdog.
const WATCHDOG: Duration = Duration::from_secs(240);
/// Snapshots each reader takes.
const SNAPSHOTS: &str = "5";

/// Runs `<pair>_writer <scene> <writer_args>` and `<pair>_reader <scene> 5`; returns the
/// reader's snapshot lines (those with `generation=`), after checking both exit cleanly.
fn run_pair(pair: &str, writer_args: &[&str]) -> Vec<String> {
    let scene = TestScene::new(&format!("example-{pair}"));
    let dog = Watchdog::new(WATCHDOG);
    let mut args = vec![scene.name.as_str()];
    args.extend_from_slice(writer_args);
    let mut writer = Proc::spawn(
        scene.command_for(&example(&format!("{pair}_writer")), &args),
        "writer",
        &dog,
    );
    writer.expect_line(STEP, |l| l.starts_with("serving "));
    let mut reader = Proc::spawn(
        scene.command_for(
            &example(&format!("{pair}_reader")),
            &[&scene.name, SNAPSHOTS],
        ),
        "reader",
        &dog,
    );
    let status = reader.wait_exit(STEP);
    assert!(status.success(), "{}", reader.describe());
    let lines: Vec<String> = reader
        .stdout()
        .into_iter()
        .filter(|l| field(l, "generation").is_some())
        .collect();
    assert!(!lines.is_empty(), "no snapshot seen: {}", reader.describe());
    writer.signal(Signal::TERM);
    let status = writer.wait_exit(STEP);
    assert!(status.success(), "{}", writer.describe());
    writer.expect_line(STEP, |l| l.starts_with("stopped "));
    scene.assert_no_leftovers(Duration::from_secs(5));
    lines
}

/// The id in `key=<id>` of `line`.
fn id(line: &str, key: &str) -> u64 {
    field(line, key)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no {key}=<id> in {line:?}"))
}

#[test]
fn minimal_pair_answers_with_the_writers_objects_and_stops_cleanly() {
    let lines = run_pair("minimal", &[]);
    for line in &lines {
        // The writer's objects are 100 (chair), 101 (desk) and 102 (light).
        assert!((100..=102).contains(&id(line, "nearest")), "{line}");
        assert_eq!(field(line, "lights"), Some("102"), "{line}");
        assert!(id(line, "poses") > 0, "{line}");
    }
}

#[test]
fn office_pair_answers_nearest_and_within_with_object_ids_and_stops_cleanly() {
    let lines = run_pair("office", &["0.05"]);
    for line in &lines {
        let nearest = id(line, "nearest");
        assert!(nearest > 0, "{line}");
        let within = id(line, "within");
        let ids = field(line, "ids").expect("ids");
        if within > 0 {
            let ids: Vec<u64> = ids.split(',').map(|i| i.parse().expect("an id")).collect();
            assert_eq!(ids.len() as u64, within, "{line}");
        } else {
            assert_eq!(ids, "none", "{line}");
        }
    }
    // Snapshots keep coming: generations rise.
    let generations: Vec<u64> = lines.iter().map(|l| id(l, "generation")).collect();
    assert!(
        generations.windows(2).all(|w| w[0] < w[1]),
        "{generations:?}"
    );
}
