//! `ygg-soak` (ygg-testkit) with real processes: a short run passes every check (writer SIGKILLed
//! and SIGTERMed and picked up by the readers, reader churn, brute-force checks,
//! descriptors and `/dev/shm` files back to their start values), Ctrl-C stops it leaving
//! nothing behind, and a reader role stops on SIGTERM even while it waits for a writer.

use std::time::Duration;

use rustix::process::Signal;
use ygg_testkit::{Proc, TestScene, Watchdog, catches_signal, wait_until};

const STEP: Duration = Duration::from_secs(120);
const WATCHDOG: Duration = Duration::from_secs(240);

fn summary(proc: &Proc) -> serde_json::Value {
    let line = proc.expect_line(STEP, |l| l.contains("\"event\":\"summary\""));
    serde_json::from_str(&line).expect("summary is JSON")
}

#[test]
fn a_short_soak_passes_every_check_and_leaves_nothing() {
    let scene = TestScene::new("soak");
    let watchdog = Watchdog::new(WATCHDOG);
    // A small office and a short warm-up: the stream's window is not full yet, so the RSS
    // bound is loose here; the 2-minute CI run and the 30-minute soak hold the real one.
    let mut soak = Proc::spawn(
        scene.command(
            "ygg-soak",
            &[
                "--minutes",
                "0.6",
                "--scale",
                "0.05",
                "--warmup-secs",
                "5",
                "--progress-secs",
                "5",
                "--max-rss-growth",
                "50",
                "--max-reader-anon-growth",
                "50",
            ],
        ),
        "soak",
        &watchdog,
    );
    let v = summary(&soak);
    let status = soak.wait_exit(STEP);
    assert!(status.success(), "{v}\n{}", soak.stderr().join("\n"));
    assert_eq!(v["ok"], true, "{v}");
    assert_eq!(v["tally"]["writer_restarts"], 2, "{v}");
    assert!(v["tally"]["pickups"].as_u64() >= Some(2), "{v}");
    assert!(v["answers_checked"].as_u64() > Some(0), "{v}");
    assert_eq!(v["answers_checked"], v["answers_matched"], "{v}");
    assert!(soak.count_lines(|l| l.contains("\"event\":\"progress\"")) >= 3);
    scene.assert_no_leftovers(Duration::from_secs(5));
}

#[test]
fn ctrl_c_stops_the_soak_and_every_process_cleanly() {
    let scene = TestScene::new("soak-int");
    let watchdog = Watchdog::new(WATCHDOG);
    let mut soak = Proc::spawn(
        scene.command(
            "ygg-soak",
            &["--minutes", "5", "--scale", "0.05", "--warmup-secs", "2"],
        ),
        "soak",
        &watchdog,
    );
    soak.expect_line(STEP, |l| l.contains("\"event\":\"start\""));
    // The long-lived reader attached (the first progress line follows the warm-up).
    soak.expect_line(STEP, |l| l.contains("\"event\":\"progress\""));
    // Ctrl-C while the writer, the long-lived reader and a churning one run, each handling
    // the SIGTERM the soak stops it with.
    wait_until(STEP, "3 processes of the soak handle SIGTERM", || {
        let children = soak.children();
        children.len() >= 3
            && children
                .iter()
                .all(|&pid| catches_signal(pid, Signal::TERM))
    });
    soak.signal(Signal::INT);
    let v = summary(&soak);
    let status = soak.wait_exit(STEP);
    assert!(!status.success(), "an interrupted soak has no verdict: {v}");
    assert_eq!(v["interrupted"], true, "{v}");
    assert!(
        soak.stderr().join("\n").contains("interrupted"),
        "{}",
        soak.stderr().join("\n")
    );
    assert!(v["left_in_dev_shm"].is_null(), "{v}");
    scene.assert_no_leftovers(Duration::from_secs(5));
}

#[test]
fn a_reader_role_stops_on_sigterm_while_it_waits_for_a_writer() {
    let scene = TestScene::new("role-wait");
    let watchdog = Watchdog::new(WATCHDOG);
    let mut role = Proc::spawn(
        scene.command(
            "ygg",
            &[
                "demo-role",
                "--scene",
                &scene.name,
                "--role",
                "labels",
                "--wait-for-writer",
                "100",
            ],
        ),
        "role",
        &watchdog,
    );
    // It installs its signal handler right after creating its first iceoryx2 node, then
    // waits for a writer.
    wait_until(STEP, "the role handles SIGTERM", || {
        role.catches(Signal::TERM)
    });
    assert!(!scene.files().is_empty(), "the role made no node");
    role.signal(Signal::TERM);
    let status = role.wait_exit(Duration::from_secs(10));
    assert!(status.success(), "{}", role.describe());
    let v = summary(&role);
    assert_eq!(v["attached"], false, "{v}");
    scene.assert_no_leftovers(Duration::from_secs(5));
}
