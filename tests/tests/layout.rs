//! The workspace's layout rules (`.ci/check-deps`, DESIGN.md §6) hold on the real
//! workspace, and the check fails, naming the rule, when a forbidden edge is added to the
//! real metadata (the planner's library `ygg-reader` depending on `clap`).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::{Value, json};

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ is in the workspace")
        .to_owned()
}

fn check_deps(args: &[&std::ffi::OsStr]) -> Output {
    let root = workspace();
    Command::new("python3")
        .arg(root.join(".ci/check-deps"))
        .args(args)
        .current_dir(&root)
        .output()
        .expect("run python3 .ci/check-deps")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// `cargo metadata` of the workspace.
fn metadata() -> Value {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_owned());
    let out = Command::new(cargo)
        .args(["metadata", "--format-version", "1"])
        .current_dir(workspace())
        .output()
        .expect("run cargo metadata");
    assert!(out.status.success(), "{}", text(&out.stderr));
    serde_json::from_slice(&out.stdout).expect("metadata is JSON")
}

/// The package id of the crate `name` in `meta`.
fn package_id(meta: &Value, name: &str) -> Value {
    meta["packages"]
        .as_array()
        .expect("packages")
        .iter()
        .find(|p| p["name"] == name)
        .unwrap_or_else(|| panic!("{name} is not in the metadata"))["id"]
        .clone()
}

#[test]
fn the_workspace_keeps_its_layout_rules() {
    let out = check_deps(&[]);
    assert!(
        out.status.success(),
        "{}{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    assert!(text(&out.stdout).contains("layout rules hold"));
}

#[test]
fn a_reader_that_depends_on_clap_breaks_the_layout_and_is_named() {
    let mut meta = metadata();
    let reader = package_id(&meta, "ygg-reader");
    let clap = package_id(&meta, "clap");
    let node = meta["resolve"]["nodes"]
        .as_array_mut()
        .expect("resolve nodes")
        .iter_mut()
        .find(|n| n["id"] == reader)
        .expect("ygg-reader is resolved");
    node["deps"]
        .as_array_mut()
        .expect("deps")
        .push(json!({"name": "clap", "pkg": clap, "dep_kinds": [{"kind": null, "target": null}]}));
    let dir = tempfile::tempdir().expect("tempdir");
    let file = dir.path().join("metadata.json");
    std::fs::write(&file, meta.to_string()).expect("write metadata");

    let out = check_deps(&["--metadata".as_ref(), file.as_os_str()]);
    let stdout = text(&out.stdout);
    assert!(!out.status.success(), "the forbidden edge passed: {stdout}");
    assert!(
        stdout.contains("ygg-reader -> clap (rule: ygg-reader must not reach clap)"),
        "{stdout}"
    );
    // Nothing else is reported: the rest of the real workspace still holds.
    assert_eq!(stdout.lines().count(), 1, "{stdout}");
}
